//! The self-contact collider: the cloth's triangles, edges and 1-ring, the scratch buffers of
//! the passes, and the stencils of its pairs.

use super::bvh::TopologyBvh;
use super::changed::Changed;
use super::jacobi::{Correction, JacobiPass, Keyed};
use super::report::SelfContactReport;
use super::rest::{Csr, RestShape};
use super::stencil::Stencil;
use super::touch::SelfTouch;
use crate::collide::broad::{Aabb, PairScratch, SpatialHash};
use crate::collide::ring::one_ring;
use crate::Vec3;

pub(crate) struct SelfCollider {
    pub(super) triangles: Vec<[u32; 3]>,
    pub(super) edges: Vec<[u32; 2]>,
    /// CSR vertex -> neighbour vertices (1-ring), for excluding adjacent vertex-vertex pairs.
    pub(super) nbr_start: Vec<u32>,
    pub(super) nbr: Vec<u32>,
    pub(super) hash: SpatialHash,
    /// The vertex-triangle and edge-edge broad phase (built on the first state it sees).
    pub(super) bvh: Option<TopologyBvh>,
    pub(super) qboxes: Vec<Aabb>,
    pub(super) iboxes: Vec<Aabb>,
    pub(super) stamp: PairScratch,
    /// The end positions in the frame of the cloth's mean motion (the CCD broad phase's).
    pub(super) x_mean_frame: Vec<Vec3>,
    /// The translation of that frame at the hierarchy's last refit when it was swept (CCD),
    /// kept by a re-test's refit of what changed.
    pub(super) swept_frame: Option<Vec3>,
    /// The answers of a pass and their per-vertex means, reused.
    pub(super) found: Vec<Correction>,
    pub(super) jacobi: JacobiPass,
    /// What changed since the last repulsion pass, and since the last correcting CCD pass.
    pub(super) rep_changed: Changed,
    pub(super) ccd_changed: Changed,
    pub(super) pairs: Vec<(u32, u32)>,
    pub(super) pairs_ee: Vec<(u32, u32)>,
    /// A repulsion pass's vertex-triangle answers, keyed by their pair, before they are merged
    /// in order with the near pairs' (`proximity::near_answers`).
    pub(super) found_vt: Vec<Keyed>,
    pub(super) found_near: Vec<Keyed>,
    /// The near pairs whose boxes overlapped at the last refit (`proximity::near_answers`),
    /// valid while `near_kept_valid` (a refit clears it).
    pub(super) near_kept: Vec<(u32, u32)>,
    pub(super) near_kept_valid: bool,
    /// The pairs of two layers this substep's repulsion answered (see [`super::SelfTouch`]).
    pub(super) touches: Vec<SelfTouch>,
    /// Per vertex, the triangles around it (a touch's faces to hand over to, `touch`).
    pub(super) vertex_faces: Csr,
    pub(super) w: Vec<f64>,
    /// Inverse masses without the obstacle-contact weighting of `w`: friction's impulses are
    /// distributed by these, equal and opposite on the two layers.
    pub(super) w_true: Vec<f64>,
    /// The positions the repulsion passes started from, for the caller's hold on what they
    /// stretched (see [`SelfCollider::resolve`]).
    pub(super) before_repulsion: Vec<Vec3>,
    pub(super) parent: Vec<u32>,
    pub(super) zone_members: Vec<Vec<u32>>,
    pub(super) in_zone: Vec<bool>,
    /// The rest shape's neighbourhoods (built on the first `resolve`), for rest proximity.
    pub(super) rest: Option<RestShape>,
    /// Per vertex: bits of the seams being sewn near it (empty: none).
    pub(super) seam_bits: Vec<u64>,
    /// The counts of the current `resolve`.
    pub(super) report: SelfContactReport,
}

pub(super) fn shares_vertex(a: &[u32], b: &[u32]) -> bool {
    a.iter().any(|v| b.contains(v))
}

/// The four vertices of vertex-triangle pair `(v, t)`.
pub(super) fn vt_vertices(triangles: &[[u32; 3]], v: u32, t: u32) -> [u32; 4] {
    let tri = triangles[t as usize];
    [v, tri[0], tri[1], tri[2]]
}

