//! Obstacle features (rod axes, box and mesh edges and corners) against cloth faces and edges.
//!
//! The vertex stage only asks whether a cloth vertex meets an obstacle. A thin obstacle (a 5 mm
//! rod, a box edge) can pass through a cloth face between vertices without any vertex touching
//! it. Here the obstacle is reduced to features in its local frame: corner points and segments,
//! inflated by a common radius (the rod radius, 0 for box and mesh edges). Each feature moves
//! with the obstacle from `pose_prev` to `pose` (linearly per feature point); each cloth
//! triangle and edge moves linearly from `x0` to `x1`. Corner points are tested against cloth
//! triangles and segments against cloth edges with the conservative-advancement CCD of
//! [`super::narrow`] at `eta = radius + thickness`: at the first time a segment comes within
//! `eta` of a triangle, the closest pair is a segment end vs the triangle or the segment vs a
//! triangle edge, so these two families catch every first contact.
//!
//! Response (Bridson et al. 2002 style, the obstacle has infinite mass): the cloth contact
//! point `c = sum w_k x_k` (barycentric weights) is pushed along the contact normal until it is
//! `eta` in front of the feature at the end pose; the displacement is split as
//! `dx_k = w_k m_k^-1 I` with `I = push / sum w_k^2 m_k^-1`, which moves `c` exactly by `push`
//! and never moves kinematic vertices. Each moving vertex of the contact loses its velocity
//! towards the feature (inelastic, so `c` no longer approaches) and its tangential velocity
//! loses `mu` times that normal change (Coulomb); see `respond` for why per vertex.

use super::broad::{Aabb, SpatialHash};
use super::narrow::{edge_edge_ccd_thick, vertex_triangle_ccd_thick};
use super::obstacle::{Geom, Obstacle};
use super::stage::DetectionMode;
use crate::Vec3;
use rayon::prelude::*;

/// Meshes with more unique edges than this get no edge features (the cost would be
/// features x candidate cloth edges per step); their vertices still collide with the cloth.
pub(crate) const MAX_MESH_EDGES: usize = 4096;

/// Detect-and-respond passes per step: a push can bring a neighbouring face into contact.
const PASSES: usize = 4;

/// The end gap is set to `eta (1 + PUSH_SLACK)` so the next pass (tolerance `1e-6 eta`) does
/// not see the same contact again.
const PUSH_SLACK: f64 = 1e-3;

/// Feature set of one obstacle, in its local frame.
#[derive(Debug, Clone, Default)]
pub(crate) struct Features {
    points: Vec<Vec3>,
    segments: Vec<[Vec3; 2]>,
    radius: f64,
    /// Box features only (else empty): per point, then per segment, the signs of the faces the
    /// feature lies on (`+-1` per such axis, 0 otherwise). Its outward normal cone is the set
    /// of `n` with `n_k cone_k >= 0` on those axes: see [`in_cone`].
    cones: Vec<Vec3>,
}

/// Whether local normal `n` lies in the outward normal cone `cone` of a box feature (corner or
/// edge), i.e. whether the feature is the box's closest point to a point off it along `n`.
/// A cloth face or edge that wraps around a box edge, its chord passing inside the edge,
/// gives the CCD a normal pointing into the box; answering it pushes the cloth into the faces'
/// vertex contacts, which push back next step: the jitter of cloth resting on box edges. Such
/// a pair is not this feature's contact (the faces own it), so it is skipped. The tolerance
/// admits normals along a face normal up to rounding.
fn in_cone(cone: Vec3, n: Vec3) -> bool {
    const TOL: f64 = 1e-9;
    (0..3).all(|k| cone[k] == 0.0 || n[k] * cone[k] >= -TOL)
}

