//! Implicit backward Euler after Baraff and Witkin (1998): one linearised solve per step,
//!
//! `(M - h df/dv - h^2 df/dx) dv = h (f0 + h df/dx v0)`,   `v1 = v0 + dv`,   `x1 = x0 + h v1`,
//!
//! with the modified preconditioned conjugate gradient that keeps every iterate inside the
//! constraint set: the filter `S_i = I - p p^T` removes constrained directions and the constrained
//! components of `dv` are fixed to `z` (the velocity change that meets the target).
//!
//! When that one solve creates energy (stiff springs rotating: see [`EnergyCheck`]), Newton
//! iterations on the nonlinear system `M dv = h f(x0 + h v1, v1)` follow until it no longer does;
//! ordinary cloth steps pass the check after the single solve and cost one extra force pass.
//!
//! The preconditioner is smoothed-aggregation multigrid on the filtered operator (see
//! [`super::precond`]); its hierarchy gets new values along the same aggregates when the
//! iteration count drifts up, a full rebuild when that no longer helps, and block Jacobi takes
//! over whenever the hierarchy cannot be built. The solve starts from the combination of the
//! last two steps' velocity changes that is best in the energy norm.

use super::contact::ContactSpring;
use super::dynamics::Dynamics;
use super::friction::{self, Drag};
use super::integrator::{Capabilities, Integrator, StepReport};
use super::precond::{Csr, Multigrid};
use crate::effects::{EffectSet, State};
use crate::linalg::{scratch, Filter};
use crate::linalg::{BlockCsr, PatternBuilder};
use crate::{Mat3, Vec3};
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImplicitSettings {
    /// Relative residual at which conjugate gradients stop.
    pub cg_tolerance: f64,
    pub cg_max_iterations: u32,
}

impl Default for ImplicitSettings {
    fn default() -> Self {
        Self {
            cg_tolerance: 1e-5,
            cg_max_iterations: 200,
        }
    }
}

/// Which `M^-1` the conjugate gradient uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preconditioner {
    BlockJacobi,
    /// Smoothed-aggregation multigrid, falling back to block Jacobi when its setup fails.
    Multigrid,
}

/// Rebuild the hierarchy at least this often (steps); sooner when the iteration count exceeds
/// the one right after the last full build by a quarter (plus two).
const REBUILD_EVERY: u32 = 50;
/// Cost of a rebuild along the kept aggregates (new values only), in PCG iterations (measured
/// about two at 64x64). A swinging towel's coarse levels go stale within a few substeps
/// (measured 20, 23, 27, 31 iterations at ages 0 to 3); such a rebuild brings the count back.
const REFRESH_COST: u32 = 2;

/// Solves at most with friction drags refitted to the sliding speed (see [`super::friction`]).
const MAX_REFITS: u32 = 2;

/// Newton iterations at most beyond Baraff and Witkin's one linearised solve.
const MAX_NEWTON: u32 = 8;
/// Energy a step may create, relative to its kinetic energy (start plus end), before Newton
/// iterations are added: well above what the linearisation error of an ordinary cloth step
/// creates, far below a stiff spring's rotation gain (see [`EnergyCheck`]).
const CREATED_ENERGY: f64 = 1e-2;
/// Relative round-off of the energy sums (the gravity potential can dwarf the changes).
const ROUND_OFF: f64 = 1e-12;

/// The energy a backward-Euler iterate `v1 = v0 + dv`, `x1 = x0 + h v1` creates.
///
/// With `g = M dv - h f(x1, v1)` the residual of the nonlinear system, the kinetic energy obeys
/// `KE1 - KE0 = v1 . M dv - |dv|^2_M / 2` exactly, so
///
/// `E1 - E0 = [U1 - U0 - (x1 - x0) . grad U(x1)] + h v1 . f_other + v1 . (I - S) g + v1 . S g - |dv|^2_M / 2`
///
/// (`f_other` the damping and wind forces, `(I - S) g` the constraint reaction). The bracket is
/// `<= 0` for convex `U`; so a converged step (`S g = 0`) dissipates, and
/// `created = E1 - E0 - h v1 . f_other - v1 . (I - S) g` is the energy the step makes up.
///
/// One linearised solve leaves `S g` large when stiff springs rotate: the linearisation has no
/// transverse stiffness at rest length, so moving along the tangent stretches the spring to
/// second order (`dL ~ |dx|^2 / 2L`) and `k dL^2 / 2` appears from nothing (a 1e6 N/m cloth
/// gains joules per step). Newton iterations remove it.
#[derive(Debug, Clone, Copy)]
struct EnergyCheck {
    created: f64,
    allowed: f64,
    /// Potential energy at the iterate's end positions.
    u1: f64,
}

impl EnergyCheck {
    fn accepted(&self) -> bool {
        self.created <= self.allowed
    }
}

/// Potential energy of the conservative effects at `x`.
fn potential(d: &Dynamics, x: &[Vec3]) -> f64 {
    d.effects.energy(x)
}

/// The state-independent parts of `df/dx` and `df/dv`, assembled once in `prepare`.
struct Constant {
    dfdx: BlockCsr,
    dfdv: BlockCsr,
}

/// The multigrid state kept across steps.
struct Hierarchy {
    mg: Multigrid,
    /// Solves since the last build (full or along the kept aggregates).
    steps: u32,
    /// Solves since the last full build.
    age: u32,
    /// Iterations of the first solve after the last build, and after the last full build.
    iterations_at_build: u32,
    iterations_at_full: u32,
    /// Iterations beyond `iterations_at_build` summed over the solves since the last build.
    excess: u32,
    /// Rebuild along the kept aggregates before the next solve.
    rebuild: bool,
}

/// What one conjugate-gradient solve did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SolveStats {
    pub iterations: u32,
    /// `|S (b - A dv)| / |S b|` at exit.
    pub residual: f64,
}

/// Scratch vectors of the modified PCG.
#[derive(Default)]
pub(crate) struct Pcg {
    pinv: Vec<Mat3>,
    r: Vec<Vec3>,
    c: Vec<Vec3>,
    q: Vec<Vec3>,
    s: Vec<Vec3>,
    /// The second start direction and its product.
    h: Vec<Vec3>,
    ah: Vec<Vec3>,
}

