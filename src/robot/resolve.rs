//! Mesh URI resolution: `package://`, `file://` and plain paths, the way ROS tools and
//! pybullet find meshes, and the one rule for where a mesh may come from.
//!
//! **Where meshes may come from.** After resolution, every mesh reference (whatever its form:
//! `package://`, `file://`, relative or absolute, through any symlinks) is resolved to its real
//! path and must lie inside one of [`allowed_roots`]: the URDF's package tree (the URDF's folder,
//! or the ancestor that is the package: it holds a `package.xml` or bears the package's name),
//! the package folders the user configured (`search_paths`, `ROS_PACKAGE_PATH`,
//! `AMENT_PREFIX_PATH`), and the caller's extra roots (the scene's folder and its
//! `mesh_paths` allow-list). The check runs before the mesh is opened.

use std::path::{Component, Path, PathBuf};

/// Where to look for `package://pkg/...` besides the URDF's own directory tree.
#[derive(Debug, Clone, Default)]
pub struct SearchPaths {
    /// Caller-supplied directories that are a package or contain packages.
    pub extra: Vec<PathBuf>,
    /// `ROS_PACKAGE_PATH` entries (a package dir or a dir containing packages).
    pub ros_package_path: Vec<PathBuf>,
    /// `AMENT_PREFIX_PATH` prefixes (`<prefix>/share/<pkg>`).
    pub ament_prefixes: Vec<PathBuf>,
}

impl SearchPaths {
    /// `extra` plus the two ROS environment variables, if set.
    pub fn from_env(extra: Vec<PathBuf>) -> Self {
        let split = |var: &str| -> Vec<PathBuf> {
            std::env::var_os(var)
                .map(|v| {
                    std::env::split_paths(&v)
                        .filter(|p| !p.as_os_str().is_empty())
                        .collect()
                })
                .unwrap_or_default()
        };
        Self {
            extra,
            ros_package_path: split("ROS_PACKAGE_PATH"),
            ament_prefixes: split("AMENT_PREFIX_PATH"),
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub enum ResolveError {
    /// No candidate file exists; every path that was tried, in order.
    NotFound(Vec<PathBuf>),
    /// The URI's path climbs out of its package (or is absolute inside `package://`).
    Escape,
    /// A scheme other than `package://` / `file://`, or a malformed URI.
    Unsupported(String),
}

/// Lexically normalises a relative path, failing if `..` climbs above its start.
fn normalize_relative(rest: &str) -> Option<PathBuf> {
    let mut out = PathBuf::new();
    let mut depth = 0usize;
    for c in Path::new(rest).components() {
        match c {
            Component::Normal(s) => {
                out.push(s);
                depth += 1;
            }
            Component::CurDir => {}
            Component::ParentDir => {
                if depth == 0 {
                    return None;
                }
                out.pop();
                depth -= 1;
            }
            Component::RootDir | Component::Prefix(_) => return None,
        }
    }
    Some(out)
}

/// Candidate package directories for `pkg`, most specific first.
fn package_dirs(pkg: &str, urdf_dir: Option<&Path>, paths: &SearchPaths) -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    let is_or_contains = |d: &Path, dirs: &mut Vec<PathBuf>| {
        if d.file_name().is_some_and(|n| n == pkg) {
            dirs.push(d.to_path_buf());
        }
        dirs.push(d.join(pkg));
    };
    for d in paths.extra.iter().chain(&paths.ros_package_path) {
        is_or_contains(d, &mut dirs);
    }
    for p in &paths.ament_prefixes {
        dirs.push(p.join("share").join(pkg));
    }
    if let Some(dir) = urdf_dir {
        // pybullet-style layouts: the package is the URDF's folder, a folder beside it, or an
        // ancestor; `pkg/urdf/robot.urdf` next to `pkg/meshes` is the ROS convention.
        for (level, a) in dir.ancestors().take(4).enumerate() {
            if a.as_os_str().is_empty() {
                continue;
            }
            is_or_contains(a, &mut dirs);
            if level <= 1 {
                dirs.push(a.to_path_buf());
            }
        }
    }
    let mut seen = std::collections::HashSet::new();
    dirs.retain(|d| seen.insert(d.clone()));
    dirs
}

/// How many folders above the URDF's own a package root is looked for (`pkg/urdf/x.urdf`).
const PACKAGE_LEVELS: usize = 3;

/// The folders a mesh referenced by `uri` from a URDF in `urdf_dir` may lie in (see the module
/// doc); `extra` are the caller's roots (scene folder, allow-list).
pub fn allowed_roots(
    uri: &str,
    urdf_dir: Option<&Path>,
    paths: &SearchPaths,
    extra: &[PathBuf],
) -> Vec<PathBuf> {
    let mut roots: Vec<PathBuf> = extra.to_vec();
    let pkg = uri
        .trim()
        .strip_prefix("package://")
        .and_then(|r| r.split_once('/'))
        .map(|(p, _)| p);
    if let Some(dir) = urdf_dir {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        roots.push(dir.to_path_buf());
        let canonical = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
        for a in canonical.ancestors().skip(1).take(PACKAGE_LEVELS) {
            let named = pkg.is_some_and(|p| a.file_name().is_some_and(|n| n == p));
            if named || a.join("package.xml").is_file() {
                roots.push(a.to_path_buf());
                break;
            }
        }
    }
    roots.extend(paths.extra.iter().cloned());
    roots.extend(paths.ros_package_path.iter().cloned());
    roots.extend(paths.ament_prefixes.iter().map(|p| p.join("share")));
    roots
}

/// Resolves a URDF mesh `filename` to an existing file.
pub fn resolve_uri(
    uri: &str,
    urdf_dir: Option<&Path>,
    paths: &SearchPaths,
) -> Result<PathBuf, ResolveError> {
    let uri = uri.trim();
    if let Some(rest) = uri.strip_prefix("package://") {
        let (pkg, inner) = rest.split_once('/').ok_or_else(|| {
            ResolveError::Unsupported(format!("`{uri}` has no path after the package"))
        })?;
        if pkg.is_empty() || pkg == "." || pkg == ".." {
            return Err(ResolveError::Escape);
        }
        let inner = normalize_relative(inner).ok_or(ResolveError::Escape)?;
        let mut tried = Vec::new();
        for d in package_dirs(pkg, urdf_dir, paths) {
            let p = d.join(&inner);
            // Anything but a folder counts as found: `crate::input` then refuses what is not a
            // regular file with a clear error (a FIFO, a device) instead of "not found".
            if p.exists() && !p.is_dir() {
                return Ok(p);
            }
            tried.push(p);
        }
        return Err(ResolveError::NotFound(tried));
    }
    let raw = if let Some(p) = uri.strip_prefix("file://") {
        p
    } else if uri.contains("://") {
        return Err(ResolveError::Unsupported(format!(
            "unsupported URI scheme in `{uri}`"
        )));
    } else {
        uri
    };
    let path = Path::new(raw);
    let candidate = match urdf_dir {
        Some(d) if path.is_relative() => d.join(path),
        _ => path.to_path_buf(),
    };
    if candidate.exists() && !candidate.is_dir() {
        Ok(candidate)
    } else {
        Err(ResolveError::NotFound(vec![candidate]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalization_rejects_escapes_only() {
        assert_eq!(normalize_relative("a/./b/../c"), Some(PathBuf::from("a/c")));
        assert_eq!(normalize_relative("a/../../etc/passwd"), None);
        assert_eq!(normalize_relative("../x"), None);
        assert_eq!(normalize_relative("/etc/passwd"), None);
    }
}
