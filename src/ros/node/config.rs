//! How the simulation loop runs: its publishing rates, frame and colour ([`LoopConfig`]), and
//! the real-time preview that trades an implicit scene's accuracy for speed
//! ([`real_time_preview`]).

use crate::ros::Distro;
use crate::scene::Scene;

/// How the loop publishes.
#[derive(Debug, Clone)]
pub struct LoopConfig {
    /// Node name: diagnostics status name and marker namespace.
    pub name: String,
    pub distro: Distro,
    /// Empty: the robot's root link, else `world`.
    pub frame_id: String,
    pub publish_rate: f64,
    /// 0: no obstacle markers.
    pub obstacles_rate: f64,
    pub diagnostics_rate: f64,
    pub max_backlog_steps: u32,
    pub paused: bool,
    pub color: [f32; 4],
}

impl Default for LoopConfig {
    fn default() -> Self {
        Self {
            name: "drape".into(),
            distro: Distro::Jazzy,
            frame_id: String::new(),
            publish_rate: 30.0,
            obstacles_rate: 2.0,
            diagnostics_rate: 1.0,
            max_backlog_steps: 6,
            paused: false,
            color: [0.85, 0.35, 0.2, 1.0],
        }
    }
}

/// The real-time preview solver settings: one substep, CG tolerance 1e-2, at most 50 CG
/// iterations, for an implicit scene (other integrators keep their settings: fewer substeps
/// would make them unstable). Trades accuracy (stiffer-looking, less converged cloth) for a
/// step several times cheaper, so a large cloth can keep real time.
pub fn real_time_preview(scene: &mut Scene) {
    if scene.solver.integrator == crate::integrate::IntegratorKind::Implicit {
        scene.solver.substeps = 1;
        scene.solver.cg_tolerance = scene.solver.cg_tolerance.max(1e-2);
        scene.solver.cg_max_iterations = scene.solver.cg_max_iterations.min(50);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn towel(res: usize) -> Scene {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/config/robot_towel.yaml");
        let mut scene = Scene::load(path.as_ref()).expect("robot_towel scene");
        scene.cloths[0].grid.resolution = [res, res];
        scene
    }

    #[test]
    fn real_time_preview_changes_only_implicit_solver_settings() {
        let mut scene = towel(6);
        real_time_preview(&mut scene);
        let s = &scene.solver;
        assert_eq!(
            (s.substeps, s.cg_tolerance, s.cg_max_iterations),
            (1, 1e-2, 50)
        );
        let mut explicit = towel(6);
        explicit.solver.integrator = crate::integrate::IntegratorKind::SymplecticEuler;
        explicit.solver.substeps = 40;
        let before = explicit.solver.clone();
        real_time_preview(&mut explicit);
        assert_eq!(explicit.solver, before);
    }
}
