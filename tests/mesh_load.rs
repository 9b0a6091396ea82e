//! Mesh loaders on small files generated here: STL (binary, ASCII), OBJ, Collada, and hostile
//! inputs. Reference values are exact volumes of unit solids (divergence theorem).

use drape::mesh::{convex_hull, load_mesh, MeshError, TriMeshData};
use drape::Vec3;
use std::path::{Path, PathBuf};

/// Right tetrahedron (0,0,0),(1,0,0),(0,1,0),(0,0,1), outward winding; volume 1/6.
const TETRA: [[[f32; 3]; 3]; 4] = [
    [[0., 0., 0.], [0., 1., 0.], [1., 0., 0.]],
    [[0., 0., 0.], [1., 0., 0.], [0., 0., 1.]],
    [[0., 0., 0.], [0., 0., 1.], [0., 1., 0.]],
    [[1., 0., 0.], [0., 1., 0.], [0., 0., 1.]],
];

fn binary_stl(header: &[u8], tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut b = header.to_vec();
    b.resize(80, b' ');
    b.extend((tris.len() as u32).to_le_bytes());
    for t in tris {
        b.extend([0f32; 3].iter().flat_map(|x| x.to_le_bytes()));
        for v in t {
            b.extend(v.iter().flat_map(|x| x.to_le_bytes()));
        }
        b.extend([0u8; 2]);
    }
    b
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).expect("write test file");
    p
}

fn close(a: f64, b: f64) -> bool {
    // f32 storage of small integers/fractions is exact; 1e-12 covers f64 summation.
    (a - b).abs() < 1e-12
}

#[test]
fn binary_stl_is_merged_and_oriented() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "t.stl", &binary_stl(b"binary", &TETRA));
    let m = load_mesh(&p, Vec3::ONE).unwrap();
    assert_eq!(m.vertices.len(), 4, "identical corners must be merged");
    assert_eq!(m.indices.len(), 4);
    assert!(close(m.signed_volume(), 1.0 / 6.0), "{}", m.signed_volume());
}

#[test]
fn binary_stl_whose_header_starts_with_solid_is_still_binary() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "sw.STL",
        &binary_stl(b"solid exported by CAD", &TETRA),
    );
    let m = load_mesh(&p, Vec3::ONE).unwrap();
    assert_eq!(m.indices.len(), 4);
}

#[test]
fn ascii_stl_matches_binary() {
    let mut s = String::from("solid tetra\n");
    for t in TETRA {
        s.push_str("facet normal 0 0 0\nouter loop\n");
        for v in t {
            s.push_str(&format!("vertex {} {} {}\n", v[0], v[1], v[2]));
        }
        s.push_str("endloop\nendfacet\n");
    }
    s.push_str("endsolid tetra\n");
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "a.stl", s.as_bytes());
    let m = load_mesh(&p, Vec3::new(2.0, 2.0, 2.0)).unwrap();
    assert_eq!(m.indices.len(), 4);
    assert!(close(m.signed_volume(), 8.0 / 6.0), "{}", m.signed_volume());
}

#[test]
fn stl_header_claiming_four_billion_triangles_is_rejected() {
    let mut b = binary_stl(b"hostile", &TETRA[..1]);
    b[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "huge.stl", &b);
    let err = load_mesh(&p, Vec3::ONE).unwrap_err();
    let msg = err.to_string();
    assert!(
        matches!(
            err,
            MeshError::StlTruncated {
                claimed: 4294967295,
                len: 134,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(
        msg.contains("4294967295") && msg.contains("huge.stl"),
        "{msg}"
    );
}

#[test]
fn truncated_stl_and_stl_with_nan_are_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "short.stl", b"tiny");
    assert!(matches!(
        load_mesh(&p, Vec3::ONE),
        Err(MeshError::StlHeader { len: 4, .. })
    ));
    let mut t = TETRA;
    t[3][1][0] = f32::NAN;
    let p = write(dir.path(), "nan.stl", &binary_stl(b"nan", &t));
    let err = load_mesh(&p, Vec3::ONE).unwrap_err();
    assert!(matches!(err, MeshError::NonFinite { .. }), "{err:?}");
    assert!(err.to_string().contains("nan.stl"));
    let p = write(dir.path(), "empty.stl", &binary_stl(b"none", &[]));
    assert!(matches!(
        load_mesh(&p, Vec3::ONE),
        Err(MeshError::Empty { .. })
    ));
}

const CUBE_OBJ: &str = "# unit cube, quads, outward\n\
o cube\n\
v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

#[test]
fn obj_quads_are_triangulated_and_scaled() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "cube.obj", CUBE_OBJ.as_bytes());
    let m = load_mesh(&p, Vec3::ONE).unwrap();
    assert_eq!((m.vertices.len(), m.indices.len()), (8, 12));
    assert!(close(m.signed_volume(), 1.0));
    let m = load_mesh(&p, Vec3::new(2.0, 3.0, 4.0)).unwrap();
    assert!(close(m.signed_volume(), 24.0));
    // A mirroring scale must keep the winding outward.
    let m = load_mesh(&p, Vec3::new(-1.0, 1.0, 1.0)).unwrap();
    assert!(close(m.signed_volume(), 1.0), "{}", m.signed_volume());
    assert!(matches!(
        load_mesh(&p, Vec3::new(0.0, 1.0, 1.0)),
        Err(MeshError::BadScale { .. })
    ));
}

