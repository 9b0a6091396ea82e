//! The `drape` command line.

#[cfg(feature = "ros")]
use anyhow::Context;
use anyhow::Result;
use clap::{Parser, Subcommand};
use std::path::PathBuf;

#[cfg(feature = "ros")]
#[path = "drape/sweep_cli.rs"]
mod sweep_cli;
#[cfg(feature = "ros")]
use sweep_cli::{sweep, SweepCommand};

#[derive(Parser)]
#[command(name = "drape", version, about = "Cloth simulation on robots")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The scene file of `record` and `check`: `drape check SCENE`, or `--scene SCENE`.
#[derive(clap::Args)]
struct SceneArg {
    /// Scene file (YAML).
    #[arg(value_name = "SCENE", required_unless_present = "scene_option")]
    scene: Option<PathBuf>,
    /// The scene file, as an option instead of the positional SCENE.
    #[arg(
        long = "scene",
        id = "scene_option",
        value_name = "SCENE",
        conflicts_with = "scene"
    )]
    scene_option: Option<PathBuf>,
}

impl SceneArg {
    fn path(self) -> Result<PathBuf> {
        // clap requires one of the two.
        self.scene
            .or(self.scene_option)
            .ok_or_else(|| anyhow::anyhow!("no scene: pass SCENE or --scene SCENE"))
    }
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene offline and record the cloth to a rosbag2 MCAP file.
    #[cfg(feature = "ros")]
    Record {
        #[command(flatten)]
        scene: SceneArg,
        /// Output bag (.mcap).
        #[arg(long)]
        out: PathBuf,
        /// Simulated seconds (default: the scene's duration).
        #[arg(long)]
        duration: Option<f64>,
        /// Marker layout: humble or jazzy (default: $ROS_DISTRO, else jazzy).
        #[arg(long)]
        distro: Option<String>,
        /// Frame id of the published cloth (default: the robot's root link, else `world`).
        #[arg(long)]
        frame_id: Option<String>,
        /// Drive the scene's robot from the `/joint_states` of this rosbag2 MCAP file instead
        /// of the scene's trajectory.
        #[arg(long)]
        joints: Option<PathBuf>,
        /// Also write the run summary (the printed table) as JSON to this file.
        #[arg(long)]
        summary: Option<PathBuf>,
        /// Also write each frame's step wall time on `/diagnostics` (the bag then differs from
        /// run to run).
        #[arg(long)]
        wall_time_in_bag: bool,
        /// Folder searched for the robot's `package://` meshes, besides $ROS_PACKAGE_PATH and
        /// $AMENT_PREFIX_PATH (repeatable).
        #[arg(long, value_name = "DIR")]
        package_path: Vec<PathBuf>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Run the live ROS 2 node: joint states in, cloth mesh and points out at a fixed rate.
    #[cfg(feature = "ros")]
    Node {
        /// ROS 2 parameters file (`drape: ros__parameters: ...`); files after `--ros-args
        /// --params-file` are read after it, and a later file's values win.
        #[arg(long, value_name = "FILE")]
        params: Option<PathBuf>,
        /// Folder searched for the robot's `package://` meshes, besides $ROS_PACKAGE_PATH,
        /// $AMENT_PREFIX_PATH and the `package_paths` parameter (repeatable).
        #[arg(long, value_name = "DIR")]
        package_path: Vec<PathBuf>,
        /// ROS arguments: `--ros-args --params-file F -r __ns:=/ns -r __node:=name -p k:=v`
        /// (`-p scene:=SCENE` alone is enough to run).
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        ros_args: Vec<String>,
    },
    /// Parse and validate a scene, print what it builds, and warn about likely mistakes.
    ///
    /// Warnings (the check still succeeds): an angle over 2*pi (degrees written where radians
    /// belong), attached cloth more than 0.25 m from its link or frame, a `near` selection that
    /// picks no vertex, a cloth with no obstacle or robot link within 1 m (or twice its size).
    Check {
        #[command(flatten)]
        scene: SceneArg,
        /// Also print each robot link's world pose at t = 0 (xyz, rpy), to place cloth by.
        #[arg(long)]
        links: bool,
        /// Folder searched for the robot's `package://` meshes, besides $ROS_PACKAGE_PATH and
        /// $AMENT_PREFIX_PATH (repeatable).
        #[arg(long, value_name = "DIR")]
        package_path: Vec<PathBuf>,
    },
    /// Developer tools: the accuracy/cost study and the hard-case catalogue.
    #[cfg(feature = "tools")]
    Dev {
        #[command(subcommand)]
        command: DevCommand,
    },
    /// Measure what accuracy costs in time (`drape dev study`).
    #[cfg(feature = "tools")]
    #[command(hide = true)]
    Study(StudyArgs),
    /// Run the hard-case catalogue (`drape dev hard-cases`).
    #[cfg(feature = "tools")]
    #[command(hide = true)]
    HardCases(HardCasesArgs),
    /// Draw recorded bags (cloth shaded, robot collision shapes) to a PNG sheet or a GIF.
    #[cfg(feature = "ros")]
    Render {
        /// Bags (.mcap); several are drawn side by side.
        #[arg(required = true)]
        bags: Vec<PathBuf>,
        /// Output picture: .png (tiles) or .gif (animated).
        #[arg(long)]
        out: PathBuf,
        /// Frames nearest these times (s), comma separated (default: the last frame; a GIF
        /// animates every frame).
        #[arg(long, value_delimiter = ',')]
        at: Vec<f64>,
        /// N frames evenly spread over each bag (a strip).
        #[arg(long)]
        frames: Option<usize>,
        /// Tile size in pixels, WIDTHxHEIGHT (default: square, 320 a side, smaller when a
        /// row of tiles would be wider than 960).
        #[arg(long)]
        size: Option<String>,
        /// Tiles per row.
        #[arg(long)]
        columns: Option<usize>,
        /// Camera azimuth in degrees (default: of eight, the one showing the most cloth,
        /// -60 unless another shows clearly more).
        #[arg(long, allow_hyphen_values = true)]
        azimuth: Option<f64>,
        /// Camera elevation in degrees.
        #[arg(long, default_value_t = 22.0, allow_hyphen_values = true)]
        elevation: f64,
        /// Do not draw the robot.
        #[arg(long)]
        no_robot: bool,
        /// Do not write the scene's name and the time on the tiles.
        #[arg(long)]
        no_label: bool,
        /// Folder searched for the robot's `package://` meshes (repeatable), besides where
        /// the recording found them and ROS_PACKAGE_PATH / AMENT_PREFIX_PATH.
        #[arg(long)]
        package_path: Vec<PathBuf>,
    },
    /// Many varied recordings of one scene: plan, run (one job, or all locally), collect, emit.
    #[cfg(feature = "ros")]
    Sweep {
        #[command(subcommand)]
        command: SweepCommand,
    },
}

/// `drape dev`: tools for working on drape itself rather than with it.
#[cfg(feature = "tools")]
#[derive(Subcommand)]
enum DevCommand {
    /// Measure what accuracy costs in time: sweep integrators, steps, CG settings and resolutions.
    Study(StudyArgs),
    /// Run the hard-case catalogue and write its Markdown summary of worst values.
    HardCases(HardCasesArgs),
}

#[cfg(feature = "tools")]
#[derive(clap::Args)]
struct StudyArgs {
    /// Small sweep (under 2 minutes) instead of the full study.
    #[arg(long)]
    quick: bool,
    /// Output folder (runs.csv, summary.md, plots, cached references).
    #[arg(long)]
    out: PathBuf,
}

#[cfg(feature = "tools")]
#[derive(clap::Args)]
struct HardCasesArgs {
    /// Full resolution and duration (minutes) instead of the CI variants (seconds).
    #[arg(long)]
    full: bool,
    /// Output Markdown file, e.g. docs/hard_cases.md.
    #[arg(long)]
    out: PathBuf,
    /// Run only the cases whose name contains this text (e.g. `real_`).
    #[arg(long, value_name = "TEXT")]
    only: Option<String>,
}

fn main() {
    // RustDDS warns about every datagram over 1500 bytes (each mesh); that is normal here.
    env_logger::Builder::from_env(
        env_logger::Env::default().default_filter_or("info,rustdds=warn,ros2_client=warn"),
    )
    .filter_module("rustdds::network::udp_sender", log::LevelFilter::Error)
    .init();
    if let Err(e) = run(Cli::parse()) {
        eprintln!("drape: {}", chain(&e));
        std::process::exit(1);
    }
}

/// `error: <top>` then one `  caused by: <cause>` line per cause, each printed once (a cause
/// whose text already ends the line above is not repeated).
fn chain(e: &anyhow::Error) -> String {
    let mut out = format!("error: {e}");
    let mut last = e.to_string();
    for c in e.chain().skip(1) {
        let text = c.to_string();
        if !last.ends_with(&text) {
            out.push_str("\n  caused by: ");
            out.push_str(&text);
        }
        last = text;
    }
    out
}

/// Set while the recorder runs: it ends on a stop request by finishing its bag. In every other
/// phase (loading, building, sewing) a stop request ends the process at once.
#[cfg(feature = "ros")]
static FINISHES_ON_STOP: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// SIGINT and SIGTERM set [`drape::cancel`]'s flag (polled by the recorder's and the sewing
/// loops); outside the recording loop they end the process with status 130.
#[cfg(feature = "ros")]
fn install_stop_handler(graceful_always: bool) -> Result<()> {
    use std::sync::atomic::Ordering;
    ctrlc::set_handler(move || {
        drape::cancel::request();
        if !graceful_always && !FINISHES_ON_STOP.load(Ordering::SeqCst) {
            eprintln!("drape: stopped by a signal");
            std::process::exit(130);
        }
    })
    .context("cannot install the Ctrl-C handler")
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        #[cfg(feature = "ros")]
        Command::Record {
            scene,
            out,
            duration,
            distro,
            frame_id,
            joints,
            summary,
            wall_time_in_bag,
            package_path,
            quiet,
        } => record(RecordArgs {
            scene_path: scene.path()?,
            out,
            duration,
            distro,
            frame_id,
            joints,
            summary,
            wall_time_in_bag,
            package_paths: package_path,
            quiet,
        }),
        #[cfg(feature = "tools")]
        Command::Study(a)
        | Command::Dev {
            command: DevCommand::Study(a),
        } => study(a.quick, a.out),
        #[cfg(feature = "tools")]
        Command::HardCases(a)
        | Command::Dev {
            command: DevCommand::HardCases(a),
        } => hard_cases(a.full, a.out, a.only),
        #[cfg(feature = "ros")]
        Command::Node {
            params,
            package_path,
            ros_args,
        } => node(params, package_path, ros_args),
        #[cfg(feature = "ros")]
        Command::Sweep { command } => sweep(command),
        #[cfg(feature = "ros")]
        Command::Render {
            bags,
            out,
            at,
            frames,
            size,
            columns,
            azimuth,
            elevation,
            no_robot,
            no_label,
            package_path,
        } => {
            use drape::render::{render, Pick, RenderOptions};
            let pick = match (at.is_empty(), frames) {
                (false, Some(_)) => anyhow::bail!("--at and --frames: pick one"),
                (false, None) => Pick::Times(at),
                (true, Some(n)) => Pick::Spread(n),
                (true, None) => Pick::Last,
            };
            let (w, h) = match size {
                Some(size) => size
                    .split_once('x')
                    .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
                    .ok_or_else(|| anyhow::anyhow!("--size {size}: expected WIDTHxHEIGHT"))?,
                None => {
                    let gif = out
                        .extension()
                        .is_some_and(|e| e.eq_ignore_ascii_case("gif"));
                    let per_bag = match &pick {
                        Pick::Times(t) if !gif => t.len(),
                        Pick::Spread(n) if !gif => *n,
                        _ => 1,
                    };
                    let per_row = columns.unwrap_or(if per_bag > 1 { per_bag } else { bags.len() });
                    let side = RenderOptions::default_tile(per_row);
                    (side, side)
                }
            };
            let opts = RenderOptions {
                width: w,
                height: h,
                pick,
                columns,
                azimuth,
                elevation,
                robot: !no_robot,
                package_paths: package_path,
                label: !no_label,
            };
            render(&bags, &out, &opts)?;
            println!("wrote {}", out.display());
            Ok(())
        }
        Command::Check {
            scene,
            links,
            package_path,
        } => check(&scene.path()?, links, package_path),
    }
}

