//! [`Multigrid`]: building the levels (aggregate, prolong, Galerkin product) down to the
//! coarsest, rebuilding them along kept aggregates, refreshing the finest level, and applying
//! one V-cycle as the preconditioner.

use super::aggregate::aggregate;
use super::csr::{Csr, Part};
use super::cycle::cycle;
use super::dense::Dense;
use super::error::MultigridError;
use super::prolong::{smoothed_prolongator, spectral_radius};
use super::smooth::{invert_block, invert_diagonal, Halves, Level};
use crate::linalg::{BlockCsr, Filter};
use crate::Vec3;

/// Stop coarsening at this many block rows; solve there with dense Cholesky.
const COARSEST_ROWS: usize = 64;
/// Larger coarsest levels (coarsening stalled) get symmetric Gauss-Seidel sweeps instead.
const DENSE_MAX_ROWS: usize = 400;
const MAX_LEVELS: usize = 12;

/// A smoothed-aggregation hierarchy; [`Multigrid::apply`] is one symmetric V-cycle.
#[derive(Debug, Clone)]
pub struct Multigrid {
    pub(super) levels: Vec<Level>,
    pub(super) dense: Option<Dense>,
    pub(super) tmp: Vec<f64>,
    /// How each level was coarsened, for [`Multigrid::rebuild`].
    pub(super) coarsening: Vec<Coarsening>,
    /// Scratch of [`Multigrid::refilter_finest`]: the rows it rewrote.
    rows: Vec<u32>,
    /// Storage of the build's products, written into again by the next rebuild: each level's
    /// `A P`, the halves of a product, the prolongator's column marker.
    products: Products,
}

/// What [`Multigrid::construct`] computes into besides the levels (see [`Multigrid::rebuild`]).
#[derive(Debug, Clone, Default)]
struct Products {
    ap: Vec<Csr>,
    parts: [Part; 2],
    marker: Vec<usize>,
}

/// The symbolic part of one coarsening: the aggregate of every row, the aggregate count and
/// the prolongator's damping `omega = 4 / (3 rho(D^-1 A))`.
#[derive(Debug, Clone)]
pub(super) struct Coarsening {
    pub(super) agg: Vec<u32>,
    pub(super) nc: usize,
    pub(super) omega: f32,
}

impl Multigrid {
    /// Builds the hierarchy for the (filtered, SPD) matrix `a`.
    pub fn build(a: Csr) -> Result<Multigrid, MultigridError> {
        Self::construct(a, None, Vec::new(), Products::default())
    }

    /// [`Multigrid::build`] computing into `old`'s storage (a hierarchy aged out: the new one
    /// is about as large).
    pub fn build_reusing(a: Csr, old: Multigrid) -> Result<Multigrid, MultigridError> {
        Self::construct(a, None, old.levels, old.products)
    }

    /// Rebuilds the hierarchy for `a` (same size) with the last build's aggregates and
    /// prolongator damping: new prolongator values and Galerkin products, but no aggregation
    /// and no spectral-radius estimate. For a cloth that rotates, the coarse levels follow its
    /// springs' new directions at a fraction of a full build's cost.
    pub fn rebuild(&mut self, a: Csr) -> Result<(), MultigridError> {
        if a.rows() != self.rows() {
            *self = Self::build(a)?;
            return Ok(());
        }
        // The old levels' storage is written into again (warm memory).
        let plan = std::mem::take(&mut self.coarsening);
        let old = std::mem::take(&mut self.levels);
        let products = std::mem::take(&mut self.products);
        *self = Self::construct(a, Some(plan), old, products)?;
        Ok(())
    }

