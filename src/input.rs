//! Every file drape reads from outside (scene, URDF, mesh, joints bag, node parameters) is
//! opened here, through one set of rules:
//!
//! - only regular files: a directory, FIFO, socket or device (`/dev/zero`) is refused from
//!   its metadata before it is opened, the file is opened with `O_NONBLOCK` (so a FIFO swapped
//!   in afterwards cannot block the open) and the opened descriptor is checked again;
//! - a size cap per kind ([`InputKind::cap`]), enforced while reading (`take(cap + 1)`), so a
//!   file that grows or lies about its size cannot make drape read without bound;
//! - symlinks are resolved before any containment check ([`contained`]), so a link inside an
//!   allowed tree that points outside it is refused before the target is opened;
//! - every file opened is remembered by device and inode ([`opened`]), so an output
//!   ([`crate::output`]) is never written onto one of the command's own inputs.

use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// What a file is read as; decides its size cap and names it in errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum InputKind {
    Scene,
    Urdf,
    Mesh,
    JointsBag,
    NodeParams,
    /// A sweep file (`drape sweep ...`).
    Sweep,
    /// A sweep's `plan.json`.
    SweepPlan,
    /// A sweep job's result record (`jobs/I.json`).
    JobRecord,
    /// A cached study reference solution.
    StudyCache,
}

impl InputKind {
    /// Largest file accepted, in bytes. A scene or parameter file is hand-written text; a
    /// URDF with inline comments stays well under a few megabytes; meshes and bags are data.
    pub const fn cap(self) -> u64 {
        match self {
            InputKind::Scene => 4 << 20,
            InputKind::NodeParams => 1 << 20,
            InputKind::Urdf => 16 << 20,
            InputKind::Mesh => 256 << 20,
            InputKind::JointsBag => 1 << 30,
            InputKind::Sweep => 4 << 20,
            InputKind::JobRecord => 1 << 20,
            // Every job's values, one line each, for at most `sweep::plan::MAX_JOBS` jobs.
            InputKind::SweepPlan => 256 << 20,
            InputKind::StudyCache => 256 << 20,
        }
    }
}

impl fmt::Display for InputKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            InputKind::Scene => "scene",
            InputKind::Urdf => "URDF",
            InputKind::Mesh => "mesh",
            InputKind::JointsBag => "joints bag",
            InputKind::NodeParams => "parameters file",
            InputKind::Sweep => "sweep file",
            InputKind::SweepPlan => "sweep plan",
            InputKind::JobRecord => "job record",
            InputKind::StudyCache => "study cache",
        })
    }
}

/// Why an input file was not read. Every variant starts with the file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum InputError {
    #[error("{path}: cannot open {kind}")]
    Open {
        path: PathBuf,
        kind: InputKind,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {kind} is a {found}, not a regular file")]
    NotRegular {
        path: PathBuf,
        kind: InputKind,
        found: &'static str,
    },
    #[error("{path}: {kind} is larger than the {cap} bytes allowed")]
    TooLarge {
        path: PathBuf,
        kind: InputKind,
        cap: u64,
    },
    #[error("{path}: cannot read {kind}")]
    Read {
        path: PathBuf,
        kind: InputKind,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {kind} is not UTF-8 text")]
    NotUtf8 {
        path: PathBuf,
        kind: InputKind,
        #[source]
        source: std::string::FromUtf8Error,
    },
    #[error("{path}: resolves to {resolved}, outside the allowed folders ({})", list(.allowed))]
    Outside {
        path: PathBuf,
        resolved: PathBuf,
        allowed: Vec<PathBuf>,
    },
}

fn list(paths: &[PathBuf]) -> String {
    if paths.is_empty() {
        return "none".into();
    }
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// A file drape has read, by identity (device and inode) and canonical path.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OpenedInput {
    pub dev: u64,
    pub ino: u64,
    pub path: PathBuf,
    pub kind: InputKind,
}

static OPENED: Mutex<Vec<OpenedInput>> = Mutex::new(Vec::new());

/// Every input file read so far by this process.
pub fn opened() -> Vec<OpenedInput> {
    OPENED.lock().map(|v| v.clone()).unwrap_or_default()
}

fn remember(input: OpenedInput) {
    if let Ok(mut v) = OPENED.lock() {
        // An entry of the same identity is an earlier file whose inode was freed and reused
        // (or this file read again): the newest path is the one that leads to it.
        match v
            .iter_mut()
            .find(|o| o.dev == input.dev && o.ino == input.ino)
        {
            Some(o) => *o = input,
            None => v.push(input),
        }
    }
}

fn file_type_name(ft: std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if ft.is_dir() {
        "directory"
    } else if ft.is_fifo() {
        "FIFO"
    } else if ft.is_char_device() {
        "character device"
    } else if ft.is_block_device() {
        "block device"
    } else if ft.is_socket() {
        "socket"
    } else {
        "special file"
    }
}

/// Reads a whole input file (see the module doc for the rules).
pub fn read_bytes(path: &Path, kind: InputKind) -> Result<Vec<u8>, InputError> {
    use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
    let open_err = |source| InputError::Open {
        path: path.to_path_buf(),
        kind,
        source,
    };
    let not_regular = |m: &std::fs::Metadata| InputError::NotRegular {
        path: path.to_path_buf(),
        kind,
        found: file_type_name(m.file_type()),
    };
    let too_large = || InputError::TooLarge {
        path: path.to_path_buf(),
        kind,
        cap: kind.cap(),
    };
    let meta = std::fs::metadata(path).map_err(open_err)?;
    if !meta.is_file() {
        return Err(not_regular(&meta));
    }
    if meta.len() > kind.cap() {
        return Err(too_large());
    }
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(path)
        .map_err(open_err)?;
    let meta = file.metadata().map_err(open_err)?;
    if !meta.is_file() {
        return Err(not_regular(&meta));
    }
    let mut bytes = Vec::with_capacity(meta.len().min(kind.cap()) as usize);
    file.take(kind.cap() + 1)
        .read_to_end(&mut bytes)
        .map_err(|source| InputError::Read {
            path: path.to_path_buf(),
            kind,
            source,
        })?;
    if bytes.len() as u64 > kind.cap() {
        return Err(too_large());
    }
    remember(OpenedInput {
        dev: meta.dev(),
        ino: meta.ino(),
        path: std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()),
        kind,
    });
    Ok(bytes)
}

