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
//! for a vertex within the obstacle's reach (see [`outruns`]), the substep is split. Cloth
//! carried by the link moves with it and asks for nothing; static obstacles are skipped here.
//!
//! What the prediction cannot see is cloth the solve drives into an obstacle (a towel swinging
//! into a still arm, cloth landing on a seat): the same position jump, measured after the pass
//! instead of predicted ([`jumped`]); the step rolls such a substep back and splits it within the
//! same levels. A scene whose cloth meets nothing faster than a third of its spacing per substep
//! does exactly what it did.

use crate::cloth::Cloth;
use crate::collide::Obstacle;
use crate::{Pose, Vec3};

/// Largest motion of an obstacle relative to the cloth near it within one substep, in local
/// cloth spacings. A vertex the obstacle reaches is put on its surface after the solve (the
/// solver holds it from the next substep on), so the jump stretches its edges by up to this
/// fraction; a third keeps the cloth a rod carries within the impact strain `1 + v / c`
/// (`tests/fast_links.rs`), where a half does not and a tenth costs substeps for no gain.
pub(super) const REACH: f64 = 1.0 / 3.0;

/// How far around an obstacle that touches the cloth a vertex is within reach, in the cloth's
/// longest spacing (plus the thickness): two rings of edges. The vertices next to the ones a
/// link carries trail behind it until the solve takes them along; with one ring a substep long
/// enough to carry the cloth 1.5 spacings was allowed as soon as the first row moved with the
/// link, and the solve left the trailing edges stretched beyond the impact bound; so does
/// allowing the second ring twice the motion (its edges share it).
pub(super) const REACH_RINGS: f64 = 2.0;

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

/// How far from an obstacle a cloth vertex is within its reach over one substep.
#[derive(Debug, Clone, Copy)]
pub(super) struct Reach {
    /// The cloth's largest thickness (m): the layer a vertex is met at.
    pub thickness: f64,
    /// The cloth's largest rest spacing (m).
    pub spacing: f64,
}

impl Reach {
    /// The distance around an obstacle that touches the cloth within which vertices trail the
    /// ones it carries ([`REACH_RINGS`] spacings beyond the layer).
    fn trailing(&self) -> f64 {
        self.thickness + REACH_RINGS * self.spacing
    }
}

/// Whether obstacle `o`, moving from pose `a` to `b` over a substep of `h`, moves more than
/// [`REACH`] local spacings (`spacing(i)`) relative to a cloth vertex within its reach.
///
/// A vertex is within reach when the obstacle's motion relative to it could bring it to the
/// vertex's layer within the substep (its start distance, less the thickness, is at most that
/// motion) or, while the obstacle touches the cloth (a vertex within a spacing of its layer),
/// to the vertices that trail the ones it carries ([`Reach::trailing`]). Cloth the link carries
/// along far ahead of it (a towel's flaps swinging around a bar) is not: counted by the swept
/// box alone, such vertices would split substeps for cloth no obstacle is about to meet
/// (`benches/fast_links.rs` measures the substeps). `near` is scratch.
pub(super) fn outruns(
    o: &Obstacle,
    (a, b): (Pose, Pose),
    cloth: &Cloth,
    h: f64,
    reach: Reach,
    spacing: impl Fn(usize) -> f64,
    near: &mut Vec<(usize, f64, f64)>,
) -> bool {
    if a == b {
        return false;
    }
    let pad = reach.trailing();
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
    // The vertices in the padded swept box: (vertex, start distance to the surface, how far the
    // obstacle moves relative to it).
    near.clear();
    near.extend(
        (cloth.x.iter().zip(&cloth.v).enumerate())
            .filter(|(_, (x, _))| !(x.cmplt(lo).any() || x.cmpgt(hi).any()))
            .map(|(i, (x, v))| {
                let local = a.inverse_transform_point(*x);
                let distance = o.closest_local(local, local).signed_distance;
                let relative = motion.transform_point(*x) - *x - *v * h;
                (i, distance, relative.length())
            }),
    );
    let touching = (near.iter()).any(|&(_, d, _)| d <= reach.thickness + reach.spacing);
    let within = if touching { pad } else { reach.thickness };
    near.iter()
        .any(|&(i, d, moved)| d - within <= moved && moved > REACH * spacing(i))
}

