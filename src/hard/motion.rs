//! Fast and contact cases: an impact at 20 m/s, a robot swinging at its velocity limit, a pinch
//! below the cloth's thickness, a crumpled heap.

use super::setup::{build, fill, parse, pick, G};
use super::{Case, Criteria, EnergyCheck, HardError, Resolution};

pub(super) fn impact(res: Resolution) -> Result<Case, HardError> {
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
    // wall gives 2 V. The sheet's corners whip beyond that as it wraps the ball, to about 3 V at
    // full resolution whatever the substeps per frame (converged: the model's whip), so a
    // blow-up shows above 4 V.
    let mut criteria = Criteria::base(V * duration + 0.3 + 1.0, 4.0 * V);
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

pub(super) fn robot_swing(res: Resolution) -> Result<Case, HardError> {
    // right_shoulder_pitch is limited to 2.0 rad/s and right_wrist to 3.0 rad/s (drape_bot.urdf):
    // both swing at exactly their limit (wrist 0 -> 2.9 rad, its position limit, in 0.9667 s;
    // shoulder 1.9333 rad down past the torso in the same time, and back) after the cloth has
    // settled on the arm for 1 s. The sheet lands on a floor. Without one it falls past the base
    // and the descending hand catches it against base_link; vertices pinched between two facing
    // obstacles sit midway between them (collide/stage.rs), so that does no harm: with the floor
    // moved 5 m down the full-resolution sheet falls freely to it (free fall from 5 m gives
    // 9.9 m/s) without penetrating it.
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

pub(super) fn pinch(res: Resolution) -> Result<Case, HardError> {
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
    // `gap / 2` from each, i.e. `thickness - gap / 2` = 4.25 mm into both layers. (Pushed out of
    // one layer instead, it would land in the other obstacle's solid.)
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

pub(super) fn crumple(res: Resolution) -> Result<Case, HardError> {
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
    // d = (1 - toi) v h + thickness at once (1/2 k d^2, gone within a frame), and so does
    // friction's projection of a sticking vertex back against neighbours the implicit step
    // moved with it (a fraction of a joule a substep while the heap forms at full resolution,
    // put in and damped out over the run). That work is not observable
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
