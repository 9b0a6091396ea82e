//! Cloth resting on a static box's edges must come to rest: after settling, the kinetic energy
//! decays under air damping and friction instead of being fed by the contact response.

use drape::collide::{DetectionMode, ResponseMode};
use drape::integrate::IntegratorKind;
use drape::scene::Scene;

/// A strap (0.5 m x 0.1 m) laid across the top of a 0.2 m wide box so both ends hang over the
/// two top edges, like the shirt's shoulder straps on the torso.
fn strap_scene(air: f64) -> Scene {
    let yaml = format!(
        r#"
name: strap
duration: 5.0
effects: [gravity, stretch, shear, bending, damping]
solver: {{ integrator: implicit, dt: 0.016666666666666666, substeps: 2 }}
cloths:
  - name: strap
    grid: {{ size: [0.5, 0.1], resolution: [26, 6], pose: {{ xyz: [0.013, 0.0, 0.712] }} }}
    material:
      density: 0.2
      stretch: 1000.0
      shear: 100.0
      bend_warp: 1.0e-4
      bend_weft: 1.0e-4
      damping: {{ spring: 0.05, air: {air} }}
      thickness: 0.006
      friction: 0.5
obstacles:
  - {{ name: torso, shape: {{ type: box, half_extents: [0.1, 0.2, 0.2] }}, pose: {{ xyz: [0.0, 0.0, 0.5] }} }}
collision: {{ mode: continuous }}
"#
    );
    Scene::from_yaml(&yaml, "contact_rest").unwrap_or_else(|e| panic!("{e}"))
}

struct Rest {
    /// Kinetic energy at the end (J).
    ke: f64,
    /// Largest kinetic energy over the last second (J).
    ke_tail: f64,
    /// Largest vertex speed over the last second (m/s).
    speed_tail: f64,
    /// Vertices faster than 1 cm/s at the end.
    fast: usize,
    contacts: usize,
}

fn settle(scene: &Scene, seconds: f64) -> Rest {
    let mut sim = scene.build().unwrap_or_else(|e| panic!("{e}"));
    let steps = (seconds / sim.settings.dt).round() as usize;
    let tail = (1.0 / sim.settings.dt).round() as usize;
    let mut out = Rest {
        ke: 0.0,
        ke_tail: 0.0,
        speed_tail: 0.0,
        fast: 0,
        contacts: 0,
    };
    for k in 0..steps {
        let m = sim.step().unwrap_or_else(|e| panic!("{e}"));
        if k + tail >= steps {
            out.ke_tail = out.ke_tail.max(m.kinetic_energy);
            out.speed_tail = out.speed_tail.max(m.max_speed);
        }
        out.ke = m.kinetic_energy;
        out.contacts = m.contacts;
    }
    out.fast = sim.cloth.v.iter().filter(|v| v.length() > 0.01).count();
    out
}

/// Air damping of the strap tests (1/s): free motion loses kinetic energy as `exp(-2 c t)`.
const AIR: f64 = 2.0;
/// Settling time (s).
const SETTLE: f64 = 4.0;

/// Energy scale of the drape: the hanging ends (~0.4 of the strap's 0.01 kg) fall ~0.1 m.
fn fall_energy() -> f64 {
    0.4 * 0.5 * 0.1 * 0.2 * 9.81 * 0.1
}

/// Strict rest: after the fall (~1 s) the kinetic energy decays at least like free damped
/// motion, `E_fall exp(-2 c (T - 1))` (~3e-8 J here; friction and contacts only remove
/// energy), and no vertex moves faster than 1 cm/s.
fn assert_strict(label: &str, r: &Rest) {
    let bound = fall_energy() * (-2.0 * AIR * (SETTLE - 1.0)).exp();
    assert!(
        r.ke < bound && r.fast == 0,
        "{label}: ke {:.3e} J (bound {bound:.3e}), {} vertices above 1 cm/s",
        r.ke,
        r.fast
    );
}

fn strap(integrator: IntegratorKind, mode: DetectionMode, response: ResponseMode) -> Rest {
    let mut scene = strap_scene(AIR);
    scene.solver.integrator = integrator;
    if integrator == IntegratorKind::SymplecticEuler {
        scene.solver.substeps = 40;
    }
    scene.collision.mode = mode;
    scene.collision.response = response;
    let r = settle(&scene, SETTLE);
    eprintln!(
        "{integrator:?} {mode:?} {response:?}: ke {:.3e} ke_tail {:.3e} speed_tail {:.3e} \
         fast {} contacts {}",
        r.ke, r.ke_tail, r.speed_tail, r.fast, r.contacts
    );
    r
}

