//! Edge cases of the input: a degenerate mesh, a vertex pinned inside an obstacle, a cape whose
//! hem starts inside the robot's base, 50 m/s wind, a ten-minute run.

use super::setup::{build, bundled_scene, fill, parse, pick, G};
use super::{Case, Criteria, EnergyCheck, HardError, Resolution};
use crate::cloth::topology::{bending_stencils, springs, SpringKind};
use crate::cloth::{Cloth, Material, Panel};
use crate::effects::{AirDrag, Bending, EffectSet, Gravity, SpringDamping, Springs};
use crate::integrate::{ImplicitSettings, IntegratorKind};
use crate::sim::{Frames, GuardSettings, Simulation, StepSettings};
use crate::Vec3;
use glam::DVec2;

/// A 0.3 m grid mesh with the defects a garment mesher can produce: a vertex coincident with a
/// corner (zero-length spring, zero-area triangle), a vertex on an edge (zero-area collinear
/// triangle) and a 1 um-high sliver, hanging from two corners.
pub(super) fn degenerate_mesh(res: Resolution) -> Result<Case, HardError> {
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
        Panel::from_triangles("mesh", uv, positions, tris).map_err(|message| HardError::Panel {
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

pub(super) fn pinned_inside_obstacle(res: Resolution) -> Result<Case, HardError> {
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
    // The initial state is infeasible: free vertices within the ball are led out of it over
    // the first frames, stretching the springs to the pinned ones once (joules here). Energy is
    // judged from the end of the frame they are all out on.
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

/// robot_cape.yaml with the cape 5 cm longer, its hem 5 cm into drape_bot's 10 cm base box (two
/// rows of vertices): the cloth is led out upwards, the way it came in, while the arms swing.
/// Pushed to each vertex's nearest face instead, the box would end between two rows for good
/// (the edges across it stretched over it, the guard subdividing nearly every step).
pub(super) fn cape_hem_inside_base(res: Resolution) -> Result<Case, HardError> {
    let name = "cape_hem_inside_base";
    let mut scene = bundled_scene(name, "robot_cape.yaml")?;
    let per_side = pick(res, 24, 48);
    let g = &mut scene.cloths[0].grid;
    g.size = [0.6, 0.65];
    g.resolution = [per_side, per_side * 13 / 12];
    g.pose.xyz[2] = 0.375;
    let (sim, driver) = scene
        .build_with_robot()
        .map_err(|source| HardError::Scene { case: name, source })?;
    // As the cape under swinging arms: hands ~0.75 m out at ~1.6 rad/s at most, 1.2 m/s; cloth
    // whipping at 3x that and falling at most its 0.65 m length; within 1.5 m of the root. The
    // led-out hem is not penetration (it is counted as exiting): the layer bound holds throughout.
    let mut criteria = Criteria::base(1.5, 3.0 * 1.2 + (2.0 * G * 0.65).sqrt());
    criteria.energy = EnergyCheck::NotMeasured;
    criteria.max_penetration = Some(0.008);
    Ok(Case {
        name,
        description:
            "robot_cape with its hem hanging 5 cm into drape_bot's base box at the start, \
                      led out while the arms swing"
                .into(),
        sim,
        driver,
        duration: pick(res, 2.0, 4.0),
        criteria,
    })
}

/// robot_drape_arm.yaml with the cloth lowered onto the outstretched arm's axis (z = 0.64 m):
/// the arm lies in the cloth, the patch inside the upper arm, forearm, palm and fingers came in
/// from both sides and leaves across the cloth, to the nearer side, as one, its rim (outside the
/// arm, inside its contact layer) with it. Judged over the first second, while the arm is still:
/// the lead-out moves a vertex at most `EXIT_STEP` of its shortest edge a pass, and the solve
/// follows within a pass, so no edge exceeds `1 + 2 EXIT_STEP` (4/3). The rim leaves with the
/// patch: left to the vertex pass, it would be pushed sideways in the cloth's plane, its edges
/// far past rest (friction 0.5).
pub(super) fn arm_lying_in_cloth(res: Resolution) -> Result<Case, HardError> {
    let name = "arm_lying_in_cloth";
    let mut scene = bundled_scene(name, "robot_drape_arm.yaml")?;
    let per_side = pick(res, 22, 44);
    let g = &mut scene.cloths[0].grid;
    g.resolution = [per_side, per_side];
    g.pose.xyz[2] = 0.64;
    let (sim, driver) = scene
        .build_with_robot()
        .map_err(|source| HardError::Scene { case: name, source })?;
    // Within 1.5 m of the root; the arm is still, so the cloth is at most falling: from its
    // 0.64 m to the floor. The led-out patch is not penetration (it is counted as exiting).
    let mut criteria = Criteria::base(1.5, (2.0 * G * 0.64).sqrt());
    criteria.energy = EnergyCheck::NotMeasured;
    criteria.max_penetration = Some(0.008);
    criteria.max_stretch = Some(1.0 + 2.0 * crate::collide::overlap::EXIT_STEP);
    Ok(Case {
        name,
        description: "robot_drape_arm with the cloth lowered onto the still arm's axis: the \
                      patch inside the arm led out across the cloth"
            .into(),
        sim,
        driver,
        duration: 1.0,
        criteria,
    })
}

pub(super) fn wind(res: Resolution) -> Result<Case, HardError> {
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
    // The guard's default energy_growth (0.5) lets one implicit substep gain a large share of
    // the flag's energy beyond the wind's work as the flag snaps taut early on: the single
    // linearised solve overshoots on strongly stretched springs. 0.05 makes the guard halve
    // those few substeps.
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

pub(super) fn long_run(res: Resolution) -> Result<Case, HardError> {
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
