//! The cases. Each builds its scene from YAML (so the parser and the builder are part of what is
//! tested) or, for degenerate geometry the scene format cannot express, from a hand-made mesh.
//! Bounds are derived in the comments next to them.

use super::{Case, Criteria, EnergyCheck, HardError, Resolution};
use crate::cloth::topology::{bending_stencils, springs, SpringKind};
use crate::cloth::{Cloth, Material, Panel};
use crate::effects::{AirDrag, Bending, EffectSet, Gravity, SpringDamping, Springs};
use crate::integrate::{ImplicitSettings, IntegratorKind};
use crate::scene::Scene;
use crate::sim::{Frames, GuardSettings, Simulation, StepSettings};
use crate::Vec3;
use glam::DVec2;
use std::path::PathBuf;

/// Builds one case at a resolution.
pub type CaseFn = fn(Resolution) -> Result<Case, HardError>;

/// Every case, in the order of the summary.
pub fn catalogue() -> Vec<(&'static str, CaseFn)> {
    vec![
        ("stiff_implicit", stiff_implicit),
        ("stiff_explicit_near_limit", stiff_explicit_near_limit),
        ("stiff_explicit_over_limit", stiff_explicit_over_limit),
        ("light_cloth", light_cloth),
        ("heavy_cloth", heavy_cloth),
        ("tiny_cloth", tiny_cloth),
        ("huge_cloth", huge_cloth),
        ("impact_20_m_s", impact),
        ("robot_swing_at_velocity_limit", robot_swing),
        ("pinch_below_thickness", pinch),
        ("crumple_heap", crumple),
        ("degenerate_mesh", degenerate_mesh),
        ("pinned_inside_obstacle", pinned_inside_obstacle),
        ("wind_50_m_s", wind),
        ("long_run_10_min", long_run),
    ]
}

const G: f64 = 9.81;

/// Fills `@KEY@` placeholders (YAML flow maps use braces, so `format!` would be unreadable).
fn fill(template: &str, values: &[(&str, String)]) -> String {
    values.iter().fold(template.to_string(), |t, (k, v)| {
        t.replace(&format!("@{k}@"), v)
    })
}

fn parse(case: &'static str, text: &str) -> Result<Scene, HardError> {
    let mut s = Scene::from_yaml(text, case).map_err(|source| HardError::Scene { case, source })?;
    // Robot scenes name ../urdf/drape_bot.urdf relative to config/.
    s.base_dir = Some(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("config"));
    Ok(s)
}

fn build(case: &'static str, scene: &Scene) -> Result<Simulation, HardError> {
    scene
        .build()
        .map_err(|source| HardError::Scene { case, source })
}

fn pick<T>(res: Resolution, ci: T, full: T) -> T {
    match res {
        Resolution::Ci => ci,
        Resolution::Full => full,
    }
}

/// A horizontal square cloth at height `z`, hanging from two corners.
const HANGING: &str = r#"
effects: [gravity, stretch, shear, bending, damping]
solver: { integrator: @INTEGRATOR@, dt: @DT@, substeps: 1 }
cloths:
  - name: cloth
    grid: { size: [@SIZE@, @SIZE@], resolution: [@RES@, @RES@], pose: { xyz: [0, 0, @Z@] } }
    material:
      density: @DENSITY@
      stretch: @STRETCH@
      shear: @SHEAR@
      bend_warp: @BEND@
      bend_weft: @BEND@
      damping: { spring: @KD@, air: 0.05 }
    pins: [ { region: top_left }, { region: top_right } ]
"#;

struct Hanging {
    integrator: &'static str,
    dt: f64,
    size: f64,
    res: usize,
    density: f64,
    stretch: f64,
    bend: f64,
    spring_damping: f64,
}

impl Hanging {
    fn new(size: f64, res: usize) -> Self {
        Self {
            integrator: "implicit",
            dt: 1.0 / 60.0,
            size,
            res,
            density: 0.2,
            stretch: 1000.0,
            bend: 1e-4,
            spring_damping: 0.05,
        }
    }