impl Features {
    /// Spheres and planes have none (a sphere's curvature radius exceeds the cloth spacing
    /// for any sphere the vertex test cannot already hold).
    pub fn of(o: &Obstacle) -> Features {
        let axis = |hh: f64, radius: f64| {
            let (a, b) = (Vec3::new(0.0, -hh, 0.0), Vec3::new(0.0, hh, 0.0));
            Features {
                points: vec![a, b],
                segments: vec![[a, b]],
                radius,
                cones: Vec::new(),
            }
        };
        match o.geom {
            Geom::Ball { .. } | Geom::HalfSpace { .. } => Features::default(),
            Geom::Capsule {
                radius,
                half_height,
            } => axis(half_height, radius),
            Geom::Cuboid { half } => {
                let corner = |k: usize| {
                    Vec3::new(
                        if k & 1 == 0 { -half.x } else { half.x },
                        if k & 2 == 0 { -half.y } else { half.y },
                        if k & 4 == 0 { -half.z } else { half.z },
                    )
                };
                let points: Vec<Vec3> = (0..8).map(corner).collect();
                let mut segments = Vec::with_capacity(12);
                for k in 0..8 {
                    for bit in [1, 2, 4] {
                        if k & bit == 0 {
                            segments.push([points[k], points[k | bit]]);
                        }
                    }
                }
                let sign = |p: Vec3| Vec3::new(p.x.signum(), p.y.signum(), p.z.signum());
                let cones = points
                    .iter()
                    .map(|&p| sign(p))
                    .chain(segments.iter().map(|[a, b]| {
                        // The segment's own axis is where its ends differ: no face there.
                        let (sa, sb) = (sign(*a), sign(*b));
                        Vec3::select(sa.cmpeq(sb), sa, Vec3::ZERO)
                    }))
                    .collect();
                Features {
                    points,
                    segments,
                    radius: 0.0,
                    cones,
                }
            }
            Geom::Solid => match o.shape.as_cylinder() {
                Some(c) => cylinder(f64::from(c.half_height), f64::from(c.radius)),
                None => Features::default(),
            },
            Geom::Surface => match o.shape.as_trimesh() {
                Some(m) => {
                    let vertices: Vec<Vec3> = m.vertices().iter().map(|v| v.as_dvec3()).collect();
                    let (points, mut segments) = sharp_features(&vertices, m.indices());
                    if segments.len() > MAX_MESH_EDGES {
                        log::warn!(
                            "obstacle '{}': {} sharp mesh edges exceed {MAX_MESH_EDGES}; only its \
                             vertices are tested against cloth faces",
                            o.name,
                            segments.len()
                        );
                        segments.clear();
                    }
                    Features {
                        points,
                        segments,
                        radius: 0.0,
                        cones: Vec::new(),
                    }
                }
                None => Features::default(),
            },
        }
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty() && self.segments.is_empty()
    }

    /// Inflation radius of the features (the rod radius; 0 for edges).
    pub fn radius(&self) -> f64 {
        self.radius
    }
}

/// Angle (rad) below which a mesh edge's fold, or a mesh vertex's angle defect, counts as
/// smooth. A fold of exterior angle `a` under a cloth face of size `L` rises at most
/// `(L / 2) tan(a / 2)` above the chord the vertex test already holds off: below half the
/// thickness for 20 degrees as long as the cloth spacing stays under ~5.7 thicknesses (the
/// bundled robot scenes, whose head is a mesh: 1.3 to 3.3). Smooth parts are left to the vertex
/// test, as spheres are; a coarser cloth over a finely curved mesh can let a fold graze a face.
pub(crate) const SHARP_ANGLE: f64 = 20.0 * std::f64::consts::PI / 180.0;

