//! The order-independent answer of one pass: every pair's correction is computed on the state
//! the pass starts from, and each vertex moves by the mean of the moves its pairs ask of it,
//! weighted by their lengths (Jacobi with averaging).
//!
//! Answered one after another (Gauss-Seidel), each pair would see its predecessors'
//! corrections, so the outcome would follow the pair order: on the 2x crumple the stretch
//! differs widely between leaf, descending and ascending order, and each order fails a
//! different scene's bound (ascending: robot_pick_towel at 2x, from its repulsion pass alone).
//!
//! Why weighted by length: a vertex over a layer is pushed by its own pair and, a little, by the
//! pairs of the layer's vertices with the triangles around it (its barycentric share). Counted
//! alike (a plain mean), those small moves dilute its own: two springless sheets dropped on each
//! other rest well inside their contact distance. Weighted by length, the pairs that hold a
//! vertex decide; equal moves still give their mean (no overshoot when k pairs push one way), and
//! two opposite moves give their sum (a vertex squeezed between layers).

use super::impulses::{Impact, Impulses};
use super::stencil::Stencil;
use crate::Vec3;

/// Per vertex: the sum of its moves weighted by their lengths, and the sum of the lengths; only
/// touched vertices are reset, so a pass costs its pairs, not the cloth.
#[derive(Default)]
pub(super) struct Averaged {
    sum: Vec<Vec3>,
    weight: Vec<f64>,
    touched: Vec<u32>,
}

impl Averaged {
    /// Adds one pair's change `d` of its stencil (its minimal-energy moves); false when none
    /// of its vertices can move.
    pub fn add(&mut self, st: &Stencil, w: &[f64], d: Vec3) -> bool {
        let Some(moves) = st.moves(w, d) else {
            return false;
        };
        if self.sum.len() < w.len() {
            self.sum.resize(w.len(), Vec3::ZERO);
            self.weight.resize(w.len(), 0.0);
        }
        for (k, m) in moves.iter().enumerate().take(st.len) {
            let i = st.idx[k] as usize;
            let len = m.length();
            if w[i] <= 0.0 || len.is_nan() || len <= 0.0 {
                continue;
            }
            if self.weight[i] == 0.0 {
                self.touched.push(i as u32);
            }
            self.sum[i] += *m * len;
            self.weight[i] += len;
        }
        true
    }

    /// Moves every touched vertex of `x` by its weighted mean move and clears the sums.
    pub fn apply(&mut self, x: &mut [Vec3]) {
        for &i in &self.touched {
            let i = i as usize;
            x[i] += self.sum[i] / self.weight[i];
            self.sum[i] = Vec3::ZERO;
            self.weight[i] = 0.0;
        }
        self.touched.clear();
    }
}

/// A vertex-triangle pair's answer with its pair, the key the passes merge answers by.
pub(super) type Keyed = ((u32, u32), Correction);

/// One pair's answer, computed on the pass's start state: its stencil, the change of its
/// positions' weighted sum, and the normal and friction coefficient its velocities are
/// answered with (`impulses`; a zero normal: none).
#[derive(Clone, Copy)]
pub(super) struct Correction {
    pub st: Stencil,
    pub dx: Vec3,
    pub n: Vec3,
    pub mu: f64,
    /// How far short of its target the pair is, as a fraction of its contact distance.
    pub residual: f64,
    /// A vertex-triangle pair of two layers: the face normal towards the vertex and the
    /// contact distance (see [`super::SelfTouch`]).
    pub layers: Option<(Vec3, f64)>,
}

/// Averaged position corrections of one pass, and its pairs' velocity answers for
/// `impulses` (which conserve momentum, where averaged moves do not).
#[derive(Default)]
pub(super) struct JacobiPass {
    dx: Averaged,
    impacts: Vec<Impact>,
    impulses: Impulses,
}

impl JacobiPass {
    pub fn add(&mut self, c: &Correction, w: &[f64]) {
        if self.dx.add(&c.st, w, c.dx) && c.n != Vec3::ZERO {
            self.impacts.push(Impact {
                st: c.st,
                n: c.n,
                mu: c.mu,
            });
        }
    }

    /// Moves positions by their averaged corrections and answers velocities by impulses
    /// distributed by the true inverse masses `w_true`; returns the pairs whose friction slid.
    pub fn apply(&mut self, x: &mut [Vec3], v: &mut [Vec3], w_true: &[f64]) -> usize {
        self.dx.apply(x);
        let sliding = self.impulses.apply(&self.impacts, w_true, v);
        self.impacts.clear();
        sliding
    }
}
