//! Self-contact broad phase over a bounding-volume hierarchy built once on the cloth's mesh, with
//! normal cones, so that flat or gently curved parts of the cloth cost no pair tests at all.
//!
//! Why: on a spatial hash nearly every visit is a mesh neighbour, so the visits far outnumber the
//! candidate pairs; the hierarchy skips whole patches that cannot touch themselves. A surface patch
//! that is a topological disk, whose normals all lie strictly within 90 degrees of one axis and
//! whose contour, projected along that axis, is a simple curve, is a height field over the plane
//! normal to the axis and cannot intersect itself (Volino and Magnenat-Thalmann 1994; Provot 1997).
//! A node needs no test inside it when it passes both halves, and so do two adjacent leaves whose
//! union does (`unions`, precomputed). The contour half is needed: a sheet can fold in its own
//! plane, every normal up (two sheets crumpled without springs do, in `collide_self`), and the cone
//! alone would let a vertex through a triangle two rings away. The contour test is star-shapedness
//! about the contour's centroid (Schvartzman, Perez and Otaduy 2010): sufficient and linear in the
//! contour; it needs convex-ish nodes, so the tree splits quads (triangle pairs), not triangles,
//! between rows along the grid's own directions (`split`), and a grid's nodes are rectangles.
//!
//! Over a step the cone bounds the normal at every instant: with vertices moving linearly the
//! normal is a quadratic Bezier curve in time whose control vectors are the start normal, the end
//! normal and their cross term, and a cone holding those holds the curve (a positive combination).
//!
//! Proximity (distance below the contact distance `d`) is culled with a narrower cone (45
//! degrees): such a patch is a graph of slope at most 1 over the plane normal to the axis, so two
//! of its points closer than `d` are at most `sqrt(2) d` apart along the cloth. Pairs that near
//! in the rest shape are exempt from proximity (`exempt`) or kept on the rest shape's near lists
//! (`RestShape::near_vt`, `near_ee`, within `FOLD_ARC d > sqrt(2) d`), which the caller tests
//! whatever the cones say; a wider cone would skip the two sides of a crease that is closing.
//!
//! Vertices and edges are each owned by one leaf (the first of their triangles in leaf order),
//! so every vertex-triangle and edge-edge pair is tested once: inside a leaf or between two.
//!
//! Files: `build` (the tree, its contours and leaf unions, once on the rest shape), `refit`
//! (boxes and cones for a motion), `traversal` (the pair queries over node pairs), `elements`
//! (the element tests of two leaves), `star` (the contour test).

use crate::collide::broad::Aabb;
use crate::Vec3;
use std::f64::consts::{FRAC_PI_2, PI};

mod build;
mod elements;
mod refit;
mod star;
#[cfg(test)]
mod test_support;
mod traversal;

/// Triangles per leaf: small enough that a leaf is flat where the cloth is, large enough that
/// the tree's node tests stay fewer than the element tests they save.
const LEAF: usize = 8;

/// Candidate pairs: (vertex, triangle) or (edge, edge).
type Pairs = Vec<(u32, u32)>;

/// Cosine of the widest cone that culls intersection (CCD): just inside 90 degrees, for the
/// round-off of the cone merges.
const CCD_CONE_COS: f64 = 1e-3;
/// Cosine of the widest cone that culls proximity (45 degrees; see the module doc).
const PROXIMITY_CONE_COS: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// A cone of directions: `axis` (unit), half-angle `half` (rad; `PI` holds every direction)
/// and its cosine.
#[derive(Debug, Clone, Copy)]
struct Cone {
    axis: Vec3,
    half: f64,
    cos: f64,
}

impl Cone {
    const FULL: Cone = Cone {
        axis: Vec3::Z,
        half: PI,
        cos: -1.0,
    };

    fn new(axis: Vec3, half: f64) -> Cone {
        Cone {
            axis,
            half,
            cos: half.cos(),
        }
    }

