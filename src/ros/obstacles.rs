//! The scene's own obstacles (spheres, boxes, capsules, cylinders, planes, meshes; not the
//! robot's links, which `/tf` and `/robot_description` carry) as `visualization_msgs/msg/Marker`s,
//! one message per marker on `<prefix>/obstacles`: what RViz and Foxglove show, and what
//! `drape render` draws them from.
//!
//! Shapes map to marker primitives in the obstacle's frame: a sphere to SPHERE, a box to CUBE, a
//! cylinder (parry's local y axis) to CYLINDER turned onto the marker's z axis, a capsule to a
//! CYLINDER and two SPHEREs, a mesh to a TRIANGLE_LIST, and a plane (unbounded) to a flat CUBE
//! [`PLANE_SIZE`] wide in namespace [`PLANE_NS`], so a viewer can tell it from the solids.

use crate::collide::{Motion, Obstacle};
use crate::ros::msg::{ColorRGBA, Distro, Header, Marker, Point, Pose, Time, Vector3};
use crate::{Pose as RigidPose, Vec3};
use glam::DQuat;

/// Namespace of solid obstacles' markers.
pub const OBSTACLE_NS: &str = "drape/obstacles";
/// Namespace of planes' markers (squares standing for unbounded half-spaces).
pub const PLANE_NS: &str = "drape/planes";
/// Side of the square drawn for a plane (m), and its thickness.
pub const PLANE_SIZE: f64 = 4.0;
const PLANE_THICKNESS: f64 = 1e-3;
/// Colour of solid obstacles (a muted green, apart from the cloth's and the robot's).
pub const OBSTACLE_COLOR: [f32; 4] = [0.40, 0.62, 0.42, 1.0];
const PLANE_COLOR: [f32; 4] = [0.78, 0.78, 0.74, 1.0];

/// True for obstacles the scene moves itself (scripted motion): their markers are written
/// again every frame; static ones once.
pub fn moves(o: &Obstacle) -> bool {
    matches!(o.motion, Motion::Velocity { .. } | Motion::Waypoints(_))
}

/// True for the scene's own obstacles (robot links are driven from outside).
pub fn is_scene_obstacle(o: &Obstacle) -> bool {
    !matches!(o.motion, Motion::External)
}

