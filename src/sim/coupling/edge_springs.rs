//! Obstacle edges, corners and rod axes that touch the cloth between vertices, as one-sided
//! springs of the solve: a static feature's at the scene's substep with in-solve friction from
//! its lagged end force, a moving feature's at this substep, aimed at where the feature will be
//! at its end.

use super::{Coupling, StartState};
use crate::collide::{CollisionStage, FEATURE_DEEP};
use crate::integrate::{Capabilities, ContactSpring};
use crate::linalg::Filter;

/// `k h^2 / m` of an edge spring at the contact point's mass `m`: the spring stops the point
/// within a step, and a load of the cloth's own weight per vertex deflects it by `g h^2 / 1e3`
/// (a micrometre at 120 Hz). A spring as stiff as the cloth's stiffest mode (`m omega^2`, far
/// stiffer) turns the re-detection's drift of micrometres into newtons and slows a frictionless
/// strip sliding over the edge (`tests/table_edge.rs`).
pub(super) const CONTACT_STIFFNESS: f64 = 1e3;

/// `k h^2 / m` of a moving feature's spring, at the (split) substep's `h`: implicit Euler leaves
/// `1 / (1 + k h^2 / m)` of the contact's gap, 0.5 % here. Fast-contact splitting keeps a link's
/// move within a substep to a third of the cloth's spacing, so what is left (0.04 mm at 2.6 cm
/// spacing) is far below any cloth's thickness. Unlike a static edge's spring (at the scene's
/// substep, small in a split one), this term is as large in the matrix as the spring says: a
/// stiffer one costs many more CG iterations a frame on a thin rod moving fast
/// (`benches/fast_links.rs`), and holds the cloth no better: the cloth does not cross the rod
/// at either stiffness (`tests/fast_links.rs`), and this one stretches its edges less.
const MOVING_CONTACT_STIFFNESS: f64 = 200.0;

impl Coupling {
    /// Obstacle edges and corners the cloth touched in the last collision pass (a moving one's
    /// aimed at the end of this substep, without friction) become
    /// one-sided springs of this substep when the integrator solves them (see
    /// [`ContactSpring`]), with in-solve Coulomb friction whose limit is `mu` times the force
    /// the same contact's spring ended the last substep with, shared by weight. The stage then
    /// leaves those contacts to the solver unless they end deep.
    pub(super) fn edge_springs(
        &mut self,
        stage: Option<&CollisionStage>,
        s: &StartState,
        caps: &Capabilities,
    ) {
        self.constraints.contacts.clear();
        self.constraints.front_strain.clear();
        self.moving_springs.clear();
        self.layers_from = 0;
        if !caps.solves_contacts {
            return;
        }
        // The scene's substep, not a subdivided one: a spring stiffened by `1 / h^2` as the guard
        // halves the step would only store more energy in a contact that is already deep.
        let h = s.h_scene;
        let n = s.cloth.len();
        let Some(stage) = stage else {
            return;
        };
        let (mass, filter) = (&s.cloth.mass, &self.constraints.filter);
        let lagged = &self.spring_forces;
        let mut sprung = Vec::new();
        let mut seen = std::collections::HashSet::new();
        for c in stage.feature_contacts() {
            // A face or edge answered in two passes is one contact: keep the first.
            if c.verts.iter().any(|&v| v as usize >= n) || !seen.insert(c.verts) {
                continue;
            }
            let [a, b, d] = c.verts;
            let [wa, wb, wd] = c.weights;
            let mut spring = ContactSpring {
                verts: [a, b, d, d],
                weights: [wa, wb, wd, 0.0],
                normal: c.normal,
                point: c.point,
                gap: c.gap,
                stiffness: 0.0,
                friction: 0.0,
            };
            // `k h^2 / m` at the contact point's mass. A moving feature's spring is stiff for
            // this substep (split where a link moves fast): it must carry the cloth with the
            // link within the substep, not within a scene substep's time.
            let (h, k) = if c.moving {
                (s.h, MOVING_CONTACT_STIFFNESS)
            } else {
                (h, CONTACT_STIFFNESS)
            };
            let m: f64 = spring.slots().map(|(i, w)| w * mass[i]).sum();
            spring.stiffness = k * m / (h * h);
            let movable = spring.slots().any(|(i, _)| filter[i] != Filter::Fixed);
            // A contact already deep (cloth pinched below its thickness under a press that
            // stopped) stays with the collision stage's pinch and push: as a spring it would
            // start with a large stored force, released within one step.
            let deep = spring.depth(&s.cloth.x) > (1.0 - FEATURE_DEEP) * c.gap;
            // A moving feature holds the cloth where it will be at the substep's end.
            (spring.point, spring.normal) = (c.end_point, c.end_normal);
            if !spring.is_valid(n) || !movable || deep {
                continue;
            }
            // The normal force of the last solve's spring on this face or edge (none for a new
            // contact: the collision stage gave it friction): the start depth holds the
            // re-detection's drift, micrometres that the stiff spring turns into newtons.
            let normal_force = lagged
                .binary_search_by(|l| l.0.cmp(&spring.verts))
                .map_or(0.0, |k| lagged[k].1);
            if caps.solves_friction {
                spring.friction = c.mu * normal_force;
            }
            sprung.push(c.verts);
            if c.moving {
                self.moving_springs.push(self.constraints.contacts.len());
            }
            self.constraints.contacts.push(spring);
        }
        self.feedback.set_sprung(sprung);
        self.front.strain(
            s.cloth,
            &self.constraints.contacts,
            &self.moving_springs,
            s.h,
            &mut self.constraints.front_strain,
        );
    }
}