    /// A full build (`plan` = `None`), or one along a given coarsening; the products are
    /// computed into the storage of `old` levels and `products` where given.
    fn construct(
        a: Csr,
        plan: Option<Vec<Coarsening>>,
        old: Vec<Level>,
        mut products: Products,
    ) -> Result<Multigrid, MultigridError> {
        if a.rows() == 0 {
            return Err(MultigridError::Empty);
        }
        // The old levels' prolongators and their transposes by depth, the rest of each old
        // level the storage of the new one at its depth.
        let mut old = old.into_iter();
        let mut old_p: Vec<(Csr, Csr)> = Vec::new();
        let mut next_old = |old_p: &mut Vec<(Csr, Csr)>| {
            let mut l = old.next().unwrap_or_default();
            old_p.push((std::mem::take(&mut l.p), std::mem::take(&mut l.pt)));
            l
        };
        let mut levels = vec![Level::reusing(a, 0, next_old(&mut old_p))?];
        let mut coarsening = Vec::new();
        let mut plan = plan.map(Vec::into_iter);
        while levels.len() < MAX_LEVELS {
            let depth = levels.len() - 1;
            let fine = &mut levels[depth];
            let n = fine.a.rows();
            let step = match plan.as_mut() {
                Some(p) => match p.next() {
                    Some(c) if c.agg.len() == n => c,
                    _ => break,
                },
                None => {
                    if n <= COARSEST_ROWS {
                        break;
                    }
                    let diag = fine.a.diagonal_blocks(depth)?;
                    let (agg, nc) = aggregate(&fine.a, &diag);
                    if nc as f64 > 0.85 * n as f64 || nc == 0 {
                        break; // coarsening stalled
                    }
                    let omega = 4.0 / (3.0 * spectral_radius(&fine.a, &fine.dinv));
                    Coarsening { agg, nc, omega }
                }
            };
            let nc = step.nc;
            let mut storage = next_old(&mut old_p);
            let (mut p, mut pt) = std::mem::take(&mut old_p[depth]);
            let mut coarse = std::mem::take(&mut storage.a);
            if products.ap.len() <= depth {
                products.ap.resize_with(depth + 1, Csr::default);
            }
            let ap = &mut products.ap[depth];
            let marker = &mut products.marker;
            smoothed_prolongator(
                &fine.a, &fine.dinv, &step.agg, nc, step.omega, &mut p, marker,
            );
            p.transpose_into(nc, &mut pt);
            fine.a.matmul_into(&p, nc, ap, &mut products.parts);
            pt.matmul_into(ap, nc, &mut coarse, &mut products.parts);
            fine.p = p;
            fine.pt = pt;
            coarsening.push(step);
            let level = levels.len();
            levels.push(Level::reusing(coarse, level, storage)?);
        }
        // A dense factor where coarsening reached its target, or stalled below a coarse level.
        // Not when it stalled at the finest level: there the matrix has no strong connections
        // (mass-dominated, a small step), so sweeps already solve it in an iteration or two,
        // and a factor of up to DENSE_MAX_ROWS blocks refactored at every rebuild would cost
        // many times the step (the study's 16x16 sheet at its smallest steps).
        let last = levels.last().map_or(0, |l| l.a.rows());
        let dense = if last <= COARSEST_ROWS || (levels.len() > 1 && last <= DENSE_MAX_ROWS) {
            Some(Dense::factor(&levels[levels.len() - 1].a)?)
        } else {
            None
        };
        Ok(Multigrid {
            levels,
            dense,
            tmp: Vec::new(),
            coarsening,
            rows: Vec::new(),
            products,
        })
    }

    /// Block rows of the finest level.
    pub fn rows(&self) -> usize {
        self.levels[0].dinv.len()
    }

    /// Whether the finest level smooths two halves in parallel.
    #[cfg(test)]
    pub fn has_parallel_halves(&self) -> bool {
        self.levels[0].halves.is_some()
    }

    /// Block rows per level, finest first.
    #[cfg(test)]
    pub fn level_sizes(&self) -> Vec<usize> {
        self.levels.iter().map(|l| l.a.rows()).collect()
    }

    /// Replaces the finest-level matrix by `a` (same size) without rebuilding the coarse levels:
    /// the smoother then sees the current matrix while the coarse correction is from the last
    /// build. Still a symmetric positive definite preconditioner.
    pub fn refresh_finest(&mut self, mut a: Csr) -> Result<(), MultigridError> {
        // The sweeps index `x` by column unchecked: same square size as the level it replaces.
        assert!(
            a.ncols == a.rows() && a.rows() == self.rows(),
            "finest matrix is not square or has another size"
        );
        a.sort_rows();
        let l0 = &mut self.levels[0];
        a.diagonal_slots_into(0, &mut l0.diag)?;
        invert_diagonal(&a, &l0.diag, 0, &mut l0.dinv)?;
        l0.halves = Halves::refit(l0.halves.take(), &a);
        l0.a = a;
        Ok(())
    }