impl Pcg {
    /// Solves `S A S dv = S b` with `(I - S) dv = z` by the modified PCG (Baraff-Witkin, section
    /// 5.3). `dv` holds the initial guess (its free components are used), `mg` the preconditioner
    /// (block Jacobi when `None`). Stops at `|S r| <= tol |S b|`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn solve(
        &mut self,
        a: &BlockCsr,
        filt: &[Filter],
        b: &[Vec3],
        z: &[Vec3],
        mut mg: Option<&mut Multigrid>,
        tol: f64,
        max_iterations: u32,
        dv: &mut [Vec3],
        second: Option<&[Vec3]>,
    ) -> SolveStats {
        let n = b.len();
        for buf in [&mut self.r, &mut self.c, &mut self.q, &mut self.s] {
            scratch(buf, n);
        }
        self.pinv.resize(n, Mat3::IDENTITY);
        let (mut guess, mut target) = (false, false);
        for i in 0..n {
            let di = a.diagonal(i);
            let inv = di.inverse();
            self.pinv[i] = if di.determinant().abs() > 0.0 && inv.is_finite() {
                inv
            } else {
                Mat3::IDENTITY
            };
            // The free part of the guess in `c`, the constrained part (`z`) in `dv`.
            self.c[i] = filt[i].apply(dv[i]);
            dv[i] = z[i];
            guess |= self.c[i] != Vec3::ZERO;
            target |= z[i] != Vec3::ZERO;
        }
        // r = S (b - A z): the residual of the start without the guess.
        if target {
            a.mul(dv, &mut self.q);
        } else {
            self.q.fill(Vec3::ZERO);
        }
        let mut bnorm2 = 0.0;
        for i in 0..n {
            let sb = filt[i].apply(b[i]);
            self.r[i] = sb - filt[i].apply(self.q[i]);
            bnorm2 += sb.length_squared();
        }
        // The guess enters as the combination of its directions (`g`, and `h` when given) that
        // minimises the error's energy norm over their span (a Galerkin step on `S A S`): never
        // worse than starting from zero, exact when the solution lies in the span.
        if guess {
            a.mul(&self.c, &mut self.q);
            let (mut gr, mut gag) = (0.0, 0.0);
            for i in 0..n {
                self.q[i] = filt[i].apply(self.q[i]);
                gr += self.c[i].dot(self.r[i]);
                gag += self.c[i].dot(self.q[i]);
            }
            let mut two = None;
            if let Some(second) = second.filter(|h| h.len() == n) {
                scratch(&mut self.h, n);
                scratch(&mut self.ah, n);
                for i in 0..n {
                    self.h[i] = filt[i].apply(second[i]);
                }
                a.mul(&self.h, &mut self.ah);
                let (mut hr, mut hah, mut gah) = (0.0, 0.0, 0.0);
                for i in 0..n {
                    self.ah[i] = filt[i].apply(self.ah[i]);
                    hr += self.h[i].dot(self.r[i]);
                    hah += self.h[i].dot(self.ah[i]);
                    gah += self.c[i].dot(self.ah[i]);
                }
                // 2x2 Gram system; skipped when `h` is (nearly) parallel to `g`.
                let det = gag * hah - gah * gah;
                if det > 1e-8 * gag * hah {
                    let (ag, ah) = ((gr * hah - hr * gah) / det, (hr * gag - gr * gah) / det);
                    if ag.is_finite() && ah.is_finite() {
                        two = Some((ag, ah));
                    }
                }
            }
            // With one direction, `h` is `g` with coefficient zero.
            let (ag, ah, h, ahv) = match two {
                Some((ag, ah)) => (ag, ah, &self.h, &self.ah),
                None if gag > 0.0 && (gr / gag).is_finite() => (gr / gag, 0.0, &self.c, &self.q),
                None => (0.0, 0.0, &self.c, &self.q),
            };
            // Taken only when it also lowers the residual PCG stops on: the energy-norm optimum
            // can leave a larger residual than the zero start (at loose tolerances, e.g. the
            // node's real-time preview at 1e-2, that costs iterations).
            let (mut before, mut after) = (0.0, 0.0);
            for i in 0..n {
                before += self.r[i].length_squared();
                after += (self.r[i] - self.q[i] * ag - ahv[i] * ah).length_squared();
            }
            if (ag != 0.0 || ah != 0.0) && after < before {
                for i in 0..n {
                    dv[i] += self.c[i] * ag + h[i] * ah;
                    self.r[i] -= self.q[i] * ag + ahv[i] * ah;
                }
            }
        }
        let rnorm2: f64 = self.r.iter().map(|r| r.length_squared()).sum();
        let mut rnorm2 = rnorm2;
        let bnorm2 = bnorm2.max(f64::MIN_POSITIVE);
        let tol2 = tol * tol;
        let precondition =
            |pinv: &[Mat3], mg: &mut Option<&mut Multigrid>, r: &[Vec3], out: &mut [Vec3]| {
                match mg {
                    Some(mg) => mg.apply(r, out),
                    None => out
                        .iter_mut()
                        .zip(r)
                        .zip(pinv)
                        .for_each(|((o, r), p)| *o = *p * *r),
                }
                out.iter_mut().zip(filt).for_each(|(o, f)| *o = f.apply(*o));
            };
        precondition(&self.pinv, &mut mg, &self.r, &mut self.c);
        let mut delta = dot(&self.r, &self.c);
        let mut iterations = 0;
        while rnorm2 > tol2 * bnorm2 && iterations < max_iterations {
            a.mul(&self.c, &mut self.q);
            let mut cq = 0.0;
            for ((q, c), f) in self.q.iter_mut().zip(&self.c).zip(filt) {
                *q = f.apply(*q);
                cq += c.dot(*q);
            }
            if cq <= 0.0 || !cq.is_finite() || delta <= 0.0 || !delta.is_finite() {
                // Not positive definite along c (only possible with degenerate input): stop with
                // the best iterate so far rather than divide by zero.
                break;
            }
            let alpha = delta / cq;
            rnorm2 = 0.0;
            for (((x, r), c), q) in dv.iter_mut().zip(&mut self.r).zip(&self.c).zip(&self.q) {
                *x += *c * alpha;
                *r -= *q * alpha;
                rnorm2 += r.length_squared();
            }
            iterations += 1;
            if rnorm2 <= tol2 * bnorm2 {
                break;
            }
            precondition(&self.pinv, &mut mg, &self.r, &mut self.s);
            let delta_old = delta;
            delta = dot(&self.r, &self.s);
            let beta = delta / delta_old;
            for (c, s) in self.c.iter_mut().zip(&self.s) {
                *c = *s + *c * beta;
            }
        }
        SolveStats {
            iterations,
            residual: (rnorm2 / bnorm2).sqrt(),
        }
    }
}

pub struct Implicit {
    settings: ImplicitSettings,
    preconditioner: Preconditioner,
    /// df/dx, then reused in place as the system matrix A.
    a: Option<BlockCsr>,
    dfdv: Option<BlockCsr>,
    constant: Option<Constant>,
    hierarchy: Option<Hierarchy>,
    /// Storage for the filtered fine matrix handed to the multigrid.
    filtered: Csr,
    pcg: Pcg,
    /// Friction drags of the current step's held vertices.
    drags: Vec<Drag>,
    /// Per edge spring of the step's constraints: whether it acts in the current system.
    spring_active: Vec<bool>,
    /// Friction of acting edge springs' contact points: (spring index, drag).
    edge_drags: Vec<(usize, Drag)>,
    /// The current step's filter and the held vertices it released (see `settle_holds`).
    filter: Vec<Filter>,
    released: Vec<(usize, Vec3)>,
    /// Constraint impulses of the current step (see [`StepReport::constraint_impulses`]): the
    /// report's buffer, swapped in for the step and back out at its end.
    impulses: Vec<Vec3>,
    f0: Vec<Vec3>,
    b: Vec<Vec3>,
    dv: Vec<Vec3>,
    z: Vec<Vec3>,
    /// End state `x0 + h v1`, `v1 = v0 + dv` of the current Newton iterate.
    xk: Vec<Vec3>,
    vk: Vec<Vec3>,
    delta: Vec<Vec3>,
    /// Potential energy at the end positions of the last step (still in `xk`).
    end_potential: Option<f64>,
    /// The least energy-creating Newton iterate so far.
    best: Vec<Vec3>,
    /// The velocity change of the step before the last (a start direction of the solve), and
    /// the copy of the last one taken before it is overwritten.
    older: Vec<Vec3>,
    last: Vec<Vec3>,
}

