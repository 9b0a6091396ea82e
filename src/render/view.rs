//! Where each bag is seen from: the sphere around everything drawn (cloth, robot, obstacles)
//! over the bag's drawn frames, and an azimuth that shows the cloth. Unless `--azimuth` is
//! given, a few azimuths are tried on small coverage renders and the one showing the most cloth
//! pixels wins; the default azimuth is kept unless another shows clearly more, so scenes whose
//! cloth is in plain view keep one familiar angle.

use super::frames::Frame;
use super::options::RenderOptions;
use super::raster::{Camera, Raster};
use crate::Vec3;

/// The azimuth used when the cloth shows about as well from it as from any other (degrees).
pub const DEFAULT_AZIMUTH: f64 = -60.0;
/// Azimuths tried, 45 degrees apart, starting at the default.
const CANDIDATES: usize = 8;
/// Another azimuth wins only when it shows this much more cloth than the default.
const CLEARLY_MORE: f64 = 1.15;
/// Side of the coverage renders (pixels) and most frames they sample.
const PROBE: usize = 64;
const PROBE_FRAMES: usize = 6;

/// How a bag's tiles are seen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Bounding sphere of the drawn meshes over the frames (planes left out: unbounded).
    pub center: Vec3,
    pub radius: f64,
    /// Degrees, from +x towards +y.
    pub azimuth: f64,
}

impl View {
    /// The camera of a `width` x `height` tile at `elevation` degrees.
    pub fn camera(&self, elevation: f64, width: usize, height: usize) -> Camera {
        Camera::framing(
            self.center,
            self.radius,
            self.azimuth.to_radians(),
            elevation.to_radians(),
            width,
            height,
        )
    }
}

/// The box around the meshes of frames added one at a time (planes left out: unbounded).
#[derive(Debug, Clone, Copy)]
pub(super) struct Extent {
    lo: Vec3,
    hi: Vec3,
}

impl Extent {
    pub fn new() -> Extent {
        Extent {
            lo: Vec3::splat(f64::INFINITY),
            hi: Vec3::splat(f64::NEG_INFINITY),
        }
    }

    pub fn add(&mut self, f: &Frame) {
        for m in &f.meshes {
            for p in &m.positions {
                if p.is_finite() {
                    self.lo = self.lo.min(*p);
                    self.hi = self.hi.max(*p);
                }
            }
        }
    }

    /// Centre and radius of the bounding sphere (a unit sphere at the origin when empty).
    pub fn sphere(&self) -> (Vec3, f64) {
        if !self.lo.is_finite() {
            return (Vec3::ZERO, 1.0);
        }
        let c = (self.lo + self.hi) / 2.0;
        (c, ((self.hi - self.lo).length() / 2.0).max(0.05))
    }
}

/// Bounding sphere of the meshes of some frames (planes left out: unbounded).
pub fn bounds(frames: &[Frame]) -> (Vec3, f64) {
    let mut e = Extent::new();
    for f in frames {
        e.add(f);
    }
    e.sphere()
}

/// The view of a bag drawn as `frames`: `o.azimuth` if given, else the chosen one.
pub fn view(frames: &[Frame], o: &RenderOptions) -> View {
    view_of(bounds(frames), frames, o)
}

/// [`view`] with the sphere already known (`frames` may be a sample of the drawn ones).
pub(super) fn view_of((center, radius): (Vec3, f64), frames: &[Frame], o: &RenderOptions) -> View {
    let mut v = View {
        center,
        radius,
        azimuth: o.azimuth.unwrap_or(DEFAULT_AZIMUTH),
    };
    if o.azimuth.is_none() {
        v.azimuth = showing_most_cloth(v, frames, o.elevation);
    }
    v
}

/// Of the candidate azimuths, the one whose coverage renders of (a sample of) `frames` show
/// the most cloth pixels; the default unless another shows [`CLEARLY_MORE`].
fn showing_most_cloth(v: View, frames: &[Frame], elevation: f64) -> f64 {
    let step = frames.len().div_ceil(PROBE_FRAMES).max(1);
    let sample: Vec<&Frame> = frames.iter().step_by(step).collect();
    let score = |azimuth: f64| -> usize {
        let cam = View { azimuth, ..v }.camera(elevation, PROBE, PROBE);
        sample
            .iter()
            .map(|f| {
                let mut r = Raster::new(PROBE, PROBE, &cam);
                for m in &f.meshes {
                    r.draw(&cam, m);
                }
                let cloth = f.cloths as u32;
                r.owners().iter().filter(|&&k| k >= 1 && k <= cloth).count()
            })
            .sum()
    };
    let default = score(DEFAULT_AZIMUTH);
    let (mut best, mut best_score) = (DEFAULT_AZIMUTH, default);
    for k in 1..CANDIDATES {
        let azimuth = DEFAULT_AZIMUTH + 360.0 * k as f64 / CANDIDATES as f64;
        let s = score(azimuth);
        if s > best_score {
            (best, best_score) = (azimuth, s);
        }
    }
    if best_score as f64 > CLEARLY_MORE * default as f64 {
        best
    } else {
        DEFAULT_AZIMUTH
    }
}