/// Reads an input file as UTF-8 text; a leading byte-order mark is dropped.
pub fn read_text(path: &Path, kind: InputKind) -> Result<String, InputError> {
    let mut bytes = read_bytes(path, kind)?;
    if bytes.starts_with(b"\xEF\xBB\xBF") {
        bytes.drain(..3);
    }
    String::from_utf8(bytes).map_err(|source| InputError::NotUtf8 {
        path: path.to_path_buf(),
        kind,
        source,
    })
}

/// Drops a leading UTF-8 byte-order mark from text that did not come through [`read_text`].
pub fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// Deepest flow-collection nesting (`[[[`, `{a: {a:`) accepted in YAML: libyaml's flow parser
/// takes time quadratic in the depth (100,000 levels: minutes), and serde's recursion limit
/// (128) would reject anything deeper anyway.
pub const MAX_YAML_DEPTH: usize = 128;

/// Checks, in one linear pass, that no flow collection in `text` nests deeper than
/// [`MAX_YAML_DEPTH`]; on failure returns the 1-based line where the limit was passed.
/// Brackets inside quoted scalars and comments do not count.
pub fn check_yaml_depth(text: &str) -> Result<(), usize> {
    let mut depth = 0usize;
    let mut line = 1usize;
    let mut prev = b'\n';
    let bytes = text.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        let b = bytes[i];
        let scalar_start = matches!(
            prev,
            b' ' | b'\t' | b'\n' | b'[' | b'{' | b',' | b':' | b'-'
        );
        match b {
            b'\n' => line += 1,
            b'#' if matches!(prev, b' ' | b'\t' | b'\n') => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'"' | b'\'' if scalar_start => {
                let quote = b;
                i += 1;
                while i < bytes.len() {
                    match bytes[i] {
                        b'\\' if quote == b'"' => i += 1,
                        b'\n' => line += 1,
                        c if c == quote => break,
                        _ => {}
                    }
                    i += 1;
                }
            }
            b'[' | b'{' => {
                depth += 1;
                if depth > MAX_YAML_DEPTH {
                    return Err(line);
                }
            }
            b']' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
        prev = bytes.get(i).copied().unwrap_or(b' ');
        i += 1;
    }
    Ok(())
}

/// Resolves `path` (every symlink, `..`) and checks that the result lies inside one of
/// `allowed` (themselves resolved); returns the resolved path. Nothing is opened.
pub fn contained(path: &Path, allowed: &[PathBuf]) -> Result<PathBuf, InputError> {
    let resolved = std::fs::canonicalize(path).map_err(|source| InputError::Open {
        path: path.to_path_buf(),
        kind: InputKind::Mesh,
        source,
    })?;
    let roots: Vec<PathBuf> = allowed
        .iter()
        .filter_map(|r| std::fs::canonicalize(r).ok())
        .collect();
    if roots.iter().any(|r| resolved.starts_with(r)) {
        Ok(resolved)
    } else {
        Err(InputError::Outside {
            path: path.to_path_buf(),
            resolved,
            allowed: allowed.to_vec(),
        })
    }
}

