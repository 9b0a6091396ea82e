//! Scene validation: every number that could make the run meaningless is checked here, with the
//! key path in the error (`cloths[0].material.stretch: must be > 0`).

use super::{EffectKind, Scene, Selection};

type Invalid = (String, String);

fn positive(key: String, v: f64) -> Result<(), Invalid> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err((key, format!("must be > 0 (got {v})")))
    }
}

fn non_negative(key: String, v: f64) -> Result<(), Invalid> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err((key, format!("must be >= 0 (got {v})")))
    }
}

fn finite3(key: String, v: [f64; 3]) -> Result<(), Invalid> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err((key, "must be finite".into()))
    }
}

/// Largest grid accepted (vertices): a typo such as `resolution: [10000, 10000]` must not
/// allocate gigabytes.
pub const MAX_VERTICES: usize = 4_000_000;

impl Scene {
    pub(super) fn validate(&self) -> Result<(), Invalid> {
        positive("duration".into(), self.duration)?;
        positive("publish_rate".into(), self.publish_rate)?;
        finite3("gravity".into(), self.gravity)?;
        let s = &self.solver;
        positive("solver.dt".into(), s.dt)?;
        if s.substeps == 0 || s.substeps > 100_000 {
            return Err(("solver.substeps".into(), "must be in 1..=100000".into()));
        }
        if !(s.cg_tolerance > 0.0 && s.cg_tolerance < 1.0) {
            return Err((
                "solver.cg_tolerance".into(),
                format!("must be in (0, 1) (got {})", s.cg_tolerance),
            ));
        }
        if s.cg_max_iterations == 0 {
            return Err(("solver.cg_max_iterations".into(), "must be >= 1".into()));
        }
        positive("solver.guard.max_speed".into(), s.guard.max_speed)?;
        non_negative("solver.guard.energy_growth".into(), s.guard.energy_growth)?;
        if s.guard.max_subdivisions > 20 {
            return Err((
                "solver.guard.max_subdivisions".into(),
                "must be <= 20".into(),
            ));
        }
        let mut seen = std::collections::HashSet::new();
        for (i, e) in self.effects.iter().enumerate() {
            if !seen.insert(*e) {
                return Err((format!("effects[{i}]"), format!("{e:?} is listed twice")));
            }
        }
        match (&self.wind, self.has(EffectKind::Wind)) {
            (None, true) => {
                return Err((
                    "wind".into(),
                    "the effect list names wind but there is no wind section".into(),
                ))
            }
            (Some(_), false) => {
                log::warn!("scene has a wind section but `wind` is not in effects: no wind")
            }
            _ => {}
        }
        if let Some(w) = &self.wind {
            finite3("wind.velocity".into(), w.velocity.into())?;
            positive("wind.air_density".into(), w.air_density)?;
            non_negative("wind.drag_coefficient".into(), w.drag_coefficient)?;
            for (k, g) in w.gusts.iter().enumerate() {
                finite3(format!("wind.gusts[{k}].amplitude"), g.amplitude.into())?;
                non_negative(format!("wind.gusts[{k}].frequency"), g.frequency)?;
            }
            for (k, key) in w.keys.iter().enumerate() {
                finite3(format!("wind.keys[{k}].velocity"), key.velocity.into())?;
                if k > 0 && key.t <= w.keys[k - 1].t {
                    return Err((format!("wind.keys[{k}].t"), "times must increase".into()));
                }
            }
        }
        let mut names = std::collections::HashSet::new();
        for (i, f) in self.frames.iter().enumerate() {
            if !names.insert(f.name.as_str()) {
                return Err((
                    format!("frames[{i}].name"),
                    format!("duplicate frame '{}'", f.name),
                ));
            }
            finite3(format!("frames[{i}].pose.xyz"), f.pose.xyz)?;
            finite3(format!("frames[{i}].pose.rpy"), f.pose.rpy)?;
            finite3(format!("frames[{i}].linear_velocity"), f.linear_velocity)?;
            finite3(format!("frames[{i}].angular_velocity"), f.angular_velocity)?;
        }
        if self.cloths.is_empty() && self.garments.is_empty() {
            return Err(("cloths".into(), "a scene needs at least one cloth".into()));
        }
        if !self.garments.is_empty() && !self.cloths.is_empty() {
            return Err((
                "garments".into(),
                "a scene with garments cannot also have grid cloths".into(),
            ));
        }
        for (i, g) in self.garments.iter().enumerate() {
            crate::garment::pattern::validate(g)
                .map_err(|e| (format!("garments[{i}]"), e.to_string()))?;
        }
        let mut total = 0usize;
        let mut cloth_names = std::collections::HashSet::new();
        for (i, c) in self.cloths.iter().enumerate() {
            let key = |k: &str| format!("cloths[{i}].{k}");
            if !cloth_names.insert(c.name.as_str()) {
                return Err((key("name"), format!("duplicate cloth '{}'", c.name)));
            }
            positive(key("grid.size[0]"), c.grid.size[0])?;
            positive(key("grid.size[1]"), c.grid.size[1])?;
            let [nu, nv] = c.grid.resolution;
            if nu < 2 || nv < 2 {
                return Err((
                    key("grid.resolution"),
                    "needs at least 2 vertices each way".into(),
                ));
            }
            let n = nu
                .checked_mul(nv)
                .filter(|&n| n <= MAX_VERTICES)
                .ok_or_else(|| {
                    (
                        key("grid.resolution"),
                        format!("more than {MAX_VERTICES} vertices"),
                    )
                })?;
            total += n;
            finite3(key("grid.pose.xyz"), c.grid.pose.xyz)?;
            finite3(key("grid.pose.rpy"), c.grid.pose.rpy)?;
            let m = &c.material;
            positive(key("material.density"), m.density)?;
            let needs = |e: EffectKind, v: f64, name: &str| {
                if self.has(e) {
                    positive(key(&format!("material.{name}")), v)
                } else {
                    non_negative(key(&format!("material.{name}")), v)
                }
            };
            needs(EffectKind::Stretch, m.stretch, "stretch")?;
            needs(EffectKind::Shear, m.shear, "shear")?;
            needs(EffectKind::SkipOne, m.skip_one, "skip_one")?;
            non_negative(key("material.bend_warp"), m.bend_warp)?;
            non_negative(key("material.bend_weft"), m.bend_weft)?;
            non_negative(key("material.twist"), m.twist)?;
            non_negative(key("material.damping.spring"), m.damping.spring)?;
            non_negative(key("material.damping.air"), m.damping.air)?;
            non_negative(key("material.damping.diffusion"), m.damping.diffusion)?;
            positive(key("material.thickness"), m.thickness)?;
            non_negative(key("material.friction"), m.friction)?;
            for (k, p) in c.pins.iter().enumerate() {
                check_selection(&key(&format!("pins[{k}]")), p, n)?;
            }
            for (k, a) in c.attach.iter().enumerate() {
                if !names.contains(a.frame.as_str()) {
                    return Err((
                        key(&format!("attach[{k}].frame")),
                        format!("no frame named '{}'", a.frame),
                    ));
                }
                check_selection(&key(&format!("attach[{k}]")), &a.selection(), n)?;
            }
        }
        self.validate_robot()?;
        crate::collide::validate_obstacles(&self.obstacles, "obstacles")
            .map_err(|e| (e.path, e.message))?;
        self.collection_check()?;
        if total > MAX_VERTICES {
            return Err((
                "cloths".into(),
                format!("more than {MAX_VERTICES} vertices in all"),
            ));
        }
        Ok(())
    }
}

