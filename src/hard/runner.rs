//! Runs one hard case and keeps the worst value of every monitored quantity, then judges it
//! against the case's criteria.

use super::{Case, Criteria, EnergyCheck};
use crate::cloth::Kinematic;
use crate::collide::Solids;
use crate::effects::State;
use crate::sim::Simulation;
use crate::Vec3;
use std::time::Instant;

/// Worst values seen over a run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Worst {
    pub frames: usize,
    pub simulated_s: f64,
    /// Every position and velocity was finite after every frame.
    pub all_finite: bool,
    pub max_abs_x: f64,
    pub max_speed: f64,
    /// `max_t (E(t) - E(0) - W_ext(t)) / scale` (negative: the cloth lost energy), when measured.
    pub energy_excess: Option<f64>,
    /// Simulated time of the worst energy excess (s).
    pub energy_excess_at: f64,
    /// The energy scale the excess is relative to (J).
    pub energy_scale: f64,
    pub max_penetration: f64,
    /// Deepest cloth vertex inside an obstacle's solid (m), where the case judges it.
    pub max_inside_solid: Option<f64>,
    /// Largest edge length over rest length at a frame end.
    pub max_stretch: f64,
    pub max_self_intersections: Option<usize>,
    pub max_attached_drift: f64,
    pub subdivisions: u64,
    pub unresolved_contacts: u64,
    pub energy_creep: Option<f64>,
    /// The divergence guard stopped the run with this error.
    pub guard_stop: Option<Box<crate::sim::DivergenceError>>,
    pub wall_s: f64,
}

/// A judged run.
#[derive(Debug, Clone)]
pub struct Outcome {
    pub name: &'static str,
    pub description: String,
    pub vertices: usize,
    pub integrator: &'static str,
    pub dt: f64,
    pub substeps: u32,
    pub criteria: Criteria,
    pub worst: Worst,
    /// Each violated criterion, in words; empty when the case passed.
    pub failures: Vec<String>,
}

impl Outcome {
    pub fn passed(&self) -> bool {
        self.failures.is_empty()
    }
}

/// Forces through which the outside does work on the cloth: wind on free vertices, and for
/// driven vertices minus every force the cloth and gravity put on them (what the driver supplies).
fn external_forces(sim: &Simulation, out: &mut Vec<Vec3>, scratch: &mut Vec<Vec3>) {
    let n = sim.cloth.len();
    out.clear();
    out.resize(n, Vec3::ZERO);
    let s = State {
        t: sim.time(),
        x: &sim.cloth.x,
        v: &sim.cloth.v,
    };
    sim.effects().injecting_forces(&s, out);
    if sim.cloth.kinematic.is_empty() {
        return;
    }
    scratch.clear();
    scratch.resize(n, Vec3::ZERO);
    sim.effects().forces(&s, scratch);
    for (i, _) in &sim.cloth.kinematic {
        out[*i as usize] = -scratch[*i as usize];
    }
}

/// The deepest free cloth vertex inside an obstacle's solid (m; 0 when none is), at the
/// obstacles' current poses (see [`Solids`]).
fn deepest_free(solids: &Solids, sim: &Simulation) -> f64 {
    let Some(stage) = sim.collision() else {
        return 0.0;
    };
    (sim.cloth.x.iter().enumerate())
        // A held vertex is where the scene puts it; only free vertices are judged.
        .filter(|(i, _)| sim.cloth.kinematic_of(*i as u32).is_none())
        .map(|(_, p)| solids.depth(stage, *p))
        .fold(0.0, f64::max)
}

fn attached_drift(sim: &Simulation) -> f64 {
    sim.cloth
        .kinematic
        .iter()
        .map(|(i, k)| {
            let target = match *k {
                Kinematic::Pinned(p) => p,
                Kinematic::Attached { frame, local } => {
                    sim.frames.pose(frame).transform_point(local)
                }
            };
            (sim.cloth.x[*i as usize] - target).length()
        })
        .fold(0.0, f64::max)
}

