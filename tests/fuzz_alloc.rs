//! No unbounded allocation: files whose headers or attributes claim billions of elements must be
//! rejected (or read) without allocating for the claim. A counting global allocator records the
//! peak of live heap bytes while each file is loaded; this binary holds a single test so that no
//! other test allocates concurrently.

use drape::mesh::load_mesh;
use drape::scene::Scene;
use drape::Vec3;
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let live = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
        PEAK.fetch_max(live, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size > layout.size() {
            let live = LIVE.fetch_add(new_size - layout.size(), Ordering::Relaxed) + new_size
                - layout.size();
            PEAK.fetch_max(live, Ordering::Relaxed);
        } else {
            LIVE.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

/// Peak live heap growth (bytes) while `f` runs.
fn peak_during<T>(f: impl FnOnce() -> T) -> (T, usize) {
    let base = LIVE.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let r = f();
    (r, PEAK.load(Ordering::Relaxed).saturating_sub(base))
}

/// Far below what any of the claims would need (4e9 triangles of 12-byte indices are 48 GB),
/// far above what the small files need.
const CAP: usize = 16 << 20;

fn load(dir: &Path, name: &str, bytes: &[u8]) -> (String, usize) {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("temp file");
    let (r, peak) = peak_during(|| load_mesh(&path, Vec3::ONE).map(|m| m.indices.len()));
    let what = match r {
        Ok(n) => format!("ok: {n} triangles"),
        Err(e) => e.to_string(),
    };
    (what, peak)
}

#[test]
fn huge_claims_do_not_allocate_for_the_claim() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let mut cases: Vec<(&str, Vec<u8>, &str)> = Vec::new();

    // Binary STL claiming 4e9 triangles with one record of body.
    let mut stl = vec![0u8; 84 + 50];
    stl[80..84].copy_from_slice(&4_000_000_000u32.to_le_bytes());
    cases.push(("claim.stl", stl.clone(), "4000000000"));
    // The same, but the body is padded with "solid" so the ASCII sniffing is tried too.
    let mut ascii_like = b"solid x".to_vec();
    ascii_like.resize(84 + 50, b' ');
    ascii_like[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
    cases.push(("solid.stl", ascii_like, "solid.stl"));
    // OBJ with a face index near u32::MAX and a negative one.
    cases.push((
        "claim.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4294967295\nf 1 2 -4000000000\n".to_vec(),
        "claim.obj",
    ));
    // DAE whose accessor and float_array claim 4e9 entries, and whose primitive count does.
    let dae = |accessor: &str, prim: &str| {
        format!(
            r##"<COLLADA><library_geometries><geometry id="g"><mesh>
<source id="s"><float_array id="a" count="4000000000">0 0 0 1 0 0 0 1 0</float_array>
<technique_common><accessor source="#a" count="{accessor}" stride="3"/></technique_common></source>
<vertices id="v"><input semantic="POSITION" source="#s"/></vertices>
<triangles count="{prim}"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>
</mesh></geometry></library_geometries>
<library_visual_scenes><visual_scene id="vs"><node><instance_geometry url="#g"/></node></visual_scene></library_visual_scenes>
<scene><instance_visual_scene url="#vs"/></scene></COLLADA>"##
        )
        .into_bytes()
    };
    cases.push(("accessor.dae", dae("4000000000", "1"), "accessor.dae"));
    cases.push(("prim.dae", dae("3", "4000000000"), "prim.dae"));
    // A well-formed file loads, and the counter sees its allocations (the cap can be hit).
    let (what, peak) = load(d, "ok.dae", &dae("3", "1"));
    assert!(what.starts_with("ok: 1"), "{what}");
    assert!(peak > 0, "the counting allocator saw nothing");

    for (name, bytes, expect) in &cases {
        let (what, peak) = load(d, name, bytes);
        eprintln!("{name}: {what} (peak {peak} bytes)");
        assert!(
            peak < CAP,
            "{name}: {peak} bytes allocated for a {}-byte file ({what})",
            bytes.len()
        );
        assert!(
            what.contains(expect) || what.starts_with("ok"),
            "{name}: {what}"
        );
    }
    // The binary STL claim must be an error that states the claim.
    let (what, _) = load(d, "claim2.stl", &stl);
    assert!(
        what.contains("4000000000") && what.contains("claim2.stl"),
        "{what}"
    );

    // A scene asking for a 1e5 x 1e5 grid is rejected before anything is allocated for it.
    let yaml = "effects: [gravity]\ncloths:\n  - name: huge\n    grid: { size: [1, 1], resolution: [100000, 100000] }\n";
    let (r, peak) = peak_during(|| Scene::from_yaml(yaml, "huge.yaml"));
    let err = r.expect_err("a 1e10-vertex grid must be rejected");
    assert!(peak < CAP, "scene: {peak} bytes");
    assert!(err.to_string().contains("resolution"), "{err}");
}
