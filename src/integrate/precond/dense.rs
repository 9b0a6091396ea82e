//! The coarsest level's exact solve: dense Cholesky of the small coarsest matrix.

use super::csr::Csr;
use super::error::MultigridError;
use glam::Vec3A as V3;

/// Dense Cholesky factor of the coarsest matrix (row-major lower triangle).
#[derive(Debug, Clone)]
pub(super) struct Dense {
    pub(super) n: usize,
    pub(super) l: Vec<f64>,
}

impl Dense {
    pub(super) fn factor(a: &Csr) -> Result<Dense, MultigridError> {
        let n = a.rows() * 3;
        let mut l = vec![0.0; n * n];
        for r in 0..a.rows() {
            let (cols, vals) = a.row(r);
            for (&c, m) in cols.iter().zip(vals) {
                for bi in 0..3 {
                    for bj in 0..3 {
                        // glam is column-major: col(bj)[bi] is row bi, column bj.
                        l[(3 * r + bi) * n + 3 * c as usize + bj] = f64::from(m.col(bj)[bi]);
                    }
                }
            }
        }
        for j in 0..n {
            let mut d = l[j * n + j];
            for k in 0..j {
                d -= l[j * n + k] * l[j * n + k];
            }
            if !(d > 0.0 && d.is_finite()) {
                return Err(MultigridError::CoarseNotPositive { rows: n, pivot: j });
            }
            let d = d.sqrt();
            l[j * n + j] = d;
            for i in j + 1..n {
                let mut s = l[i * n + j];
                for k in 0..j {
                    s -= l[i * n + k] * l[j * n + k];
                }
                l[i * n + j] = s / d;
            }
        }
        Ok(Dense { n, l })
    }

    pub(super) fn solve(&self, b: &[V3], x: &mut [V3], tmp: &mut Vec<f64>) {
        let n = self.n;
        tmp.clear();
        tmp.extend(b.iter().flat_map(|v| [v.x, v.y, v.z].map(f64::from)));
        for i in 0..n {
            let row = &self.l[i * n..i * n + i];
            let s: f64 = row.iter().zip(&tmp[..i]).map(|(l, t)| l * t).sum();
            tmp[i] = (tmp[i] - s) / self.l[i * n + i];
        }
        for i in (0..n).rev() {
            let s: f64 = (i + 1..n).map(|k| self.l[k * n + i] * tmp[k]).sum();
            tmp[i] = (tmp[i] - s) / self.l[i * n + i];
        }
        for (i, xi) in x.iter_mut().enumerate() {
            *xi = V3::new(
                tmp[3 * i] as f32,
                tmp[3 * i + 1] as f32,
                tmp[3 * i + 2] as f32,
            );
        }
    }
}
