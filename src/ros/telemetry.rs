//! The quality of a recording: per frame, as `diagnostic_msgs/msg/DiagnosticArray` on
//! `/diagnostics` in the bag (the node's keys, so the same plots work on both), and for the whole
//! run, as the table `drape record` prints and the JSON `--summary FILE` writes.
//!
//! A frame's values cover the steps since the previous frame: counts are summed (substeps,
//! subdivisions, CG iterations), extremes are the worst over those steps (CG residual, deepest
//! penetration), states are the frame's own (contacts, pinched vertices and their grip, energy,
//! edge stretch, self-intersections).
//! Step wall time is left out of the bag unless asked for ([`FrameQuality::diagnostics`]'s
//! `wall_time`): with it a bag is no longer the same bytes from run to run.
//!
//! Edge stretch of an edge `(i, j)` is `|x_i - x_j| / |uv_i - uv_j| - 1` (the rest material
//! coordinates `uv` are in metres), over every triangle edge; the frame reports the largest.

use crate::cloth::Cloth;
use crate::integrate::LinearPath;
use crate::ros::msg::{DiagnosticArray, DiagnosticStatus, Header, KeyValue, Time};
use crate::sim::StepMetrics;
use serde::{Deserialize, Serialize};

/// Quality of one recorded frame (the steps since the previous frame).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrameQuality {
    pub sim_time: f64,
    pub steps: u64,
    pub substeps: u64,
    pub subdivisions: u64,
    /// Substeps split where a link moved fast relative to the cloth near it.
    pub contact_splits: u64,
    /// Substeps where a link still outran the cloth past the split levels allowed.
    pub contact_splits_refused: u64,
    pub cg_iterations: u64,
    /// Most CG iterations of one step.
    pub cg_iterations_max: u32,
    pub cg_residual_max: f64,
    /// Obstacle contacts at the end of the last step.
    pub contacts: usize,
    pub unresolved_contacts: usize,
    /// Vertices still on their way out of an obstacle the cloth started inside (last step).
    pub exiting_vertices: usize,
    /// Cloth-cloth contacts whose friction slid (last step; see `StepMetrics`).
    pub slipping_vertices: usize,
    pub deepest_penetration: f64,
    /// Largest relative edge stretch at the frame (0 at rest length).
    pub max_edge_stretch: f64,
    /// Intersecting triangle pairs at the last step, when the scene counts them.
    pub self_intersections: Option<usize>,
    pub kinetic_energy: f64,
    pub potential_energy: f64,
    /// Wall time of the steps (s).
    pub wall_time_s: f64,
    /// Edges the strain limit shortened (`None`: the scene sets no limit).
    pub strain_limited: Option<u64>,
    /// Largest elongation beyond the strain limit left after its passes (0: it held).
    pub strain_limit_excess: f64,
    /// Vertices squeezed between two obstacles (a pinch) at the last step.
    pub pinched_vertices: usize,
    /// The pinch's grip normal force at the last step (N; see [`StepMetrics`]).
    pub grip_normal_force: f64,
    /// Held vertices inside an obstacle's solid at the last step, and the deepest over the
    /// window (m; see [`StepMetrics`]).
    pub held_inside: usize,
    pub held_inside_depth: f64,
    /// The implicit step's linear path at the last step (`None`: an explicit method), and the
    /// Cholesky factorisations of the direct path.
    pub linear_path: Option<LinearPath>,
    pub factorisations: u64,
}

impl FrameQuality {
    /// Adds one step's metrics.
    pub fn add_step(&mut self, m: &StepMetrics) {
        self.sim_time = m.time;
        self.steps += 1;
        self.substeps += u64::from(m.substeps);
        self.subdivisions += u64::from(m.subdivisions);
        self.contact_splits += u64::from(m.contact_splits);
        self.contact_splits_refused += u64::from(m.contact_splits_refused);
        self.cg_iterations += u64::from(m.cg_iterations);
        self.cg_iterations_max = self.cg_iterations_max.max(m.cg_iterations);
        self.cg_residual_max = self.cg_residual_max.max(m.cg_residual_max);
        self.contacts = m.contacts;
        self.unresolved_contacts = m.unresolved_contacts;
        self.exiting_vertices = m.exiting_vertices;
        self.slipping_vertices = m.slipping_vertices;
        self.deepest_penetration = self.deepest_penetration.max(m.deepest_penetration);
        self.self_intersections = m.self_intersections;
        self.kinetic_energy = m.kinetic_energy;
        self.potential_energy = m.potential_energy;
        self.wall_time_s += m.wall_time_s;
        self.linear_path = m.linear_path;
        self.factorisations += u64::from(m.factorisations);
        if let Some(n) = m.strain_limited {
            *self.strain_limited.get_or_insert(0) += u64::from(n);
        }
        self.strain_limit_excess = self.strain_limit_excess.max(m.strain_limit_excess);
        self.pinched_vertices = m.pinched_vertices;
        self.grip_normal_force = m.grip_normal_force;
        self.held_inside = m.held_inside;
        self.held_inside_depth = self.held_inside_depth.max(m.held_inside_depth);
    }

