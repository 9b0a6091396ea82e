//! Proptest-driven fuzzing of every loader on malformed input: start from valid files, then flip
//! bytes, insert and delete runs, truncate, and replace numbers with huge, negative or non-finite
//! ones. Every loader must answer with an error naming the file (or accept the input), never
//! panic. Case counts are bounded so the whole file runs in seconds.

use drape::mesh::load_mesh;
use drape::robot::{Robot, UrdfOptions};
use drape::scene::Scene;
use drape::Vec3;
use proptest::prelude::*;
use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// One edit of a file's bytes; positions are fractions of the current length.
#[derive(Debug, Clone)]
enum Edit {
    Flip(f64, u8),
    Insert(f64, Vec<u8>),
    Delete(f64, usize),
    Truncate(f64),
    /// Replace the next run of ASCII digits with a nasty number.
    Number(f64, &'static str),
    /// Duplicate a chunk (repeated elements, repeated headers).
    Duplicate(f64, usize),
}

const NASTY: [&str; 10] = [
    "4294967295",
    "4000000000",
    "18446744073709551616",
    "-1",
    "0",
    "1e308",
    "-1e308",
    "nan",
    "inf",
    "99999999999999999999999999",
];

fn edit() -> impl Strategy<Value = Edit> {
    let pos = 0.0..1.0f64;
    prop_oneof![
        3 => (pos.clone(), any::<u8>()).prop_map(|(p, b)| Edit::Flip(p, b)),
        1 => (pos.clone(), prop::collection::vec(any::<u8>(), 1..16)).prop_map(|(p, b)| Edit::Insert(p, b)),
        1 => (pos.clone(), 1usize..64).prop_map(|(p, n)| Edit::Delete(p, n)),
        1 => pos.clone().prop_map(Edit::Truncate),
        3 => (pos.clone(), prop::sample::select(NASTY.to_vec())).prop_map(|(p, s)| Edit::Number(p, s)),
        1 => (pos, 1usize..256).prop_map(|(p, n)| Edit::Duplicate(p, n)),
    ]
}

fn edits() -> impl Strategy<Value = Vec<Edit>> {
    prop::collection::vec(edit(), 1..6)
}

fn at(len: usize, f: f64) -> usize {
    ((len as f64 * f) as usize).min(len)
}

fn mutate(mut b: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for e in edits {
        let len = b.len();
        match e {
            Edit::Flip(p, x) => {
                if len > 0 {
                    let i = at(len - 1, *p);
                    b[i] = *x;
                }
            }
            Edit::Insert(p, bytes) => {
                let i = at(len, *p);
                b.splice(i..i, bytes.iter().copied());
            }
            Edit::Delete(p, n) => {
                let i = at(len, *p);
                let j = (i + n).min(len);
                b.drain(i..j);
            }
            Edit::Truncate(p) => b.truncate(at(len, *p)),
            Edit::Number(p, s) => {
                let start = at(len, *p);
                if let Some(i) = (start..len).find(|&i| b[i].is_ascii_digit()) {
                    let j = (i..len).find(|&j| !b[j].is_ascii_digit()).unwrap_or(len);
                    b.splice(i..j, s.bytes());
                }
            }
            Edit::Duplicate(p, n) => {
                let i = at(len, *p);
                let j = (i + n).min(len);
                let chunk: Vec<u8> = b[i..j].to_vec();
                b.splice(j..j, chunk);
            }
        }
    }
    b
}

const TETRA_OBJ: &str = "# tetrahedron\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\n\
f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2//1 3//1 4//1\n";

const TETRA_ASCII_STL: &str = "solid tetra\n\
facet normal 0 0 -1\n outer loop\n  vertex 0 0 0\n  vertex 0 1 0\n  vertex 1 0 0\n endloop\nendfacet\n\
facet normal 0 -1 0\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 0 1\n endloop\nendfacet\n\
facet normal -1 0 0\n outer loop\n  vertex 0 0 0\n  vertex 0 0 1\n  vertex 0 1 0\n endloop\nendfacet\n\
facet normal 1 1 1\n outer loop\n  vertex 1 0 0\n  vertex 0 1 0\n  vertex 0 0 1\n endloop\nendfacet\n\
endsolid tetra\n";

const CUBE_DAE: &str = r##"<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="centimeter" meter="0.01"/><up_axis>Y_UP</up_axis></asset>
  <library_geometries>
    <geometry id="cube" name="cube"><mesh>
      <source id="cube-pos">
        <float_array id="cube-pos-array" count="24">0 0 0 100 0 0 100 100 0 0 100 0 0 0 100 100 0 100 100 100 100 0 100 100</float_array>
        <technique_common><accessor source="#cube-pos-array" count="8" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common>
      </source>
      <vertices id="cube-vtx"><input semantic="POSITION" source="#cube-pos"/></vertices>
      <polylist count="6">
        <input semantic="VERTEX" source="#cube-vtx" offset="0"/>
        <vcount>4 4 4 4 4 4</vcount>
        <p>0 3 2 1 4 5 6 7 0 1 5 4 1 2 6 5 2 3 7 6 3 0 4 7</p>
      </polylist>
      <triangles count="2"><input semantic="VERTEX" source="#cube-vtx" offset="0"/><p>0 1 2 0 2 3</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene">
      <node id="a"><matrix>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1</matrix><instance_geometry url="#cube"/>
        <node id="b"><translate>0 0 200</translate><scale>2 2 2</scale><instance_geometry url="#cube"/></node>
      </node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>"##;

/// Loads mutated bytes as a mesh file named `name`: an error must name the file.
fn check_mesh(name: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    let dir = tempfile::tempdir().map_err(|e| TestCaseError::fail(e.to_string()))?;
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).map_err(|e| TestCaseError::fail(e.to_string()))?;
    match load_mesh(&path, Vec3::ONE) {
        Ok(m) => {
            // Accepted input must satisfy the mesh invariants.
            prop_assert!(!m.indices.is_empty());
            prop_assert!(m.vertices.iter().all(|v| v.is_finite()));
            prop_assert!(m
                .indices
                .iter()
                .flatten()
                .all(|&i| (i as usize) < m.vertices.len()));
        }
        Err(e) => prop_assert!(
            e.to_string().contains(name),
            "error does not name the file: {}",
            e
        ),
    }
    Ok(())
}

