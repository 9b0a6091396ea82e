//! The quality of a recording: per frame, as `diagnostic_msgs/msg/DiagnosticArray` on
//! `/diagnostics` in the bag (the node's keys, so the same plots work on both), and for the whole
//! run, as the table `drape record` prints and the JSON `--summary FILE` writes.
//!
//! A frame's values cover the steps since the previous frame: counts are summed (substeps,
//! subdivisions, CG iterations), extremes are the worst over those steps (CG residual, deepest
//! penetration), states are the frame's own (contacts, energy, edge stretch, self-intersections).
//! Step wall time is left out of the bag unless asked for ([`FrameQuality::diagnostics`]'s
//! `wall_time`): with it a bag is no longer the same bytes from run to run.
//!
//! Edge stretch of an edge `(i, j)` is `|x_i - x_j| / |uv_i - uv_j| - 1` (the rest material
//! coordinates `uv` are in metres), over every triangle edge; the frame reports the largest.

use crate::cloth::Cloth;
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
}

impl FrameQuality {
    /// Adds one step's metrics.
    pub fn add_step(&mut self, m: &StepMetrics) {
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
        self.deepest_penetration = self.deepest_penetration.max(m.deepest_penetration);
        self.self_intersections = m.self_intersections;
        self.kinetic_energy = m.kinetic_energy;
        self.potential_energy = m.potential_energy;
        self.wall_time_s += m.wall_time_s;
        if let Some(n) = m.strain_limited {
            *self.strain_limited.get_or_insert(0) += u64::from(n);
        }
        self.strain_limit_excess = self.strain_limit_excess.max(m.strain_limit_excess);
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
        let (level, message) = if self.unresolved_contacts > 0 {
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
        let kv = |k: &str, v: String| KeyValue {
            key: k.to_string(),
            value: v,
        };
        // Shortest round-trip decimals: a reader gets back the exact f64.
        let mut values = vec![
            kv("sim_time_s", self.sim_time.to_string()),
            kv("steps", self.steps.to_string()),
            kv("substeps", self.substeps.to_string()),
            kv("subdivisions", self.subdivisions.to_string()),
            kv("contact_splits", self.contact_splits.to_string()),
            kv(
                "contact_splits_refused",
                self.contact_splits_refused.to_string(),
            ),
            kv("cg_iterations", self.cg_iterations.to_string()),
            kv("cg_iterations_max", self.cg_iterations_max.to_string()),
            kv("cg_residual_max", self.cg_residual_max.to_string()),
            kv("contacts", self.contacts.to_string()),
            kv("unresolved_contacts", self.unresolved_contacts.to_string()),
            kv(
                "deepest_penetration_m",
                self.deepest_penetration.to_string(),
            ),
            kv("max_edge_stretch", self.max_edge_stretch.to_string()),
            kv("kinetic_energy_j", self.kinetic_energy.to_string()),
            kv("potential_energy_j", self.potential_energy.to_string()),
            kv(
                "energy_j",
                (self.kinetic_energy + self.potential_energy).to_string(),
            ),
        ];
        if let Some(n) = self.self_intersections {
            values.push(kv("self_intersections", n.to_string()));
        }
        // Only where the scene limits strain: other bags keep their bytes.
        if let Some(n) = self.strain_limited {
            values.push(kv("strain_limited_edges", n.to_string()));
            values.push(kv(
                "strain_limit_excess",
                self.strain_limit_excess.to_string(),
            ));
        }
        // Only while there are any: bags of scenes that start clear keep their bytes.
        if self.exiting_vertices > 0 {
            values.push(kv("exiting_vertices", self.exiting_vertices.to_string()));
        }
        if wall_time {
            values.push(kv(
                "step_wall_time_ms",
                format!("{:.3}", self.wall_time_s * 1e3),
            ));
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
