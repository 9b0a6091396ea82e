//! Fixed-step pacing of the simulation against a clock (wall or `/clock`), with a bounded
//! backlog.
//!
//! Policy: the simulation owes one step per `dt` of clock time. When it is more than
//! `max_backlog` steps behind (the solver is slower than real time, or the clock jumped
//! forward), it runs `max_backlog` steps and forgives the rest: the forgiven steps are counted,
//! and the time origin moves forward so stamps stay close to the clock. The real-time factor
//! then drops below 1 instead of the node falling ever further behind.

/// Clock-time bookkeeping of a fixed-step simulation.
#[derive(Debug, Clone)]
pub struct Pacer {
    dt: f64,
    max_backlog: u32,
    /// Clock time that corresponds to simulation time 0.
    origin: f64,
    dropped_steps: u64,
}

impl Pacer {
    /// `dt` > 0 (s), `max_backlog` >= 1; simulation time 0 is clock time `now`.
    pub fn new(dt: f64, max_backlog: u32, now: f64) -> Pacer {
        Pacer {
            dt,
            max_backlog: max_backlog.max(1),
            origin: now,
            dropped_steps: 0,
        }
    }

    /// Steps to run now to catch up with clock time `now` (at most `max_backlog`; a larger
    /// backlog is dropped). A clock that went backwards by more than the backlog (a bag
    /// restarting) re-anchors instead of stalling.
    pub fn due_steps(&mut self, now: f64, sim_time: f64) -> u32 {
        let behind = ((now - self.origin - sim_time) / self.dt + 1e-9).floor();
        let max = f64::from(self.max_backlog);
        if behind < -max {
            self.hold(now, sim_time);
            return 0;
        }
        if behind <= 0.0 {
            return 0;
        }
        if behind > max {
            let drop = behind - max;
            self.origin += drop * self.dt;
            self.dropped_steps += drop as u64;
            return self.max_backlog;
        }
        behind as u32
    }

    /// Owes nothing at `now` (paused, or after a reset): the clock runs on, the simulation
    /// does not fall behind.
    pub fn hold(&mut self, now: f64, sim_time: f64) {
        self.origin = now - sim_time;
    }

    /// Clock time of simulation time `sim_time` (the stamp of outputs).
    pub fn clock_of(&self, sim_time: f64) -> f64 {
        self.origin + sim_time
    }

    /// Clock time at which the next step falls due.
    pub fn next_due(&self, sim_time: f64) -> f64 {
        self.origin + sim_time + self.dt
    }

    /// Steps forgiven so far.
    pub fn dropped_steps(&self) -> u64 {
        self.dropped_steps
    }

    pub fn dt(&self) -> f64 {
        self.dt
    }
}

/// Evenly spaced instants at `rate` Hz on a clock; instants the clock skipped over are
/// skipped, not bunched.
#[derive(Debug, Clone)]
pub struct Schedule {
    period: f64,
    next: f64,
}

impl Schedule {
    /// First instant at `start`.
    pub fn new(rate: f64, start: f64) -> Schedule {
        Schedule {
            period: 1.0 / rate,
            next: start,
        }
    }

    /// True (once) when `now` reached the next instant.
    pub fn due(&mut self, now: f64) -> bool {
        if now + 1e-9 < self.next {
            return false;
        }
        self.next += self.period;
        if self.next <= now {
            // Fell behind by more than a period: restart from now.
            self.next = now + self.period;
        }
        true
    }

    /// Like [`Schedule::due`], but also true (once) when the next instant is at most `lead`
    /// ahead of `now`: that instant is taken early. The instants after it stay on the grid,
    /// so the mean rate is unchanged and no instant fires twice.
    pub fn due_within(&mut self, now: f64, lead: f64) -> bool {
        if now + lead.max(0.0) + 1e-9 < self.next {
            return false;
        }
        self.next += self.period;
        if self.next <= now {
            self.next = now + self.period;
        }
        true
    }

    /// Changes the rate; the next instant is at most one new period away.
    pub fn set_rate(&mut self, rate: f64, now: f64) {
        self.period = 1.0 / rate;
        self.next = self.next.min(now + self.period);
    }