    fn scene(&self, case: &'static str) -> Result<Scene, HardError> {
        let z = self.size;
        parse(
            case,
            &fill(
                HANGING,
                &[
                    ("INTEGRATOR", self.integrator.into()),
                    ("DT", format!("{:e}", self.dt)),
                    ("SIZE", format!("{:e}", self.size)),
                    ("RES", self.res.to_string()),
                    ("Z", format!("{z:e}")),
                    ("DENSITY", format!("{:e}", self.density)),
                    ("STRETCH", format!("{:e}", self.stretch)),
                    ("SHEAR", format!("{:e}", 0.1 * self.stretch)),
                    ("BEND", format!("{:e}", self.bend)),
                    ("KD", format!("{:e}", self.spring_damping)),
                ],
            ),
        )
    }

    /// Bounds of a cloth hanging from two corners, from energy: no point can get further from a
    /// pin than the diagonal (stretched by `strain`), and no vertex can be faster than if the whole
    /// fall of the cloth's centre of mass (at most the diagonal) went into that one vertex's kinetic
    /// energy: `v^2 <= 2 g d M / m_min`.
    fn criteria(&self, sim: &Simulation, strain: f64) -> Criteria {
        let diag = self.size * std::f64::consts::SQRT_2;
        let pin = Vec3::new(0.5 * self.size, 0.5 * self.size, self.size).length();
        let m_total: f64 = sim.cloth.mass.iter().sum();
        let m_min = sim.cloth.mass.iter().copied().fold(f64::INFINITY, f64::min);
        let v_max = (2.0 * G * diag * (1.0 + strain) * m_total / m_min).sqrt();
        Criteria::base(pin + diag * (1.0 + strain), v_max)
    }
}

fn hanging_case(
    name: &'static str,
    description: String,
    h: Hanging,
    duration: f64,
    strain: f64,
) -> Result<Case, HardError> {
    let sim = build(name, &h.scene(name)?)?;
    let criteria = h.criteria(&sim, strain);
    Ok(Case {
        name,
        description,
        sim,
        driver: None,
        duration,
        criteria,
    })
}

fn stiff_implicit(res: Resolution) -> Result<Case, HardError> {
    let mut h = Hanging::new(0.5, pick(res, 12, 32));
    h.stretch = 1e6;
    hanging_case(
        "stiff_implicit",
        "0.5 m cloth, stretch 1e6 N/m (shear 1e5), implicit at dt = 1/60 s, dropped from two corners"
            .into(),
        h,
        pick(res, 2.0, 5.0),
        // Weight over stiffness: 0.05 kg * g / 1e6 N/m per spring is far below 1 %.
        0.01,
    )
}

/// A symplectic Euler run at `h * omega_bound = ratio` of the stiff cloth.
fn stiff_explicit(name: &'static str, res: Resolution, ratio: f64) -> Result<Case, HardError> {
    let mut h = Hanging::new(0.5, pick(res, 8, 16));
    h.stretch = 1e6;
    h.integrator = "symplectic_euler";
    // Find omega from the built cloth, then rebuild at the step that gives the ratio.
    let probe = build(name, &h.scene(name)?)?;
    // The same bound the simulation uses: omega^2 <= the sum of every elastic effect's bound.
    let bounds = probe.effects().stiffness(&probe.cloth.mass);
    let omega = (!bounds.is_empty())
        .then(|| bounds.iter().map(|b| b.omega_sq).sum::<f64>().sqrt())
        .ok_or_else(|| HardError::Build {
            case: name,
            message: "no elastic effect to take the stability limit from".into(),
        })?;
    h.dt = ratio / omega;
    let description = format!(
        "as stiff_implicit at {}x{} with symplectic Euler at h*omega_bound = {ratio} (limit 2), \
         guard policy subdivide",
        h.res, h.res
    );
    hanging_case(name, description, h, pick(res, 0.1, 0.5), 0.01)
}