    /// The smallest cone (up to the merge's over-estimate) holding both; `FULL` once it is
    /// wider than 90 degrees, since no cone that wide culls.
    fn merge(self, o: Cone) -> Cone {
        if self.half >= FRAC_PI_2 || o.half >= FRAC_PI_2 {
            return Cone::FULL;
        }
        let phi = self.axis.dot(o.axis).clamp(-1.0, 1.0).acos();
        if phi + o.half <= self.half {
            return self;
        }
        if phi + self.half <= o.half {
            return o;
        }
        let half = 0.5 * (phi + self.half + o.half);
        if half >= FRAC_PI_2 || phi <= 0.0 {
            return Cone::FULL;
        }
        // Rotate `self.axis` towards `o.axis` by `half - self.half` (spherical interpolation).
        let t = half - self.half;
        let axis = (self.axis * (phi - t).sin() + o.axis * t.sin()) / phi.sin();
        let axis = axis.normalize_or_zero();
        if axis == Vec3::ZERO || !axis.is_finite() {
            return Cone::FULL;
        }
        Cone::new(axis, half)
    }

    /// Whether the cone is narrower than the half-angle whose cosine is `cos`.
    fn culls(&self, cos: f64) -> bool {
        self.cos > cos
    }
}

/// One node: a leaf's triangles are `order[first..first + count]`; an internal node's children
/// are the next node (`index + 1`, pre-order) and `right`.
#[derive(Debug, Clone)]
struct Node {
    first: u32,
    count: u32,
    right: u32,
    /// Its triangles form a topological disk (edge-connected, manifold, one boundary loop,
    /// Euler characteristic 1): only then can its cone cull. The loop (ordered along the
    /// triangles' orientation) is `contour[loop.0..loop.1]`, empty when not a disk.
    contour: (u32, u32),
    /// A leaf's own vertices and edges: ranges into `owned_v`, `owned_e`.
    verts: (u32, u32),
    edges: (u32, u32),
}

impl Node {
    fn is_leaf(&self) -> bool {
        self.right == 0
    }
}

/// The hierarchy (built once) and the boxes and cones of its last refit.
#[derive(Debug, Default)]
pub(super) struct TopologyBvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    contour: Vec<u32>,
    /// Leaf pairs `(lower, higher)` forming a disk, sorted, with their union's contour range.
    unions: Vec<((u32, u32), (u32, u32))>,
    owned_v: Vec<u32>,
    owned_e: Vec<u32>,
    /// The last refit's motion (`xb` only when `swept`), for the contour tests.
    xa: Vec<Vec3>,
    xb: Vec<Vec3>,
    swept: bool,
    /// Per refit: per vertex its swept box and margin, per triangle and edge its swept box, per
    /// node its box (no margin), largest margin and cone.
    vbox: Vec<Aabb>,
    margin: Vec<f64>,
    tbox: Vec<Aabb>,
    ebox: Vec<Aabb>,
    nbox: Vec<Aabb>,
    nmargin: Vec<f64>,
    cone: Vec<Cone>,
    /// Leaf pairs the last traversal left to the element tests, and how many node pairs it
    /// tested.
    leaf_pairs: Vec<(u32, u32)>,
    pub node_tests: usize,
    /// Per node, for the current traversal: whether it may hold a changed element (empty:
    /// every node may).
    changed: Vec<bool>,
    chunks: Vec<(Pairs, Pairs)>,
}

/// A vertex's box over its motion `a -> b`: empty where that is not finite.
fn swept_box(a: Vec3, b: Vec3) -> Aabb {
    let bx = Aabb::from_points(&[a, b], 0.0);
    if bx.lo.is_finite() && bx.hi.is_finite() {
        bx
    } else {
        Aabb::EMPTY
    }
}

/// The box of an element from its vertices' boxes: empty where one is (a non-finite vertex
/// box), so the element is near nothing.
fn joined(a: Aabb, b: Aabb) -> Aabb {
    if a == Aabb::EMPTY || b == Aabb::EMPTY {
        return Aabb::EMPTY;
    }
    Aabb {
        lo: a.lo.min(b.lo),
        hi: a.hi.max(b.hi),
    }
}

/// The box holding both (the empty box holds nothing).
fn hull(a: Aabb, b: Aabb) -> Aabb {
    Aabb {
        lo: a.lo.min(b.lo),
        hi: a.hi.max(b.hi),
    }
}

/// Whether two boxes come nearer than `m` (Euclidean: tighter than growing one by `m` on each
/// axis, and as conservative, since every point of either element lies in its box). Empty
/// boxes (elements with a non-finite vertex) are near nothing.
fn near(a: &Aabb, b: &Aabb, m: f64) -> bool {
    let gap = (b.lo - a.hi).max(a.lo - b.hi).max(Vec3::ZERO);
    gap.length_squared() < m * m
}
