//! Free vertices arriving at a still solid within the coming substep: where the path their
//! start velocity predicts ends in a static solid's contact layer. The implicit solve holds
//! each with a one-sided spring on the layer's tangent plane (see `sim::coupling`), so a
//! vertex that whips in is stopped inside the solve, with its neighbours, instead of being
//! pushed back out alone by the response after it (which stretches its edges, and splits the
//! substep when the push exceeds a third of a spacing: S1 128x128's landing).

use super::motion::Motion;
use super::obstacle::Obstacle;
use super::stage::CollisionStage;
use crate::Vec3;

/// A free vertex whose predicted path ends in a static solid's contact layer, with the layer's
/// tangent plane where the path meets it (world).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arrival {
    pub vertex: u32,
    pub obstacle: usize,
    /// The solid's surface point and outward unit normal.
    pub point: Vec3,
    pub normal: Vec3,
    /// The vertex's contact thickness (m): the distance it keeps from the surface.
    pub gap: f64,
    /// Where the predicted path enters the layer (world).
    pub hit: Vec3,
    /// Whether Coulomb friction stops the vertex where it hits: its slip at most the
    /// coefficient times its approach speed (the impact's impulse ratio).
    pub sticks: bool,
}

impl CollisionStage {
    /// The vertices not `skip`ped whose straight path `x -> x + h v` over the substep ends in
    /// the contact layer of a static solid (or crosses into it) while they start clear of that
    /// layer, into `out` (one arrival per vertex: the deepest predicted end). Moving obstacles
    /// are left to fast-contact splitting, surfaces (two-sided) and half-spaces' far side to
    /// the response.
    pub fn arrivals(
        &self,
        x: &[Vec3],
        v: &[Vec3],
        h: f64,
        skip: impl Fn(usize) -> bool,
        out: &mut Vec<Arrival>,
    ) {
        out.clear();
        let still: Vec<(usize, &Obstacle)> = (self.obstacles.iter().enumerate())
            .filter(|(_, o)| matches!(o.motion, Motion::Static))
            .collect();
        if still.is_empty() {
            return;
        }
        let n = self.n_vertices.min(x.len()).min(v.len());
        for i in 0..n {
            if skip(i) {
                continue;
            }
            let th = self.thickness[i];
            let (a, b) = (x[i], x[i] + v[i] * h);
            if !(a.is_finite() && b.is_finite()) {
                continue;
            }
            let mut best: Option<(f64, Arrival)> = None;
            for &(k, o) in &still {
                let Some(((point, normal), hit, depth)) = arrival_at(o, a, b, th) else {
                    continue;
                };

                if best.is_none_or(|(d, _)| depth > d) {
                    // Coulomb's threshold on the impact: the normal impulse stops the approach,
                    // friction the slip if it is at most `mu` times that.
                    let (vn, vt) = (-v[i].dot(normal), v[i] - normal * v[i].dot(normal));
                    let arrival = Arrival {
                        vertex: i as u32,
                        obstacle: k,
                        point,
                        normal,
                        gap: th,
                        hit,
                        sticks: vt.length() <= self.friction_coefficient(i, k) * vn,
                    };
                    best = Some((depth, arrival));
                }
            }
            out.extend(best.map(|(_, a)| a));
        }
    }
}

