//! Springs and finite-difference stencils derived from a piece's rest (u, v) layout.
//!
//! On a lattice (grid panels, or a grid cut to a pattern outline) the stencils are the classic ones:
//! warp/weft edges, the two diagonals, skip-one neighbours, `(1, -2, 1)` second differences along
//! each direction and the `(1, -1, -1, 1)` mixed difference. A free triangle mesh gets its edges as
//! structural springs and second differences along the neighbours best aligned with u or v.

use super::{Lattice, Piece};
use glam::DVec2;

/// A two-point spring with its rest length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spring {
    pub i: u32,
    pub j: u32,
    pub rest: f64,
}

/// A linear finite-difference stencil `s = sum_k w[k] * x[idx[k]]` with energy `c/2 |s|^2`.
/// Weights already include the integration area, so `c` is the material rigidity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stencil<const N: usize> {
    pub idx: [u32; N],
    pub w: [f64; N],
}

/// Which springs of a piece to build.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpringKind {
    Structural,
    Shear,
    SkipOne,
}

fn spring(piece: &Piece, a: u32, b: u32) -> Spring {
    let uv = &piece.panel.uv;
    Spring {
        i: piece.global(a),
        j: piece.global(b),
        rest: (uv[a as usize] - uv[b as usize]).length(),
    }
}

fn lattice_pairs(l: &Lattice, offsets: &[(isize, isize)]) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for j in 0..l.nv as isize {
        for i in 0..l.nu as isize {
            let Some(a) = l.at(i, j) else { continue };
            for &(di, dj) in offsets {
                if let Some(b) = l.at(i + di, j + dj) {
                    out.push((a, b));
                }
            }
        }
    }
    out
}

/// Unique undirected edges of a triangle list.
pub fn unique_edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut e: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}

/// Springs of one kind for a piece (global indices).
pub fn springs(piece: &Piece, kind: SpringKind) -> Vec<Spring> {
    let pairs = match (&piece.panel.lattice, kind) {
        (Some(l), SpringKind::Structural) => lattice_pairs(l, &[(1, 0), (0, 1)]),
        (Some(l), SpringKind::Shear) => {
            let mut p = lattice_pairs(l, &[(1, 1)]);
            // The other diagonal: from (i+1, j) to (i, j+1).
            p.extend(lattice_pairs(l, &[(-1, 1)]));
            p
        }
        (Some(l), SpringKind::SkipOne) => lattice_pairs(l, &[(2, 0), (0, 2)]),
        (None, SpringKind::Structural) => unique_edges(&piece.panel.triangles),
        // A free triangle mesh resists shear through its own edges; skip-one needs a lattice.
        (None, _) => Vec::new(),
    };
    pairs
        .into_iter()
        .map(|(a, b)| spring(piece, a, b))
        .collect()
}

/// Hooke's constant of each spring of `springs(piece, kind)`, in that order. The material's
/// per-spring constant, except for the structural springs of a grid whose material gives a
/// tensile stiffness per unit width `E` (N/m): a warp spring then stands for the width of
/// cloth beside it, `dv / 2` for each whole cell it borders (`dv` inside, `dv / 2` on a free
/// edge), and gets `k = E width / du`, so that a strip of any width, edges and all, stretches as
/// the tensile stiffness says (weft springs likewise with `du` and `dv` swapped).
pub fn spring_stiffness(piece: &Piece, kind: SpringKind) -> Vec<f64> {
    let m = &piece.material;
    let per_spring = |k: f64| vec![k; springs(piece, kind).len()];
    match (kind, &piece.panel.lattice, m.tensile) {
        (SpringKind::Structural, Some(l), Some(t)) => {
            let whole = |ci: isize, cj: isize| whole_cell(l, ci, cj) as u8 as f64;
            let mut k = Vec::new();
            for j in 0..l.nv as isize {
                for i in 0..l.nu as isize {
                    if l.at(i, j).is_none() {
                        continue;
                    }
                    if l.at(i + 1, j).is_some() {
                        let width = 0.5 * l.dv * (whole(i, j - 1) + whole(i, j));
                        k.push(t.warp * width / l.du);
                    }
                    if l.at(i, j + 1).is_some() {
                        let width = 0.5 * l.du * (whole(i - 1, j) + whole(i, j));
                        k.push(t.weft * width / l.dv);
                    }
                }
            }
            k
        }
        (SpringKind::Structural, _, _) => per_spring(m.stretch),
        (SpringKind::Shear, _, _) => per_spring(m.shear),
        (SpringKind::SkipOne, _, _) => per_spring(m.skip_one),
    }
}

