//! The layering of the core's lower modules, checked on the source text: `linalg`
//! and `par` sit below everything and import nothing of the simulator; `effects` sits below
//! `integrate` and never imports it; `collide` takes the velocity filter from `linalg`, not
//! from `integrate`. Every `crate::` path a file names (in `use` lines or inline) counts.

use std::fs;
use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The top-level modules `file` names through `crate::` paths, comments left out.
fn crate_modules(file: &Path) -> Vec<String> {
    let text = fs::read_to_string(file).unwrap_or_default();
    let mut found = Vec::new();
    for line in text.lines() {
        let code = line.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(k) = rest.find("crate::") {
            let tail = &rest[k + "crate::".len()..];
            let name: String = tail
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                found.push(name);
            }
            rest = tail;
        }
    }
    found
}

/// Files under `src/<module>` (or `src/<module>.rs`) that name any of `forbidden`.
fn violations(module: &str, forbidden: &[&str]) -> Vec<String> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src.join(module), &mut files);
    let single = src.join(format!("{module}.rs"));
    if single.exists() {
        files.push(single);
    }
    assert!(!files.is_empty(), "no source files for module {module}");
    let mut bad = Vec::new();
    for f in &files {
        for m in crate_modules(f) {
            if forbidden.contains(&m.as_str()) {
                bad.push(format!("{} imports crate::{m}", f.display()));
            }
        }
    }
    bad
}

const SIMULATOR: &[&str] = &[
    "cloth",
    "collide",
    "effects",
    "garment",
    "hard",
    "integrate",
    "mesh",
    "robot",
    "ros",
    "scene",
    "sim",
    "study",
];

#[test]
fn linalg_and_par_import_nothing_of_the_simulator() {
    let mut bad = violations("linalg", SIMULATOR);
    bad.extend(violations("par", SIMULATOR));
    assert!(bad.is_empty(), "{bad:#?}");
}

#[test]
fn effects_sit_below_the_integrators() {
    let bad = violations("effects", &["integrate", "sim", "collide", "scene", "ros"]);
    assert!(bad.is_empty(), "{bad:#?}");
}

#[test]
fn integrators_do_not_reach_up_into_the_simulation() {
    let bad = violations("integrate", &["sim", "collide", "scene", "ros", "garment"]);
    assert!(bad.is_empty(), "{bad:#?}");
}

#[test]
fn collide_does_not_import_the_integrators() {
    let bad = violations("collide", &["integrate"]);
    assert!(bad.is_empty(), "{bad:#?}");
}