/// The sharp features of a triangle mesh: edges whose adjacent faces fold by more than
/// [`SHARP_ANGLE`] (and boundary or non-manifold edges), and the vertices that end such an edge
/// or whose angle defect (2 pi minus the face angles around it; a cone tip) exceeds it.
/// A finely tessellated smooth part (a ball, a rounded link) has none; a cube keeps its 12 edges
/// and 8 corners but not its face diagonals.
fn sharp_features(v: &[Vec3], tris: &[[u32; 3]]) -> (Vec<Vec3>, Vec<[Vec3; 2]>) {
    // (min, max, face, same direction as min->max) per directed edge of every face.
    let mut half: Vec<(u32, u32, u32, bool)> = Vec::with_capacity(3 * tris.len());
    let mut defect = vec![2.0 * std::f64::consts::PI; v.len()];
    let normal = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|i| v[i as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    };
    for (f, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            half.push((a.min(b), a.max(b), f as u32, a < b));
            let (e1, e2) = (v[b as usize] - v[a as usize], v[c as usize] - v[a as usize]);
            defect[a as usize] -= e1.angle_between(e2);
        }
    }
    half.sort_unstable();
    let mut sharp_vertex: Vec<bool> = defect
        .iter()
        .map(|d| d.abs() > SHARP_ANGLE || !d.is_finite())
        .collect();
    let mut edges: Vec<[u32; 2]> = Vec::new();
    for group in half.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
        let sharp = match group {
            [p, q] => {
                let (n1, n2) = (normal(&tris[p.2 as usize]), normal(&tris[q.2 as usize]));
                // Consistent winding walks a shared edge in opposite directions.
                let n2 = if p.3 == q.3 { -n2 } else { n2 };
                n1 == Vec3::ZERO || n2 == Vec3::ZERO || n1.angle_between(n2) > SHARP_ANGLE
            }
            _ => true,
        };
        if sharp {
            let (a, b) = (group[0].0, group[0].1);
            edges.push([a, b]);
            sharp_vertex[a as usize] = true;
            sharp_vertex[b as usize] = true;
        }
    }
    let points = v
        .iter()
        .zip(&sharp_vertex)
        .filter(|(_, s)| **s)
        .map(|(p, _)| *p)
        .collect();
    let segments = edges
        .iter()
        .map(|e| [v[e[0] as usize], v[e[1] as usize]])
        .collect();
    (points, segments)
}

/// Cylinder (axis y) features, inside the shape so cloth resting on it at its thickness is
/// never pushed: the axis shortened by the radius at each end, inflated by the radius. Only for
/// cylinders longer than wide (rods); a wide, flat cylinder (a table top) is left to the vertex
/// test, whose curvature-radius argument holds for its faces (its sharp rims are a known gap).
fn cylinder(hh: f64, r: f64) -> Features {
    if hh <= r {
        return Features::default();
    }
    let (a, b) = (Vec3::new(0.0, r - hh, 0.0), Vec3::new(0.0, hh - r, 0.0));
    Features {
        points: vec![a, b],
        segments: vec![[a, b]],
        radius: r,
        cones: Vec::new(),
    }
}

/// One feature-vs-cloth contact found by the CCD.
#[derive(Debug, Clone, Copy)]
struct Hit {
    t: f64,
    verts: [u32; 3],
    w: [f64; 3],
    /// World unit normal from the feature towards the side the cloth came from.
    normal: Vec3,
    /// Feature contact point in the obstacle's local frame.
    local: Vec3,
}

/// Per-step inputs shared by detection and response.
pub(crate) struct ClothState<'a> {
    pub x0: &'a [Vec3],
    pub inv_mass: &'a [f64],
    pub thickness: &'a [f64],
    pub friction: &'a [f64],
    pub h: f64,
    pub mode: DetectionMode,
    /// Per vertex, the normals whose friction the solver applied (empty: none).
    pub friction_solved: &'a [[Vec3; 3]],
    /// The cloth faces and edges the solver held with an edge spring this step (sorted).
    pub sprung: &'a [[u32; 3]],
}

/// A contact of a static obstacle's edge or corner with the cloth, for the implicit solver to
/// hold as a one-sided spring next substep (see [`crate::integrate::ContactSpring`]): the cloth
/// point `sum weights_k x_k` stays `gap` in front of `point` along `normal`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeatureContact {
    pub verts: [u32; 3],
    pub weights: [f64; 3],
    /// World unit normal from the feature towards the cloth.
    pub normal: Vec3,
    /// The feature's contact point (world).
    pub point: Vec3,
    /// Contact distance `radius + thickness` (m).
    pub gap: f64,
    pub mu: f64,
}

/// A contact the solver held as a spring is answered here only once the cloth point is deeper
/// than this fraction of the contact distance into it (a safety net: the spring's deflection
/// under load is micrometres). Above it, a push by position would stretch the cloth over the
/// edge: the solver moves the segment's vertices with their neighbours and the push moves only
/// them back, and that spurious tension's normal force gripped a strip the hanging weight pulls
/// off a table 50 times more than its weight (tests/table_edge.rs).
pub const DEEP: f64 = 0.5;