/// `drape check`: what the scene builds, the robot's summary (and link poses with `--links`),
/// cloth starting inside obstacles, then the likely mistakes as warnings (not errors).
fn check(path: &std::path::Path, links: bool, package_paths: Vec<PathBuf>) -> Result<()> {
    #[cfg(feature = "ros")]
    install_stop_handler(false)?;
    let mut s = drape::scene::Scene::load(path)?;
    s.package_paths = package_paths;
    let (sim, driver) = drape::scene::build_with_robot(&s)?;
    println!(
        "{}: {} vertices, {} triangles, effects {:?}, integrator {}, dt {} s x {} substeps",
        path.display(),
        sim.cloth.len(),
        sim.cloth.triangles.len(),
        sim.effects().names(),
        sim.integrator_name(),
        sim.settings.dt,
        sim.settings.substeps
    );
    if let Some(d) = &driver {
        print!("{}", drape::robot::RobotSummary::of(d.robot()));
    }
    if links {
        match &driver {
            Some(d) => {
                println!(
                    "link poses at t = 0 (world frame: the root link `{}`):",
                    d.root_link()
                );
                // Rounded first, so that -0.00001 prints as 0.0000, not -0.0000.
                let f = |v: [f64; 3]| {
                    let r = v.map(|x| (x * 1e4).round() / 1e4 + 0.0);
                    format!("[{:.4}, {:.4}, {:.4}]", r[0], r[1], r[2])
                };
                for (name, pose) in d.robot().link_names().iter().zip(d.link_poses()) {
                    println!(
                        "  {name}: {{ xyz: {}, rpy: {} }}",
                        f(pose.translation.to_array()),
                        f(pose.rpy())
                    );
                }
            }
            None => println!("no robot: the scene has no `robot:` section"),
        }
    }
    if let Some(stage) = sim.collision() {
        let overlaps = stage.overlaps(&sim.cloth.x);
        println!(
            "{} obstacles; {}",
            stage.obstacles().len(),
            if overlaps.is_empty() {
                "no cloth vertex starts inside one"
            } else {
                "cloth starting inside them:"
            }
        );
        for o in overlaps {
            println!("  {o}");
        }
    }
    let warnings = drape::scene::lint(&s, &sim, driver.as_ref());
    for w in &warnings {
        println!("warning: {}: {w}", path.display());
    }
    if warnings.is_empty() {
        println!("no warnings");
    }
    Ok(())
}