/// Whether the collision pass moved a vertex it answered for an obstacle (`by_obstacle`) more
/// than [`REACH`] of its local spacing (`spacing`) from where the solve left it (`solved`), to
/// `x`: the vertex jumped while its neighbours stayed, stretching its edges by up to that
/// fraction. [`outruns`] predicts this for links; cloth the solve drives into a still obstacle
/// (a towel swinging into an arm, cloth landing on a seat) is only seen here, once
/// the pass has answered it. Only the vertices that jumped are asked about their contact.
pub(super) fn jumped(
    solved: &[Vec3],
    x: &[Vec3],
    spacing: impl Fn(usize) -> f64,
    by_obstacle: impl Fn(usize) -> bool,
) -> bool {
    (solved.iter().zip(x).enumerate())
        .any(|(i, (a, b))| a.distance(*b) > REACH * spacing(i) && by_obstacle(i))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::{Material, Panel};

    /// A 20 cm sheet of 9 x 9 vertices (2.5 cm spacing) in the world x-z plane at y = `y`,
    /// moving along y at `speed`.
    fn sheet(y: f64, speed: f64) -> Cloth {
        let pose = Pose::new(
            Vec3::new(0.0, y, 0.0),
            glam::DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2),
        );
        let mut cloth = Cloth::new();
        cloth.add_panel(
            Panel::grid("s", [0.2, 0.2], [9, 9], &pose),
            Material::default(),
        );
        cloth
            .v
            .iter_mut()
            .for_each(|v| *v = Vec3::new(0.0, speed, 0.0));
        cloth
    }

    /// Whether a 5 mm rod along x, moving along y from `start` by `dy` over `h`, outruns
    /// `cloth`.
    fn rod_outruns(cloth: &Cloth, start: Vec3, dy: f64, h: f64) -> bool {
        let rod = Obstacle::capsule("rod", 0.0025, 0.5, Pose::IDENTITY).expect("valid capsule");
        let along_x = glam::DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
        let a = Pose::new(start, along_x);
        let b = Pose::new(start + Vec3::new(0.0, dy, 0.0), along_x);
        let reach = Reach {
            thickness: 0.004,
            spacing: 0.025,
        };
        outruns(&rod, (a, b), cloth, h, reach, |_| 0.025, &mut Vec::new())
    }

    #[test]
    fn a_link_splits_where_it_reaches_cloth_it_outruns() {
        let at = |y: f64, z: f64| Vec3::new(0.0, y, z);
        // Still cloth 5 cm ahead: a 1 cm move cannot reach it, a 6 cm move does.
        let still = sheet(0.05, 0.0);
        assert!(!rod_outruns(&still, at(0.0, 0.0), 0.01, 0.001));
        assert!(rod_outruns(&still, at(0.0, 0.0), 0.06, 0.001));
        // A rod between two rows of the sheet touches it: its trailing rings count, so moving
        // half a spacing across the sheet splits.
        assert!(rod_outruns(
            &sheet(0.0, 0.0),
            at(0.0, 0.0125),
            0.0125,
            0.001
        ));
        // Cloth 13 cm ahead moving nearly with the rod (a flap it swings): within the swept box,
        // out of reach.
        let flap = sheet(0.13, 9.0);
        assert!(!rod_outruns(&flap, at(0.0, 0.0), 0.1, 0.01));
        // Cloth moving with the rod is never outrun.
        let carried = sheet(0.0, 10.0);
        assert!(!rod_outruns(&carried, at(0.0, 0.0125), 0.1, 0.01));
    }
}