/// Settles the strap with `integrator` in every detection mode and response and checks strict
/// rest, with the strap on the box.
fn assert_rest_everywhere(integrator: IntegratorKind) {
    for mode in [
        DetectionMode::Continuous,
        DetectionMode::Proximity,
        DetectionMode::Spheres,
    ] {
        for response in [ResponseMode::Both, ResponseMode::Projection] {
            let r = strap(integrator, mode, response);
            assert_strict(&format!("{integrator:?} {mode:?} {response:?}"), &r);
            assert!(
                r.contacts > 10,
                "{mode:?} {response:?}: strap not on the box"
            );
        }
    }
}

/// The full acceptance with the implicit solver: every detection mode and response comes to
/// strict rest. With the filter in spheres mode the strap used to stay in a period-2 cycle at
/// 2 cm/s (two vertices just outside the contact band). Before box edges were springs inside the
/// solve, the filter with box-edge features crept (the edge's push by position after the solve,
/// undone by the next solve) and projection kept ~1e-7 J at up to 0.15 m/s.
#[test]
fn strap_over_box_edges_comes_to_rest_with_the_implicit_solver() {
    assert_rest_everywhere(IntegratorKind::Implicit);
}

/// Symplectic Euler (40 substeps) does not settle at this stiffness even without features:
/// 1.6e-7 J and 7 vertices above 1 cm/s in continuous mode, where the bound is 2.4e-8 J. Its
/// contacts are answered only after the step, by position (it has no solve to take them).
#[test]
#[ignore = "known gap: symplectic Euler's post-step contact response keeps the strap moving"]
fn strap_over_box_edges_comes_to_rest_with_symplectic_euler() {
    assert_rest_everywhere(IntegratorKind::SymplecticEuler);
}

