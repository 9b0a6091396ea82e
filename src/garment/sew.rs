//! The sewing stage: panels placed around the body, seam springs closing along the schedule with
//! gravity and wind off and collisions on, then the weld and the switch to normal simulation.

use super::crossing::{crossings, nearest_seam};
use super::error::{GarmentError, Length, MeshProblem, SharedStageError};
use super::mesh::mesh_garment;
use super::pattern;
use super::placement::place;
use super::seam::{gaps, SeamPairs, SeamSprings};
use super::spec::{GarmentAttachSpec, GarmentSpec};
use super::weld::{weld, Topology, Welded};
use crate::cloth::{Cloth, Panel};
use crate::effects::EffectPlan;
use crate::robot::RobotDriver;
use crate::sim::Simulation;
use crate::Vec3;

/// What the sewing of one garment did.
#[derive(Debug, Clone, PartialEq)]
pub struct SewReport {
    pub garment: String,
    /// Simulated sewing time (s) and frame steps.
    pub time: f64,
    pub steps: usize,
    /// Largest seam gap when the pairs were welded (m), and per seam.
    pub max_gap: f64,
    pub seam_gaps: Vec<(String, f64)>,
    /// Vertices before (sum over panels) and after welding.
    pub panel_vertices: usize,
    pub welded_vertices: usize,
    pub seam_pairs: usize,
    /// Edges along the seams after welding, in the simulation's vertex indices.
    pub seam_edges: Vec<(u32, u32)>,
}

/// A garment's panels as separate pieces of one cloth, with its seam pairs in global indices.
pub fn assemble(g: &GarmentSpec) -> Result<(Cloth, Vec<SeamPairs>), GarmentError> {
    pattern::validate(g)?;
    let mesh = mesh_garment(g)?;
    let mut cloth = Cloth::new();
    let mut first = Vec::new();
    for (p, m) in g.panels.iter().zip(&mesh.panels) {
        let positions: Vec<Vec3> = m.points.iter().map(|q| place(&p.placement, *q)).collect();
        let panel = Panel::from_triangles(
            &format!("{}/{}", g.name, p.name),
            m.uv.clone(),
            positions,
            m.triangles.clone(),
        )
        .map_err(|reason| GarmentError::Mesh {
            garment: g.name.clone(),
            panel: p.name.clone(),
            problem: MeshProblem::Panel(reason),
        })?;
        first.push(cloth.x.len() as u32);
        cloth.add_panel(panel, g.material);
    }
    let seams = g
        .seams
        .iter()
        .zip(&mesh.seams)
        .map(|(s, (a, b))| SeamPairs {
            name: s.name.clone(),
            pairs: a
                .vertices
                .iter()
                .zip(&b.vertices)
                .map(|(&va, &vb)| (first[a.panel] + va, first[b.panel] + vb))
                .collect(),
        })
        .collect();
    Ok((cloth, seams))
}

/// How one garment's sewing ended: simulated time (s), frame steps, largest gap per seam (m).
pub type Sewn = (f64, usize, Vec<(String, f64)>);

