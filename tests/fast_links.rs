//! Fast thin links through a full simulation: a rod (capsule or cylinder) or a thin
//! plate moving at constant velocity through a hanging sheet, stepped from a scene file through
//! `Simulation`, judged on the state every frame step ends in.
//!
//! - Crossings, exactly: each cloth column (a polyline from the sheet's top to its bottom) winds
//!   around the rod's axis. A column the rod pushes ahead of it, carries or wraps passes the
//!   axis on the side the rod moves towards: its winding angle (about the axis, signed so that
//!   passing in front is negative) is below zero. A column the rod passed through lies partly
//!   behind it and winds the other way: a winding above `pi / 2` is a crossing (a column that
//!   slid off lies on one side: `|W| < pi / 2`; one carried around is near `-pi`). For a plate:
//!   a vertex inside the plate's outline and behind its back face.
//! - Stretch: the largest edge length over rest length of the mesh edges, against the physical
//!   bound `1 + v / c` of an impact at speed `v` on a sheet of wave speed
//!   `c = spacing sqrt(k / m) = sqrt(stretch / density)` (a spring chain of stiffness `k` and
//!   vertex mass `m = density spacing^2`; the strain behind the front of a step in velocity `v`
//!   is `v / c`), plus what gravity explains (the whole sheet's weight `M g` on one spring of
//!   stiffness `k`: `M g / k`, 0.05 % here). Acceptance: within that bound plus 10 %.

use drape::scene::Scene;
use drape::sim::Simulation;
use drape::Vec3;

