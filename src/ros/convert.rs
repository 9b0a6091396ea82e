//! Cloth state to ROS messages. Pure functions: no I/O, no clocks.

use crate::ros::msg::{
    ColorRGBA, Distro, Header, Marker, Point, PointCloud2, PointField, Pose, Time, Vector3,
};
use crate::Vec3;

/// Bytes per cloud point: x y z normal_x normal_y normal_z as f32.
pub const CLOUD_POINT_STEP: u32 = 24;

/// A TRIANGLE_LIST Marker of the mesh: three points per triangle (in triangle order),
/// action ADD, identity pose, unit scale, one `color`, id 0, lifetime forever.
///
/// # Panics
/// If a triangle indexes past `positions` (a mesh invariant the cloth upholds).
pub fn mesh_marker(
    distro: Distro,
    stamp: Time,
    frame_id: &str,
    ns: &str,
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    color: ColorRGBA,
) -> Marker {
    let points = triangles
        .iter()
        .flatten()
        .map(|&i| Point::from(positions[i as usize]))
        .collect();
    Marker {
        distro,
        header: Header::new(stamp, frame_id),
        ns: ns.to_string(),
        id: 0,
        r#type: Marker::TRIANGLE_LIST,
        action: Marker::ADD,
        pose: Pose::default(),
        scale: Vector3 {
            x: 1.0,
            y: 1.0,
            z: 1.0,
        },
        color,
        frame_locked: false,
        points,
        ..Marker::default()
    }
}

/// An unorganised cloud (height 1) with one point per vertex in index order; fields
/// x y z normal_x normal_y normal_z as little-endian FLOAT32 at offsets 0, 4, .., 20.
///
/// # Panics
/// If `normals` and `positions` differ in length.
pub fn point_cloud(
    stamp: Time,
    frame_id: &str,
    positions: &[Vec3],
    normals: &[Vec3],
) -> PointCloud2 {
    assert_eq!(
        positions.len(),
        normals.len(),
        "point_cloud: one normal per position"
    );
    let fields = ["x", "y", "z", "normal_x", "normal_y", "normal_z"]
        .iter()
        .zip((0u32..).step_by(4))
        .map(|(name, offset)| PointField {
            name: name.to_string(),
            offset,
            datatype: PointField::FLOAT32,
            count: 1,
        })
        .collect();
    let mut data = Vec::with_capacity(positions.len() * CLOUD_POINT_STEP as usize);
    for (p, n) in positions.iter().zip(normals) {
        for v in [p.x, p.y, p.z, n.x, n.y, n.z] {
            data.extend_from_slice(&(v as f32).to_le_bytes());
        }
    }
    let width = u32::try_from(positions.len()).unwrap_or(u32::MAX);
    PointCloud2 {
        header: Header::new(stamp, frame_id),
        height: 1,
        width,
        fields,
        is_bigendian: false,
        point_step: CLOUD_POINT_STEP,
        row_step: width.saturating_mul(CLOUD_POINT_STEP),
        data,
        is_dense: true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn marker_expands_triangles_in_order() {
        let pos = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.5),
        ];
        let color = ColorRGBA::new(0.1, 0.2, 0.3, 1.0);
        let m = mesh_marker(
            Distro::Humble,
            Time::from_nanos(5),
            "world",
            "cloth",
            &pos,
            &[[2, 0, 1], [1, 2, 0]],
            color,
        );
        let xs: Vec<[f64; 3]> = m.points.iter().map(|p| [p.x, p.y, p.z]).collect();
        assert_eq!(
            xs,
            [
                [0.0, 1.0, 0.5],
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.5],
                [0.0, 0.0, 0.0]
            ]
        );
        assert_eq!((m.r#type, m.action, m.distro), (11, 0, Distro::Humble));
        assert_eq!(m.pose.orientation.w, 1.0);
        assert_eq!((m.scale.x, m.scale.y, m.scale.z), (1.0, 1.0, 1.0));
        assert_eq!(m.color, color);
        assert_eq!(m.header.frame_id, "world");
        assert!(!m.frame_locked);
    }

    #[test]
    fn cloud_packs_little_endian_f32() {
        let pos = [Vec3::new(1.0, -2.0, 0.25), Vec3::new(3.0, 4.0, 5.0)];
        let nrm = [Vec3::Z, Vec3::new(0.6, 0.8, 0.0)];
        let c = point_cloud(Time::default(), "map", &pos, &nrm);
        assert_eq!(
            (c.width, c.height, c.point_step, c.row_step),
            (2, 1, 24, 48)
        );
        assert_eq!(c.data.len(), 48);
        let f = |i: usize| f32::from_le_bytes(c.data[4 * i..4 * i + 4].try_into().unwrap());
        let got: Vec<f32> = (0..12).map(f).collect();
        assert_eq!(
            got,
            [1.0, -2.0, 0.25, 0.0, 0.0, 1.0, 3.0, 4.0, 5.0, 0.6, 0.8, 0.0]
        );
        let names: Vec<&str> = c.fields.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["x", "y", "z", "normal_x", "normal_y", "normal_z"]);
        assert!(c.fields.iter().all(|f| f.datatype == 7 && f.count == 1));
        assert_eq!(c.fields[5].offset, 20);
        assert!(c.is_dense && !c.is_bigendian);
    }
}