    /// The finest level refiltered from `a` in the rows that changed since its last filtering
    /// (see [`Csr::refiltered`]), the coarse levels as they were: what
    /// [`Multigrid::refresh_finest`] gives, for a fraction of the full pass. `Ok(false)` when it
    /// cannot (the caller refreshes in full).
    pub fn refilter_finest(
        &mut self,
        a: &BlockCsr,
        filter: &[Filter],
        edited: &[u32],
    ) -> Result<bool, MultigridError> {
        let mut rows = std::mem::take(&mut self.rows);
        let l0 = &mut self.levels[0];
        let done = l0.a.refiltered(a, filter, edited, &mut rows);
        let result = match done {
            None => Ok(false),
            Some(moved) => {
                if moved {
                    // Rows moved in the arrays: the diagonal's slots and the halves' cuts anew.
                    l0.a.diagonal_slots_into(0, &mut l0.diag)?;
                    if let Some(h) = l0.halves.as_mut() {
                        h.find_split(&l0.a);
                    }
                }
                rows.iter()
                    .map(|&r| r as usize)
                    .try_for_each(|r| {
                        l0.dinv[r] = invert_block(l0.a.vals[l0.diag[r]])
                            .ok_or(MultigridError::SingularDiagonal { level: 0, row: r })?;
                        Ok(())
                    })
                    .map(|()| true)
            }
        };
        self.rows = rows;
        result
    }

    /// Floating-point operations and least bytes streamed by one [`Multigrid::apply`] (see
    /// [`super::cycle`]): per level above the coarsest, the forward sweep from zero and the
    /// residual after it read the level's blocks once together, the backward sweep reads them
    /// again, restriction and prolongation read `P^T` and `P`; blocks are `Mat3A` (48 bytes)
    /// with a `u32` column, vectors `Vec3A` (16 bytes); the coarsest level's dense factor is
    /// read twice (forward and back substitution over its lower triangle).
    pub fn apply_cost(&self) -> (f64, f64) {
        const BLOCK: f64 = 48.0 + 4.0;
        const VEC: f64 = 16.0;
        let (mut flops, mut bytes) = (0.0, 0.0);
        let n0 = self.rows() as f64;
        // In and out of single precision: read r (f64) and write b, read x and write z.
        bytes += n0 * (24.0 + VEC) * 2.0;
        for (k, l) in self.levels.iter().enumerate() {
            let n = l.a.rows() as f64;
            let a = l.a.cols.len() as f64;
            if k + 1 == self.levels.len() {
                match self.dense.as_ref() {
                    Some(d) => {
                        let m = d.n as f64;
                        flops += 2.0 * m * m;
                        bytes += m * m * 8.0 + 2.0 * n * VEC;
                    }
                    None => {
                        // COARSE_SWEEPS symmetric sweeps over the level.
                        flops += 16.0 * (18.0 * a + 18.0 * n);
                        bytes += 16.0 * (a * BLOCK + n * (48.0 + 3.0 * VEC));
                    }
                }
                break;
            }
            let p = l.p.cols.len() as f64;
            // Sweeps: two passes over the blocks (forward + residual, backward), dinv twice.
            flops += 2.0 * 18.0 * a + 2.0 * 18.0 * n;
            bytes += 2.0 * a * BLOCK + 2.0 * (l.a.row_start.len() as f64) * 8.0;
            bytes += 2.0 * n * 48.0 + n * VEC * 8.0;
            // Restriction and prolongation.
            flops += 2.0 * 18.0 * p;
            bytes += 2.0 * p * BLOCK + n * VEC * 2.0;
        }
        (flops, bytes)
    }

    /// Finest-level matrix (for reuse of its storage).
    pub fn take_finest(&mut self) -> Csr {
        std::mem::take(&mut self.levels[0].a)
    }

    /// `z = M^-1 r`, one V(1,1)-cycle (in single precision: only the preconditioner's
    /// accuracy depends on it, never the residual PCG checks, which stays in double).
    pub fn apply(&mut self, r: &[Vec3], z: &mut [Vec3]) {
        for (b, r) in self.levels[0].b.iter_mut().zip(r) {
            *b = r.as_vec3a();
        }
        cycle(&mut self.levels, self.dense.as_ref(), &mut self.tmp);
        for (z, x) in z.iter_mut().zip(&self.levels[0].x) {
            *z = x.as_dvec3();
        }
    }
}

#[cfg(test)]
mod tests;