/// The sheet: `size` m square, `res` vertices per side, hanging in the world x-z plane, its
/// centre at z = 1; free (falling), pinned at its two top corners, or (for the measurement of
/// where a pinned sheet's stretch arises) along its whole top row; Coulomb `friction` with the
/// link.
struct Sheet {
    size: f64,
    res: usize,
    pins: Pins,
    friction: f64,
    /// `material.strain_limit`, where set.
    strain_limit: Option<f64>,
    /// `material.stretch_knee` and `knee_stiffening`, where set.
    knee: Option<f64>,
    stiffening: Option<f64>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Pins {
    Free,
    Corners,
    TopRow,
}

#[derive(Clone, Copy, Debug)]
enum Link {
    Capsule(f64),
    Cylinder(f64),
    /// A plate of this thickness (m), 2 m x 1.2 m, covering the sheet.
    Plate(f64),
}

/// One case: the link moves along +y at `speed`, its axis along x turned by `angle` (rad)
/// about y (in the sheet's plane).
struct Case {
    sheet: Sheet,
    link: Link,
    speed: f64,
    angle: f64,
    frames: usize,
}

const DENSITY: f64 = 0.2;
const STRETCH: f64 = 1000.0;
const START_Y: f64 = -0.05;
const CENTRE_Z: f64 = 1.0;

fn yaml(c: &Case) -> String {
    let s = &c.sheet;
    let shape = match c.link {
        Link::Capsule(r) => format!("{{ type: capsule, radius: {r}, half_height: 0.8 }}"),
        Link::Cylinder(r) => format!("{{ type: cylinder, radius: {r}, half_height: 0.8 }}"),
        Link::Plate(t) => format!("{{ type: box, half_extents: [1.0, {}, 0.6] }}", t / 2.0),
    };
    // Rods lie along local y: a roll by `angle` tilts the axis towards z, the yaw lays it along
    // x, so it ends along (-cos angle, 0, sin angle), turned in the sheet's plane.
    let rpy = match c.link {
        Link::Plate(_) => format!("[0.0, {}, 0.0]", c.angle),
        _ => format!("[{}, 0.0, 1.5707963267948966]", c.angle),
    };
    let pins = match s.pins {
        Pins::Free => String::new(),
        Pins::Corners => "    pins: [ { region: top_left }, { region: top_right } ]\n".into(),
        Pins::TopRow => {
            let top: Vec<String> = (s.res * (s.res - 1)..s.res * s.res)
                .map(|i| i.to_string())
                .collect();
            format!("    pins: [ {{ vertices: [{}] }} ]\n", top.join(", "))
        }
    };
    format!(
        r#"
name: fast_link
duration: 1.0
effects: [gravity, stretch, shear, bending, damping]
solver: {{ integrator: implicit, dt: 0.016666666666666666, substeps: {substeps} }}
cloths:
  - name: sheet
    grid: {{ size: [{size}, {size}], resolution: [{res}, {res}], pose: {{ xyz: [0.0, 0.0, {CENTRE_Z}], rpy: [1.5707963267948966, 0.0, 0.0] }} }}
    material:
      density: {DENSITY}
      stretch: {STRETCH}
      shear: 100.0
      bend_warp: 1.0e-5
      bend_weft: 1.0e-5
      thickness: 0.004
      friction: {friction}
{limit}{knee}{pins}obstacles:
  - name: link
    shape: {shape}
    pose: {{ xyz: [0.0, {START_Y}, {CENTRE_Z}], rpy: {rpy} }}
    motion: {{ type: velocity, linear: [0.0, {speed}, 0.0], angular: [0.0, 0.0, 0.0] }}
collision: {{ mode: continuous }}
"#,
        size = s.size,
        res = s.res,
        speed = c.speed,
        friction = s.friction,
        substeps = substeps(),
        limit = s
            .strain_limit
            .map_or(String::new(), |l| format!("      strain_limit: {l}\n")),
        knee = s
            .knee
            .map_or(String::new(), |l| format!("      stretch_knee: {l}\n"))
            + &s.stiffening
                .map_or(String::new(), |r| format!("      knee_stiffening: {r}\n")),
    )
}

/// Substeps per frame: 1, or `FAST_LINK_SUBSTEPS` for [`one_case`]'s convergence runs.
fn substeps() -> u32 {
    std::env::var("FAST_LINK_SUBSTEPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1)
}

/// What a case measured over its frames.
#[derive(Debug, Default)]
struct Outcome {
    /// Frames that ended with a crossing, and the first one's description.
    crossed_frames: usize,
    first_crossing: Option<String>,
    max_stretch: f64,
    /// The largest stretch of a structural (warp or weft) edge, and that edge's grid
    /// `(column, row)` of its lower vertex and direction (`'|'` along a column, `'-'` along a
    /// row; rows counted from the bottom), at the frame it was largest.
    max_structural: f64,
    structural_at: Option<(usize, usize, char)>,
    bound: f64,
    substeps: u32,
    splits: u32,
    subdivisions: u32,
}

/// Winding angle (rad) of the polyline `pts` about the line through `o` along unit `axis`,
/// signed so that a path passing the axis on the `ahead` side winds negatively.
fn winding(pts: &[Vec3], o: Vec3, axis: Vec3, ahead: Vec3) -> f64 {
    // In the plane normal to the axis: e1 = ahead, e2 = axis x ahead (up for a rod along x
    // moving along y); a path from up (+e2) to down (-e2) through +e1 turns clockwise.
    let e1 = (ahead - axis * ahead.dot(axis)).normalize();
    let e2 = axis.cross(e1);
    let angle = |p: Vec3| {
        let d = p - o;
        d.dot(e2).atan2(d.dot(e1))
    };
    let mut w = 0.0;
    for pair in pts.windows(2) {
        let mut d = angle(pair[1]) - angle(pair[0]);
        while d > std::f64::consts::PI {
            d -= std::f64::consts::TAU;
        }
        while d < -std::f64::consts::PI {
            d += std::f64::consts::TAU;
        }
        w += d;
    }
    // Top to bottom past the front is clockwise in (e1, e2): negative.
    w
}

/// A crossing at the current state, described, if any.
fn crossing(sim: &Simulation, c: &Case) -> Option<String> {
    let stage = sim.collision()?;
    let o = &stage.obstacles()[0];
    let pose = o.pose;
    let res = c.sheet.res;
    let x = &sim.cloth.x;
    let ahead = Vec3::Y;
    match c.link {
        Link::Plate(t) => {
            let back = pose.translation.y - t / 2.0;
            let inside = |p: &Vec3| {
                let l = pose.inverse_transform_point(*p);
                l.x.abs() < 1.0 && l.z.abs() < 0.6
            };
            let worst = x
                .iter()
                .filter(|p| inside(p))
                .map(|p| back - p.y)
                .fold(f64::NEG_INFINITY, f64::max);
            (worst > 0.0).then(|| format!("a vertex {worst:.4} m behind the plate"))
        }
        _ => {
            let axis = pose.transform_vector(Vec3::Y);
            // Along +x, so that `axis x ahead` is up.
            let axis = if axis.x < 0.0 { -axis } else { axis };
            for i in 0..res {
                // Grid rows run along local v, which the roll turns to world z: row j = top
                // at j = res - 1.
                let col: Vec<Vec3> = (0..res).rev().map(|j| x[j * res + i]).collect();
                let w = winding(&col, pose.translation, axis, ahead);
                if w > std::f64::consts::FRAC_PI_2 {
                    return Some(format!("column {i} winds {w:.2} rad around the rod"));
                }
            }
            None
        }
    }
}

/// Largest edge length over rest length of the mesh edges.
fn max_stretch(sim: &Simulation) -> f64 {
    let cl = &sim.cloth;
    let mut worst: f64 = 0.0;
    for t in &cl.triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let rest = (cl.uv[a] - cl.uv[b]).length();
            worst = worst.max((cl.x[a] - cl.x[b]).length() / rest);
        }
    }
    worst
}

