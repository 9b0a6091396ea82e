//! Welding: each seam pair becomes one vertex, and the springs and bending stencils are rebuilt
//! so that they act across the seams.
//!
//! A welded vertex has a rest position in each panel it came from, so rest lengths are taken per
//! triangle from the panel that owns it (a seam edge, owned by one triangle on each side, gets the
//! mean of its two nearly equal rest lengths). Bending inside a panel keeps the panel's stencils;
//! across a seam, each welded vertex gets a second difference from the neighbour on side a most
//! nearly perpendicular to the seam, through the vertex, to the like neighbour on side b.

use super::seam::SeamPairs;
use crate::cloth::topology::{
    bending_stencils, springs, unique_edges, Spring, SpringKind, Stencil,
};
use crate::cloth::{Cloth, Material, Panel, Piece};
use crate::effects::plan::{Elements, Pairs, SpringGroup, StencilGroup};
use crate::effects::Knee;
use crate::Vec3;
use glam::DVec2;
use std::collections::HashMap;

/// Elastic topology of a cloth: stretch springs and bending stencils, each with the material of
/// the garment it belongs to.
#[derive(Debug, Clone, Default)]
pub struct Topology {
    pub springs: Vec<Spring>,
    /// Per spring: the material it was cut from (stiffness and damping).
    pub spring_material: Vec<Material>,
    pub bending: Vec<Stencil<3>>,
    pub bending_rigidity: Vec<f64>,
}

impl Topology {
    /// The topology of separate pieces (before welding): each piece's own edges and stencils.
    pub fn of_pieces(pieces: &[Piece]) -> Topology {
        let mut t = Topology::default();
        for p in pieces {
            let s = springs(p, SpringKind::Structural);
            t.spring_material
                .extend(std::iter::repeat_n(p.material, s.len()));
            t.springs.extend(s);
            for (along_u, b) in [(true, p.material.bend_warp), (false, p.material.bend_weft)] {
                let s = bending_stencils(p, along_u);
                t.bending_rigidity.extend(std::iter::repeat_n(b, s.len()));
                t.bending.extend(s);
            }
        }
        t
    }
}

/// A welded garment.
#[derive(Debug, Clone)]
pub struct Welded {
    pub cloth: Cloth,
    pub topology: Topology,
    /// Pre-weld global vertex -> welded vertex.
    pub map: Vec<u32>,
    /// Per seam, the welded vertices along it (from `a.from` to `a.to`).
    pub seams: Vec<(String, Vec<u32>)>,
}

fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        parent[i as usize] = parent[parent[i as usize] as usize];
        i = parent[i as usize];
    }
    i
}

