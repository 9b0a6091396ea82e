//! Scene validation: one pass over every number of the scene file, before anything is built.
//! Each must be finite and inside a range that makes physical and computational sense, also
//! relative to the others (the step against the run's length, the publish rate against the
//! step, the number of steps and loop iterations one value can cause), so that no single value
//! can make a run hang, overflow f64 or silently do nothing. Errors carry the key path
//! (`cloths[0].material.stretch`) and a typed [`Problem`].

use super::problem::*;
use super::{EffectKind, Scene, Selection};
use crate::collide::spec::{MotionSpec, ObstacleSpec, PoseSpec, ShapeSpec};

fn finite(key: &str, v: f64) -> Result<(), Invalid> {
    if v.is_finite() {
        Ok(())
    } else {
        Err((key.to_string(), Problem::NotFinite { value: v }))
    }
}

/// Finite and `|v| <= max`.
fn bounded(key: &str, v: f64, max: f64, unit: &'static str) -> Result<(), Invalid> {
    finite(key, v)?;
    if v.abs() <= max {
        Ok(())
    } else {
        Err((
            key.to_string(),
            Problem::TooLarge {
                value: v,
                max,
                unit,
            },
        ))
    }
}

fn bounded3(key: &str, v: [f64; 3], max: f64, unit: &'static str) -> Result<(), Invalid> {
    for (i, x) in v.iter().enumerate() {
        bounded(&format!("{key}[{i}]"), *x, max, unit)?;
    }
    Ok(())
}

/// In `(0, max]`.
fn positive(key: &str, v: f64, max: f64, unit: &'static str) -> Result<(), Invalid> {
    finite(key, v)?;
    if v <= 0.0 {
        return Err((key.to_string(), Problem::NotPositive { value: v }));
    }
    bounded(key, v, max, unit)
}

/// In `[0, max]`.
fn non_negative(key: &str, v: f64, max: f64, unit: &'static str) -> Result<(), Invalid> {
    finite(key, v)?;
    if v < 0.0 {
        return Err((key.to_string(), Problem::Negative { value: v }));
    }
    bounded(key, v, max, unit)
}

fn count(key: &str, v: u64, min: u64, max: u64) -> Result<(), Invalid> {
    if (min..=max).contains(&v) {
        Ok(())
    } else {
        Err((
            key.to_string(),
            Problem::CountOutOfRange { value: v, min, max },
        ))
    }
}

fn pose(key: &str, p: &PoseSpec) -> Result<(), Invalid> {
    bounded3(&format!("{key}.xyz"), p.xyz, MAX_LENGTH, " m")?;
    bounded3(&format!("{key}.rpy"), p.rpy, MAX_ANGLE, " rad")
}

/// Finite, within [`MAX_TIME`], and after `previous`.
fn time_after(key: &str, t: f64, previous: Option<f64>) -> Result<(), Invalid> {
    bounded(key, t, MAX_TIME, " s")?;
    match previous {
        Some(p) if t <= p => Err((
            key.to_string(),
            Problem::NotIncreasing {
                value: t,
                previous: p,
            },
        )),
        _ => Ok(()),
    }
}

