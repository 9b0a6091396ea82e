//! The contour half of the self-intersection test: a node's (or a leaf union's) boundary loop,
//! projected along its cone's axis, star-shaped about its centroid over the whole motion.

use super::TopologyBvh;
use crate::Vec3;
use std::f64::consts::PI;

impl TopologyBvh {
    /// Whether the contour `contour[s..e]`, projected along `axis`, is star-shaped about its
    /// centroid at every instant of the last refit's motion (then it is a simple curve, and
    /// with the cone the node cannot touch itself: Schvartzman, Perez and Otaduy 2010). Each
    /// contour edge's orientation about the centroid is quadratic in time; its Bernstein
    /// coefficients all positive bound it above zero over the step.
    pub(super) fn star(&self, (s, e): (u32, u32), axis: Vec3) -> bool {
        let lp = &self.contour[s as usize..e as usize];
        if lp.len() < 3 {
            return false;
        }
        let u = axis.any_orthonormal_vector();
        let w = axis.cross(u);
        let (xa, xb) = (&self.xa, if self.swept { &self.xb } else { &self.xa });
        let at = |x: &[Vec3], i: u32| x.get(i as usize).copied().unwrap_or(Vec3::NAN);
        let centre = |x: &[Vec3]| lp.iter().map(|&i| at(x, i)).sum::<Vec3>() / lp.len() as f64;
        let (c0, c1) = (centre(xa), centre(xb));
        let flat = |p: Vec3| (p.dot(u), p.dot(w));
        let cross = |a: (f64, f64), b: (f64, f64)| a.0 * b.1 - a.1 * b.0;
        let mut turn = 0.0;
        for (i, &p) in lp.iter().enumerate() {
            let q = lp[(i + 1) % lp.len()];
            let (a0, b0) = (flat(at(xa, p) - c0), flat(at(xa, q) - c0));
            let (a1, b1) = (flat(at(xb, p) - c1), flat(at(xb, q) - c1));
            let (f0, f2) = (cross(a0, b0), cross(a1, b1));
            let f1 = 0.5 * (cross(a0, b1) + cross(a1, b0));
            // Written so that NaN fails.
            if !(f0 > 0.0 && f1 > 0.0 && f2 > 0.0) {
                return false;
            }
            turn += f0.atan2(a0.0 * b0.0 + a0.1 * b0.1);
        }
        // Every edge turns forward about the centre: the loop winds once (2 pi), not twice.
        turn < 3.0 * PI
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{brute, found};
    use super::super::{TopologyBvh, CCD_CONE_COS};
    use super::*;

    /// A ribbon wound one and a half turns in (nearly) one plane: every normal is within a few
    /// degrees of +z, so only its contour shows that it overlaps itself. Every pair between
    /// the overlapping turns that brute force finds is found (an in-plane fold, which the cone
    /// test alone misses, as in two sheets crumpled without springs).
    #[test]
    fn a_ribbon_wound_over_itself_in_plane_is_not_culled() {
        let (segs, turns) = (96usize, 1.5);
        let mut x = Vec::new();
        for i in 0..=segs {
            let a = 2.0 * PI * turns * i as f64 / segs as f64;
            let z = 0.002 * a / (2.0 * PI);
            for r in [0.1, 0.2] {
                x.push(Vec3::new(r * a.cos(), r * a.sin(), z));
            }
        }
        let mut tris = Vec::new();
        for i in 0..segs as u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            // Counter-clockwise seen from +z: outer (odd) vertices lead.
            tris.push([a, b, d]);
            tris.push([a, d, c]);
        }
        let edges: Vec<[u32; 2]> = crate::cloth::topology::unique_edges(&tris)
            .into_iter()
            .map(|(a, b)| [a, b])
            .collect();
        for t in &tris {
            let [a, b, c] = t.map(|i| x[i as usize]);
            assert!((b - a).cross(c - a).normalize().z > 0.99);
        }
        let mut bvh = TopologyBvh::build(&tris, &edges, &x);
        bvh.refit(&tris, &edges, &x, &x, |_| 0.004, false);
        assert!(bvh.cone[0].culls(CCD_CONE_COS));
        let (vt, _) = found(&mut bvh, &tris, &edges, CCD_CONE_COS);
        let (bvt, _) = brute(&bvh, &tris, &edges, x.len());
        // Pairs a turn apart along the ribbon.
        let seg = |v: u32| (v / 2) as i64;
        let across: Vec<_> = bvt
            .iter()
            .filter(|(v, t)| (seg(*v) - seg(tris[*t as usize][0])).abs() > segs as i64 / 3)
            .collect();
        assert!(across.len() > 20, "{}", across.len());
        for p in across {
            assert!(vt.binary_search(p).is_ok(), "pair {p:?} culled");
        }
    }
}