/// The most stretched structural edge of a `res` x `res` grid: (stretch, column, row,
/// direction) as in [`Outcome::max_structural`].
fn structural(sim: &Simulation, res: usize) -> (f64, (usize, usize, char)) {
    let cl = &sim.cloth;
    let mut w = (0.0, (0, 0, '-'));
    for j in 0..res {
        for i in 0..res {
            let a = j * res + i;
            let along_row = (i + 1 < res).then_some((a + 1, '-'));
            let along_column = (j + 1 < res).then_some((a + res, '|'));
            for (b, dir) in along_row.into_iter().chain(along_column) {
                let r = (cl.x[a] - cl.x[b]).length() / (cl.uv[a] - cl.uv[b]).length();
                if r > w.0 {
                    w = (r, (i, j, dir));
                }
            }
        }
    }
    w
}

fn metrics_substeps(sim: &Simulation) -> u32 {
    sim.last_metrics().substeps
}

fn run(c: &Case) -> Outcome {
    let scene = Scene::from_yaml(&yaml(c), "fast_link").unwrap_or_else(|e| panic!("{e}"));
    let mut sim = scene.build().unwrap_or_else(|e| panic!("{e}"));
    let spacing = c.sheet.size / (c.sheet.res - 1) as f64;
    let m = DENSITY * spacing * spacing;
    let wave = spacing * (STRETCH / m).sqrt();
    let weight = DENSITY * c.sheet.size * c.sheet.size * 9.81;
    let mut out = Outcome {
        bound: 1.0 + c.speed / wave + weight / STRETCH,
        ..Outcome::default()
    };
    for _ in 0..c.frames {
        let metrics = sim.step().unwrap_or_else(|e| panic!("{e}"));
        out.substeps += metrics.substeps;
        out.splits += metrics.contact_splits;
        out.subdivisions += metrics.subdivisions;
        if let Some(what) = crossing(&sim, c) {
            out.crossed_frames += 1;
            out.first_crossing.get_or_insert(what);
        }
        out.max_stretch = out.max_stretch.max(max_stretch(&sim));
        let (st, at) = structural(&sim, c.sheet.res);
        if st > out.max_structural {
            (out.max_structural, out.structural_at) = (st, Some(at));
        }
        if std::env::var_os("FAST_LINK_FRAMES").is_some() {
            eprintln!(
                "t {:.3}: structural {st:.3} at {at:?}, stretch {:.3}, lowest z {:.3}, rod y {:.3}, substeps {}",
                sim.time(),
                max_stretch(&sim),
                sim.cloth
                    .x
                    .iter()
                    .map(|p| p.z)
                    .fold(f64::INFINITY, f64::min),
                sim.collision()
                    .map_or(0.0, |s| s.obstacles()[0].pose.translation.y),
                metrics_substeps(&sim)
            );
        }
        assert!(sim.cloth.x.iter().all(|p| p.is_finite()));
    }
    out
}