fn stiff_explicit_near_limit(res: Resolution) -> Result<Case, HardError> {
    stiff_explicit("stiff_explicit_near_limit", res, 1.9)
}

fn stiff_explicit_over_limit(res: Resolution) -> Result<Case, HardError> {
    let mut c = stiff_explicit("stiff_explicit_over_limit", res, 4.0)?;
    c.criteria.expect_subdivisions = true;
    Ok(c)
}

fn light_cloth(res: Resolution) -> Result<Case, HardError> {
    let mut h = Hanging::new(0.5, pick(res, 12, 32));
    h.density = 0.002;
    hanging_case(
        "light_cloth",
        "0.5 m cloth of 0.002 kg/m^2 (100x lighter than cotton), implicit at 1/60 s".into(),
        h,
        pick(res, 2.0, 5.0),
        0.01,
    )
}

fn heavy_cloth(res: Resolution) -> Result<Case, HardError> {
    let mut h = Hanging::new(0.5, pick(res, 12, 32));
    h.density = 20.0;
    hanging_case(
        "heavy_cloth",
        "0.5 m cloth of 20 kg/m^2 (100x heavier than cotton, 1e4 x the light one) on the same \
         1000 N/m springs, implicit at 1/60 s"
            .into(),
        h,
        pick(res, 2.0, 5.0),
        // 5 kg on 1000 N/m springs stretches a lot: allow the diagonal to double.
        1.0,
    )
}

fn tiny_cloth(res: Resolution) -> Result<Case, HardError> {
    let h = Hanging::new(0.01, pick(res, 8, 16));
    hanging_case(
        "tiny_cloth",
        "1 cm cloth (cotton material), implicit at 1/60 s".into(),
        h,
        pick(res, 2.0, 5.0),
        0.01,
    )
}

fn huge_cloth(res: Resolution) -> Result<Case, HardError> {
    let mut h = Hanging::new(10.0, pick(res, 16, 48));
    h.bend = 1e-2;
    hanging_case(
        "huge_cloth",
        "10 m cloth (cotton density, 1000 N/m), implicit at 1/60 s".into(),
        h,
        pick(res, 4.0, 10.0),
        // 20 kg on 1000 N/m springs: the diagonal may stretch by half.
        0.5,
    )
}

fn impact(res: Resolution) -> Result<Case, HardError> {
    const V: f64 = 20.0;
    let text = fill(
        r#"
effects: [gravity, stretch, shear, bending, damping]
solver: { integrator: implicit, dt: 0.016666666666666666, substeps: 2 }
cloths:
  - name: sheet
    grid: { size: [0.6, 0.6], resolution: [@RES@, @RES@], pose: { xyz: [0, 0, 0] } }
    material: { thickness: 0.005 }
obstacles:
  - name: ball
    shape: { type: sphere, radius: 0.1 }
    pose: { xyz: [0, 0, -0.3] }
    motion: { type: velocity, linear: [0, 0, @V@], angular: [0, 0, 0] }
collision: { mode: continuous }
"#,
        &[("RES", pick(res, 12, 32).to_string()), ("V", V.to_string())],
    );
    let scene = parse("impact_20_m_s", &text)?;
    let sim = build("impact_20_m_s", &scene)?;
    let duration = pick(res, 0.15, 0.3);
    // Cloth that rides on the ball moves at its speed; a perfectly elastic bounce off a moving
    // wall gives 2 V. Anything a free edge gains beyond that by whipping is bounded by 3 V here.
    let mut criteria = Criteria::base(V * duration + 0.3 + 1.0, 3.0 * V);
    criteria.energy = EnergyCheck::NotMeasured;
    criteria.max_penetration = Some(0.005);
    Ok(Case {
        name: "impact_20_m_s",
        description: format!(
            "free 0.6 m sheet hit from below by a 0.1 m ball at {V} m/s (2 substeps at 60 Hz: \
             the ball moves 1.7 diameters per substep)"
        ),
        sim,
        driver: None,
        duration,
        criteria,
    })
}

