//! Stage-level tests of obstacle features vs cloth faces: a 5 mm rod swept through a particle
//! sheet whose vertex spacing (5 cm) is ten times the rod's diameter, so no vertex ever meets it.

use drape::collide::narrow::{point_triangle_closest, segment_segment_closest};
use drape::collide::SolverFeedback;
use drape::collide::{CollisionSettings, CollisionStage, DetectionMode, Motion, Obstacle};
use drape::{Pose, Vec3};

const H: f64 = 1.0 / 60.0;
const N: usize = 11;
const SPACING: f64 = 0.05;
const R: f64 = 0.005;
const TH: f64 = 0.003;
const HALF_LEN: f64 = 0.2;
/// Rod height: between two vertex rows, so the rod meets only triangle interiors and edges.
const ROD_Z: f64 = 0.0 + 0.5 * SPACING + 0.007;

/// `N x N` vertices in the world x-z plane at y = 0, centred on the origin.
fn sheet() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let half = (N - 1) as f64 * SPACING / 2.0;
    let mut x = Vec::new();
    for i in 0..N {
        for j in 0..N {
            x.push(Vec3::new(
                j as f64 * SPACING - half,
                0.0,
                i as f64 * SPACING - half,
            ));
        }
    }
    let id = |i: usize, j: usize| (i * N + j) as u32;
    let mut tris = Vec::new();
    for i in 0..N - 1 {
        for j in 0..N - 1 {
            tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (x, tris)
}

/// Rod along world x (parry's local y yawed by 90 degrees) at `y`, moving at `speed` along +y.
fn rod(cylinder: bool, y: f64, speed: f64) -> Obstacle {
    let pose = Pose::from_xyz_rpy([0.0, y, ROD_Z], [0.0, 0.0, std::f64::consts::FRAC_PI_2]);
    let o = if cylinder {
        Obstacle::cylinder("rod", R, HALF_LEN, pose)
    } else {
        Obstacle::capsule("rod", R, HALF_LEN, pose)
    };
    o.expect("valid rod").with_motion(Motion::Velocity {
        linear: Vec3::new(0.0, speed, 0.0),
        angular: Vec3::ZERO,
    })
}

fn stage(mode: DetectionMode, o: Obstacle, tris: Vec<[u32; 3]>, n: usize) -> CollisionStage {
    let settings = CollisionSettings {
        mode,
        ..CollisionSettings::default()
    };
    CollisionStage::new(settings, vec![o], tris, n, vec![TH; n], vec![0.3; n]).expect("stage")
}

/// Exact distance from segment `p q` to triangle `t`.
fn segment_triangle_distance(p: Vec3, q: Vec3, t: [Vec3; 3]) -> f64 {
    let nrm = (t[1] - t[0]).cross(t[2] - t[0]);
    let (dp, dq) = (nrm.dot(p - t[0]), nrm.dot(q - t[0]));
    if dp * dq <= 0.0 && dp != dq {
        let x = p + (q - p) * (dp / (dp - dq));
        let (c, _) = point_triangle_closest(x, t[0], t[1], t[2]);
        if c.distance(x) < 1e-12 {
            return 0.0;
        }
    }
    let mut d = f64::INFINITY;
    for e in [p, q] {
        d = d.min(point_triangle_closest(e, t[0], t[1], t[2]).0.distance(e));
    }
    for k in 0..3 {
        let (_, _, a, b) = segment_segment_closest(p, q, t[k], t[(k + 1) % 3]);
        d = d.min(a.distance(b));
    }
    d
}

/// The material point of the sheet under the rod's middle at the start: (triangle, barycentrics).
fn carried_point(x: &[Vec3], tris: &[[u32; 3]]) -> ([u32; 3], [f64; 3]) {
    let probe = Vec3::new(0.013, 0.0, ROD_Z);
    tris.iter()
        .find_map(|t| {
            let [a, b, c] = t.map(|i| x[i as usize]);
            let (q, bary) = point_triangle_closest(probe, a, b, c);
            (q.distance(probe) < 1e-12).then_some((*t, bary))
        })
        .expect("probe lies on the sheet")
}

/// Where the carried material point is in `x`.
fn at(x: &[Vec3], (t, bary): ([u32; 3], [f64; 3])) -> Vec3 {
    (0..3).map(|k| x[t[k] as usize] * bary[k]).sum()
}

/// Steps the free particle sheet (no gravity, no springs) against the rod; returns the rod's
/// y and the sheet after each step.
fn sweep(mode: DetectionMode, cylinder: bool, speed: f64, steps: usize) -> Vec<(f64, Vec<Vec3>)> {
    let (mut x, tris) = sheet();
    let n = x.len();
    let mut v = vec![Vec3::ZERO; n];
    let w = vec![1.0; n];
    let mut st = stage(mode, rod(cylinder, -0.1, speed), tris, n);
    let mut out = Vec::new();
    for k in 0..steps {
        let t = k as f64 * H;
        st.advance_obstacles(t, t + H);
        let x0 = x.clone();
        for (xi, vi) in x.iter_mut().zip(&v) {
            *xi += *vi * H;
        }
        st.resolve(&x0, &mut x, &mut v, &w, H, &SolverFeedback::default());
        out.push((st.obstacles()[0].pose.translation.y, x.clone()));
    }
    out
}

#[test]
fn rod_at_5_and_20_m_per_s_carries_the_sheet_and_stays_clear_of_every_face() {
    let (x_start, tris) = sheet();
    let carried = carried_point(&x_start, &tris);
    for cylinder in [false, true] {
        for speed in [5.0, 20.0] {
            // 20 m/s crosses the sheet within the first step; 5 m/s within two.
            for (k, (rod_y, x)) in sweep(DetectionMode::Continuous, cylinder, speed, 4)
                .into_iter()
                .enumerate()
            {
                let (a, b) = (
                    Vec3::new(-HALF_LEN, rod_y, ROD_Z),
                    Vec3::new(HALF_LEN, rod_y, ROD_Z),
                );
                // Capsule: the features are the shape; cylinder: its axis shortened by R.
                let (a, b) = if cylinder {
                    (a + Vec3::X * R, b - Vec3::X * R)
                } else {
                    (a, b)
                };
                let worst = tris
                    .iter()
                    .map(|t| segment_triangle_distance(a, b, t.map(|i| x[i as usize])))
                    .fold(f64::INFINITY, f64::min);
                // Pushed to (R + TH)(1 + 1e-3); rounding is far below 1e-9 m.
                assert!(
                    worst >= R + TH - 1e-9,
                    "cylinder {cylinder}, {speed} m/s, step {k}: a face is {worst} m from the axis"
                );
                // The sheet point that was under the rod must stay ahead of it (carried),
                // not behind it (slipped through).
                let c = at(&x, carried);
                assert!(
                    c.y > rod_y + R,
                    "cylinder {cylinder}, {speed} m/s, step {k}: the point under the rod is at \
                     y = {} behind the rod at {rod_y}",
                    c.y
                );
            }
        }
    }
}

#[test]
fn without_feature_tests_the_rod_slips_between_the_vertices() {
    // Spheres mode tests vertices only: the same sweep leaves the sheet behind the rod, which
    // is what the continuous-mode test above would catch.
    let (x_start, tris) = sheet();
    let carried = carried_point(&x_start, &tris);
    let (rod_y, x) = sweep(DetectionMode::Spheres, false, 20.0, 1).remove(0);
    assert!(rod_y > 0.2);
    assert!(at(&x, carried).y < rod_y);
}

#[test]
fn proximity_mode_pushes_a_face_out_of_a_resting_rod() {
    let (mut x, tris) = sheet();
    let n = x.len();
    let mut v = vec![Vec3::ZERO; n];
    // A static rod 2 mm in front of the sheet (inside R + TH = 8 mm of it).
    let mut st = stage(
        DetectionMode::Proximity,
        rod(false, -0.002, 0.0),
        tris.clone(),
        n,
    );
    let x0 = x.clone();
    let report = st.resolve(
        &x0,
        &mut x,
        &mut v,
        &vec![1.0; n],
        H,
        &SolverFeedback::default(),
    );
    assert!(report.feature_contacts > 0);
    let (a, b) = (
        Vec3::new(-HALF_LEN, -0.002, ROD_Z),
        Vec3::new(HALF_LEN, -0.002, ROD_Z),
    );
    let worst = tris
        .iter()
        .map(|t| segment_triangle_distance(a, b, t.map(|i| x[i as usize])))
        .fold(f64::INFINITY, f64::min);
    assert!(worst >= R + TH - 1e-9, "closest face {worst} m");
}

#[test]
fn kinematic_vertices_are_never_moved_by_a_feature() {
    let (x_start, tris) = sheet();
    let n = x_start.len();
    let mut x = x_start.clone();
    let mut v = vec![Vec3::ZERO; n];
    let mut st = stage(DetectionMode::Continuous, rod(false, -0.1, 20.0), tris, n);
    st.advance_obstacles(0.0, H);
    st.resolve(
        &x_start,
        &mut x,
        &mut v,
        &vec![0.0; n],
        H,
        &SolverFeedback::default(),
    );
    assert_eq!(x, x_start);
    assert!(v.iter().all(|v| *v == Vec3::ZERO));
}
