//! Reference solutions: each scene and resolution run once with RK4 at a step much smaller than
//! any in the sweep, cached in the output folder so later studies reuse it.
//!
//! Cache file: one text header line naming everything the solution depends on, then little-endian
//! f64s: for each sample its energy and the positions. A header that does not match is recomputed.

use super::run::{run, Horizon, RunSettings, Trajectory};
use super::scenes::StudyScene;
use super::StudyError;
use crate::integrate::IntegratorKind;
use crate::Vec3;
use std::path::{Path, PathBuf};

/// Bumped whenever the scenes, the reference method or the physics a scene runs change (the
/// obstacle response's friction moves the sphere drape's reference, for one), to invalidate
/// old caches.
const FORMAT: &str = "drape-study-reference v2";

/// How many finer levels are tried when RK4 is unstable at the requested step.
const RETRIES: u32 = 3;

#[derive(Debug, Clone)]
pub struct Reference {
    pub trajectory: Trajectory,
    /// `dt = 1 / (60 * 2^dt_level)` actually used.
    pub dt_level: u32,
    pub vertices: usize,
    /// True if read from the cache.
    pub cached: bool,
}

fn header(scene: StudyScene, n: usize, stiffness: f64, horizon: &Horizon, level: u32) -> String {
    format!(
        "{FORMAT} scene={} res={:?} stiffness={stiffness:e} samples={:?} integrator=rk4 min_dt_level={level}",
        scene.name(),
        scene.resolution(n),
        horizon.sample_frames
    )
}

/// Cache file of a scene at resolution `n`.
pub fn cache_path(dir: &Path, scene: StudyScene, n: usize, stiffness: f64) -> PathBuf {
    let [a, b] = scene.resolution(n);
    dir.join("reference")
        .join(format!("{}_{a}x{b}_k{stiffness:e}.ref", scene.name()))
}

/// The reference of `scene` at resolution `n`: RK4 at `dt_level` (or finer if that is unstable).
pub fn reference(
    dir: &Path,
    scene: StudyScene,
    n: usize,
    stiffness: f64,
    horizon: &Horizon,
    dt_level: u32,
) -> Result<Reference, StudyError> {
    let path = cache_path(dir, scene, n, stiffness);
    let head = header(scene, n, stiffness, horizon, dt_level);
    if let Some(r) = read(&path, &head, horizon.sample_frames.len())? {
        return Ok(r);
    }
    for level in dt_level..=dt_level + RETRIES {
        let settings = RunSettings {
            scene,
            n,
            stiffness,
            integrator: IntegratorKind::Rk4,
            dt_level: level,
            cg_tolerance: 1e-10,
            cg_max_iterations: 1000,
            collision: None,
        };
        let out = run(&settings, horizon)?;
        if out.diverged.is_some() {
            log::warn!(
                "reference {} n={n}: RK4 unstable at level {level}, halving the step",
                scene.name()
            );
            continue;
        }
        let r = Reference {
            trajectory: out.trajectory,
            dt_level: level,
            vertices: out.vertices,
            cached: false,
        };
        write(&path, &head, &r)?;
        return Ok(r);
    }
    Err(StudyError::ReferenceDiverged {
        scene: scene.name().to_string(),
        n,
        dt_level: dt_level + RETRIES,
    })
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> StudyError + '_ {
    move |source| StudyError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn write(path: &Path, head: &str, r: &Reference) -> Result<(), StudyError> {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).map_err(io_err(parent))?;
    }
    let mut bytes = format!("{head} level={} vertices={}\n", r.dt_level, r.vertices).into_bytes();
    for (e, xs) in r.trajectory.energy.iter().zip(&r.trajectory.positions) {
        bytes.extend(e.to_le_bytes());
        for x in xs {
            for c in x.to_array() {
                bytes.extend(c.to_le_bytes());
            }
        }
    }
    Ok(crate::output::write(path, &bytes, &[])?)
}