    pub fn next(&self) -> f64 {
        self.next
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_pace_without_drift() {
        let dt = 0.01;
        let mut p = Pacer::new(dt, 5, 100.0);
        let mut sim = 0.0;
        let mut steps = 0;
        // 1000 polls at irregular instants over 2 s of clock.
        for k in 1..=1000 {
            let now = 100.0 + 2.0 * k as f64 / 1000.0 + if k % 3 == 0 { 0.0013 } else { 0.0 };
            let n = p.due_steps(now, sim);
            steps += n;
            sim = steps as f64 * dt;
            assert!(now - p.clock_of(sim) < dt + 1e-9, "fell behind at {now}");
            assert!(p.clock_of(sim) <= now + 1e-9, "ran ahead at {now}");
        }
        // Clock ends at 102.0013 (last poll k=999 was offset, k=1000 not): 200 steps.
        assert_eq!(steps, 200);
        assert_eq!(p.dropped_steps(), 0);
    }

    #[test]
    fn drops_backlog_beyond_limit() {
        let mut p = Pacer::new(0.01, 4, 0.0);
        // A 1 s stall: 100 steps owed, 4 run, 96 forgiven.
        assert_eq!(p.due_steps(1.0, 0.0), 4);
        assert_eq!(p.dropped_steps(), 96);
        // After running them the simulation is on time again.
        assert_eq!(p.due_steps(1.0, 0.04), 0);
        assert!((p.clock_of(0.04) - 1.0).abs() < 1e-9);
        // A solver that needs 2 clock steps per step: each poll owes 2, never more than 4.
        let mut sim = 0.04;
        let mut now = 1.0;
        for _ in 0..50 {
            now += 0.02;
            let n = p.due_steps(now, sim);
            assert!(n <= 4);
            // The lag the loop sees is bounded by the backlog limit.
            assert!(now - p.clock_of(sim) < 0.05 + 1e-9);
            sim += f64::from(n) * 0.01;
            now += f64::from(n) * 0.02;
        }
        assert!(p.dropped_steps() > 96);
    }

    #[test]
    fn hold_and_clock_going_back() {
        let mut p = Pacer::new(0.1, 3, 0.0);
        assert_eq!(p.due_steps(0.25, 0.0), 2);
        p.hold(10.0, 0.2);
        assert_eq!(p.due_steps(10.05, 0.2), 0);
        assert_eq!(p.due_steps(10.1, 0.2), 1);
        // The clock restarts at 0: re-anchor rather than wait ten seconds.
        assert_eq!(p.due_steps(0.0, 0.3), 0);
        assert_eq!(p.due_steps(0.1, 0.3), 1);
        assert_eq!(p.dropped_steps(), 0);
    }

    #[test]
    fn schedule_skips_instead_of_bunching() {
        let mut s = Schedule::new(10.0, 0.0);
        assert!(s.due(0.0));
        assert!(!s.due(0.05));
        assert!(s.due(0.1));
        // Half a second passes in one go: one event, then on schedule from there.
        assert!(s.due(0.6));
        assert!(!s.due(0.65));
        assert!(s.due(0.7));
        s.set_rate(1.0, 0.7);
        assert!(!s.due(0.75));
        assert!(s.due(0.8));
        assert!(!s.due(1.7));
        assert!(s.due(1.8));
    }

    #[test]
    fn schedule_takes_an_instant_early_without_changing_the_rate() {
        let mut s = Schedule::new(10.0, 0.0);
        assert!(s.due(0.0));
        // 0.1 is more than 0.03 away at 0.06, within it at 0.08: taken early, once.
        assert!(!s.due_within(0.06, 0.03));
        assert!(s.due_within(0.08, 0.03));
        assert!(!s.due(0.1));
        assert!(!s.due_within(0.15, 0.03));
        // The grid is kept: 0.2, 0.3, ...
        assert!(s.due(0.2));
        assert!(!s.due(0.29));
        assert!(s.due(0.3));
        // No lead: the same as `due`.
        assert!(!s.due_within(0.35, 0.0));
        assert!(s.due_within(0.4, 0.0));
        // Far behind: restarts from now, not from now + lead.
        assert!(s.due_within(2.0, 0.05));
        assert!((s.next() - 2.1).abs() < 1e-12);
    }
}