fn robot_swing(res: Resolution) -> Result<Case, HardError> {
    // right_shoulder_pitch is limited to 2.0 rad/s and right_wrist to 3.0 rad/s (drape_bot.urdf):
    // both swing at exactly their limit (wrist 0 -> 2.9 rad, its position limit, in 0.9667 s;
    // shoulder 1.9333 rad down past the torso in the same time, and back) after the cloth has
    // settled on the arm for 1 s. The sheet lands on a floor. Without one (first version of this
    // case) it fell past the base and the descending hand caught it against base_link, reaching
    // 3 kJ of elastic energy and 104 m/s at full resolution; since vertices pinched between two
    // facing obstacles sit midway between them (collide/stage.rs) that no longer happens: with the
    // floor moved 5 m down the full-resolution sheet falls freely to it (9.6 m/s, free fall from
    // 5 m gives 9.9) with 8e-9 m penetration.
    let text = fill(
        r#"
effects: [gravity, stretch, shear, bending, damping]
solver: { integrator: implicit, dt: 0.016666666666666666, substeps: 2 }
cloths:
  - name: sheet
    grid: { size: [0.44, 0.44], resolution: [@RES@, @RES@], pose: { xyz: [0.5, -0.26, 0.72] } }
    material:
      density: 0.2
      stretch: 1500.0
      shear: 150.0
      bend_warp: 1.0e-4
      bend_weft: 1.0e-4
      damping: { spring: 0.05, air: 0.1 }
      thickness: 0.008
      friction: 0.5
robot:
  urdf: ../urdf/drape_bot.urdf
  trajectory:
    names: [right_shoulder_pitch, right_wrist]
    points:
      - { t: 0.0, positions: [-1.57, 0.0] }
      - { t: 1.0, positions: [-1.57, 0.0] }
      - { t: 1.9666666666666667, positions: [0.36333333333333334, 2.9] }
      - { t: 2.9333333333333333, positions: [-1.57, 0.0] }
obstacles:
  - { name: floor, shape: { type: plane, normal: [0.0, 0.0, 1.0] } }
collision: { mode: continuous }
"#,
        &[("RES", pick(res, 12, 22).to_string())],
    );
    let name = "robot_swing_at_velocity_limit";
    let scene = parse(name, &text)?;
    let (sim, driver) = scene
        .build_with_robot()
        .map_err(|source| HardError::Scene { case: name, source })?;
    // The hand is at most ~0.75 m from the shoulder: 2 rad/s gives 1.5 m/s at the hand, and the
    // wrist adds 3 rad/s over the ~0.1 m hand. Cloth flung off falls at most 1 m to the floor
    // (sqrt(2 g) = 4.4 m/s); the bound takes 3x the link speed plus that fall. Everything stays
    // within the arm's reach (~1 m) plus the sheet's diagonal (0.62 m) of the root.
    let mut criteria = Criteria::base(2.0, 3.0 * 1.8 + (2.0 * G).sqrt());
    criteria.energy = EnergyCheck::NotMeasured;
    criteria.max_penetration = Some(0.008);
    Ok(Case {
        name,
        description: "sheet draped over drape_bot's right arm; shoulder pitch swings through it \
                      at its 2.0 rad/s limit and the wrist at its 3.0 rad/s limit, then back"
            .into(),
        sim,
        driver,
        duration: 3.0,
        criteria,
    })
}

