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

/// Second-difference stencils along the warp (`along_u = true`) or the weft.
pub fn bending_stencils(piece: &Piece, along_u: bool) -> Vec<Stencil<3>> {
    match &piece.panel.lattice {
        Some(l) => {
            let (h, area) = if along_u {
                (l.du, l.du * l.dv)
            } else {
                (l.dv, l.du * l.dv)
            };
            let s = area.sqrt() / (h * h);
            let (di, dj) = if along_u { (1, 0) } else { (0, 1) };
            let mut out = Vec::new();
            for j in 0..l.nv as isize {
                for i in 0..l.nu as isize {
                    let (Some(a), Some(b), Some(c)) =
                        (l.at(i - di, j - dj), l.at(i, j), l.at(i + di, j + dj))
                    else {
                        continue;
                    };
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

/// Mixed-difference (twist) stencils; only lattice pieces have them.
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