/// Cloth topology and scratch buffers for feature contacts (kept across steps).
#[derive(Debug, Default)]
pub(crate) struct FeatureCollider {
    /// Swept feature boxes (points, segments) hashed per detection pass, so each cloth face or
    /// edge meets only the features near it (meshes have thousands).
    point_hash: SpatialHash,
    segment_hash: SpatialHash,
    point_boxes: Vec<Aabb>,
    segment_boxes: Vec<Aabb>,
    triangles: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    tri_edges: Vec<[u32; 3]>,
    cand_tris: Vec<u32>,
    cand_edges: Vec<u32>,
    hits: Vec<Hit>,
    /// Vertices moved by the previous pass: only their faces and edges can have new contacts.
    dirty: Vec<bool>,
    /// Vertices moved by the current pass.
    moved: Vec<bool>,
    /// Contacts of the last `resolve` with static obstacles.
    contacts: Vec<FeatureContact>,
}

impl FeatureCollider {
    pub fn new(triangles: &[[u32; 3]]) -> Self {
        let key = |a: u32, b: u32| [a.min(b), a.max(b)];
        let mut edges: Vec<[u32; 2]> = triangles
            .iter()
            .flat_map(|t| [key(t[0], t[1]), key(t[1], t[2]), key(t[2], t[0])])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let id = |e: [u32; 2]| edges.binary_search(&e).unwrap_or(0) as u32;
        let tri_edges = triangles
            .iter()
            .map(|t| {
                [
                    id(key(t[0], t[1])),
                    id(key(t[1], t[2])),
                    id(key(t[2], t[0])),
                ]
            })
            .collect();
        Self {
            triangles: triangles.to_vec(),
            edges,
            tri_edges,
            ..Self::default()
        }
    }

    /// Detects and answers feature contacts of obstacle `o` over the step, updating `x1`, `v1`.
    /// Marks every moved vertex in `touched`. Returns the number of contacts answered.
    pub fn resolve(
        &mut self,
        o: &Obstacle,
        f: &Features,
        s: &ClothState,
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        touched: &mut [bool],
    ) -> usize {
        if f.is_empty() || self.triangles.is_empty() || s.mode == DetectionMode::Spheres {
            return 0;
        }
        let mut answered = 0;
        self.contacts.clear();
        for pass in 0..PASSES {
            self.detect(o, f, s, x1, pass > 0);
            if self.hits.is_empty() {
                break;
            }
            self.moved.clear();
            self.moved.resize(x1.len(), false);
            let mut any = false;
            for hit in &self.hits {
                let r = respond(
                    o,
                    f.radius,
                    hit,
                    s,
                    (x1, v1),
                    &mut self.moved,
                    &mut self.contacts,
                );
                answered += usize::from(r.is_some());
                any |= r.unwrap_or(false);
            }
            for (t, &m) in touched.iter_mut().zip(&self.moved) {
                *t |= m;
            }
            std::mem::swap(&mut self.dirty, &mut self.moved);
            if !any {
                break;
            }
        }
        answered
    }

    /// The last `resolve`'s contacts with static obstacles (one per cloth face or edge and
    /// feature; earlier passes first).
    pub fn contacts(&self) -> &[FeatureContact] {
        &self.contacts
    }