/// Welds the seam pairs of `cloth` (whose pieces are the panels of one garment) into one piece
/// named `name`. Merged vertices sit at the mean position and velocity of their sources and carry
/// the sum of their masses.
pub fn weld(cloth: &Cloth, seams: &[SeamPairs], name: &str, material: Material) -> Welded {
    let n = cloth.len();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    for s in seams {
        for &(a, b) in &s.pairs {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra != rb {
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
        }
    }
    let mut map = vec![0u32; n];
    let mut count = 0u32;
    let mut root_new: HashMap<u32, u32> = HashMap::new();
    for i in 0..n as u32 {
        let r = find(&mut parent, i);
        map[i as usize] = *root_new.entry(r).or_insert_with(|| {
            count += 1;
            count - 1
        });
    }
    let m = count as usize;
    let mut sum_x = vec![Vec3::ZERO; m];
    let mut sum_v = vec![Vec3::ZERO; m];
    let mut members = vec![0.0f64; m];
    let mut mass = vec![0.0; m];
    let mut uv = vec![DVec2::ZERO; m];
    let mut uv_set = vec![false; m];
    for i in 0..n {
        let w = map[i] as usize;
        sum_x[w] += cloth.x[i];
        sum_v[w] += cloth.v[i];
        members[w] += 1.0;
        mass[w] += cloth.mass[i];
        if !uv_set[w] {
            uv[w] = cloth.uv[i];
            uv_set[w] = true;
        }
    }
    let x: Vec<Vec3> = sum_x.iter().zip(&members).map(|(s, c)| *s / *c).collect();
    let v: Vec<Vec3> = sum_v.iter().zip(&members).map(|(s, c)| *s / *c).collect();
    let triangles: Vec<[u32; 3]> = cloth
        .triangles
        .iter()
        .map(|t| t.map(|i| map[i as usize]))
        .collect();

    // Stretch: rest lengths from the owning panel; shared (seam) edges averaged.
    let mut rest: HashMap<(u32, u32), (f64, f64)> = HashMap::new();
    for p in &cloth.pieces {
        for (a, b) in unique_edges(&p.panel.triangles) {
            let l = (p.panel.uv[a as usize] - p.panel.uv[b as usize]).length();
            let (ga, gb) = (map[p.global(a) as usize], map[p.global(b) as usize]);
            let e = rest.entry((ga.min(gb), ga.max(gb))).or_insert((0.0, 0.0));
            e.0 += l;
            e.1 += 1.0;
        }
    }
    let mut spring_list: Vec<Spring> = rest
        .into_iter()
        .map(|((i, j), (sum, c))| Spring {
            i,
            j,
            rest: sum / c,
        })
        .collect();
    spring_list.sort_by_key(|s| (s.i, s.j));

    // Bending inside panels, remapped.
    let mut topology = Topology {
        spring_material: vec![material; spring_list.len()],
        springs: spring_list,
        ..Topology::default()
    };
    for p in &cloth.pieces {
        for (along_u, b) in [(true, p.material.bend_warp), (false, p.material.bend_weft)] {
            for s in bending_stencils(p, along_u) {
                topology.bending.push(Stencil {
                    idx: s.idx.map(|i| map[i as usize]),
                    w: s.w,
                });
                topology.bending_rigidity.push(b);
            }
        }
    }
    let cross = 0.5 * (material.bend_warp + material.bend_weft);
    let mut seam_vertices = Vec::new();
    for s in seams {
        for st in cross_seam_bending(cloth, s) {
            topology.bending.push(Stencil {
                idx: st.idx.map(|i| map[i as usize]),
                w: st.w,
            });
            topology.bending_rigidity.push(cross);
        }
        seam_vertices.push((
            s.name.clone(),
            s.pairs.iter().map(|&(a, _)| map[a as usize]).collect(),
        ));
    }

    let panel = Panel {
        name: name.to_string(),
        uv: uv.clone(),
        positions: x.clone(),
        triangles: triangles.clone(),
        lattice: None,
    };
    let welded = Cloth {
        x,
        v,
        mass,
        uv,
        triangles: triangles.clone(),
        thickness: vec![material.thickness; m],
        friction: vec![material.friction; m],
        kinematic: Vec::new(),
        pieces: vec![Piece {
            name: name.to_string(),
            first_vertex: 0,
            vertex_count: m,
            first_triangle: 0,
            triangle_count: triangles.len(),
            material,
            panel,
        }],
    };
    Welded {
        cloth: welded,
        topology,
        map,
        seams: seam_vertices,
    }
}

/// Second-difference stencils across one seam, in pre-weld indices: `[l, a, r]` with `l` a
/// neighbour of `a` in a's panel and `r` a neighbour of `b` in b's panel, each the one most nearly
/// perpendicular to the seam (within 30 degrees) in its panel's rest coordinates. After welding,
/// `a` and `b` are one vertex, so the stencil measures the kink across the seam.
fn cross_seam_bending(cloth: &Cloth, s: &SeamPairs) -> Vec<Stencil<3>> {
    let n = cloth.len();
    let mut ring: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut area = vec![0.0; n];
    for t in &cloth.triangles {
        let [a, b, c] = t.map(|i| cloth.uv[i as usize]);
        let ar = 0.5 * (b - a).perp_dot(c - a).abs();
        for k in 0..3 {
            let (i, j) = (t[k] as usize, t[(k + 1) % 3]);
            ring[i].push(j);
            ring[j as usize].push(t[k]);
            area[i] += ar / 3.0;
        }
    }
    let on_seam: std::collections::HashSet<u32> =
        s.pairs.iter().flat_map(|&(a, b)| [a, b]).collect();
    let cos_min = 30f64.to_radians().cos();
    // Neighbour of `v` most perpendicular to the seam tangent `t` (rest coordinates).
    let across = |v: u32, t: DVec2| -> Option<(u32, f64)> {
        let t = t.normalize_or_zero();
        ring[v as usize]
            .iter()
            .filter(|k| !on_seam.contains(k))
            .filter_map(|&k| {
                let d = cloth.uv[k as usize] - cloth.uv[v as usize];
                let len = d.length();
                let perp = (1.0 - (d.dot(t) / len).powi(2)).max(0.0).sqrt();
                (len > 0.0 && perp >= cos_min).then_some((k, perp, len))
            })
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(k, _, len)| (k, len))
    };
    let np = s.pairs.len();
    let mut out = Vec::new();
    for p in 0..np {
        let (a, b) = s.pairs[p];
        let (pa, pb) = (s.pairs[p.saturating_sub(1)], s.pairs[(p + 1).min(np - 1)]);
        let ta = cloth.uv[pb.0 as usize] - cloth.uv[pa.0 as usize];
        let tb = cloth.uv[pb.1 as usize] - cloth.uv[pa.1 as usize];
        let (Some((l, hl)), Some((r, hr))) = (across(a, ta), across(b, tb)) else {
            continue;
        };
        let w = (area[a as usize] + area[b as usize]).sqrt() * 2.0 / (hl + hr);
        out.push(Stencil {
            idx: [l, a, r],
            w: [w / hl, -w * (1.0 / hl + 1.0 / hr), w / hr],
        });
    }
    out
}