/// Gravity scale `M g L` of the cloth: the energy a fall through its own size releases.
fn gravity_scale(sim: &Simulation) -> f64 {
    let c = &sim.cloth;
    let mass: f64 = c.mass.iter().sum();
    let (lo, hi) = c.x.iter().fold(
        (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let size = if c.x.is_empty() {
        0.0
    } else {
        (hi - lo).length()
    };
    mass * sim.effects().gravity().length() * size
}

/// Runs `case` to its duration (or until the guard stops it) and judges it.
pub fn run_case(case: Case) -> Outcome {
    let Case {
        name,
        description,
        mut sim,
        mut driver,
        duration,
        criteria,
    } = case;
    let wall = Instant::now();
    let dt = sim.settings.dt;
    let frames = (duration / dt).round().max(1.0) as usize;
    let mut w = Worst {
        all_finite: true,
        ..Worst::default()
    };
    let mut e_start = {
        let (ke, pe) = sim.energy();
        ke + pe
    };
    let dynamic0 = sim.energy().0 + sim.effects().energy_split(&sim.cloth.x).0;
    let gravity0 = gravity_scale(&sim);
    let mut work = 0.0;
    let mut referenced = false;
    let mut peak_dynamic = dynamic0;
    let mut excess = f64::NEG_INFINITY;
    let mut energies = Vec::with_capacity(frames);
    let (mut f0, mut f1, mut scratch) = (Vec::new(), Vec::new(), Vec::new());
    let mut x0 = Vec::new();
    let solids = (criteria.max_inside_solid)
        .and(sim.collision())
        .map(Solids::of);
    for frame in 0..frames {
        // Energy is always measured and reported; it is judged only where the case says so.
        external_forces(&sim, &mut f0, &mut scratch);
        x0.clone_from(&sim.cloth.x);
        if let Some(d) = driver.as_mut() {
            let t = sim.time() + dt;
            d.advance(&mut sim, t);
        }
        let m = match sim.step() {
            Ok(m) => m.clone(),
            Err(e) => {
                w.guard_stop = Some(e);
                break;
            }
        };
        w.frames = frame + 1;
        w.subdivisions += u64::from(m.subdivisions);
        w.unresolved_contacts += m.unresolved_contacts as u64;
        w.max_penetration = w.max_penetration.max(m.deepest_penetration);
        if let Some(si) = m.self_intersections {
            w.max_self_intersections = Some(w.max_self_intersections.unwrap_or(0).max(si));
        }
        let c = &sim.cloth;
        if !c.x.iter().chain(&c.v).all(|p| p.is_finite()) {
            w.all_finite = false;
            break;
        }
        w.max_abs_x = c.x.iter().map(|p| p.length()).fold(w.max_abs_x, f64::max);
        w.max_stretch = w.max_stretch.max(1.0 + c.max_edge_stretch());
        if let Some(solids) = &solids {
            let d = deepest_free(solids, &sim);
            w.max_inside_solid = Some(w.max_inside_solid.unwrap_or(0.0).max(d));
        }
        w.max_speed = w.max_speed.max(m.max_speed);
        w.max_attached_drift = w.max_attached_drift.max(attached_drift(&sim));
        let e = m.kinetic_energy + m.potential_energy;
        energies.push(e);
        external_forces(&sim, &mut f1, &mut scratch);
        let dw: f64 = (0..c.len())
            .map(|i| 0.5 * (f0[i] + f1[i]).dot(c.x[i] - x0[i]))
            .sum();
        work += dw;
        peak_dynamic = peak_dynamic.max(m.kinetic_energy + sim.effects().energy_split(&c.x).0);
        // A case that starts inside an obstacle pays its lead-out once: the reference is the
        // first frame from `energy_from_frame` on that ends with every vertex out.
        if !referenced
            && criteria.energy_from_frame > 0
            && frame + 1 >= criteria.energy_from_frame
            && m.exiting_vertices == 0
        {
            (e_start, work, referenced) = (e, 0.0, true);
        }
        if e - e_start - work > excess {
            excess = e - e_start - work;
            w.energy_excess_at = sim.time();
        }
    }
    w.simulated_s = sim.time();
    w.energy_scale = peak_dynamic.max(gravity0);
    if excess.is_finite() && w.energy_scale > 0.0 {
        w.energy_excess = Some(excess / w.energy_scale);
    }
    if criteria.max_energy_creep.is_some() && energies.len() >= 20 {
        let tenth = energies.len() / 10;
        let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
        let early = mean(&energies[tenth..2 * tenth]);
        let late = mean(&energies[energies.len() - tenth..]);
        w.energy_creep = Some((late - early) / gravity0.max(f64::MIN_POSITIVE));
    }
    w.wall_s = wall.elapsed().as_secs_f64();
    let failures = judge(&criteria, &w, frames);
    Outcome {
        name,
        description,
        vertices: sim.cloth.len(),
        integrator: sim.integrator_name(),
        dt,
        substeps: sim.settings.substeps,
        criteria,
        worst: w,
        failures,
    }
}

fn judge(c: &Criteria, w: &Worst, frames: usize) -> Vec<String> {
    let mut f = Vec::new();
    if let Some(e) = &w.guard_stop {
        f.push(format!("stopped by the divergence guard: {e}"));
    }
    if !w.all_finite {
        f.push("non-finite position or velocity".into());
    }
    if w.frames < frames && w.guard_stop.is_none() && w.all_finite {
        f.push(format!("ran {} of {frames} frames", w.frames));
    }
    if w.max_abs_x > c.max_abs_x {
        f.push(format!(
            "max |x| {:.3e} m > {:.3e} m",
            w.max_abs_x, c.max_abs_x
        ));
    }
    if w.max_speed > c.max_speed {
        f.push(format!(
            "max speed {:.3e} m/s > {:.3e} m/s",
            w.max_speed, c.max_speed
        ));
    }
    if let (EnergyCheck::Bounded { margin }, Some(e)) = (c.energy, w.energy_excess) {
        if e > margin {
            f.push(format!(
                "energy exceeds initial + external work by {e:.3e} of the scale (margin {margin})"
            ));
        }
    }
    if let Some(p) = c.max_penetration {
        if w.max_penetration > p {
            f.push(format!(
                "penetration {:.3e} m > {p:.3e} m",
                w.max_penetration
            ));
        }
    }
    if let (Some(limit), Some(d)) = (c.max_inside_solid, w.max_inside_solid) {
        if d > limit {
            f.push(format!(
                "a vertex {d:.3e} m inside an obstacle's solid > {limit:.3e} m"
            ));
        }
    }
    if let Some(limit) = c.max_stretch {
        if w.max_stretch > limit {
            f.push(format!(
                "an edge stretched to {:.3} times its rest length > {limit:.3}",
                w.max_stretch
            ));
        }
    }
    if let (Some(limit), Some(n)) = (c.max_self_intersections, w.max_self_intersections) {
        if n > limit {
            f.push(format!("{n} self-intersecting triangle pairs > {limit}"));
        }
    }
    if w.max_attached_drift > c.max_attached_drift {
        f.push(format!(
            "attached vertex drift {:.3e} m > {:.3e} m",
            w.max_attached_drift, c.max_attached_drift
        ));
    }
    if let (Some(limit), Some(creep)) = (c.max_energy_creep, w.energy_creep) {
        if creep.abs() > limit {
            f.push(format!("energy creep {creep:.3e} > {limit}"));
        }
    }
    if c.expect_subdivisions && w.subdivisions == 0 {
        f.push("the case is built to need subdivision but the guard never subdivided".into());
    }
    f
}