impl Scene {
    pub(super) fn validate(&self) -> Result<(), Invalid> {
        self.validate_run()?;
        self.validate_effects()?;
        let mut names = std::collections::HashSet::new();
        for (i, f) in self.frames.iter().enumerate() {
            if !names.insert(f.name.as_str()) {
                return Err((
                    format!("frames[{i}].name"),
                    Problem::Duplicate {
                        name: f.name.clone(),
                    },
                ));
            }
            pose(&format!("frames[{i}].pose"), &f.pose)?;
            let k = |f: &str| format!("frames[{i}].{f}");
            bounded3(&k("linear_velocity"), f.linear_velocity, MAX_SPEED, " m/s")?;
            bounded3(
                &k("angular_velocity"),
                f.angular_velocity,
                MAX_SPEED,
                "rad/s",
            )?;
        }
        if self.cloths.is_empty() && self.garments.is_empty() {
            return Err(("cloths".into(), Problem::NoCloth));
        }
        if !self.garments.is_empty() && !self.cloths.is_empty() {
            return Err(("garments".into(), Problem::GarmentsAndCloths));
        }
        // Estimated vertices of every cloth so far, against MAX_VERTICES.
        let mut total = 0.0;
        // Per cloth: its thickness key, estimated vertices, thickness over shortest edge.
        let mut contact: Vec<(String, f64, f64)> = Vec::new();
        let mut garment_names = std::collections::HashSet::new();
        for (i, g) in self.garments.iter().enumerate() {
            if !garment_names.insert(g.name.as_str()) {
                return Err((
                    format!("garments[{i}].name"),
                    Problem::Duplicate {
                        name: g.name.clone(),
                    },
                ));
            }
            self.validate_material(&format!("garments[{i}]"), &g.material, false)?;
            let n =
                crate::garment::pattern::validate_within(g, total, MAX_VERTICES).map_err(|e| {
                    let key = match e.key_in(g) {
                        k if k.is_empty() => format!("garments[{i}]"),
                        k => format!("garments[{i}].{k}"),
                    };
                    (key, Problem::Garment(e))
                })?;
            total += n;
            contact.push((
                format!("garments[{i}].material.thickness"),
                n,
                g.material.thickness / g.edge_length,
            ));
            // Sewing runs until the seams close or `max_time`: bound its steps like a run's.
            self.check_run_length(g.sewing.max_time.max(self.solver.dt))
                .map_err(|p| (format!("garments[{i}].sewing.max_time"), p))?;
        }
        let mut cloth_names = std::collections::HashSet::new();
        for (i, c) in self.cloths.iter().enumerate() {
            let key = |k: &str| format!("cloths[{i}].{k}");
            if !cloth_names.insert(c.name.as_str()) {
                return Err((
                    key("name"),
                    Problem::Duplicate {
                        name: c.name.clone(),
                    },
                ));
            }
            positive(&key("grid.size[0]"), c.grid.size[0], MAX_LENGTH, " m")?;
            positive(&key("grid.size[1]"), c.grid.size[1], MAX_LENGTH, " m")?;
            let [nu, nv] = c.grid.resolution;
            if nu < 2 || nv < 2 {
                return Err((
                    key("grid.resolution"),
                    Problem::TooFewVertices {
                        got: [nu, nv],
                        min: 2,
                    },
                ));
            }
            let n = nu.saturating_mul(nv);
            total += n as f64;
            if total > MAX_VERTICES as f64 {
                return Err((
                    key("grid.resolution"),
                    Problem::TooManyVertices {
                        count: total,
                        max: MAX_VERTICES,
                    },
                ));
            }
            let edges = [0, 1].map(|k| c.grid.size[k] / (c.grid.resolution[k] - 1) as f64);
            for (k, &edge) in edges.iter().enumerate() {
                if edge < MIN_EDGE_LENGTH {
                    return Err((
                        key(&format!("grid.size[{k}]")),
                        Problem::EdgeTooShort {
                            edge,
                            min: MIN_EDGE_LENGTH,
                        },
                    ));
                }
            }
            pose(&key("grid.pose"), &c.grid.pose)?;
            self.validate_material(&format!("cloths[{i}]"), &c.material, true)?;
            contact.push((
                key("material.thickness"),
                n as f64,
                c.material.thickness / edges[0].min(edges[1]),
            ));
            // The lightest vertex (a corner) carries a sixth of a grid cell.
            let mass = c.material.density * edges[0] * edges[1] / 6.0;
            if !mass.is_normal() {
                return Err((key("material.density"), Problem::MassTooSmall { mass }));
            }
            for (k, p) in c.pins.iter().enumerate() {
                check_selection(&key(&format!("pins[{k}]")), p, n)?;
            }
            for (k, a) in c.attach.iter().enumerate() {
                if !names.contains(a.frame.as_str()) {
                    return Err((
                        key(&format!("attach[{k}].frame")),
                        Problem::Unknown {
                            what: "frame",
                            name: a.frame.clone(),
                        },
                    ));
                }
                check_selection(&key(&format!("attach[{k}]")), &a.selection(), n)?;
            }
        }
        self.validate_robot()?;
        validate_obstacles(&self.obstacles)?;
        crate::collide::validate_obstacles(&self.obstacles, "obstacles")
            .map_err(|e| (e.path, Problem::Collision(e.problem)))?;
        self.validate_collision()?;
        if self.collision.self_collision {
            self_contact_load(&contact)?;
        }
        Ok(())
    }