    /// The next window's start: no steps yet, the state values (time, contacts, vertices on
    /// their way out, self-intersections, energies, edge stretch, linear path) kept until a step replaces
    /// them.
    pub fn next_window(&self) -> FrameQuality {
        FrameQuality {
            sim_time: self.sim_time,
            contacts: self.contacts,
            exiting_vertices: self.exiting_vertices,
            pinched_vertices: self.pinched_vertices,
            grip_normal_force: self.grip_normal_force,
            held_inside: self.held_inside,
            self_intersections: self.self_intersections,
            kinetic_energy: self.kinetic_energy,
            potential_energy: self.potential_energy,
            linear_path: self.linear_path,
            ..FrameQuality::default()
        }
    }

    /// The window's values on `/diagnostics`, one per row of [`METRICS`] that has one.
    pub fn values(&self) -> Vec<KeyValue> {
        (METRICS.iter())
            .filter_map(|(key, value)| {
                value(self).map(|value| KeyValue {
                    key: key.to_string(),
                    value,
                })
            })
            .collect()
    }

    /// Sets the frame's state values (time, edge stretch) from the cloth at the frame.
    pub fn at_frame(&mut self, sim_time: f64, cloth: &Cloth) {
        self.sim_time = sim_time;
        self.max_edge_stretch = max_edge_stretch(cloth);
    }

    /// The frame as one `DiagnosticStatus` named `<name>: quality` (WARN when a substep was
    /// subdivided or cloth-cloth contacts stayed unresolved). `wall_time` adds
    /// `step_wall_time_ms`, which makes the bag differ from run to run.
    pub fn diagnostics(&self, name: &str, stamp: Time, wall_time: bool) -> DiagnosticArray {
        let (level, message) = if self.held_inside > 0 {
            (
                DiagnosticStatus::WARN,
                format!(
                    "{} held cloth vertices inside an obstacle, up to {:.1} mm: the scene drives \
                     held cloth into a solid",
                    self.held_inside,
                    self.held_inside_depth * 1e3
                ),
            )
        } else if self.unresolved_contacts > 0 {
            (
                DiagnosticStatus::WARN,
                format!("{} unresolved cloth contacts", self.unresolved_contacts),
            )
        } else if self.contact_splits_refused > 0 {
            (
                DiagnosticStatus::WARN,
                format!(
                    "{} substeps answered a fast link coarser than fast contact asks \
                     (solver.guard.max_contact_split_levels)",
                    self.contact_splits_refused
                ),
            )
        } else if self.strain_limit_excess > 0.0 {
            (
                DiagnosticStatus::WARN,
                format!(
                    "edges {:.2} % beyond the strain limit after its passes",
                    self.strain_limit_excess * 1e2
                ),
            )
        } else if self.subdivisions > 0 {
            (
                DiagnosticStatus::WARN,
                format!("{} substeps subdivided for stability", self.subdivisions),
            )
        } else if self.exiting_vertices > 0 {
            (
                DiagnosticStatus::WARN,
                format!(
                    "{} cloth vertices still on their way out of an obstacle they started inside",
                    self.exiting_vertices
                ),
            )
        } else {
            (DiagnosticStatus::OK, "ok".to_string())
        };
        let mut values = self.values();
        if wall_time {
            values.push(KeyValue {
                key: "step_wall_time_ms".into(),
                value: format!("{:.3}", self.wall_time_s * 1e3),
            });
        }
        DiagnosticArray {
            header: Header::new(stamp, ""),
            status: vec![DiagnosticStatus {
                level,
                name: format!("{name}: quality"),
                message,
                hardware_id: name.to_string(),
                values,
            }],
        }
    }
}

/// A window's value of one metric on `/diagnostics` (`None`: not written for this window).
type Value = fn(&FrameQuality) -> Option<String>;

