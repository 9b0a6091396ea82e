//! A mesh-heavy robot written to a temporary folder: 30 links on revolute joints, each a finely
//! tessellated sphere (binary STL, ~2200 triangles), 20 of them in a grid under a cloth and 10
//! far away, plus a scene dropping a square cloth on them over a ground plane.
//! Shared by `tests/robot_heavy.rs` and `benches/robot_heavy.rs`.

#![allow(dead_code)]

use std::f64::consts::PI;
use std::path::PathBuf;

pub const SPHERE_RADIUS: f64 = 0.05;
pub const NEAR_LINKS: usize = 20;
pub const FAR_LINKS: usize = 10;

pub struct HeavyRobot {
    pub dir: tempfile::TempDir,
    pub scene: PathBuf,
    /// Collision triangles over all links.
    pub triangles: usize,
    /// Sphere centres at t = 0 (all joints rotate about their own z axis through the centre).
    pub centres: Vec<[f64; 3]>,
}

/// UV sphere of radius `r` with `stacks` x `slices` quads (poles as fans), outward winding.
pub fn sphere(r: f64, stacks: usize, slices: usize) -> (Vec<[f32; 3]>, Vec<[usize; 3]>) {
    let mut v = vec![[0.0, 0.0, r as f32]];
    for i in 1..stacks {
        let th = PI * i as f64 / stacks as f64;
        for j in 0..slices {
            let ph = 2.0 * PI * j as f64 / slices as f64;
            v.push([
                (r * th.sin() * ph.cos()) as f32,
                (r * th.sin() * ph.sin()) as f32,
                (r * th.cos()) as f32,
            ]);
        }
    }
    v.push([0.0, 0.0, -r as f32]);
    let bottom = v.len() - 1;
    let ring = |i: usize, j: usize| 1 + (i - 1) * slices + j % slices;
    let mut t = Vec::new();
    for j in 0..slices {
        t.push([0, ring(1, j), ring(1, j + 1)]);
        t.push([bottom, ring(stacks - 1, j + 1), ring(stacks - 1, j)]);
    }
    for i in 1..stacks - 1 {
        for j in 0..slices {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            t.push([a, c, d]);
            t.push([a, d, b]);
        }
    }
    (v, t)
}

fn write_stl(path: &std::path::Path, v: &[[f32; 3]], t: &[[usize; 3]]) {
    let tris: Vec<stl_io::Triangle> = t
        .iter()
        .map(|tri| {
            let p = tri.map(|i| stl_io::Vertex::new(v[i]));
            stl_io::Triangle {
                normal: stl_io::Normal::new([0.0, 0.0, 0.0]),
                vertices: p,
            }
        })
        .collect();
    let mut f = std::fs::File::create(path).unwrap();
    stl_io::write_stl(&mut f, tris.iter()).unwrap();
}

/// Writes the robot and a scene: a `res` x `res` cloth of 1 m, `frames` at 60 Hz.
pub fn write(res: usize, stacks: usize, duration: f64) -> HeavyRobot {
    let dir = tempfile::tempdir().unwrap();
    let (v, t) = sphere(SPHERE_RADIUS, stacks, 2 * stacks);
    write_stl(&dir.path().join("ball.stl"), &v, &t);
    let mut centres = Vec::new();
    for i in 0..5 {
        for j in 0..4 {
            centres.push([-0.4 + 0.2 * i as f64, -0.3 + 0.2 * j as f64, 0.0]);
        }
    }
    for k in 0..FAR_LINKS {
        centres.push([2.0, -0.9 + 0.2 * k as f64, 0.0]);
    }
    let mut urdf = String::from("<robot name=\"heavy\">\n  <link name=\"base\"/>\n");
    for (k, c) in centres.iter().enumerate() {
        urdf += &format!(
            "  <link name=\"ball{k}\"><collision><geometry><mesh filename=\"ball.stl\"/>\
             </geometry></collision></link>\n  <joint name=\"j{k}\" type=\"revolute\">\
             <parent link=\"base\"/><child link=\"ball{k}\"/><origin xyz=\"{} {} {}\"/>\
             <axis xyz=\"0 0 1\"/><limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/>\
             </joint>\n",
            c[0], c[1], c[2]
        );
    }
    urdf += "</robot>\n";
    std::fs::write(dir.path().join("heavy.urdf"), urdf).unwrap();
    let names: Vec<String> = (0..centres.len()).map(|k| format!("j{k}")).collect();
    let zeros = vec!["0.0"; centres.len()].join(", ");
    let turned = vec!["1.0"; centres.len()].join(", ");
    let scene = format!(
        r#"name: heavy_robot
duration: {duration}
effects: [gravity, stretch, shear, bending, damping]
solver: {{ integrator: implicit, dt: 0.016666666666666666, substeps: 1 }}
cloths:
  - name: sheet
    grid: {{ size: [1.0, 1.0], resolution: [{res}, {res}], pose: {{ xyz: [0.0, 0.0, 0.07] }} }}
    material:
      density: 0.2
      stretch: 1000.0
      shear: 100.0
      bend_warp: 1.0e-4
      bend_weft: 1.0e-4
      damping: {{ spring: 0.05, air: 0.1 }}
      thickness: 0.005
      friction: 0.3
obstacles:
  - {{ name: ground, shape: {{ type: plane, normal: [0.0, 0.0, 1.0] }}, pose: {{ xyz: [0.0, 0.0, -0.05] }} }}
robot:
  urdf: heavy.urdf
  trajectory:
    names: [{names}]
    points:
      - {{ t: 0.0, positions: [{zeros}] }}
      - {{ t: {duration}, positions: [{turned}] }}
collision: {{ mode: continuous }}
"#,
        names = names.join(", ")
    );
    let scene_path = dir.path().join("heavy.yaml");
    std::fs::write(&scene_path, scene).unwrap();
    HeavyRobot {
        triangles: t.len() * centres.len(),
        dir,
        scene: scene_path,
        centres,
    }
}