fn pinch(res: Resolution) -> Result<Case, HardError> {
    // The sheet (thickness 5 mm) lies on a table; a block comes down onto it and stops with a
    // 1.5 mm gap to the table, less than the thickness: the contact cannot be resolved, the
    // cloth must stay put and finite.
    let text = fill(
        r#"
effects: [gravity, stretch, shear, bending, damping]
solver: { integrator: implicit, dt: 0.016666666666666666, substeps: 2 }
cloths:
  - name: sheet
    grid: { size: [0.4, 0.4], resolution: [@RES@, @RES@], pose: { xyz: [0, 0, 0.005] } }
    material: { thickness: 0.005, friction: 0.5 }
obstacles:
  - { name: table, shape: { type: box, half_extents: [0.5, 0.5, 0.1] }, pose: { xyz: [0, 0, -0.1] } }
  - name: press
    shape: { type: box, half_extents: [0.1, 0.1, 0.1] }
    pose: { xyz: [0, 0, 0.3] }
    motion:
      type: waypoints
      points:
        - { t: 0.0, pose: { xyz: [0, 0, 0.3] } }
        - { t: 0.5, pose: { xyz: [0, 0, 0.1015] } }
        - { t: 10.0, pose: { xyz: [0, 0, 0.1015] } }
collision: { mode: continuous }
"#,
        &[("RES", pick(res, 12, 32).to_string())],
    );
    let scene = parse("pinch_below_thickness", &text)?;
    let sim = build("pinch_below_thickness", &scene)?;
    // The press moves at 0.4 m/s; nothing in the scene can fling the cloth faster than a few
    // times that, nor further than the table.
    let mut criteria = Criteria::base(1.0, 2.0);
    criteria.energy = EnergyCheck::NotMeasured;
    // The two thickness layers overlap: a pinched vertex is put midway between the surfaces,
    // `gap / 2` from each, i.e. `thickness - gap / 2` = 4.25 mm into both layers. (Before that
    // fix it was pushed out of one layer into the other obstacle's solid: 8.5 mm.)
    criteria.max_penetration = Some(0.005 - 0.5 * 0.0015 + 1e-9);
    Ok(Case {
        name: "pinch_below_thickness",
        description:
            "sheet on a table squeezed by a block closing to a 1.5 mm gap (thickness 5 mm)".into(),
        sim,
        driver: None,
        duration: pick(res, 1.0, 2.0),
        criteria,
    })
}

fn crumple(res: Resolution) -> Result<Case, HardError> {
    let text = fill(
        r#"
effects: [gravity, stretch, shear, bending, damping]
solver: { integrator: implicit, dt: 0.008333333333333333 }
cloths:
  - name: cloth
    grid: { size: [0.8, 0.8], resolution: [@RES@, @RES@], pose: { xyz: [0.0, 0.0, 0.7], rpy: [1.2, 0.3, 0.0] } }
    material:
      density: 0.2
      stretch: 800.0
      shear: 80.0
      bend_warp: 2.0e-5
      bend_weft: 2.0e-5
      damping: { spring: 0.05, air: 0.2 }
      thickness: 0.006
      friction: 0.4
obstacles:
  - { name: ground, shape: { type: plane, normal: [0.0, 0.0, 1.0] } }
collision: { mode: continuous, self_collision: true, count_self_intersections: true }
"#,
        &[("RES", pick(res, 14, 32).to_string())],
    );
    let scene = parse("crumple_heap", &text)?;
    let sim = build("crumple_heap", &scene)?;
    // Dropped from at most 1.1 m: free fall gives sqrt(2 g 1.1) = 4.6 m/s; 2x for whipping.
    let mut criteria = Criteria::base(2.0, 2.0 * (2.0 * G * 1.1f64).sqrt());
    // The ground's positional correction does work: a vertex that crosses it within a step is put
    // back on its surface while its neighbours moved on, compressing its springs by up to
    // d = (1 - toi) v h + thickness at once (1/2 k d^2, about 0.1 J for the first corner here,
    // gone within a frame), and so does friction's projection of a sticking vertex back against
    // neighbours the implicit step moved with it (0.2-0.7 J a substep while the heap forms at full
    // resolution, 12 J put in and damped out over the run; 239 J when the held vertices' friction
    // took the springs' start-of-step load as its normal impulse). That work is not observable
    // from outside the collision stage, so energy is reported, not judged; speed, penetration and
    // intersections are (tests/hard_cases.rs bounds the excess at CI resolution).
    criteria.energy = EnergyCheck::NotMeasured;
    criteria.max_penetration = Some(0.006);
    criteria.max_self_intersections = Some(0);
    Ok(Case {
        name: "crumple_heap",
        description: "0.8 m cloth dropped edge-first onto the ground, folding onto itself \
                      (continuous self-collision, impact zones)"
            .into(),
        sim,
        driver: None,
        duration: pick(res, 1.5, 3.0),
        criteria,
    })
}