/// Whether `path` names the same file (device and inode) as one of the inputs read so far.
/// An input is only one while its own path still leads to that file: an inode freed by a
/// deleted or replaced input (and reused for a new file) is not mistaken for it.
pub fn is_an_input(path: &Path) -> Option<OpenedInput> {
    use std::os::unix::fs::MetadataExt;
    let meta = std::fs::metadata(path).ok()?;
    opened().into_iter().find(|o| {
        o.dev == meta.dev()
            && o.ino == meta.ino()
            && std::fs::metadata(&o.path).is_ok_and(|m| m.dev() == o.dev && m.ino() == o.ino)
    })
}

/// The error and every cause below it, one per line: `error: <top>` then `  caused by: ...`.
/// A cause whose text is already the end of the message above it is not repeated.
pub fn error_chain(e: &(dyn std::error::Error + 'static)) -> String {
    format!("error: {}", joined(e, "\n  caused by: "))
}

/// [`error_chain`] on one line, `top: cause: cause` (a log line, a service reply, a record).
pub fn error_line(e: &(dyn std::error::Error + 'static)) -> String {
    joined(e, ": ")
}

fn joined(e: &(dyn std::error::Error + 'static), sep: &str) -> String {
    let mut out = e.to_string();
    let mut last = out.clone();
    let mut cur = e.source();
    while let Some(c) = cur {
        let text = c.to_string();
        if !last.ends_with(&text) {
            out.push_str(sep);
            out.push_str(&text);
        }
        last = text;
        cur = c.source();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_directories_and_fifos_are_refused_before_reading() {
        let dir = tempfile::tempdir().unwrap();
        for p in [Path::new("/dev/zero"), dir.path()] {
            let e = read_bytes(p, InputKind::Scene).unwrap_err();
            assert!(matches!(e, InputError::NotRegular { .. }), "{e}");
        }
        let fifo = dir.path().join("f");
        let c = std::ffi::CString::new(fifo.as_os_str().as_encoded_bytes()).unwrap();
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let e = read_bytes(&fifo, InputKind::Mesh).unwrap_err();
        assert!(
            matches!(e, InputError::NotRegular { found: "FIFO", .. }),
            "{e}"
        );
    }

    #[test]
    fn size_cap_and_bom() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.yaml");
        std::fs::write(&p, vec![b' '; (InputKind::NodeParams.cap() + 1) as usize]).unwrap();
        let e = read_bytes(&p, InputKind::NodeParams).unwrap_err();
        assert!(matches!(e, InputError::TooLarge { .. }), "{e}");
        std::fs::write(&p, b"\xEF\xBB\xBFa: 1").unwrap();
        assert_eq!(read_text(&p, InputKind::Scene).unwrap(), "a: 1");
        assert!(is_an_input(&p).is_some());
    }

    #[test]
    fn symlinks_are_resolved_before_containment() {
        let dir = tempfile::tempdir().unwrap();
        let inside = dir.path().join("pkg");
        std::fs::create_dir(&inside).unwrap();
        let outside = dir.path().join("secret.stl");
        std::fs::write(&outside, b"x").unwrap();
        let link = inside.join("m.stl");
        std::os::unix::fs::symlink(&outside, &link).unwrap();
        let e = contained(&link, std::slice::from_ref(&inside)).unwrap_err();
        assert!(matches!(e, InputError::Outside { .. }), "{e}");
        assert!(contained(&link, &[dir.path().to_path_buf()]).is_ok());
    }

    #[test]
    fn yaml_depth_counts_flow_nesting_outside_strings_and_comments() {
        assert_eq!(check_yaml_depth(&"[".repeat(100_000)), Err(1));
        assert_eq!(
            check_yaml_depth(&format!("a: 1\nb: {}", "{a: ".repeat(200))),
            Err(2)
        );
        assert!(check_yaml_depth("a: [1, {b: [2]}]\nname: don't [\n").is_ok());
        let hidden = format!(
            "a: \"{}\" # {}\nb: '{}'",
            "[".repeat(500),
            "{".repeat(500),
            "[".repeat(500)
        );
        assert!(check_yaml_depth(&hidden).is_ok());
        // Closing brackets in strings cannot hide real nesting.
        let sneaky = "[ \"]\", ".repeat(200);
        assert!(check_yaml_depth(&sneaky).is_err());
    }

    #[test]
    fn chain_prints_each_cause_once() {
        let io = std::io::Error::from_raw_os_error(21);
        let e = InputError::Read {
            path: "x".into(),
            kind: InputKind::Scene,
            source: io,
        };
        let s = error_chain(&e);
        assert_eq!(s.matches("os error 21").count(), 1, "{s}");
        assert!(s.starts_with("error: x: "), "{s}");
    }
}
