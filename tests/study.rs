//! The quick study, run in-process into a temporary folder: every planned run is in the CSV with
//! finite numbers or an explicit "diverged", the summary has its tables, the plots exist.

use drape::study::{reference, run_study, Horizon, Plan, StudyScene};

fn field<'a>(header: &[&str], row: &'a [&str], name: &str) -> &'a str {
    let i = header
        .iter()
        .position(|h| *h == name)
        .unwrap_or_else(|| panic!("no column {name}"));
    row[i]
}

/// Splits a CSV line whose last field may be a quoted message containing commas.
fn split(line: &str) -> Vec<&str> {
    let (head, msg) = match line.find(",\"") {
        Some(i) => (&line[..i], &line[i + 1..]),
        None => (line, ""),
    };
    let mut v: Vec<&str> = head.split(',').collect();
    v.push(msg);
    v
}

#[test]
fn quick_study_writes_complete_tables_and_plots() {
    let dir = tempfile::tempdir().expect("tempdir");
    let plan = Plan::quick();
    let planned = plan.runs();
    let result = run_study(&plan, dir.path(), |_| {}).expect("study runs");
    assert_eq!(result.runs.len(), planned.len());

    let csv = std::fs::read_to_string(dir.path().join("runs.csv")).expect("runs.csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(split).collect();
    assert_eq!(rows.len(), planned.len(), "one row per planned run");
    for r in &rows {
        assert_eq!(r.len(), header.len(), "row {r:?}");
    }

    // Every planned setting appears exactly once.
    for p in &planned {
        let s = &p.settings;
        let [a, b] = s.scene.resolution(s.n);
        let hits = rows
            .iter()
            .filter(|r| {
                field(&header, r, "scene") == s.scene.name()
                    && field(&header, r, "integrator") == s.integrator.name()
                    && field(&header, r, "resolution") == format!("{a}x{b}")
                    && field(&header, r, "stiffness") == s.stiffness.to_string()
                    && match s.collision {
                        Some((m, sc)) => {
                            field(&header, r, "collision_mode") == format!("{m:?}").to_lowercase()
                                && field(&header, r, "self_collision") == sc.to_string()
                        }
                        None => matches!(field(&header, r, "collision_mode"), "scene" | "n/a"),
                    }
                    && (field(&header, r, "dt_s").parse::<f64>().expect("dt") - s.dt()).abs()
                        < 1e-6 * s.dt()
                    && (s.integrator != drape::integrate::IntegratorKind::Implicit
                        || (field(&header, r, "cg_tolerance")
                            .parse::<f64>()
                            .expect("tol")
                            == s.cg_tolerance
                            && field(&header, r, "cg_max_iterations")
                                == s.cg_max_iterations.to_string()))
            })
            .count();
        assert_eq!(hits, 1, "planned run {s:?} found {hits} times");
    }

    // Numbers are finite, or the run is marked diverged with a message.
    let always = [
        "steps",
        "simulated_s",
        "wall_s",
        "wall_per_sim_s",
        "us_per_vertex_step",
        "realtime_factor",
        "cg_per_step",
        "collision_share",
    ];
    let errors = [
        "rms_error_m",
        "max_error_m",
        "final_rms_error_m",
        "energy_drift_rel",
        "sag_error_m",
    ];
    let mut diverged = 0;
    for r in &rows {
        for c in always {
            let v: f64 = field(&header, r, c).parse().unwrap_or(f64::NAN);
            assert!(v.is_finite(), "{c} = {} in {r:?}", field(&header, r, c));
        }
        match field(&header, r, "diverged") {
            "no" => {
                for c in errors {
                    let v: f64 = field(&header, r, c).parse().expect(c);
                    assert!(v.is_finite(), "{c} in {r:?}");
                }
            }
            "yes" => {
                diverged += 1;
                for c in errors {
                    assert_eq!(field(&header, r, c), "diverged");
                }
                assert!(field(&header, r, "message").contains("diverged"), "{r:?}");
                let at: f64 = field(&header, r, "diverged_at_s").parse().expect("time");
                assert!(at.is_finite());
            }
            other => panic!("diverged = {other}"),
        }
    }
    // Explicit Euler at 1/60 s with the scenes' own stiffness must blow up, and be reported.
    assert!(diverged > 0);
    assert!(rows
        .iter()
        .any(|r| field(&header, r, "integrator") == "explicit_euler"
            && field(&header, r, "stiffness") == "1"
            && (field(&header, r, "dt_s").parse::<f64>().unwrap_or(0.0) - 1.0 / 60.0).abs()
                < 1e-8
            && field(&header, r, "diverged") == "yes"));

    let summary = std::fs::read_to_string(dir.path().join("summary.md")).expect("summary.md");
    for section in [
        "## Measured convergence order",
        "## Stability",
        "## Implicit against explicit",
        "## Implicit solver tolerance",
        "## Resolution",
        "## Collision detection mode",
        "## Conclusions",
    ] {
        assert!(summary.contains(section), "summary lacks {section}");
    }
    for scene in StudyScene::ALL {
        assert!(summary.contains(scene.name()));
    }
    assert!(
        !summary.contains("NaN") && !summary.contains("inf"),
        "{summary}"
    );

    for f in &result.files {
        let text = std::fs::read_to_string(f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert!(!text.is_empty(), "{}", f.display());
        if f.extension().is_some_and(|e| e == "svg") {
            assert!(
                text.contains("<svg") && text.contains("</svg>"),
                "{}",
                f.display()
            );
        }
    }
    let svgs = result
        .files
        .iter()
        .filter(|f| f.extension().is_some_and(|e| e == "svg"))
        .count();
    assert_eq!(svgs, plan.scenes.len() * (2 + plan.stiffnesses.len()));
}

#[test]
fn reference_is_cached_and_reused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let h = Horizon {
        sample_frames: vec![1, 2],
    };
    let a = reference::reference(dir.path(), StudyScene::HangingSwing, 6, 1.0, &h, 7).expect("ref");
    assert!(!a.cached);
    let b = reference::reference(dir.path(), StudyScene::HangingSwing, 6, 1.0, &h, 7).expect("ref");
    assert!(b.cached);
    assert_eq!(a.trajectory, b.trajectory);
    assert_eq!(a.dt_level, b.dt_level);
    // A different horizon must not reuse it.
    let h2 = Horizon {
        sample_frames: vec![1],
    };
    let c =
        reference::reference(dir.path(), StudyScene::HangingSwing, 6, 1.0, &h2, 7).expect("ref");
    assert!(!c.cached);
    // A corrupt cache is recomputed, not trusted.
    let path = reference::cache_path(dir.path(), StudyScene::HangingSwing, 6, 1.0);
    let bytes = std::fs::read(&path).expect("cache");
    std::fs::write(&path, &bytes[..bytes.len() - 8]).expect("truncate");
    let d =
        reference::reference(dir.path(), StudyScene::HangingSwing, 6, 1.0, &h2, 7).expect("ref");
    assert!(!d.cached);
    assert_eq!(c.trajectory, d.trajectory);
}
