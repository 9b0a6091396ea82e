//! A towel dropped on a sphere, driven from Rust through drape's library API.
//!
//! Shows the whole loop a program embedding drape writes:
//! 1. load a scene file (`config/sphere_drape.yaml`) into a [`Scene`] and adjust it in code
//!    (here a coarser grid, so the example runs in a few seconds);
//! 2. build the [`Simulation`] it describes and step it, reading each step's metrics;
//! 3. read the cloth's mesh back: vertex positions and triangles, per cloth piece.
//!
//! Run it with
//!
//! ```text
//! cargo run --release --example towel_on_sphere
//! ```
//!
//! Every failure comes back as an error from `main`: a missing or invalid scene file names the
//! file and the key at fault, a step that diverges names the cloth, the vertex and the time.

use drape::collide::ShapeSpec;
use drape::scene::Scene;
use drape::sim::Simulation;
use drape::Vec3;
use std::path::Path;

/// Simulated time (s).
const SECONDS: f64 = 1.0;
/// Vertices along each side of the towel (the bundled scene has 32).
const RESOLUTION: usize = 24;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // 1. The scene: read from its YAML file and validated on load. Its fields can then be
    //    changed in code; such changes are not validated again, so keep them in range.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/sphere_drape.yaml");
    let mut scene = Scene::load(&path)?;
    let towel = scene.cloths.first_mut().ok_or("the scene has no cloth")?;
    towel.grid.resolution = [RESOLUTION, RESOLUTION];
    let sphere_top = sphere_top(&scene).ok_or("the scene has no sphere obstacle")?;

    // 2. Build and step. `step` advances one frame of `dt` (with the scene's substeps) and
    //    returns what the step did; it fails only if the cloth diverges beyond rescue.
    let mut sim = scene.build()?;
    println!(
        "{}: {} vertices, {} triangles, {} integrator, dt {:.4} s; sphere top at z = {:.3} m",
        scene.name,
        sim.cloth.len(),
        sim.cloth.triangles.len(),
        sim.integrator_name(),
        sim.settings.dt,
        sphere_top,
    );
    println!("    t (s)  max speed (m/s)  contacts  lowest z - top (m)  highest z - top (m)");
    let steps = (SECONDS / sim.settings.dt).round() as usize;
    let report_every = (steps / 6).max(1);
    for k in 1..=steps {
        let metrics = sim.step()?;
        if k % report_every == 0 || k == steps {
            let (lowest, highest) = height_range(&sim);
            println!(
                "    {:5.3}  {:15.3}  {:8}  {:+18.3}  {:+19.3}",
                metrics.time,
                metrics.max_speed,
                metrics.contacts,
                lowest - sphere_top,
                highest - sphere_top,
            );
        }
    }

    // 3. The mesh: `cloth.x` holds every vertex position (world frame, metres) and
    //    `cloth.triangles` the triangles as indices into it; `cloth.pieces` says which range of
    //    each belongs to which cloth of the scene.
    let cloth = &sim.cloth;
    for piece in &cloth.pieces {
        let triangles =
            &cloth.triangles[piece.first_triangle..piece.first_triangle + piece.triangle_count];
        let area: f64 = triangles
            .iter()
            .map(|&[a, b, c]| {
                let (a, b, c) = (
                    cloth.x[a as usize],
                    cloth.x[b as usize],
                    cloth.x[c as usize],
                );
                0.5 * (b - a).cross(c - a).length()
            })
            .sum();
        let centre = mean(&cloth.x[piece.vertices()]);
        println!(
            "cloth '{}': {} vertices, {} triangles, area {:.3} m^2, centre ({:.3}, {:.3}, {:.3})",
            piece.name,
            piece.vertex_count,
            piece.triangle_count,
            area,
            centre.x,
            centre.y,
            centre.z,
        );
    }
    println!(
        "largest edge stretch: {:.1} % over its rest length; {:.3} s simulated",
        100.0 * cloth.max_edge_stretch(),
        sim.time()
    );
    Ok(())
}

/// Height of the top of the scene's first sphere obstacle.
fn sphere_top(scene: &Scene) -> Option<f64> {
    scene.obstacles.iter().find_map(|o| match o.shape {
        ShapeSpec::Sphere { radius } => Some(o.pose.xyz[2] + radius),
        _ => None,
    })
}

/// Heights of the cloth's lowest and highest vertices.
fn height_range(sim: &Simulation) -> (f64, f64) {
    sim.cloth
        .x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.z), hi.max(p.z))
        })
}

fn mean(points: &[Vec3]) -> Vec3 {
    points.iter().copied().sum::<Vec3>() / points.len().max(1) as f64
}