impl Implicit {
    pub fn new(settings: ImplicitSettings) -> Self {
        Self::with_preconditioner(settings, Preconditioner::Multigrid)
    }

    pub fn with_preconditioner(settings: ImplicitSettings, preconditioner: Preconditioner) -> Self {
        Self {
            settings,
            preconditioner,
            a: None,
            dfdv: None,
            constant: None,
            hierarchy: None,
            filtered: Csr::default(),
            pcg: Pcg::default(),
            drags: Vec::new(),
            spring_active: Vec::new(),
            edge_drags: Vec::new(),
            filter: Vec::new(),
            released: Vec::new(),
            impulses: Vec::new(),
            f0: Vec::new(),
            b: Vec::new(),
            dv: Vec::new(),
            z: Vec::new(),
            xk: Vec::new(),
            vk: Vec::new(),
            delta: Vec::new(),
            end_potential: None,
            best: Vec::new(),
            older: Vec::new(),
            last: Vec::new(),
        }
    }

    /// Assembles `A = M - h df/dv - h^2 df/dx` at `s` (Jacobians only).
    fn assemble_matrix(&mut self, d: &Dynamics, s: &State, h: f64) {
        let (Some(a), Some(dfdv), Some(k)) =
            (self.a.as_mut(), self.dfdv.as_mut(), self.constant.as_ref())
        else {
            unreachable!("prepared before assembling");
        };
        a.assign(&k.dfdx);
        dfdv.assign(&k.dfdv);
        d.effects.add_varying_jacobians(s, a, dfdv);
        a.axpby(-h * h, -h, dfdv);
        a.add_diagonal(d.mass);
        friction::add_to_matrix(a, &self.drags, h);
        let n = s.x.len();
        for c in &d.constraints.contacts {
            if c.is_valid(n) && c.depth(s.x) > 0.0 {
                c.add_jacobian(a, h * h);
            }
        }
        for (k, g) in &self.edge_drags {
            d.constraints.contacts[*k].add_point_block(a, g.damping(), h);
        }
    }

    /// Baraff-Witkin's first step at `s`: `f0`, `b = h (f0 + h df/dx v0)` and `A`.
    fn assemble(&mut self, d: &Dynamics, s: &State, h: f64) {
        let n = s.x.len();
        let (Some(a), Some(dfdv), Some(k)) =
            (self.a.as_mut(), self.dfdv.as_mut(), self.constant.as_ref())
        else {
            unreachable!("prepared before assembling");
        };
        d.effects.forces(s, &mut self.f0);
        a.assign(&k.dfdx);
        dfdv.assign(&k.dfdv);
        d.effects.add_varying_jacobians(s, a, dfdv);
        a.mul(s.v, &mut self.b);
        for i in 0..n {
            self.b[i] = (self.f0[i] + self.b[i] * h) * h;
        }
        a.axpby(-h * h, -h, dfdv);
        a.add_diagonal(d.mass);
        // Friction drags: linear in v, so `A += h c S` and `b += h f_drag(v0)` are exact.
        let filt = &d.constraints.filter;
        self.drags.clear();
        self.drags
            .extend(d.constraints.friction.iter().filter_map(|f| {
                let i = f.vertex as usize;
                (i < n)
                    .then(|| Drag::fit(f, &filt[i], s.v[i], h / d.mass[i]))
                    .flatten()
            }));
        friction::add_to_matrix(a, &self.drags, h);
        for g in &self.drags {
            self.b[g.vertex] += g.force(s.v[g.vertex]) * h;
        }
        // Edge springs the cloth is in or heading into.
        self.spring_active.clear();
        for c in &d.constraints.contacts {
            let active = c.is_valid(n) && (c.depth(s.x) > 0.0 || c.depth_after(s.x, s.v, h) > 0.0);
            if active {
                spring_terms(c, a, &mut self.b, s, h, 1.0);
            }
            self.spring_active.push(active);
        }
        // Their contact points' friction: a drag on the point's slip (as the vertex drags
        // above), shared by weight like the normal force.
        self.edge_drags.clear();
        for (k, c) in d.constraints.contacts.iter().enumerate() {
            if !self.spring_active[k] || c.friction <= 0.0 {
                continue;
            }
            let u = c.point_velocity(s.v);
            let Some(g) = Drag::at_point(c.friction, c.normal, u, h / c.point_mass(d.mass)) else {
                continue;
            };
            c.add_point_block(a, g.damping(), h);
            c.add_point_force(g.force(u), h, &mut self.b);
            self.edge_drags.push((k, g));
        }
    }

    /// [`Self::refit_drags`] for the edge springs' contact points.
    fn refit_edge_drags(&mut self, d: &Dynamics, v0: &[Vec3], h: f64) -> bool {
        let Some(a) = self.a.as_mut() else {
            return false;
        };
        let mut changed = false;
        for (k, g) in self.edge_drags.iter_mut() {
            let c = &d.constraints.contacts[*k];
            let u0 = c.point_velocity(v0);
            let Some(mode) = g.refit(u0 + c.point_velocity(&self.dv)) else {
                continue;
            };
            let (old_force, old_damping) = (g.force(u0), g.damping());
            g.mode = mode;
            c.add_point_block(a, g.damping() - old_damping, h);
            c.add_point_force(g.force(u0) - old_force, h, &mut self.b);
            changed = true;
        }
        changed
    }

    /// Adds (`sign` 1) or removes (-1) edge springs so that exactly those whose cloth point ends
    /// the solved step inside their layer act (see [`super::contact`]); returns whether any
    /// changed (the system then needs a new solve).
    fn refit_springs(&mut self, d: &Dynamics, s: &State, h: f64) -> bool {
        let Some(a) = self.a.as_mut() else {
            return false;
        };
        let n = s.x.len();
        let mut changed = false;
        for (c, active) in d
            .constraints
            .contacts
            .iter()
            .zip(self.spring_active.iter_mut())
        {
            if !c.is_valid(n) {
                continue;
            }
            let wanted = c.depth_after(s.x, s.v, h) - h * c.along(&self.dv) > 0.0;
            if wanted != *active {
                spring_terms(c, a, &mut self.b, s, h, if wanted { 1.0 } else { -1.0 });
                *active = wanted;
                changed = true;
            }
        }
        changed
    }

    /// Refits drags stronger than their Coulomb limit at the iterate `v0 + dv` (see
    /// [`super::friction`]); returns whether any changed (the system then needs a new solve).
    fn refit_drags(&mut self, v0: &[Vec3], h: f64) -> bool {
        let Some(a) = self.a.as_mut() else {
            return false;
        };
        let mut changed = false;
        for g in self.drags.iter_mut() {
            let i = g.vertex;
            let Some(mode) = g.refit(v0[i] + self.dv[i]) else {
                continue;
            };
            let (old_force, old_damping) = (g.force(v0[i]), g.damping());
            g.mode = mode;
            a.add(i as u32, i as u32, (g.damping() - old_damping) * h);
            self.b[i] += (g.force(v0[i]) - old_force) * h;
            changed = true;
        }
        changed
    }