/// Where the path `a -> b` (world) of a vertex of thickness `th` meets solid `o`'s contact
/// layer: the surface point and outward normal, the path's entry into the layer, and how deep
/// into the layer the path ends; `None` when it starts in the layer or inside (the stage's
/// contact, or a lead-out), ends clear, or does not head into the surface.
fn arrival_at(o: &Obstacle, a: Vec3, b: Vec3, th: f64) -> Option<((Vec3, Vec3), Vec3, f64)> {
    let (la, lb) = (
        o.pose.inverse_transform_point(a),
        o.pose.inverse_transform_point(b),
    );
    // The path's box against the solid's, grown by the layer.
    let (lo, hi) = (la.min(lb) - Vec3::splat(th), la.max(lb) + Vec3::splat(th));
    if lo.cmpgt(o.local_max).any() || hi.cmplt(o.local_min).any() {
        return None;
    }
    if o.contains_local(la) || o.in_layer(la, th).is_some() {
        return None;
    }
    // A path into the solid (or through it) meets the layer where it crosses the surface
    // first; one that ends in the layer, at the surface point under its end.
    let (point, normal, depth) = match o.cast_local(la, lb) {
        Some(hit) => (hit.point, hit.normal, th + (hit.point - lb).dot(hit.normal)),
        None => {
            let (normal, depth) = o.in_layer(lb, th)?;
            (o.closest_local(lb, lb).point, normal, depth)
        }
    };
    // Only a path that heads into the surface.
    if normal.dot(lb - la) >= 0.0 || !(point.is_finite() && normal.is_finite()) {
        return None;
    }
    // The entry into the layer, from the distances at both ends (exact on a plane).
    let (d0, d1) = (
        o.closest_local(la, la).signed_distance,
        o.closest_local(lb, la).signed_distance,
    );
    let s = if d0 > d1 {
        ((d0 - th) / (d0 - d1)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let world_normal = (o.pose.rotation * normal).normalize();
    Some((
        (o.pose.transform_point(point), world_normal),
        a + (b - a) * s,
        depth,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collide::CollisionSettings;
    use crate::Pose;

    fn ball_stage() -> CollisionStage {
        let ball = Obstacle::sphere(
            "ball",
            0.3,
            Pose::from_translation(Vec3::new(0.0, 0.0, 0.5)),
        )
        .expect("valid ball");
        CollisionStage::new(
            CollisionSettings::default(),
            vec![ball],
            Vec::new(),
            2,
            vec![0.005; 2],
            vec![0.5; 2],
        )
        .expect("valid stage")
    }

    #[test]
    fn a_vertex_whose_step_ends_in_the_layer_arrives_on_the_tangent_plane() {
        let stage = ball_stage();
        // Vertex 0 falls onto the ball's top at 3 m/s and ends 1 cm below its surface; vertex 1
        // falls beside it and stays clear.
        let x = [Vec3::new(0.0, 0.0, 0.84), Vec3::new(0.5, 0.0, 0.84)];
        let v = [Vec3::new(0.0, 0.0, -3.0), Vec3::new(0.0, 0.0, -3.0)];
        let mut out = Vec::new();
        stage.arrivals(&x, &v, 1.0 / 60.0, |_| false, &mut out);
        assert_eq!(out.len(), 1, "{out:?}");
        let a = out[0];
        assert_eq!((a.vertex, a.obstacle), (0, 0));
        assert!(
            (a.point - Vec3::new(0.0, 0.0, 0.8)).length() < 1e-9,
            "{a:?}"
        );
        assert!((a.normal - Vec3::Z).length() < 1e-9, "{a:?}");
        assert_eq!(a.gap, 0.005);
        // 3 m/s for a sixtieth: 5 cm from 0.84 to 0.79, entering the layer at 0.805; straight
        // in, so friction holds it there.
        assert!(
            (a.hit - Vec3::new(0.0, 0.0, 0.805)).length() < 1e-9,
            "{a:?}"
        );
        assert!(a.sticks, "{a:?}");
    }

    #[test]
    fn vertices_in_the_layer_moving_away_or_skipped_do_not_arrive() {
        let stage = ball_stage();
        let h = 1.0 / 60.0;
        let mut out = Vec::new();
        // Already in the layer (the stage's contact), and rising from the ball.
        let x = [Vec3::new(0.0, 0.0, 0.803), Vec3::new(0.0, 0.0, 0.81)];
        let v = [Vec3::new(0.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.0)];
        stage.arrivals(&x, &v, h, |_| false, &mut out);
        assert!(out.is_empty(), "{out:?}");
        // Falling in, but skipped (held by the filter, say).
        let x = [Vec3::new(0.0, 0.0, 0.84), Vec3::new(0.0, 0.0, 0.84)];
        let v = [Vec3::new(0.0, 0.0, -3.0); 2];
        stage.arrivals(&x, &v, h, |_| true, &mut out);
        assert!(out.is_empty(), "{out:?}");
    }
}
