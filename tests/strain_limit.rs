//! `material.strain_limit` in full simulations: what it holds, what it reports, what it costs
//! when absent, and how bad values are refused.

use drape::scene::Scene;
use std::path::Path;

fn load(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config")
        .join(name);
    Scene::load(&path).expect("bundled scene loads")
}

/// The tolerance of the limit's passes: 1 % of the allowed elongation (`sim/limit.rs`).
const SLACK: f64 = 0.01;

/// What a run measured.
struct Run {
    /// Largest edge stretch over the frame ends (0 at rest).
    stretch: f64,
    /// Largest energy gain over the start (J; kinetic, elastic and gravity).
    gain: f64,
    /// Largest excess the limit's passes left, over the run and over its last second.
    excess: f64,
    excess_last_second: f64,
}

/// Runs `scene` to its end, checking every frame end against the limit and the excess the step
/// reported.
fn run(scene: &Scene, limit: Option<f64>) -> Run {
    let mut sim = scene.build().expect("scene builds");
    let (ke0, pe0) = sim.energy();
    let e0 = ke0 + pe0;
    let mut gain: f64 = f64::NEG_INFINITY;
    let frames = (scene.duration / sim.settings.dt).round() as usize;
    let mut worst: f64 = 0.0;
    let (mut worst_excess, mut last_excess): (f64, f64) = (0.0, 0.0);
    for _ in 0..frames {
        let m = sim.step().expect("no divergence");
        let stretch = sim.cloth.max_edge_stretch();
        assert!(stretch.is_finite());
        match limit {
            Some(s) => {
                // What the passes left is reported, and the state is within it.
                let excess = m.strain_limit_excess.max(SLACK * s / (1.0 + s));
                assert!(m.strain_limited.is_some());
                assert!(
                    1.0 + stretch <= (1.0 + s) * (1.0 + excess) + 1e-9,
                    "t = {:.3}: {stretch} over the limit {s} and the reported excess {excess}",
                    m.time
                );
                worst_excess = worst_excess.max(m.strain_limit_excess);
                if m.time > scene.duration - 1.0 {
                    last_excess = last_excess.max(m.strain_limit_excess);
                }
            }
            None => assert_eq!(m.strain_limited, None, "no limit, no work"),
        }
        worst = worst.max(stretch);
        gain = gain.max(m.kinetic_energy + m.potential_energy - e0);
    }
    eprintln!(
        "largest stretch {worst:.4}, excess left by the passes {worst_excess:.4} \
         ({last_excess:.4} over the last second), energy gain {gain:.3e} J"
    );
    Run {
        stretch: worst,
        gain,
        excess: worst_excess,
        excess_last_second: last_excess,
    }
}

/// The soft three-corner cloth (100 N/m springs): its own weight stretches its edges 71 % with
/// springs alone. With a 10 % limit every frame ends within the limit and the excess its passes
/// reported (no obstacle answers after the limit here), the limit binds (the worst edge sits at
/// it), and the energy never rises above the start's: the pins do no work and gravity is in the
/// potential, so the limit must not pump energy in. Measured (one run): the passes leave up to
/// 9.8 % beyond the limit while the free corner falls (0.2-0.3 s; the stretch 0.21, against
/// 0.70 with springs alone) and up to 1.9 % in the last second, as it swings: Gauss-Seidel over
/// the edges converges slowly where the whole sheet is pulled, and the excess is reported, not
/// hidden (a limit inside the implicit solve is the way to hold it exactly).
#[test]
fn a_soft_cloth_hangs_within_its_limit_without_gaining_energy() {
    let free = load("three_corner_soft_stretch.yaml");
    let springs_alone = run(&free, None);
    assert!(springs_alone.stretch > 0.5, "{}", springs_alone.stretch);
    let mut limited = free.clone();
    limited.cloths[0].material.strain_limit = Some(0.1);
    let r = run(&limited, Some(0.1));
    assert!(
        r.stretch > 0.1 * (1.0 - SLACK),
        "the limit binds: {}",
        r.stretch
    );
    assert!(r.gain <= 1e-9, "energy rose {} J over the start", r.gain);
    // What the passes leave is well short of what the springs alone allow.
    assert!(r.stretch < 0.5 * springs_alone.stretch, "{}", r.stretch);
    assert!(r.excess_last_second <= r.excess);
}

/// A bag of a limited scene carries the limit's counts on `/diagnostics`; one without a limit
/// keeps its keys (and bytes) as before.
#[test]
fn diagnostics_carry_the_limit_only_where_a_scene_sets_one() {
    use drape::ros::telemetry::FrameQuality;
    let mut scene = load("three_corner_soft_stretch.yaml");
    for (limit, present) in [(None, false), (Some(0.1), true)] {
        scene.cloths[0].material.strain_limit = limit;
        let mut sim = scene.build().unwrap();
        let mut f = FrameQuality::default();
        for _ in 0..30 {
            f.add_step(&sim.step().unwrap());
        }
        f.at_frame(sim.time(), &sim.cloth);
        let d = f.diagnostics("drape", drape::ros::msg::Time::default(), false);
        let keys: Vec<&str> = d.status[0]
            .values
            .iter()
            .map(|kv| kv.key.as_str())
            .collect();
        assert_eq!(keys.contains(&"strain_limited_edges"), present, "{keys:?}");
        assert_eq!(keys.contains(&"strain_limit_excess"), present, "{keys:?}");
    }
}

/// Out-of-range limits are refused with the key named.
#[test]
fn bad_limits_name_their_key() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("config/three_corner_soft_stretch.yaml"),
    )
    .unwrap();
    for bad in ["-0.1", "0", ".nan", "1e300"] {
        let yaml = text.replace(
            "      stretch: 100\n",
            &format!("      stretch: 100\n      strain_limit: {bad}\n"),
        );
        assert_ne!(yaml, text);
        let err = Scene::from_yaml(&yaml, "limit").map_or_else(|e| e.to_string(), |_| "ok".into());
        assert!(
            err.contains("cloths[0].material.strain_limit"),
            "{bad}: {err}"
        );
    }
}
