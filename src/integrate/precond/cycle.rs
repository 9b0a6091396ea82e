//! The V-cycle: forward sweep, restriction, coarse correction (dense solve or sweeps on the
//! coarsest level), prolongation, backward sweep; symmetric, so PCG may use it.

use super::dense::Dense;
use super::smooth::Level;
use glam::Vec3A as V3;

const COARSE_SWEEPS: usize = 8;

pub(super) fn cycle(levels: &mut [Level], dense: Option<&Dense>, tmp: &mut Vec<f64>) {
    let Some((l, rest)) = levels.split_first_mut() else {
        return;
    };
    if rest.is_empty() {
        match dense {
            Some(d) => d.solve(&l.b, &mut l.x, tmp),
            None => {
                l.x.iter_mut().for_each(|x| *x = V3::ZERO);
                for _ in 0..COARSE_SWEEPS {
                    l.gauss_seidel(false);
                    l.gauss_seidel(true);
                }
            }
        }
        return;
    }
    l.forward_sweep_from_zero();
    l.residual_after_forward_sweep();
    l.pt.mul(&l.r, &mut rest[0].b);
    cycle(rest, dense, tmp);
    l.p.mul(&rest[0].x, &mut l.r);
    for (xi, ci) in l.x.iter_mut().zip(&l.r) {
        *xi += *ci;
    }
    l.backward_sweep();
}

#[cfg(test)]
mod tests;
