//! The effect plan: which force terms a run builds and in which order (the order their forces
//! are summed in), with the parameters every vertex shares (gravity, the wind), and the one
//! builder that turns a plan into an [`EffectSet`] for any cloth.
//!
//! What differs between a cloth of grid pieces and a welded garment is only where the elements
//! come from (springs, bending and twist stencils, damped pairs) and which scene key names their
//! parameters; that is the [`Elements`] trait. [`Lattice`] gives a grid cloth's elements piece by
//! piece; the garment's welded topology implements it too. The scene turns its `effects:` list
//! into a plan; a term the plan does not name is never built.

use super::springs::Knee;
use super::{
    AirDrag, Bending, EffectSet, Gravity, Gust, SpringDamping, Springs, Twist, VelocityDiffusion,
    Wind, WindKey,
};
use crate::cloth::topology::{
    bending_stencils, clamp_edges, spring_stiffness, springs, twist_stencils, Spring, SpringKind,
    Stencil,
};
use crate::cloth::Cloth;
use crate::Vec3;
use serde::{Deserialize, Serialize};

/// One force term of a plan: an effect a scene can ask for (its `effects:` list, in
/// snake_case). The scene's `EffectKind` is this type, so the two cannot drift apart.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectKind {
    Gravity,
    /// Structural springs along warp and weft edges.
    Stretch,
    /// Diagonal springs.
    Shear,
    /// Springs between second neighbours along warp and weft.
    SkipOne,
    /// Second derivative along warp and along weft (separate rigidities).
    Bending,
    /// Mixed second derivative.
    Twist,
    Wind,
    /// Spring damping, air drag and velocity diffusion (per the material's `damping`).
    Damping,
}

impl EffectKind {
    /// Every effect, in the order the benchmarks and the bitwise step tests list them (the
    /// order effects are built in is the order their forces are summed in).
    pub const ALL: [EffectKind; 8] = [
        EffectKind::Gravity,
        EffectKind::Stretch,
        EffectKind::Shear,
        EffectKind::SkipOne,
        EffectKind::Bending,
        EffectKind::Twist,
        EffectKind::Damping,
        EffectKind::Wind,
    ];
}

/// The wind's parameters, without the triangles it acts on.
#[derive(Debug, Clone, PartialEq)]
pub struct WindPlan {
    /// Constant wind velocity (m/s).
    pub velocity: Vec3,
    pub keys: Vec<WindKey>,
    pub gusts: Vec<Gust>,
    pub air_density: f64,
    pub drag_coefficient: f64,
}

impl WindPlan {
    /// The wind effect on a cloth of these triangles.
    pub fn effect(&self, triangles: Vec<[u32; 3]>) -> Wind {
        Wind::new(
            self.velocity,
            self.keys.clone(),
            self.gusts.clone(),
            self.air_density,
            self.drag_coefficient,
            triangles,
        )
    }
}

/// Which effects to build, in order, and their shared parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct EffectPlan {
    pub terms: Vec<EffectKind>,
    /// Gravitational acceleration (m/s^2), for [`EffectKind::Gravity`].
    pub gravity: Vec3,
    /// The wind, for [`EffectKind::Wind`] (no wind is built without it).
    pub wind: Option<WindPlan>,
}

/// Springs sharing one scene parameter: per spring its stiffness (N/m).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SpringGroup {
    pub springs: Vec<Spring>,
    pub k: Vec<f64>,
    /// The scene key of the stiffness, e.g. `cloths[0].material.stretch`.
    pub parameter: String,
    /// Per spring where its material stiffens it (`material.stretch_knee`); empty when no
    /// spring of the group has a knee.
    pub knee: Vec<Option<Knee>>,
}

/// Bending or twist stencils sharing one scene parameter: per stencil its rigidity.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StencilGroup<const N: usize> {
    pub stencils: Vec<Stencil<N>>,
    pub rigidity: Vec<f64>,
    pub parameter: String,
}

/// Vertex pairs with a coefficient each (damped springs, diffusion).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Pairs {
    pub pairs: Vec<(u32, u32)>,
    pub k: Vec<f64>,
}

/// Where a cloth's elements come from. Groups with no element are skipped by the builder.
pub trait Elements {
    /// Springs of `kind` with a positive stiffness.
    fn springs(&self, kind: SpringKind) -> Vec<SpringGroup>;
    fn bending(&self) -> Vec<StencilGroup<3>>;
    fn twist(&self) -> Vec<StencilGroup<4>>;
    /// Damped spring pairs with their damping coefficient (`damping.spring`).
    fn spring_damping(&self) -> Pairs;
    /// Velocity-diffusion pairs with their coefficient (`damping.diffusion`).
    fn diffusion(&self) -> Pairs;
}

impl EffectPlan {
    /// The plan without external loads (gravity, wind): what a garment is sewn under.
    pub fn without_loads(&self) -> EffectPlan {
        EffectPlan {
            terms: self
                .terms
                .iter()
                .copied()
                .filter(|t| !matches!(t, EffectKind::Gravity | EffectKind::Wind))
                .collect(),
            gravity: self.gravity,
            wind: None,
        }
    }

    /// Whether the plan names `term`.
    pub fn has(&self, term: EffectKind) -> bool {
        self.terms.contains(&term)
    }