/// Second-difference stencils along the warp (`along_u = true`) or the weft.
///
/// A stencil's weight carries the square root of its vertex's tributary area
/// ([`lattice_tributary_area`]), so a line of vertices on a free edge or a cut outline bends with
/// the width of cloth it stands for, not a whole spacing's.
pub fn bending_stencils(piece: &Piece, along_u: bool) -> Vec<Stencil<3>> {
    match &piece.panel.lattice {
        Some(l) => {
            let h = if along_u { l.du } else { l.dv };
            let (di, dj) = if along_u { (1, 0) } else { (0, 1) };
            let mut out = Vec::new();
            for j in 0..l.nv as isize {
                for i in 0..l.nu as isize {
                    let (Some(a), Some(b), Some(c)) =
                        (l.at(i - di, j - dj), l.at(i, j), l.at(i + di, j + dj))
                    else {
                        continue;
                    };
                    let s = lattice_tributary_area(l, i, j).sqrt() / (h * h);
                    out.push(Stencil {
                        idx: [a, b, c].map(|k| piece.global(k)),
                        w: [s, -2.0 * s, s],
                    });
                }
            }
            out
        }
        None => free_mesh_bending(piece, along_u),
    }
}

/// Bending at a clamp's edge, where a stencil `[a, b, c]` is centred on a held vertex `b` with
/// one neighbour held and the other free (a strip's first two columns pinned, a gripper's pads).
/// The two held vertices fix the slope at `b`, so the curvature there is that of a second
/// difference through the held neighbour's mirror image across `b`: twice the stencil's
/// one-sided difference. It bends over half a spacing (the other half is inside the clamp), so
/// the stencil's energy doubles and its weights grow by `sqrt 2`. Without this a clamped strip
/// droops as if its overhang were half a spacing longer.
pub fn clamp_edges(stencils: &mut [Stencil<3>], held: impl Fn(u32) -> bool) {
    for s in stencils {
        let [a, b, c] = s.idx;
        if held(b) && held(a) != held(c) {
            s.w = s.w.map(|w| w * std::f64::consts::SQRT_2);
        }
    }
}

/// The rest area a lattice vertex stands for: a quarter `du dv` of each of the (up to four) cells
/// around it that the lattice has whole (all four corners present). `du dv` inside the cloth,
/// half of it on a free edge or a straight cut, a quarter at a corner. This is the vertex's
/// Voronoi cell clipped to the cloth (for a lattice's right triangles it is the circumcentric
/// split, whichever way a cell's diagonal runs).
pub fn lattice_tributary_area(l: &Lattice, i: isize, j: isize) -> f64 {
    let cells = [(i - 1, j - 1), (i, j - 1), (i - 1, j), (i, j)]
        .into_iter()
        .filter(|&(ci, cj)| whole_cell(l, ci, cj))
        .count();
    0.25 * cells as f64 * l.du * l.dv
}

/// Whether the lattice cell with lower corner `(i, j)` is cloth: all four corners present.
fn whole_cell(l: &Lattice, i: isize, j: isize) -> bool {
    l.at(i, j).is_some()
        && l.at(i + 1, j).is_some()
        && l.at(i, j + 1).is_some()
        && l.at(i + 1, j + 1).is_some()
}

