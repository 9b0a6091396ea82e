//! Official `.msg` definitions (comments stripped) of every type drape writes.
//!
//! rosbag2 readers rebuild the message layout from this text, so it must match the
//! upstream definitions field for field; `tests/py/check_bag.py` compares them with the
//! type store of the independent `rosbags` library.

use super::Distro;

const TIME: &str = "int32 sec\nuint32 nanosec\n";

const DURATION: &str = "int32 sec\nuint32 nanosec\n";

const HEADER: &str = "builtin_interfaces/Time stamp\nstring frame_id\n";

const COLOR_RGBA: &str = "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n";

const STRING: &str = "string data\n";

const POINT: &str = "float64 x\nfloat64 y\nfloat64 z\n";

const VECTOR3: &str = "float64 x\nfloat64 y\nfloat64 z\n";

const QUATERNION: &str = "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n";

const POSE: &str = "Point position\nQuaternion orientation\n";

const TRANSFORM: &str = "Vector3 translation\nQuaternion rotation\n";

const TRANSFORM_STAMPED: &str =
    "std_msgs/Header header\nstring child_frame_id\nTransform transform\n";

const MARKER_CONSTANTS: &str = "int32 ARROW=0
int32 CUBE=1
int32 SPHERE=2
int32 CYLINDER=3
int32 LINE_STRIP=4
int32 LINE_LIST=5
int32 CUBE_LIST=6
int32 SPHERE_LIST=7
int32 POINTS=8
int32 TEXT_VIEW_FACING=9
int32 MESH_RESOURCE=10
int32 TRIANGLE_LIST=11
";

const MARKER_ACTIONS_AND_HEAD: &str = "
int32 ADD=0
int32 MODIFY=0
int32 DELETE=2
int32 DELETEALL=3

std_msgs/Header header
string ns
int32 id
int32 type
int32 action
geometry_msgs/Pose pose
geometry_msgs/Vector3 scale
std_msgs/ColorRGBA color
builtin_interfaces/Duration lifetime
bool frame_locked

geometry_msgs/Point[] points
std_msgs/ColorRGBA[] colors
";

const MARKER_HUMBLE_TAIL: &str = "
string text

string mesh_resource
bool mesh_use_embedded_materials
";

const MARKER_JAZZY_TAIL: &str = "
string texture_resource
sensor_msgs/CompressedImage texture
UVCoordinate[] uv_coordinates

string text

string mesh_resource
MeshFile mesh_file
bool mesh_use_embedded_materials
";

const MARKER_ARRAY: &str = "Marker[] markers\n";

const UV_COORDINATE: &str = "float32 u\nfloat32 v\n";

const MESH_FILE: &str = "string filename\n\nuint8[] data\n";

const COMPRESSED_IMAGE: &str = "std_msgs/Header header\nstring format\nuint8[] data\n";

const POINT_FIELD: &str = "uint8 INT8    = 1
uint8 UINT8   = 2
uint8 INT16   = 3
uint8 UINT16  = 4
uint8 INT32   = 5
uint8 UINT32  = 6
uint8 FLOAT32 = 7
uint8 FLOAT64 = 8

string name
uint32 offset
uint8  datatype
uint32 count
";

const POINT_CLOUD2: &str = "std_msgs/Header header

uint32 height
uint32 width

PointField[] fields

bool    is_bigendian
uint32  point_step
uint32  row_step
uint8[] data

bool is_dense
";

const JOINT_STATE: &str = "std_msgs/Header header

string[] name
float64[] position
float64[] velocity
float64[] effort
";

const TF_MESSAGE: &str = "geometry_msgs/TransformStamped[] transforms\n";

const CLOCK: &str = "builtin_interfaces/Time clock\n";

const DIAGNOSTIC_ARRAY: &str = "std_msgs/Header header\nDiagnosticStatus[] status\n";

const DIAGNOSTIC_STATUS: &str = "byte OK=0
byte WARN=1
byte ERROR=2
byte STALE=3

byte level
string name
string message
string hardware_id
KeyValue[] values
";

const KEY_VALUE: &str = "string key\nstring value\n";

/// The `.msg` text of `type_name` (`pkg/msg/Type`) for `distro`, or `None` for a type
/// drape does not define.
pub fn msg_text(type_name: &str, distro: Distro) -> Option<String> {
    let text = match type_name {
        "builtin_interfaces/msg/Time" => TIME,
        "builtin_interfaces/msg/Duration" => DURATION,
        "std_msgs/msg/Header" => HEADER,
        "std_msgs/msg/ColorRGBA" => COLOR_RGBA,
        "std_msgs/msg/String" => STRING,
        "geometry_msgs/msg/Point" => POINT,
        "geometry_msgs/msg/Vector3" => VECTOR3,
        "geometry_msgs/msg/Quaternion" => QUATERNION,
        "geometry_msgs/msg/Pose" => POSE,
        "geometry_msgs/msg/Transform" => TRANSFORM,
        "geometry_msgs/msg/TransformStamped" => TRANSFORM_STAMPED,
        "visualization_msgs/msg/Marker" => return Some(marker_text(distro)),
        "visualization_msgs/msg/MarkerArray" => MARKER_ARRAY,
        "visualization_msgs/msg/UVCoordinate" => UV_COORDINATE,
        "visualization_msgs/msg/MeshFile" => MESH_FILE,
        "sensor_msgs/msg/CompressedImage" => COMPRESSED_IMAGE,
        "sensor_msgs/msg/PointField" => POINT_FIELD,
        "sensor_msgs/msg/PointCloud2" => POINT_CLOUD2,
        "sensor_msgs/msg/JointState" => JOINT_STATE,
        "tf2_msgs/msg/TFMessage" => TF_MESSAGE,
        "rosgraph_msgs/msg/Clock" => CLOCK,
        "diagnostic_msgs/msg/DiagnosticArray" => DIAGNOSTIC_ARRAY,
        "diagnostic_msgs/msg/DiagnosticStatus" => DIAGNOSTIC_STATUS,
        "diagnostic_msgs/msg/KeyValue" => KEY_VALUE,
        _ => return None,
    };
    Some(text.to_string())
}

fn marker_text(distro: Distro) -> String {
    match distro {
        Distro::Humble => [
            MARKER_CONSTANTS,
            MARKER_ACTIONS_AND_HEAD,
            MARKER_HUMBLE_TAIL,
        ]
        .concat(),
        Distro::Jazzy => [
            MARKER_CONSTANTS,
            "int32 ARROW_STRIP=12\n",
            MARKER_ACTIONS_AND_HEAD,
            MARKER_JAZZY_TAIL,
        ]
        .concat(),
    }
}