fn full_sheet(pins: Pins) -> Sheet {
    Sheet {
        size: 1.0,
        res: 40,
        pins,
        friction: 0.3,
        strain_limit: None,
        knee: None,
        stiffening: None,
    }
}

/// `pinned` in `FAST_LINK` pins the corners, or the top row with `FAST_LINK_ROW` set.
fn pins_of(pinned: bool) -> Pins {
    match (pinned, std::env::var_os("FAST_LINK_ROW").is_some()) {
        (false, _) => Pins::Free,
        (true, false) => Pins::Corners,
        (true, true) => Pins::TopRow,
    }
}

/// One case picked by the environment (`FAST_LINK=capsule:0.005:20`, `:pinned` appended for
/// corner pins; `FAST_LINK_ROW=1` pins the top row instead, `FAST_LINK_MU` sets the friction,
/// `FAST_LINK_CI=1` the CI sheet, `FAST_LINK_FRAMES=1` prints every frame,
/// `FAST_LINK_SUBSTEPS` the substeps per frame, `FAST_LINK_LIMIT` the strain limit,
/// `FAST_LINK_KNEE` the stretch knee, `FAST_LINK_STIFFENING` its stiffening, `FAST_LINK_ANGLE`
/// the rod's turn in the sheet's plane, `FAST_LINK_RES` the vertices a side), printed.
#[test]
#[ignore]
fn one_case() {
    let spec = std::env::var("FAST_LINK").unwrap_or_else(|_| "capsule:0.005:20".into());
    let p: Vec<&str> = spec.split(':').collect();
    let r: f64 = p[1].parse().unwrap();
    let link = match p[0] {
        "capsule" => Link::Capsule(r),
        "cylinder" => Link::Cylinder(r),
        _ => Link::Plate(r),
    };
    let pins = pins_of(p.get(3) == Some(&"pinned"));
    let mut sheet = if std::env::var_os("FAST_LINK_CI").is_some() {
        ci_sheet(pins)
    } else {
        full_sheet(pins)
    };
    if let Some(res) = std::env::var("FAST_LINK_RES")
        .ok()
        .and_then(|m| m.parse().ok())
    {
        sheet.res = res;
    }
    if let Some(mu) = std::env::var("FAST_LINK_MU")
        .ok()
        .and_then(|m| m.parse().ok())
    {
        sheet.friction = mu;
    }
    sheet.strain_limit = std::env::var("FAST_LINK_LIMIT")
        .ok()
        .and_then(|l| l.parse().ok());
    sheet.knee = std::env::var("FAST_LINK_KNEE")
        .ok()
        .and_then(|l| l.parse().ok());
    sheet.stiffening = std::env::var("FAST_LINK_STIFFENING")
        .ok()
        .and_then(|l| l.parse().ok());
    let c = Case {
        sheet,
        link,
        speed: p[2].parse().unwrap(),
        angle: std::env::var("FAST_LINK_ANGLE")
            .ok()
            .and_then(|a| a.parse().ok())
            .unwrap_or(0.0),
        frames: 9,
    };
    println!("{:?}", run(&c));
}

/// Every link at 5 and 20 m/s through the full free sheet, printed (run with `--ignored
/// --nocapture`).
#[test]
#[ignore]
fn full_sheet_table() {
    for link in [
        Link::Capsule(0.02),
        Link::Capsule(0.005),
        Link::Capsule(0.003),
        Link::Cylinder(0.005),
        Link::Plate(0.002),
    ] {
        for speed in [5.0, 20.0] {
            let c = Case {
                sheet: full_sheet(Pins::Free),
                link,
                speed,
                angle: 0.0,
                frames: 9,
            };
            let o = run(&c);
            println!(
                "{link:?} {speed} m/s: crossed {} of {} frames ({:?}), stretch {:.2} (bound \
                 {:.3}), substeps {}, splits {}, subdivisions {}",
                o.crossed_frames,
                c.frames,
                o.first_crossing,
                o.max_stretch,
                o.bound,
                o.substeps,
                o.splits,
                o.subdivisions
            );
        }
    }
}