#[test]
fn obj_with_two_objects_is_concatenated() {
    let two = format!("{CUBE_OBJ}o second\nv 5 5 5\nv 6 5 5\nv 5 6 5\nf 9 10 11\n");
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "two.obj", two.as_bytes());
    let m = load_mesh(&p, Vec3::ONE).unwrap();
    assert_eq!(m.indices.len(), 13);
    let last = m.indices[12].map(|i| m.vertices[i as usize]);
    assert_eq!(last[1], Vec3::new(6.0, 5.0, 5.0));
}

#[test]
fn bad_obj_inputs_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "oob.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
    );
    let err = load_mesh(&p, Vec3::ONE).unwrap_err();
    assert!(err.to_string().contains("oob.obj"), "{err}");
    let p = write(
        dir.path(),
        "nan.obj",
        b"v 0 0 0\nv 1 0 0\nv NaN 1 0\nf 1 2 3\n",
    );
    let err = load_mesh(&p, Vec3::ONE).unwrap_err();
    assert!(err.to_string().contains("nan.obj"), "{err}");
    let p = write(dir.path(), "empty.obj", b"# nothing\n");
    assert!(matches!(
        load_mesh(&p, Vec3::ONE),
        Err(MeshError::Empty { .. })
    ));
}

#[test]
fn unknown_extension_and_missing_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "x.ply", b"ply");
    assert!(matches!(
        load_mesh(&p, Vec3::ONE),
        Err(MeshError::UnsupportedFormat { .. })
    ));
    let missing = dir.path().join("missing.stl");
    let err = load_mesh(&missing, Vec3::ONE).unwrap_err();
    assert!(matches!(err, MeshError::Io { .. }) && err.to_string().contains("missing.stl"));
}

/// A 100-unit cube (centimetres) as a `<polylist>` of quads, placed twice by the scene.
fn cube_dae(up: &str, extra_node: &str) -> String {
    format!(
        r##"<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="centimeter" meter="0.01"/><up_axis>{up}</up_axis></asset>
  <library_geometries>
    <geometry id="cube" name="cube"><mesh>
      <source id="cube-pos">
        <float_array id="cube-pos-array" count="24">0 0 0 100 0 0 100 100 0 0 100 0 0 0 100 100 0 100 100 100 100 0 100 100</float_array>
        <technique_common><accessor source="#cube-pos-array" count="8" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common>
      </source>
      <source id="cube-nrm"><float_array id="n" count="3">0 0 1</float_array>
        <technique_common><accessor source="#n" count="1" stride="3"/></technique_common></source>
      <vertices id="cube-vtx"><input semantic="POSITION" source="#cube-pos"/></vertices>
      <polylist count="6">
        <input semantic="VERTEX" source="#cube-vtx" offset="0"/>
        <input semantic="NORMAL" source="#cube-nrm" offset="1"/>
        <vcount>4 4 4 4 4 4</vcount>
        <p>0 0 3 0 2 0 1 0  4 0 5 0 6 0 7 0  0 0 1 0 5 0 4 0  1 0 2 0 6 0 5 0  2 0 3 0 7 0 6 0  3 0 0 0 4 0 7 0</p>
      </polylist>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene">
      <node id="a"><translate>0 0 0</translate><instance_geometry url="#cube"/></node>
      {extra_node}
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>"##
    )
}

#[test]
fn dae_units_scene_transforms_and_z_up() {
    let dir = tempfile::tempdir().unwrap();
    let second = r#"<node id="b"><matrix>1 0 0 500 0 1 0 0 0 0 1 0 0 0 0 1</matrix><scale>2 1 1</scale><instance_geometry url="cube"/></node>"#;
    let p = write(dir.path(), "cube.dae", cube_dae("Z_UP", second).as_bytes());
    let m = load_mesh(&p, Vec3::ONE).unwrap();
    assert_eq!(m.indices.len(), 24);
    // 1 m^3 plus a cube stretched 2x in x: 3 m^3.
    assert!(
        (m.signed_volume() - 3.0).abs() < 1e-9,
        "{}",
        m.signed_volume()
    );
    let (lo, hi) = m.aabb().unwrap();
    assert!((lo - Vec3::ZERO).length() < 1e-12);
    // Second cube: x in [5, 7] m (matrix translation 500 cm, then scale 2).
    assert!((hi - Vec3::new(7.0, 1.0, 1.0)).length() < 1e-9, "{hi}");
}

