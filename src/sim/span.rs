//! A substep's span: its time interval, where it lies in its frame, and how often the guard
//! halved the scene's substep to reach it.

use crate::collide::Obstacle;
use crate::Pose;

/// One substep: the interval `[t, t + h]`, the fractions `s0..s1` of its frame (driven
/// obstacles and frames move between their frame's start and end pose by these), and its
/// `depth`: how many times the guard halved the scene's substep `dt / substeps` to get it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Span {
    pub t: f64,
    pub h: f64,
    pub s0: f64,
    pub s1: f64,
    pub depth: u32,
}

impl Span {
    /// Scene substep `k` of `n`, each of `h`, in the frame that starts at `t0`.
    pub fn of_frame(t0: f64, h: f64, k: u32, n: u32) -> Span {
        Span {
            t: t0 + f64::from(k) * h,
            h,
            s0: f64::from(k) / f64::from(n),
            s1: f64::from(k + 1) / f64::from(n),
            depth: 0,
        }
    }

    /// The two halves, in order, one level deeper.
    pub fn halves(self) -> [Span; 2] {
        let (h, sm, depth) = (0.5 * self.h, 0.5 * (self.s0 + self.s1), self.depth + 1);
        [
            Span {
                t: self.t,
                h,
                s0: self.s0,
                s1: sm,
                depth,
            },
            Span {
                t: self.t + h,
                h,
                s0: sm,
                s1: self.s1,
                depth,
            },
        ]
    }

    /// The start and end pose of obstacle `o` over the span (`target`: its frame's start and
    /// end pose when it is driven from outside; scripted obstacles follow their motion in time).
    pub fn poses(&self, o: &Obstacle, target: Option<&(Pose, Pose)>) -> (Pose, Pose) {
        if o.motion.is_scripted() {
            (
                o.motion.pose_at(&o.initial_pose, self.t),
                o.motion.pose_at(&o.initial_pose, self.t + self.h),
            )
        } else {
            match target {
                Some((a, b)) => (a.lerp(b, self.s0), a.lerp(b, self.s1)),
                None => (o.pose, o.pose),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halves_tile_the_span_in_time_and_frame() {
        let s = Span::of_frame(1.0, 0.25, 1, 4);
        assert_eq!((s.t, s.s0, s.s1, s.depth), (1.25, 0.25, 0.5, 0));
        let [a, b] = s.halves();
        assert_eq!(
            (a.t, a.h, a.s0, a.s1, a.depth),
            (1.25, 0.125, 0.25, 0.375, 1)
        );
        assert_eq!(
            (b.t, b.h, b.s0, b.s1, b.depth),
            (1.375, 0.125, 0.375, 0.5, 1)
        );
    }
}
