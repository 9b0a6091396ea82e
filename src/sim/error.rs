//! The error of a simulation that diverged: what the guard measured, where, and (only when the
//! integrator's stability bound says so) which effect is the cause.

use crate::collide::ContactKind;
use std::fmt;

/// Why a substep was rejected: what the guard measured.
#[derive(Debug, Clone, PartialEq)]
pub enum Symptom {
    NonFinite,
    /// Speed of the fastest vertex (m/s), above the guard's `max_speed`.
    Speed(f64),
    /// Energy gained in one substep beyond what external work and the allowances explain (J).
    EnergyGain {
        gained: f64,
        allowed: f64,
    },
    /// An edge (from the reported vertex to `other`, its index within the same piece) ended the
    /// substep `ratio` times its rest length, beyond the `bound` the material and the speeds in
    /// the scene allow, and the solve had left it within: the collision stage's response
    /// stretched it (see the guard's strain check). `contact`: the contact kind that moved its
    /// vertices (`None`: the stage's pass is not known).
    Stretch {
        other: usize,
        ratio: f64,
        bound: f64,
        contact: Option<ContactKind>,
    },
}

impl fmt::Display for Symptom {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Symptom::NonFinite => write!(f, "has a non-finite position or velocity"),
            Symptom::Speed(s) => write!(f, "moves at {s:.3e} m/s"),
            Symptom::EnergyGain { gained, allowed } => write!(
                f,
                "is where energy runs away ({gained:.3e} J gained in one step, {allowed:.3e} J \
                 allowed)"
            ),
            Symptom::Stretch {
                other,
                ratio,
                bound,
                contact,
            } => {
                write!(
                    f,
                    "ends an edge (to vertex {other}) stretched to {ratio:.3} times its rest \
                     length, beyond the {bound:.3} the material and the speeds allow; the solve \
                     left it within, the collision stage's "
                )?;
                match contact {
                    Some(kind) => write!(f, "{kind} stretched it"),
                    None => write!(f, "response stretched it"),
                }
            }
        }
    }
}

/// What the guard can say about the cause of a divergence.
#[derive(Debug, Clone, PartialEq)]
pub enum Cause {
    /// The step is over the integrator's stability bound `h omega <= limit` (`omega` the
    /// bound on the cloth's highest angular frequency); `parameter` is the scene parameter of
    /// the effect contributing the largest `omega^2`.
    Unstable {
        parameter: String,
        /// `h omega` of the failed step.
        h_omega: f64,
        limit: f64,
    },
    /// The integrator is stable for no step size of an undamped oscillation (forward Euler).
    NoStableStep,
    /// Within the stability bound, or the integrator has none (implicit): the guard measured
    /// the symptom only, and names no culprit it has not measured.
    Unknown,
}

/// A simulation that diverged and could not be rescued by the policy.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "cloth '{cloth}' diverged at t = {time:.4} s (step {step:.3e} s, {integrator}): vertex \
     {vertex} {symptom}{}",
    CauseText(.cause, .integrator)
)]
pub struct DivergenceError {
    pub time: f64,
    pub step: f64,
    pub cloth: String,
    /// Vertex index within its cloth piece.
    pub vertex: usize,
    pub symptom: Symptom,
    pub integrator: &'static str,
    pub cause: Cause,
}

/// The cause's part of the message, with advice where the cause is known.
struct CauseText<'a>(&'a Cause, &'a &'static str);

impl fmt::Display for CauseText<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let integrator = *self.1;
        match self.0 {
            Cause::Unstable {
                parameter,
                h_omega,
                limit,
            } => {
                write!(
                    f,
                    "; cause: the step is over the stability limit of {integrator} (h*omega = \
                     {h_omega:.3} > {limit:.3}, stiffest: {parameter}): lower dt, raise \
                     solver.substeps or soften {parameter}, or use the implicit integrator"
                )
            }
            Cause::NoStableStep => write!(
                f,
                "; cause: {integrator} is stable for no step of an undamped spring: use \
                 symplectic_euler, rk4 or the implicit integrator"
            ),
            Cause::Unknown => Ok(()),
        }
    }
}

/// The error for a substep `(t, h)` that failed at `vertex` (flat index) with `symptom`.
/// An effect is blamed only when the step is over the integrator's stability bound
/// `h omega > limit` (`omega_bound` the bound on the cloth's highest angular frequency, known
/// where the integrator has a limit): the one contributing the largest `omega^2`.
/// Otherwise (within the bound, or an integrator without one) the error reports what the guard
/// measured and suggests no step size.
pub(super) fn divergence_error(
    (cloth, effects): (&crate::cloth::Cloth, &crate::effects::EffectSet),
    integrator: &'static str,
    (stability_limit, omega_bound): (Option<f64>, Option<f64>),
    (t, h): (f64, f64),
    vertex: usize,
    symptom: Symptom,
) -> DivergenceError {
    let (name, local) = match cloth.piece_of(vertex) {
        Some(p) => (p.name.clone(), vertex - p.first_vertex),
        None => (String::from("?"), vertex),
    };
    let cause = match stability_limit {
        None => Cause::Unknown,
        Some(limit) if limit <= 0.0 => Cause::NoStableStep,
        Some(limit) => {
            let h_omega = h * omega_bound.unwrap_or(0.0);
            let stiffest = effects
                .stiffness(&cloth.mass)
                .into_iter()
                .max_by(|a, b| a.omega_sq.total_cmp(&b.omega_sq));
            match stiffest {
                Some(b) if h_omega > limit => Cause::Unstable {
                    parameter: b.parameter,
                    h_omega,
                    limit,
                },
                _ => Cause::Unknown,
            }
        }
    };
    DivergenceError {
        time: t,
        step: h,
        cloth: name,
        vertex: local,
        symptom,
        integrator,
        cause,
    }
}