/// A 0.3 m grid mesh with the defects a garment mesher can produce: a vertex coincident with a
/// corner (zero-length spring, zero-area triangle), a vertex on an edge (zero-area collinear
/// triangle) and a 1 um-high sliver, hanging from two corners.
fn degenerate_mesh(res: Resolution) -> Result<Case, HardError> {
    let name = "degenerate_mesh";
    let n = pick(res, 6usize, 16);
    let size = 0.3;
    let step = size / (n - 1) as f64;
    let mut uv = Vec::new();
    for j in 0..n {
        for i in 0..n {
            uv.push(DVec2::new(i as f64 * step, j as f64 * step));
        }
    }
    let id = |i: usize, j: usize| (j * n + i) as u32;
    let mut tris = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let corner = id(n - 1, n - 1);
    let coincident = uv.len() as u32;
    uv.push(uv[corner as usize]);
    tris.push([corner, id(n - 2, n - 1), coincident]);
    let on_edge = uv.len() as u32;
    uv.push(0.5 * (uv[0] + uv[1]));
    tris.push([id(0, 0), id(1, 0), on_edge]);
    let sliver = uv.len() as u32;
    uv.push(0.5 * (uv[id(0, 1) as usize] + uv[id(1, 1) as usize]) + DVec2::new(0.0, 1e-6));
    tris.push([id(0, 1), id(1, 1), sliver]);
    let z = 0.5;
    let positions: Vec<Vec3> = uv.iter().map(|p| Vec3::new(p.x, p.y, z)).collect();
    let panel =
        Panel::from_triangles("mesh", uv, positions, tris).map_err(|message| HardError::Build {
            case: name,
            message,
        })?;
    let material = Material::default();
    let mut cloth = Cloth::new();
    cloth.add_panel(panel, material);
    cloth.pin(id(0, n - 1));
    cloth.pin(corner);
    let piece = cloth.pieces[0].clone();
    let mut effects = EffectSet::new();
    effects.push_gravity(Gravity::new(Vec3::new(0.0, 0.0, -G), &cloth.mass));
    let s = springs(&piece, SpringKind::Structural);
    let pairs: Vec<(u32, u32)> = s.iter().map(|s| (s.i, s.j)).collect();
    let k = vec![material.stretch; s.len()];
    effects.push(Box::new(Springs::new(
        "stretch",
        s,
        k,
        "cloths[0].material.stretch".into(),
    )));
    let mut st = bending_stencils(&piece, true);
    st.extend(bending_stencils(&piece, false));
    let c = vec![material.bend_warp; st.len()];
    effects.push(Box::new(Bending::new(
        st,
        c,
        "cloths[0].material.bend_warp".into(),
    )));
    let kd = vec![material.damping.spring; pairs.len()];
    effects.push(Box::new(SpringDamping::new(pairs, kd)));
    let air = vec![material.damping.air; cloth.len()];
    effects.push(Box::new(AirDrag::new(&air, &cloth.mass)));
    let sim = Simulation::new(
        cloth,
        effects,
        IntegratorKind::Implicit.build(ImplicitSettings::default()),
        Frames::default(),
        StepSettings {
            dt: 1.0 / 60.0,
            substeps: 1,
            guard: GuardSettings::default(),
        },
    );
    let diag = size * std::f64::consts::SQRT_2;
    let m_total: f64 = sim.cloth.mass.iter().sum();
    let m_min = sim.cloth.mass.iter().copied().fold(f64::INFINITY, f64::min);
    let criteria = Criteria::base(
        Vec3::new(size, size, z).length() + 1.1 * diag,
        (2.0 * G * 1.1 * diag * m_total / m_min).sqrt(),
    );
    Ok(Case {
        name,
        description: format!(
            "{n}x{n} triangle mesh with a coincident vertex (zero-length spring, zero-area \
             triangle), a collinear zero-area triangle and a 1 um sliver, hanging from two corners"
        ),
        sim,
        driver: None,
        duration: pick(res, 2.0, 5.0),
        criteria,
    })
}

