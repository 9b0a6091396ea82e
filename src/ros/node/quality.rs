//! Adaptive quality: the node lowers the solver's quality (substeps, CG tolerance and cap) when
//! a frame step costs more wall time than the simulated time it covers, and raises it back when
//! there is room, so the real-time factor stays at 1 ([`QualityController`]).
//!
//! The rule is pure: the measured wall time of each frame step in, the quality of the next
//! step out; no clock, no simulation, so every property below has a unit test.
//!
//! **Ladder.** Level 0 is the scene's own settings; the last level is the bounds
//! ([`QualityBounds`]: fewest substeps, loosest tolerance, smallest cap, never beyond the
//! scene's own). Levels between interpolate each setting geometrically, so neighbours differ in
//! cost by a roughly constant factor. Only the implicit integrator adapts: fewer substeps
//! would make an explicit one unstable, so its ladder is its one level.
//!
//! **Load** is `wall / dt`, the share of real time a step takes, judged as the median of the
//! last [`WINDOW`] frames at the current level: one slow frame (a multigrid rebuild, the OS)
//! moves no decision, and every decision sees only frames of the level it judges.
//! - Over [`LOWER_ABOVE`] (10 % is left for publishing and message handling): one level down.
//! - One level up, after the level's wait, when the level above is predicted to cost under
//!   [`RAISE_TARGET`]: the load times that level's measured cost over this one's. Each move
//!   between two neighbours measures that ratio (the last window before the move against the
//!   first full one after it); until a pair has been measured it is taken as
//!   [`ASSUMED_RATIO`]. Neighbours' costs differ by 1.08-2x from scene to scene (one rung of a
//!   towel dragged with self-collision costs 1.1x the next, a halved substep count 2x), so a
//!   fixed threshold either stays low where rungs are cheap or raises into overload where
//!   they are dear. Under [`RAISE_BELOW`] a level is tried whatever its measured ratio (the
//!   pair may have been measured while the scene's load changed). Between a raise that is not
//!   predicted to hold and [`LOWER_ABOVE`] nothing changes (hysteresis).
//! - A raise undone within [`PROBE`] frames (the level above could not hold real time)
//!   doubles the wait before that level is tried again, up to [`MAX_WAIT`]: the controller
//!   probes ever more rarely instead of oscillating.
//! - At the lowest allowed level with a load over 1 the node cannot hold real time; the
//!   controller says so once per episode, with the real-time factor it reaches.
//! - The divergence guard still rules: a divergence at level `l > 0` bans `l` and everything
//!   below it for the rest of the run (the node rebuilds the cloth and goes to `l - 1`).

use crate::integrate::{ImplicitSettings, IntegratorKind};
use crate::scene::Scene;

/// Frames whose median load a decision judges (8 frames: 0.13 s at 60 Hz).
pub const WINDOW: usize = 8;
/// Median load above which quality goes down.
pub const LOWER_ABOVE: f64 = 0.9;
/// The load the level above must be predicted to cost for a raise: room under [`LOWER_ABOVE`]
/// for the median's noise between windows (a few percent) and a mispredicted ratio.
pub const RAISE_TARGET: f64 = 0.75;
/// The cost of a level over the one below it, until a move between them has measured it: a
/// raise from under [`RAISE_BELOW`] then mostly lands under [`LOWER_ABOVE`] (adjacent levels
/// cost up to ~2x each other).
pub const ASSUMED_RATIO: f64 = 1.5;
/// Median load under which quality goes up, whatever the level above was measured to cost.
pub const RAISE_BELOW: f64 = RAISE_TARGET / ASSUMED_RATIO;
/// Frames at a level before the first try of the level above (0.5 s at 60 Hz).
pub const MIN_WAIT: u32 = 30;
/// Longest wait before a probe (~64 s at 60 Hz).
pub const MAX_WAIT: u32 = 3840;
/// A lowering this many frames after a raise means the raise failed (2 s at 60 Hz).
pub const PROBE: u32 = 120;