/// Mixed-difference (twist) stencils; only lattice pieces have them. One per whole cell, weighted
/// by the cell's area, so cells along a free edge already carry exactly the cloth they cover.
pub fn twist_stencils(piece: &Piece) -> Vec<Stencil<4>> {
    let Some(l) = &piece.panel.lattice else {
        return Vec::new();
    };
    let s = 1.0 / (l.du * l.dv).sqrt();
    let mut out = Vec::new();
    for j in 0..l.nv as isize - 1 {
        for i in 0..l.nu as isize - 1 {
            let (Some(a), Some(b), Some(c), Some(d)) = (
                l.at(i, j),
                l.at(i + 1, j),
                l.at(i, j + 1),
                l.at(i + 1, j + 1),
            ) else {
                continue;
            };
            out.push(Stencil {
                idx: [a, b, c, d].map(|k| piece.global(k)),
                w: [s, -s, -s, s],
            });
        }
    }
    out
}

/// For an unstructured mesh: at each vertex, take the 1-ring neighbours best aligned with +dir and
/// -dir in rest (u, v) (within 30 degrees) and build the non-uniform second difference
/// `2 [ (x_r - x_i)/h_r - (x_i - x_l)/h_l ] / (h_l + h_r)`.
fn free_mesh_bending(piece: &Piece, along_u: bool) -> Vec<Stencil<3>> {
    let uv = &piece.panel.uv;
    let n = uv.len();
    let mut ring: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (a, b) in unique_edges(&piece.panel.triangles) {
        ring[a as usize].push(b);
        ring[b as usize].push(a);
    }
    let dir = if along_u { DVec2::X } else { DVec2::Y };
    let cos_min = (30f64).to_radians().cos();
    let mut areas = vec![0.0; n];
    for (t, a) in piece.panel.triangles.iter().zip(piece.panel.rest_areas()) {
        for &i in t {
            areas[i as usize] += a / 3.0;
        }
    }
    let mut out = Vec::new();
    for i in 0..n {
        let best = |sign: f64| {
            ring[i]
                .iter()
                .filter_map(|&k| {
                    let d = uv[k as usize] - uv[i];
                    let len = d.length();
                    let c = sign * d.dot(dir) / len.max(1e-300);
                    (len > 0.0 && c >= cos_min).then_some((k, c, len))
                })
                .max_by(|a, b| a.1.total_cmp(&b.1))
        };
        let (Some((l, _, hl)), Some((r, _, hr))) = (best(-1.0), best(1.0)) else {
            continue;
        };
        let s = areas[i].sqrt() * 2.0 / (hl + hr);
        out.push(Stencil {
            idx: [l, i as u32, r].map(|k| piece.global(k)),
            w: [s / hl, -s * (1.0 / hl + 1.0 / hr), s / hr],
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::{Cloth, Material, Panel};
    use crate::{Pose, Vec3};

    /// A `nu x nv` sheet (spacings `du`, `dv`) rolled onto a cylinder of radius `r` about the v
    /// axis, so every warp line has curvature `1 / r`, with the sites `holes` cut out.
    fn rolled(nu: usize, nv: usize, r: f64, holes: &[(usize, usize)]) -> Piece {
        let mut panel = Panel::grid("sheet", [0.1, 0.06], [nu, nv], &Pose::IDENTITY);
        for p in panel.positions.iter_mut().zip(&panel.uv) {
            let (u, v) = (p.1.x, p.1.y);
            *p.0 = Vec3::new(r * (u / r).sin(), v, r * (1.0 - (u / r).cos()));
        }
        if let Some(l) = panel.lattice.as_mut() {
            for &(i, j) in holes {
                l.index[j * l.nu + i] = None;
            }
        }
        let mut cloth = Cloth::new();
        cloth.add_panel(panel, Material::default());
        cloth.pieces.remove(0)
    }

    /// Bending energy per unit rigidity of the warp stencils, summed per weft line `j`.
    fn energy_per_line(piece: &Piece) -> Vec<f64> {
        let l = piece.panel.lattice.as_ref().expect("a lattice");
        let mut e = vec![0.0; l.nv];
        for s in bending_stencils(piece, true) {
            let d: Vec3 = (0..3)
                .map(|k| piece.panel.positions[s.idx[k] as usize] * s.w[k])
                .sum();
            e[s.idx[1] as usize / l.nu] += 0.5 * d.length_squared();
        }
        e
    }

    #[test]
    fn free_edges_bend_with_their_half_spacing() {
        let r = 0.2;
        let piece = rolled(21, 7, r, &[]);
        let l = piece.panel.lattice.as_ref().expect("a lattice");
        // Each line's stencils cover its bent length (nu - 2) du; a line stands for dv of the
        // sheet inside and dv / 2 on an edge.
        let length = (l.nu - 2) as f64 * l.du;
        let per_area = 0.5 / (r * r);
        for (j, e) in energy_per_line(&piece).into_iter().enumerate() {
            let width = if j == 0 || j == l.nv - 1 { 0.5 } else { 1.0 } * l.dv;
            let density = e / (length * width);
            assert!(
                (density / per_area - 1.0).abs() < 1e-3,
                "line {j}: {density} per unit area against {per_area}"
            );
        }
    }

    #[test]
    fn a_cut_outline_bends_with_the_cloth_left_around_it() {
        // A notch cut from the middle of the top edge: the line below it becomes a free edge
        // where the notch is.
        let piece = rolled(9, 5, 0.2, &[(3, 4), (4, 4), (5, 4)]);
        let l = piece.panel.lattice.as_ref().expect("a lattice");
        let area = |i, j| {
            let a = lattice_tributary_area(l, i, j) / (l.du * l.dv);
            (a * 1e12).round() / 1e12
        };
        assert_eq!(area(4, 3), 0.5, "under the notch: a free edge");
        assert_eq!(area(3, 3), 0.5, "under the notch's end");
        assert_eq!(area(2, 3), 0.75, "the notch's inner corner");
        assert_eq!(area(2, 4), 0.25, "a convex corner the cut made");
        assert_eq!(area(4, 2), 1.0, "inside");
        assert_eq!(area(0, 0), 0.25, "the sheet's corner");
        // The stencils carry it: the one under the notch has half the energy of one inside.
        let w = |i: u32, j: u32| {
            bending_stencils(&piece, true)
                .into_iter()
                .find(|s| s.idx[1] == piece.global(l.at(i as isize, j as isize).unwrap_or(0)))
                .map(|s| s.w[0])
                .unwrap_or(0.0)
        };
        assert!((w(4, 3).powi(2) / w(4, 2).powi(2) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn a_tensile_stiffness_is_shared_out_by_width() {
        let mut piece = rolled(5, 3, 0.2, &[]);
        piece.material.tensile = Some(crate::cloth::Tensile {
            warp: 800.0,
            weft: 400.0,
            strain: 0.02,
        });
        let s = springs(&piece, SpringKind::Structural);
        let k = spring_stiffness(&piece, SpringKind::Structural);
        assert_eq!(s.len(), k.len());
        // Pulled along the warp by a strain e, the springs leaving the edge u = 0 carry
        // 800 e per unit of the sheet's width (0.06 m), edge springs and all; the weft's
        // leaving v = 0 carry 400 e per unit of its width (0.1 m).
        let uv = &piece.panel.uv;
        for (axis, stiffness, width) in [(DVec2::X, 800.0, 0.06), (DVec2::Y, 400.0, 0.1)] {
            let per_strain: f64 = s
                .iter()
                .zip(&k)
                .filter(|(sp, _)| {
                    let (a, b) = (uv[sp.i as usize], uv[sp.j as usize]);
                    a.dot(axis) == 0.0 && (b - a).dot(axis) > 0.0
                })
                .map(|(sp, k)| k * sp.rest)
                .sum();
            assert!(
                (per_strain / width / stiffness - 1.0).abs() < 1e-12,
                "{axis}: {per_strain}"
            );
        }
    }

    #[test]
    fn a_clamps_edge_bends_with_its_mirror_image() {
        let piece = rolled(6, 2, 0.2, &[]);
        let mut st = bending_stencils(&piece, true);
        let before = st.clone();
        // Columns 0 and 1 held: the stencils centred on column 1 are the clamp's edge.
        clamp_edges(&mut st, |v| v % 6 < 2);
        for (a, b) in st.iter().zip(&before) {
            let f = if a.idx[1] % 6 == 1 {
                std::f64::consts::SQRT_2
            } else {
                1.0
            };
            assert_eq!(a.w, b.w.map(|w| w * f));
        }
    }
}