    /// The run's length, step, rates and solver budgets, against each other.
    fn validate_run(&self) -> Result<(), Invalid> {
        let s = &self.solver;
        positive("duration", self.duration, MAX_DURATION, " s")?;
        finite("solver.dt", s.dt)?;
        if s.dt <= 0.0 {
            return Err(("solver.dt".into(), Problem::NotPositive { value: s.dt }));
        }
        if s.dt < MIN_DT {
            return Err((
                "solver.dt".into(),
                Problem::TooSmall {
                    value: s.dt,
                    min: MIN_DT,
                    unit: " s",
                },
            ));
        }
        bounded("solver.dt", s.dt, MAX_DT, " s")?;
        count("solver.substeps", s.substeps as u64, 1, 100_000)?;
        self.check_run_length(self.duration)
            .map_err(|p| ("duration".to_string(), p))?;
        positive("publish_rate", self.publish_rate, 1.0 / MIN_DT, " Hz")?;
        // Frames the run writes: bounded like its steps (1e300 Hz stalled the recorder).
        let frames = self.publish_rate * self.duration;
        if frames > MAX_TOTAL_SUBSTEPS {
            return Err((
                "publish_rate".into(),
                Problem::TooManyFrames {
                    rate: self.publish_rate,
                    duration: self.duration,
                    max: MAX_TOTAL_SUBSTEPS,
                },
            ));
        }
        if self.publish_rate > 1.0 / s.dt * (1.0 + 1e-9) {
            log::warn!(
                "publish_rate {} Hz is faster than the {} s step: a frame is written every step",
                self.publish_rate,
                s.dt
            );
        }
        bounded3("gravity", self.gravity, MAX_GRAVITY, " m/s^2")?;
        finite("solver.cg_tolerance", s.cg_tolerance)?;
        if !(s.cg_tolerance > 0.0 && s.cg_tolerance < 1.0) {
            return Err((
                "solver.cg_tolerance".into(),
                Problem::TooLarge {
                    value: s.cg_tolerance,
                    max: 1.0,
                    unit: " (exclusive, and > 0)",
                },
            ));
        }
        count(
            "solver.cg_max_iterations",
            s.cg_max_iterations as u64,
            1,
            MAX_ITERATIONS,
        )?;
        positive(
            "solver.linearisation_tolerance",
            s.linearisation_tolerance,
            1e12,
            "",
        )?;
        positive("solver.guard.max_speed", s.guard.max_speed, 1e12, " m/s")?;
        non_negative(
            "solver.guard.energy_growth",
            s.guard.energy_growth,
            1e12,
            "",
        )?;
        count(
            "solver.guard.max_subdivisions",
            s.guard.max_subdivisions as u64,
            0,
            20,
        )?;
        if let Some(l) = s.guard.max_contact_split_levels {
            count("solver.guard.max_contact_split_levels", l as u64, 0, 20)?;
        }
        Ok(())
    }

    /// Whether a run of `duration` seconds is bounded with this scene's step: the step fits in
    /// the run and `duration / dt * substeps` stays under [`MAX_TOTAL_SUBSTEPS`]. Used for the
    /// scene's own `duration` and for a `--duration` given on the command line.
    pub fn check_run_length(&self, duration: f64) -> Result<(), Problem> {
        let s = &self.solver;
        if !duration.is_finite() {
            return Err(Problem::NotFinite { value: duration });
        }
        if duration <= 0.0 {
            return Err(Problem::NotPositive { value: duration });
        }
        if duration > MAX_DURATION {
            return Err(Problem::TooLarge {
                value: duration,
                max: MAX_DURATION,
                unit: " s",
            });
        }
        if s.dt > duration * (1.0 + 1e-9) {
            return Err(Problem::StepLongerThanRun { dt: s.dt, duration });
        }
        let n = (duration / s.dt).ceil() * s.substeps as f64;
        if n > MAX_TOTAL_SUBSTEPS {
            return Err(Problem::TooManySteps {
                duration,
                dt: s.dt,
                substeps: s.substeps,
                count: n,
                max: MAX_TOTAL_SUBSTEPS,
            });
        }
        Ok(())
    }

