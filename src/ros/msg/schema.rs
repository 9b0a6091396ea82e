//! rosbag2 `ros2msg` schema text: the main `.msg` followed by every type it uses.
//!
//! Dependencies are found by parsing the field lines of the definitions themselves,
//! so the list is complete by construction (readers such as `rosbags` refuse a schema
//! with a missing dependency section).

use super::defs::msg_text;
use super::Distro;

const PRIMITIVES: &[&str] = &[
    "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16", "int32",
    "uint32", "int64", "uint64", "string", "wstring",
];

/// Separator line rosbag2 puts before each dependency section.
const SEPARATOR: &str =
    "================================================================================";

/// Full rosbag2 schema text of `type_name` (`pkg/msg/Type`), or `None` if it (or a
/// dependency) is not one of drape's message types.
pub fn schema_text(type_name: &str, distro: Distro) -> Option<String> {
    let mut out = msg_text(type_name, distro)?;
    let mut seen = vec![type_name.to_string()];
    let mut order = Vec::new();
    collect_dependencies(type_name, distro, &mut seen, &mut order)?;
    for dep in order {
        let text = msg_text(&dep, distro)?;
        if !out.ends_with('\n') {
            out.push('\n');
        }
        out.push_str(SEPARATOR);
        out.push_str("\nMSG: ");
        out.push_str(&dep.replacen("/msg/", "/", 1));
        out.push('\n');
        out.push_str(&text);
    }
    Some(out)
}

/// Depth-first, first-use order, each type once.
fn collect_dependencies(
    type_name: &str,
    distro: Distro,
    seen: &mut Vec<String>,
    order: &mut Vec<String>,
) -> Option<()> {
    let text = msg_text(type_name, distro)?;
    let package = type_name.split('/').next().unwrap_or_default();
    for field_type in field_types(&text) {
        let Some(full) = resolve(field_type, package) else {
            continue;
        };
        if seen.contains(&full) {
            continue;
        }
        seen.push(full.clone());
        order.push(full.clone());
        collect_dependencies(&full, distro, seen, order)?;
    }
    Some(())
}

/// Type tokens of the field lines (constants and comments skipped).
fn field_types(text: &str) -> impl Iterator<Item = &str> {
    text.lines().filter_map(|line| {
        let line = line.split('#').next().unwrap_or_default().trim();
        if line.is_empty() || line.contains('=') && !line.contains("<=") {
            return None;
        }
        line.split_whitespace().next()
    })
}

/// `pkg/msg/Type` for a non-primitive field type; arrays and bounds stripped.
fn resolve(field_type: &str, package: &str) -> Option<String> {
    let base = field_type.split('[').next().unwrap_or_default();
    let base = base.split("<=").next().unwrap_or_default();
    if PRIMITIVES.contains(&base) {
        return None;
    }
    Some(match base.split_once('/') {
        Some((pkg, name)) => format!("{pkg}/msg/{name}"),
        None if base == "Header" => "std_msgs/msg/Header".to_string(),
        None => format!("{package}/msg/{base}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joint_state_schema_has_header_then_time() {
        let text = schema_text("sensor_msgs/msg/JointState", Distro::Jazzy).unwrap();
        let sep = "=".repeat(80);
        let expected_tail = format!(
            "float64[] effort\n{sep}\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\n\
             string frame_id\n{sep}\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
        );
        assert!(text.ends_with(&expected_tail), "{text}");
        assert!(text.starts_with("std_msgs/Header header\n"));
    }

    #[test]
    fn marker_dependencies_differ_by_distro() {
        let sections = |d| {
            let text = schema_text("visualization_msgs/msg/MarkerArray", d).unwrap();
            let mut names: Vec<String> = text
                .lines()
                .filter_map(|l| l.strip_prefix("MSG: ").map(str::to_string))
                .collect();
            names.sort();
            names
        };
        let humble = sections(Distro::Humble);
        assert_eq!(
            humble,
            [
                "builtin_interfaces/Duration",
                "builtin_interfaces/Time",
                "geometry_msgs/Point",
                "geometry_msgs/Pose",
                "geometry_msgs/Quaternion",
                "geometry_msgs/Vector3",
                "std_msgs/ColorRGBA",
                "std_msgs/Header",
                "visualization_msgs/Marker",
            ]
        );
        let jazzy = sections(Distro::Jazzy);
        for extra in [
            "sensor_msgs/CompressedImage",
            "visualization_msgs/MeshFile",
            "visualization_msgs/UVCoordinate",
        ] {
            assert!(jazzy.iter().any(|s| s == extra), "{extra} missing");
        }
        assert_eq!(jazzy.len(), humble.len() + 3);
    }
}
