//! Fast thin links: a 5 mm rod at 20 m/s through a free hanging sheet whose spacing is 2.6
//! diameters (200 g/m^2, stretch 1000 N/m). `tests/fast_links.rs` judges the crossings (winding of
//! every cloth column around the rod) and the stretch bound over the full matrix; here the
//! catalogue's criteria (finite, speed, penetration, the stretch bound) hold at CI and full
//! resolution.

use super::setup::{build, fill, impact_stretch_bound, parse, pick};
use super::{Case, Criteria, EnergyCheck, HardError, Resolution};

pub(super) fn rod_through_sheet(res: Resolution) -> Result<Case, HardError> {
    const V: f64 = 20.0;
    const TH: f64 = 0.004;
    let (size, n) = pick(res, (0.5, 20), (1.0, 40));
    let text = fill(
        r#"
effects: [gravity, stretch, shear, bending, damping]
solver: { integrator: implicit, dt: 0.016666666666666666 }
cloths:
  - name: sheet
    grid: { size: [@SIZE@, @SIZE@], resolution: [@RES@, @RES@], pose: { xyz: [0, 0, 1], rpy: [1.5707963267948966, 0, 0] } }
    material: { density: 0.2, stretch: 1000.0, shear: 100.0, bend_warp: 1.0e-5, bend_weft: 1.0e-5, thickness: @TH@ }
obstacles:
  - name: rod
    shape: { type: capsule, radius: 0.005, half_height: 0.8 }
    pose: { xyz: [0, -0.05, 1], rpy: [0, 0, 1.5707963267948966] }
    motion: { type: velocity, linear: [0, @V@, 0], angular: [0, 0, 0] }
collision: { mode: continuous }
"#,
        &[
            ("SIZE", size.to_string()),
            ("RES", n.to_string()),
            ("TH", TH.to_string()),
            ("V", V.to_string()),
        ],
    );
    let scene = parse("fast_rod_20_m_s", &text)?;
    let sim = build("fast_rod_20_m_s", &scene)?;
    let duration = 0.15;
    // Carried cloth moves at the rod's speed and a free edge whipping round the rod faster (up
    // to about 2 V), so a blow-up shows above 3 V. The rod moves 3 m in the run.
    let mut criteria = Criteria::base(V * duration + size + 1.5, 3.0 * V);
    criteria.energy = EnergyCheck::NotMeasured;
    // Never through the thickness layer.
    criteria.max_penetration = Some(TH);
    // The impact stretch bound, with the whole weight on one spring.
    criteria.max_stretch = Some(impact_stretch_bound(V, 1000.0, 0.2, size * size));
    Ok(Case {
        name: "fast_rod_20_m_s",
        description: format!(
            "free {size} m sheet ({n} x {n}) hit at mid-height by a 5 mm capsule at {V} m/s (13 \
             spacings per 60 Hz frame; split where it meets the cloth)"
        ),
        sim,
        driver: None,
        duration,
        criteria,
    })
}