/// One setting of the step's cost against its accuracy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quality {
    pub substeps: u32,
    pub cg_tolerance: f64,
    pub cg_max_iterations: u32,
    /// Newton iterations while a spring stretches more than this beyond its linearised
    /// prediction (see `ImplicitSettings::linearisation_tolerance`).
    pub linearisation_tolerance: f64,
}

impl Quality {
    /// The implicit solver's part of this quality.
    pub fn solver(&self) -> ImplicitSettings {
        ImplicitSettings {
            cg_tolerance: self.cg_tolerance,
            cg_max_iterations: self.cg_max_iterations,
            linearisation_tolerance: self.linearisation_tolerance,
        }
    }
}

impl std::fmt::Display for Quality {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} substep(s), CG tolerance {:.1e}, cap {}, linearisation tolerance {:.2}",
            self.substeps, self.cg_tolerance, self.cg_max_iterations, self.linearisation_tolerance
        )
    }
}

/// How low the node may take quality (node parameters `quality.*`). The defaults are the old
/// `real_time_preview` settings: one substep, CG tolerance 1e-2, at most 50 iterations; and
/// Newton iterations only for springs turned past 90 degrees in a step (linearisation
/// tolerance 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QualityBounds {
    pub min_substeps: u32,
    pub max_cg_tolerance: f64,
    pub min_cg_max_iterations: u32,
    /// The loosest linearisation tolerance: with the scene's default (0.1) the Newton iterations
    /// it asks for make the towel dragged by drape_bot's gripper with self-collision slower
    /// than real time even at the lowest rung (`cargo bench --bench node_latency`, the
    /// self-collision row), so the lower rungs loosen it up to this bound.
    pub max_linearisation_tolerance: f64,
    /// Rungs from the scene's quality to the bounds, both included (at least 2).
    pub levels: u32,
}

impl Default for QualityBounds {
    fn default() -> Self {
        Self {
            min_substeps: 1,
            max_cg_tolerance: 1e-2,
            min_cg_max_iterations: 50,
            max_linearisation_tolerance: 1.0,
            levels: 8,
        }
    }
}

/// What the controller asks of the loop after a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Decision {
    Keep,
    /// Run from the next step on at this (lower) quality; `load` is what the old one cost.
    Lowered {
        quality: Quality,
        load: f64,
    },
    Raised {
        quality: Quality,
        load: f64,
    },
    /// The lowest allowed quality costs `load` times real time (> 1); said once per episode.
    CannotHold {
        quality: Quality,
        load: f64,
    },
}

/// What `/diagnostics` reports about quality.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QualityStatus {
    pub quality: Quality,
    /// 0: the scene's own quality.
    pub level: usize,
    pub levels: usize,
    pub adaptive: bool,
    /// While real time cannot be held at the lowest allowed quality: its load (> 1).
    pub short_of_real_time: Option<f64>,
}

/// The update rule (see the module doc).
#[derive(Debug, Clone)]
pub struct QualityController {
    ladder: Vec<Quality>,
    level: usize,
    /// Highest level index allowed (divergences lower it).
    lowest: usize,
    /// Loads of the frames at the current level, oldest first (at most [`WINDOW`]).
    window: Vec<f64>,
    frames_at_level: u32,
    /// `wait[l]`: frames at level `l + 1` before level `l` is tried.
    wait: Vec<u32>,
    /// The level last raised into and the frames since.
    probe: Option<(usize, u32)>,
    short: Option<f64>,
    /// `ratio[l]`: the measured cost of level `l` over level `l + 1` (see the module doc).
    ratio: Vec<Option<f64>>,
    /// The last move: the level left and its last window's load, until the new level's first
    /// full window measures the pair's ratio.
    moved_from: Option<(usize, f64)>,
}