/// The simulation's metrics on `/diagnostics`, in order: each key with its value and format.
/// The recorder's bags and the node both write these rows, so the same plots work on both; a
/// new metric is a field of [`StepMetrics`] and [`FrameQuality`] and a row here. Numbers are
/// written as their shortest round-trip decimals: a reader gets back the exact f64. Rows that
/// only some scenes have are left out where they have nothing to say, so that other bags keep
/// their bytes.
pub const METRICS: &[(&str, Value)] = &[
    ("sim_time_s", |q| Some(q.sim_time.to_string())),
    ("steps", |q| Some(q.steps.to_string())),
    ("substeps", |q| Some(q.substeps.to_string())),
    ("subdivisions", |q| Some(q.subdivisions.to_string())),
    ("contact_splits", |q| Some(q.contact_splits.to_string())),
    ("contact_splits_refused", |q| {
        Some(q.contact_splits_refused.to_string())
    }),
    ("cg_iterations", |q| Some(q.cg_iterations.to_string())),
    ("cg_iterations_max", |q| {
        Some(q.cg_iterations_max.to_string())
    }),
    ("cg_residual_max", |q| Some(q.cg_residual_max.to_string())),
    ("contacts", |q| Some(q.contacts.to_string())),
    ("unresolved_contacts", |q| {
        Some(q.unresolved_contacts.to_string())
    }),
    ("deepest_penetration_m", |q| {
        Some(q.deepest_penetration.to_string())
    }),
    ("max_edge_stretch", |q| Some(q.max_edge_stretch.to_string())),
    ("kinetic_energy_j", |q| Some(q.kinetic_energy.to_string())),
    ("potential_energy_j", |q| {
        Some(q.potential_energy.to_string())
    }),
    ("energy_j", |q| {
        Some((q.kinetic_energy + q.potential_energy).to_string())
    }),
    // Only where the scene counts them.
    ("self_intersections", |q| {
        q.self_intersections.map(|n| n.to_string())
    }),
    // Only where the scene limits strain.
    ("strain_limited_edges", |q| {
        q.strain_limited.map(|n| n.to_string())
    }),
    ("strain_limit_excess", |q| {
        (q.strain_limited.is_some()).then(|| q.strain_limit_excess.to_string())
    }),
    // Only on the direct linear path (PCG's runs keep their bytes).
    ("linear_path", |q| {
        (q.linear_path == Some(LinearPath::Direct)).then(|| LinearPath::Direct.name().to_string())
    }),
    ("factorisations", |q| {
        (q.factorisations > 0).then(|| q.factorisations.to_string())
    }),
    // Only while there are any.
    ("exiting_vertices", |q| {
        (q.exiting_vertices > 0).then(|| q.exiting_vertices.to_string())
    }),
    // Only while something pinches the cloth.
    ("pinched_vertices", |q| {
        (q.pinched_vertices > 0).then(|| q.pinched_vertices.to_string())
    }),
    ("grip_normal_force_n", |q| {
        (q.pinched_vertices > 0).then(|| q.grip_normal_force.to_string())
    }),
    // Only while held cloth is inside a solid.
    ("held_inside_vertices", |q| {
        (q.held_inside > 0).then(|| q.held_inside.to_string())
    }),
    ("held_inside_depth_m", |q| {
        (q.held_inside > 0).then(|| q.held_inside_depth.to_string())
    }),
    // Only while cloth slides on cloth.
    ("slipping_vertices", |q| {
        (q.slipping_vertices > 0).then(|| q.slipping_vertices.to_string())
    }),
];

/// Largest `|x_i - x_j| / |uv_i - uv_j| - 1` over the triangle edges (0 for no cloth); edges of
/// zero rest length are skipped.
pub fn max_edge_stretch(cloth: &Cloth) -> f64 {
    cloth.max_edge_stretch()
}

/// Totals over a whole recording, gathered frame by frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunQuality {
    pub substeps: u64,
    pub cg_iterations: u64,
    pub cg_iterations_max: u32,
    pub cg_residual_max: f64,
    pub contacts_max: usize,
    pub unresolved_contacts_max: usize,
    pub worst_penetration: f64,
    pub worst_stretch: f64,
    pub self_intersections_max: Option<usize>,
}

