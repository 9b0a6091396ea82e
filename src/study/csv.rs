//! `runs.csv`: every run of a study, one row each, numbers in full precision.

use super::format::{collision_mode, write};
use super::{StudyError, StudyResult};
use crate::integrate::IntegratorKind;
use std::path::{Path, PathBuf};

/// Columns of `runs.csv`.
pub const CSV_HEADER: &str = "scene,groups,integrator,dt_s,resolution,stiffness,collision_mode,self_collision,vertices,cg_tolerance,cg_max_iterations,steps,simulated_s,wall_s,wall_per_sim_s,us_per_vertex_step,realtime_factor,cg_per_step,rms_error_m,max_error_m,final_rms_error_m,energy_drift_rel,sag_error_m,deepest_penetration_m,self_intersections,collision_share,diverged,diverged_at_s,message";

fn num(x: f64) -> String {
    format!("{x:.6e}")
}

pub fn write_csv(out: &Path, r: &StudyResult) -> Result<PathBuf, StudyError> {
    let mut s = String::from(CSV_HEADER);
    s.push('\n');
    for x in &r.runs {
        let implicit = x.settings.integrator == IntegratorKind::Implicit;
        let err = |v: f64| {
            if x.diverged {
                "diverged".to_string()
            } else {
                num(v)
            }
        };
        let [a, b] = x.settings.scene.resolution(x.settings.n);
        let fields = [
            x.settings.scene.name().to_string(),
            x.groups.join("+"),
            x.settings.integrator.name().to_string(),
            num(x.settings.dt()),
            format!("{a}x{b}"),
            x.settings.stiffness.to_string(),
            collision_mode(x),
            match x.settings.collision {
                _ if !x.collides => "n/a".into(),
                Some((_, s)) => s.to_string(),
                None => "scene".into(),
            },
            x.vertices.to_string(),
            if implicit {
                num(x.settings.cg_tolerance)
            } else {
                "n/a".into()
            },
            if implicit {
                x.settings.cg_max_iterations.to_string()
            } else {
                "n/a".into()
            },
            x.steps.to_string(),
            num(x.simulated),
            num(x.wall),
            num(x.wall_per_sim_s),
            num(x.us_per_vertex_step),
            num(x.realtime_factor),
            num(x.cg_per_step),
            err(x.rms_error),
            err(x.max_error),
            err(x.final_rms_error),
            err(x.energy_drift),
            err(x.sag_error),
            if x.collides {
                num(x.deepest_penetration)
            } else {
                "n/a".into()
            },
            if x.collides {
                x.self_intersections.to_string()
            } else {
                "n/a".into()
            },
            num(x.collision_share),
            if x.diverged { "yes" } else { "no" }.to_string(),
            x.diverged_at.map_or("n/a".into(), num),
            format!("\"{}\"", x.message.replace('"', "'")),
        ];
        s.push_str(&fields.join(","));
        s.push('\n');
    }
    write(out.join("runs.csv"), &s)
}
