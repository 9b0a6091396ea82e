//! [`Implicit`]: the solver's state kept across steps (matrices with their fixed pattern, the
//! multigrid hierarchy, the warm-start history, scratch vectors) and its [`Integrator`] face.
//! A step itself is `step.rs`.

use super::auto::AutoPath;
use super::factor::Direct;
use super::hierarchy::Hierarchy;
use super::settings::{ImplicitSettings, LinearPath, LinearSolver, Preconditioner};
use crate::effects::EffectSet;
use crate::integrate::cg::Pcg;
use crate::integrate::friction::Drag;
use crate::integrate::integrator::{Capabilities, Integrator, StepReport};
use crate::integrate::precond::Csr;
use crate::integrate::Dynamics;
use crate::linalg::{BlockCsr, Filter, PatternBuilder};
use crate::Vec3;

/// The state-independent parts of `df/dx` and `df/dv`, assembled once in `prepare`.
pub(super) struct Constant {
    pub(super) dfdx: BlockCsr,
    pub(super) dfdv: BlockCsr,
}

pub struct Implicit {
    /// Whether the current step is a split or subdivided one (see `solve.rs`).
    pub(super) short_step: bool,
    pub(super) settings: ImplicitSettings,
    pub(super) preconditioner: Preconditioner,
    /// The scene's choice of linear path, the path the current step runs, and what `auto`
    /// decides it from.
    pub(super) linear: LinearSolver,
    pub(super) path: LinearPath,
    pub(super) auto: AutoPath,
    /// The direct path's Cholesky factor with its cached symbolic analysis.
    pub(super) direct: Direct,
    /// df/dx, then reused in place as the system matrix A.
    pub(super) a: Option<BlockCsr>,
    pub(super) dfdv: Option<BlockCsr>,
    pub(super) constant: Option<Constant>,
    pub(super) hierarchy: Option<Hierarchy>,
    /// Storage for the filtered fine matrix handed to the multigrid.
    pub(super) filtered: Csr,
    pub(super) pcg: Pcg,
    /// Friction drags of the current step's held vertices.
    pub(super) drags: Vec<Drag>,
    /// Per vertex: the tangential force (N) the rest of the system put on it in the last step,
    /// `m dv / h - f_friction(v1)` (zero for vertices without friction), which decides the
    /// next step's friction modes (see `Drag::fit`); and the sum of its Coulomb limits.
    pub(super) loads: Vec<Vec3>,
    pub(super) limit_sum: Vec<f64>,
    /// Per edge spring of the step's constraints: whether it acts in the current system.
    pub(super) spring_active: Vec<bool>,
    /// Friction of acting edge springs' contact points: (spring index, drag).
    pub(super) edge_drags: Vec<(usize, Drag)>,
    /// The current step's filter and the held vertices it released (see `settle_holds`).
    pub(super) filter: Vec<Filter>,
    pub(super) released: Vec<(usize, Vec3)>,
    /// Constraint impulses of the current step (see [`StepReport::constraint_impulses`]): the
    /// report's buffer, swapped in for the step and back out at its end.
    pub(super) impulses: Vec<Vec3>,
    pub(super) f0: Vec<Vec3>,
    pub(super) b: Vec<Vec3>,
    pub(super) dv: Vec<Vec3>,
    pub(super) z: Vec<Vec3>,
    /// End state `x0 + h v1`, `v1 = v0 + dv` of the current Newton iterate.
    pub(super) xk: Vec<Vec3>,
    pub(super) vk: Vec<Vec3>,
    /// The positions the current Newton correction's matrix was assembled at (the iterate
    /// before), against which its result's unseen stretch is judged (see `newton::unseen_stretch`).
    pub(super) x_lin: Vec<Vec3>,
    pub(super) delta: Vec<Vec3>,
    /// Potential energy at the end positions of the last step (still in `xk`).
    pub(super) end_potential: Option<f64>,
    /// The least energy-creating Newton iterate so far.
    pub(super) best: Vec<Vec3>,
    /// The velocity change of the step before the last (a start direction of the solve), and
    /// the copy of the last one taken before it is overwritten.
    pub(super) older: Vec<Vec3>,
    pub(super) last: Vec<Vec3>,
}

impl Implicit {
    pub fn new(settings: ImplicitSettings) -> Self {
        Self::with_preconditioner(settings, Preconditioner::Multigrid)
    }

    /// An implicit solver on the given linear path (`solver.linear`).
    pub fn with_linear(settings: ImplicitSettings, linear: LinearSolver) -> Self {
        Self {
            linear,
            ..Self::new(settings)
        }
    }

    pub fn with_preconditioner(settings: ImplicitSettings, preconditioner: Preconditioner) -> Self {
        Self {
            short_step: false,
            settings,
            preconditioner,
            linear: LinearSolver::Pcg,
            path: LinearPath::Pcg,
            auto: AutoPath::default(),
            direct: Direct::default(),
            a: None,
            dfdv: None,
            constant: None,
            hierarchy: None,
            filtered: Csr::default(),
            pcg: Pcg::default(),
            drags: Vec::new(),
            loads: Vec::new(),
            limit_sum: Vec::new(),
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
            x_lin: Vec::new(),
            vk: Vec::new(),
            delta: Vec::new(),
            end_potential: None,
            best: Vec::new(),
            older: Vec::new(),
            last: Vec::new(),
        }
    }
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

    fn set_solver_settings(&mut self, settings: ImplicitSettings) -> bool {
        self.settings = settings;
        true
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
        self.loads.clear();
    }

    /// Runs the step on the caller's thread; its products, filter pass, Galerkin products and
    /// sweeps fork on [`crate::par`]'s spinning helper. On rayon's pool (the step inside a
    /// `rayon::scope`) every fork wakes a sleeping worker, dozens of times per PCG iteration,
    /// which at 64x64 costs what the second thread gains; the spinning helper is awake already
    /// (`cargo bench --bench contact` measures the CG time per frame).
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
        self.step_in_pool(d, t, h, x, v, report);
        std::mem::swap(&mut self.impulses, &mut report.constraint_impulses);
    }
}