/// The shirt of config/shirt.yaml hanging on drape_bot's torso (the garment scene): kinetic energy
/// and fast vertices over its last simulated second.
fn shirt_rest(seconds: f64) -> Rest {
    use drape::garment::dress;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("config/shirt.yaml");
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let mut bare = scene.clone();
    bare.garments.clear();
    let (mut sim, mut driver) = bare.build_with_robot().unwrap_or_else(|e| panic!("{e}"));
    dress(
        &mut sim,
        &scene.garments,
        &scene.effect_plan(),
        driver.as_mut(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut driver = driver.unwrap_or_else(|| panic!("shirt scene has a robot"));
    let steps = (seconds / sim.settings.dt).round() as usize;
    let tail = (1.0 / sim.settings.dt).round() as usize;
    let mut out = Rest {
        ke: 0.0,
        ke_tail: 0.0,
        speed_tail: 0.0,
        fast: 0,
        contacts: 0,
    };
    for k in 0..steps {
        let next = sim.time() + sim.settings.dt;
        driver.advance(&mut sim, next);
        let m = sim.step().unwrap_or_else(|e| panic!("{e}"));
        if k + tail >= steps {
            out.ke_tail = out.ke_tail.max(m.kinetic_energy);
            out.speed_tail = out.speed_tail.max(m.max_speed);
        }
        out.ke = m.kinetic_energy;
        out.contacts = m.contacts;
    }
    out.fast = sim.cloth.v.iter().filter(|v| v.length() > 0.1).count();
    out
}

/// The shirt scene settles far more than before (before: ke 7.4e-4 J, 146 vertices above
/// 0.1 m/s, 1.09 m/s over the last second; after: 7 vertices, peak energy 2e-4 to 5e-4 J
/// depending on round-off, since a few strap vertices still stick and slip on the box edges).
/// Since friction of filter-held vertices takes the filter's impulse from the implicit step
/// instead of the start-of-step spring load (which overstated it up to 1e3 times and pumped the
/// crumple heap, see tests/hard_cases.rs), 48 vertices, ke 2.8e-4 J, 0.52 m/s.
/// The bound (60 vertices above 0.1 m/s) catches a return of the pumping of whole strap
/// regions; full rest is a known gap (the ignored test above).
#[test]
fn shirt_on_torso_stops_pumping() {
    let r = shirt_rest(5.0);
    eprintln!(
        "shirt: ke {:.3e} ke_tail {:.3e} speed_tail {:.3e} fast(>0.1) {} contacts {}",
        r.ke, r.ke_tail, r.speed_tail, r.fast, r.contacts
    );
    assert!(r.fast < 60, "{} vertices above 0.1 m/s", r.fast);
}

/// A sheet (0.4 m, 2 cm spacing, 8 mm thick) dropped diagonally over the corner of a static box
/// so that it drapes over the corner and its three edges, with the scene's friction.
fn corner_scene(turn: f64) -> Scene {
    let yaml = format!(
        r#"
name: corner
duration: 3.0
effects: [gravity, stretch, shear, bending, damping]
solver: {{ integrator: implicit, dt: 0.016666666666666666, substeps: 2 }}
cloths:
  - name: sheet
    grid: {{ size: [0.4, 0.4], resolution: [21, 21], pose: {{ xyz: [0.1, 0.1, 0.64], rpy: [0.0, 0.0, {turn}] }} }}
    material:
      density: 0.2
      stretch: 1500.0
      shear: 150.0
      bend_warp: 1.0e-4
      bend_weft: 1.0e-4
      damping: {{ spring: 0.05, air: 0.1 }}
      thickness: 0.008
      friction: 0.5
obstacles:
  - {{ name: block, shape: {{ type: box, half_extents: [0.1, 0.1, 0.1] }}, pose: {{ xyz: [0.0, 0.0, 0.5] }} }}
collision: {{ mode: continuous }}
"#
    );
    Scene::from_yaml(&yaml, "contact_rest").unwrap_or_else(|e| panic!("{e}"))
}

/// Draped over a box corner, the cloth lies still: no edge of it is pushed off the corner and
/// pulled back by the next solve. Judged over the last two of three seconds (landed at 0.1 s):
/// - the fastest vertex within free fall from the highest start to the lowest a vertex can
///   hang (the box top less the sheet's half diagonal), `sqrt(2 g H)` = 2.5 m/s. Before a box
///   edge's contact closest at its corner took the separation as its normal, a cloth edge 8 mm
///   above the corner read a 1 mm gap along the two edges' plane normal and was pushed 7 mm
///   sideways every substep: 10.2 m/s at `turn` 0;
/// - the largest edge within the landing's impact bound plus 10 %, `1.1 (1 + 2 v / c + M g /
///   k)` (v from the 3.2 cm drop, `c` the spacing times `sqrt(k / m)`, M the whole sheet);
/// - no guard subdivision.
#[test]
fn a_sheet_draped_over_a_box_corner_lies_still() {
    let g = 9.81;
    let (side, spacing, density, k, top, start): (f64, f64, f64, f64, f64, f64) =
        (0.4, 0.02, 0.2, 1500.0, 0.6, 0.64);
    let half_diagonal = side * std::f64::consts::FRAC_1_SQRT_2;
    let speed_bound = (2.0 * g * (start - (top - half_diagonal))).sqrt();
    let v = (2.0 * g * (start - top - 0.008)).sqrt();
    let m = density * spacing * spacing;
    let c = spacing * (k / m).sqrt();
    let sheet_weight = density * side * side * g;
    let stretch_bound = 1.1 * (1.0 + 2.0 * v / c + sheet_weight / k);
    for turn in [0.0, 0.3, 0.785] {
        let scene = corner_scene(turn);
        let mut sim = scene.build().unwrap_or_else(|e| panic!("{e}"));
        let edges: Vec<(usize, usize, f64)> = (sim.cloth.triangles.iter())
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .map(|(a, b)| (a as usize, b as usize))
            .filter(|(a, b)| a < b)
            .map(|(a, b)| (a, b, (sim.cloth.x[a] - sim.cloth.x[b]).length()))
            .collect();
        let (mut stretch, mut subdivisions, mut speed) = (0.0f64, 0, 0.0f64);
        for k in 0..180 {
            let m = sim.step().unwrap_or_else(|e| panic!("{e}"));
            if k < 60 {
                continue;
            }
            subdivisions += m.subdivisions;
            speed = speed.max(m.max_speed);
            let s = (edges.iter())
                .map(|&(a, b, r)| (sim.cloth.x[a] - sim.cloth.x[b]).length() / r)
                .fold(0.0, f64::max);
            stretch = stretch.max(s);
        }
        eprintln!("turn {turn}: stretch {stretch:.4} subdivisions {subdivisions} speed {speed:.3}");
        assert!(
            speed <= speed_bound,
            "turn {turn}: a vertex at {speed:.2} m/s (bound {speed_bound:.2})"
        );
        assert!(
            stretch <= stretch_bound,
            "turn {turn}: an edge {stretch:.3}x rest (bound {stretch_bound:.3})"
        );
        assert_eq!(subdivisions, 0, "turn {turn}");
    }
}