    fn validate_effects(&self) -> Result<(), Invalid> {
        let mut seen = std::collections::HashSet::new();
        for (i, e) in self.effects.iter().enumerate() {
            if !seen.insert(*e) {
                return Err((
                    format!("effects[{i}]"),
                    Problem::Duplicate {
                        name: format!("{e:?}"),
                    },
                ));
            }
        }
        match (&self.wind, self.has(EffectKind::Wind)) {
            (None, true) => return Err(("wind".into(), Problem::WindMissing)),
            (Some(_), false) => {
                log::warn!("scene has a wind section but `wind` is not in effects: no wind")
            }
            _ => {}
        }
        let Some(w) = &self.wind else {
            return Ok(());
        };
        bounded3("wind.velocity", w.velocity.into(), MAX_WIND, " m/s")?;
        positive(
            "wind.air_density",
            w.air_density,
            MAX_AIR_DENSITY,
            " kg/m^3",
        )?;
        non_negative("wind.drag_coefficient", w.drag_coefficient, MAX_DRAG, "")?;
        for (k, g) in w.gusts.iter().enumerate() {
            let key = |f: &str| format!("wind.gusts[{k}].{f}");
            bounded3(&key("amplitude"), g.amplitude.into(), MAX_WIND, " m/s")?;
            non_negative(&key("frequency"), g.frequency, MAX_FREQUENCY, " Hz")?;
            bounded(&key("phase"), g.phase, MAX_ANGLE, " rad")?;
        }
        let mut previous = None;
        for (k, key) in w.keys.iter().enumerate() {
            time_after(&format!("wind.keys[{k}].t"), key.t, previous)?;
            previous = Some(key.t);
            bounded3(
                &format!("wind.keys[{k}].velocity"),
                key.velocity.into(),
                MAX_WIND,
                "m/s",
            )?;
        }
        Ok(())
    }

    /// A cloth's or a garment's material (`at`: `cloths[0]` or `garments[0]`). A garment is a
    /// free mesh: it has no shear or skip-one springs, so those keys may be zero whatever the
    /// effects say; every key is held to the same bounds.
    fn validate_material(
        &self,
        at: &str,
        m: &crate::cloth::Material,
        lattice: bool,
    ) -> Result<(), Invalid> {
        let key = |k: &str| format!("{at}.material.{k}");
        positive(&key("density"), m.density, MAX_DENSITY, " kg/m^2")?;
        let needs = |e: EffectKind, v: f64, name: &str| {
            let springs_of_a_lattice = matches!(e, EffectKind::Shear | EffectKind::SkipOne);
            if self.has(e) && (lattice || !springs_of_a_lattice) {
                positive(&key(name), v, MAX_STIFFNESS, " N/m")
            } else {
                non_negative(&key(name), v, MAX_STIFFNESS, " N/m")
            }
        };
        if m.tensile.is_none() {
            needs(EffectKind::Stretch, m.stretch, "stretch")?;
        }
        needs(EffectKind::Shear, m.shear, "shear")?;
        needs(EffectKind::SkipOne, m.skip_one, "skip_one")?;
        non_negative(&key("bend_warp"), m.bend_warp, MAX_RIGIDITY, " N m")?;
        non_negative(&key("bend_weft"), m.bend_weft, MAX_RIGIDITY, " N m")?;
        non_negative(&key("twist"), m.twist, MAX_RIGIDITY, " N m")?;
        non_negative(&key("damping.spring"), m.damping.spring, MAX_DAMPING, "")?;
        non_negative(&key("damping.air"), m.damping.air, MAX_DAMPING, "")?;
        non_negative(
            &key("damping.diffusion"),
            m.damping.diffusion,
            MAX_DAMPING,
            "",
        )?;
        positive(&key("thickness"), m.thickness, 1.0, " m")?;
        non_negative(&key("friction"), m.friction, MAX_FRICTION, "")?;
        positive(
            &key("compressive_modulus"),
            m.compressive_modulus,
            MAX_MODULUS,
            " Pa",
        )?;
        if let Some(limit) = m.strain_limit {
            positive(&key("strain_limit"), limit, MAX_STRAIN_LIMIT, "")?;
        }
        if let Some(knee) = m.stretch_knee {
            positive(&key("stretch_knee"), knee, MAX_STRETCH_KNEE, "")?;
        }
        if let Some(r) = m.knee_stiffening {
            if m.stretch_knee.is_none() {
                let needs = "stretch_knee";
                return Err((key("knee_stiffening"), Problem::Without { needs }));
            }
            finite(&key("knee_stiffening"), r)?;
            if r < 1.0 {
                let (min, unit) = (1.0, "");
                return Err((
                    key("knee_stiffening"),
                    Problem::TooSmall {
                        value: r,
                        min,
                        unit,
                    },
                ));
            }
            bounded(&key("knee_stiffening"), r, MAX_KNEE_STIFFENING, "")?;
        }
        Ok(())
    }

