//! Friction between two cloths, judged on full simulations.

use drape::scene::Scene;
use drape::sim::Simulation;
use drape::Vec3;

fn build(yaml: &str, name: &str) -> Simulation {
    let scene = Scene::from_yaml(yaml, name).unwrap_or_else(|e| panic!("{e}"));
    scene.build().unwrap_or_else(|e| panic!("{e}"))
}

/// Centre of mass and momentum of piece `k`.
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

fn napkin_yaml(mu: f64) -> String {
    let var = |k: &str, d: &str| std::env::var(k).unwrap_or_else(|_| d.to_string());
    let (z, roll, pitch, mat) = (var("NZ", "0.85"), var("NR", "0.12"), var("NP", "0.08"), var("NMAT", "density: 0.2, stretch: 1500.0, shear: 150.0, bend_warp: 2.0e-4, bend_weft: 2.0e-4, damping: { spring: 0.05, air: 0.1 }, thickness: 0.004,"));
    format!(
        r#"
name: napkin_on_towel
duration: 3.0
effects: [gravity, stretch, shear, bending, damping]
solver: {{ integrator: implicit, dt: 0.016666666666666666 }}
cloths:
  - name: towel
    grid: {{ size: [0.7, 0.7], resolution: [28, 28], pose: {{ xyz: [0.0, 0.0, 0.755] }} }}
    material: {{ {mat} friction: {mu} }}
  - name: napkin
    grid: {{ size: [0.4, 0.4], resolution: [20, 20], pose: {{ xyz: [0.0, 0.0, {z}], rpy: [{roll}, {pitch}, 0.0] }} }}
    material: {{ {mat} friction: {mu} }}
obstacles:
  - {{ name: table, shape: {{ type: box, half_extents: [0.6, 0.6, 0.05] }}, pose: {{ xyz: [0.0, 0.0, 0.7] }} }}
collision: {{ mode: continuous, self_collision: true, count_self_intersections: true }}
"#
    )
}

#[test]
#[ignore = "probe"]
fn probe_napkin() {
    for mu in std::env::var("MUS")
        .unwrap_or("0 0.5 1".into())
        .split(' ')
        .map(|m| m.parse::<f64>().unwrap_or(0.5))
    {
        let mut sim = build(&napkin_yaml(mu), "napkin");
        let frames = (3.0 / sim.settings.dt).round() as usize;
        for f in 0..frames {
            let m = sim.step().unwrap_or_else(|e| panic!("{e}"));
            if f % 12 == 0 {
                let (c, p, _) = piece_state(&sim, 1);
                let (ct, pt, _) = piece_state(&sim, 0);
                eprintln!(
                    "mu {mu} t {:.2} napkin {:.4} {:.4} {:.4} p {:.4?} towel {:.4} {:.4} p {:.4?} si {:?} rep {}",
                    m.time, c.x, c.y, c.z, p, ct.x, ct.y, pt, m.self_intersections, m.self_contact.repulsions
                );
            }
        }
    }
}