/// Runs every hard case, writes the summary, and fails if any case failed its criteria.
#[cfg(feature = "tools")]
fn hard_cases(full: bool, out: PathBuf, only: Option<String>) -> Result<()> {
    use drape::hard::{catalogue, markdown, run_case, Resolution};
    let res = if full {
        Resolution::Full
    } else {
        Resolution::Ci
    };
    let mut outcomes = Vec::new();
    let chosen = catalogue()
        .into_iter()
        .filter(|(name, _)| only.as_deref().is_none_or(|o| name.contains(o)));
    for (name, build) in chosen {
        let o = run_case(build(res)?);
        log::info!(
            "{name}: {} in {:.1} s{}",
            if o.passed() { "pass" } else { "FAIL" },
            o.worst.wall_s,
            if o.passed() {
                String::new()
            } else {
                format!(" ({})", o.failures.join("; "))
            }
        );
        outcomes.push(o);
    }
    drape::output::write(&out, markdown(&outcomes, res).as_bytes(), &[])?;
    let failed: Vec<&str> = outcomes
        .iter()
        .filter(|o| !o.passed())
        .map(|o| o.name)
        .collect();
    println!(
        "{}: {} of {} hard cases pass",
        out.display(),
        outcomes.len() - failed.len(),
        outcomes.len()
    );
    if !failed.is_empty() {
        anyhow::bail!("hard cases failed: {}", failed.join(", "));
    }
    Ok(())
}