    /// Checks of the `robot:` section that need no URDF; joint and link names are checked
    /// against the URDF when the scene is built.
    fn validate_robot(&self) -> Result<(), Invalid> {
        let Some(r) = &self.robot else {
            return Ok(());
        };
        if r.urdf.trim().is_empty() {
            return Err(("robot.urdf".into(), Problem::Empty));
        }
        if let Some(tr) = &r.trajectory {
            if tr.points.is_empty() {
                return Err(("robot.trajectory.points".into(), Problem::Empty));
            }
            let mut previous = None;
            for (k, p) in tr.points.iter().enumerate() {
                let key = |f: &str| format!("robot.trajectory.points[{k}].{f}");
                if p.positions.len() != tr.names.len() {
                    return Err((
                        key("positions"),
                        Problem::Length {
                            found: p.positions.len(),
                            expected: tr.names.len(),
                        },
                    ));
                }
                for (j, x) in p.positions.iter().enumerate() {
                    bounded(&format!("{}[{j}]", key("positions")), *x, MAX_JOINT, "")?;
                }
                time_after(&key("t"), p.t, previous)?;
                previous = Some(p.t);
            }
        }
        for (k, a) in r.attach.iter().enumerate() {
            let key = format!("robot.attach[{k}]");
            let Some(c) = self.cloths.iter().find(|c| c.name == a.cloth) else {
                return Err((
                    format!("{key}.cloth"),
                    Problem::Unknown {
                        what: "cloth",
                        name: a.cloth.clone(),
                    },
                ));
            };
            let n = c.grid.resolution[0].saturating_mul(c.grid.resolution[1]);
            check_selection(&key, &a.selection(), n)?;
        }
        for (k, g) in r.grasps.iter().enumerate() {
            let key = |f: &str| format!("robot.grasps[{k}].{f}");
            bounded(&key("close_below"), g.close_below, MAX_JOINT, "")?;
            bounded(&key("open_above"), g.open_above, MAX_JOINT, "")?;
            bounded3(&key("pads.xyz"), g.pads.xyz, MAX_LENGTH, " m")?;
            bounded3(&key("pads.rpy"), g.pads.rpy, MAX_ANGLE, " rad")?;
            for (i, h) in g.pads.half_extents.iter().enumerate() {
                positive(
                    &key(&format!("pads.half_extents[{i}]")),
                    *h,
                    MAX_LENGTH,
                    "m",
                )?;
            }
        }
        Ok(())
    }

    fn validate_collision(&self) -> Result<(), Invalid> {
        let c = &self.collision;
        count(
            "collision.self_iterations",
            c.self_iterations as u64,
            0,
            MAX_ITERATIONS,
        )?;
        count(
            "collision.zone_iterations",
            c.zone_iterations as u64,
            0,
            MAX_ITERATIONS,
        )?;
        c.validate("collision")
            .map_err(|e| (e.path, Problem::Collision(e.problem)))
    }
}