impl QualityController {
    /// A controller starting at the scene's quality `full`; `adaptive` false (or an explicit
    /// integrator) keeps it there.
    pub fn new(full: Quality, bounds: &QualityBounds, adaptive: bool) -> Self {
        let ladder = if adaptive {
            ladder(full, bounds)
        } else {
            vec![full]
        };
        let n = ladder.len();
        Self {
            ladder,
            level: 0,
            lowest: n - 1,
            window: Vec::with_capacity(WINDOW),
            frames_at_level: 0,
            wait: vec![MIN_WAIT; n],
            probe: None,
            short: None,
            ratio: vec![None; n],
            moved_from: None,
        }
    }

    pub fn ladder(&self) -> &[Quality] {
        &self.ladder
    }

    pub fn quality(&self) -> Quality {
        self.ladder[self.level]
    }

    pub fn status(&self) -> QualityStatus {
        QualityStatus {
            quality: self.quality(),
            level: self.level,
            levels: self.ladder.len(),
            adaptive: self.ladder.len() > 1,
            short_of_real_time: self.short,
        }
    }

    /// Takes one frame step's wall time `wall` for `dt` simulated seconds.
    pub fn update(&mut self, wall: f64, dt: f64) -> Decision {
        if !(wall.is_finite() && wall >= 0.0 && dt > 0.0) {
            return Decision::Keep;
        }
        self.frames_at_level = self.frames_at_level.saturating_add(1);
        if let Some((_, age)) = &mut self.probe {
            *age = age.saturating_add(1);
        }
        if self.window.len() == WINDOW {
            self.window.remove(0);
        }
        self.window.push(wall / dt);
        if self.window.len() < WINDOW {
            return Decision::Keep;
        }
        let load = median(&self.window);
        if let Some((from, before)) = self.moved_from.take() {
            self.measure(from, before, load);
        }
        if load > LOWER_ABOVE && self.level < self.lowest {
            if let Some((l, age)) = self.probe.take() {
                if l == self.level && age <= PROBE {
                    self.wait[l] = (self.wait[l] * 2).min(MAX_WAIT);
                }
            }
            self.go(self.level + 1, load);
            return Decision::Lowered {
                quality: self.quality(),
                load,
            };
        }
        if load > 1.0 && self.level == self.lowest && self.ladder.len() > 1 {
            let first = self.short.is_none();
            self.short = Some(load);
            return if first {
                Decision::CannotHold {
                    quality: self.quality(),
                    load,
                }
            } else {
                Decision::Keep
            };
        }
        if load < LOWER_ABOVE {
            self.short = None;
        }
        if let Some((l, age)) = self.probe {
            if age > PROBE {
                // The raise held: the next failure there starts its backoff afresh.
                self.wait[l] = MIN_WAIT;
                self.probe = None;
            }
        }
        if self.level > 0
            && (load < RAISE_BELOW || self.predicted_above(load) < RAISE_TARGET)
            && self.frames_at_level >= self.wait[self.level - 1]
        {
            self.go(self.level - 1, load);
            self.probe = Some((self.level, 0));
            return Decision::Raised {
                quality: self.quality(),
                load,
            };
        }
        Decision::Keep
    }

    /// After a divergence: bans the current level and those below it, and goes one level up.
    /// Returns the new quality, `None` at the scene's own quality (nothing to undo).
    pub fn on_divergence(&mut self) -> Option<Quality> {
        if self.level == 0 {
            return None;
        }
        self.lowest = self.level - 1;
        self.short = None;
        self.probe = None;
        self.go(self.lowest, f64::NAN);
        self.moved_from = None;
        Some(self.quality())
    }

    /// The load the level above would have at this one's `load`: times the pair's measured
    /// ratio, or [`ASSUMED_RATIO`].
    fn predicted_above(&self, load: f64) -> f64 {
        let ratio = self.level.checked_sub(1).and_then(|l| self.ratio[l]);
        load * ratio.unwrap_or(ASSUMED_RATIO)
    }

