//! Arrival springs: free vertices whose start velocity carries them into a static solid's
//! contact layer within the substep are stopped on the layer's tangent plane inside the solve,
//! anchored where their path hit it when friction stops them there; their normal impulse goes
//! out as the stage's friction bound.

use super::edge_springs::CONTACT_STIFFNESS;
use super::{Coupling, StartState};
use crate::cloth::Cloth;
use crate::collide::CollisionStage;
use crate::integrate::{Capabilities, ContactSpring};
use crate::linalg::Filter;

/// `k h^2 / m` of the tangential anchor that holds an arriving vertex friction stops where its
/// path hit the layer (see `Coupling::arrival_springs`): it leaves a hundredth of the slip the
/// step would have carried it on by (a patch landing on a slope it sticks to,
/// `tests/landing.rs`). As stiff as the normal spring ([`CONTACT_STIFFNESS`]), the anchors hold
/// against the pull of a whipping border and stretch its edges further (S1 64x64 in
/// `cargo bench --bench contact`).
const ANCHOR_STIFFNESS: f64 = 100.0;

impl Coupling {
    /// Free vertices whose start velocity carries them into a static solid's contact layer
    /// within this substep (see [`CollisionStage::arrivals`]) get a one-sided spring on the
    /// layer's tangent plane, as stiff as an edge's: the solve stops them at the layer with
    /// their neighbours, where the response would push them back alone after it. A spring acts
    /// only while the solved step ends inside the layer (the active set, see [`ContactSpring`]).
    /// One that Coulomb friction stops where it hits is anchored there in the tangent plane
    /// too (see [`ANCHOR_STIFFNESS`]); a sliding one's friction is the stage's, after the
    /// solve. Vertices the last pass touched (held or released) are the stage's, as are those
    /// starting in a solid or its layer.
    pub(super) fn arrival_springs(
        &mut self,
        stage: Option<&CollisionStage>,
        s: &StartState,
        caps: &Capabilities,
    ) {
        self.arrivals.clear();
        self.arrival_springs.clear();
        let Some(stage) = stage.filter(|_| caps.solves_contacts) else {
            return;
        };
        let n = s.cloth.len();
        self.touched.clear();
        self.touched.resize(n, false);
        for c in stage.contacts() {
            if let Some(t) = self.touched.get_mut(c.vertex as usize) {
                *t = true;
            }
        }
        let (filter, touched) = (&self.constraints.filter, &self.touched);
        let skip = |i: usize| filter[i] != Filter::Free || touched[i];
        let mut arrivals = std::mem::take(&mut self.arrivals);
        stage.arrivals(&s.cloth.x, &s.cloth.v, s.h, skip, &mut arrivals);
        let h = s.h_scene;
        for a in &arrivals {
            let i = a.vertex;
            let spring = ContactSpring {
                verts: [i; 4],
                weights: [1.0, 0.0, 0.0, 0.0],
                normal: a.normal,
                point: a.point,
                gap: a.gap,
                stiffness: CONTACT_STIFFNESS * s.cloth.mass[i as usize] / (h * h),
                friction: 0.0,
            };
            // An invalid spring (non-finite input) keeps its slot; the solver leaves it unused.
            self.arrival_springs.push(self.constraints.contacts.len());
            self.constraints.contacts.push(spring);
            if a.sticks {
                // Friction stops it where it hits: anchored there along the tangent plane by
                // two opposed one-sided springs per direction (the active set keeps the one on
                // the side the vertex ends), so the solve ends it there, neighbours included.
                let (t1, t2) = a.normal.any_orthonormal_pair();
                for t in [t1, -t1, t2, -t2] {
                    self.constraints.contacts.push(ContactSpring {
                        normal: t,
                        point: a.hit,
                        gap: 0.0,
                        stiffness: ANCHOR_STIFFNESS * spring.stiffness / CONTACT_STIFFNESS,
                        ..spring
                    });
                }
            }
        }
        self.arrivals = arrivals;
    }

    /// Arrival springs that ended acting: their normal impulse per unit mass counts in the
    /// stage's friction bound, as a held vertex's does (substep `h`).
    pub(super) fn arrival_feedback(&mut self, cloth: &Cloth, h: f64) {
        let n = cloth.len();
        for (a, f) in self.arrivals.iter().zip(&self.arrival_forces) {
            let i = a.vertex as usize;
            if *f > 0.0 && i < n {
                self.feedback.hold(i, a.normal, f * h / cloth.mass[i]);
            }
        }
    }
}
