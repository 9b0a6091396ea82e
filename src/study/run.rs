//! One run of the study: a scene with one setting of the accuracy knobs, stepped for a fixed
//! simulated time, sampled at fixed times, timed step by step.

use super::scenes::StudyScene;
use crate::collide::narrow::triangles_intersect;
use crate::collide::DetectionMode;
use crate::integrate::IntegratorKind;
use crate::scene::SceneError;
use crate::sim::DivergencePolicy;
use crate::Vec3;
use std::time::Instant;

/// Frame rate every step size in the study divides: `dt = 1 / (BASE_RATE * 2^level)`.
pub const BASE_RATE: f64 = 60.0;

/// The knobs of one run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSettings {
    pub scene: StudyScene,
    /// Vertices along the longer side of the grid.
    pub n: usize,
    /// Factor on the scene's stretch and shear stiffness.
    pub stiffness: f64,
    pub integrator: IntegratorKind,
    /// `dt = 1 / (60 * 2^dt_level)`.
    pub dt_level: u32,
    pub cg_tolerance: f64,
    pub cg_max_iterations: u32,
    /// Collision detection mode and self-collision; `None` keeps the scene's own.
    pub collision: Option<(DetectionMode, bool)>,
}

impl RunSettings {
    pub fn dt(&self) -> f64 {
        1.0 / (BASE_RATE * f64::from(1u32 << self.dt_level))
    }
}

/// How long a run lasts and when it is compared with the reference, in base frames (1/60 s).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Horizon {
    /// Sample times in base frames, increasing; the last one ends the run.
    pub sample_frames: Vec<u32>,
}

impl Horizon {
    pub fn duration(&self) -> f64 {
        f64::from(self.sample_frames.last().copied().unwrap_or(0)) / BASE_RATE
    }
    pub fn sample_times(&self) -> Vec<f64> {
        self.sample_frames
            .iter()
            .map(|&f| f64::from(f) / BASE_RATE)
            .collect()
    }
}

/// Cloth state at the sample times (fewer samples if the run diverged first).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Trajectory {
    pub positions: Vec<Vec<Vec3>>,
    /// Total energy (kinetic + potential) at each sample.
    pub energy: Vec<f64>,
}

/// What a run did, before comparison with the reference.
#[derive(Debug, Clone, Default)]
pub struct RunOutput {
    pub trajectory: Trajectory,
    pub vertices: usize,
    pub steps: u64,
    /// Simulated time reached (s).
    pub simulated: f64,
    /// Wall time spent inside `Simulation::step` (s).
    pub wall: f64,
    pub cg_iterations: u64,
    pub force_evaluations: u64,
    pub total_mass: f64,
    /// `Some(message)` if the divergence guard stopped the run.
    pub diverged: Option<String>,
    /// Time at which it diverged.
    pub diverged_at: Option<f64>,
    /// Whether the scene has a collision stage (the two figures below are meaningful).
    pub collides: bool,
    /// Deepest penetration into an obstacle's thickness layer over all steps (m).
    pub deepest_penetration: f64,
    /// Most intersecting non-adjacent triangle pairs at any sample time (brute force).
    pub self_intersections: usize,
    /// Wall time of the collision stage (s).
    pub collision_wall: f64,
}

/// Runs one setting. The guard's policy is `stop`, so an unstable setting ends with a
/// [`crate::sim::DivergenceError`] and is reported, never silently rescued by subdivision.
pub fn run(settings: &RunSettings, horizon: &Horizon) -> Result<RunOutput, SceneError> {
    let mut scene = settings.scene.scene(settings.n, settings.stiffness)?;
    scene.solver.integrator = settings.integrator;
    scene.solver.dt = settings.dt();
    scene.solver.substeps = 1;
    scene.solver.cg_tolerance = settings.cg_tolerance;
    scene.solver.cg_max_iterations = settings.cg_max_iterations;
    scene.solver.guard.policy = DivergencePolicy::Stop;
    if let Some((mode, self_collision)) = settings.collision {
        scene.collision.mode = mode;
        scene.collision.self_collision = self_collision;
    }
    let collides = scene.needs_collision();
    let mut sim = scene.build()?;
    let per_frame = 1u64 << settings.dt_level;
    let mut out = RunOutput {
        vertices: sim.cloth.len(),
        collides,
        total_mass: sim.cloth.mass.iter().sum(),
        ..RunOutput::default()
    };
    let mut frame = 0u64;
    'samples: for &target in &horizon.sample_frames {
        while frame < u64::from(target) {
            for _ in 0..per_frame {
                let t0 = Instant::now();
                let result = sim.step().map(|m| {
                    (
                        m.cg_iterations,
                        m.force_evaluations,
                        m.deepest_penetration,
                        m.collision_time_s,
                    )
                });
                out.wall += t0.elapsed().as_secs_f64();
                match result {
                    Ok((cg, fe, pen, ct)) => {
                        out.deepest_penetration = out.deepest_penetration.max(pen);
                        out.collision_wall += ct;
                        out.steps += 1;
                        out.cg_iterations += u64::from(cg);
                        out.force_evaluations += u64::from(fe);
                    }
                    Err(e) => {
                        out.diverged_at = Some(e.time);
                        out.diverged = Some(e.to_string());
                        break 'samples;
                    }
                }
            }
            frame += 1;
        }
        let (ke, pe) = sim.energy();
        if collides {
            out.self_intersections = out
                .self_intersections
                .max(count_intersections(&sim.cloth.x, &sim.cloth.triangles));
        }
        out.trajectory.positions.push(sim.cloth.x.clone());
        out.trajectory.energy.push(ke + pe);
    }
    out.simulated = sim.time();
    Ok(out)
}

/// Intersecting pairs of triangles that share no vertex, by brute force with a bounding-box
/// cull: independent of the collision stage it is measuring.
pub fn count_intersections(x: &[Vec3], triangles: &[[u32; 3]]) -> usize {
    let tri = |t: &[u32; 3]| t.map(|i| x[i as usize]);
    let boxes: Vec<(Vec3, Vec3)> = triangles
        .iter()
        .map(|t| {
            let p = tri(t);
            (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]))
        })
        .collect();
    let mut count = 0;
    for a in 0..triangles.len() {
        for b in a + 1..triangles.len() {
            let (ta, tb) = (&triangles[a], &triangles[b]);
            if ta.iter().any(|v| tb.contains(v)) {
                continue;
            }
            let (ba, bb) = (boxes[a], boxes[b]);
            if ba.0.cmpgt(bb.1).any() || bb.0.cmpgt(ba.1).any() {
                continue;
            }
            if triangles_intersect(tri(ta), tri(tb)) {
                count += 1;
            }
        }
    }
    count
}
