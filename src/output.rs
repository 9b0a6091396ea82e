//! Every file drape writes (bags, `--summary`, pictures, sweep plans, records, manifests and
//! scheduler files, study tables) goes through one set of rules:
//!
//! - never onto one of the command's inputs: the target is compared by device and inode with
//!   every file read through [`crate::input`] and with the paths the caller names, so a
//!   symlink or a hard link to an input counts as the input;
//! - a directory is refused; an existing device or FIFO (`/dev/null`, `/dev/stdout`) is a
//!   stream and is written in place;
//! - a regular file is written to a new temporary file beside the target
//!   (`.<name>.partial-<pid>-<n>`, created exclusively) and renamed onto the target only once
//!   every byte is written, flushed and synced; a failed write, flush or sync is an error, the
//!   temporary file is removed and nothing is left under the final name.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Why an output file was not written. Every variant starts with the file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// `kind`: what the file is to the command (`the scene this command reads`).
    #[error("{}: is {kind} ({}); refusing to overwrite it", .path.display(), .input.display())]
    OntoInput {
        path: PathBuf,
        input: PathBuf,
        kind: String,
    },
    #[error("{}: is a directory", .path.display())]
    IsDirectory { path: PathBuf },
    #[error("{}: cannot write", .path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: cannot move the finished file into place from {}", .path.display(), .from.display())]
    Rename {
        path: PathBuf,
        from: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl OutputError {
    /// The I/O error under a write or rename failure.
    pub fn io(&self) -> Option<&std::io::Error> {
        match self {
            OutputError::Write { source, .. } | OutputError::Rename { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// Where an output goes: a staging file to rename, or the target itself (a stream).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Target {
    /// Write to `tmp`, then rename it onto the target.
    Staged { tmp: PathBuf },
    /// An existing device or FIFO: written in place.
    Stream,
}

/// Checks `path` as an output before any work: not one of the inputs read so far (but a stale
/// cache drape wrote, which it replaces), not one of
/// `also` (inputs the caller has not read yet, e.g. the bags a render is about to read), not a
/// directory. Returns where to write.
pub fn check(path: &Path, also: &[&Path]) -> Result<Target, OutputError> {
    use std::os::unix::fs::MetadataExt;
    // A stale cache drape wrote itself (the study's reference) is replaced: that is its use.
    let replaceable = |i: &crate::input::OpenedInput| i.kind == crate::input::InputKind::StudyCache;
    if let Some(input) = crate::input::is_an_input(path).filter(|i| !replaceable(i)) {
        return Err(OutputError::OntoInput {
            path: path.to_path_buf(),
            input: input.path,
            kind: format!("the {} this command reads", input.kind),
        });
    }
    let meta = std::fs::metadata(path).ok();
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    for a in also {
        let same_file = match (&meta, std::fs::metadata(a)) {
            (Some(m), Ok(am)) => am.dev() == m.dev() && am.ino() == m.ino(),
            _ => absolute(a) == absolute(path),
        };
        if same_file {
            return Err(OutputError::OntoInput {
                path: path.to_path_buf(),
                input: std::fs::canonicalize(a).unwrap_or_else(|_| absolute(a)),
                kind: "a file this command reads or writes".into(),
            });
        }
    }
    match meta {
        Some(m) if m.is_dir() => Err(OutputError::IsDirectory {
            path: path.to_path_buf(),
        }),
        Some(m) if !m.is_file() => Ok(Target::Stream),
        _ => Ok(Target::Staged {
            tmp: staging_name(path),
        }),
    }
}

/// `.<name>.partial-<pid>-<n>` beside `path`: unique per process and call, hidden.
pub fn staging_name(path: &Path) -> PathBuf {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().map_or_else(
        || std::ffi::OsString::from("out"),
        std::ffi::OsStr::to_os_string,
    );
    let mut tmp = std::ffi::OsString::from(".");
    tmp.push(&name);
    tmp.push(format!(
        ".partial-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ));
    path.with_file_name(tmp)
}

/// An output file being written (see the module doc). Dropped without [`Output::finish`],
/// it removes its temporary file and leaves the target as it was.
pub struct Output {
    path: PathBuf,
    tmp: Option<PathBuf>,
    file: Option<BufWriter<std::fs::File>>,
}

impl std::fmt::Debug for Output {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Output")
            .field("path", &self.path)
            .field("tmp", &self.tmp)
            .finish()
    }
}

impl Output {
    /// Starts writing `path` after [`check`]ing it (with `also` as further inputs).
    pub fn create(path: &Path, also: &[&Path]) -> Result<Output, OutputError> {
        let write_err = |source| OutputError::Write {
            path: path.to_path_buf(),
            source,
        };
        let (file, tmp) = match check(path, also)? {
            Target::Stream => (
                std::fs::OpenOptions::new()
                    .write(true)
                    .open(path)
                    .map_err(write_err)?,
                None,
            ),
            Target::Staged { tmp } => {
                let f = std::fs::OpenOptions::new()
                    .write(true)
                    .create_new(true)
                    .open(&tmp)
                    .map_err(write_err)?;
                (f, Some(tmp))
            }
        };
        Ok(Output {
            path: path.to_path_buf(),
            tmp,
            file: Some(BufWriter::with_capacity(1 << 16, file)),
        })
    }

    /// The file the caller asked for.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes, syncs and renames the temporary file onto the target.
    pub fn finish(mut self) -> Result<(), OutputError> {
        let write_err = |source| OutputError::Write {
            path: self.path.clone(),
            source,
        };
        let Some(w) = self.file.take() else {
            return Ok(());
        };
        let file = w.into_inner().map_err(|e| write_err(e.into_error()))?;
        if let Some(tmp) = &self.tmp {
            file.sync_all().map_err(write_err)?;
            drop(file);
            std::fs::rename(tmp, &self.path).map_err(|source| OutputError::Rename {
                path: self.path.clone(),
                from: tmp.clone(),
                source,
            })?;
            self.tmp = None;
        }
        Ok(())
    }

    fn writer(&mut self) -> std::io::Result<&mut BufWriter<std::fs::File>> {
        self.file
            .as_mut()
            .ok_or_else(|| std::io::Error::other("output already finished"))
    }
}

impl Write for Output {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.writer()?.write(buf)
    }
    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        self.writer()?.write_all(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.writer()?.flush()
    }
}

impl Drop for Output {
    fn drop(&mut self) {
        // Unwritten buffered bytes are dropped with the temporary file they belong to.
        if let Some(w) = self.file.take() {
            let (file, _) = w.into_parts();
            drop(file);
        }
        if let Some(tmp) = self.tmp.take() {
            let _ = std::fs::remove_file(tmp);
        }
    }
}

/// Writes `bytes` to `path` through [`Output`]: the old file or the whole new one, never a part.
pub fn write(path: &Path, bytes: &[u8], also: &[&Path]) -> Result<(), OutputError> {
    let mut out = Output::create(path, also)?;
    out.write_all(bytes).map_err(|source| OutputError::Write {
        path: path.to_path_buf(),
        source,
    })?;
    out.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::InputKind;

    #[test]
    fn inputs_directories_and_streams() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("s.yaml");
        std::fs::write(&input, "a: 1").unwrap();
        crate::input::read_text(&input, InputKind::Scene).unwrap();
        let link = dir.path().join("l");
        std::os::unix::fs::symlink(&input, &link).unwrap();
        for p in [&input, &link] {
            let e = write(p, b"x", &[]).unwrap_err();
            assert!(matches!(e, OutputError::OntoInput { .. }), "{e}");
        }
        let other = dir.path().join("o.txt");
        std::fs::write(&other, "keep").unwrap();
        let e = write(&other, b"x", &[&other]).unwrap_err();
        assert!(matches!(e, OutputError::OntoInput { .. }), "{e}");
        let e = write(dir.path(), b"x", &[]).unwrap_err();
        assert!(matches!(e, OutputError::IsDirectory { .. }), "{e}");
        write(Path::new("/dev/null"), b"x", &[]).unwrap();
        write(&other, b"new", &[]).unwrap();
        assert_eq!(std::fs::read(&other).unwrap(), b"new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 3);
    }

    #[test]
    fn an_unfinished_output_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.png");
        let mut o = Output::create(&p, &[]).unwrap();
        o.write_all(b"half").unwrap();
        drop(o);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