/// Runs the sewing schedule on `sim` (whose cloth holds the assembled garments and whose effects
/// include their seam springs) until, for every garment, its seams have closed and every gap is
/// below its tolerance. Returns per garment the time it took, the steps and the final gaps.
pub fn sew(
    sim: &mut Simulation,
    garments: &[(&GarmentSpec, Vec<SeamPairs>)],
) -> Result<Vec<Sewn>, GarmentError> {
    let t0 = sim.time();
    let mut steps = 0;
    let mut done: Vec<Option<Sewn>> = vec![None; garments.len()];
    loop {
        let names = || {
            garments
                .iter()
                .map(|g| g.0.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        if crate::cancel::requested() {
            return Err(GarmentError::Cancelled { garments: names() });
        }
        sim.step().map_err(|source| GarmentError::SewingDiverged {
            garments: names(),
            source,
        })?;
        steps += 1;
        let t = sim.time() - t0;
        for (k, (g, seams)) in garments.iter().enumerate() {
            if done[k].is_some() {
                continue;
            }
            let per_seam: Vec<(String, f64)> = seams
                .iter()
                .map(|s| {
                    let m = gaps(&sim.cloth.x, &s.pairs).into_iter().fold(0.0, f64::max);
                    (s.name.clone(), m)
                })
                .collect();
            let worst = per_seam
                .iter()
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .cloned()
                .unwrap_or_default();
            let spec = g.sewing;
            if t >= spec.close_time && worst.1 < spec.tolerance {
                done[k] = Some((t, steps, per_seam));
            } else if t >= spec.max_time {
                return Err(GarmentError::SeamOpen {
                    garment: g.name.clone(),
                    seam: worst.0,
                    gap: worst.1,
                    time: t,
                    tolerance: spec.tolerance,
                });
            }
        }
        if done.iter().all(Option::is_some) {
            return Ok(done.into_iter().flatten().collect());
        }
    }
}

/// Dresses `garments` onto the body in `sim`: the garments are assembled and sewn together (each
/// with its own schedule) under `plan` without its loads (no gravity, no wind), each is welded
/// into one piece, and the simulation then continues from t = 0 with the welded garments, at
/// rest, under the whole `plan` (gravity on). A simulation with garments holds no other cloth.
/// Garment attachments bind to the robot's links through `driver` (required when a garment has
/// any).
pub fn dress(
    sim: &mut Simulation,
    garments: &[GarmentSpec],
    plan: &EffectPlan,
    mut driver: Option<&mut RobotDriver>,
) -> Result<Vec<SewReport>, GarmentError> {
    let mut all = Cloth::new();
    let mut parts = Vec::new();
    let mut sewing_springs = Vec::new();
    for g in garments {
        let (cloth, seams) = assemble(g)?;
        let off = all.len() as u32;
        let first_piece = all.pieces.len();
        for p in cloth.pieces {
            all.add_panel(p.panel, p.material);
        }
        let seams: Vec<SeamPairs> = seams
            .into_iter()
            .map(|mut s| {
                s.pairs.iter_mut().for_each(|p| *p = (p.0 + off, p.1 + off));
                s
            })
            .collect();
        if g.sewing.stiffness > 0.0 {
            let pairs: Vec<(u32, u32)> = seams.iter().flat_map(|s| s.pairs.clone()).collect();
            sewing_springs.push(SeamSprings::new(
                pairs,
                &all.x,
                g.sewing.stiffness,
                sim.time(),
                g.sewing.close_time,
            ));
        }
        parts.push((g, seams, first_piece..all.pieces.len()));
    }
    let topo = Topology::of_pieces(&all.pieces);
    let mut set = plan.without_loads().build(&all, &topo);
    for s in sewing_springs {
        set.push(Box::new(s));
    }
    let stage_error = |e: crate::collide::StageError| GarmentError::Stage {
        garments: garments
            .iter()
            .map(|g| g.name.as_str())
            .collect::<Vec<_>>()
            .join(", "),
        source: SharedStageError(std::sync::Arc::new(e)),
    };
    sim.replace_cloth(all, set).map_err(stage_error)?;
    // Self-contact must not hold the seams open: their neighbourhoods are exempt until the weld
    // (which replaces the stage).
    let seam_pairs: Vec<Vec<(u32, u32)>> = parts
        .iter()
        .flat_map(|(_, seams, _)| seams.iter().map(|s| s.pairs.clone()))
        .collect();
    let x = sim.cloth.x.clone();
    if let Some(stage) = sim.collision_mut() {
        stage.set_sewing_seams(&seam_pairs, &x);
    }
    let sewn: Vec<(&GarmentSpec, Vec<SeamPairs>)> =
        parts.iter().map(|(g, s, _)| (*g, s.clone())).collect();
    let results = sew(sim, &sewn)?;

    let mut done = Cloth::new();
    let mut done_topo = Topology::default();
    let mut reports = Vec::new();
    for ((g, seams, pieces), (time, steps, _)) in parts.into_iter().zip(results) {
        // Gaps as welded (a garment that closed early kept sewing while the others closed).
        let seam_gaps: Vec<(String, f64)> = seams
            .iter()
            .map(|s| {
                let m = gaps(&sim.cloth.x, &s.pairs).into_iter().fold(0.0, f64::max);
                (s.name.clone(), m)
            })
            .collect();
        let (sub, off) = sub_cloth(&sim.cloth, pieces);
        let local: Vec<SeamPairs> = seams
            .iter()
            .map(|s| SeamPairs {
                name: s.name.clone(),
                pairs: s.pairs.iter().map(|p| (p.0 - off, p.1 - off)).collect(),
            })
            .collect();
        let welded = weld(&sub, &local, &g.name, g.material);
        if let Some(t) = welded
            .cloth
            .triangles
            .iter()
            .position(|t| t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
        {
            return Err(GarmentError::WeldCollapse {
                garment: g.name.clone(),
                triangle: t,
                edge_length: g.edge_length,
            });
        }
        refuse_crossings(g, &welded)?;
        log::info!(
            "garment '{}': sewn in {time:.2} s ({steps} steps), largest gap {}, {} -> {} vertices",
            g.name,
            Length(seam_gaps.iter().map(|s| s.1).fold(0.0, f64::max)),
            sub.len(),
            welded.cloth.len()
        );
        let base = done.len() as u32;
        let seam_edges = welded
            .seams
            .iter()
            .flat_map(|(_, v)| {
                v.windows(2)
                    .map(|w| (w[0] + base, w[1] + base))
                    .collect::<Vec<_>>()
            })
            .collect();
        reports.push(SewReport {
            garment: g.name.clone(),
            time,
            steps,
            max_gap: seam_gaps.iter().map(|s| s.1).fold(0.0, f64::max),
            seam_gaps,
            panel_vertices: sub.len(),
            welded_vertices: welded.cloth.len(),
            seam_pairs: local.iter().map(|s| s.pairs.len()).sum(),
            seam_edges,
        });
        let first = done.len();
        append(&mut done, &mut done_topo, welded.cloth, welded.topology);
        for (k, a) in g.attach.iter().enumerate() {
            attach(sim, driver.as_deref_mut(), &mut done, first, g, k, a)?;
        }
    }
    done.v.iter_mut().for_each(|v| *v = Vec3::ZERO);
    let set = plan.build(&done, &done_topo);
    sim.replace_cloth(done, set).map_err(stage_error)?;
    sim.restart_clock();
    Ok(reports)
}

/// The pieces `pieces` of `cloth` (contiguous) as a cloth of their own, at their current state,
/// and the global index of its first vertex.
pub fn sub_cloth(cloth: &Cloth, pieces: std::ops::Range<usize>) -> (Cloth, u32) {
    let mut out = Cloth::new();
    let first = cloth.pieces[pieces.start].first_vertex;
    for p in &cloth.pieces[pieces] {
        let mut panel = p.panel.clone();
        panel.positions = cloth.x[p.vertices()].to_vec();
        let k = out.add_panel(panel, p.material);
        let range = out.pieces[k].vertices();
        out.v[range].copy_from_slice(&cloth.v[p.vertices()]);
    }
    (out, first as u32)
}

/// Attaches the welded garment's vertices (from `first` on) near `a.point` to `a.link`.
fn attach(
    sim: &mut Simulation,
    driver: Option<&mut RobotDriver>,
    done: &mut Cloth,
    first: usize,
    g: &GarmentSpec,
    k: usize,
    a: &GarmentAttachSpec,
) -> Result<(), GarmentError> {
    let Some(driver) = driver else {
        return Err(GarmentError::AttachNeedsRobot {
            garment: g.name.clone(),
            index: k,
        });
    };
    let link = driver
        .robot()
        .link_index(&a.link)
        .ok_or_else(|| GarmentError::AttachLink {
            garment: g.name.clone(),
            index: k,
            link: a.link.clone(),
        })?;
    let pose = driver.link_poses()[link];
    let frame = driver.link_frame(link, &mut sim.frames);
    let centre = pose.transform_point(Vec3::from(a.point));
    let picked: Vec<u32> = (first..done.len())
        .filter(|&i| (done.x[i] - centre).length() <= a.radius)
        .map(|i| i as u32)
        .collect();
    if picked.is_empty() {
        return Err(GarmentError::AttachSelectsNothing {
            garment: g.name.clone(),
            index: k,
            link: a.link.clone(),
            point: a.point,
            radius: a.radius,
        });
    }
    for v in picked {
        done.attach(v, frame, &pose);
    }
    Ok(())
}

/// Appends a welded garment (one piece) to the cloth of the dressed garments.
fn append(done: &mut Cloth, topo: &mut Topology, c: Cloth, t: Topology) {
    let off = done.len() as u32;
    let first_triangle = done.triangles.len();
    done.x.extend(c.x);
    done.v.extend(c.v);
    done.mass.extend(c.mass);
    done.uv.extend(c.uv);
    done.thickness.extend(c.thickness);
    done.friction.extend(c.friction);
    done.triangles
        .extend(c.triangles.iter().map(|t| t.map(|i| i + off)));
    for mut p in c.pieces {
        p.first_vertex += off as usize;
        p.first_triangle += first_triangle;
        done.pieces.push(p);
    }
    topo.springs.extend(t.springs.into_iter().map(|mut s| {
        s.i += off;
        s.j += off;
        s
    }));
    topo.bending.extend(t.bending.into_iter().map(|mut s| {
        s.idx = s.idx.map(|i| i + off);
        s
    }));
    topo.spring_material.extend(t.spring_material);
    topo.bending_rigidity.extend(t.bending_rigidity);
}

/// Deepest penetration of any cloth vertex below an obstacle's surface (m, >= 0).
pub fn body_penetration(sim: &Simulation) -> f64 {
    let Some(stage) = sim.collision() else {
        return 0.0;
    };
    let mut deepest: f64 = 0.0;
    for o in stage.obstacles() {
        for &x in &sim.cloth.x {
            let local = o.pose.inverse_transform_point(x);
            let sp = o.closest_local(local, Vec3::ZERO);
            deepest = deepest.max(-sp.signed_distance);
        }
    }
    deepest
}

/// Intersecting pairs of triangles that share no vertex (exact).
pub fn self_intersections(x: &[Vec3], triangles: &[[u32; 3]]) -> usize {
    crossings(x, triangles).len()
}

/// Fails when the welded garment crosses itself, naming the seam nearest the first crossing
/// (within three edge lengths of it) or saying that no seam is near.
fn refuse_crossings(g: &GarmentSpec, welded: &Welded) -> Result<(), GarmentError> {
    let x = &welded.cloth.x;
    let found = crossings(x, &welded.cloth.triangles);
    let Some(&(a, b)) = found.first() else {
        return Ok(());
    };
    let centre = |t: u32| {
        let t = welded.cloth.triangles[t as usize];
        (x[t[0] as usize] + x[t[1] as usize] + x[t[2] as usize]) / 3.0
    };
    let at = (centre(a) + centre(b)) / 2.0;
    let seam = nearest_seam(x, &welded.seams, at)
        .filter(|(_, d)| *d <= 3.0 * g.edge_length)
        .map(|(name, _)| name.to_string());
    Err(GarmentError::WeldedCrossing {
        garment: g.name.clone(),
        seam,
        pairs: found.len(),
        triangles: (a, b),
        at: at.as_vec3().to_array(),
    })
}
