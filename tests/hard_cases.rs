//! The hard-case catalogue (`src/hard/`) at CI resolution: every case must meet its criteria.
//! Full resolution: `cargo test --release --test hard_cases -- --ignored`.

use drape::hard::{catalogue, run_case, Outcome, Resolution};

fn run(name: &str, res: Resolution) -> Outcome {
    let (_, build) = catalogue()
        .into_iter()
        .find(|(n, _)| *n == name)
        .unwrap_or_else(|| panic!("no hard case {name}"));
    let case = build(res).unwrap_or_else(|e| panic!("{e}"));
    let o = run_case(case);
    eprintln!("{name}: {:?}", o.worst);
    o
}

/// Cases known to fail their criteria, with the measured failure: each must still fail (a case
/// that passes again has to leave this list), so the gap stays visible instead of ignored.
const KNOWN_FAILING: &[(&str, &str)] = &[
    (
        "real_kuka_towel_whip",
        "1.30x over the 1.22 impact bound with no contact: the towel swung round the held \
         corner pulls on the few springs there, which linear springs do not limit; it grows \
         with resolution (1.29, 1.39, 1.44 at 20, 30, 40 vertices a side) and with finer steps \
         (1.40 at 8 substeps), so it is the linear model's answer, not a 1-D front's",
    ),
    (
        "real_kuka_self_towel_whip",
        "1.30x: the same pull at the held corner",
    ),
];

fn check(name: &str, res: Resolution) {
    let o = run(name, res);
    match KNOWN_FAILING.iter().find(|(n, _)| *n == name) {
        Some((_, why)) if res == Resolution::Ci => {
            assert!(
                !o.passed(),
                "{name} passes again: take it off KNOWN_FAILING ({why})"
            );
            eprintln!("{name}: known failure ({why}): {}", o.failures.join("; "));
        }
        _ => assert!(o.passed(), "{name}: {}", o.failures.join("; ")),
    }
}

macro_rules! cases {
    ($($name:ident),* $(,)?) => {
        const TESTED: &[&str] = &[$(stringify!($name)),*];
        mod ci {
            $( #[test] fn $name() { super::check(stringify!($name), super::Resolution::Ci); } )*
        }
        mod full {
            $( #[test] #[ignore = "full resolution: minutes"] fn $name() {
                super::check(stringify!($name), super::Resolution::Full);
            } )*
        }
    };
}

cases!(
    stiff_implicit,
    stiff_explicit_near_limit,
    stiff_explicit_over_limit,
    light_cloth,
    heavy_cloth,
    tiny_cloth,
    huge_cloth,
    impact_20_m_s,
    fast_rod_20_m_s,
    robot_swing_at_velocity_limit,
    pinch_below_thickness,
    crumple_heap,
    degenerate_mesh,
    pinned_inside_obstacle,
    cape_hem_inside_base,
    arm_lying_in_cloth,
    wind_50_m_s,
    long_run_10_min,
    self_towel_shaken_at_velocity_limits,
    self_cape_under_swinging_arms,
    self_sleeve_sewn_and_worn,
    self_towel_picked_from_table,
    self_shirt_of_another_cut_worn,
    real_panda_towel_whip,
    real_panda_self_towel_whip,
    real_kuka_towel_whip,
    real_kuka_self_towel_whip,
    real_xarm6_towel_whip,
    real_xarm6_self_towel_whip,
    real_xarm6_self_wipe_table,
    real_panda_self_towel_pick,
);

#[test]
fn every_catalogued_case_has_a_test() {
    let names: Vec<&str> = catalogue().iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names, TESTED,
        "catalogue and cases!() must list the same cases"
    );
}

/// The full-resolution pinch up to 0.25 s after the press stops (0.5 s), where it used to fail:
/// feature contacts of the press's bottom edges pushed pinched vertices outward a little every
/// substep and the pinch only restored their height, so they were squeezed out from under the
/// press (8 mm, 9 J of spring energy) and flung at 3.1 m/s. Runs in about a second.
#[test]
fn pinch_at_full_resolution_until_after_the_press_stops() {
    let (_, build) = catalogue()
        .into_iter()
        .find(|(n, _)| *n == "pinch_below_thickness")
        .expect("catalogued");
    let mut case = build(Resolution::Full).expect("builds");
    case.duration = 0.75;
    let o = run_case(case);
    assert!(o.passed(), "{}", o.failures.join("; "));
}

/// Contact response must not pump energy into the crumpled heap. Friction of filter-held
/// vertices counted the springs' explicit load `f h / m` (90-600 m/s) as the normal impulse, so
/// every held vertex stuck and its projection back against its neighbours stretched the springs
/// each step: 0.81 of the energy scale above the initial energy, 40 J put in and damped out
/// over 1.5 s. The bound: 0.1 of the scale (measured 0.078 with the fix; the rest is the ground's
/// projection of the first vertices to land, see `crumple` in src/hard/cases.rs).
#[test]
fn crumple_contact_response_does_not_pump_energy() {
    let o = run("crumple_heap", Resolution::Ci);
    let excess = o.worst.energy_excess.expect("energy is measured");
    assert!(excess < 0.1, "energy excess {excess:.3} of the scale");
}

/// The summary command's Markdown lists every case with its verdict and worst values.
#[test]
fn summary_lists_every_case() {
    let (_, build) = catalogue()
        .into_iter()
        .find(|(n, _)| *n == "tiny_cloth")
        .expect("tiny_cloth is catalogued");
    let o = run_case(build(Resolution::Ci).expect("builds"));
    let md = drape::hard::markdown(std::slice::from_ref(&o), Resolution::Ci);
    assert!(md.contains("| tiny_cloth | yes |"), "{md}");
    assert!(md.contains("### tiny_cloth"), "{md}");
    assert!(md.contains("1 of 1 cases pass"), "{md}");
}

/// The robot case really swings at the URDF velocity limits, not below or above them.
#[test]
fn robot_swing_moves_at_the_joint_velocity_limits() {
    let (_, build) = catalogue()
        .into_iter()
        .find(|(n, _)| *n == "robot_swing_at_velocity_limit")
        .expect("catalogued");
    let case = build(Resolution::Ci).expect("builds");
    let d = case.driver.expect("the case has a robot");
    let kin = d.robot().kinematics();
    for name in ["right_shoulder_pitch", "right_wrist"] {
        let ji = kin.joint_index(name).expect("joint exists");
        let limit = kin.joints()[ji].velocity_limit.expect("URDF gives a limit");
        let h = 1e-3;
        let fastest = (0..3000)
            .map(|k| {
                let t = k as f64 * h;
                let (a, _) = kin.effective_position(&d.positions_at(t), ji);
                let (b, _) = kin.effective_position(&d.positions_at(t + h), ji);
                ((b - a) / h).abs()
            })
            .fold(0.0, f64::max);
        // Piecewise-linear motion: the finite difference is exact except across a knot.
        assert!(
            (fastest - limit).abs() < 1e-6 * limit,
            "{name}: {fastest} rad/s vs limit {limit}"
        );
    }
}
