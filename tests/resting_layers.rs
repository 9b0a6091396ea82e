//! A cloth resting on another cloth, judged on the full simulation: the layer underneath carries
//! the weight of the one on top (Newton's third law through cloth-cloth contact), and the two
//! stay apart.

use drape::effects::State;
use drape::scene::Scene;
use drape::Vec3;

/// A towel (0.24 m square, 0.6 kg/m^2) dropped 2 mm onto the middle of a hammock (0.6 m square,
/// pinned along two opposite edges) and left to settle, self-collision on. Over the last second
/// of 4 s, the contact force the towel puts on the hammock, `C = -sum f` over the hammock's free
/// vertices of every force the scene's effects put on them (gravity, springs, damping: what
/// holds a vertex still but the contact), averaged over the frames, is the towel's weight
/// `M g` (0.339 N) downwards, and the towel's own `sum f` is the same force upwards: Newton's
/// third law across the contact. Tolerance: 5 % of the weight for what is left of the settling
/// motion (the cloth's momentum change over the second, measured, is under 0.1 %) and the
/// averaging over frame ends. A solve that held the towel up without loading the hammock (an
/// anchor that follows the hammock but does not push it) would give a contact force of 0.
#[test]
fn a_towel_on_a_hammock_bows_it_with_its_weight() {
    let yaml = r#"
name: hammock
duration: 4.0
effects: [gravity, stretch, shear, bending, damping]
solver: { integrator: implicit, dt: 0.016666666666666666 }
cloths:
  - name: hammock
    grid: { size: [0.6, 0.6], resolution: [13, 13], pose: { xyz: [0.0, 0.0, 0.5] } }
    material: { density: 0.2, stretch: 200.0, shear: 20.0, bend_warp: 1.0e-5, bend_weft: 1.0e-5, damping: { spring: 0.1, air: 0.5 }, thickness: 0.005, friction: 0.3 }
    pins: [ { region: left_edge }, { region: right_edge } ]
  - name: towel
    grid: { size: [0.24, 0.24], resolution: [7, 7], pose: { xyz: [0.0, 0.0, 0.512] } }
    material: { density: 0.6, stretch: 200.0, shear: 20.0, bend_warp: 1.0e-5, bend_weft: 1.0e-5, damping: { spring: 0.1, air: 0.5 }, thickness: 0.005, friction: 0.3 }
collision: { mode: continuous, self_collision: true, count_self_intersections: true }
"#;
    let scene = Scene::from_yaml(yaml, "hammock").unwrap_or_else(|e| panic!("{e}"));
    let mut sim = scene.build().unwrap_or_else(|e| panic!("{e}"));
    let g = 9.81;
    let pieces = sim.cloth.pieces.clone();
    let (hammock, towel) = (pieces[0].vertices(), pieces[1].vertices());
    let towel_mass: f64 = towel.clone().map(|i| sim.cloth.mass[i]).sum();
    let weight = towel_mass * g;
    let pinned: Vec<usize> = sim
        .cloth
        .kinematic
        .iter()
        .map(|(i, _)| *i as usize)
        .collect();
    let free_hammock: Vec<usize> = hammock.filter(|i| !pinned.contains(i)).collect();
    let frames = (4.0 / sim.settings.dt).round() as usize;
    let averaged = frames - (1.0 / sim.settings.dt).round() as usize;
    let (mut contact, mut support, mut count) = (Vec3::ZERO, Vec3::ZERO, 0.0);
    let momentum = |sim: &drape::sim::Simulation, idx: &mut dyn Iterator<Item = usize>| {
        idx.map(|i| sim.cloth.v[i] * sim.cloth.mass[i])
            .sum::<Vec3>()
    };
    let mut p_start = Vec3::ZERO;
    let mut f = vec![Vec3::ZERO; sim.cloth.len()];
    for frame in 0..frames {
        let m = sim.step().unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            m.self_intersections,
            Some(0),
            "layers crossed at t = {}",
            m.time
        );
        if frame + 1 == averaged {
            p_start = momentum(&sim, &mut (0..sim.cloth.len()));
        }
        if frame < averaged {
            continue;
        }
        f.iter_mut().for_each(|x| *x = Vec3::ZERO);
        let s = State {
            t: sim.time(),
            x: &sim.cloth.x,
            v: &sim.cloth.v,
        };
        sim.effects().forces(&s, &mut f);
        contact -= free_hammock.iter().map(|&i| f[i]).sum::<Vec3>();
        support -= towel.clone().map(|i| f[i]).sum::<Vec3>();
        count += 1.0;
    }
    let (contact, support) = (contact / count, support / count);
    let drift = (momentum(&sim, &mut (0..sim.cloth.len())) - p_start).length();
    eprintln!(
        "towel weight {weight:.4} N; contact on the hammock {contact:.4?} N; on the towel \
         {support:.4?} N; momentum change over the last second {drift:.2e} N s"
    );
    let tol = 0.05 * weight;
    assert!(
        (contact.z + weight).abs() <= tol,
        "the hammock carries {:.4} N of the towel's {weight:.4} N",
        -contact.z
    );
    assert!(
        (support.z - weight).abs() <= tol,
        "the towel is held up by {:.4} N against its weight {weight:.4} N",
        support.z
    );
    // The towel lies on the hammock, not beside or under it.
    let lowest_towel = towel
        .clone()
        .map(|i| sim.cloth.x[i].z)
        .fold(f64::INFINITY, f64::min);
    let middle = free_hammock
        .iter()
        .map(|&i| sim.cloth.x[i])
        .filter(|p| p.x.abs() < 0.05 && p.y.abs() < 0.05)
        .map(|p| p.z)
        .fold(f64::INFINITY, f64::min);
    assert!(
        lowest_towel > middle,
        "towel at {lowest_towel:.4} m, hammock's middle at {middle:.4} m"
    );
}
