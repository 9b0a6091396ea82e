//! The simulation thread: waits for [`Command`]s until the next thing is due, ticks the
//! [`SimLoop`], and sends its [`Output`]s. The only file of the simulation side that touches
//! channels and real time.

use super::clock::{ClockMode, WallClock};
use super::messages::{Command, Level, Output};
use super::sim_loop::SimLoop;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

/// The simulation thread: waits for commands until the next thing is due, ticks, and sends the
/// outputs. Returns on [`Command::Stop`], on `stop`, or when either channel closes.
pub fn run(
    mut core: SimLoop,
    mode: ClockMode,
    wall: WallClock,
    rx: Receiver<Command>,
    tx: Sender<Output>,
    stop: &AtomicBool,
) {
    let mut out = Vec::new();
    let mut now = match mode {
        ClockMode::Wall => Some(wall.now()),
        ClockMode::Sim => None,
    };
    if let Some(n) = now {
        core.sync_clock(n);
    }
    let mut behind = false;
    let started = Instant::now();
    let mut warned_no_clock = false;
    while !stop.load(Ordering::Relaxed) {
        if now.is_none() && !warned_no_clock && started.elapsed() > Duration::from_secs(5) {
            warned_no_clock = true;
            out.push(Output::Log {
                level: Level::Warn,
                text: "use_sim_time is set but no /clock (rosgraph_msgs/msg/Clock) has arrived \
                       in 5 s: the simulation waits for it"
                    .into(),
            });
        }
        let wait = match (mode, now) {
            _ if behind => 0.0,
            (ClockMode::Wall, _) => (core.next_wake() - wall.now()).clamp(0.0, 0.05),
            _ => 0.05,
        };
        let mut pending = Vec::new();
        match rx.recv_timeout(Duration::from_secs_f64(wait)) {
            Ok(c) => pending.push(c),
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => return,
        }
        pending.extend(rx.try_iter());
        if mode == ClockMode::Wall {
            now = Some(wall.now());
        }
        for cmd in pending {
            if let (ClockMode::Sim, Command::Clock(t)) = (mode, &cmd) {
                if now.is_none() {
                    core.sync_clock(*t);
                }
                now = Some(*t);
            }
            let t = now.unwrap_or(0.0);
            if !core.handle(cmd, t, &mut out) {
                return;
            }
        }
        behind = match now {
            Some(t) => core.tick(t, &mut out),
            None => false,
        };
        for o in out.drain(..) {
            if tx.send(o).is_err() {
                return;
            }
        }
    }
}