    /// The constraint impulses of the linear system just solved, `(I - S)(A dv - b)` (zero for
    /// free vertices; none computed when no vertex is constrained).
    fn linear_impulses(&mut self, filt: &[Filter]) {
        let n = self.dv.len();
        self.impulses.clear();
        self.impulses.resize(n, Vec3::ZERO);
        if filt.iter().all(|f| *f == Filter::Free) {
            return;
        }
        let Some(a) = self.a.as_ref() else {
            return;
        };
        a.mul(&self.dv, &mut self.impulses);
        for i in 0..n {
            self.impulses[i] = filt[i].constrained(self.impulses[i] - self.b[i]);
        }
    }

    /// Releases the vertices held against one surface whose constraint impulse (just computed by
    /// `linear_impulses`) pulls them into it, and holds again released ones the solve then
    /// moves into it: the filter is bilateral, a contact can only push (an active set, like the
    /// springs'). The collision stage decides from the start-of-step forces which contacts to
    /// hold; a vertex next to an obstacle edge is lifted by the edge's spring within the solve,
    /// and held down it glued the lever a strip bent over the edge rests on. Returns whether
    /// any changed.
    fn settle_holds(&mut self, filt: &mut [Filter], d: &Dynamics, v0: &[Vec3]) -> bool {
        /// Adhesion below this velocity change (m/s) is round-off, not a pull.
        const TOL: f64 = 1e-5;
        let mut changed = false;
        for (i, n) in self.released.iter().copied() {
            let target = d.constraints.target_velocity[i];
            if (v0[i] + self.dv[i] - target).dot(n) < -TOL {
                filt[i] = Filter::Direction(n);
                self.z[i] = filt[i].constrained(target - v0[i]);
                changed = true;
            }
        }
        self.released.retain(|(i, _)| filt[*i] == Filter::Free);
        for (i, f) in filt.iter_mut().enumerate() {
            if let Filter::Direction(n) = *f {
                if self.impulses[i].dot(n) < -TOL * d.mass[i]
                    && !self.released.iter().any(|r| r.0 == i)
                {
                    *f = Filter::Free;
                    self.z[i] = Vec3::ZERO;
                    self.released.push((i, n));
                    changed = true;
                }
            }
        }
        changed
    }

    /// Solves `A dv = b` with the constrained part `z` (dv holds the start).
    /// `history`: `dv` holds the last step's velocity change and `older` the one before, both
    /// start directions (else `dv` alone).
    fn solve(&mut self, filt: &[Filter], history: bool) -> SolveStats {
        let (tol, max_it) = (self.settings.cg_tolerance, self.settings.cg_max_iterations);
        let use_mg = self.update_hierarchy(filt).is_some();
        let Some(a) = self.a.as_ref() else {
            unreachable!("prepared above");
        };
        let mgref = match self.hierarchy.as_mut() {
            Some(h) if use_mg => Some(&mut h.mg),
            _ => None,
        };
        let second = history.then_some(self.older.as_slice());
        let mut stats = self.pcg.solve(
            a,
            filt,
            &self.b,
            &self.z,
            mgref,
            tol,
            max_it,
            &mut self.dv,
            second,
        );
        if use_mg && (stats.residual.is_nan() || stats.residual > tol) && stats.iterations < max_it
        {
            // The multigrid-preconditioned iteration broke down early (degenerate input): retry
            // from scratch with block Jacobi and rebuild the hierarchy next step.
            log::debug!("multigrid PCG stopped early ({stats:?}); retrying with block Jacobi");
            self.hierarchy = None;
            self.dv.iter_mut().for_each(|x| *x = Vec3::ZERO);
            stats = self.pcg.solve(
                a,
                filt,
                &self.b,
                &self.z,
                None,
                tol,
                max_it,
                &mut self.dv,
                None,
            );
        }
        if let Some(h) = self.hierarchy.as_mut() {
            let its = stats.iterations;
            if h.steps == 0 {
                h.iterations_at_build = its;
                h.excess = 0;
                if h.age == 0 {
                    h.iterations_at_full = its;
                }
            } else if its > h.iterations_at_full + h.iterations_at_full / 4 + 2 {
                h.age = REBUILD_EVERY; // drifted despite the cheap rebuilds: full rebuild next
            } else {
                // The coarse levels go stale as the cloth turns: new values once the iterations
                // lost to staleness add up to what the rebuild costs (at most twice the best
                // rebuild schedule's cost, as in ski rental).
                h.excess += its.saturating_sub(h.iterations_at_build);
                h.rebuild = h.excess >= REFRESH_COST;
            }
        }
        stats
    }

    /// Energy bookkeeping of the iterate in `xk`, `vk` (see [`EnergyCheck`]); leaves the forces
    /// at the iterate's end state in `f0` and the right-hand side of the next Newton correction,
    /// `-g = h f(x1, v1) - M dv`, in `b`.
    fn energy_check(&mut self, d: &Dynamics, t1: f64, h: f64, v0: &[Vec3], u0: f64) -> EnergyCheck {
        let filt = &d.constraints.filter;
        let s = State {
            t: t1,
            x: &self.xk,
            v: &self.vk,
        };
        // Conservative (position-only) forces and their energy in one pass into `f0`; the rest
        // (damping, wind) into `b`.
        self.f0.fill(Vec3::ZERO);
        self.b.fill(Vec3::ZERO);
        let mut u1 = 0.0;
        for e in d.effects.iter() {
            if e.position_only() {
                u1 += e.add_forces_energy(&s, &mut self.f0);
            } else {
                e.add_forces(&s, &mut self.b);
            }
        }
        for g in &self.drags {
            self.b[g.vertex] += g.force(self.vk[g.vertex]);
        }
        // Edge springs count as outside work (their energy is not in the potential).
        for c in &d.constraints.contacts {
            if c.is_valid(self.xk.len()) {
                c.add_force(c.depth(&self.xk).max(0.0), 1.0, &mut self.b);
            }
        }
        for (k, g) in &self.edge_drags {
            let c = &d.constraints.contacts[*k];
            c.add_point_force(g.force(c.point_velocity(&self.vk)), 1.0, &mut self.b);
        }
        let (mut ke0, mut ke1, mut w_other, mut w_constraint) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..self.f0.len() {
            let (m, v1) = (d.mass[i], self.vk[i]);
            let g = self.dv[i] * m - (self.f0[i] + self.b[i]) * h;
            w_other += h * v1.dot(self.b[i]);
            w_constraint += v1.dot(filt[i].constrained(g));
            ke0 += 0.5 * m * v0[i].length_squared();
            ke1 += 0.5 * m * v1.length_squared();
            self.b[i] = -g;
        }
        EnergyCheck {
            u1,
            created: (ke1 + u1) - (ke0 + u0) - w_other - w_constraint,
            allowed: CREATED_ENERGY * (ke0 + ke1) + ROUND_OFF * (ke0 + ke1 + u0.abs() + u1.abs()),
        }
    }

