//! Property: any valid material, step, integrator and cloth size either runs finite or stops with
//! the documented `DivergenceError` (naming the cloth); positions, velocities and the ROS messages
//! made from them are never NaN. Case counts are bounded so the file runs in seconds.

use drape::integrate::IntegratorKind;
use drape::scene::Scene;
use drape::sim::DivergencePolicy;
use proptest::prelude::*;

/// A hanging sheet; every parameter comes from the strategy.
#[allow(clippy::too_many_arguments)]
fn scene(
    size: f64,
    res: usize,
    density: f64,
    stretch: f64,
    bend: f64,
    damping: (f64, f64),
    integrator: IntegratorKind,
    dt: f64,
    policy: DivergencePolicy,
) -> Scene {
    let text = format!(
        "effects: [gravity, stretch, shear, bending, twist, damping]\n\
         solver: {{ integrator: {}, dt: {dt:e}, guard: {{ policy: {policy}, max_subdivisions: 4 }} }}\n\
         cloths:\n  - name: sheet\n    grid: {{ size: [{size:e}, {size:e}], resolution: [{res}, {res}] }}\n\
         \x20   material: {{ density: {density:e}, stretch: {stretch:e}, shear: {:e}, bend_warp: {bend:e}, \
         bend_weft: {bend:e}, twist: {:e}, damping: {{ spring: {:e}, air: {:e} }} }}\n\
         \x20   pins: [ {{ region: top_left }}, {{ region: top_right }} ]\n",
        integrator.name(),
        0.1 * stretch,
        0.1 * bend,
        damping.0,
        damping.1,
    );
    Scene::from_yaml(&text, "prop").expect("the strategy only makes valid scenes")
}

fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.ln()..hi.ln()).prop_map(f64::exp)
}

fn integrator() -> impl Strategy<Value = IntegratorKind> {
    prop::sample::select(IntegratorKind::ALL.to_vec())
}

fn policy() -> impl Strategy<Value = DivergencePolicy> {
    prop::sample::select(vec![DivergencePolicy::Subdivide, DivergencePolicy::Stop])
}

/// Case count: the bounded default, or `PROPTEST_CASES` for a longer run.
fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(48), ..ProptestConfig::default() })]

    #[test]
    fn random_materials_run_finite_or_stop_with_the_documented_error(
        size in log_uniform(0.01, 10.0),
        res in 2usize..8,
        density in log_uniform(1e-3, 1e2),
        stretch in log_uniform(1.0, 1e7),
        bend in log_uniform(1e-8, 1e-1),
        damping in (0.0..1.0f64, 0.0..2.0f64),
        integrator in integrator(),
        dt in log_uniform(1e-4, 0.05),
        policy in policy(),
    ) {
        let s = scene(size, res, density, stretch, bend, damping, integrator, dt, policy);
        let mut sim = s.build().expect("valid scene builds");
        for _ in 0..8 {
            match sim.step() {
                Ok(m) => {
                    prop_assert!(m.kinetic_energy.is_finite() && m.potential_energy.is_finite());
                }
                Err(e) => {
                    // The documented error: names the cloth and a vertex of it, and the guard
                    // restored the last good state.
                    let msg = e.to_string();
                    prop_assert!(msg.contains("cloth 'sheet'"), "{}", msg);
                    prop_assert!(e.vertex < sim.cloth.len());
                    // Advice fits the run: an implicit run is not told to switch to implicit.
                    prop_assert!(
                        e.integrator != "implicit" || !msg.contains("use the implicit integrator"),
                        "{}", msg
                    );
                    prop_assert!(sim.cloth.x.iter().chain(&sim.cloth.v).all(|p| p.is_finite()));
                    break;
                }
            }
            prop_assert!(
                sim.cloth.x.iter().chain(&sim.cloth.v).all(|p| p.is_finite()),
                "non-finite state without a DivergenceError"
            );
        }
        check_messages(&sim)?;
    }
}

#[cfg(feature = "ros")]
fn check_messages(sim: &drape::sim::Simulation) -> Result<(), TestCaseError> {
    use drape::ros::msg::{ColorRGBA, Distro, Time};
    let c = &sim.cloth;
    let normals = c.vertex_normals();
    prop_assert!(normals.iter().all(|n| n.is_finite()), "non-finite normal");
    let cloud = drape::ros::point_cloud(Time::from_nanos(1), "world", &c.x, &normals);
    prop_assert_eq!(cloud.data.len(), 24 * c.len());
    for chunk in cloud.data.chunks_exact(4) {
        let v = f32::from_le_bytes([chunk[0], chunk[1], chunk[2], chunk[3]]);
        prop_assert!(v.is_finite(), "non-finite float in PointCloud2");
    }
    let marker = drape::ros::mesh_marker(
        Distro::Jazzy,
        Time::from_nanos(1),
        "world",
        "cloth",
        &c.x,
        &c.triangles,
        ColorRGBA::new(1.0, 1.0, 1.0, 1.0),
    );
    prop_assert_eq!(marker.points.len(), 3 * c.triangles.len());
    prop_assert!(marker
        .points
        .iter()
        .all(|p| p.x.is_finite() && p.y.is_finite() && p.z.is_finite()));
    Ok(())
}

#[cfg(not(feature = "ros"))]
fn check_messages(sim: &drape::sim::Simulation) -> Result<(), TestCaseError> {
    prop_assert!(sim.cloth.vertex_normals().iter().all(|n| n.is_finite()));
    Ok(())
}