    /// A move from level `from` (its last window's load `before`) to the current level, whose
    /// first full window's load is `after`: the ratio of the upper level's cost over the
    /// lower's, at least 1 (a higher quality never costs less; a smaller measurement is the
    /// scene's load changing between the windows).
    fn measure(&mut self, from: usize, before: f64, after: f64) {
        let (upper, lower) = if from < self.level {
            (before, after)
        } else {
            (after, before)
        };
        let pair = from.min(self.level);
        if from.abs_diff(self.level) == 1 && lower > 0.0 && upper.is_finite() {
            self.ratio[pair] = Some((upper / lower).max(1.0));
        }
    }

    /// Moves to `level`, leaving the current one at `load`.
    fn go(&mut self, level: usize, load: f64) {
        self.moved_from = Some((self.level, load));
        self.level = level;
        self.window.clear();
        self.frames_at_level = 0;
    }
}

/// Sets an implicit scene's solver to the lowest quality `bounds` allow, the last rung of the
/// ladder (benches measure it; other integrators keep their settings).
pub fn lowest_quality(scene: &mut Scene, bounds: &QualityBounds) {
    if scene.solver.integrator == IntegratorKind::Implicit {
        let s = &mut scene.solver;
        let full = Quality {
            substeps: s.substeps,
            cg_tolerance: s.cg_tolerance,
            cg_max_iterations: s.cg_max_iterations,
            linearisation_tolerance: s.linearisation_tolerance,
        };
        if let Some(low) = ladder(full, bounds).last() {
            (s.substeps, s.cg_tolerance, s.cg_max_iterations) =
                (low.substeps, low.cg_tolerance, low.cg_max_iterations);
            s.linearisation_tolerance = low.linearisation_tolerance;
        }
    }
}