#[cfg(feature = "tools")]
fn study(quick: bool, out: PathBuf) -> Result<()> {
    use anyhow::Context as _;
    use drape::study::{run_study, Plan};
    let plan = if quick { Plan::quick() } else { Plan::full() };
    let start = std::time::Instant::now();
    let r = run_study(&plan, &out, |line| log::info!("{line}"))
        .with_context(|| format!("study into {}", out.display()))?;
    println!(
        "{} runs in {:.0} s; wrote {}",
        r.runs.len(),
        start.elapsed().as_secs_f64(),
        r.files
            .iter()
            .map(|f| f.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}

#[cfg(feature = "ros")]
struct RecordArgs {
    scene_path: PathBuf,
    out: PathBuf,
    duration: Option<f64>,
    distro: Option<String>,
    frame_id: Option<String>,
    joints: Option<PathBuf>,
    summary: Option<PathBuf>,
    wall_time_in_bag: bool,
    package_paths: Vec<PathBuf>,
    quiet: bool,
}

#[cfg(feature = "ros")]
fn record(args: RecordArgs) -> Result<()> {
    use drape::ros::record::{record_with_robot, RecordOptions};
    use drape::ros::Distro;
    use std::sync::atomic::Ordering;
    let RecordArgs {
        scene_path,
        out,
        duration,
        distro,
        frame_id,
        joints,
        summary: summary_file,
        wall_time_in_bag,
        package_paths,
        quiet,
    } = args;

    // Ctrl-C and SIGTERM end every phase: at once while loading and building, by finishing
    // the bag while recording.
    install_stop_handler(false)?;
    let mut scene = drape::scene::Scene::load(&scene_path)?;
    scene.package_paths = package_paths;
    // The summary goes through the same output rules as the bag; checked before the run so
    // that a summary naming an input (or the bag) fails before anything is simulated.
    if let Some(file) = &summary_file {
        let mut also = vec![out.as_path()];
        also.extend(joints.as_deref());
        drape::output::check(file, &also)
            .with_context(|| format!("--summary {}", file.display()))?;
    }
    if let Some(d) = duration {
        scene
            .check_run_length(d)
            .with_context(|| format!("--duration {d:e}"))?;
    }
    let distro = match distro {
        Some(d) => d
            .parse::<Distro>()
            .map_err(|e| anyhow::anyhow!("--distro: {e}"))?,
        None => Distro::from_env().map_err(|e| anyhow::anyhow!("ROS_DISTRO: {e}"))?,
    };
    let (mut sim, mut driver) = scene.build_with_robot()?;
    if let Some(bag) = &joints {
        let d = driver
            .as_mut()
            .ok_or_else(|| anyhow::anyhow!("--joints: the scene has no robot"))?;
        drape::ros::drive::drive_from_bag(d, bag)?;
    }
    let frame_id = frame_id
        .or_else(|| driver.as_ref().map(|d| d.root_link().to_string()))
        .unwrap_or_else(|| "world".into());
    let opts = RecordOptions {
        duration: duration.unwrap_or(scene.duration),
        publish_rate: scene.publish_rate,
        distro,
        frame_id,
        wall_time_in_bag,
        scene_file: Some(scene_path.clone()),
        scene_name: Some(scene.name.clone()),
        package_paths: scene.package_paths.clone(),
        ..RecordOptions::default()
    };

    // From here a stop request ends the loop, which finishes the bag instead of cutting it.
    FINISHES_ON_STOP.store(true, Ordering::SeqCst);
    if drape::cancel::requested() {
        std::process::exit(130);
    }

    let bar = if quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new((opts.duration * 1000.0).round() as u64)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let start = sim.time();
    let total = opts.duration;
    let stop = drape::cancel::flag();
    let summary = record_with_robot(&mut sim, driver.as_mut(), &out, &opts, stop, |t| {
        bar.set_position(((t - start) * 1000.0) as u64);
        bar.set_message(format!("{:.2}/{total:.2} s simulated", t - start));
    })
    .with_context(|| format!("{}: recording to {}", scene_path.display(), out.display()))?;
    bar.finish_and_clear();
    println!(
        "{}: {} frames, {:.2} s simulated in {} steps{}{}",
        out.display(),
        summary.frames_written,
        summary.simulated_seconds,
        summary.steps,
        if summary.subdivisions > 0 {
            format!(
                ", {} substeps subdivided for stability",
                summary.subdivisions
            )
        } else {
            String::new()
        },
        if summary.interrupted {
            " (interrupted, file finished)"
        } else {
            ""
        }
    );
    let run = summary.run_summary();
    print!("{}", run.table());
    if let Some(file) = summary_file {
        drape::output::write(&file, (run.to_json() + "\n").as_bytes(), &[&out])
            .with_context(|| format!("--summary {}", file.display()))?;
    }
    Ok(())
}

/// `drape node`: parameters from `--params` then each `--ros-args --params-file` (a later
/// file's values win), node name and namespace from `-r __node:=` / `-r __ns:=`, then `-p`
/// overrides (enough on their own: `--ros-args -p scene:=SCENE`).
#[cfg(feature = "ros")]
fn node(params: Option<PathBuf>, package_paths: Vec<PathBuf>, ros_args: Vec<String>) -> Result<()> {
    use drape::ros::node::{parse_ros_args, run_node, NodeParams};
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    let ra = parse_ros_args(&ros_args)?;
    // Checked here, before any DDS participant exists: ros2-client accepts some malformed
    // names at first and fails on them later.
    if let Some(ns) = &ra.namespace {
        check_ros_name(ns, true).map_err(|why| anyhow::anyhow!("-r __ns:={ns}: {why}"))?;
    }
    if let Some(n) = &ra.node_name {
        check_ros_name(n, false).map_err(|why| anyhow::anyhow!("-r __node:={n}: {why}"))?;
    }
    let name = ra.node_name.clone().unwrap_or_else(|| "drape".to_string());
    let files: Vec<PathBuf> = params.into_iter().chain(ra.params_files).collect();
    if files.is_empty() && ra.overrides.is_empty() {
        anyhow::bail!(
            "no parameters: pass --params FILE, --ros-args --params-file FILE, or at least \
             --ros-args -p scene:=SCENE"
        );
    }
    let mut p = NodeParams::from_sources(&files, &ra.overrides, &name)?;
    p.package_paths.extend(package_paths);
    if let Some(ns) = ra.namespace {
        p.namespace = ns;
    }
    let origin = match files.last() {
        Some(f) => f.display().to_string(),
        None => "command line".to_string(),
    };
    check_ros_name(&p.namespace, true)
        .map_err(|why| anyhow::anyhow!("{origin}: namespace {:?}: {why}", p.namespace))?;
    check_ros_name(&p.name, false)
        .map_err(|why| anyhow::anyhow!("{origin}: node name {:?}: {why}", p.name))?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    // The stop flag ends the run loop; the cancellation flag ends a scene build in progress
    // (sewing a garment polls it), so a signal during start-up stops the node too.
    ctrlc::set_handler(move || {
        drape::cancel::request();
        flag.store(true, Ordering::Relaxed)
    })
    .context("cannot install the Ctrl-C handler")?;
    let s = run_node(&p, stop).with_context(|| format!("node with {origin}"))?;
    log::info!(
        "drape node stopped: {} frames published, {} joint states received",
        s.frames_published,
        s.joint_states_received
    );
    Ok(())
}

/// A ROS 2 namespace (`/`, or `/` then tokens joined by single `/`, no trailing `/`) or node
/// name (one token); a token is a letter or `_`, then letters, digits and `_`.
#[cfg(feature = "ros")]
fn check_ros_name(name: &str, namespace: bool) -> std::result::Result<(), &'static str> {
    let token = |t: &str| {
        let mut c = t.chars();
        matches!(c.next(), Some(f) if f.is_ascii_alphabetic() || f == '_')
            && c.all(|c| c.is_ascii_alphanumeric() || c == '_')
    };
    if !namespace {
        return if token(name) {
            Ok(())
        } else {
            Err("a node name is a letter or `_` then letters, digits and `_`")
        };
    }
    if name == "/" {
        return Ok(());
    }
    let Some(rest) = name.strip_prefix('/') else {
        return Err("a namespace starts with `/`");
    };
    if rest.split('/').all(token) {
        Ok(())
    } else {
        Err("a namespace is `/`-separated tokens (a letter or `_` then letters, digits and `_`), with no empty token (`//`) and no trailing `/`")
    }
}
