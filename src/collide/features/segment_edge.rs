//! Query: obstacle segments (box and mesh edges, rod axes) against moving cloth edges, by thick
//! edge-edge CCD at `eta = radius + thickness`.

use super::contact::Hit;
use super::sweep::Sweep;
use crate::collide::broad::Aabb;
use crate::collide::narrow::edge_edge_ccd_thick;
use rayon::prelude::*;

/// Appends the hits of the feature segments against the candidate cloth edges `cand_edges`.
pub(super) fn segment_edge_hits(
    sw: &Sweep,
    edges: &[[u32; 2]],
    cand_edges: &[u32],
    out: &mut Vec<Hit>,
) {
    let (x0, x1) = (sw.x0, sw.x1);
    let n_points = sw.f.points.len();
    let ee = cand_edges.par_iter().with_min_len(64).flat_map_iter(|&k| {
        let ed = edges[k as usize];
        let skip = sw.kinematic(&ed);
        let e = sw.eta(&ed);
        let p0 = ed.map(|v| x0[v as usize]);
        let p1 = ed.map(|v| x1[v as usize]);
        let found = if skip {
            Vec::new()
        } else {
            let b = Aabb::from_points(&[p0, p1].concat(), 0.0);
            Sweep::near(sw.segment_hash, sw.segment_boxes, &b)
        };
        found.into_iter().filter_map(move |i| {
            let (q0, q1) = sw.segs[i];
            let hit = edge_edge_ccd_thick(p0, p1, q0, q1, e)?;
            if !sw.cone_ok(n_points + i, hit.normal) {
                return None;
            }
            let [a, b] = sw.f.segments[i];
            Some(Hit {
                t: hit.t,
                verts: [ed[0], ed[1], ed[1]],
                w: [1.0 - hit.s, hit.s, 0.0],
                normal: hit.normal,
                local: a + (b - a) * hit.u,
            })
        })
    });
    out.par_extend(ee);
}
