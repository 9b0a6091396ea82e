//! The guard's checks around contact with moving obstacles: fast contact before the solve
//! (split a substep in which an obstacle would outrun the cloth near it), and after the
//! collision pass the strain check (an edge the response stretched beyond what the material and
//! the speeds in the scene allow, see [`crate::sim::strain`]) and the response-jump check (a
//! vertex the response moved more than fast contact allows, see [`crate::sim::fast`]).

use super::settings::GuardSettings;
use super::verdict::{Failure, Redo, Verdict, Why};
use super::{Guard, Inside};
use crate::cloth::Cloth;
use crate::collide::CollisionStage;
use crate::effects::EffectSet;
use crate::sim::error::Symptom;
use crate::sim::fast;
use crate::sim::metrics::StepMetrics;
use crate::sim::span::Span;
use crate::{Pose, Vec3};

impl Guard {
    /// Whether a moving obstacle outruns cloth within its reach over `span` (see [`fast`]):
    /// then the substep is split, within the guard's levels of halving and of fast contact;
    /// where `max_contact_split_levels` refuses the split, the refusal is counted and the
    /// substep goes on. Also notes the fastest obstacle point's speed for the strain bound.
    /// Static obstacles cost nothing. `near` is scratch.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn fast_contact(
        &mut self,
        g: &GuardSettings,
        span: Span,
        stage: &CollisionStage,
        targets: &[Option<(Pose, Pose)>],
        (cloth, effects): (&Cloth, &EffectSet),
        near: &mut Vec<(usize, f64, f64)>,
        m: &mut StepMetrics,
    ) -> Verdict {
        let may_split = span.depth < g.split_levels();
        // At the budget's depth (not the guard's) the test still runs, to count the refusal.
        let test = may_split || span.depth < g.max_subdivisions;
        let (mut top, mut refused) = (0.0f64, false);
        let mut thickness = None;
        for (k, o) in stage.obstacles().iter().enumerate() {
            let poses = span.poses(o, targets.get(k).and_then(Option::as_ref));
            if poses.0 == poses.1 {
                continue;
            }
            top = top.max(fast::top_speed(o, poses, span.h));
            if !test || refused {
                continue;
            }
            let strain = self.strain_model(cloth, effects);
            let reach = fast::Reach {
                thickness: *thickness
                    .get_or_insert_with(|| cloth.thickness.iter().copied().fold(0.0, f64::max)),
                spacing: strain.max_spacing(),
            };
            if fast::outruns(o, poses, cloth, span.h, reach, |i| strain.spacing(i), near) {
                if !may_split {
                    refused = true;
                    continue;
                }
                return Err(Redo::Split(Why::FastContact));
            }
        }
        m.contact_splits_refused += u32::from(refused);
        self.obstacle_speed = top;
        Ok(())
    }

    /// The strain check of the state the substep ends in: an edge the collision pass stretched
    /// beyond the bound of the material and the fastest impact of the run so far (this
    /// substep's: the fastest speed of its start state `(x0, v0)`, plus the fastest obstacle
    /// point), from within it after the solve (`solved`). An edge the solve itself left beyond
    /// the bound is the scene's doing (a kinematic link dragging pinned cloth stretches it
    /// without limit) and the energy check's business; so is cloth the scene started inside an
    /// obstacle, until it is out.
    pub(super) fn check_strain(
        &mut self,
        stage: &CollisionStage,
        cloth: &Cloth,
        (x0, v0): (&[Vec3], &[Vec3]),
        solved: &[Vec3],
    ) -> Result<(), Failure> {
        let v_cloth = (v0.iter())
            .map(|v| v.length_squared())
            .fold(0.0, f64::max)
            .sqrt();
        let speed = self.book.peak_speed.max(v_cloth + self.obstacle_speed);
        self.book.peak_speed = speed;
        if self.inside == Inside::Unknown {
            self.inside = if stage.overlaps(x0).is_empty() {
                Inside::Out
            } else {
                Inside::Leaving
            };
        }
        if self.inside == Inside::Leaving {
            if !stage.overlaps(&cloth.x).is_empty() {
                return Ok(());
            }
            self.inside = Inside::Out;
        }
        let Some(strain) = self.strain.as_ref() else {
            return Ok(());
        };
        let bound = strain.bound(speed);
        // Only edges an obstacle's pass moved an end of: halving bounds how far an obstacle
        // moves per substep, not how far self-contact pushes a layer squeezed against kinematic
        // cloth (at most its contact distance), which no amount of halving undoes.
        let by_obstacle = |i: usize| stage.contact_kind(i, false).is_some();
        let judged = |a: usize, b: usize| by_obstacle(a) || by_obstacle(b);
        let Some(worst) = strain.grown_beyond(solved, &cloth.x, bound, judged) else {
            return Ok(());
        };
        let (a, b) = worst.vertices;
        let moved = |i: usize| solved[i] != cloth.x[i];
        let contact = (stage.contact_kind(a, moved(a))).or_else(|| stage.contact_kind(b, moved(b)));
        let other = match cloth.piece_of(b) {
            Some(p) => b - p.first_vertex,
            None => b,
        };
        let symptom = Symptom::Stretch {
            other,
            ratio: worst.ratio,
            bound,
            contact,
        };
        Err(Failure { vertex: a, symptom })
    }

    /// Whether the collision pass moved a vertex it answered for an obstacle by more than a
    /// third of its spacing from where the solve left it (`solved`; see [`fast::jumped`]). Not
    /// while the cloth is still leaving an obstacle the scene started it in (the lead-out moves
    /// a vertex a sixth of its shortest edge per pass at most; the strain check waits too).
    pub(super) fn response_jumped(
        &self,
        stage: &CollisionStage,
        cloth: &Cloth,
        solved: &[Vec3],
    ) -> bool {
        let Some(strain) = self.strain.as_ref() else {
            return false;
        };
        if self.inside != Inside::Out {
            return false;
        }
        fast::jumped(
            solved,
            &cloth.x,
            |i| strain.spacing(i),
            |i| stage.contact_kind(i, false).is_some(),
        )
    }
}
