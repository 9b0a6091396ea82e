//! Friction between two cloths, judged on full simulations through `Simulation`: a cloth on a
//! cloth incline follows Coulomb's law (sticks below `tan(theta) = mu`, slides with
//! `g (sin theta - mu cos theta)` above), a napkin dropped on a towel stops where it lands, and
//! the two layers exchange momentum without creating any.

use drape::scene::Scene;
use drape::sim::Simulation;
use drape::Vec3;

const G: f64 = 9.81;

fn build(yaml: &str, name: &str) -> Simulation {
    let scene = Scene::from_yaml(yaml, name).unwrap_or_else(|e| panic!("{name}: {e}"));
    scene.build().unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Centre of mass, momentum and mass of piece `k`.
fn piece_state(sim: &Simulation, k: usize) -> (Vec3, Vec3, f64) {
    let (mut c, mut p, mut m) = (Vec3::ZERO, Vec3::ZERO, 0.0);
    for i in sim.cloth.pieces[k].vertices() {
        let mi = sim.cloth.mass[i];
        c += sim.cloth.x[i] * mi;
        p += sim.cloth.v[i] * mi;
        m += mi;
    }
    (c / m, p, m)
}

fn step(sim: &mut Simulation) -> drape::sim::StepMetrics {
    let m = sim.step().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        m.self_intersections,
        Some(0),
        "layers crossed at t = {}",
        m.time
    );
    m
}

/// A 0.12 m cloth (6x6) resting on a 1 m cloth tilted by `theta` about x and pinned whole (a
/// rigid incline of cloth), both with Coulomb coefficient `mu`, no air drag. Returns the small
/// cloth's centre-of-mass displacement down the slope over `[t1, t2]`, its acceleration down
/// the slope over that window, from its momentum at `t1` and `t2`, and the slipping vertices
/// the step at `t2` reports.
fn incline(theta: f64, mu: f64, t1: f64, t2: f64) -> (f64, f64, usize) {
    let thickness = 0.004;
    // The small cloth starts at rest 2.5 contact distances (two thicknesses) above the
    // incline's plane and drops onto it. Started within `pi/2` contact distances, the pair
    // would count as near in the rest shape (a sheet's own neighbourhood, answered in-plane).
    let lift = 5.0 * thickness;
    let (s, c) = theta.sin_cos();
    let normal = Vec3::new(0.0, -s, c);
    let up_slope = Vec3::new(0.0, c, s);
    let centre = up_slope * 0.25 + normal * lift;
    let material = format!(
        "{{ density: 0.2, stretch: 2000.0, shear: 200.0, bend_warp: 1.0e-4, bend_weft: 1.0e-4, \
         damping: {{ spring: 0.05 }}, thickness: {thickness}, friction: {mu} }}"
    );
    let yaml = format!(
        r#"
name: incline
duration: 2.0
effects: [gravity, stretch, shear, bending, damping]
solver: {{ integrator: implicit, dt: 0.016666666666666666 }}
cloths:
  - name: incline
    grid: {{ size: [0.6, 1.0], resolution: [13, 21], pose: {{ xyz: [0.0, 0.0, 0.0], rpy: [{theta}, 0.0, 0.0] }} }}
    material: {material}
    pins: [ {{ near: {{ point: [0.0, 0.0, 0.0], radius: 2.0 }} }} ]
  - name: block
    grid: {{ size: [0.12, 0.12], resolution: [6, 6], pose: {{ xyz: [{}, {}, {}], rpy: [{theta}, 0.0, 0.0] }} }}
    material: {material}
collision: {{ mode: continuous, self_collision: true, count_self_intersections: true }}
"#,
        centre.x, centre.y, centre.z
    );
    let mut sim = build(&yaml, "incline");
    let dt = sim.settings.dt;
    let (k1, k2) = ((t1 / dt).round() as usize, (t2 / dt).round() as usize);
    let down = -up_slope;
    let (mut c1, mut p1, mut slipping) = (Vec3::ZERO, Vec3::ZERO, 0);
    for frame in 1..=k2 {
        slipping = step(&mut sim).slipping_vertices;
        if frame == k1 {
            (c1, p1, _) = piece_state(&sim, 1);
        }
    }
    let (c2, p2, m) = piece_state(&sim, 1);
    let window = (k2 - k1) as f64 * dt;
    let accel = (p2 - p1).dot(down) / m / window;
    ((c2 - c1).dot(down), accel, slipping)
}