    /// Finds contacts over the step; with `only_dirty`, only on faces and edges with a vertex
    /// moved by the previous pass (the others' contacts were answered and cannot change).
    fn detect(
        &mut self,
        o: &Obstacle,
        f: &Features,
        s: &ClothState,
        x1: &[Vec3],
        only_dirty: bool,
    ) {
        let continuous = s.mode == DetectionMode::Continuous;
        let x0 = if continuous { s.x0 } else { x1 };
        let start_pose = if continuous { o.pose_prev } else { o.pose };
        let n = x0.len().min(x1.len()).min(s.thickness.len());
        let max_th = s.thickness[..n].iter().copied().fold(0.0, f64::max);
        let (olo, ohi) = o.swept_aabb(max_th + f.radius);

        let triangles = &self.triangles;
        let dirty = &self.dirty;
        self.cand_tris.clear();
        self.cand_tris.par_extend(
            (0..triangles.len() as u32)
                .into_par_iter()
                .with_min_len(512)
                .filter(|&k| {
                    let t = triangles[k as usize];
                    if t.iter().any(|&v| v as usize >= n)
                        || (only_dirty && !t.iter().any(|&v| dirty[v as usize]))
                    {
                        return false;
                    }
                    let (mut lo, mut hi) =
                        (Vec3::splat(f64::INFINITY), -Vec3::splat(f64::INFINITY));
                    for &v in &t {
                        let (a, b) = (x0[v as usize], x1[v as usize]);
                        lo = lo.min(a).min(b);
                        hi = hi.max(a).max(b);
                    }
                    !(lo.cmpgt(ohi).any() || hi.cmplt(olo).any())
                }),
        );
        self.cand_edges.clear();
        for &k in &self.cand_tris {
            self.cand_edges
                .extend_from_slice(&self.tri_edges[k as usize]);
        }
        self.cand_edges.sort_unstable();
        self.cand_edges.dedup();
        if only_dirty {
            let (edges, dirty) = (&self.edges, &self.dirty);
            self.cand_edges
                .retain(|&k| edges[k as usize].iter().any(|&v| dirty[v as usize]));
        }

        let world = |p: &Vec3| (start_pose.transform_point(*p), o.pose.transform_point(*p));
        let pts: Vec<(Vec3, Vec3)> = f.points.iter().map(world).collect();
        let segs: Vec<([Vec3; 2], [Vec3; 2])> = f
            .segments
            .iter()
            .map(|[a, b]| {
                let (a0, a1) = world(a);
                let (b0, b1) = world(b);
                ([a0, b0], [a1, b1])
            })
            .collect();
        // Swept boxes of the features, inflated by the largest contact distance: a CCD hit needs
        // the cloth face's (or edge's) swept box to overlap its feature's, so the hash lookup
        // below drops no contact.
        let pad = Vec3::splat(f.radius + max_th);
        let swept = |ps: &[Vec3]| {
            let mut b = Aabb::from_points(ps, 0.0);
            b.lo -= pad;
            b.hi += pad;
            b
        };
        self.point_boxes.clear();
        self.point_boxes
            .extend(pts.iter().map(|(a, b)| swept(&[*a, *b])));
        self.segment_boxes.clear();
        self.segment_boxes.extend(
            segs.iter()
                .map(|(s0, s1)| swept(&[s0[0], s0[1], s1[0], s1[1]])),
        );
        let cell = |boxes: &[Aabb]| {
            let n = boxes.len().max(1) as f64;
            boxes
                .iter()
                .map(|b| (b.hi - b.lo).max_element())
                .sum::<f64>()
                / n
        };
        self.point_hash
            .build(cell(&self.point_boxes), &self.point_boxes);
        self.segment_hash
            .build(cell(&self.segment_boxes), &self.segment_boxes);
        let (point_hash, segment_hash) = (&self.point_hash, &self.segment_hash);
        let (point_boxes, segment_boxes) = (&self.point_boxes, &self.segment_boxes);
        // Features whose boxes overlap `b`, each once, in index order.
        let near = |hash: &SpatialHash, boxes: &[Aabb], b: &Aabb| {
            let mut out: Vec<usize> = Vec::new();
            hash.query(b, |i| {
                if boxes[i as usize].overlaps(b) {
                    out.push(i as usize);
                }
            });
            out.sort_unstable();
            out.dedup();
            out
        };
        let (pts, segs) = (&pts, &segs);

        let eta = |verts: &[u32]| {
            f.radius
                + verts
                    .iter()
                    .map(|&v| s.thickness[v as usize])
                    .fold(0.0, f64::max)
        };
        let kinematic = |verts: &[u32]| verts.iter().all(|&v| s.inv_mass[v as usize] <= 0.0);
        let cone_ok = |k: usize, world_normal: Vec3| {
            f.cones
                .get(k)
                .is_none_or(|&c| in_cone(c, o.pose.rotation.inverse() * world_normal))
        };

        let vt = self
            .cand_tris
            .par_iter()
            .with_min_len(64)
            .flat_map_iter(|&k| {
                let t = triangles[k as usize];
                let skip = kinematic(&t);
                let e = eta(&t);
                let tri0 = t.map(|v| x0[v as usize]);
                let tri1 = t.map(|v| x1[v as usize]);
                let found = if skip {
                    Vec::new()
                } else {
                    let b = Aabb::from_points(&[tri0, tri1].concat(), 0.0);
                    near(point_hash, point_boxes, &b)
                };
                found.into_iter().filter_map(move |i| {
                    let (p0, p1) = pts[i];
                    let hit = vertex_triangle_ccd_thick(p0, p1, tri0, tri1, e)?;
                    if !cone_ok(i, -hit.normal) {
                        return None;
                    }
                    Some(Hit {
                        t: hit.t,
                        verts: t,
                        w: hit.bary,
                        normal: -hit.normal,
                        local: f.points[i],
                    })
                })
            });
        let edges = &self.edges;
        let ee = self
            .cand_edges
            .par_iter()
            .with_min_len(64)
            .flat_map_iter(|&k| {
                let ed = edges[k as usize];
                let skip = kinematic(&ed);
                let e = eta(&ed);
                let p0 = ed.map(|v| x0[v as usize]);
                let p1 = ed.map(|v| x1[v as usize]);
                let found = if skip {
                    Vec::new()
                } else {
                    let b = Aabb::from_points(&[p0, p1].concat(), 0.0);
                    near(segment_hash, segment_boxes, &b)
                };
                found.into_iter().filter_map(move |i| {
                    let (q0, q1) = segs[i];
                    let hit = edge_edge_ccd_thick(p0, p1, q0, q1, e)?;
                    if !cone_ok(f.points.len() + i, hit.normal) {
                        return None;
                    }
                    let [a, b] = f.segments[i];
                    Some(Hit {
                        t: hit.t,
                        verts: [ed[0], ed[1], ed[1]],
                        w: [1.0 - hit.s, hit.s, 0.0],
                        normal: hit.normal,
                        local: a + (b - a) * hit.u,
                    })
                })
            });
        self.hits.clear();
        self.hits.par_extend(vt);
        self.hits.par_extend(ee);
        // Earliest contacts first; ties broken by the cloth vertices for determinism.
        self.hits.sort_unstable_by(|a, b| {
            a.t.total_cmp(&b.t)
                .then(a.verts.cmp(&b.verts))
                .then(a.w[0].total_cmp(&b.w[0]))
        });
    }
}