/// The CI sheet: 0.5 m at 20 vertices a side (2.6 cm spacing, as the full sheet's).
fn ci_sheet(pins: Pins) -> Sheet {
    Sheet {
        size: 0.5,
        res: 20,
        pins,
        friction: 0.3,
        strain_limit: None,
        knee: None,
        stiffening: None,
    }
}

/// Runs a case and checks the acceptance: no crossing at any frame end, finite, no guard stop
/// and, when `stretch` says so, the largest stretch within the physical bound plus 10 %
/// (`1.1 (1 + v / c + M g / k)`).
fn accept(c: &Case, stretch: bool) -> Outcome {
    let o = run(c);
    let what = format!(
        "{:?} at {} m/s, angle {}, pins {:?}",
        c.link, c.speed, c.angle, c.sheet.pins
    );
    eprintln!("{what}: {o:?}");
    assert_eq!(
        o.crossed_frames, 0,
        "{what}: crossed ({:?})",
        o.first_crossing
    );
    assert!(
        !stretch || o.max_stretch <= 1.1 * o.bound,
        "{what}: edges stretched {:.3} times their rest length, bound {:.3}",
        o.max_stretch,
        o.bound
    );
    o
}

/// Rods of 3 and 5 mm diameter (the spacing is 8.8 and 5.3 diameters) at 5, 20 and 40 m/s, along
/// the grid and turned 0.5 rad in the sheet's plane.
fn rods(cylinder: bool, pins: Pins, stretch: bool) {
    for r in [0.0015, 0.0025] {
        for speed in [5.0, 20.0, 40.0] {
            for angle in [0.0, 0.5] {
                let link = if cylinder {
                    Link::Cylinder(r)
                } else {
                    Link::Capsule(r)
                };
                let c = Case {
                    sheet: ci_sheet(pins),
                    link,
                    speed,
                    angle,
                    frames: 9,
                };
                accept(&c, stretch);
            }
        }
    }
}

#[test]
fn capsules_through_a_free_sheet_carry_it_without_crossing_or_overstretching() {
    rods(false, Pins::Free, true);
}

#[test]
fn cylinders_through_a_free_sheet_carry_it_without_crossing_or_overstretching() {
    rods(true, Pins::Free, true);
}

/// The pinned-sheet rod cases: a 3 mm capsule and a 5 mm cylinder at 5, 20 and 40 m/s, along
/// the grid and turned 0.5 rad, through the CI sheet pinned at its top corners, its material
/// set by `material`; 9 frames each.
fn pinned_rod_cases(material: impl Fn(&mut Sheet)) -> Vec<Case> {
    let mut cases = Vec::new();
    for link in [Link::Capsule(0.0015), Link::Cylinder(0.0025)] {
        for speed in [5.0, 20.0, 40.0] {
            for angle in [0.0, 0.5] {
                let mut sheet = ci_sheet(Pins::Corners);
                material(&mut sheet);
                cases.push(Case {
                    sheet,
                    link,
                    speed,
                    angle,
                    frames: 9,
                });
            }
        }
    }
    cases
}

/// Rods of 3 and 5 mm at 5, 20 and 40 m/s, along the grid and turned 0.5 rad, through the CI
/// sheet pinned at its top corners, of a fabric that stiffens past 3 % (`stretch_knee: 0.03`,
/// `effects/springs.rs`): no crossing, and every edge within 1.06 of its rest length at every
/// frame end.
///
/// With linear springs the sheet overstretches far past the bound `1 + v / c + M g / k` of a
/// 1-D front, and that is the model's answer, not an error: the pull of the columns over the
/// rod goes through the two pinned vertices, a point load, and an independent 1-D reference
/// of the same material (`pinned_sheet_stretch_against_the_reference_string`) stretches more
/// than drape's pinned sheets at every speed. Where it arises is measured by
/// `pinned_sheet_stretch_by_pins_and_friction`.
#[test]
#[ignore = "known limit: 1.07-1.22 against 1.06, no crossing. The two pinned vertices take the \
            sheet's pull as point loads (pinned along its top row the sheet stays within 1.052 \
            at 5 m/s), and at 40 m/s the sheet whips round its pins after the rod has let go, \
            at one step a frame"]