/// Coulomb's threshold and sliding law on a cloth incline, `mu` 0.5 (`tan(theta) = mu` at
/// 26.6 degrees): at 20 and 24 degrees the small cloth stays, at 30 and 35 it slides with
/// `g (sin theta - mu cos theta)` within 5 %, measured over 0.3 s to 0.7 s (sliding from the
/// start, it stays on the incline for that window). Staying means moving less than in-solve
/// friction's creep allows: a sticking pair's drag is `mu N / STICK_SPEED` per m/s, so under a
/// load below `mu N` it creeps under 0.1 mm/s, 0.04 mm over the window; 1 mm is well above
/// that and 20 times below the slide at 30 degrees. The steps report no slipping vertex on the
/// cloth that stays, and some on the one that slides.
#[test]
fn cloth_on_a_cloth_incline_sticks_below_tan_theta_mu_and_slides_with_coulombs_acceleration() {
    let mu = 0.5;
    let (t1, t2) = (0.3, 0.7);
    for degrees in [20.0_f64, 24.0] {
        let (moved, accel, slipping) = incline(degrees.to_radians(), mu, t1, t2);
        eprintln!(
            "{degrees} deg: moved {moved:.6} m, acceleration {accel:.4} m/s^2, {slipping} slipping"
        );
        assert!(
            moved.abs() < 1e-3 && slipping == 0,
            "at {degrees} degrees (tan < mu) the cloth moved {moved:.5} m, {slipping} vertices slipping"
        );
    }
    for degrees in [30.0_f64, 35.0] {
        let theta = degrees.to_radians();
        let expect = G * (theta.sin() - mu * theta.cos());
        let (moved, accel, slipping) = incline(theta, mu, t1, t2);
        eprintln!(
            "{degrees} deg: moved {moved:.4} m, acceleration {accel:.4} (analytic {expect:.4}) \
             m/s^2, {slipping} slipping"
        );
        assert!(
            (accel - expect).abs() <= 0.05 * expect && slipping > 0,
            "at {degrees} degrees: acceleration {accel:.4} m/s^2, Coulomb's {expect:.4}; \
             {slipping} vertices slipping"
        );
    }
}

/// The napkin scene: a 0.7 m towel lying flat on a table and a 0.4 m napkin (20x20) dropped
/// 19 cm onto it, tilted by 0.25 rad about x and 0.1 rad about y, both with coefficient `mu`.
fn napkin_yaml(mu: f64) -> String {
    format!(
        r#"
name: napkin_on_towel
duration: 3.0
effects: [gravity, stretch, shear, bending, damping]
solver: {{ integrator: implicit, dt: 0.016666666666666666 }}
cloths:
  - name: towel
    grid: {{ size: [0.7, 0.7], resolution: [28, 28], pose: {{ xyz: [0.0, 0.0, 0.755] }} }}
    material: {{ friction: {mu} }}
  - name: napkin
    grid: {{ size: [0.4, 0.4], resolution: [20, 20], pose: {{ xyz: [0.0, 0.0, 0.95], rpy: [0.25, 0.1, 0.0] }} }}
    material: {{ friction: {mu} }}
obstacles:
  - {{ name: table, shape: {{ type: box, half_extents: [0.6, 0.6, 0.05] }}, pose: {{ xyz: [0.0, 0.0, 0.7] }} }}
collision: {{ mode: continuous, self_collision: true, count_self_intersections: true }}
"#
    )
}

/// The napkin's horizontal centre-of-mass travel from the frame it first touches the towel
/// (a napkin vertex within two contact distances of the towel's top) over the next `span`
/// seconds, the largest distance from that point.
fn napkin_slide(mu: f64, span: f64) -> f64 {
    let mut sim = build(&napkin_yaml(mu), "napkin_on_towel");
    let dt = sim.settings.dt;
    let towel_top = sim.cloth.pieces[0]
        .vertices()
        .map(|i| sim.cloth.x[i].z)
        .fold(f64::NEG_INFINITY, f64::max);
    let reach = towel_top + 2.0 * 0.01;
    let mut landed = None;
    let mut farthest: f64 = 0.0;
    for _ in 0..(3.0 / dt).round() as usize {
        step(&mut sim);
        let (c, _, _) = piece_state(&sim, 1);
        let flat = Vec3::new(c.x, c.y, 0.0);
        match landed {
            None => {
                let lowest = sim.cloth.pieces[1]
                    .vertices()
                    .map(|i| sim.cloth.x[i].z)
                    .fold(f64::INFINITY, f64::min);
                if lowest < reach {
                    landed = Some((sim.time(), flat));
                }
            }
            Some((t, at)) if sim.time() <= t + span => {
                farthest = farthest.max((flat - at).length())
            }
            Some(_) => break,
        }
    }
    assert!(landed.is_some(), "the napkin never reached the towel");
    farthest
}

/// Coulomb friction at 0.5 or 1.0 stops a napkin landing at under 2 m/s within millimetres of
/// sliding (`v^2 / (2 mu g)`: 4 mm for a tangential 0.2 m/s at mu 0.5); the napkin's centre
/// stays within 4 cm of where it touched the towel over the next 1.6 s.
#[test]
fn a_napkin_dropped_on_a_towel_stops_where_it_lands() {
    for mu in [0.5, 1.0] {
        let slide = napkin_slide(mu, 1.6);
        eprintln!("mu {mu}: napkin slid {slide:.4} m");
        assert!(slide < 0.04, "mu {mu}: the napkin slid {slide:.4} m");
    }
}

