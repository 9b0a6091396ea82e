//! The catalogue: every hard case, in the order of the summary. The cases live by theme in
//! [`super::hanging`], [`super::motion`] and [`super::edge`]. Each builds its scene from YAML (so
//! the parser and the builder are part of what is tested) or, for degenerate geometry the scene
//! format cannot express, from a hand-made mesh. Bounds are derived in the comments next to them.

use super::edge::{
    arm_lying_in_cloth, cape_hem_inside_base, degenerate_mesh, long_run, pinned_inside_obstacle,
    wind,
};
use super::fast_links::rod_through_sheet;
use super::hanging::{
    heavy_cloth, huge_cloth, light_cloth, stiff_explicit_near_limit, stiff_explicit_over_limit,
    stiff_implicit, tiny_cloth,
};
use super::motion::{crumple, impact, pinch, robot_swing};
use super::real_robots::{
    kuka_self_towel_whip, kuka_towel_whip, panda_self_towel_pick, panda_self_towel_whip,
    panda_towel_whip, xarm_self_towel_whip, xarm_self_wipe, xarm_towel_whip,
};
use super::self_contact::{
    cape_swinging, shirt_cut_long_worn, sleeve_worn, towel_picked, towel_shaken,
};
use super::{Case, HardError, Resolution};

/// Builds one case at a resolution.
pub type CaseFn = fn(Resolution) -> Result<Case, HardError>;

/// Every case, in the order of the summary.
pub fn catalogue() -> Vec<(&'static str, CaseFn)> {
    vec![
        ("stiff_implicit", stiff_implicit),
        ("stiff_explicit_near_limit", stiff_explicit_near_limit),
        ("stiff_explicit_over_limit", stiff_explicit_over_limit),
        ("light_cloth", light_cloth),
        ("heavy_cloth", heavy_cloth),
        ("tiny_cloth", tiny_cloth),
        ("huge_cloth", huge_cloth),
        ("impact_20_m_s", impact),
        ("fast_rod_20_m_s", rod_through_sheet),
        ("robot_swing_at_velocity_limit", robot_swing),
        ("pinch_below_thickness", pinch),
        ("crumple_heap", crumple),
        ("degenerate_mesh", degenerate_mesh),
        ("pinned_inside_obstacle", pinned_inside_obstacle),
        ("cape_hem_inside_base", cape_hem_inside_base),
        ("arm_lying_in_cloth", arm_lying_in_cloth),
        ("wind_50_m_s", wind),
        ("long_run_10_min", long_run),
        ("self_towel_shaken_at_velocity_limits", towel_shaken),
        ("self_cape_under_swinging_arms", cape_swinging),
        ("self_sleeve_sewn_and_worn", sleeve_worn),
        ("self_towel_picked_from_table", towel_picked),
        ("self_shirt_of_another_cut_worn", shirt_cut_long_worn),
        ("real_panda_towel_whip", panda_towel_whip),
        ("real_panda_self_towel_whip", panda_self_towel_whip),
        ("real_kuka_towel_whip", kuka_towel_whip),
        ("real_kuka_self_towel_whip", kuka_self_towel_whip),
        ("real_xarm6_towel_whip", xarm_towel_whip),
        ("real_xarm6_self_towel_whip", xarm_self_towel_whip),
        ("real_xarm6_self_wipe_table", xarm_self_wipe),
        ("real_panda_self_towel_pick", panda_self_towel_pick),
    ]
}
