//! What a study measures: one [`RunRecord`] per run, and the [`StudyResult`] of the whole study.

use super::plan::Plan;
use super::run::RunSettings;
use super::scenes::StudyScene;
use std::path::PathBuf;

/// One run, measured and compared with its reference.
#[derive(Debug, Clone)]
pub struct RunRecord {
    pub groups: Vec<&'static str>,
    pub settings: RunSettings,
    pub vertices: usize,
    pub steps: u64,
    pub simulated: f64,
    pub wall: f64,
    /// Wall seconds per simulated second (1 = real time); for a diverged run, per second attempted.
    pub wall_per_sim_s: f64,
    /// Wall microseconds per vertex per step.
    pub us_per_vertex_step: f64,
    pub realtime_factor: f64,
    pub cg_per_step: f64,
    /// RMS over all sample times and vertices of the position error (m).
    pub rms_error: f64,
    /// Largest vertex position error at any sample time (m).
    pub max_error: f64,
    /// RMS position error at the last sample (m).
    pub final_rms_error: f64,
    /// (E_run - E_ref) at the last sample over total mass x |g| x scene length.
    pub energy_drift: f64,
    /// |lowest point of run - lowest point of reference| at the last sample (m).
    pub sag_error: f64,
    pub diverged: bool,
    pub diverged_at: Option<f64>,
    pub message: String,
    /// Whether the run had a collision stage; the next three are meaningful only then.
    pub collides: bool,
    /// Deepest penetration into an obstacle's thickness layer over all steps (m).
    pub deepest_penetration: f64,
    /// Most intersecting non-adjacent triangle pairs at any sample time.
    pub self_intersections: usize,
    /// Share of the step's wall time spent in the collision stage.
    pub collision_share: f64,
}

impl RunRecord {
    /// Cost on the plots' x axis.
    pub fn cost(&self) -> f64 {
        self.wall_per_sim_s
    }
}

/// Everything a study produced.
#[derive(Debug, Clone)]
pub struct StudyResult {
    pub plan: Plan,
    pub runs: Vec<RunRecord>,
    /// (scene, n, stiffness factor, reference dt, cached)
    pub references: Vec<(StudyScene, usize, f64, f64, bool)>,
    pub files: Vec<PathBuf>,
}
