//! Aggregation: vertices grouped along strong connections `|A_ij|_F^2 >= theta^2 |A_ii|_F
//! |A_jj|_F`, each aggregate one coarse vertex.

use super::csr::{frob2, Csr};
use glam::Mat3A as M3;

/// Strength threshold on `|A_ij|_F^2 >= theta^2 |A_ii|_F |A_jj|_F`.
const THETA: f32 = 0.08;

/// A row in no aggregate: no strong connection at all (see [`aggregate`]).
pub(super) const ISOLATED: u32 = u32::MAX;

/// Aggregates of the strong-connection graph (Vanek, Mandel, Brezina 1996): seeds whose strong
/// neighbourhood is untouched become aggregates, leftovers join a neighbouring aggregate, the rest
/// form their own. Returns the aggregate of each row and the aggregate count.
///
/// A row with no strong connection ([`ISOLATED`]: its diagonal dominates, e.g. a vertex held by
/// a sticking friction drag, `mu N / STICK_SPEED` per m/s) is in no aggregate: the smoother
/// solves it, and the coarse levels leave it out. As singleton aggregates such rows would stall
/// the coarsening (S1 64x64 with friction 5 at rest: coarse levels a quarter of the fine one
/// and more, dense after smoothing the prolongator, and slow to build).
pub(super) fn aggregate(a: &Csr, diag: &[M3]) -> (Vec<u32>, usize) {
    let n = a.rows();
    let dnorm: Vec<f32> = diag.iter().map(|d| frob2(d).sqrt()).collect();
    let strong =
        |i: usize, j: usize, m: &M3| i != j && frob2(m) >= THETA * THETA * dnorm[i] * dnorm[j];
    const NONE: u32 = u32::MAX - 1;
    let mut agg = vec![NONE; n];
    let mut count = 0u32;
    for (i, ai) in agg.iter_mut().enumerate() {
        let (cols, vals) = a.row(i);
        if !cols
            .iter()
            .zip(vals)
            .any(|(&j, m)| strong(i, j as usize, m))
        {
            *ai = ISOLATED;
        }
    }
    // Phase 1: untouched neighbourhoods.
    for i in 0..n {
        if agg[i] != NONE {
            continue;
        }
        let (cols, vals) = a.row(i);
        let free = cols
            .iter()
            .zip(vals)
            .all(|(&j, m)| !strong(i, j as usize, m) || agg[j as usize] == NONE);
        if !free {
            continue;
        }
        agg[i] = count;
        for (&j, m) in cols.iter().zip(vals) {
            if strong(i, j as usize, m) {
                agg[j as usize] = count;
            }
        }
        count += 1;
    }
    // Phase 2: join the most strongly connected phase-1 aggregate.
    let phase1 = agg.clone();
    for (i, ai) in agg.iter_mut().enumerate() {
        if *ai != NONE {
            continue;
        }
        let (cols, vals) = a.row(i);
        let mut best = (0.0, NONE);
        for (&j, m) in cols.iter().zip(vals) {
            let s = frob2(m);
            if strong(i, j as usize, m) && phase1[j as usize] != NONE && s > best.0 {
                best = (s, phase1[j as usize]);
            }
        }
        *ai = best.1;
    }
    // Phase 3: whatever is left (rows whose strong neighbours were all taken) forms its own
    // aggregates.
    for i in 0..n {
        if agg[i] != NONE {
            continue;
        }
        agg[i] = count;
        let (cols, vals) = a.row(i);
        for (&j, m) in cols.iter().zip(vals) {
            if strong(i, j as usize, m) && agg[j as usize] == NONE {
                agg[j as usize] = count;
            }
        }
        count += 1;
    }
    (agg, count as usize)
}