fn rods_through_a_pinned_sheet_of_stiffening_fabric_stay_near_its_knee() {
    let mut worst = Vec::new();
    for c in pinned_rod_cases(|s| s.knee = Some(0.03)) {
        let o = accept(&c, false);
        worst.push((
            format!("{:?} at {} m/s, angle {}", c.link, c.speed, c.angle),
            o.max_stretch,
        ));
    }
    eprintln!("{worst:?}");
    let over: Vec<_> = worst.iter().filter(|(_, s)| *s > 1.06).collect();
    assert!(over.is_empty(), "edges past 1.06: {over:?}");
}

/// What does hold for a sheet pinned at its top corners (the stretch does not, see below): no
/// crossing at any frame end, finite, no guard stop, for a 3 mm capsule and a 5 mm cylinder at
/// 5, 20 and 40 m/s, along the grid and turned 0.5 rad.
#[test]
fn rods_through_a_pinned_sheet_do_not_cross_it() {
    for c in pinned_rod_cases(|_| {}) {
        accept(&c, false);
    }
}

/// A material with `strain_limit: 0.1` (`sim/limit.rs`) against the same rods through the same
/// corner-pinned sheet: the limit moves the cloth after the solve, and must not pull it through a
/// rod (no crossing at any frame end, finite, no guard stop); the stretch is printed, not judged.
/// The limit holds the stretch far below what the springs alone reach, within 10 % of it after
/// its passes; the collision pass after it stretches edges again, by more than the third of a
/// spacing fast contact bounds a link's step by.
#[test]
fn with_a_strain_limit_rods_through_a_pinned_sheet_do_not_cross_it() {
    for c in pinned_rod_cases(|s| s.strain_limit = Some(0.1)) {
        accept(&c, false);
    }
}

/// Where a pinned sheet's stretch arises, printed (run with `--ignored --nocapture`): a 3 mm
/// capsule through the CI sheet pinned at its two top corners or along its whole top row, with
/// friction 0.3 or none; the largest stretch of any edge and of a structural one, and where.
#[test]
#[ignore]
fn pinned_sheet_stretch_by_pins_and_friction() {
    for speed in [5.0, 20.0, 40.0] {
        for pins in [Pins::Corners, Pins::TopRow] {
            for friction in [0.3, 0.0] {
                let mut sheet = ci_sheet(pins);
                sheet.friction = friction;
                let c = Case {
                    sheet,
                    link: Link::Capsule(0.0015),
                    speed,
                    angle: 0.0,
                    frames: 9,
                };
                let o = run(&c);
                println!(
                    "{speed} m/s, {pins:?}, mu {friction}: crossed {}, stretch {:.3}, \
                     structural {:.3} at {:?}, bound 1 + 2 (v / c + M g / k) {:.3}, substeps {}",
                    o.crossed_frames,
                    o.max_stretch,
                    o.max_structural,
                    o.structural_at,
                    2.0 * o.bound - 1.0,
                    o.substeps
                );
            }
        }
    }
}

/// Free sheets only: a plate covering a pinned sheet would have to pass its pins.
#[test]
fn a_2_mm_plate_pushes_the_sheet_without_passing_it() {
    for speed in [5.0, 20.0, 40.0] {
        let c = Case {
            sheet: ci_sheet(Pins::Free),
            link: Link::Plate(0.002),
            speed,
            angle: 0.3,
            frames: 9,
        };
        accept(&c, true);
    }
}

