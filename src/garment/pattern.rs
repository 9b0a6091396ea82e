//! Pattern validation: a panel outline must be a simple closed polygon (a self-intersecting cut
//! cannot be sewn or meshed), and seams must name existing panels, valid stretches and stretches
//! of comparable length.

use super::error::{GarmentError, OutlineProblem};
use super::spec::{GarmentSpec, PanelSpec, SeamSide, SeamSpec};
use crate::scene::{MAX_VERTICES, MIN_EDGE_LENGTH};
use glam::DVec2;

/// Largest accepted relative difference of the two sides of a seam: `|La - Lb| / max(La, Lb)`.
/// Real patterns ease a few percent; beyond this the seam would have to stretch the cloth hard.
pub const MAX_SEAM_MISMATCH: f64 = 0.2;

/// The outline as 2D points.
pub fn outline(p: &PanelSpec) -> Vec<DVec2> {
    p.outline.iter().map(|q| DVec2::new(q[0], q[1])).collect()
}

/// Signed area (positive for counter-clockwise).
pub fn signed_area(pts: &[DVec2]) -> f64 {
    let n = pts.len();
    0.5 * (0..n)
        .map(|i| pts[i].perp_dot(pts[(i + 1) % n]))
        .sum::<f64>()
}

/// Proper or touching intersection of segments `ab` and `cd`.
fn segments_intersect(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let o = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let (d1, d2, d3, d4) = (o(c, d, a), o(c, d, b), o(a, b, c), o(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    let on = |p: DVec2, q: DVec2, r: DVec2, side: f64| {
        side == 0.0
            && r.x >= p.x.min(q.x)
            && r.x <= p.x.max(q.x)
            && r.y >= p.y.min(q.y)
            && r.y <= p.y.max(q.y)
    };
    on(c, d, a, d1) || on(c, d, b, d2) || on(a, b, c, d3) || on(a, b, d, d4)
}

/// Checks one panel's outline: at least 3 finite points, no zero-length edge, no two
/// non-adjacent edges touching, non-zero area.
pub fn validate_outline(p: &PanelSpec) -> Result<(), GarmentError> {
    let bad = |problem: OutlineProblem| GarmentError::Outline {
        panel: p.name.clone(),
        problem,
    };
    let pts = outline(p);
    let n = pts.len();
    if n < 3 {
        return Err(bad(OutlineProblem::TooFewPoints { count: n }));
    }
    if n > MAX_OUTLINE_POINTS {
        return Err(bad(OutlineProblem::TooManyPoints {
            count: n,
            max: MAX_OUTLINE_POINTS,
        }));
    }
    if let Some(i) = pts.iter().position(|q| !q.is_finite()) {
        return Err(bad(OutlineProblem::NotFinite { point: i }));
    }
    for i in 0..n {
        if (pts[(i + 1) % n] - pts[i]).length() <= 1e-9 {
            return Err(bad(OutlineProblem::Coincident {
                a: i,
                b: (i + 1) % n,
            }));
        }
    }
    for i in 0..n {
        for j in i + 1..n {
            // Adjacent edges share a vertex by construction.
            if j == i + 1 || (i == 0 && j == n - 1) {
                continue;
            }
            if segments_intersect(pts[i], pts[(i + 1) % n], pts[j], pts[(j + 1) % n]) {
                return Err(GarmentError::SelfIntersecting {
                    panel: p.name.clone(),
                    edge_a: i,
                    edge_b: j,
                });
            }
        }
    }
    if signed_area(&pts).abs() < 1e-8 {
        return Err(bad(OutlineProblem::ZeroArea));
    }
    Ok(())
}

/// Outline edges `from, from+1, ..` (wrapping) up to vertex `to`, as edge indices.
pub fn stretch_edges(n: usize, side: &SeamSide) -> Vec<usize> {
    let mut out = Vec::new();
    let mut i = side.from;
    while i != side.to && out.len() < n {
        out.push(i);
        i = (i + 1) % n;
    }
    out
}

/// Points of a stretch along the outline, `from` first and `to` last.
pub fn stretch_points(pts: &[DVec2], side: &SeamSide) -> Vec<DVec2> {
    let mut out: Vec<DVec2> = stretch_edges(pts.len(), side)
        .into_iter()
        .map(|e| pts[e])
        .collect();
    out.push(pts[side.to]);
    out
}

/// Length of a polyline.
pub fn polyline_length(pts: &[DVec2]) -> f64 {
    pts.windows(2).map(|w| (w[1] - w[0]).length()).sum()
}

/// Vertices a panel is estimated to mesh into at `edge_length`, before any meshing: the refined
/// interior (refinement splits triangles above the equilateral area of the target edge, so
/// about two triangles, one vertex, per such area) plus [`BOUNDARY_GRADING`] vertices per
/// boundary vertex. The boundary keeps every outline point and splits each outline edge into
/// segments of the target length; a seam side takes its longer partner's count, at most
/// `1 / (1 - MAX_SEAM_MISMATCH)` times its own.
pub fn estimated_vertices(p: &PanelSpec, edge_length: f64) -> f64 {
    let pts = outline(p);
    let n = pts.len();
    let boundary: f64 = (0..n)
        .map(|i| {
            (pts[(i + 1) % n] - pts[i]).length() / edge_length / (1.0 - MAX_SEAM_MISMATCH) + 1.0
        })
        .sum();
    let target = 3f64.sqrt() / 4.0 * edge_length * edge_length;
    signed_area(&pts).abs() / target + BOUNDARY_GRADING * boundary
}

/// Vertices a panel's mesh has per boundary vertex beyond its area's share: refinement grades
/// the triangles from the boundary's spacing up to the target edge, so an outline of points
/// much closer than `edge_length` fills its panel with about three vertices per boundary
/// vertex (measured on circles of 1000 points); four bounds it.
pub const BOUNDARY_GRADING: f64 = 4.0;

/// Validates every panel and seam of a garment, the garment alone within
/// [`MAX_VERTICES`](crate::scene::MAX_VERTICES).
pub fn validate(g: &GarmentSpec) -> Result<(), GarmentError> {
    validate_within(g, 0.0, MAX_VERTICES).map(|_| ())
}

/// Validates every panel and seam of a garment whose scene already holds `before` vertices
/// (other cloths and garments, estimated), refusing the panel with which the estimated total
/// passes `max` before any panel is meshed. Returns the garment's estimated vertices.
pub fn validate_within(g: &GarmentSpec, before: f64, max: usize) -> Result<f64, GarmentError> {
    if g.panels.is_empty() {
        return Err(GarmentError::NoPanels {
            garment: g.name.clone(),
        });
    }
    if !(g.edge_length.is_finite() && g.edge_length >= MIN_EDGE_LENGTH) {
        return Err(GarmentError::EdgeLength {
            garment: g.name.clone(),
            edge_length: g.edge_length,
            min: MIN_EDGE_LENGTH,
        });
    }
    validate_parameters(g)?;
    let mut names = std::collections::HashSet::new();
    let mut total = before;
    for p in &g.panels {
        if !names.insert(p.name.as_str()) {
            return Err(GarmentError::DuplicatePanel {
                garment: g.name.clone(),
                panel: p.name.clone(),
            });
        }
        validate_outline(p)?;
        total += estimated_vertices(p, g.edge_length);
        // NaN: an area that overflowed.
        if total.is_nan() || total > max as f64 {
            return Err(GarmentError::Outline {
                panel: p.name.clone(),
                problem: OutlineProblem::TooManyVertices {
                    vertices: total,
                    edge_length: g.edge_length,
                    limit: max,
                },
            });
        }
        let pose = &p.placement.pose;
        if pose.xyz.iter().chain(&pose.rpy).any(|v| !v.is_finite()) || !p.grain.is_finite() {
            return Err(GarmentError::Outline {
                panel: p.name.clone(),
                problem: OutlineProblem::NonFinitePlacement,
            });
        }
        if let Some(w) = &p.placement.wrap {
            if !(w.radius.is_finite() && w.radius > 0.0) {
                return Err(GarmentError::Outline {
                    panel: p.name.clone(),
                    problem: OutlineProblem::WrapRadius { radius: w.radius },
                });
            }
        }
    }
    let panels = panel_indices(g);
    // Edges already claimed by a seam, per panel: a boundary edge is sewn at most once.
    let mut used: Vec<Vec<Option<String>>> = g
        .panels
        .iter()
        .map(|p| vec![None; p.outline.len()])
        .collect();
    let mut seams = std::collections::HashSet::new();
    for s in &g.seams {
        if !seams.insert(s.name.as_str()) {
            return Err(GarmentError::DuplicateSeam {
                garment: g.name.clone(),
                seam: s.name.clone(),
            });
        }
        validate_seam(g, &panels, s, &mut used)?;
    }
    Ok(total - before)
}

/// Each panel's index by name (names are unique in a validated garment; the first wins).
pub fn panel_indices(g: &GarmentSpec) -> std::collections::HashMap<&str, usize> {
    let mut out = std::collections::HashMap::new();
    for (k, p) in g.panels.iter().enumerate() {
        out.entry(p.name.as_str()).or_insert(k);
    }
    out
}

/// Most points a panel's outline may have: a real pattern piece has a few hundred at most, and
/// checking an outline for self-intersection takes time quadratic in its points.
pub const MAX_OUTLINE_POINTS: usize = 1000;

/// Material, sewing schedule and attachment values.
fn validate_parameters(g: &GarmentSpec) -> Result<(), GarmentError> {
    let m = &g.material;
    let s = &g.sewing;
    let checks: [(&str, f64, bool); 15] = [
        ("material.density", m.density, true),
        ("material.stretch", m.stretch, true),
        ("material.thickness", m.thickness, true),
        ("material.shear", m.shear, false),
        ("material.skip_one", m.skip_one, false),
        ("material.bend_warp", m.bend_warp, false),
        ("material.bend_weft", m.bend_weft, false),
        ("material.twist", m.twist, false),
        ("material.friction", m.friction, false),
        ("material.damping.spring", m.damping.spring, false),
        ("material.damping.air", m.damping.air, false),
        ("material.damping.diffusion", m.damping.diffusion, false),
        ("sewing.stiffness", s.stiffness, true),
        ("sewing.tolerance", s.tolerance, true),
        ("sewing.close_time", s.close_time, false),
    ];
    let limit = m.strain_limit.map(|l| ("material.strain_limit", l, true));
    for (key, v, strictly) in checks.into_iter().chain(limit) {
        let ok = v.is_finite() && if strictly { v > 0.0 } else { v >= 0.0 };
        if !ok {
            return Err(GarmentError::Value {
                garment: g.name.clone(),
                key,
                value: v,
                strictly,
            });
        }
    }
    // Each vertex carries about the area of an equilateral triangle of the target edge.
    let mass = m.density * 3f64.sqrt() / 4.0 * g.edge_length * g.edge_length;
    if !mass.is_normal() {
        return Err(GarmentError::MassTooSmall {
            garment: g.name.clone(),
            mass,
        });
    }
    if !(s.max_time.is_finite() && s.max_time > s.close_time) {
        return Err(GarmentError::MaxTime {
            garment: g.name.clone(),
            max_time: s.max_time,
            close_time: s.close_time,
        });
    }
    for (k, a) in g.attach.iter().enumerate() {
        if !(a.radius.is_finite() && a.radius > 0.0) || a.point.iter().any(|v| !v.is_finite()) {
            return Err(GarmentError::AttachShape {
                garment: g.name.clone(),
                index: k,
            });
        }
    }
    Ok(())
}

fn validate_seam(
    g: &GarmentSpec,
    panels: &std::collections::HashMap<&str, usize>,
    s: &SeamSpec,
    used: &mut [Vec<Option<String>>],
) -> Result<(), GarmentError> {
    let mut lengths = [0.0; 2];
    for (k, side) in [&s.a, &s.b].into_iter().enumerate() {
        let Some(&pi) = panels.get(side.panel.as_str()) else {
            return Err(GarmentError::MissingPanel {
                seam: s.name.clone(),
                panel: side.panel.clone(),
            });
        };
        let n = g.panels[pi].outline.len();
        for idx in [side.from, side.to] {
            if idx >= n {
                return Err(GarmentError::SeamIndex {
                    seam: s.name.clone(),
                    panel: side.panel.clone(),
                    index: idx,
                    len: n,
                });
            }
        }
        if side.from == side.to {
            return Err(GarmentError::EmptySeamSide {
                seam: s.name.clone(),
                panel: side.panel.clone(),
            });
        }
        for e in stretch_edges(n, side) {
            if let Some(other) = &used[pi][e] {
                return Err(GarmentError::SeamOverlap {
                    seam: s.name.clone(),
                    panel: side.panel.clone(),
                    edge: e,
                    other: other.clone(),
                });
            }
            used[pi][e] = Some(s.name.clone());
        }
        lengths[k] = polyline_length(&stretch_points(&outline(&g.panels[pi]), side));
    }
    let mismatch = (lengths[0] - lengths[1]).abs() / lengths[0].max(lengths[1]);
    if mismatch > MAX_SEAM_MISMATCH {
        return Err(GarmentError::SeamLength {
            seam: s.name.clone(),
            a: lengths[0],
            b: lengths[1],
            max_mismatch: MAX_SEAM_MISMATCH,
        });
    }
    Ok(())
}