fn head_stl() -> Vec<u8> {
    std::fs::read(root().join("urdf/meshes/head.stl")).expect("bundled STL")
}

/// Case count: the bounded default, or `PROPTEST_CASES` for a longer run.
fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(256), ..ProptestConfig::default() })]

    #[test]
    fn binary_stl(e in edits()) {
        // Keep mutations mostly in the header and the first records.
        let mut b = head_stl();
        b.truncate(84 + 50 * 40);
        b[80..84].copy_from_slice(&40u32.to_le_bytes());
        check_mesh("m.stl", &mutate(b, &e))?;
    }

    #[test]
    fn binary_stl_count_field(count in any::<u32>(), body in 0usize..4000) {
        let mut b = head_stl();
        b.truncate(84 + body);
        b[80..84].copy_from_slice(&count.to_le_bytes());
        check_mesh("count.stl", &b)?;
    }

    #[test]
    fn ascii_stl(e in edits()) {
        check_mesh("a.stl", &mutate(TETRA_ASCII_STL.as_bytes().to_vec(), &e))?;
    }

    #[test]
    fn obj(e in edits()) {
        check_mesh("m.obj", &mutate(TETRA_OBJ.as_bytes().to_vec(), &e))?;
    }

    #[test]
    fn dae(e in edits()) {
        check_mesh("m.dae", &mutate(CUBE_DAE.as_bytes().to_vec(), &e))?;
    }

    #[test]
    fn urdf(e in edits()) {
        let text = std::fs::read(root().join("urdf/drape_bot.urdf")).expect("bundled URDF");
        let bytes = mutate(text, &e);
        let xml = String::from_utf8_lossy(&bytes);
        let options = UrdfOptions { use_ros_env: false, ..Default::default() };
        if let Ok(r) = Robot::from_urdf_str(&xml, Some(&root().join("urdf")), &options) {
            // Accepted robots pose finitely.
            for p in r.link_poses(&r.zero_positions()) {
                prop_assert!(p.is_finite());
            }
        }
    }

    #[test]
    fn scene(e in edits(), which in prop::sample::select(vec![
        "crumple.yaml", "flag.yaml", "sphere_drape.yaml", "robot_towel.yaml", "table.yaml",
    ])) {
        let text = std::fs::read(root().join("config").join(which)).expect("bundled scene");
        let bytes = mutate(text, &e);
        let yaml = String::from_utf8_lossy(&bytes);
        match Scene::from_yaml(&yaml, which) {
            Ok(mut s) => {
                s.base_dir = Some(root().join("config"));
                // Building a parsed scene must not panic either; errors name the scene.
                if let Err(err) = s.build() {
                    let msg = err.to_string();
                    prop_assert!(!msg.is_empty());
                }
            }
            Err(err) => prop_assert!(err.to_string().contains(which), "{}", err),
        }
    }
}

/// Found by the fuzzer: two joint origins of 1e308 m are finite, but forward kinematics adds
/// them to infinity. Lengths beyond 1e6 m are now rejected, naming the joint or link.
#[test]
fn overflowing_urdf_lengths_are_rejected() {
    let options = UrdfOptions {
        use_ros_env: false,
        ..Default::default()
    };
    let urdf = |origin: &str, radius: &str| {
        format!(
            r#"<robot name="r"><link name="a"/><link name="b"><collision><geometry>
            <sphere radius="{radius}"/></geometry></collision></link><link name="c"/>
            <joint name="j1" type="fixed"><parent link="a"/><child link="b"/><origin xyz="{origin}"/></joint>
            <joint name="j2" type="fixed"><parent link="b"/><child link="c"/><origin xyz="{origin}"/></joint>
            </robot>"#
        )
    };
    let ok = Robot::from_urdf_str(&urdf("0 0 1", "0.1"), None, &options).expect("plausible robot");
    assert!(ok
        .link_poses(&ok.zero_positions())
        .iter()
        .all(|p| p.is_finite()));
    let err = Robot::from_urdf_str(&urdf("0 0 1e308", "0.1"), None, &options)
        .expect_err("1e308 m origins overflow forward kinematics");
    let err = drape::input::error_chain(&err);
    assert!(err.contains("j1") && err.contains("origin"), "{err}");
    let err = Robot::from_urdf_str(&urdf("0 0 1", "1e308"), None, &options)
        .expect_err("a 1e308 m sphere is no robot part");
    let err = drape::input::error_chain(&err);
    assert!(err.contains("link `b`") && err.contains("radius"), "{err}");
}
