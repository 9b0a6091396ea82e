//! Placement of a flat pattern in the world: a rigid transform, optionally after wrapping the
//! pattern onto a cylinder so that it starts close to its final shape around a torso or a limb.

use super::spec::PlacementSpec;
use crate::Vec3;
use glam::DVec2;

/// World position of pattern point `p`.
///
/// Flat: `pose * (x, y, 0)`. Wrapped on radius `r`: the pattern's x becomes arc length around a
/// cylinder whose axis is parallel to local y through `(0, *, -r)`, so `pose * (r sin(x/r), y,
/// r cos(x/r) - r)`: the point `x = 0` stays where the flat placement puts it, the panel curls
/// away from its normal (local +z), and lengths along x are kept (the wrap is an isometry).
pub fn place(placement: &PlacementSpec, p: DVec2) -> Vec3 {
    let local = match &placement.wrap {
        None => Vec3::new(p.x, p.y, 0.0),
        Some(w) => {
            let r = w.radius;
            let phi = p.x / r;
            Vec3::new(r * phi.sin(), p.y, r * phi.cos() - r)
        }
    };
    placement.pose.to_pose().transform_point(local)
}