/// `full`, the bounds, and geometric steps between, without repeats; never beyond the bounds
/// nor above the scene's own quality.
fn ladder(full: Quality, b: &QualityBounds) -> Vec<Quality> {
    let low = Quality {
        substeps: b.min_substeps.clamp(1, full.substeps.max(1)),
        cg_tolerance: b.max_cg_tolerance.max(full.cg_tolerance),
        cg_max_iterations: b
            .min_cg_max_iterations
            .clamp(1, full.cg_max_iterations.max(1)),
        linearisation_tolerance: b
            .max_linearisation_tolerance
            .max(full.linearisation_tolerance),
    };
    let n = b.levels.max(2);
    // Equal ends give that value exactly (powf would round it), and nothing leaves [a, z].
    let geo = |a: f64, z: f64, s: f64| {
        if a == z {
            a
        } else {
            (a.powf(1.0 - s) * z.powf(s)).clamp(a.min(z), a.max(z))
        }
    };
    let mut out: Vec<Quality> = Vec::with_capacity(n as usize);
    for k in 0..n {
        let s = f64::from(k) / f64::from(n - 1);
        let q = if k == 0 {
            full
        } else if k == n - 1 {
            low
        } else {
            let int = |a: u32, z: u32| {
                (geo(f64::from(a), f64::from(z), s).round() as u32).clamp(z.min(a), a.max(z))
            };
            Quality {
                substeps: int(full.substeps, low.substeps),
                cg_tolerance: geo(full.cg_tolerance, low.cg_tolerance, s),
                cg_max_iterations: int(full.cg_max_iterations, low.cg_max_iterations),
                linearisation_tolerance: geo(
                    full.linearisation_tolerance,
                    low.linearisation_tolerance,
                    s,
                ),
            }
        };
        if out.last() != Some(&q) {
            out.push(q);
        }
    }
    out
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let m = s.len() / 2;
    if s.len().is_multiple_of(2) {
        0.5 * (s[m - 1] + s[m])
    } else {
        s[m]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 1.0 / 60.0;

    fn towel() -> Quality {
        Quality {
            substeps: 2,
            cg_tolerance: 1e-5,
            cg_max_iterations: 200,
            linearisation_tolerance: 0.1,
        }
    }

    fn controller() -> QualityController {
        QualityController::new(towel(), &QualityBounds::default(), true)
    }

    /// Feeds `frames` frames whose load is `load(level)`; returns the decisions that changed
    /// something.
    fn drive(
        c: &mut QualityController,
        frames: usize,
        mut load: impl FnMut(usize) -> f64,
    ) -> Vec<Decision> {
        let mut changes = Vec::new();
        for _ in 0..frames {
            let wall = load(c.status().level) * DT;
            let d = c.update(wall, DT);
            if d != Decision::Keep {
                changes.push(d);
            }
        }
        changes
    }

    #[test]
    fn ladder_runs_from_the_scene_to_the_bounds_and_never_past_them() {
        let c = controller();
        let l = c.ladder();
        assert_eq!(l[0], towel());
        assert_eq!(
            *l.last().unwrap(),
            Quality {
                substeps: 1,
                cg_tolerance: 1e-2,
                cg_max_iterations: 50,
                linearisation_tolerance: 1.0,
            }
        );
        for w in l.windows(2) {
            assert!(w[1].substeps <= w[0].substeps);
            assert!(w[1].cg_tolerance >= w[0].cg_tolerance);
            assert!(w[1].cg_max_iterations <= w[0].cg_max_iterations);
            assert!(w[1].linearisation_tolerance >= w[0].linearisation_tolerance);
            assert_ne!(w[0], w[1]);
        }
        // Bounds looser than the scene's own settings keep the scene's.
        let tight = Quality {
            substeps: 1,
            cg_tolerance: 0.05,
            cg_max_iterations: 20,
            linearisation_tolerance: 2.0,
        };
        let c = QualityController::new(tight, &QualityBounds::default(), true);
        assert_eq!(c.ladder(), &[tight]);
        assert!(!c.status().adaptive);
    }

    #[test]
    fn real_time_met_keeps_the_scene_quality() {
        let mut c = controller();
        assert!(drive(&mut c, 5000, |_| 0.7).is_empty());
        assert_eq!(c.quality(), towel());
    }

    #[test]
    fn one_slow_frame_moves_nothing() {
        let mut c = controller();
        let mut k = 0;
        let changes = drive(&mut c, 2000, |_| {
            k += 1;
            if k % 50 == 0 {
                20.0
            } else {
                0.6
            }
        });
        assert!(changes.is_empty(), "{changes:?}");
    }

    #[test]
    fn overload_lowers_until_real_time_is_held_then_settles() {
        // Level l costs 3 / 1.4^l of real time: level 4 (0.78) is the first that holds, and
        // it is above the raise threshold, so nothing moves once there.
        let cost = |l: usize| 3.0 / 1.4f64.powi(l as i32);
        let mut c = controller();
        let changes = drive(&mut c, 60 * 60, cost);
        assert_eq!(c.status().level, 4);
        assert_eq!(changes.len(), 4, "{changes:?}");
        assert!(drive(&mut c, 60 * 60, cost).is_empty());
        assert_eq!(c.status().short_of_real_time, None);
    }

    #[test]
    fn a_failing_probe_is_tried_ever_more_rarely() {
        // Dropping to one substep (level 3) halves the cost and more: 1.2 above it, 0.45 from
        // it on. Level 3 has room (under 0.5), so the controller probes level 2, which fails.
        let cost = |l: usize| if l < 3 { 1.2 } else { 0.45 };
        let mut c = controller();
        let first = drive(&mut c, 60 * 60, cost);
        let probes = |d: &[Decision]| {
            d.iter()
                .filter(|d| matches!(d, Decision::Raised { .. }))
                .count()
        };
        // Waits 30, 60, 120, ... frames: 6 probes fit in the first minute, 1-2 in the next.
        assert!((4..=7).contains(&probes(&first)), "{first:?}");
        let mut slow = 0;
        let second = drive(&mut c, 60 * 60, |l| {
            slow += usize::from(l < 3);
            cost(l)
        });
        assert!(probes(&second) <= 2, "{second:?}");
        // Each failed probe costs one window of slow frames.
        assert!(slow <= 2 * WINDOW, "{slow} slow frames");
        assert_eq!(c.status().level, 3);
    }

    #[test]
    fn room_to_spare_raises_back_to_full_quality() {
        let mut c = controller();
        drive(&mut c, 600, |_| 5.0);
        assert_eq!(c.status().level, c.ladder().len() - 1);
        let changes = drive(&mut c, 60 * 60, |_| 0.2);
        assert!(changes.iter().all(|d| matches!(d, Decision::Raised { .. })));
        assert_eq!(c.quality(), towel());
    }

    #[test]
    fn cheap_rungs_are_climbed_as_far_as_they_are_measured_to_hold() {
        // A start that overloads every level takes the controller to the lowest; then each
        // rung costs 1.08x the next (0.55 at the lowest, 0.81 two rungs from the top): a load
        // over `RAISE_BELOW` everywhere, so only the measured ratios raise it.
        let settled = |l: usize| 0.55 * 1.08f64.powi(7 - l as i32);
        let mut c = controller();
        let lowest = c.ladder().len() - 1;
        assert_eq!(lowest, 7);
        drive(&mut c, 600, |_| 5.0);
        assert_eq!(c.status().level, lowest);
        let changes = drive(&mut c, 60 * 60, settled);
        assert!(
            changes.iter().all(|d| matches!(d, Decision::Raised { .. })),
            "{changes:?}"
        );
        let level = c.status().level;
        assert!(level <= 3 && settled(level) < LOWER_ABOVE, "level {level}");
        assert!(drive(&mut c, 60 * 60, settled).is_empty());
    }

    #[test]
    fn a_raise_the_ratio_mispredicted_is_measured_and_not_repeated() {
        // Measured at 1 during the overloaded start, the lowest rung's ratio to the one above is
        // 2 once the load settles: the one probe fails and measures it.
        let settled = |l: usize| if l == 7 { 0.55 } else { 1.1 };
        let mut c = controller();
        drive(&mut c, 600, |_| 5.0);
        let changes = drive(&mut c, 60 * 60 * 5, settled);
        let raises = changes
            .iter()
            .filter(|d| matches!(d, Decision::Raised { .. }))
            .count();
        assert_eq!(raises, 1, "{changes:?}");
        assert_eq!(c.status().level, 7);
    }

    #[test]
    fn cannot_hold_is_said_once_with_its_factor() {
        let mut c = controller();
        let changes = drive(&mut c, 3000, |_| 1.6);
        let said: Vec<_> = changes
            .iter()
            .filter_map(|d| match d {
                Decision::CannotHold { load, quality } => Some((*load, *quality)),
                _ => None,
            })
            .collect();
        assert_eq!(said.len(), 1, "{changes:?}");
        assert!((said[0].0 - 1.6).abs() < 1e-12);
        assert_eq!(said[0].1, *c.ladder().last().unwrap());
        assert_eq!(c.status().short_of_real_time, Some(1.6));
        // Recovering ends the episode; a new one is said again.
        drive(&mut c, 100, |_| 0.8);
        assert_eq!(c.status().short_of_real_time, None);
        let again = drive(&mut c, 100, |_| 1.6);
        assert_eq!(again.len(), 1);
    }

    #[test]
    fn a_divergence_bans_its_level_and_those_below() {
        let mut c = controller();
        drive(&mut c, 3000, |_| 5.0);
        let lowest = c.ladder().len() - 1;
        assert_eq!(c.status().level, lowest);
        assert_eq!(c.on_divergence(), Some(c.ladder()[lowest - 1]));
        drive(&mut c, 3000, |_| 5.0);
        assert_eq!(c.status().level, lowest - 1, "the banned level came back");
        let mut full = controller();
        assert_eq!(full.on_divergence(), None);
    }

    #[test]
    fn fixed_quality_never_changes() {
        let mut c = QualityController::new(towel(), &QualityBounds::default(), false);
        assert!(drive(&mut c, 1000, |_| 10.0).is_empty());
        assert_eq!(c.status().short_of_real_time, None);
    }
}