/// Momentum between layers: no gravity, no obstacle, no air drag, a 0.2 m cloth thrown at 0.5
/// m/s along x and 0.3 m/s down onto a free 0.4 m cloth just under it (coefficient 0.5). Every
/// force between them (repulsion and CCD impulses, friction, the solve's layer springs) is
/// equal and opposite, and the cloths' own forces are internal, so the total momentum stays
/// what it was to the solver's tolerance: each backward-Euler solve leaves a relative residual
/// of at most `cg_tolerance` (1e-5) in `M dv`, a change of the momentum of that order of the
/// step's `|M dv|`, itself below the cloths' momentum `|p|`; over the 30 frames that is under
/// `30 * 2 * 1e-5 |p|` with two substeps a frame at most, bounded here by `1e-3 |p|`. The
/// lower cloth must take up a share of the momentum (the layers touched): its x momentum ends
/// above a tenth of the total.
#[test]
fn a_cloth_sliding_over_a_free_cloth_conserves_momentum() {
    let yaml = r#"
name: layers_in_space
duration: 0.5
effects: [stretch, shear, bending, damping]
solver: { integrator: implicit, dt: 0.016666666666666666 }
cloths:
  - name: lower
    grid: { size: [0.4, 0.4], resolution: [17, 17], pose: { xyz: [0.0, 0.0, 0.0] } }
    material: { density: 0.2, damping: { spring: 0.05 }, thickness: 0.004, friction: 0.5 }
  - name: upper
    grid: { size: [0.2, 0.2], resolution: [9, 9], pose: { xyz: [-0.05, 0.0, 0.0095], rpy: [0.0, 0.05, 0.0] } }
    material: { density: 0.2, damping: { spring: 0.05 }, thickness: 0.004, friction: 0.5 }
collision: { mode: continuous, self_collision: true, count_self_intersections: true }
"#;
    let mut sim = build(yaml, "layers_in_space");
    for i in sim.cloth.pieces[1].vertices() {
        sim.cloth.v[i] = Vec3::new(0.5, 0.0, -0.3);
    }
    let total = |sim: &Simulation| piece_state(sim, 0).1 + piece_state(sim, 1).1;
    let p0 = total(&sim);
    let mut repulsions = 0;
    for _ in 0..30 {
        repulsions += step(&mut sim).self_contact.repulsions;
    }
    let p1 = total(&sim);
    let lower = piece_state(&sim, 0).1;
    eprintln!("momentum {p0:.6?} -> {p1:.6?} (lower cloth {lower:.6?}); {repulsions} repulsions");
    assert!(
        (p1 - p0).length() <= 1e-3 * p0.length(),
        "momentum {p0:?} became {p1:?}"
    );
    assert!(
        repulsions > 0 && lower.x > 0.1 * p0.x,
        "the layers hardly met: {repulsions} repulsions, lower cloth's momentum {lower:?}"
    );
}

/// Without friction anywhere (towel, napkin and table at 0), nothing can push the two cloths
/// sideways as a whole: the table's normal is vertical, and every cloth-cloth impulse and force
/// is equal and opposite. Their total horizontal momentum stays zero (to the solves' tolerance,
/// bounded here by 1e-3 of the napkin's momentum as it lands) while the napkin lands tilted and
/// settles; a tilted response that the obstacle is made to carry (heavier towel vertices on the
/// table) would leave the pair sliding off together. The napkin's own horizontal travel is
/// printed: what it gets from landing tilted on a frictionless towel.
#[test]
fn without_friction_a_tilted_landing_leaves_the_layers_no_net_sideways_momentum() {
    let mut sim = build(&napkin_yaml(0.0), "napkin_on_towel");
    let dt = sim.settings.dt;
    let mut landing: f64 = 0.0;
    let mut worst: f64 = 0.0;
    let start = piece_state(&sim, 1).0;
    for _ in 0..(1.8 / dt).round() as usize {
        step(&mut sim);
        let (napkin, towel) = (piece_state(&sim, 1).1, piece_state(&sim, 0).1);
        landing = landing.max(napkin.length());
        let sideways = Vec3::new(napkin.x + towel.x, napkin.y + towel.y, 0.0);
        worst = worst.max(sideways.length());
    }
    let moved = piece_state(&sim, 1).0 - start;
    eprintln!(
        "largest total sideways momentum {worst:.3e} N s against {landing:.3e} N s landing; \
         napkin moved {:.4} m sideways",
        Vec3::new(moved.x, moved.y, 0.0).length()
    );
    assert!(
        worst <= 1e-3 * landing,
        "the layers gained {worst:.3e} N s sideways (landing momentum {landing:.3e} N s)"
    );
}
