//! Layers of cloth resting on each other: the vertex-triangle pairs the repulsion answered along
//! a face normal, kept while the vertex stays over the face, for the solver to hold apart in
//! the next substep (`sim/coupling/layer_springs.rs`) as it holds the cloth against obstacles.
//!
//! Why: without them the solve knows nothing of cloth-cloth contact, so each substep it moves a
//! vertex resting on a lower layer as far into it as its falling neighbours pull it (most of a
//! spacing a substep on the crumple at twice its resolution), and the repulsion pushes that
//! vertex alone back out: its edges stay stretched for substeps running, far beyond what the
//! solve holds them at.

use crate::collide::narrow;
use crate::Vec3;

/// A vertex over a face of another layer of the same cloth, within reach of its contact
/// distance at the end of the last collision pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelfTouch {
    pub vertex: u32,
    pub triangle: [u32; 3],
    /// The face point closest to the vertex, barycentric.
    pub bary: [f64; 3],
    /// The face's unit normal on the vertex's side.
    pub normal: Vec3,
    /// The pair's contact distance (m).
    pub gap: f64,
}

/// A pair is kept while its vertex is within this many contact distances of the face: the solve
/// that holds it ends it at about its contact distance, where the repulsion (which answers
/// pairs closer than that) no longer finds it. Held one substep and dropped the next, the
/// vertex would fall into the layer every other substep.
const KEEP_REACH: f64 = 1.5;

/// The cosine of the cone about the face normal within which a vertex is over the face (as the
/// repulsion's `OUTSIDE_CONE_COS`, a little wider so that a vertex answered there is kept).
const OVER_FACE_COS: f64 = 0.6;

impl SelfTouch {
    /// The pair at positions `x`, its face normal oriented as `self.normal` and its closest point
    /// new, or `None` when the vertex is no longer over the face within reach (or the face is
    /// degenerate).
    pub fn refreshed(&self, x: &[Vec3]) -> Option<SelfTouch> {
        self.over(self.triangle, x)
    }

    /// The pair's vertex over `triangle` at `x`, as [`SelfTouch::refreshed`].
    fn over(&self, triangle: [u32; 3], x: &[Vec3]) -> Option<SelfTouch> {
        let [a, b, c] = triangle.map(|i| x[i as usize]);
        let p = x[self.vertex as usize];
        let nf = (b - a).cross(c - a).normalize_or_zero();
        if nf == Vec3::ZERO {
            return None;
        }
        let normal = if nf.dot(self.normal) >= 0.0 { nf } else { -nf };
        let (q, bary) = narrow::point_triangle_closest(p, a, b, c);
        let r = p - q;
        let d = r.length();
        let over = normal.dot(r);
        (d < KEEP_REACH * self.gap && over >= OVER_FACE_COS * d && over >= 0.0).then_some(
            SelfTouch {
                triangle,
                bary,
                normal,
                ..*self
            },
        )
    }

    /// The pair at `x` as [`SelfTouch::refreshed`], or, when the vertex has left its face (a
    /// layer sliding over another), the nearest face around the old one's vertices
    /// (`faces_around`) that the vertex is over within reach and that does not hold the vertex.
    /// Dropped there, the vertex would fall into the layer until the repulsion (which answers
    /// pairs closer than the contact distance, where the spring holds them a little beyond)
    /// found it again, held in the meantime by position moves without friction: a cloth slid
    /// down a cloth incline at several times Coulomb's acceleration.
    pub fn handed_over(
        &self,
        x: &[Vec3],
        faces_around: impl Fn(u32) -> Vec<[u32; 3]>,
    ) -> Option<SelfTouch> {
        if let Some(t) = self.refreshed(x) {
            return Some(t);
        }
        let p = x[self.vertex as usize];
        self.triangle
            .iter()
            .flat_map(|&v| faces_around(v))
            .filter(|tri| *tri != self.triangle && !tri.contains(&self.vertex))
            .filter_map(|tri| self.over(tri, x))
            .map(|t| {
                let q: Vec3 = (0..3).map(|k| x[t.triangle[k] as usize] * t.bary[k]).sum();
                ((p - q).length_squared(), t)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, t)| t)
    }
}

/// The pairs of `found` (this pass's, first) and `kept` (the last pass's) that are still over
/// their faces at `x`, or handed over to a face around (`SelfTouch::handed_over`, with the
/// triangles around each vertex `faces_around`), refreshed, each once, into `out` sorted by
/// (vertex, triangle).
pub fn refresh(
    found: &[SelfTouch],
    kept: &[SelfTouch],
    x: &[Vec3],
    faces_around: impl Fn(u32) -> Vec<[u32; 3]>,
    out: &mut Vec<SelfTouch>,
) {
    out.clear();
    let n = x.len();
    let in_range =
        |t: &SelfTouch| (t.vertex as usize) < n && t.triangle.iter().all(|&i| (i as usize) < n);
    out.extend(
        found
            .iter()
            .chain(kept)
            .filter(|t| in_range(t))
            .filter_map(|t| t.handed_over(x, &faces_around)),
    );
    // Stable: a pair found in this pass keeps this pass's side of the face.
    out.sort_by_key(|t| (t.vertex, t.triangle));
    out.dedup_by_key(|t| (t.vertex, t.triangle));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn touch(z: f64) -> (SelfTouch, Vec<Vec3>) {
        let x = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.25, 0.25, z),
        ];
        let t = SelfTouch {
            vertex: 3,
            triangle: [0, 1, 2],
            bary: [1.0 / 3.0; 3],
            normal: Vec3::Z,
            gap: 0.01,
        };
        (t, x)
    }

    /// Kept within reach, on the side it was on, with the closest point of now; dropped beyond
    /// reach or behind the face.
    #[test]
    fn a_pair_is_kept_while_the_vertex_is_over_the_face_within_reach() {
        let (t, x) = touch(0.012);
        let r = t.refreshed(&x).expect("within 1.5 gaps");
        assert_eq!(r.normal, Vec3::Z);
        assert!((r.bary[0] - 0.5).abs() < 1e-12 && (r.bary[1] - 0.25).abs() < 1e-12);
        assert!(touch(0.016).0.refreshed(&touch(0.016).1).is_none());
        assert!(touch(-0.002).0.refreshed(&touch(-0.002).1).is_none());
        let (mut below, x) = touch(-0.008);
        below.normal = -Vec3::Z;
        assert_eq!(below.refreshed(&x).map(|r| r.normal), Some(-Vec3::Z));
    }

    /// Found and kept lists merge into one entry per pair.
    #[test]
    fn refresh_keeps_each_pair_once() {
        let (t, x) = touch(0.005);
        let mut out = Vec::new();
        refresh(&[t], &[t, t], &x, |_| Vec::new(), &mut out);
        assert_eq!(out.len(), 1);
    }
}
