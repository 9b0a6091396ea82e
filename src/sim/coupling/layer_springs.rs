//! Layers of cloth resting on each other: a vertex over a face of another layer is held apart
//! from it inside the solve by a one-sided vertex-face spring, whose forces on the two sides are
//! equal and opposite.

use super::{Coupling, StartState};
use crate::collide::CollisionStage;
use crate::integrate::{Capabilities, ContactSpring};
use crate::linalg::Filter;
use crate::Vec3;

/// `k h^2 / m` of a layer spring at its point's mass `m` and the scene's substep: a load of its
/// own weight deflects it by `g h^2 / 100`, 0.03 mm at 60 Hz. As stiff as a static edge's
/// ([`CONTACT_STIFFNESS`](super::edge_springs::CONTACT_STIFFNESS)), the springs take many more
/// CG iterations to solve a cloth lying on itself (sphere_drape.yaml, a crumple), for about the
/// same stretch.
const LAYER_STIFFNESS: f64 = 100.0;

/// A layer spring's rest length in contact distances: a little beyond the repulsion's, so that a
/// pair the spring holds under a load of a few times its weight (`g h^2 / 50` a substep, 0.05
/// mm at 60 Hz against a 10 mm distance) stays out of the repulsion's reach. At the contact
/// distance itself, the repulsion would answer every resting pair every substep, and its
/// averaged moves, which do not conserve momentum, take part of a towel's weight off the
/// hammock under it (`tests/resting_layers.rs`).
const LAYER_REST: f64 = 1.02;

/// How much of its contact distance a layer spring may restore in one substep: a pair found
/// deep gets the rest of the way over the next substeps, not as speed, `deficit / h`, at once.
const RESTORE: f64 = 0.1;

impl Coupling {
    /// Layers of cloth resting on each other in the last collision pass (a vertex over a face of
    /// another layer, [`crate::collide::SelfTouch`]) become one-sided springs of this substep
    /// between the vertex and the face's point under it (`x_p - sum b_i x_i` along the face's
    /// normal), when the integrator solves springs. The solve then carries a layer's support
    /// into the cloth around the vertex, instead of moving the vertex into the layer for the
    /// repulsion to push back alone, and the vertex's weight into the layer under it: the
    /// spring's forces on its two sides are equal and opposite. A pair closer than its contact
    /// distance is held where it is: pushed apart within the solve, the deficit would leave as
    /// speed, `deficit / h`, where the repulsion moves positions only. Stiffness
    /// [`LAYER_STIFFNESS`] at the pair's effective mass. A vertex and a face of another layer
    /// share no block of the matrix: the spring's Jacobian is lumped onto the diagonal there
    /// ([`ContactSpring::add_jacobian`]) and completed in the solver's products
    /// (`integrate::contact::OffPattern`).
    ///
    /// Why one spring between the vertex and the face (shown by chair.yaml, a cloth folding
    /// over the seat's front edge, and a towel on a hammock, `tests/resting_layers.rs`): a
    /// spring on each side, anchored on where the other side goes at the pair's common
    /// velocity, holds both sides still against each other's ghost: the lower layer's own
    /// tension, pushing up, goes into the ghost, so the hammock carries more than the towel's
    /// weight and bows only under a load added for it. With the anchors moved by gravity's pull
    /// over the substep as well, a lower layer held up by the cloth's tension (not an obstacle)
    /// is pushed down by `g h^2` a substep at many times its weight: chair's cloth slides off
    /// the seat. A vertex spring alone, with its last force as the face's load, carries into
    /// that load whatever holds the vertex up (the seat under a face, thousands of times its
    /// weight) and throws the face.
    ///
    /// Each spring carries Coulomb friction on the pair's relative velocity, the vertex's
    /// against the face point's under it (`v_p - sum b_i v_i` in the face's tangent plane),
    /// when the integrator solves friction: its limit is `mu` times the force the vertex's layer
    /// springs ended the last substep with (shared among its springs of this substep, so the
    /// load stays with a vertex sliding from face to face), spread by the spring's weights, so the friction
    /// forces on the two layers are equal and opposite like the normal ones. Why in the solve:
    /// a resting pair is held at [`LAYER_REST`] contact distances, out of the repulsion's reach,
    /// so the repulsion's friction never acts on cloth resting on cloth, and a napkin on a towel
    /// slid on as if on ice. A new pair (no force yet) has the repulsion's friction that substep.
    pub(super) fn layer_springs(
        &mut self,
        stage: Option<&CollisionStage>,
        s: &StartState,
        caps: &Capabilities,
    ) {
        let Some(stage) = stage.filter(|_| caps.solves_contacts) else {
            return;
        };
        let (x, mass, filter) = (&s.cloth.x, &s.cloth.mass, &self.constraints.filter);
        let mu = &s.cloth.friction;
        let lagged = &self.layer_forces;
        let n = x.len();
        let k = LAYER_STIFFNESS / (s.h_scene * s.h_scene);
        let touches = stage.self_touches();
        // A vertex's springs this substep, which share its lagged normal force (touches are
        // sorted by vertex).
        let springs_of = |v: u32| {
            let from = touches.partition_point(|t| t.vertex < v);
            touches[from..]
                .iter()
                .take_while(|t| t.vertex == v)
                .count()
                .max(1)
        };
        for t in touches {
            let [a, b, c] = t.triangle;
            let [wa, wb, wc] = t.bary;
            let mut spring = ContactSpring {
                verts: [t.vertex, a, b, c],
                weights: [1.0, -wa, -wb, -wc],
                normal: t.normal,
                point: Vec3::ZERO,
                gap: 0.0,
                stiffness: 0.0,
                friction: 0.0,
            };
            if !spring.verts.iter().all(|&i| (i as usize) < n)
                || spring.slots().all(|(i, _)| filter[i] == Filter::Fixed)
            {
                continue;
            }
            spring.gap = (spring.along(x) + RESTORE * t.gap).min(LAYER_REST * t.gap);
            spring.stiffness = k * spring.point_mass(mass);
            if caps.solves_friction {
                let normal_force = lagged
                    .binary_search_by(|l| l.0.cmp(&t.vertex))
                    .map_or(0.0, |k| lagged[k].1 / springs_of(t.vertex) as f64);
                spring.friction = pair_friction(&spring, mu) * normal_force;
            }
            if spring.is_valid(n) && spring.gap > 0.0 {
                self.constraints.contacts.push(spring);
            }
        }
    }
}

/// The Coulomb coefficient of a vertex-face pair: the mean of the vertex's and the face point's
/// (its vertices' by barycentric weight), as the repulsion takes it (`self_contact::proximity`).
fn pair_friction(spring: &ContactSpring, mu: &[f64]) -> f64 {
    let (sum, weight) = spring.slots().fold((0.0, 0.0), |(s, w), (i, c)| {
        (s + mu.get(i).copied().unwrap_or(0.0) * c.abs(), w + c.abs())
    });
    if weight > 0.0 {
        sum / weight
    } else {
        0.0
    }
}