/// A welded garment's elements for the effect plan: its own edges as stretch springs and its
/// bending stencils, each with its own material, keyed `garments.material.*`. Free meshes resist
/// shear with their own edges; skip-one springs and twist need a lattice, so there are none.
impl Elements for Topology {
    fn springs(&self, kind: SpringKind) -> Vec<SpringGroup> {
        if kind != SpringKind::Structural {
            return Vec::new();
        }
        let kept = || {
            (self.springs.iter())
                .zip(&self.spring_material)
                .filter(|(_, m)| m.stretch > 0.0)
        };
        let (springs, k): (Vec<Spring>, Vec<f64>) = kept().map(|(s, m)| (*s, m.stretch)).unzip();
        let knee: Vec<Option<Knee>> = kept()
            .map(|(_, m)| m.knee().map(|(strain, ratio)| Knee { strain, ratio }))
            .collect();
        vec![SpringGroup {
            springs,
            k,
            parameter: "garments.material.stretch".into(),
            knee: if knee.iter().any(Option::is_some) {
                knee
            } else {
                Vec::new()
            },
        }]
    }

    fn bending(&self) -> Vec<StencilGroup<3>> {
        vec![StencilGroup {
            stencils: self.bending.clone(),
            rigidity: self.bending_rigidity.clone(),
            parameter: "garments.material.bend_warp".into(),
        }]
    }

    fn twist(&self) -> Vec<StencilGroup<4>> {
        Vec::new()
    }

    fn spring_damping(&self) -> Pairs {
        self.per_edge(|m| m.damping.spring)
    }

    fn diffusion(&self) -> Pairs {
        self.per_edge(|m| m.damping.diffusion)
    }
}

impl Topology {
    /// Every edge whose material gives `f` > 0, with that value.
    fn per_edge(&self, f: fn(&Material) -> f64) -> Pairs {
        let (pairs, k) = self
            .springs
            .iter()
            .zip(&self.spring_material)
            .filter(|(_, m)| f(m) > 0.0)
            .map(|(s, m)| ((s.i, s.j), f(m)))
            .unzip();
        Pairs { pairs, k }
    }
}
