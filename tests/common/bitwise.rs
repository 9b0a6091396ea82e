//! The hash helpers of the bitwise trajectory tests (`tests/step_bitwise.rs`,
//! `tests/implicit_bitwise.rs`, `tests/collide_bitwise.rs`): FNV-1a over the bit patterns of a
//! run's values, the bundled scene a case starts from, and the comparison with the recorded
//! table (which prints the table to re-record from, with `--nocapture`).

#![allow(dead_code)]

use drape::cloth::Cloth;
use drape::scene::Scene;
use std::path::Path;

/// FNV-1a's offset basis: the hash of nothing.
pub const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

/// FNV-1a over the bit patterns of the values.
pub fn fnv(h: &mut u64, values: impl IntoIterator<Item = f64>) {
    for v in values {
        for b in v.to_bits().to_le_bytes() {
            *h ^= b as u64;
            *h = h.wrapping_mul(0x100_0000_01b3);
        }
    }
}

/// Adds the cloth's final state: every position, then every velocity.
pub fn fnv_state(h: &mut u64, cloth: &Cloth) {
    let x = cloth.x.iter().flat_map(|p| p.to_array());
    let v = cloth.v.iter().flat_map(|p| p.to_array());
    fnv(h, x.chain(v));
}

/// A bundled scene (`config/<file>`) with its first cloth at `res` x `res` vertices.
pub fn bundled_scene(file: &str, res: usize) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config")
        .join(file);
    let mut s = Scene::load(&path).expect("bundled scene");
    s.cloths[0].grid.resolution = [res, res];
    s
}

/// Compares each case's hash with the recorded one of the same name; prints the table of the
/// hashes found (to copy into the test after a deliberate physics change) and fails naming
/// the cases that differ.
pub fn assert_recorded(found: &[(&str, u64)], expected: &[(&str, u64)]) {
    let mut table = String::new();
    let mut mismatches = Vec::new();
    for &(name, h) in found {
        table += &format!("    (\"{name}\", 0x{h:016x}),\n");
        match expected.iter().find(|(n, _)| *n == name) {
            Some(&(_, want)) if want == h => {}
            _ => mismatches.push(name),
        }
    }
    println!("const EXPECTED: &[(&str, u64)] = &[\n{table}];");
    assert!(
        mismatches.is_empty(),
        "trajectories differ from the recorded ones: {mismatches:?}\n{table}"
    );
}