#[test]
fn dae_y_up_is_rotated_to_z_up() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "y.dae", cube_dae("Y_UP", "").as_bytes());
    let m = load_mesh(&p, Vec3::ONE).unwrap();
    let (lo, hi) = m.aabb().unwrap();
    // Y_UP -> Z_UP maps (x, y, z) to (x, -z, y): the unit cube lands in y in [-1, 0].
    assert!((lo - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-9, "{lo}");
    assert!((hi - Vec3::new(1.0, 0.0, 1.0)).length() < 1e-9, "{hi}");
    assert!((m.signed_volume() - 1.0).abs() < 1e-9);
}

#[test]
fn dae_triangles_and_bad_indices() {
    let tri = r##"<COLLADA><library_geometries><geometry id="g"><mesh>
      <source id="s"><float_array id="f" count="9">0 0 0 1 0 0 0 1 0</float_array></source>
      <vertices id="v"><input semantic="POSITION" source="#s"/></vertices>
      <triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 IDX</p></triangles>
    </mesh></geometry></library_geometries></COLLADA>"##;
    let dir = tempfile::tempdir().unwrap();
    let ok = write(dir.path(), "tri.dae", tri.replace("IDX", "2").as_bytes());
    let m = load_mesh(&ok, Vec3::ONE).unwrap();
    assert_eq!(m.indices, vec![[0, 1, 2]]);
    let bad = write(dir.path(), "bad.dae", tri.replace("IDX", "7").as_bytes());
    // The file and the geometry in the error, the element at fault in its source.
    let err = load_mesh(&bad, Vec3::ONE).unwrap_err();
    assert!(
        matches!(
            &err,
            MeshError::Collada {
                geometry: Some(g),
                source: drape::mesh::DaeError::IndexOutOfRange {
                    index: 7,
                    positions: 3
                },
                ..
            } if g == "g"
        ),
        "{err:?}"
    );
    assert_eq!(
        format!("{err}: {}", std::error::Error::source(&err).unwrap()),
        format!(
            "mesh {}: Collada geometry `g`: vertex index 7 out of range (mesh has 3 positions)",
            bad.display()
        )
    );
    let broken = write(dir.path(), "broken.dae", b"<COLLADA><library_geometries>");
    // Not well-formed XML: the XML parser's error is the cause, not a copy of its text.
    let err = load_mesh(&broken, Vec3::ONE).unwrap_err();
    assert!(
        matches!(
            &err,
            MeshError::Xml {
                source: drape::mesh::XmlError::Unclosed,
                ..
            }
        ),
        "{err:?}"
    );
    let mut chain = err.to_string();
    let mut cause = std::error::Error::source(&err);
    while let Some(c) = cause {
        chain = format!("{chain}: {c}");
        cause = c.source();
    }
    assert!(
        chain.contains("broken.dae")
            && chain.contains("document ended before the root element closed"),
        "{chain}"
    );
}

#[test]
fn convex_hull_drops_interior_points() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "cube.obj", CUBE_OBJ.as_bytes());
    let mut m: TriMeshData = load_mesh(&p, Vec3::ONE).unwrap();
    m.vertices.push(Vec3::splat(0.5));
    let hull = convex_hull(&m).unwrap();
    assert_eq!(hull.vertices.len(), 8);
    // parry works in f32: volume exact for integer corners.
    assert!(
        (hull.signed_volume() - 1.0).abs() < 1e-6,
        "{}",
        hull.signed_volume()
    );
}

#[test]
fn bundled_head_mesh_is_a_closed_inscribed_ellipsoid() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("urdf/meshes/head.stl");
    let m = load_mesh(&p, Vec3::ONE).unwrap();
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.09 * 0.08 * 0.11;
    let v = m.signed_volume();
    // All vertices lie on the ellipsoid, so the polyhedron is inside it: v < exact; a 32x16
    // tessellation loses O(1/n^2), a few percent.
    assert!(
        v < exact && v > 0.95 * exact,
        "volume {v} vs ellipsoid {exact}"
    );
}

#[test]
fn simplification_meets_the_budget_and_stays_inside() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("urdf/meshes/head.stl");
    let m = load_mesh(&p, Vec3::ONE).unwrap();
    let s = drape::mesh::simplify(&m, 200);
    assert!(
        s.indices.len() <= 200 && s.indices.len() >= 50,
        "{}",
        s.indices.len()
    );
    // Cluster representatives are means of surface points of a convex body: inside its hull,
    // so the volume can only shrink; a coarse grid loses at most a few tens of percent.
    let (v0, v1) = (m.signed_volume(), s.signed_volume());
    assert!(v1 <= v0 * (1.0 + 1e-9) && v1 > 0.6 * v0, "{v1} vs {v0}");
    let ((lo0, hi0), (lo1, hi1)) = (m.aabb().unwrap(), s.aabb().unwrap());
    assert!(lo1.cmpge(lo0 - 1e-12).all() && hi1.cmple(hi0 + 1e-12).all());
    assert!(drape::mesh::validate(&p, &s).is_ok());
    assert_eq!(
        drape::mesh::simplify(&m, 10_000),
        m,
        "within budget: unchanged"
    );
}