    /// Gives the multigrid the current filtered matrix: a fresh hierarchy when none exists or the
    /// last one has aged (iterations drifting up or `REBUILD_EVERY` steps), else only the finest
    /// level. `None` means block Jacobi (multigrid disabled or its setup failed).
    fn update_hierarchy(&mut self, filt: &[Filter]) -> Option<&mut Multigrid> {
        if self.preconditioner != Preconditioner::Multigrid {
            return None;
        }
        let a = self.a.as_ref()?;
        let n = a.rows();
        let mut fine = match self.hierarchy.as_mut() {
            Some(h) => h.mg.take_finest(),
            None => std::mem::take(&mut self.filtered),
        };
        fine.filtered(a, filt);
        let reuse = self
            .hierarchy
            .as_ref()
            .is_some_and(|h| h.mg.rows() == n && h.age < REBUILD_EVERY);
        if reuse {
            if let Some(h) = self.hierarchy.as_mut() {
                let rebuild = h.rebuild;
                let done = if rebuild {
                    h.mg.rebuild(fine)
                } else {
                    h.mg.refresh_finest(fine)
                };
                match done {
                    Ok(()) => {
                        h.age += 1;
                        h.steps = if rebuild { 0 } else { h.steps + 1 };
                        h.rebuild = false;
                        return self.hierarchy.as_mut().map(|h| &mut h.mg);
                    }
                    Err(e) => {
                        log::debug!("multigrid refresh failed ({e}); rebuilding");
                        self.hierarchy = None;
                        return None;
                    }
                }
            }
        }
        match Multigrid::build(fine) {
            Ok(mg) => {
                self.hierarchy = Some(Hierarchy {
                    mg,
                    steps: 0,
                    age: 0,
                    iterations_at_build: 0,
                    iterations_at_full: 0,
                    excess: 0,
                    rebuild: false,
                });
                self.hierarchy.as_mut().map(|h| &mut h.mg)
            }
            Err(e) => {
                log::debug!("multigrid setup failed ({e}); using block Jacobi");
                self.hierarchy = None;
                None
            }
        }
    }
}

/// Backward Euler's terms of edge spring `c` linearised at the start state `s`, times `sign`:
/// `A += h^2 k J` and `b += h (f(x0) + h df/dx v0)` (see [`super::contact`]).
fn spring_terms(c: &ContactSpring, a: &mut BlockCsr, b: &mut [Vec3], s: &State, h: f64, sign: f64) {
    c.add_jacobian(a, sign * h * h);
    c.add_force(c.depth(s.x), sign * h, b);
    c.add_jacobian_product(a, s.v, -sign * h * h, b);
}

fn dot(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(*y)).sum()
}

impl Integrator for Implicit {
    fn name(&self) -> &'static str {
        "implicit"
    }

    fn capabilities(&self) -> Capabilities {
        Capabilities {
            stability_limit: None,
            solves_friction: true,
            solves_contacts: true,
        }
    }

    fn prepare(&mut self, effects: &EffectSet, n: usize) {
        let mut p = PatternBuilder::new();
        effects.declare(&mut p);
        let m = p.build(n);
        let (mut dfdx, mut dfdv) = (m.clone(), m.clone());
        effects.constant_jacobians(&mut dfdx, &mut dfdv);
        self.constant = Some(Constant { dfdx, dfdv });
        self.dfdv = Some(m.clone());
        self.a = Some(m);
        self.hierarchy = None;
        self.end_potential = None;
        self.older.clear();
    }

    /// Runs the step on a thread of rayon's pool: its parallel products and sweeps then fork
    /// and join from inside the pool, where a join costs a deque push, instead of from the
    /// caller's thread, where each join is a cross-thread wake-up (4-35 us on the 2-core test
    /// machine, dozens per step; ~20 % of a 64x64 step was the scheduler's).
    fn step(
        &mut self,
        d: &Dynamics,
        t: f64,
        h: f64,
        x: &mut [Vec3],
        v: &mut [Vec3],
        report: &mut StepReport,
    ) {
        std::mem::swap(&mut self.impulses, &mut report.constraint_impulses);
        rayon::scope(|_| self.step_in_pool(d, t, h, x, v, report));
        std::mem::swap(&mut self.impulses, &mut report.constraint_impulses);
    }
}