/// Reads a cached reference; `None` if absent, stale or of the wrong length (it is then
/// recomputed). The file is read through [`crate::input`] (a regular file under the cache's
/// cap); the length the header implies is computed with overflow checks and compared with the
/// bytes present before anything is allocated, and a non-finite value is an error naming it.
fn read(path: &Path, head: &str, samples: usize) -> Result<Option<Reference>, StudyError> {
    let bytes = match crate::input::read_bytes(path, crate::input::InputKind::StudyCache) {
        Ok(b) => b,
        Err(crate::input::InputError::Open { source, .. })
            if source.kind() == std::io::ErrorKind::NotFound =>
        {
            return Ok(None)
        }
        Err(e) => return Err(e.into()),
    };
    let Some(nl) = bytes.iter().position(|&b| b == b'\n') else {
        return Ok(None);
    };
    let line = String::from_utf8_lossy(&bytes[..nl]);
    let Some(rest) = line.strip_prefix(head) else {
        log::info!("{}: stale reference, recomputing", path.display());
        return Ok(None);
    };
    let field = |key: &str| -> Option<usize> {
        rest.split_whitespace()
            .find_map(|kv| kv.strip_prefix(key))
            .and_then(|v| v.parse().ok())
    };
    let (Some(level), Some(vertices)) = (field("level="), field("vertices=")) else {
        return Ok(None);
    };
    let body = &bytes[nl + 1..];
    let expected = vertices
        .checked_mul(3)
        .and_then(|v| v.checked_add(1))
        .and_then(|v| v.checked_mul(samples))
        .and_then(|v| v.checked_mul(8));
    if expected != Some(body.len()) {
        log::warn!("{}: truncated reference, recomputing", path.display());
        return Ok(None);
    }
    let mut vals = body
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]));
    let bad = |what: String, sample: usize| StudyError::BadCache {
        path: path.to_path_buf(),
        what,
        sample,
    };
    let mut t = Trajectory::default();
    for s in 0..samples {
        let e = vals.next().unwrap_or(f64::NAN);
        if !e.is_finite() {
            return Err(bad("the energy".into(), s));
        }
        t.energy.push(e);
        let mut xs: Vec<Vec3> = Vec::with_capacity(vertices);
        for v in 0..vertices {
            let mut c = [0.0; 3];
            for x in &mut c {
                *x = vals.next().unwrap_or(f64::NAN);
            }
            if !c.iter().all(|x| x.is_finite()) {
                return Err(bad(format!("vertex {v}"), s));
            }
            xs.push(Vec3::from_array(c));
        }
        t.positions.push(xs);
    }
    Ok(Some(Reference {
        trajectory: t,
        dt_level: level as u32,
        vertices,
        cached: true,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cache(dir: &Path, head: &str, fields: &str, body: &[f64]) -> PathBuf {
        let p = dir.join("c.ref");
        let mut bytes = format!("{head} {fields}\n").into_bytes();
        for v in body {
            bytes.extend(v.to_le_bytes());
        }
        std::fs::write(&p, bytes).unwrap();
        p
    }

    #[test]
    fn hostile_caches_are_refused_or_recomputed() {
        let dir = tempfile::tempdir().unwrap();
        let head = "drape-study-reference v2 scene=x";
        // Two samples of one vertex: energy, x, y, z each.
        let good = [1.0, 0.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.5];
        let p = cache(dir.path(), head, "level=3 vertices=1", &good);
        let r = read(&p, head, 2).unwrap().unwrap();
        assert_eq!(r.trajectory.positions[1][0].z, 0.5);
        // A NaN sample is an error naming the file and the sample.
        let mut nan = good;
        nan[7] = f64::NAN;
        let p = cache(dir.path(), head, "level=3 vertices=1", &nan);
        let e = read(&p, head, 2).unwrap_err().to_string();
        assert!(
            e.contains("c.ref") && e.contains("vertex 0 of sample 1"),
            "{e}"
        );
        // A header claiming 2^61 vertices neither panics nor allocates: recomputed.
        let p = cache(
            dir.path(),
            head,
            "level=3 vertices=2305843009213693952",
            &good,
        );
        assert!(read(&p, head, 2).unwrap().is_none());
        // A FIFO or a device in its place is refused, not read.
        let e = read(Path::new("/dev/zero"), head, 2)
            .unwrap_err()
            .to_string();
        assert!(e.contains("/dev/zero"), "{e}");
    }
}