/// Sizes, poses, motions and friction of scripted obstacles (finiteness and names are also
/// checked by `collide::validate_obstacles`).
fn validate_obstacles(obstacles: &[ObstacleSpec]) -> Result<(), Invalid> {
    for (i, o) in obstacles.iter().enumerate() {
        let key = |f: &str| format!("obstacles[{i}].{f}");
        pose(&key("pose"), &o.pose)?;
        let len = |f: &str, v: f64| positive(&key(&format!("shape.{f}")), v, MAX_LENGTH, " m");
        match &o.shape {
            ShapeSpec::Sphere { radius } => len("radius", *radius)?,
            ShapeSpec::Box { half_extents } => {
                for (a, h) in half_extents.iter().enumerate() {
                    len(&format!("half_extents[{a}]"), *h)?;
                }
            }
            ShapeSpec::Capsule {
                radius,
                half_height,
            }
            | ShapeSpec::Cylinder {
                radius,
                half_height,
            } => {
                len("radius", *radius)?;
                len("half_height", *half_height)?;
            }
            ShapeSpec::Mesh { scale, .. } => {
                // The mesh loader's bounds, named by key here (a subnormal scale is not a scale).
                for (a, s) in scale.iter().enumerate() {
                    let k = key(&format!("shape.scale[{a}]"));
                    positive(&k, *s, crate::mesh::MAX_SCALE, "")?;
                    if *s < crate::mesh::MIN_SCALE {
                        return Err((
                            k,
                            Problem::TooSmall {
                                value: *s,
                                min: crate::mesh::MIN_SCALE,
                                unit: "",
                            },
                        ));
                    }
                }
            }
            ShapeSpec::Plane { normal } => bounded3(&key("shape.normal"), *normal, MAX_LENGTH, "")?,
        }
        if let Some(mu) = o.friction {
            non_negative(&key("friction"), mu, MAX_FRICTION, "")?;
        }
        match &o.motion {
            MotionSpec::Velocity { linear, angular } => {
                bounded3(&key("motion.linear"), *linear, MAX_SPEED, " m/s")?;
                bounded3(&key("motion.angular"), *angular, MAX_SPEED, " rad/s")?;
            }
            MotionSpec::Waypoints { points } => {
                let mut previous = None;
                for (k, w) in points.iter().enumerate() {
                    time_after(&key(&format!("motion.points[{k}].t")), w.t, previous)?;
                    previous = Some(w.t);
                    pose(&key(&format!("motion.points[{k}].pose")), &w.pose)?;
                }
            }
            MotionSpec::Static | MotionSpec::External => {}
        }
    }
    Ok(())
}

/// The self-contact load of every cloth, `vertices (1 + thickness / edge)^2` summed, against
/// [`MAX_SELF_CONTACT_LOAD`]; the cloth whose thickness passes it is named.
fn self_contact_load(cloths: &[(String, f64, f64)]) -> Result<(), Invalid> {
    let mut load = 0.0;
    for (key, vertices, ratio) in cloths {
        load += vertices * (1.0 + ratio) * (1.0 + ratio);
        if load.is_nan() || load > MAX_SELF_CONTACT_LOAD {
            return Err((
                key.clone(),
                Problem::SelfContactTooLarge {
                    vertices: *vertices,
                    ratio: *ratio,
                    load,
                    max: MAX_SELF_CONTACT_LOAD,
                },
            ));
        }
    }
    Ok(())
}

fn check_selection(key: &str, s: &Selection, n: usize) -> Result<(), Invalid> {
    let given = s.vertex.is_some() as u8
        + s.vertices.is_some() as u8
        + s.region.is_some() as u8
        + s.near.is_some() as u8;
    if given != 1 {
        return Err((key.to_string(), Problem::SelectionForm));
    }
    let check = |v: u32| {
        if (v as usize) < n {
            Ok(())
        } else {
            Err((
                key.to_string(),
                Problem::VertexOutOfRange {
                    vertex: v,
                    count: n,
                },
            ))
        }
    };
    if let Some(v) = s.vertex {
        check(v)?;
    }
    if let Some(vs) = &s.vertices {
        vs.iter().try_for_each(|v| check(*v))?;
    }
    if let Some(near) = &s.near {
        bounded3(&format!("{key}.near.point"), near.point, MAX_LENGTH, " m")?;
        positive(&format!("{key}.near.radius"), near.radius, MAX_LENGTH, " m")?;
    }
    Ok(())
}