/// The split levels a live node bounds fast contact with (`solver.guard.max_contact_split_levels`,
/// node parameter `max_contact_split_levels`): a 20 m/s rod through the CI sheet splits each
/// substep at most once at one level, and the substeps that would have split further are
/// counted (on `/diagnostics` as `contact_splits_refused`), not silent; unbounded, none is.
#[test]
fn split_levels_bound_the_substeps_and_count_what_they_refused() {
    let c = Case {
        sheet: ci_sheet(Pins::Free),
        link: Link::Capsule(0.0025),
        speed: 20.0,
        angle: 0.0,
        frames: 9,
    };
    let run_with = |levels: Option<u32>| {
        let mut scene = Scene::from_yaml(&yaml(&c), "fast_link").unwrap_or_else(|e| panic!("{e}"));
        scene.solver.guard.max_contact_split_levels = levels;
        let n_sub = scene.solver.substeps;
        let mut sim = scene.build().unwrap_or_else(|e| panic!("{e}"));
        let (mut splits, mut refused) = (0, 0);
        for f in 0..c.frames {
            let m = sim.step().unwrap_or_else(|e| panic!("{e}"));
            splits += m.contact_splits;
            refused += m.contact_splits_refused;
            if let Some(l) = levels {
                assert!(
                    m.contact_splits <= n_sub * ((1 << l) - 1),
                    "frame {f}: {} splits at {l} level(s)",
                    m.contact_splits
                );
            }
            assert!(sim.cloth.x.iter().all(|p| p.is_finite()));
        }
        (splits, refused)
    };
    let (free_splits, free_refused) = run_with(None);
    let (splits, refused) = run_with(Some(1));
    assert_eq!(free_refused, 0, "nothing refused without a bound");
    assert!(
        free_splits > splits && refused > 0,
        "unbounded {free_splits} splits; bounded {splits}, {refused} refused"
    );
}

/// The physics of a sheet pinned along its top row and swept by a rod across its whole width,
/// independent of drape: the sheet's 1-D section, a string of `nodes` nodes over `height`
/// (density `DENSITY` per unit width, tension `STRETCH` times the strain, none in compression,
/// a dashpot `kd / segment` along each segment as drape's `damping.spring` per spring gives on a
/// square grid; gravity), its top fixed, integrated explicitly (symplectic Euler) at a tenth of
/// the time a wave takes across a segment, against a frictionless circle of radius `radius`
/// (the rod's plus the cloth's thickness) moving at `speed` along y from `START_Y` at the sheet's
/// middle height. Nodes and segments that end a step inside the circle are put back on it (a
/// segment by moving both ends along its closest point's normal) and lose their velocity
/// towards it. Returns the largest segment length over rest length at any step up to `t_end`.
fn reference_string(
    speed: f64,
    radius: f64,
    height: f64,
    nodes: usize,
    t_end: f64,
    kd: f64,
) -> f64 {
    let s = height / (nodes - 1) as f64;
    let m = DENSITY * s;
    let c = (STRETCH / DENSITY).sqrt();
    let dt = 0.1 * s / c;
    let eta = kd / s;
    let top = CENTRE_Z + 0.5 * height;
    // (y, z) positions and velocities.
    let mut x: Vec<[f64; 2]> = (0..nodes).map(|i| [0.0, top - i as f64 * s]).collect();
    let mut u = vec![[0.0; 2]; nodes];
    let mut f = vec![[0.0; 2]; nodes];
    let mut worst: f64 = 1.0;
    let mut t = 0.0;
    // The outward normal and depth of a point inside the circle.
    let inside = |p: [f64; 2], centre: [f64; 2]| {
        let d = [p[0] - centre[0], p[1] - centre[1]];
        let r = (d[0] * d[0] + d[1] * d[1]).sqrt();
        (r < radius && r > 0.0).then(|| ([d[0] / r, d[1] / r], radius - r))
    };
    while t < t_end {
        f.iter_mut().for_each(|fi| *fi = [0.0, -m * 9.81]);
        for i in 0..nodes - 1 {
            let d = [x[i + 1][0] - x[i][0], x[i + 1][1] - x[i][1]];
            let l = (d[0] * d[0] + d[1] * d[1]).sqrt();
            let dv = [u[i + 1][0] - u[i][0], u[i + 1][1] - u[i][1]];
            let pull = STRETCH * (l / s - 1.0).max(0.0) + eta * (dv[0] * d[0] + dv[1] * d[1]) / l;
            for k in 0..2 {
                f[i][k] += pull * d[k] / l;
                f[i + 1][k] -= pull * d[k] / l;
            }
        }
        for i in 1..nodes {
            for k in 0..2 {
                u[i][k] += dt * f[i][k] / m;
                x[i][k] += dt * u[i][k];
            }
        }
        t += dt;
        let centre = [START_Y + speed * t, CENTRE_Z];
        let mut put_back = |i: usize, n: [f64; 2], depth: f64, x: &mut [[f64; 2]]| {
            x[i][0] += n[0] * depth;
            x[i][1] += n[1] * depth;
            let vn = (u[i][0] - speed) * n[0] + u[i][1] * n[1];
            if vn < 0.0 {
                u[i][0] -= vn * n[0];
                u[i][1] -= vn * n[1];
            }
        };
        for i in 1..nodes {
            if let Some((n, depth)) = inside(x[i], centre) {
                put_back(i, n, depth, &mut x);
            }
        }
        for i in 0..nodes - 1 {
            let (a, b) = (x[i], x[i + 1]);
            let e = [b[0] - a[0], b[1] - a[1]];
            let ee = e[0] * e[0] + e[1] * e[1];
            let w = (((centre[0] - a[0]) * e[0] + (centre[1] - a[1]) * e[1]) / ee).clamp(0.0, 1.0);
            if let Some((n, depth)) = inside([a[0] + w * e[0], a[1] + w * e[1]], centre) {
                for j in [i, i + 1].into_iter().filter(|&j| j > 0) {
                    put_back(j, n, depth, &mut x);
                }
            }
        }
        for i in 0..nodes - 1 {
            let d = [x[i + 1][0] - x[i][0], x[i + 1][1] - x[i][1]];
            worst = worst.max((d[0] * d[0] + d[1] * d[1]).sqrt() / s);
        }
    }
    worst
}

