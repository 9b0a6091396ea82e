//! A mesh-heavy robot (30 links, ~66k collision triangles) under a falling cloth: contacts are
//! found, no vertex gets into a ball, far links are culled, and culling changes nothing.

#[path = "common/heavy_robot.rs"]
mod heavy_robot;
use drape::scene::Scene;
use drape::Vec3;
use heavy_robot::{FAR_LINKS, SPHERE_RADIUS};
use std::f64::consts::PI;

#[test]
fn heavy_robot_catches_the_cloth_without_penetration() {
    let h = heavy_robot::write(24, 24, 0.5);
    assert!(h.triangles > 60_000, "{}", h.triangles);
    let scene = Scene::load(&h.scene).unwrap();
    let (mut sim, driver) = scene.build_with_robot().unwrap();
    let mut driver = driver.unwrap();
    let th = 0.005;
    let frames = (scene.duration / sim.settings.dt).round() as usize;
    let (mut contacts, mut deepest, mut culled_min) = (0, 0.0_f64, usize::MAX);
    let mut worst_inside = f64::NEG_INFINITY;
    for k in 0..frames {
        let t = sim.time() + sim.settings.dt;
        driver.advance(&mut sim, t);
        let m = sim
            .step()
            .unwrap_or_else(|e| panic!("frame {k}: {e}"))
            .clone();
        contacts = contacts.max(m.contacts);
        deepest = deepest.max(m.deepest_penetration);
        culled_min = culled_min.min(m.culled_obstacles);
        // Ball centres move only by the joint rotation about their own centre: fixed.
        for x in &sim.cloth.x {
            for c in &h.centres {
                // The flat facets lie inside the sphere by up to r (1 - cos(pi/stacks) cos(pi/slices)).
                let facet = SPHERE_RADIUS * (1.0 - (PI / 24.0).cos() * (PI / 48.0).cos());
                let d = (*x - Vec3::from(*c)).length() - SPHERE_RADIUS;
                worst_inside = worst_inside.max(th - d - facet);
            }
        }
    }
    eprintln!(
        "contacts {contacts}, deepest {deepest:.2e} m, worst layer intrusion {worst_inside:.2e} m, \
         culled >= {culled_min}"
    );
    assert!(
        contacts > 50,
        "the cloth hardly touched the balls: {contacts}"
    );
    assert!(deepest < 0.1 * th, "stage reports {deepest} m");
    assert!(
        worst_inside < 0.1 * th,
        "a vertex got {worst_inside} m into a ball's layer"
    );
    assert!(
        culled_min >= FAR_LINKS,
        "far links not culled: {culled_min}"
    );
}

#[test]
fn culling_far_links_changes_nothing() {
    let h = heavy_robot::write(16, 8, 0.25);
    let scene = Scene::load(&h.scene).unwrap();
    let run = |cull: bool| {
        let (mut sim, driver) = scene.build_with_robot().unwrap();
        let mut driver = driver.unwrap();
        sim.collision_mut().unwrap().set_culling(cull);
        let mut culled = 0;
        for _ in 0..15 {
            let t = sim.time() + sim.settings.dt;
            driver.advance(&mut sim, t);
            culled = culled.max(sim.step().unwrap().culled_obstacles);
        }
        (sim.cloth.x.clone(), sim.cloth.v.clone(), culled)
    };
    let (x_on, v_on, culled_on) = run(true);
    let (x_off, v_off, culled_off) = run(false);
    assert!(culled_on >= FAR_LINKS, "{culled_on}");
    assert_eq!(culled_off, 0);
    assert_eq!(x_on, x_off);
    assert_eq!(v_on, v_off);
}