/// The markers of the scene's own obstacles at their current poses.
pub fn scene_obstacle_markers(
    obstacles: &[Obstacle],
    distro: Distro,
    stamp: Time,
    frame_id: &str,
) -> Vec<Marker> {
    let mut out = Vec::new();
    for o in obstacles.iter().filter(|o| is_scene_obstacle(o)) {
        let marker = |ns: &str, r#type: i32, pose: RigidPose, scale: Vec3, color: [f32; 4]| {
            let [r, g, b, a] = color;
            Marker {
                distro,
                header: Header::new(stamp, frame_id),
                ns: ns.into(),
                r#type,
                action: Marker::ADD,
                pose: Pose {
                    position: pose.translation.into(),
                    orientation: pose.rotation.into(),
                },
                scale: Vector3 {
                    x: scale.x,
                    y: scale.y,
                    z: scale.z,
                },
                color: ColorRGBA::new(r, g, b, a),
                text: o.name.clone(),
                ..Marker::default()
            }
        };
        let p = o.pose;
        // Parry's cylinders and capsules run along local y; markers' along z.
        let y_up = p.mul(&RigidPose::new(
            Vec3::ZERO,
            DQuat::from_rotation_x(-std::f64::consts::FRAC_PI_2),
        ));
        let s = &o.shape;
        if let Some(b) = s.as_ball() {
            let d = 2.0 * f64::from(b.radius);
            out.push(marker(
                OBSTACLE_NS,
                Marker::SPHERE,
                p,
                Vec3::splat(d),
                OBSTACLE_COLOR,
            ));
        } else if let Some(c) = s.as_cuboid() {
            let size = 2.0 * c.half_extents.as_dvec3();
            out.push(marker(OBSTACLE_NS, Marker::CUBE, p, size, OBSTACLE_COLOR));
        } else if let Some(c) = s.as_cylinder() {
            let (d, h) = (2.0 * f64::from(c.radius), 2.0 * f64::from(c.half_height));
            out.push(marker(
                OBSTACLE_NS,
                Marker::CYLINDER,
                y_up,
                Vec3::new(d, d, h),
                OBSTACLE_COLOR,
            ));
        } else if let Some(c) = s.as_capsule() {
            let (a, b) = (c.segment.a.as_dvec3(), c.segment.b.as_dvec3());
            let d = 2.0 * f64::from(c.radius);
            let mid = p.mul(&RigidPose::new(
                (a + b) / 2.0,
                DQuat::from_rotation_arc(Vec3::Z, (b - a).normalize_or(Vec3::Z)),
            ));
            out.push(marker(
                OBSTACLE_NS,
                Marker::CYLINDER,
                mid,
                Vec3::new(d, d, (b - a).length()),
                OBSTACLE_COLOR,
            ));
            for end in [a, b] {
                let at = p.mul(&RigidPose::from_translation(end));
                out.push(marker(
                    OBSTACLE_NS,
                    Marker::SPHERE,
                    at,
                    Vec3::splat(d),
                    OBSTACLE_COLOR,
                ));
            }
        } else if let Some(h) = s.as_halfspace() {
            // The free side is +normal; the slab lies just below the surface.
            let n = h.normal.as_dvec3().normalize_or(Vec3::Z);
            let slab = p.mul(&RigidPose::new(
                -n * (PLANE_THICKNESS / 2.0),
                DQuat::from_rotation_arc(Vec3::Z, n),
            ));
            let size = Vec3::new(PLANE_SIZE, PLANE_SIZE, PLANE_THICKNESS);
            out.push(marker(PLANE_NS, Marker::CUBE, slab, size, PLANE_COLOR));
        } else if let Some(m) = s.as_trimesh() {
            let v = m.vertices();
            let mut mk = marker(
                OBSTACLE_NS,
                Marker::TRIANGLE_LIST,
                p,
                Vec3::ONE,
                OBSTACLE_COLOR,
            );
            mk.points = m
                .indices()
                .iter()
                .flatten()
                .filter_map(|&i| v.get(i as usize))
                .map(|q| Point::from(q.as_dvec3()))
                .collect();
            out.push(mk);
        }
    }
    for (k, m) in out.iter_mut().enumerate() {
        m.id = i32::try_from(k).unwrap_or(i32::MAX);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_shape_is_a_marker_at_its_pose_and_robot_links_are_left_out() {
        let at = RigidPose::from_translation(Vec3::new(0.0, 0.0, 0.5));
        let obstacles = vec![
            Obstacle::sphere("ball", 0.3, at).unwrap(),
            Obstacle::cuboid("box", Vec3::new(0.1, 0.2, 0.3), at).unwrap(),
            Obstacle::cylinder("pole", 0.05, 0.4, at).unwrap(),
            Obstacle::capsule("pill", 0.05, 0.2, at).unwrap(),
            Obstacle::plane("ground", Vec3::Z, RigidPose::IDENTITY).unwrap(),
            Obstacle::sphere("link", 0.1, at)
                .unwrap()
                .with_motion(Motion::External),
        ];
        let m = scene_obstacle_markers(&obstacles, Distro::Jazzy, Time::default(), "world");
        let kinds: Vec<(i32, &str)> = m.iter().map(|m| (m.r#type, m.text.as_str())).collect();
        assert_eq!(
            kinds,
            [
                (Marker::SPHERE, "ball"),
                (Marker::CUBE, "box"),
                (Marker::CYLINDER, "pole"),
                (Marker::CYLINDER, "pill"),
                (Marker::SPHERE, "pill"),
                (Marker::SPHERE, "pill"),
                (Marker::CUBE, "ground"),
            ]
        );
        // Sizes come back through parry's f32 shapes: equal to ~1e-7 relative.
        let near = |a: f64, b: f64| (a - b).abs() < 1e-6;
        assert!(near(m[0].scale.x, 0.6), "{:?}", m[0].scale);
        assert_eq!(m[0].pose.position.z, 0.5);
        let s = &m[1].scale;
        assert!(near(s.x, 0.2) && near(s.y, 0.4) && near(s.z, 0.6), "{s:?}");
        // The pole runs along parry's local y: its marker's z axis points along world y.
        let q = &m[2].pose.orientation;
        let z = DQuat::from_xyzw(q.x, q.y, q.z, q.w) * Vec3::Z;
        assert!((z.abs() - Vec3::Y).length() < 1e-12, "{z:?}");
        assert!((m[2].scale.z - 0.8).abs() < 1e-6);
        assert_eq!(m[6].ns, PLANE_NS);
        assert!((m[6].pose.position.z + PLANE_THICKNESS / 2.0).abs() < 1e-12);
        let ids: Vec<i32> = m.iter().map(|m| m.id).collect();
        assert_eq!(ids, (0..7).collect::<Vec<_>>());
    }
}