/// The four vertices of edge-edge pair `(e, f)`.
pub(super) fn ee_vertices(edges: &[[u32; 2]], e: u32, f: u32) -> [u32; 4] {
    let (a, b) = (edges[e as usize], edges[f as usize]);
    [a[0], a[1], b[0], b[1]]
}

impl SelfCollider {
    /// The pairs of two layers the last `resolve`'s repulsion answered.
    pub fn touches(&self) -> &[SelfTouch] {
        &self.touches
    }

    /// The triangles around vertex `v` (empty beyond the mesh).
    pub fn faces_around(&self, v: u32) -> Vec<[u32; 3]> {
        let row = if (v as usize) < self.vertex_faces.rows() {
            self.vertex_faces.row(v as usize)
        } else {
            &[]
        };
        row.iter().map(|&t| self.triangles[t as usize]).collect()
    }

    pub fn new(triangles: &[[u32; 3]], n_vertices: usize) -> Self {
        let edges: Vec<[u32; 2]> = crate::cloth::topology::unique_edges(triangles)
            .into_iter()
            .map(|(a, b)| [a, b])
            .collect();
        let (nbr_start, nbr) = one_ring(&edges, n_vertices);
        Self {
            triangles: triangles.to_vec(),
            edges,
            nbr_start,
            nbr,
            hash: SpatialHash::default(),
            bvh: None,
            qboxes: Vec::new(),
            iboxes: Vec::new(),
            stamp: PairScratch::default(),
            x_mean_frame: Vec::new(),
            swept_frame: None,
            found: Vec::new(),
            jacobi: JacobiPass::default(),
            rep_changed: Changed::default(),
            ccd_changed: Changed::default(),
            pairs: Vec::new(),
            pairs_ee: Vec::new(),
            found_vt: Vec::new(),
            found_near: Vec::new(),
            near_kept: Vec::new(),
            near_kept_valid: false,
            touches: Vec::new(),
            vertex_faces: vertex_faces(triangles, n_vertices),
            w: Vec::new(),
            w_true: Vec::new(),
            before_repulsion: Vec::new(),
            parent: Vec::new(),
            zone_members: Vec::new(),
            in_zone: Vec::new(),
            rest: None,
            seam_bits: Vec::new(),
            report: SelfContactReport::default(),
        }
    }

    pub(super) fn adjacent(&self, a: u32, b: u32) -> bool {
        let (s, e) = (
            self.nbr_start[a as usize] as usize,
            self.nbr_start[a as usize + 1] as usize,
        );
        self.nbr[s..e].contains(&b)
    }

    /// Candidate pairs over boxes of (x0 .. x1) inflated by per-element `margin`:
    /// vertex-triangle into `pairs`, edge-edge into `pairs_ee` (or vertex-vertex into `pairs`).
    pub(super) fn vt_stencil(&self, v: u32, t: u32, bary: [f64; 3]) -> Stencil {
        let tri = self.triangles[t as usize];
        Stencil {
            idx: [v, tri[0], tri[1], tri[2]],
            c: [1.0, -bary[0], -bary[1], -bary[2]],
            len: 4,
        }
    }

    pub(super) fn ee_stencil(&self, e1: u32, e2: u32, s: f64, u: f64) -> Stencil {
        let (a, b) = (self.edges[e1 as usize], self.edges[e2 as usize]);
        Stencil {
            idx: [a[0], a[1], b[0], b[1]],
            c: [1.0 - s, s, -(1.0 - u), -u],
            len: 4,
        }
    }
}

/// Per vertex, the indices of the triangles around it.
fn vertex_faces(triangles: &[[u32; 3]], n_vertices: usize) -> Csr {
    let mut rows = vec![Vec::new(); n_vertices];
    for (t, tri) in triangles.iter().enumerate() {
        for &v in tri {
            if let Some(row) = rows.get_mut(v as usize) {
                row.push(t as u32);
            }
        }
    }
    let mut csr = Csr::default();
    for row in &mut rows {
        csr.push(row);
    }
    csr
}