    /// The effects of this plan on `cloth`, whose elements `elements` gives, in the plan's order.
    pub fn build(&self, cloth: &Cloth, elements: &dyn Elements) -> EffectSet {
        let mut set = EffectSet::new();
        for term in &self.terms {
            match term {
                EffectKind::Gravity => set.push_gravity(Gravity::new(self.gravity, &cloth.mass)),
                EffectKind::Stretch | EffectKind::Shear | EffectKind::SkipOne => {
                    let (name, kind) = match term {
                        EffectKind::Stretch => ("stretch", SpringKind::Structural),
                        EffectKind::Shear => ("shear", SpringKind::Shear),
                        _ => ("skip_one", SpringKind::SkipOne),
                    };
                    for g in elements.springs(kind) {
                        if !g.springs.is_empty() {
                            let springs = Springs::new(name, g.springs, g.k, g.parameter);
                            set.push(Box::new(springs.with_knee(&g.knee)));
                        }
                    }
                }
                EffectKind::Bending => {
                    for g in elements.bending() {
                        if !g.stencils.is_empty() {
                            set.push(Box::new(Bending::new(g.stencils, g.rigidity, g.parameter)));
                        }
                    }
                }
                EffectKind::Twist => {
                    for g in elements.twist() {
                        if !g.stencils.is_empty() {
                            set.push(Box::new(Twist::new(g.stencils, g.rigidity, g.parameter)));
                        }
                    }
                }
                EffectKind::Wind => {
                    if let Some(w) = &self.wind {
                        set.push(Box::new(w.effect(cloth.triangles.clone())));
                    }
                }
                EffectKind::Damping => {
                    let d = elements.spring_damping();
                    if !d.pairs.is_empty() {
                        set.push(Box::new(SpringDamping::new(d.pairs, d.k)));
                    }
                    let mut air = vec![0.0; cloth.len()];
                    for p in &cloth.pieces {
                        air[p.vertices()].fill(p.material.damping.air);
                    }
                    if air.iter().any(|&a| a > 0.0) {
                        set.push(Box::new(AirDrag::new(&air, &cloth.mass)));
                    }
                    let d = elements.diffusion();
                    if !d.pairs.is_empty() {
                        set.push(Box::new(VelocityDiffusion::new(d.pairs, d.k)));
                    }
                }
            }
        }
        set
    }
}

/// A cloth of grid pieces: each piece's own lattice springs and stencils, keyed by the piece's
/// index (`cloths[i].material.*`).
pub struct Lattice<'a>(pub &'a Cloth);

fn material_key(i: usize, name: &str) -> String {
    format!("cloths[{i}].material.{name}")
}

impl Elements for Lattice<'_> {
    fn springs(&self, kind: SpringKind) -> Vec<SpringGroup> {
        let name = match kind {
            SpringKind::Structural => "stretch",
            SpringKind::Shear => "shear",
            SpringKind::SkipOne => "skip_one",
        };
        let mut out = Vec::new();
        for (i, p) in self.0.pieces.iter().enumerate() {
            let s = springs(p, kind);
            let k = spring_stiffness(p, kind);
            // The lattice's edges and diagonals stiffen; skip-one springs stand in for bending.
            let knee = match (kind, p.material.knee()) {
                (SpringKind::SkipOne, _) | (_, None) => Vec::new(),
                (_, Some((strain, ratio))) => vec![Some(Knee { strain, ratio }); s.len()],
            };
            if k.iter().any(|&k| k > 0.0) && !s.is_empty() {
                out.push(SpringGroup {
                    k,
                    springs: s,
                    parameter: material_key(i, name),
                    knee,
                });
            }
        }
        out
    }

    fn bending(&self) -> Vec<StencilGroup<3>> {
        let mut out = Vec::new();
        for (i, p) in self.0.pieces.iter().enumerate() {
            let mut g = StencilGroup::default();
            for (along_u, b) in [(true, p.material.bend_warp), (false, p.material.bend_weft)] {
                if b > 0.0 {
                    let mut s = bending_stencils(p, along_u);
                    clamp_edges(&mut s, |v| self.0.is_kinematic(v));
                    g.rigidity.extend(std::iter::repeat_n(b, s.len()));
                    g.stencils.extend(s);
                }
            }
            if !g.stencils.is_empty() {
                let which = if p.material.bend_warp >= p.material.bend_weft {
                    "bend_warp"
                } else {
                    "bend_weft"
                };
                g.parameter = material_key(i, which);
                out.push(g);
            }
        }
        out
    }

    fn twist(&self) -> Vec<StencilGroup<4>> {
        let mut out = Vec::new();
        for (i, p) in self.0.pieces.iter().enumerate() {
            let s = twist_stencils(p);
            if p.material.twist > 0.0 && !s.is_empty() {
                out.push(StencilGroup {
                    rigidity: vec![p.material.twist; s.len()],
                    stencils: s,
                    parameter: material_key(i, "twist"),
                });
            }
        }
        out
    }

    fn spring_damping(&self) -> Pairs {
        let mut out = Pairs::default();
        for p in &self.0.pieces {
            let d = p.material.damping.spring;
            if d > 0.0 {
                for kind in [SpringKind::Structural, SpringKind::Shear] {
                    for s in springs(p, kind) {
                        out.pairs.push((s.i, s.j));
                        out.k.push(d);
                    }
                }
            }
        }
        out
    }

    fn diffusion(&self) -> Pairs {
        let mut out = Pairs::default();
        for p in &self.0.pieces {
            let d = p.material.damping.diffusion;
            if d > 0.0 {
                for s in springs(p, SpringKind::Structural) {
                    out.pairs.push((s.i, s.j));
                    out.k.push(d);
                }
            }
        }
        out
    }
}