/// Answers one contact. `None` when it cannot move (all kinematic), else whether positions moved.
fn respond(
    o: &Obstacle,
    radius: f64,
    hit: &Hit,
    s: &ClothState,
    (x1, v1): (&mut [Vec3], &mut [Vec3]),
    touched: &mut [bool],
    contacts: &mut Vec<FeatureContact>,
) -> Option<bool> {
    let idx = hit.verts.map(|v| v as usize);
    let im = idx.map(|i| s.inv_mass[i].max(0.0));
    // A repeated vertex (edge hits use slot 2 with weight 0) must count once.
    let denom: f64 = (0..3).map(|k| hit.w[k] * hit.w[k] * im[k]).sum();
    if !(denom > 0.0 && denom.is_finite()) {
        return None;
    }
    let th = idx.iter().map(|&i| s.thickness[i]).fold(0.0, f64::max);
    let eta = radius + th;
    let n = hit.normal;
    let f_end = o.pose.transform_point(hit.local);
    let vs = if s.h > 0.0 {
        (f_end - o.pose_prev.transform_point(hit.local)) / s.h
    } else {
        Vec3::ZERO
    };
    let c: Vec3 = (0..3).map(|k| x1[idx[k]] * hit.w[k]).sum();
    let gap = n.dot(c - f_end);
    let mu = o
        .friction
        .unwrap_or_else(|| (0..3).map(|k| hit.w[k] * s.friction[idx[k]]).sum::<f64>());
    if o.pose_prev == o.pose {
        contacts.push(FeatureContact {
            verts: hit.verts,
            weights: hit.w,
            normal: n,
            point: f_end,
            gap: eta,
            mu,
        });
        if s.sprung.binary_search(&hit.verts).is_ok() && gap >= DEEP * eta {
            return Some(false);
        }
    }
    let target = eta * (1.0 + PUSH_SLACK);
    let mut moved = false;
    if gap < eta {
        let impulse = (target - gap) / denom;
        for k in 0..3 {
            if hit.w[k] != 0.0 {
                x1[idx[k]] += n * (hit.w[k] * im[k] * impulse);
                touched[idx[k]] = true;
            }
        }
        moved = true;
    }
    // Velocities per vertex, not through `c`: several cloth edges and faces around one vertex
    // touch the same feature at once (a strap over a box edge: the edge along the strap and the
    // diagonal), and distributing each contact's impulse over its vertices in turn over-corrects
    // the shared vertex, which leaves the step moving away from the feature while its
    // neighbours still approach it. That velocity, undone by the next step's push, never
    // decays (measured: 0.2-0.5 m/s at rest). Removing each moving vertex's own approaching
    // velocity is idempotent (a second contact with the same normal changes nothing), leaves
    // `c` not approaching, and is exact Coulomb friction per vertex.
    for k in 0..3 {
        if hit.w[k] == 0.0 || im[k] == 0.0 || (k == 2 && idx[2] == idx[1]) {
            continue;
        }
        let rel = v1[idx[k]] - vs;
        let vn = rel.dot(n);
        if vn >= 0.0 {
            continue;
        }
        let i = idx[k];
        let solved = s
            .friction_solved
            .get(i)
            .is_some_and(|fs| fs.iter().any(|sn| *sn != Vec3::ZERO && sn.dot(n) > 0.9));
        let dvn = -vn;
        let vt = rel - n * vn;
        let vt_len = vt.length();
        let mu_dvn = if solved { 0.0 } else { mu * dvn };
        let vt_new = if solved {
            vt
        } else if vt_len <= mu_dvn {
            Vec3::ZERO
        } else {
            vt * (1.0 - mu_dvn / vt_len)
        };
        v1[idx[k]] += n * dvn + (vt_new - vt);
        touched[idx[k]] = true;
    }
    Some(moved)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let v: Vec<Vec3> = (0..8)
            .map(|k| Vec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64))
            .collect();
        // Two triangles per face, outward winding.
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let t = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        (v, t)
    }

    #[test]
    fn cube_keeps_edges_and_corners_but_not_face_diagonals() {
        let (v, mut t) = cube();
        let (points, segments) = sharp_features(&v, &t);
        assert_eq!((points.len(), segments.len()), (8, 12));
        // Flip one triangle's winding: the fold test must not mistake its diagonal for sharp.
        t[0].swap(1, 2);
        let (_, segments) = sharp_features(&v, &t);
        assert_eq!(segments.len(), 12);
        // Every kept segment is an axis-aligned unit edge.
        assert!(segments
            .iter()
            .all(|[a, b]| ((*b - *a).abs().max_element() - 1.0).abs() < 1e-12
                && ((*b - *a).length() - 1.0).abs() < 1e-12));
    }

    #[test]
    fn fine_sphere_has_no_sharp_features_coarse_one_does() {
        let sphere = |stacks: usize, slices: usize| {
            let mut v = vec![Vec3::Z];
            for i in 1..stacks {
                let th = std::f64::consts::PI * i as f64 / stacks as f64;
                for j in 0..slices {
                    let ph = std::f64::consts::TAU * j as f64 / slices as f64;
                    v.push(Vec3::new(
                        th.sin() * ph.cos(),
                        th.sin() * ph.sin(),
                        th.cos(),
                    ));
                }
            }
            v.push(-Vec3::Z);
            let bottom = (v.len() - 1) as u32;
            let ring = |i: usize, j: usize| (1 + (i - 1) * slices + j % slices) as u32;
            let mut t = Vec::new();
            for j in 0..slices {
                t.push([0, ring(1, j), ring(1, j + 1)]);
                t.push([bottom, ring(stacks - 1, j + 1), ring(stacks - 1, j)]);
            }
            for i in 1..stacks - 1 {
                for j in 0..slices {
                    t.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
                    t.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
                }
            }
            (v, t)
        };
        let (v, t) = sphere(24, 48);
        let (points, segments) = sharp_features(&v, &t);
        assert_eq!((points.len(), segments.len()), (0, 0));
        // An octahedron-like 2 x 4 sphere folds by 90 degrees everywhere.
        let (v, t) = sphere(2, 4);
        let (points, segments) = sharp_features(&v, &t);
        assert_eq!((points.len(), segments.len()), (6, 12));
    }
}