/// What a pinned sheet's stretch is, physically (run with `--ignored --nocapture`): the 1-D
/// reference string of the CI sheet's section (0.5 m, pinned at its top, a 3 mm rod plus the 4 mm
/// thickness, frictionless) over the 9 frames the tests run, at three resolutions, undamped and
/// with drape's spring damping, against drape's CI sheet pinned along its top row (friction 0,
/// 1 substep a frame) and at its two top corners, and the impact bound `1 + 2 v / c + M g / k`.
///
/// The reference is chaotic (a tenth or a fifth of a wave's crossing time per step changes it
/// by up to a quarter) and stretches more than drape's pinned sheets, and far past the bound:
/// the free tail, pulled over the rod, whips and wraps around the rod, which then drags the
/// wrapped cloth away from the pins: a stretch no bound from the rod's speed alone describes.
/// The guard's bound (`sim/strain.rs`) counts the fastest cloth vertex with the obstacle and
/// covers it; `strain_limit` holds such a sheet (see
/// `with_a_strain_limit_rods_through_a_pinned_sheet_do_not_cross_it`).
#[test]
#[ignore]
fn pinned_sheet_stretch_against_the_reference_string() {
    let (radius, height, frames) = (0.0015 + 0.004, 0.5, 9);
    for speed in [5.0, 20.0, 40.0] {
        let t_end = frames as f64 / 60.0;
        let mut reference = Vec::new();
        for nodes in [126, 251, 501] {
            for kd in [0.0, 0.05] {
                let r = reference_string(speed, radius, height, nodes, t_end, kd);
                reference.push(format!("{nodes} nodes kd {kd}: {r:.2}"));
            }
        }
        let drape = |pins: Pins| {
            let mut sheet = ci_sheet(pins);
            sheet.friction = 0.0;
            let c = Case {
                sheet,
                link: Link::Capsule(0.0015),
                speed,
                angle: 0.0,
                frames,
            };
            let o = run(&c);
            (o.max_stretch, 2.0 * o.bound - 1.0)
        };
        let (row, bound) = drape(Pins::TopRow);
        let (corners, _) = drape(Pins::Corners);
        println!(
            "{speed} m/s: reference {}; drape top row {row:.2}, corners {corners:.2}; \
             1 + 2 v / c + M g / k {bound:.2}",
            reference.join(", ")
        );
    }
}