impl Scene {
    /// Checks of the `robot:` section that need no URDF; joint and link names are checked
    /// against the URDF when the scene is built.
    fn validate_robot(&self) -> Result<(), Invalid> {
        let Some(r) = &self.robot else {
            return Ok(());
        };
        if r.urdf.trim().is_empty() {
            return Err(("robot.urdf".into(), "must name a URDF file".into()));
        }
        if let Some(tr) = &r.trajectory {
            if tr.points.is_empty() {
                return Err((
                    "robot.trajectory.points".into(),
                    "needs at least one point".into(),
                ));
            }
            for (k, p) in tr.points.iter().enumerate() {
                let key = |f: &str| format!("robot.trajectory.points[{k}].{f}");
                if p.positions.len() != tr.names.len() {
                    return Err((
                        key("positions"),
                        format!(
                            "{} values for {} joint names",
                            p.positions.len(),
                            tr.names.len()
                        ),
                    ));
                }
                if let Some(j) = p.positions.iter().position(|x| !x.is_finite()) {
                    return Err((
                        format!("{}[{j}]", key("positions")),
                        "must be finite".into(),
                    ));
                }
                if !p.t.is_finite() || (k > 0 && p.t <= tr.points[k - 1].t) {
                    return Err((
                        key("t"),
                        format!("times must be finite and increase (got {})", p.t),
                    ));
                }
            }
        }
        for (k, a) in r.attach.iter().enumerate() {
            let key = format!("robot.attach[{k}]");
            let Some(c) = self.cloths.iter().find(|c| c.name == a.cloth) else {
                return Err((
                    format!("{key}.cloth"),
                    format!("no cloth named '{}'", a.cloth),
                ));
            };
            let n = c.grid.resolution[0].saturating_mul(c.grid.resolution[1]);
            check_selection(&key, &a.selection(), n)?;
        }
        Ok(())
    }

    fn collection_check(&self) -> Result<(), Invalid> {
        self.collision
            .validate("collision")
            .map_err(|e| (e.path, e.message))
    }
}

fn check_selection(key: &str, s: &Selection, n: usize) -> Result<(), Invalid> {
    let given = s.vertex.is_some() as u8
        + s.vertices.is_some() as u8
        + s.region.is_some() as u8
        + s.near.is_some() as u8;
    if given != 1 {
        return Err((
            key.to_string(),
            "give exactly one of vertex, vertices, region, near".into(),
        ));
    }
    let check = |v: u32| {
        if (v as usize) < n {
            Ok(())
        } else {
            Err((
                key.to_string(),
                format!("vertex {v} out of range (cloth has {n})"),
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
        finite3(format!("{key}.near.point"), near.point)?;
        positive(format!("{key}.near.radius"), near.radius)?;
    }
    Ok(())
}
