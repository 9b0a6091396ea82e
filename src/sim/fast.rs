//! Fast contact: whether an obstacle moves too far relative to the cloth near it within one
//! substep for the collision stage to follow (then the substep is split in two, recursively,
//! so the split falls where the obstacle meets the cloth), and the fastest obstacle point for
//! the guard's strain bound.
//!
//! The collision stage answers a substep after the solve, by position: a vertex the obstacle
//! reached is put on its surface with its velocity, and the solver only sees that contact in the
//! next substep. When a link moves a good part of the cloth spacing in one substep, that
//! position jump is a strain the solver never had a say in (a rod at 20 m/s moves 13 spacings of
//! a 2.6 cm sheet in a 60 Hz step), and the cloth between the vertices it touched is no longer
//! where the edge and feature tests assumed it. So, conservatively advancing against the
//! obstacle's motion: over a substep of `h`, the obstacle's material point at vertex `i` moves by
//! `d_o = T(x_i) - x_i` (`T` the rigid motion from the substep's start pose to its end pose) and
//! the vertex by about `v_i h`; when `|d_o - v_i h|` exceeds [`REACH`] times the local spacing
//! for a vertex within reach of the obstacle, the substep is split. Cloth carried by the link
//! moves with it and asks for nothing; static obstacles are skipped, so scenes without moving
//! obstacles do exactly what they did.

use crate::cloth::Cloth;
use crate::collide::Obstacle;
use crate::{Pose, Vec3};

/// Largest motion of an obstacle relative to the cloth near it within one substep, in local
/// cloth spacings. A vertex the obstacle reaches is put on its surface after the solve (the
/// solver holds it from the next substep on), so the jump stretches its edges by up to this
/// fraction; a third keeps the carried cloth of the issue-18 sheet within `1 + v / c` of the
/// impact at 5 and 20 m/s (measured in `tests/fast_links.rs`: a half let a 5 m/s rod stretch
/// edges to 1.27, a tenth cost three times the substeps for no gain).
pub(super) const REACH: f64 = 1.0 / 3.0;

/// How far around the obstacle a vertex is within reach, in the cloth's longest spacing (plus
/// the thickness): two rings of edges. The vertices next to the ones a link carries trail
/// behind it until the solve takes them along; with one ring a substep long enough to carry
/// the cloth 1.5 spacings was allowed as soon as the first row moved with the link, and the
/// solve left the trailing edges 1.19 times their length at 5 m/s.
pub(super) const REACH_RINGS: f64 = 2.0;

/// The start and end pose of obstacle `o` over the substep `[t, t + h]` at frame fractions
/// `s0..s1` (`target`: its frame's start and end pose when driven from outside).
pub(super) fn substep_poses(
    o: &Obstacle,
    target: Option<&(Pose, Pose)>,
    (t, h): (f64, f64),
    (s0, s1): (f64, f64),
) -> (Pose, Pose) {
    if o.motion.is_scripted() {
        (
            o.motion.pose_at(&o.initial_pose, t),
            o.motion.pose_at(&o.initial_pose, t + h),
        )
    } else {
        match target {
            Some((a, b)) => (a.lerp(b, s0), a.lerp(b, s1)),
            None => (o.pose, o.pose),
        }
    }
}

/// The obstacle's local bounding box corners (none for unbounded shapes).
fn corners(o: &Obstacle) -> Option<[Vec3; 8]> {
    let (lo, hi) = o.local_bounds();
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    Some(std::array::from_fn(|k| {
        Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        )
    }))
}

/// The fastest point of the obstacle's bounding box over a substep from pose `a` to `b` (m/s).
pub(super) fn top_speed(o: &Obstacle, (a, b): (Pose, Pose), h: f64) -> f64 {
    if a == b || h <= 0.0 {
        return 0.0;
    }
    match corners(o) {
        Some(c) => {
            c.iter()
                .map(|p| b.transform_point(*p).distance(a.transform_point(*p)))
                .fold(0.0, f64::max)
                / h
        }
        // A moving plane: its origin's speed (its motion along itself does nothing).
        None => b.translation.distance(a.translation) / h,
    }
}

/// Whether obstacle `o`, moving from pose `a` to `b` over a substep of `h`, moves more than
/// [`REACH`] local spacings (`spacing(i)`) relative to a cloth vertex within reach of it.
/// `pad`: how far from the obstacle's swept box a vertex counts as within reach (m).
pub(super) fn outruns(
    o: &Obstacle,
    (a, b): (Pose, Pose),
    cloth: &Cloth,
    h: f64,
    pad: f64,
    spacing: impl Fn(usize) -> f64,
) -> bool {
    if a == b {
        return false;
    }
    let (lo, hi) = match corners(o) {
        Some(c) => {
            let mut lo = Vec3::splat(f64::INFINITY);
            let mut hi = Vec3::splat(f64::NEG_INFINITY);
            for p in c
                .iter()
                .flat_map(|p| [a.transform_point(*p), b.transform_point(*p)])
            {
                lo = lo.min(p);
                hi = hi.max(p);
            }
            (lo - Vec3::splat(pad), hi + Vec3::splat(pad))
        }
        None => (Vec3::splat(f64::NEG_INFINITY), Vec3::splat(f64::INFINITY)),
    };
    // The rigid motion over the substep, world to world.
    let motion = b.mul(&a.inverse());
    cloth.x.iter().zip(&cloth.v).enumerate().any(|(i, (x, v))| {
        if x.cmplt(lo).any() || x.cmpgt(hi).any() {
            return false;
        }
        let relative = motion.transform_point(*x) - *x - *v * h;
        relative.length() > REACH * spacing(i)
    })
}
