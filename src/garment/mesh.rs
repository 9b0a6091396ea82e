//! Meshing a panel: the outline is resampled (seam stretches to their seam's shared vertex count,
//! free edges to the target length), triangulated with a constrained Delaunay triangulation and
//! refined to the target size and a minimum angle. The boundary vertices are kept exactly (the
//! refinement may not split them) so that both sides of a seam keep matching vertex counts.
//! Rest (u, v) coordinates are the pattern coordinates rotated into the grain frame.

use super::error::{GarmentError, MeshProblem};
use super::pattern::{outline, polyline_length, stretch_edges, stretch_points};
use super::spec::{GarmentSpec, PanelSpec, SeamSide};
use crate::scene::MAX_VERTICES;
use glam::DVec2;
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};

/// Minimum angle the refinement aims for (degrees). Ruppert-style refinement provably terminates
/// below about 20.7 deg with split boundaries; with the boundary kept, faces next to it can fall
/// short of the aim, so we ask for more and check the result against [`MIN_ANGLE_DEG`].
pub const REFINE_ANGLE_DEG: f64 = 28.0;
/// Guaranteed minimum triangle angle of a meshed panel (degrees); meshing fails below it.
pub const MIN_ANGLE_DEG: f64 = 20.0;

/// A meshed panel in its pattern plane.
#[derive(Debug, Clone)]
pub struct PanelMesh {
    pub name: String,
    /// Pattern-plane coordinates (m), for placement.
    pub points: Vec<DVec2>,
    /// Rest material coordinates: u along the warp (grain), v along the weft.
    pub uv: Vec<DVec2>,
    /// Counter-clockwise in the pattern plane when the outline is.
    pub triangles: Vec<[u32; 3]>,
    /// Boundary vertices in outline order (they are vertices `0..boundary.len()`).
    pub boundary: Vec<u32>,
}

/// The vertices of one seam side, from the stretch's `from` to its `to`.
#[derive(Debug, Clone, PartialEq)]
pub struct SideVertices {
    pub panel: usize,
    pub vertices: Vec<u32>,
}

/// Number of segments both sides of a seam are resampled to.
pub fn seam_segments(g: &GarmentSpec, a_len: f64, b_len: f64) -> usize {
    ((a_len.max(b_len) / g.edge_length).ceil() as usize).max(1)
}