fn pinned_inside_obstacle(res: Resolution) -> Result<Case, HardError> {
    let text = fill(
        r#"
effects: [gravity, stretch, shear, bending, damping]
solver: { integrator: implicit, dt: 0.016666666666666666 }
cloths:
  - name: sheet
    grid: { size: [0.6, 0.6], resolution: [@RES@, @RES@], pose: { xyz: [0, 0, 0.5] } }
    material: { thickness: 0.005 }
    pins: [ { near: { point: [0, 0, 0.5], radius: 0.03 } } ]
obstacles:
  - { name: ball, shape: { type: sphere, radius: 0.1 }, pose: { xyz: [0, 0, 0.5] } }
collision: { mode: continuous }
"#,
        &[("RES", pick(res, 13, 31).to_string())],
    );
    let scene = parse("pinned_inside_obstacle", &text)?;
    let sim = build("pinned_inside_obstacle", &scene)?;
    // The sheet falls around the ball from 0.5 m: speeds of free fall over at most 0.6 m, 2x.
    let mut criteria = Criteria::base(1.5, 2.0 * (2.0 * G * 0.6f64).sqrt());
    // The initial state is infeasible: free vertices within the ball are projected onto its
    // surface in the first frame, stretching the springs to the pinned ones once (~17 J here).
    // Energy is judged from the end of that frame on.
    criteria.energy_from_frame = 1;
    Ok(Case {
        name: "pinned_inside_obstacle",
        description: "sheet whose centre vertices are pinned inside a ball it then falls around"
            .into(),
        sim,
        driver: None,
        duration: pick(res, 2.0, 5.0),
        criteria,
    })
}

fn wind(res: Resolution) -> Result<Case, HardError> {
    const V: f64 = 50.0;
    let (nu, nv) = pick(res, (15, 10), (30, 20));
    let text = fill(
        r#"
effects: [gravity, stretch, shear, bending, wind, damping]
solver: { integrator: implicit, dt: 0.005, substeps: 1, guard: { energy_growth: 0.05 } }
wind:
  velocity: [@V@, 0.0, 0.0]
  gusts:
    - { amplitude: [5.0, 0.0, 0.0], frequency: 0.5 }
    - { amplitude: [0.0, 4.0, 1.5], frequency: 1.3, phase: 0.7 }
cloths:
  - name: flag
    grid: { size: [0.9, 0.6], resolution: [@NU@, @NV@], pose: { xyz: [0.45, 0.0, 2.0], rpy: [1.5707963267948966, 0.0, 0.0] } }
    material:
      density: 0.15
      stretch: 1500.0
      shear: 150.0
      bend_warp: 5.0e-5
      bend_weft: 5.0e-5
      damping: { spring: 0.02, air: 0.02 }
    pins: [ { region: left_edge } ]
"#,
        &[
            ("V", V.to_string()),
            ("NU", nu.to_string()),
            ("NV", nv.to_string()),
        ],
    );
    // The guard's default energy_growth (0.5) let one implicit substep gain 11.5 J beyond the
    // wind's work (30 % of the flag's energy) as the flag snapped taut at t = 0.13 s: the single
    // linearised solve overshoots on strongly stretched springs. 0.05 makes the guard halve
    // those substeps (3 in the first second).
    let scene = parse("wind_50_m_s", &text)?;
    let sim = build("wind_50_m_s", &scene)?;
    // Normal drag pushes every vertex toward the wind's (normal) velocity; the fastest wind is
    // 50 + 5 + 4 m/s. A flapping free edge can whip past it: 2x.
    let criteria = Criteria::base(2.0 + 1.5, 2.0 * (V + 9.0));
    Ok(Case {
        name: "wind_50_m_s",
        description: format!(
            "flag (0.9 x 0.6 m, left edge pinned) in {V} m/s wind with 5 m/s gusts, implicit at 200 Hz"
        ),
        sim,
        driver: None,
        duration: pick(res, 1.0, 3.0),
        criteria,
    })
}

