//! The order of self-collision in one step, per detection mode: proximity repulsion passes,
//! then (continuous) bounded CCD passes and the impact-zone fail-safe.

use super::collider::SelfCollider;
use super::report::SelfContactReport;
use crate::collide::settings::{CollisionSettings, DetectionMode};
use crate::Vec3;

/// Vertices touching an obstacle respond to cloth-cloth position corrections as if this much
/// heavier, so the cloth on top gives way rather than the layer pressed against the obstacle.
/// Velocities are answered by impulses at the true masses (`impulses`), which conserve the
/// layers' momentum.
const CONTACT_MASS_FACTOR: f64 = 10.0;

/// Repulsion passes on the first substep (continuous mode), each on the first one's candidates
/// (those with a changed vertex), until every pair is settled. One pass leaves a springless
/// layer resting inside its contact distance (`tests/collide_self.rs`); many passes stretch the
/// flag's and the 2x crumple's edges, where three (with the weighted mean of `jacobi`) hold
/// them. Answering only the pairs the first pass found close would overstretch the 2x crumple
/// and leave crossings to CCD.
const REPULSION_PASSES: usize = 3;

pub(crate) struct SelfOutcome {
    pub unresolved: usize,
    pub report: SelfContactReport,
}

/// What the caller does with the repulsion's answers before the CCD passes of continuous
/// detection: `repelled(before, x)`, with `before` the positions the repulsion started from (the
/// simulation holds them to a stretch bound there, `sim::limit::ResponseBound`). Repulsion keeps
/// layers a contact distance apart, which the next solve's layer springs also do; CCD and the
/// impact zones after it keep them from crossing whatever the hook took back. The proximity and
/// sphere modes have no CCD after their repulsion, which is all that keeps their layers apart:
/// they do not call it.
pub(crate) type Repelled<'a> = &'a mut dyn FnMut(&[Vec3], &mut [Vec3]);

impl SelfCollider {
    /// Cloth against itself: repulsion; in continuous mode (repulsion on a step's first pass
    /// only) `repelled` on its answers, then bounded CCD passes and the impact-zone fail-safe.
    #[allow(clippy::too_many_arguments)]
    pub fn resolve(
        &mut self,
        settings: &CollisionSettings,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        inv_mass: &[f64],
        thickness: &[f64],
        friction: &[f64],
        in_contact: &[bool],
        h: f64,
        first: bool,
        repelled: Repelled,
    ) -> SelfOutcome {
        let n = x0.len().min(x1.len()).min(inv_mass.len());
        self.report = SelfContactReport::default();
        if first {
            // A new step (a new start state): no earlier CCD pass's answers carry over.
            self.ccd_changed.forget();
            self.touches.clear();
        }
        if self.rest.is_none() {
            self.capture_rest(x0, thickness);
        }
        self.report.exempt = self.rest.as_ref().map_or(0, |r| r.pairs());
        self.w_true.clear();
        self.w_true.extend_from_slice(&inv_mass[..n]);
        self.w.clear();
        self.w.extend((0..n).map(|i| {
            if in_contact[i] {
                inv_mass[i] / CONTACT_MASS_FACTOR
            } else {
                inv_mass[i]
            }
        }));
        let iters = if first || settings.mode == DetectionMode::Continuous {
            settings.self_iterations.max(1)
        } else {
            1
        };
        match settings.mode {
            DetectionMode::Spheres => {
                for k in 0..iters {
                    if self.repulsion_pass(x0, x1, v1, thickness, friction, true, false, k == 0)
                        == 0
                    {
                        break;
                    }
                }
                self.outcome(0)
            }
            DetectionMode::Proximity => {
                for k in 0..iters {
                    if self.repulsion_pass(x0, x1, v1, thickness, friction, false, true, k == 0)
                        == 0
                    {
                        break;
                    }
                }
                self.outcome(0)
            }
            DetectionMode::Continuous => {
                if first {
                    let before = self.start_repulsion(x1);
                    // Jacobi passes close part of each deficit: repeat on the same candidates
                    // until the pairs are settled.
                    for k in 0..REPULSION_PASSES {
                        if self.repulsion_pass(
                            x0,
                            x1,
                            v1,
                            thickness,
                            friction,
                            false,
                            false,
                            k == 0,
                        ) == 0
                        {
                            break;
                        }
                    }
                    self.end_repulsion(before, x1, repelled);
                }
                let mut clean = false;
                for _ in 0..iters {
                    if self.ccd_pass(x0, x1, v1, thickness, true) == 0 {
                        clean = true;
                        break;
                    }
                }
                let unresolved = if clean {
                    0
                } else {
                    self.impact_zones(settings.zone_iterations, x0, x1, v1, thickness, h)
                };
                self.outcome(unresolved)
            }
        }
    }

    /// The positions the repulsion starts from, kept for [`Self::end_repulsion`].
    fn start_repulsion(&mut self, x1: &[Vec3]) -> Vec<Vec3> {
        let mut before = std::mem::take(&mut self.before_repulsion);
        before.clear();
        before.extend_from_slice(x1);
        before
    }

    /// Hands the repulsion's answers to the caller's hook, and keeps the buffer.
    fn end_repulsion(&mut self, before: Vec<Vec3>, x1: &mut [Vec3], repelled: Repelled) {
        repelled(&before, x1);
        self.before_repulsion = before;
    }

    fn outcome(&self, unresolved: usize) -> SelfOutcome {
        SelfOutcome {
            unresolved,
            report: self.report,
        }
    }
}