/// Points `k L / n` along a polyline for `k = 0..n` (both ends included).
pub fn resample(pts: &[DVec2], n: usize) -> Vec<DVec2> {
    let total = polyline_length(pts);
    let mut out = Vec::with_capacity(n + 1);
    let mut seg = 0;
    let mut walked = 0.0;
    for k in 0..=n {
        let s = total * k as f64 / n as f64;
        while seg + 1 < pts.len() - 1 && walked + (pts[seg + 1] - pts[seg]).length() < s {
            walked += (pts[seg + 1] - pts[seg]).length();
            seg += 1;
        }
        let len = (pts[seg + 1] - pts[seg]).length();
        let f = if len > 0.0 {
            ((s - walked) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(pts[seg].lerp(pts[seg + 1], f));
    }
    if let (Some(l), Some(p)) = (out.last_mut(), pts.last()) {
        *l = *p;
    }
    out
}

/// Resampled boundary of a panel: the loop of points and, for each stretch given as
/// `(side, segments)`, the indices of its points in the loop from `from` to `to`.
pub fn boundary(
    panel: &PanelSpec,
    edge_length: f64,
    stretches: &[(&SeamSide, usize)],
) -> (Vec<DVec2>, Vec<Vec<u32>>) {
    let pts = outline(panel);
    let n = pts.len();
    // Which stretch starts at each outline vertex, and which edges stretches cover.
    let mut starts: Vec<Option<usize>> = vec![None; n];
    let mut covered = vec![false; n];
    for (k, (side, _)) in stretches.iter().enumerate() {
        starts[side.from] = Some(k);
        for e in stretch_edges(n, side) {
            covered[e] = true;
        }
    }
    // Start the walk at a vertex no stretch passes through.
    let start = (0..n)
        .find(|&v| starts[v].is_some() || !covered[(v + n - 1) % n])
        .unwrap_or(0);
    let mut loop_pts: Vec<DVec2> = Vec::new();
    let mut sides: Vec<Vec<u32>> = vec![Vec::new(); stretches.len()];
    let mut v = start;
    let mut walked = 0;
    while walked < n {
        if let Some(k) = starts[v] {
            let (side, segs) = stretches[k];
            let sample = resample(&stretch_points(&pts, side), segs);
            let first = loop_pts.len() as u32;
            loop_pts.extend_from_slice(&sample[..segs]);
            sides[k] = (first..first + segs as u32).collect();
            let edges = stretch_edges(n, side).len();
            walked += edges;
            v = side.to;
            // The stretch's end point is the next chunk's first point (or the loop's start).
            let end = if walked >= n {
                0
            } else {
                loop_pts.len() as u32
            };
            sides[k].push(end);
        } else {
            let (a, b) = (pts[v], pts[(v + 1) % n]);
            let segs = (((b - a).length() / edge_length).ceil() as usize).max(1);
            for s in 0..segs {
                loop_pts.push(a.lerp(b, s as f64 / segs as f64));
            }
            walked += 1;
            v = (v + 1) % n;
        }
    }
    (loop_pts, sides)
}

/// Minimum interior angle of a 2D triangle (degrees).
pub fn min_angle_deg(p: [DVec2; 3]) -> f64 {
    (0..3)
        .map(|k| {
            let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
            (b - a).angle_to(c - a).abs().to_degrees()
        })
        .fold(180.0, f64::min)
}

/// Meshes a panel of garment `garment` whose boundary loop is given (see [`boundary`]).
pub fn mesh_panel(
    garment: &str,
    panel: &PanelSpec,
    loop_pts: &[DVec2],
    edge_length: f64,
) -> Result<PanelMesh, GarmentError> {
    let fail = |problem: MeshProblem| GarmentError::Mesh {
        garment: garment.to_string(),
        panel: panel.name.clone(),
        problem,
    };
    let nb = loop_pts.len();
    let verts: Vec<Point2<f64>> = loop_pts.iter().map(|p| Point2::new(p.x, p.y)).collect();
    let edges: Vec<[usize; 2]> = (0..nb).map(|i| [i, (i + 1) % nb]).collect();
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::bulk_load_cdt(verts, edges)
        .map_err(|e| fail(MeshProblem::Triangulation(e)))?;
    if cdt.num_vertices() != nb {
        return Err(fail(MeshProblem::CoincidentBoundary));
    }
    let target_area = 3f64.sqrt() / 4.0 * edge_length * edge_length;
    let area = super::pattern::signed_area(loop_pts).abs();
    // Never more than a whole scene may hold, whatever the outline makes refinement do.
    let budget = ((20.0 * area / target_area) as usize + 10 * nb + 100).min(MAX_VERTICES);
    let result = cdt.refine(
        RefinementParameters::<f64>::new()
            .exclude_outer_faces(true)
            .keep_constraint_edges()
            .with_angle_limit(AngleLimit::from_deg(REFINE_ANGLE_DEG))
            .with_max_allowed_area(target_area)
            .with_max_additional_vertices(budget),
    );
    if !result.refinement_complete {
        return Err(fail(MeshProblem::NoConvergence));
    }
    let excluded: std::collections::HashSet<_> = result.excluded_faces.iter().copied().collect();
    let mut map: Vec<Option<u32>> = vec![None; cdt.num_vertices()];
    for i in 0..nb {
        map[i] = Some(i as u32);
    }
    let mut points: Vec<DVec2> = loop_pts.to_vec();
    let mut triangles = Vec::new();
    for face in cdt.inner_faces() {
        if excluded.contains(&face.fix()) {
            continue;
        }
        let mut t = [0u32; 3];
        for (k, v) in face.vertices().iter().enumerate() {
            let i = v.fix().index();
            t[k] = *map[i].get_or_insert_with(|| {
                let p = v.position();
                points.push(DVec2::new(p.x, p.y));
                (points.len() - 1) as u32
            });
        }
        triangles.push(t);
    }
    let worst = triangles
        .iter()
        .map(|t| min_angle_deg(t.map(|i| points[i as usize])))
        .fold(180.0, f64::min);
    if triangles.is_empty() || worst < MIN_ANGLE_DEG {
        return Err(fail(MeshProblem::SharpAngle {
            worst_deg: worst,
            min_deg: MIN_ANGLE_DEG,
        }));
    }
    let g = panel.grain.to_radians();
    let (warp, weft) = (DVec2::new(g.cos(), g.sin()), DVec2::new(-g.sin(), g.cos()));
    let uv = points
        .iter()
        .map(|p| DVec2::new(p.dot(warp), p.dot(weft)))
        .collect();
    Ok(PanelMesh {
        name: panel.name.clone(),
        points,
        uv,
        triangles,
        boundary: (0..nb as u32).collect(),
    })
}

/// A garment's panels meshed, with the vertices of each seam's two sides.
#[derive(Debug, Clone)]
pub struct GarmentMesh {
    pub panels: Vec<PanelMesh>,
    /// Per seam: (side a, side b), equal lengths, paired index by index (`reversed` applied).
    pub seams: Vec<(SideVertices, SideVertices)>,
}

/// Meshes every panel of a validated garment so that paired seam sides match vertex for vertex.
pub fn mesh_garment(g: &GarmentSpec) -> Result<GarmentMesh, GarmentError> {
    let indices = super::pattern::panel_indices(g);
    let panel_of = |seam: &str, name: &str| {
        indices
            .get(name)
            .copied()
            .ok_or_else(|| GarmentError::MissingPanel {
                seam: seam.to_string(),
                panel: name.to_string(),
            })
    };
    // Segments per seam, from the longer side.
    let mut per_panel: Vec<Vec<(&SeamSide, usize, usize, usize)>> =
        vec![Vec::new(); g.panels.len()];
    for (si, s) in g.seams.iter().enumerate() {
        let (pa, pb) = (
            panel_of(&s.name, &s.a.panel)?,
            panel_of(&s.name, &s.b.panel)?,
        );
        let la = polyline_length(&stretch_points(&outline(&g.panels[pa]), &s.a));
        let lb = polyline_length(&stretch_points(&outline(&g.panels[pb]), &s.b));
        let segs = seam_segments(g, la, lb);
        per_panel[pa].push((&s.a, segs, si, 0));
        per_panel[pb].push((&s.b, segs, si, 1));
    }
    let mut sides: Vec<[Option<SideVertices>; 2]> = vec![[None, None]; g.seams.len()];
    let mut panels = Vec::with_capacity(g.panels.len());
    for (pi, p) in g.panels.iter().enumerate() {
        let stretches: Vec<(&SeamSide, usize)> =
            per_panel[pi].iter().map(|&(s, n, _, _)| (s, n)).collect();
        let (loop_pts, verts) = boundary(p, g.edge_length, &stretches);
        for (k, &(_, _, si, side)) in per_panel[pi].iter().enumerate() {
            sides[si][side] = Some(SideVertices {
                panel: pi,
                vertices: verts[k].clone(),
            });
        }
        panels.push(mesh_panel(&g.name, p, &loop_pts, g.edge_length)?);
    }
    let mut seams = Vec::with_capacity(g.seams.len());
    for (s, [a, b]) in g.seams.iter().zip(sides) {
        let (Some(a), Some(mut b)) = (a, b) else {
            return Err(GarmentError::NotResampled {
                garment: g.name.clone(),
                seam: s.name.clone(),
            });
        };
        if s.reversed {
            b.vertices.reverse();
        }
        seams.push((a, b));
    }
    Ok(GarmentMesh { panels, seams })
}
