//! visualization_msgs: Marker (Humble and Jazzy layouts) and MarkerArray.

use super::{ColorRGBA, CompressedImage, Distro, Duration, Header, Point, Pose, Vector3};
use serde::ser::{SerializeStruct, Serializer};
use serde::{Deserialize, Serialize};

/// visualization_msgs/UVCoordinate (Jazzy): texture coordinate of one Marker point.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct UVCoordinate {
    pub u: f32,
    pub v: f32,
}

/// visualization_msgs/MeshFile (Jazzy): a mesh file embedded in a Marker.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct MeshFile {
    pub filename: String,
    #[serde(with = "super::bytes")]
    pub data: Vec<u8>,
}

/// visualization_msgs/Marker. One struct for both layouts: `distro` picks the wire
/// layout, and the Jazzy-only fields (`texture_resource`, `texture`, `uv_coordinates`,
/// `mesh_file`) are left out of a Humble Marker's bytes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Marker {
    /// Wire layout; not a message field.
    pub distro: Distro,
    pub header: Header,
    pub ns: String,
    pub id: i32,
    pub r#type: i32,
    pub action: i32,
    pub pose: Pose,
    pub scale: Vector3,
    pub color: ColorRGBA,
    pub lifetime: Duration,
    pub frame_locked: bool,
    pub points: Vec<Point>,
    pub colors: Vec<ColorRGBA>,
    /// Jazzy only.
    pub texture_resource: String,
    /// Jazzy only.
    pub texture: CompressedImage,
    /// Jazzy only.
    pub uv_coordinates: Vec<UVCoordinate>,
    pub text: String,
    pub mesh_resource: String,
    /// Jazzy only.
    pub mesh_file: MeshFile,
    pub mesh_use_embedded_materials: bool,
}

impl Marker {
    pub const ARROW: i32 = 0;
    pub const CUBE: i32 = 1;
    pub const SPHERE: i32 = 2;
    pub const CYLINDER: i32 = 3;
    pub const LINE_STRIP: i32 = 4;
    pub const LINE_LIST: i32 = 5;
    pub const CUBE_LIST: i32 = 6;
    pub const SPHERE_LIST: i32 = 7;
    pub const POINTS: i32 = 8;
    pub const TEXT_VIEW_FACING: i32 = 9;
    pub const MESH_RESOURCE: i32 = 10;
    pub const TRIANGLE_LIST: i32 = 11;
    pub const ADD: i32 = 0;
    pub const MODIFY: i32 = 0;
    pub const DELETE: i32 = 2;
    pub const DELETEALL: i32 = 3;
}

impl Serialize for Marker {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let jazzy = self.distro == Distro::Jazzy;
        let mut s = serializer.serialize_struct("Marker", if jazzy { 19 } else { 15 })?;
        s.serialize_field("header", &self.header)?;
        s.serialize_field("ns", &self.ns)?;
        s.serialize_field("id", &self.id)?;
        s.serialize_field("type", &self.r#type)?;
        s.serialize_field("action", &self.action)?;
        s.serialize_field("pose", &self.pose)?;
        s.serialize_field("scale", &self.scale)?;
        s.serialize_field("color", &self.color)?;
        s.serialize_field("lifetime", &self.lifetime)?;
        s.serialize_field("frame_locked", &self.frame_locked)?;
        s.serialize_field("points", &self.points)?;
        s.serialize_field("colors", &self.colors)?;
        if jazzy {
            s.serialize_field("texture_resource", &self.texture_resource)?;
            s.serialize_field("texture", &self.texture)?;
            s.serialize_field("uv_coordinates", &self.uv_coordinates)?;
        }
        s.serialize_field("text", &self.text)?;
        s.serialize_field("mesh_resource", &self.mesh_resource)?;
        if jazzy {
            s.serialize_field("mesh_file", &self.mesh_file)?;
        }
        s.serialize_field(
            "mesh_use_embedded_materials",
            &self.mesh_use_embedded_materials,
        )?;
        s.end()
    }
}

/// visualization_msgs/MarkerArray; all markers must share one layout.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct MarkerArray {
    pub markers: Vec<Marker>,
}
