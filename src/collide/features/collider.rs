//! The feature collider of the collision stage: the cloth's faces and edges, the candidates
//! near one obstacle's swept features, and the detect-and-respond passes.

use super::contact::{ClothState, FeatureContact, Hit};
use super::point_face::point_face_hits;
use super::respond::respond;
use super::segment_edge::segment_edge_hits;
use super::set::Features;
use super::sweep::Sweep;
use crate::collide::broad::{Aabb, SpatialHash};
use crate::collide::exit::is_exiting;
use crate::collide::obstacle::Obstacle;
use crate::collide::settings::DetectionMode;
use crate::Vec3;
use rayon::prelude::*;

/// Detect-and-respond passes per step: a push can bring a neighbouring face into contact.
const PASSES: usize = 4;

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
    /// Contacts of the last `resolve`.
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

    /// The cloth's triangles.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The cloth's mesh edges, each once (`[low, high]`, sorted).
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// Detects and answers feature contacts of obstacle `o` (index `obstacle`) over the step, updating `x1`, `v1`.
    /// Marks every moved vertex in `touched`. Returns the number of contacts answered.
    #[allow(clippy::too_many_arguments)]
    pub fn resolve(
        &mut self,
        o: &Obstacle,
        obstacle: usize,
        f: &Features,
        s: &ClothState,
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        touched: &mut [bool],
    ) -> usize {
        // Cleared before any early return: the caller appends `contacts()` after every call, so
        // an obstacle without features must not hand on the previous obstacle's contacts (with
        // culling on, a featureless obstacle first in the list repeated the last near link's).
        self.contacts.clear();
        if f.is_empty() || self.triangles.is_empty() || s.mode == DetectionMode::Spheres {
            return 0;
        }
        let mut answered = 0;
        for pass in 0..PASSES {
            self.detect(o, obstacle, f, s, x1, pass > 0);
            if self.hits.is_empty() {
                break;
            }
            self.moved.clear();
            self.moved.resize(x1.len(), false);
            let mut any = false;
            for hit in &self.hits {
                let r = respond(
                    o,
                    obstacle,
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

    /// The last `resolve`'s contacts (one per cloth face or edge and
    /// feature; earlier passes first).
    pub fn contacts(&self) -> &[FeatureContact] {
        &self.contacts
    }

    /// Finds contacts over the step; with `only_dirty`, only on faces and edges with a vertex
    /// moved by the previous pass (the others' contacts were answered and cannot change).
    fn detect(
        &mut self,
        o: &Obstacle,
        obstacle: usize,
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
        let pinched = |v: u32| {
            (s.pinched_by.get(v as usize)).is_some_and(|p| p.is_some_and(|p| p.contains(&obstacle)))
        };
        self.cand_tris.clear();
        self.cand_tris.par_extend(
            (0..triangles.len() as u32)
                .into_par_iter()
                .with_min_len(512)
                .filter(|&k| {
                    let t = triangles[k as usize];
                    if t.iter().any(|&v| v as usize >= n)
                        || (only_dirty && !t.iter().any(|&v| dirty[v as usize]))
                        || t.iter()
                            .any(|&v| is_exiting(s.exits, v as usize) || pinched(v))
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
        if !s.exits.is_empty() || !s.pinched_by.is_empty() {
            let edges = &self.edges;
            self.cand_edges.retain(|&k| {
                (edges[k as usize].iter()).all(|&v| !is_exiting(s.exits, v as usize) && !pinched(v))
            });
        }
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
        let sweep = Sweep {
            o,
            f,
            s,
            x0,
            x1,
            pts: &pts,
            segs: &segs,
            point_hash: &self.point_hash,
            point_boxes: &self.point_boxes,
            segment_hash: &self.segment_hash,
            segment_boxes: &self.segment_boxes,
        };
        self.hits.clear();
        point_face_hits(&sweep, &self.triangles, &self.cand_tris, &mut self.hits);
        segment_edge_hits(&sweep, &self.edges, &self.cand_edges, &mut self.hits);
        // Earliest contacts first; ties broken by the cloth vertices for determinism.
        self.hits.sort_unstable_by(|a, b| {
            a.t.total_cmp(&b.t)
                .then(a.verts.cmp(&b.verts))
                .then(a.w[0].total_cmp(&b.w[0]))
        });
    }
}
