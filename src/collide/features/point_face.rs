//! Query: obstacle corner points (and rod ends) against moving cloth triangles, by thick
//! vertex-triangle CCD at `eta = radius + thickness`.

use super::contact::Hit;
use super::sweep::Sweep;
use crate::collide::broad::Aabb;
use crate::collide::narrow::vertex_triangle_ccd_thick;
use rayon::prelude::*;

/// Appends the hits of the feature points against the candidate triangles `cand_tris`.
pub(super) fn point_face_hits(
    sw: &Sweep,
    triangles: &[[u32; 3]],
    cand_tris: &[u32],
    out: &mut Vec<Hit>,
) {
    let (x0, x1) = (sw.x0, sw.x1);
    let vt = cand_tris.par_iter().with_min_len(64).flat_map_iter(|&k| {
        let t = triangles[k as usize];
        let skip = sw.kinematic(&t);
        let e = sw.eta(&t);
        let tri0 = t.map(|v| x0[v as usize]);
        let tri1 = t.map(|v| x1[v as usize]);
        let found = if skip {
            Vec::new()
        } else {
            let b = Aabb::from_points(&[tri0, tri1].concat(), 0.0);
            Sweep::near(sw.point_hash, sw.point_boxes, &b)
        };
        found.into_iter().filter_map(move |i| {
            let (p0, p1) = sw.pts[i];
            let hit = vertex_triangle_ccd_thick(p0, p1, tri0, tri1, e)?;
            if !sw.cone_ok(i, -hit.normal) {
                return None;
            }
            Some(Hit {
                t: hit.t,
                verts: t,
                w: hit.bary,
                normal: -hit.normal,
                local: sw.f.points[i],
            })
        })
    });
    out.par_extend(vt);
}