fn long_run(res: Resolution) -> Result<Case, HardError> {
    // drape_bot swings a towel held at a corner through a 4 s periodic motion for 10 minutes.
    const PERIOD: [(f64, [f64; 3]); 4] = [
        (0.0, [-1.5, 0.0, 0.0]),
        (1.0, [-0.9, -0.4, 0.8]),
        (2.0, [-1.6, 0.0, -0.4]),
        (3.0, [-1.0, -0.3, 0.4]),
    ];
    let duration = 600.0;
    let mut points = String::new();
    let mut t = 0.0;
    let mut k = 0;
    while t <= duration + 4.0 {
        let (dt, q) = PERIOD[k % 4];
        t = 4.0 * (k / 4) as f64 + dt;
        points.push_str(&format!(
            "      - {{ t: {t}, positions: [{}, {}, {}] }}\n",
            q[0], q[1], q[2]
        ));
        k += 1;
    }
    let text = fill(
        r#"
effects: [gravity, stretch, shear, bending, damping]
solver: { integrator: implicit, dt: @DT@, substeps: @SUB@ }
cloths:
  - name: towel
    grid: { size: [0.4, 0.4], resolution: [@RES@, @RES@], pose: { xyz: [0.879, -0.255, 0.392], rpy: [1.5707963267948966, 0.0, 0.0] } }
    material:
      density: 0.25
      stretch: 1500.0
      shear: 150.0
      bend_warp: 1.0e-4
      bend_weft: 1.0e-4
      damping: { spring: 0.05, air: 0.1 }
      thickness: 0.008
      friction: 0.4
robot:
  urdf: ../urdf/drape_bot.urdf
  trajectory:
    names: [right_shoulder_pitch, right_elbow, right_wrist]
    points:
@POINTS@
  attach:
    - { cloth: towel, link: right_palm, near: { point: [0.0, 0.0, -0.13], radius: @R@ } }
collision: { mode: continuous }
"#,
        &[
            (
                "DT",
                pick(res, "0.03333333333333333", "0.016666666666666666").into(),
            ),
            ("SUB", pick(res, "1", "2").into()),
            ("RES", pick(res, "6", "20").into()),
            ("R", pick(res, "0.09", "0.03").into()),
            ("POINTS", points.trim_end().to_string()),
        ],
    );
    let name = "long_run_10_min";
    let scene = parse(name, &text)?;
    let (sim, driver) = scene
        .build_with_robot()
        .map_err(|source| HardError::Scene { case: name, source })?;
    // The towel hangs within its 0.57 m diagonal of the hand, which stays within ~1.2 m of the
    // root; the hand moves at ~1 m/s and the towel's free corner at a few times that.
    let mut criteria = Criteria::base(2.0, 10.0);
    // Obstacles (the arm) can push the towel: its work is not measured; creep is judged instead:
    // the mean energy over the last minute may differ from the second minute's by 1 % of M g L.
    criteria.energy = EnergyCheck::NotMeasured;
    criteria.max_energy_creep = Some(0.01);
    Ok(Case {
        name,
        description: "drape_bot swings a towel held at one corner through a 4 s periodic motion \
                      for 10 minutes of simulated time"
            .into(),
        sim,
        driver,
        duration,
        criteria,
    })
}