impl Implicit {
    fn step_in_pool(
        &mut self,
        d: &Dynamics,
        t: f64,
        h: f64,
        x: &mut [Vec3],
        v: &mut [Vec3],
        report: &mut StepReport,
    ) {
        let n = x.len();
        if self.a.as_ref().is_none_or(|a| a.rows() != n) {
            self.prepare(d.effects, n);
        }
        for buf in [
            &mut self.f0,
            &mut self.b,
            &mut self.dv,
            &mut self.z,
            &mut self.xk,
            &mut self.vk,
        ] {
            scratch(buf, n);
        }
        // The step's own copy of the filter: contacts whose constraint would pull the vertex
        // into the surface are released during the step.
        let mut filter = std::mem::take(&mut self.filter);
        filter.clone_from(&d.constraints.filter);
        self.released.clear();
        let filt = &mut filter;
        self.assemble(d, &State { t, x, v }, h);
        // Constrained components of dv are fixed: z = (I - S)(v_target - v).
        for i in 0..n {
            self.z[i] = filt[i].constrained(d.constraints.target_velocity[i] - v[i]);
        }
        // The start directions: the last two steps' velocity changes.
        self.last.clone_from(&self.dv);
        let mut stats = self.solve(filt, true);
        std::mem::swap(&mut self.older, &mut self.last);
        let mut cg_iterations = stats.iterations;
        // Contact holds to settle (their impulses cost a product with the matrix).
        let holds = filt.iter().any(|f| matches!(f, Filter::Direction(_)));
        let mut impulses_current = false;
        for _ in 0..MAX_REFITS {
            let drags = self.refit_drags(v, h);
            let springs = self.refit_springs(d, &State { t, x, v }, h);
            let edge_drags = self.refit_edge_drags(d, v, h);
            let mut released = false;
            if holds {
                self.linear_impulses(filt);
                impulses_current = true;
                released = self.settle_holds(filt, d, v);
            }
            if !(drags || springs || edge_drags || released) {
                break;
            }
            stats = self.solve(filt, false);
            cg_iterations += stats.iterations;
            impulses_current = false;
        }
        if !impulses_current {
            self.linear_impulses(filt);
        }

        // Newton iterations on the nonlinear backward-Euler system, only while the step creates
        // energy (see `EnergyCheck`).
        // The potential at `x` is known when `x` is exactly where the last step ended (nothing
        // moved it since: no collision response, no kinematic reset off it).
        let u0 = match self.end_potential {
            Some(u) if self.xk.as_slice() == &x[..] => u,
            _ => potential(d, x),
        };
        self.end_potential = None;
        let mut newton = 0;
        let mut best: Option<f64> = None;
        loop {
            for i in 0..n {
                self.vk[i] = v[i] + self.dv[i];
                self.xk[i] = x[i] + self.vk[i] * h;
            }
            let check = self.energy_check(d, t + h, h, v, u0);
            // A non-finite iterate is the divergence guard's case, not Newton's.
            if check.accepted() || !check.created.is_finite() {
                self.end_potential = check.accepted().then_some(check.u1);
                break;
            }
            // Keep the iterate that created the least energy in case none is accepted.
            if best.is_none_or(|b| check.created < b) {
                best = Some(check.created);
                self.best.clone_from(&self.dv);
            }
            if newton == MAX_NEWTON {
                log::debug!(
                    "implicit step still creates energy after {newton} Newton iterations \
                     ({check:?}); keeping the best iterate"
                );
                std::mem::swap(&mut self.dv, &mut self.best);
                break;
            }
            newton += 1;
            let (xk, vk) = (std::mem::take(&mut self.xk), std::mem::take(&mut self.vk));
            self.assemble_matrix(
                d,
                &State {
                    t: t + h,
                    x: &xk,
                    v: &vk,
                },
                h,
            );
            (self.xk, self.vk) = (xk, vk);
            // Solve for the correction: `b` holds `-g`, and the constrained part is met already.
            // `dv` moves to `delta` while the correction is solved for in `dv` (from zero).
            std::mem::swap(&mut self.dv, &mut self.delta);
            scratch(&mut self.dv, n);
            self.dv.fill(Vec3::ZERO);
            self.z.fill(Vec3::ZERO);
            stats = self.solve(filt, false);
            cg_iterations += stats.iterations;
            for (total, c) in self.delta.iter_mut().zip(&self.dv) {
                *total += *c;
            }
            std::mem::swap(&mut self.dv, &mut self.delta);
        }

        if newton > 0 {
            // Newton's last residual `g = M dv - h f(x1, v1)` (in `b` as `-g`): converged, its
            // constrained part is the reaction of the nonlinear system.
            for i in 0..n {
                self.impulses[i] = filt[i].constrained(-self.b[i]);
            }
        }
        for i in 0..n {
            v[i] += self.dv[i];
            x[i] += v[i] * h;
        }
        report.contact_forces.clear();
        report
            .contact_forces
            .extend(d.constraints.contacts.iter().map(|c| {
                if c.is_valid(n) {
                    c.force(x)
                } else {
                    0.0
                }
            }));
        self.filter = filter;
        report.force_evaluations = 2 + newton;
        report.cg_iterations = cg_iterations;
        report.cg_residual = stats.residual;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic xorshift numbers in [-1, 1).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
        fn vec3(&mut self) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next())
        }
    }

    /// `M + sum_ij k_ij (e_i - e_j)(e_i - e_j)^T (x) D_ij` with `D_ij` symmetric positive
    /// semidefinite, so `A` is SPD. `pairs` gives `(i, j, k, d)`: `D = d d^T + 0.02 I`.
    fn spring_system(n: usize, mass: f64, pairs: &[(u32, u32, f64, Vec3)]) -> BlockCsr {
        let mut p = PatternBuilder::new();
        for &(i, j, _, _) in pairs {
            p.couple(i, j);
        }
        let mut a = p.build(n);
        for &(i, j, k, d) in pairs {
            let blk = (Mat3::from_cols(d * d.x, d * d.y, d * d.z) + Mat3::IDENTITY * 0.02) * k;
            a.add(i, i, blk);
            a.add(j, j, blk);
            a.add(i, j, -blk);
            a.add(j, i, -blk);
        }
        a.add_diagonal(&vec![mass; n]);
        a
    }

    /// The hanging cloth's `M + h^2 K` at `res x res`: axial springs (`h^2 k` = 0.56, 1e4 times
    /// the vertex mass as at 64x64), shear at a tenth, bending-like distance-2 couplings.
    fn cloth_system(res: usize) -> BlockCsr {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let id = |i: usize, j: usize| (i * res + j) as u32;
        let mut pairs = Vec::new();
        for i in 0..res {
            for j in 0..res {
                for (di, dj, k) in [
                    (0, 1, 1.0),
                    (1, 0, 1.0),
                    (1, 1, 0.1),
                    (1, -1, 0.1),
                    (0, 2, 1e-3),
                    (2, 0, 1e-3),
                ] {
                    let (a, b) = (i as i64 + di, j as i64 + dj);
                    if a < res as i64 && b >= 0 && b < res as i64 {
                        let d =
                            (Vec3::new(di as f64, dj as f64, 0.0) + rng.vec3() * 0.1).normalize();
                        pairs.push((id(i, j), id(a as usize, b as usize), 0.56 * k, d));
                    }
                }
            }
        }
        spring_system(res * res, 5e-5, &pairs)
    }

    /// Random sparse SPD system: each vertex coupled to a few random others.
    fn random_system(n: usize, seed: u64) -> BlockCsr {
        let mut rng = Rng(seed);
        let mut pairs = Vec::new();
        for i in 0..n as u32 {
            for _ in 0..3 {
                let j = ((rng.next() * 0.5 + 0.5) * n as f64) as u32 % n as u32;
                if j != i {
                    let k = 10f64.powf(3.0 * rng.next());
                    pairs.push((i, j, k, rng.vec3().normalize()));
                }
            }
        }
        spring_system(n, 1e-3, &pairs)
    }

    /// Pinned vertices, contact-like `Direction` filters and free ones, with targets `z`.
    fn constraints(n: usize, rng: &mut Rng) -> (Vec<Filter>, Vec<Vec3>) {
        let filt: Vec<Filter> = (0..n)
            .map(|i| match i % 17 {
                0 if i < n / 4 => Filter::Fixed,
                3 | 11 => Filter::Direction(rng.vec3().normalize()),
                _ => Filter::Free,
            })
            .collect();
        let z = filt.iter().map(|f| f.constrained(rng.vec3())).collect();
        (filt, z)
    }

    fn solve(
        a: &BlockCsr,
        filt: &[Filter],
        b: &[Vec3],
        z: &[Vec3],
        mg: bool,
        tol: f64,
    ) -> (Vec<Vec3>, SolveStats) {
        let mut fine = Csr::default();
        fine.filtered(a, filt);
        let mut m = if mg {
            Some(Multigrid::build(fine).expect("hierarchy"))
        } else {
            None
        };
        let mut dv = vec![Vec3::ZERO; b.len()];
        let stats = Pcg::default().solve(a, filt, b, z, m.as_mut(), tol, 100_000, &mut dv, None);
        (dv, stats)
    }

    /// Multigrid-preconditioned and tight block-Jacobi solves agree, meet `(I - S) dv = z` and
    /// the residual bound. Both stop at `|r| <= 1e-12 |b|`, so each is within `kappa * 1e-12` of
    /// the exact solution (relative); with `kappa <~ 1e4` they agree to 2e-8 (measured: 3e-13).
    fn check_agreement(a: &BlockCsr, seed: u64) {
        let n = a.rows();
        let mut rng = Rng(seed);
        let (filt, z) = constraints(n, &mut rng);
        let b: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
        let (reference, rs) = solve(a, &filt, &b, &z, false, 1e-12);
        let (dv, ms) = solve(a, &filt, &b, &z, true, 1e-12);
        assert!(
            rs.residual <= 1e-12 && ms.residual <= 1e-12,
            "{rs:?} {ms:?}"
        );
        assert!(
            ms.iterations < rs.iterations,
            "multigrid {ms:?} vs jacobi {rs:?}"
        );
        let scale = reference.iter().map(|v| v.length()).fold(0.0, f64::max);
        for i in 0..n {
            assert!(
                (dv[i] - reference[i]).length() <= 2e-8 * scale,
                "vertex {i}: {} vs {}",
                dv[i],
                reference[i]
            );
            let c = filt[i].constrained(dv[i]) - z[i];
            assert!(
                c.length() <= 1e-14 * scale.max(1.0),
                "vertex {i} constrained part off by {c}"
            );
            assert!(dv[i].is_finite());
        }
        // The filtered residual really is small (not just the solver's bookkeeping).
        let mut q = vec![Vec3::ZERO; n];
        a.mul(&dv, &mut q);
        let r2: f64 = (0..n)
            .map(|i| filt[i].apply(b[i] - q[i]).length_squared())
            .sum();
        let b2: f64 = (0..n).map(|i| filt[i].apply(b[i]).length_squared()).sum();
        assert!(r2.sqrt() <= 1e-11 * b2.sqrt());
    }

    /// The start from the span of two directions: exact (no iteration) when the solution lies
    /// in it, while the first direction alone needs iterations; a useless second direction
    /// (parallel to the first, or not finite) falls back to the first alone.
    #[test]
    fn start_directions_span_the_solution() {
        let a = cloth_system(12);
        let n = a.rows();
        let mut rng = Rng(21);
        let (filt, z) = constraints(n, &mut rng);
        let b: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
        let (x, _) = solve(&a, &filt, &b, &z, false, 1e-13);
        let e: Vec<Vec3> = (0..n).map(|_| rng.vec3() * 0.1).collect();
        // x = (g - h) / 0.3 on the free components.
        let g: Vec<Vec3> = x.iter().zip(&e).map(|(x, e)| *x * 0.3 + *e).collect();
        let run = |second: Option<&[Vec3]>| {
            let mut dv = g.clone();
            let s = Pcg::default().solve(&a, &filt, &b, &z, None, 1e-9, 10_000, &mut dv, second);
            (dv, s)
        };
        let (dv, two) = run(Some(&e));
        assert_eq!(two.iterations, 0, "{two:?}");
        let scale = x.iter().map(|v| v.length()).fold(0.0, f64::max);
        for i in 0..n {
            assert!((dv[i] - x[i]).length() <= 1e-6 * scale, "vertex {i}");
        }
        let (_, one) = run(None);
        assert!(one.iterations > 5, "{one:?}");
        let parallel: Vec<Vec3> = g.iter().map(|v| *v * 2.0).collect();
        let mut bad = e.clone();
        bad[3] = Vec3::NAN;
        for second in [&parallel, &bad] {
            let (dv, s) = run(Some(second));
            assert_eq!(s.iterations, one.iterations, "{s:?} vs {one:?}");
            assert!(s.residual <= 1e-9 && dv.iter().all(|v| v.is_finite()));
        }
    }

    #[test]
    fn multigrid_matches_block_jacobi_on_random_spd_system() {
        check_agreement(&random_system(600, 7), 11);
    }

    #[test]
    fn multigrid_matches_block_jacobi_on_constrained_cloth() {
        check_agreement(&cloth_system(24), 5);
    }

    #[test]
    fn vcycle_is_symmetric_positive_definite() {
        let a = cloth_system(20);
        let n = a.rows();
        let mut rng = Rng(3);
        let (filt, _) = constraints(n, &mut rng);
        let mut fine = Csr::default();
        fine.filtered(&a, &filt);
        let mut mg = Multigrid::build(fine).expect("hierarchy");
        assert!(mg.level_sizes().len() >= 2, "{:?}", mg.level_sizes());
        for _ in 0..5 {
            let u: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
            let v: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
            let (mut mu, mut mv) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
            mg.apply(&u, &mut mu);
            mg.apply(&v, &mut mv);
            let (vmu, umv) = (dot(&v, &mu), dot(&u, &mv));
            // Symmetric in exact arithmetic; the hierarchy is single precision, so up to
            // ~100 f32 ulps (1.2e-5; measured 3e-7). A one-sided smoother is off by ~1e-1.
            assert!(
                (vmu - umv).abs() <= 1e-5 * vmu.abs().max(umv.abs()),
                "{vmu} vs {umv}"
            );
            assert!(dot(&u, &mu) > 0.0);
        }
    }

    /// Large levels smooth two halves in parallel; the V-cycle must stay symmetric positive
    /// definite (48 x 48 = 2304 rows, above the parallel-sweep threshold).
    #[test]
    fn vcycle_with_parallel_halves_is_symmetric_positive_definite() {
        let a = cloth_system(48);
        let n = a.rows();
        let mut rng = Rng(9);
        let (filt, _) = constraints(n, &mut rng);
        let mut fine = Csr::default();
        fine.filtered(&a, &filt);
        let mut mg = Multigrid::build(fine).expect("hierarchy");
        assert!(mg.has_parallel_halves());
        for _ in 0..3 {
            let u: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
            let v: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
            let (mut mu, mut mv) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
            mg.apply(&u, &mut mu);
            mg.apply(&v, &mut mv);
            let (vmu, umv) = (dot(&v, &mu), dot(&u, &mv));
            // Symmetric in exact arithmetic; the hierarchy is single precision, so up to
            // ~100 f32 ulps (1.2e-5; measured 3e-7). A one-sided smoother is off by ~1e-1.
            assert!(
                (vmu - umv).abs() <= 1e-5 * vmu.abs().max(umv.abs()),
                "{vmu} vs {umv}"
            );
            assert!(dot(&u, &mu) > 0.0);
        }
    }

    /// A rebuild along the kept aggregates reproduces a full build of the same matrix exactly
    /// (same aggregates and damping, so the same numbers); rebuilt for a rotated cloth
    /// (`R A R^T` blockwise) it preconditions as well as a fresh build (iterations within one),
    /// while the stale hierarchy of the unrotated cloth does not (measured: 19 and 20
    /// iterations, stale 167).
    #[test]
    fn rebuild_along_kept_aggregates_follows_a_rotation() {
        let a = cloth_system(32);
        let n = a.rows();
        let filt = vec![Filter::Free; n];
        let mut fine = Csr::default();
        fine.filtered(&a, &filt);
        let mut full = Multigrid::build(fine.clone()).expect("hierarchy");
        let mut kept = Multigrid::build(fine.clone()).expect("hierarchy");
        kept.rebuild(fine).expect("rebuild");
        let mut rng = Rng(17);
        let u: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
        let (mut zf, mut zk) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
        full.apply(&u, &mut zf);
        kept.apply(&u, &mut zk);
        assert_eq!(zf, zk);
        // Rotate every block by 60 degrees about x: the springs point elsewhere.
        let r = Mat3::from_rotation_x(std::f64::consts::FRAC_PI_3);
        let mut p = PatternBuilder::new();
        for i in 0..n {
            for &j in a.row(i).0 {
                p.couple(i as u32, j);
            }
        }
        let mut rotated = p.build(n);
        for i in 0..n {
            let (cols, vals) = a.row(i);
            for (&j, m) in cols.iter().zip(vals) {
                rotated.add(i as u32, j, r * *m * r.transpose());
            }
        }
        let mut fine = Csr::default();
        fine.filtered(&rotated, &filt);
        let b: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
        let z = vec![Vec3::ZERO; n];
        let iterations = |mg: &mut Multigrid| {
            let mut dv = vec![Vec3::ZERO; n];
            Pcg::default()
                .solve(&rotated, &filt, &b, &z, Some(mg), 1e-8, 1000, &mut dv, None)
                .iterations
        };
        let mut fresh = Multigrid::build(fine.clone()).expect("hierarchy");
        kept.refresh_finest(fine.clone()).expect("refresh");
        let stale_its = iterations(&mut kept);
        kept.rebuild(fine).expect("rebuild");
        let (kept_its, fresh_its) = (iterations(&mut kept), iterations(&mut fresh));
        assert!(kept_its <= fresh_its + 1, "{kept_its} vs fresh {fresh_its}");
        assert!(
            stale_its > fresh_its + 1,
            "stale {stale_its} vs fresh {fresh_its}"
        );
    }

    #[test]
    fn iterations_do_not_grow_with_resolution() {
        let mut its = Vec::new();
        for res in [16, 32, 64] {
            let a = cloth_system(res);
            let n = a.rows();
            let filt: Vec<Filter> = (0..n)
                .map(|i| {
                    if i == 0 || i == res - 1 {
                        Filter::Fixed
                    } else {
                        Filter::Free
                    }
                })
                .collect();
            let b = vec![Vec3::new(0.0, 0.0, -9.81 * 5e-5 / 60.0); n];
            let (_, s) = solve(&a, &filt, &b, &vec![Vec3::ZERO; n], true, 1e-5);
            its.push(s.iterations);
        }
        // Measured 12, 13, 13 (block Jacobi: 185, 359, 628, growing like res).
        assert!(its.iter().all(|&k| k <= 20), "{its:?}");
    }

    #[test]
    fn degenerate_matrix_falls_back_to_block_jacobi() {
        // A zero diagonal block (massless, unconnected vertex) makes the hierarchy fail...
        let mut a = cloth_system(6);
        let mut p = PatternBuilder::new();
        p.couple(0, 1);
        let mut bad = p.build(2);
        bad.add(0, 0, Mat3::IDENTITY);
        let mut fine = Csr::default();
        fine.filtered(&bad, &[Filter::Free, Filter::Free]);
        assert_eq!(
            Multigrid::build(fine).err(),
            Some(crate::integrate::precond::MultigridError::SingularDiagonal { level: 0, row: 1 })
        );
        // ...and the block-Jacobi solve of a healthy system stays finite and converges.
        a.add_diagonal(&[0.0; 36]);
        let b = vec![Vec3::X; 36];
        let (dv, s) = solve(&a, &[Filter::Free; 36], &b, &[Vec3::ZERO; 36], false, 1e-8);
        assert!(s.residual <= 1e-8 && dv.iter().all(|v| v.is_finite()));
    }

    /// A stiff spring swinging about a pinned end (issue 7's root cause in one spring): at rest
    /// length the linearisation has no transverse stiffness, so one Baraff-Witkin solve moves the
    /// free end along the tangent by `v h` and stretches the spring by
    /// `sqrt(l^2 + (v h)^2) - l` = 7 mm, i.e. `k e^2 / 2` = 26 J out of 25 uJ of kinetic energy.
    /// The Newton iterations must bring it back onto (about) the circle without creating energy.
    /// A vertex held on a surface (normal +z) by the filter, pulled off it or pressed into it by a
    /// spring to a fixed vertex above: the filter is bilateral, the contact is not. Pulled, the
    /// step releases it (it moves up, no impulse); pressed, it stays held with a pushing impulse.
    #[test]
    fn holds_are_released_only_when_they_would_pull() {
        use crate::cloth::topology::Spring;
        use crate::effects::Springs;
        use crate::integrate::Constraints;
        for (rest, pulled) in [(0.05, true), (0.2, false)] {
            let mut effects = EffectSet::new();
            effects.push(Box::new(Springs::new(
                "stretch",
                vec![Spring { i: 0, j: 1, rest }],
                vec![100.0],
                "k".into(),
            )));
            let mass = [1e-3, 1e-3];
            let mut constraints = Constraints::free(2);
            constraints.filter[0] = Filter::Fixed;
            constraints.filter[1] = Filter::Direction(Vec3::Z);
            let d = Dynamics {
                effects: &effects,
                mass: &mass,
                constraints: &constraints,
            };
            let mut x = [Vec3::new(0.0, 0.0, 0.1), Vec3::ZERO];
            let mut v = [Vec3::ZERO; 2];
            let mut solver = Implicit::new(ImplicitSettings::default());
            solver.prepare(&effects, 2);
            let mut report = StepReport::default();
            solver.step(&d, 0.0, 1.0 / 120.0, &mut x, &mut v, &mut report);
            let impulse = report.impulses().map_or(Vec3::ZERO, |r| r[1]);
            if pulled {
                assert!(v[1].z > 0.0, "pulled vertex stayed held: v {:?}", v[1]);
                assert_eq!(
                    impulse,
                    Vec3::ZERO,
                    "a released vertex has no constraint impulse"
                );
            } else {
                assert_eq!(v[1].z, 0.0, "pressed vertex left the surface: v {:?}", v[1]);
                assert!(impulse.z > 0.0, "the surface must push: {impulse:?}");
            }
        }
    }

    #[test]
    fn stiff_rotating_spring_creates_no_energy() {
        use crate::cloth::topology::Spring;
        use crate::effects::Springs;
        use crate::integrate::Constraints;
        let (l, k, m, speed, h) = (1.0 / 64.0, 1e6, 5e-5, 1.0, 1.0 / 60.0);
        let mut effects = EffectSet::new();
        effects.push(Box::new(Springs::new(
            "stretch",
            vec![Spring {
                i: 0,
                j: 1,
                rest: l,
            }],
            vec![k],
            "k".into(),
        )));
        let mass = [m, m];
        let mut constraints = Constraints::free(2);
        constraints.filter[0] = Filter::Fixed;
        let d = Dynamics {
            effects: &effects,
            mass: &mass,
            constraints: &constraints,
        };
        let mut x = [Vec3::ZERO, Vec3::new(l, 0.0, 0.0)];
        let mut v = [Vec3::ZERO, Vec3::new(0.0, speed, 0.0)];
        let energy = |x: &[Vec3], v: &[Vec3]| 0.5 * m * v[1].length_squared() + effects.energy(x);
        let e0 = energy(&x, &v);
        let mut solver = Implicit::new(ImplicitSettings {
            cg_tolerance: 1e-10,
            ..ImplicitSettings::default()
        });
        solver.prepare(&effects, 2);
        for step in 0..20 {
            let before = energy(&x, &v);
            let mut stats = StepReport::default();
            solver.step(&d, step as f64 * h, h, &mut x, &mut v, &mut stats);
            let after = energy(&x, &v);
            assert!(
                after.is_finite() && after <= before,
                "step {step}: {before} J -> {after} J ({stats:?})"
            );
            // Backward Euler keeps the stiff spring near its rest length: within the strain
            // whose energy is the kinetic energy, sqrt(2 E0 / k) / l.
            let strain = (x[1].length() - l).abs() / l;
            assert!(
                strain <= (2.0 * e0 / k).sqrt() / l,
                "step {step}: strain {strain}"
            );
            assert!(
                stats.force_evaluations > 2 || step > 0,
                "the first step must iterate"
            );
        }
    }
}