impl RunQuality {
    /// Adds a written frame.
    pub fn add_frame(&mut self, f: &FrameQuality) {
        self.substeps += f.substeps;
        self.cg_iterations += f.cg_iterations;
        self.cg_iterations_max = self.cg_iterations_max.max(f.cg_iterations_max);
        self.cg_residual_max = self.cg_residual_max.max(f.cg_residual_max);
        self.contacts_max = self.contacts_max.max(f.contacts);
        self.unresolved_contacts_max = self.unresolved_contacts_max.max(f.unresolved_contacts);
        self.worst_penetration = self.worst_penetration.max(f.deepest_penetration);
        self.worst_stretch = self.worst_stretch.max(f.max_edge_stretch);
        if let Some(n) = f.self_intersections {
            self.self_intersections_max = Some(self.self_intersections_max.unwrap_or(0).max(n));
        }
    }
}

/// The run summary `drape record` prints and writes with `--summary FILE` (JSON), and a sweep
/// job keeps in its result record.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    pub frames: u64,
    pub steps: u64,
    pub substeps: u64,
    pub subdivisions: u64,
    pub cg_iterations_mean: f64,
    pub cg_iterations_max: u32,
    pub cg_residual_max: f64,
    pub contacts_max: usize,
    pub worst_penetration_m: f64,
    pub worst_stretch: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub self_intersections_max: Option<usize>,
    pub simulated_s: f64,
    pub wall_s: f64,
    /// Simulated over wall seconds.
    pub real_time_factor: f64,
    pub interrupted: bool,
}

impl RunSummary {
    /// Rows of `name | value` as a Markdown-style table for the terminal.
    pub fn table(&self) -> String {
        let rows: Vec<(&str, String)> = vec![
            ("frames", self.frames.to_string()),
            ("steps", self.steps.to_string()),
            ("substeps", self.substeps.to_string()),
            ("subdivisions", self.subdivisions.to_string()),
            (
                "CG iterations / step (mean, max)",
                format!("{:.1}, {}", self.cg_iterations_mean, self.cg_iterations_max),
            ),
            ("CG residual (max)", format!("{:.2e}", self.cg_residual_max)),
            ("contacts (max)", self.contacts_max.to_string()),
            (
                "worst penetration",
                format!("{:.3} mm", self.worst_penetration_m * 1e3),
            ),
            (
                "worst edge stretch",
                format!("{:.2} %", self.worst_stretch * 1e2),
            ),
            (
                "self-intersections (max)",
                self.self_intersections_max
                    .map_or_else(|| "not counted".to_string(), |n| n.to_string()),
            ),
            ("simulated", format!("{:.3} s", self.simulated_s)),
            ("wall time", format!("{:.3} s", self.wall_s)),
            ("real-time factor", format!("{:.3}", self.real_time_factor)),
        ];
        let w = rows.iter().map(|r| r.0.len()).max().unwrap_or(0);
        let mut out = String::new();
        for (k, v) in rows {
            out.push_str(&format!("{k:<w$}  {v}\n"));
        }
        if self.interrupted {
            out.push_str("(interrupted: the bag was finished early)\n");
        }
        out
    }

    /// As pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|_| "{}".to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::{Material, Panel};
    use crate::Pose;

    #[test]
    fn edge_stretch_of_a_scaled_grid() {
        let mut c = Cloth::new();
        let panel = Panel::grid("g", [1.0, 1.0], [4, 4], &Pose::IDENTITY);
        c.add_panel(panel, Material::default());
        assert!(max_edge_stretch(&c).abs() < 1e-12);
        for x in &mut c.x {
            x.x *= 1.1;
        }
        assert!((max_edge_stretch(&c) - 0.1).abs() < 1e-9);
    }

    #[test]
    fn frame_keys_and_wall_time_only_on_request() {
        let mut f = FrameQuality::default();
        f.add_step(&StepMetrics {
            substeps: 2,
            cg_iterations: 7,
            wall_time_s: 0.002,
            ..StepMetrics::default()
        });
        let keys = |d: &DiagnosticArray| -> Vec<String> {
            d.status[0].values.iter().map(|kv| kv.key.clone()).collect()
        };
        let a = f.diagnostics("drape", Time::default(), false);
        assert!(keys(&a).contains(&"cg_iterations".to_string()));
        assert!(!keys(&a).contains(&"step_wall_time_ms".to_string()));
        assert!(!keys(&a).contains(&"self_intersections".to_string()));
        let b = f.diagnostics("drape", Time::default(), true);
        assert!(keys(&b).contains(&"step_wall_time_ms".to_string()));
        assert_eq!(a.status[0].level, DiagnosticStatus::OK);
    }
}
