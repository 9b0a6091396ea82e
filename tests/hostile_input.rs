//! Hostile input against the built `drape` binary: every kind of input a hostile or
//! careless user can hand to `drape check` / `drape record` (scene YAML, URDF, meshes, joints
//! bag, command-line values), each run as a child process with a time limit and a memory limit.
//!
//! For every case: the exit status is an error (or success for valid input such as a BOM), the
//! child neither panicked nor died of a signal, the message names the file and the key, the
//! inputs are byte for byte unchanged, any bag written holds only finite values, and no file
//! outside the allowed folders was opened (a FIFO outside them notices an open).
#![cfg(feature = "ros")]

use drape::ros::msg::{JointState, PointCloud2, TFMessage};
use drape::ros::{read_topic, BagWriter, Distro};
use std::collections::BTreeMap;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Memory limit of the child (address space).
const MEMORY_LIMIT: u64 = 200 << 20;
/// Budget per case; the machine running the tests is shared, so the assertion allows
/// `SLACK` times this, and the child is killed at `KILL_AFTER`.
const BUDGET: Duration = Duration::from_secs(2);
const SLACK: u32 = 3;
const KILL_AFTER: Duration = Duration::from_secs(10);
/// Budget of a large input that must still succeed (or be refused by a documented limit).
const LARGE_BUDGET: Duration = Duration::from_secs(20);
/// Memory limit (address space) of a large input that must still succeed.
const LARGE_MEMORY_LIMIT: u64 = 2 << 30;

#[path = "common/tiny_scene.rs"]
mod tiny_scene;
use tiny_scene::TINY_SCENE as SCENE;

/// The tiny scene on the layout's robot (`Layout`: `scene/pkg/urdf/robot.urdf`).
fn robot_scene() -> String {
    tiny_scene::tiny_robot_scene("pkg/urdf/robot.urdf")
}

fn urdf(mesh: &str, extra: &str) -> String {
    format!(
        r#"<robot name="r">
  <link name="base"/>
  <link name="arm"><collision><geometry><mesh filename="{mesh}"/></geometry></collision></link>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  {extra}
</robot>
"#
    )
}

const TETRA: &str = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0.1 0 0\nvertex 0 0.1 0\nendloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0 0.1 0\nvertex 0 0 0.1\nendloop\nendfacet\nendsolid t\n";

/// A scene folder: `scene/scene.yaml`, `scene/pkg/urdf/robot.urdf`, `scene/pkg/meshes/m.stl`,
/// and `outside/secret.stl` beside (not inside) the scene folder.
struct Layout {
    _tmp: tempfile::TempDir,
    root: PathBuf,
    scene_dir: PathBuf,
}

impl Layout {
    fn new() -> Layout {
        let tmp = tempfile::tempdir().expect("tempdir");
        let root = tmp.path().to_path_buf();
        let scene_dir = root.join("scene");
        for d in ["scene/pkg/urdf", "scene/pkg/meshes", "outside"] {
            std::fs::create_dir_all(root.join(d)).expect("mkdir");
        }
        std::fs::write(root.join("scene/pkg/package.xml"), "<package/>").expect("write");
        std::fs::write(root.join("scene/pkg/meshes/m.stl"), TETRA).expect("write");
        std::fs::write(root.join("outside/secret.stl"), TETRA).expect("write");
        Layout {
            _tmp: tmp,
            root,
            scene_dir,
        }
    }
    fn path(&self, rel: &str) -> PathBuf {
        self.root.join(rel)
    }
    fn write(&self, rel: &str, text: impl AsRef<[u8]>) -> PathBuf {
        let p = self.path(rel);
        if let Some(d) = p.parent() {
            std::fs::create_dir_all(d).expect("mkdir");
        }
        std::fs::write(&p, text).expect("write");
        p
    }
    fn scene(&self, text: &str) -> PathBuf {
        self.write("scene/scene.yaml", text)
    }
    fn robot(&self, mesh: &str, extra: &str) -> PathBuf {
        self.write("scene/pkg/urdf/robot.urdf", urdf(mesh, extra));
        self.scene(&robot_scene())
    }
    fn fifo(&self, rel: &str) -> PathBuf {
        let p = self.path(rel);
        let c = std::ffi::CString::new(p.as_os_str().as_encoded_bytes()).expect("path");
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
        p
    }
    fn symlink(&self, target: &Path, rel: &str) -> PathBuf {
        let p = self.path(rel);
        std::os::unix::fs::symlink(target, &p).expect("symlink");
        p
    }
    fn sparse(&self, rel: &str, len: u64) -> PathBuf {
        let p = self.path(rel);
        let f = std::fs::File::create(&p).expect("create");
        f.set_len(len).expect("set_len");
        p
    }
    /// Every regular file under the layout (symlinks not followed) and its bytes' hash.
    fn hashes(&self) -> BTreeMap<PathBuf, u64> {
        fn walk(d: &Path, out: &mut BTreeMap<PathBuf, u64>) {
            let Ok(rd) = std::fs::read_dir(d) else { return };
            for e in rd.flatten() {
                let p = e.path();
                let Ok(m) = std::fs::symlink_metadata(&p) else {
                    continue;
                };
                if m.is_dir() {
                    walk(&p, out);
                } else if m.is_file() && m.len() < (64 << 20) {
                    use std::hash::{Hash, Hasher};
                    let mut h = std::collections::hash_map::DefaultHasher::new();
                    std::fs::read(&p).unwrap_or_default().hash(&mut h);
                    out.insert(p, h.finish());
                }
            }
        }
        let mut out = BTreeMap::new();
        walk(&self.root, &mut out);
        out
    }
}

/// A FIFO outside the allowed folders with a writer waiting on it: if drape opens it for
/// reading, the writer's open returns and `opened()` is true.
struct Tripwire {
    path: PathBuf,
    handle: Option<std::thread::JoinHandle<bool>>,
}

impl Tripwire {
    fn new(l: &Layout, rel: &str) -> Tripwire {
        let path = l.fifo(rel);
        let p = path.clone();
        let handle = std::thread::spawn(move || {
            // Blocks until a reader opens the FIFO (drape, or `opened()` below).
            let f = std::fs::OpenOptions::new().write(true).open(&p);
            let by_us = std::fs::metadata(p.with_extension("released")).is_ok();
            drop(f);
            !by_us
        });
        Tripwire {
            path,
            handle: Some(handle),
        }
    }
    /// Whether anyone but this test opened the FIFO.
    fn opened(mut self) -> bool {
        use std::os::unix::fs::OpenOptionsExt;
        let h = self.handle.take().expect("once");
        if !h.is_finished() {
            std::fs::write(self.path.with_extension("released"), b"").expect("marker");
            let _r = std::fs::OpenOptions::new()
                .read(true)
                .custom_flags(libc::O_NONBLOCK)
                .open(&self.path)
                .expect("open fifo");
            return h.join().expect("writer thread");
        }
        h.join().expect("writer thread")
    }
}

struct Outcome {
    code: Option<i32>,
    signal: Option<i32>,
    stderr: String,
    elapsed: Duration,
}

/// The binary under test: the one cargo built, or `HOSTILE_DRAPE` (to measure another build,
/// e.g. main before this suite, with `HOSTILE_REPORT=1` to list every failing case).
fn binary() -> PathBuf {
    std::env::var_os("HOSTILE_DRAPE")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_drape")))
}

/// With `HOSTILE_REPORT` set, failures are printed (`FAIL case: why`) instead of failing.
fn report_only() -> bool {
    std::env::var_os("HOSTILE_REPORT").is_some()
}

fn drape(args: &[&std::ffi::OsStr]) -> Outcome {
    drape_limited(args, None)
}

/// [`drape`] with a limit on the size of any file the child writes (`RLIMIT_FSIZE`: a write
/// past it fails with `EFBIG`, as on a full disk; `SIGXFSZ` is ignored so the write returns).
fn drape_limited(args: &[&std::ffi::OsStr], file_size: Option<u64>) -> Outcome {
    drape_with(args, file_size, KILL_AFTER)
}

fn drape_with(args: &[&std::ffi::OsStr], file_size: Option<u64>, kill_after: Duration) -> Outcome {
    drape_within(args, file_size, kill_after, MEMORY_LIMIT)
}

/// A large input that must still succeed: [`LARGE_MEMORY_LIMIT`], killed after
/// [`LARGE_BUDGET`] x [`SLACK`], on one worker thread so that the cases running beside it keep
/// a core of the shared machine.
fn drape_large(args: &[&std::ffi::OsStr]) -> Outcome {
    drape_within(args, None, LARGE_BUDGET * SLACK, LARGE_MEMORY_LIMIT)
}

/// [`drape_with`] under another memory limit; above [`MEMORY_LIMIT`], on one worker thread.
fn drape_within(
    args: &[&std::ffi::OsStr],
    file_size: Option<u64>,
    kill_after: Duration,
    memory: u64,
) -> Outcome {
    let mut cmd = Command::new(binary());
    if memory > MEMORY_LIMIT {
        cmd.env("RAYON_NUM_THREADS", "1");
    }
    cmd.args(args)
        .env("RUST_LOG", "error")
        .env("MALLOC_ARENA_MAX", "2")
        .env_remove("ROS_PACKAGE_PATH")
        .env_remove("AMENT_PREFIX_PATH")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    unsafe {
        cmd.pre_exec(move || {
            let lim = libc::rlimit {
                rlim_cur: memory,
                rlim_max: memory,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            if let Some(n) = file_size {
                let lim = libc::rlimit {
                    rlim_cur: n,
                    rlim_max: n,
                };
                libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
                if libc::setrlimit(libc::RLIMIT_FSIZE, &lim) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
            }
            Ok(())
        });
    }
    let start = Instant::now();
    let mut child = cmd.spawn().expect("spawn drape");
    let mut stderr = child.stderr.take().expect("stderr");
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut stderr, &mut s);
        s
    });
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        if start.elapsed() > kill_after {
            let _ = child.kill();
            let s = child.wait().expect("wait");
            if !report_only() {
                panic!("drape {args:?} still running after {kill_after:?}; killed ({s})");
            }
            break s;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let elapsed = start.elapsed();
    use std::os::unix::process::ExitStatusExt;
    Outcome {
        code: status.code(),
        signal: status.signal(),
        stderr: reader.join().unwrap_or_default(),
        elapsed,
    }
}

fn check(scene: &Path) -> Outcome {
    drape(&["check".as_ref(), "--scene".as_ref(), scene.as_os_str()])
}

fn record(scene: &Path, out: &Path, extra: &[&str]) -> Outcome {
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "record".as_ref(),
        "--quiet".as_ref(),
        "--scene".as_ref(),
        scene.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ];
    args.extend(extra.iter().map(|a| std::ffi::OsStr::new(*a)));
    drape(&args)
}

/// Every float in every message of a bag drape wrote is finite.
fn assert_bag_finite(bag: &Path) {
    if !bag.is_file() {
        return;
    }
    if let Ok(r) = read_topic::<PointCloud2>(bag, "/drape/points") {
        for (_, m) in &r.messages {
            for c in m.data.chunks_exact(4) {
                let v = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
                assert!(v.is_finite(), "{}: non-finite point", bag.display());
            }
        }
    }
    if let Ok(r) = read_topic::<JointState>(bag, "/joint_states") {
        for (_, m) in &r.messages {
            assert!(
                m.position.iter().all(|v| v.is_finite()),
                "{}",
                bag.display()
            );
        }
    }
    if let Ok(r) = read_topic::<TFMessage>(bag, "/tf") {
        for (_, m) in &r.messages {
            for t in &m.transforms {
                let (p, q) = (&t.transform.translation, &t.transform.rotation);
                assert!(
                    [p.x, p.y, p.z, q.x, q.y, q.z, q.w]
                        .iter()
                        .all(|v| v.is_finite()),
                    "{}: non-finite /tf",
                    bag.display()
                );
            }
        }
    }
}

/// What a case must end with.
enum Expect<'a> {
    /// Exit 1 with an error whose text contains every one of these.
    Error(&'a [&'a str]),
    /// Exit 0.
    Ok,
}

/// The common assertions of every case.
fn judge(name: &str, l: &Layout, before: &BTreeMap<PathBuf, u64>, o: &Outcome, want: Expect) {
    judge_within(name, l, before, o, want, BUDGET)
}

/// [`judge`] with another time budget (a large input that must still succeed).
fn judge_within(
    name: &str,
    l: &Layout,
    before: &BTreeMap<PathBuf, u64>,
    o: &Outcome,
    want: Expect,
    budget: Duration,
) {
    let failures = verdict(l, before, o, want, budget);
    let err = o.stderr.trim().replace('\n', "\n    ");
    if failures.is_empty() {
        eprintln!("{name}: ok in {:?}\n    {err}", o.elapsed);
    } else if report_only() {
        eprintln!("FAIL {name}: {}\n    {err}", failures.join("; "));
    } else {
        panic!("{name}: {}\n    {err}", failures.join("; "));
    }
}

fn verdict(
    l: &Layout,
    before: &BTreeMap<PathBuf, u64>,
    o: &Outcome,
    want: Expect,
    budget: Duration,
) -> Vec<String> {
    let mut f = Vec::new();
    let err = &o.stderr;
    if let Some(s) = o.signal {
        f.push(format!("killed by signal {s}"));
    }
    if err.contains("panicked") {
        f.push("panicked".into());
    }
    if o.elapsed >= budget * SLACK {
        f.push(format!("took {:?} (budget {budget:?})", o.elapsed));
    }
    match want {
        Expect::Ok => {
            if o.code != Some(0) {
                f.push(format!("exit {:?}, expected success", o.code));
            }
        }
        Expect::Error(parts) => {
            if o.code != Some(1) {
                f.push(format!("exit {:?}, expected 1", o.code));
            }
            if !err.contains("drape: error: ") {
                f.push("no error message".into());
            }
            for p in parts {
                if !err.contains(p) {
                    f.push(format!("error lacks `{p}`"));
                }
            }
            if err.lines().next().unwrap_or("").contains("NAMEXYZ") {
                f.push("error starts with the scene's name, not its file".into());
            }
            let lines: Vec<&str> = err
                .lines()
                .map(|x| x.trim().trim_start_matches("caused by: "))
                .collect();
            for (i, a) in lines.iter().enumerate() {
                if a.len() >= 12 && lines[i + 1..].contains(a) {
                    f.push("a line is repeated".into());
                }
            }
        }
    }
    let after = l.hashes();
    for (p, h) in before {
        if p.file_name() == Some("out.mcap".as_ref()) {
            continue;
        }
        if after.get(p) != Some(h) {
            f.push(format!("input {} changed", p.display()));
        }
    }
    for p in after.keys() {
        if p.extension().is_some_and(|e| e == "mcap") {
            if let Err(e) = std::panic::catch_unwind(|| assert_bag_finite(p)) {
                let why = e.downcast_ref::<String>().cloned().unwrap_or_default();
                f.push(format!("non-finite value in a bag: {why}"));
            }
        }
    }
    f
}

/// Runs one scene text through `drape check` and `drape record`, expecting the same outcome.
fn scene_case(name: &str, text: &str, want_key: &str) {
    let l = Layout::new();
    let scene = l.scene(text);
    let before = l.hashes();
    let o = check(&scene);
    judge(
        name,
        &l,
        &before,
        &o,
        Expect::Error(&["scene.yaml", want_key]),
    );
    let o = record(&scene, &l.path("scene/out.mcap"), &[]);
    judge(
        name,
        &l,
        &before,
        &o,
        Expect::Error(&["scene.yaml", want_key]),
    );
}

fn with(base: &str, from: &str, to: &str) -> String {
    assert!(base.contains(from), "{from}");
    base.replacen(from, to, 1)
}

// ---------------------------------------------------------------- panics and aborts

#[test]
fn non_finite_and_overflowing_wind_keys_are_rejected() {
    let windy = with(
        SCENE,
        "effects: [gravity, stretch, shear]",
        "effects: [gravity, stretch, shear, wind]\nwind: { keys: [ { t: 0.0, velocity: [1, 0, 0] }, { t: T, velocity: [2, 0, 0] } ] }",
    );
    for (t, key) in [
        (".nan", "wind.keys[1].t"),
        (".inf", "wind.keys[1].t"),
        ("-.inf", "wind.keys[1].t"),
        ("1e300", "wind.keys[1].t"),
        ("-1.0", "wind.keys[1].t"),
    ] {
        scene_case(&format!("wind key t = {t}"), &windy.replace("T", t), key);
    }
    let gust = with(
        SCENE,
        "effects: [gravity, stretch, shear]",
        "effects: [gravity, stretch, shear, wind]\nwind: { gusts: [ { amplitude: [1, 0, 0], frequency: 1e300 } ] }",
    );
    scene_case("gust frequency 1e300", &gust, "wind.gusts[0].frequency");
}

#[test]
fn deep_nesting_is_rejected_without_overflowing_the_stack() {
    let l = Layout::new();
    let deep = "<a>".repeat(100_000) + &"</a>".repeat(100_000);
    l.write("scene/pkg/urdf/robot.urdf", urdf("../meshes/m.stl", &deep));
    let scene = l.scene(&robot_scene());
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "URDF 100k nested",
        &l,
        &before,
        &o,
        Expect::Error(&["robot.urdf", "nested deeper"]),
    );

    // Nested inside a link, and as an unclosed flood.
    let l = Layout::new();
    l.write(
        "scene/pkg/urdf/robot.urdf",
        format!(
            "<robot name='r'><link name='a'>{}",
            "<visual>".repeat(200_000)
        ),
    );
    let scene = l.scene(&robot_scene());
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "URDF unclosed flood",
        &l,
        &before,
        &o,
        Expect::Error(&["robot.urdf"]),
    );

    // Collada mesh nested 100k deep.
    let l = Layout::new();
    l.write(
        "scene/pkg/meshes/deep.dae",
        "<COLLADA>".to_string()
            + &"<node>".repeat(100_000)
            + &"</node>".repeat(100_000)
            + "</COLLADA>",
    );
    let scene = l.robot("../meshes/deep.dae", "");
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "Collada 100k nested",
        &l,
        &before,
        &o,
        Expect::Error(&["deep.dae", "arm"]),
    );

    // YAML: sequences and maps nested 100k deep.
    for (what, text) in [
        (
            "YAML sequences",
            format!(
                "{SCENE}extra: {}{}\n",
                "[".repeat(100_000),
                "]".repeat(100_000)
            ),
        ),
        (
            "YAML maps",
            format!(
                "{SCENE}extra: {}1{}\n",
                "{a: ".repeat(100_000),
                "}".repeat(100_000)
            ),
        ),
        ("YAML block maps", {
            let mut s = SCENE.to_string() + "extra:\n";
            for d in 1..2500 {
                s.push_str(&" ".repeat(d));
                s.push_str("a:\n");
            }
            s
        }),
    ] {
        let l = Layout::new();
        let scene = l.scene(&text);
        let before = l.hashes();
        let o = check(&scene);
        judge(what, &l, &before, &o, Expect::Error(&["scene.yaml"]));
    }
}

// ---------------------------------------------------------------- hangs

#[test]
fn values_that_would_never_end_are_rejected() {
    for (name, from, to, key) in [
        (
            "publish_rate 1e300",
            "duration: 0.1",
            "duration: 0.1\npublish_rate: 1e300",
            "publish_rate",
        ),
        (
            "publish_rate x duration",
            "duration: 0.1",
            "duration: 1000\npublish_rate: 1e5",
            "publish_rate",
        ),
        ("dt 1e-300", "dt: 0.02", "dt: 1e-300", "solver.dt"),
        (
            "dt 1e-5 for 1e6 s",
            "duration: 0.1",
            "duration: 1e6",
            "duration",
        ),
        (
            "substeps x duration",
            "dt: 0.02",
            "dt: 0.02, substeps: 100000 }\nduration: 1e5\nx: {",
            "solver",
        ),
        (
            "cg_max_iterations 4e9",
            "dt: 0.02",
            "dt: 0.02, cg_max_iterations: 4000000000",
            "solver.cg_max_iterations",
        ),
        (
            "duration 1e300",
            "duration: 0.1",
            "duration: 1e300",
            "duration",
        ),
    ] {
        if name == "substeps x duration" {
            // Huge run length through substeps: duration / dt * substeps.
            let text = with(SCENE, "dt: 0.02 }", "dt: 0.02, substeps: 100000 }");
            let text = with(&text, "duration: 0.1", "duration: 2000");
            scene_case(name, &text, "duration");
            continue;
        }
        scene_case(name, &with(SCENE, from, to), key);
    }
    let collide =
        format!("{SCENE}collision: {{ self_collision: true, self_iterations: 1000000000 }}\n");
    scene_case("self_iterations 1e9", &collide, "collision.self_iterations");
}

#[test]
fn command_line_run_length_is_bounded() {
    let l = Layout::new();
    let scene = l.scene(SCENE);
    let before = l.hashes();
    for d in ["1e300", "inf", "NaN", "-1", "1e-9", "0"] {
        let arg = format!("--duration={d}");
        let o = record(&scene, &l.path("scene/out.mcap"), &[&arg]);
        judge(
            &format!("--duration {d}"),
            &l,
            &before,
            &o,
            Expect::Error(&["--duration"]),
        );
    }
}

#[test]
fn fifos_never_block() {
    // Scene, URDF, mesh, joints bag and obstacle mesh as FIFOs with no writer.
    let l = Layout::new();
    let scene = l.fifo("scene/fifo.yaml");
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "FIFO scene",
        &l,
        &before,
        &o,
        Expect::Error(&["fifo.yaml", "FIFO"]),
    );

    let l = Layout::new();
    l.fifo("scene/pkg/urdf/robot.urdf");
    let scene = l.scene(&robot_scene());
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "FIFO URDF",
        &l,
        &before,
        &o,
        Expect::Error(&["robot.urdf", "FIFO"]),
    );

    let l = Layout::new();
    l.fifo("scene/pkg/meshes/f.stl");
    let scene = l.robot("../meshes/f.stl", "");
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "FIFO mesh",
        &l,
        &before,
        &o,
        Expect::Error(&["f.stl", "arm"]),
    );

    let l = Layout::new();
    l.fifo("scene/ob.stl");
    let scene = l.scene(&format!(
        "{SCENE}obstacles:\n  - {{ name: rock, shape: {{ type: mesh, path: ob.stl }} }}\n"
    ));
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "FIFO obstacle mesh",
        &l,
        &before,
        &o,
        Expect::Error(&["ob.stl", "obstacles[0]"]),
    );

    let l = Layout::new();
    let scene = l.robot("../meshes/m.stl", "");
    let joints = l.fifo("scene/joints.mcap");
    let before = l.hashes();
    let o = record(
        &scene,
        &l.path("scene/out.mcap"),
        &["--joints", joints.to_str().expect("utf8")],
    );
    judge(
        "FIFO joints bag",
        &l,
        &before,
        &o,
        Expect::Error(&["joints.mcap", "FIFO"]),
    );
}

// ---------------------------------------------------------------- unbounded reads

#[test]
fn devices_and_huge_files_are_not_read() {
    let zero = Path::new("/dev/zero");
    // Scene: /dev/zero itself, a symlink to it, a sparse 8 GB file.
    let l = Layout::new();
    let link = l.symlink(zero, "scene/zero.yaml");
    for (name, p) in [
        ("/dev/zero scene", zero.to_path_buf()),
        ("symlink to /dev/zero", link),
    ] {
        let before = l.hashes();
        let o = check(&p);
        judge(
            name,
            &l,
            &before,
            &o,
            Expect::Error(&["zero", "character device"]),
        );
    }
    let big = l.sparse("scene/big.yaml", 8 << 30);
    let before = l.hashes();
    let o = check(&big);
    judge(
        "8 GB scene",
        &l,
        &before,
        &o,
        Expect::Error(&["big.yaml", "larger than"]),
    );

    // URDF and mesh as /dev/zero links and as sparse files.
    let l = Layout::new();
    l.symlink(zero, "scene/pkg/urdf/robot.urdf");
    let scene = l.scene(&robot_scene());
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "URDF -> /dev/zero",
        &l,
        &before,
        &o,
        Expect::Error(&["robot.urdf", "device"]),
    );

    let l = Layout::new();
    l.sparse("scene/pkg/urdf/robot.urdf", 1 << 32);
    let scene = l.scene(&robot_scene());
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "4 GB URDF",
        &l,
        &before,
        &o,
        Expect::Error(&["robot.urdf", "larger than"]),
    );

    let l = Layout::new();
    l.symlink(zero, "scene/pkg/meshes/z.stl");
    let scene = l.robot("package://pkg/meshes/z.stl", "");
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "mesh -> /dev/zero",
        &l,
        &before,
        &o,
        Expect::Error(&["z.stl", "arm"]),
    );

    let l = Layout::new();
    l.sparse("scene/pkg/meshes/huge.stl", 1 << 33);
    let scene = l.robot("../meshes/huge.stl", "");
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "8 GB mesh",
        &l,
        &before,
        &o,
        Expect::Error(&["huge.stl", "larger than"]),
    );

    let l = Layout::new();
    l.symlink(zero, "scene/zero.stl");
    let scene = l.scene(&format!(
        "{SCENE}obstacles:\n  - {{ name: rock, shape: {{ type: mesh, path: zero.stl }} }}\n"
    ));
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "obstacle mesh -> /dev/zero",
        &l,
        &before,
        &o,
        Expect::Error(&["zero.stl", "obstacles[0]"]),
    );

    // Joints bag: /dev/zero and an 8 GB sparse file.
    let l = Layout::new();
    let scene = l.robot("../meshes/m.stl", "");
    let zj = l.symlink(zero, "scene/zero.mcap");
    let bj = l.sparse("scene/big.mcap", 8 << 30);
    for (name, j, what) in [
        ("joints -> /dev/zero", zj, "device"),
        ("8 GB joints bag", bj, "larger than"),
    ] {
        let before = l.hashes();
        let o = record(
            &scene,
            &l.path("scene/out.mcap"),
            &["--joints", j.to_str().expect("utf8")],
        );
        judge(name, &l, &before, &o, Expect::Error(&["--joints", what]));
    }

    // A scene of 5 million pin indices (about 40 MB) is over the scene cap.
    let l = Layout::new();
    let mut text = with(
        SCENE,
        "pins: [ { region: top_left } ]",
        "pins: [ { vertices: [",
    );
    text.reserve(40 << 20);
    for _ in 0..5_000_000 {
        text.push_str("0, ");
    }
    text.push_str("0] } ]\n");
    let scene = l.scene(&text);
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "5M pin indices",
        &l,
        &before,
        &o,
        Expect::Error(&["scene.yaml", "larger than"]),
    );
}

// ---------------------------------------------------------------- silent garbage, non-finite output

#[test]
fn overflowing_numbers_are_named_by_their_key() {
    for (name, from, to, key) in [
        (
            "grid xyz 1e308",
            "xyz: [0, 0, 1]",
            "xyz: [1e308, 0, 1.5]",
            "cloths[0].grid.pose.xyz[0]",
        ),
        (
            "grid rpy 1e300",
            "xyz: [0, 0, 1]",
            "xyz: [0, 0, 1], rpy: [1e300, 0, 0]",
            "cloths[0].grid.pose.rpy[0]",
        ),
        (
            "grid size 1e300",
            "size: [0.2, 0.2]",
            "size: [1e300, 0.2]",
            "cloths[0].grid.size[0]",
        ),
        (
            "stretch 1e308",
            "pins:",
            "material: { stretch: 1e308 }\n    pins:",
            "cloths[0].material.stretch",
        ),
        (
            "density 1e308",
            "pins:",
            "material: { density: 1e308 }\n    pins:",
            "cloths[0].material.density",
        ),
        (
            "density NaN",
            "pins:",
            "material: { density: .nan }\n    pins:",
            "cloths[0].material.density",
        ),
        (
            "friction inf",
            "pins:",
            "material: { friction: .inf }\n    pins:",
            "cloths[0].material.friction",
        ),
        (
            "thickness 1e10",
            "pins:",
            "material: { thickness: 1e10 }\n    pins:",
            "cloths[0].material.thickness",
        ),
        (
            "gravity -1e308",
            "duration: 0.1",
            "duration: 0.1\ngravity: [0, 0, -1e308]",
            "gravity[2]",
        ),
        ("dt 1e9 for 0.2 s", "dt: 0.02", "dt: 1e9", "solver.dt"),
        (
            "linearisation tolerance NaN",
            "dt: 0.02",
            "dt: 0.02, linearisation_tolerance: .nan",
            "solver.linearisation_tolerance",
        ),
        (
            "linearisation tolerance 0",
            "dt: 0.02",
            "dt: 0.02, linearisation_tolerance: 0",
            "solver.linearisation_tolerance",
        ),
        (
            "dt above duration",
            "duration: 0.1",
            "duration: 0.01",
            "duration",
        ),
        (
            "near radius inf",
            "pins: [ { region: top_left } ]",
            "pins: [ { near: { point: [0, 0, 1], radius: .inf } } ]",
            "cloths[0].pins[0].near.radius",
        ),
    ] {
        scene_case(name, &with(SCENE, from, to), key);
    }
    let framed = format!(
        "{SCENE}frames:\n  - {{ name: h, pose: {{ xyz: [0, 0, 1] }}, linear_velocity: [1e300, 0, 0] }}\n"
    );
    scene_case(
        "frame velocity 1e300",
        &framed,
        "frames[0].linear_velocity[0]",
    );
    let obstacle = format!(
        "{SCENE}obstacles:\n  - {{ name: rock, shape: {{ type: sphere, radius: 0.1 }}, pose: {{ xyz: [1e308, 0, 0] }} }}\n"
    );
    scene_case("obstacle pose 1e308", &obstacle, "obstacles[0].pose.xyz[0]");
    let waypoints = format!(
        "{SCENE}obstacles:\n  - {{ name: rock, shape: {{ type: sphere, radius: 0.1 }}, motion: {{ type: waypoints, points: [ {{ t: .nan, pose: {{}} }} ] }} }}\n"
    );
    scene_case(
        "waypoint t NaN",
        &waypoints,
        "obstacles[0].motion.points[0].t",
    );
    let traj = with(
        &robot_scene(),
        "urdf: pkg/urdf/robot.urdf",
        "urdf: pkg/urdf/robot.urdf\n  trajectory: { names: [j], points: [ { t: 0, positions: [1e300] } ] }",
    );
    let l = Layout::new();
    l.write("scene/pkg/urdf/robot.urdf", urdf("../meshes/m.stl", ""));
    let scene = l.scene(&traj);
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "trajectory 1e300",
        &l,
        &before,
        &o,
        Expect::Error(&["scene.yaml", "robot.trajectory.points[0].positions[0]"]),
    );
}

#[test]
fn mimic_multipliers_and_offsets_must_be_finite_and_plausible() {
    for (name, attrs) in [
        ("mimic multiplier NaN", r#"multiplier="nan""#),
        ("mimic multiplier inf", r#"multiplier="inf""#),
        ("mimic offset 1e308", r#"offset="1e308""#),
        ("mimic multiplier -1e300", r#"multiplier="-1e300""#),
    ] {
        let l = Layout::new();
        let extra = format!(
            r#"<link name="finger"/><joint name="m" type="revolute"><parent link="arm"/><child link="finger"/>
               <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/><mimic joint="j" {attrs}/></joint>"#
        );
        let scene = l.robot("../meshes/m.stl", &extra);
        let before = l.hashes();
        let o = check(&scene);
        judge(
            name,
            &l,
            &before,
            &o,
            Expect::Error(&["robot.urdf", "joint `m`", "mimic"]),
        );
        let o = record(&scene, &l.path("scene/out.mcap"), &[]);
        judge(
            name,
            &l,
            &before,
            &o,
            Expect::Error(&["robot.urdf", "joint `m`"]),
        );
    }
}

// ---------------------------------------------------------------- escapes

#[test]
fn meshes_outside_the_allowed_folders_are_refused_before_opening() {
    let outside = |l: &Layout| l.path("outside/secret.stl");
    // A symlink in the package pointing outside, through every reference form.
    for (name, uri) in [
        ("package:// symlink", "package://pkg/meshes/link.stl"),
        ("relative symlink", "../meshes/link.stl"),
        ("file:// symlink", "FILE"),
    ] {
        let l = Layout::new();
        l.symlink(&outside(&l), "scene/pkg/meshes/link.stl");
        let uri = if uri == "FILE" {
            format!("file://{}", l.path("scene/pkg/meshes/link.stl").display())
        } else {
            uri.to_string()
        };
        let scene = l.robot(&uri, "");
        let before = l.hashes();
        let o = check(&scene);
        judge(
            name,
            &l,
            &before,
            &o,
            Expect::Error(&["robot.urdf", "arm", "outside the allowed"]),
        );
    }
    // Plain paths and package URIs that land outside.
    for (name, uri) in [
        ("../../.. relative", "../../../outside/secret.stl"),
        ("absolute path", "ABS"),
        ("file:// absolute", "FILEABS"),
        (
            "package://pkg/../..",
            "package://pkg/../../outside/secret.stl",
        ),
    ] {
        let l = Layout::new();
        let uri = match uri {
            "ABS" => outside(&l).display().to_string(),
            "FILEABS" => format!("file://{}", outside(&l).display()),
            u => u.to_string(),
        };
        let scene = l.robot(&uri, "");
        let before = l.hashes();
        let o = check(&scene);
        judge(name, &l, &before, &o, Expect::Error(&["robot.urdf", "arm"]));
    }
    // `package://outside/...` must not find a sibling folder of the scene named like the URI.
    let l = Layout::new();
    let scene = l.robot("package://outside/secret.stl", "");
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "package://<sibling>",
        &l,
        &before,
        &o,
        Expect::Error(&["robot.urdf", "arm"]),
    );

    // Scene obstacle meshes: `..`, absolute, and a symlink out.
    for (name, path) in [
        ("obstacle ..", "../outside/secret.stl"),
        ("obstacle absolute", "ABS"),
        ("obstacle symlink", "LINK"),
    ] {
        let l = Layout::new();
        let path = match path {
            "ABS" => outside(&l).display().to_string(),
            "LINK" => {
                l.symlink(&outside(&l), "scene/rock.stl");
                "rock.stl".to_string()
            }
            p => p.to_string(),
        };
        let scene = l.scene(&format!(
            "{SCENE}obstacles:\n  - {{ name: rock, shape: {{ type: mesh, path: '{path}' }} }}\n"
        ));
        let before = l.hashes();
        let o = check(&scene);
        judge(
            name,
            &l,
            &before,
            &o,
            Expect::Error(&["scene.yaml", "obstacles[0]", "outside the allowed"]),
        );
    }

    // The tripwire: a FIFO outside the allowed folders, reached through a symlink in the
    // package, must never be opened (the check happens before the open).
    let l = Layout::new();
    let wire = Tripwire::new(&l, "outside/wire.stl");
    l.symlink(&l.path("outside/wire.stl"), "scene/pkg/meshes/wire.stl");
    let scene = l.robot("package://pkg/meshes/wire.stl", "");
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "tripwire",
        &l,
        &before,
        &o,
        Expect::Error(&["robot.urdf", "outside the allowed"]),
    );
    assert!(
        !wire.opened(),
        "drape opened a file outside the allowed folders"
    );
}

#[test]
fn inside_the_rules_meshes_load() {
    // Package, relative and symlink-inside references, and an explicit allow-list entry.
    for uri in [
        "package://pkg/meshes/m.stl",
        "../meshes/m.stl",
        "package://pkg/meshes/inner.stl",
    ] {
        let l = Layout::new();
        l.symlink(
            &l.path("scene/pkg/meshes/m.stl"),
            "scene/pkg/meshes/inner.stl",
        );
        let scene = l.robot(uri, "");
        let before = l.hashes();
        let o = check(&scene);
        judge(uri, &l, &before, &o, Expect::Ok);
    }
    let l = Layout::new();
    l.write(
        "scene/pkg/urdf/robot.urdf",
        urdf("../../../outside/secret.stl", ""),
    );
    let scene = l.scene(&format!("{}mesh_paths: [../outside]\n", robot_scene()));
    let before = l.hashes();
    let o = check(&scene);
    judge("allow-listed folder", &l, &before, &o, Expect::Ok);
}

// ---------------------------------------------------------------- destroyed input

fn joints_bag(path: &Path) {
    let mut bag = BagWriter::create(path).expect("bag");
    let t = bag
        .add_topic::<JointState>("/joint_states", Distro::Jazzy, None)
        .expect("topic");
    for k in 0..5u64 {
        let js = JointState {
            name: vec!["j".into()],
            position: vec![0.1 * k as f64],
            ..JointState::default()
        };
        bag.write(t, k * 20_000_000, &js).expect("write");
    }
    bag.finish().expect("finish");
}

#[test]
fn the_recorder_never_writes_onto_its_inputs() {
    let l = Layout::new();
    let scene = l.robot("package://pkg/meshes/m.stl", "");
    let joints = l.path("scene/joints.mcap");
    joints_bag(&joints);
    let link = l.symlink(&scene, "scene/link.mcap");
    let hard = l.path("scene/hard.mcap");
    std::fs::hard_link(l.path("scene/pkg/urdf/robot.urdf"), &hard).expect("hard link");
    let j = joints.to_str().expect("utf8");
    for (name, out, extra) in [
        ("--out = scene", scene.clone(), vec![]),
        ("--out = symlink to scene", link, vec![]),
        ("--out = hard link of the URDF", hard, vec![]),
        ("--out = mesh", l.path("scene/pkg/meshes/m.stl"), vec![]),
        ("--out = joints bag", joints.clone(), vec!["--joints", j]),
        ("--out = directory", l.path("scene/pkg"), vec![]),
    ] {
        let before = l.hashes();
        let o = record(&scene, &out, &extra);
        judge(
            name,
            &l,
            &before,
            &o,
            Expect::Error(&[&out.display().to_string()]),
        );
    }
    // And a normal recording with the joints bag works and leaves no staging file behind.
    let before = l.hashes();
    let out = l.path("scene/out.mcap");
    let o = record(&scene, &out, &["--joints", j]);
    judge("record with joints", &l, &before, &o, Expect::Ok);
    assert!(report_only() || out.is_file());
    let names: Vec<String> = std::fs::read_dir(&l.scene_dir)
        .expect("dir")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        report_only() || !names.iter().any(|n| n.contains(".partial")),
        "{names:?}"
    );
}

// ---------------------------------------------------------------- wrong or unclear errors

#[test]
fn valid_input_with_a_byte_order_mark_is_accepted() {
    let l = Layout::new();
    let scene = l.scene(&format!("\u{feff}{SCENE}"));
    let before = l.hashes();
    judge("BOM scene", &l, &before, &check(&scene), Expect::Ok);
    let l = Layout::new();
    l.write(
        "scene/pkg/urdf/robot.urdf",
        format!("\u{feff}{}", urdf("../meshes/m.stl", "")),
    );
    let scene = l.scene(&format!("\u{feff}{}", robot_scene()));
    let before = l.hashes();
    judge("BOM URDF", &l, &before, &check(&scene), Expect::Ok);
}

#[test]
fn errors_name_the_file_and_say_what_is_wrong() {
    // A misspelled URDF root.
    let l = Layout::new();
    l.write(
        "scene/pkg/urdf/robot.urdf",
        urdf("../meshes/m.stl", "")
            .replace("<robot", "<robt")
            .replace("</robot>", "</robt>"),
    );
    let scene = l.scene(&robot_scene());
    let before = l.hashes();
    judge(
        "<robt> root",
        &l,
        &before,
        &check(&scene),
        Expect::Error(&["robot.urdf", "<robt>"]),
    );

    // A truncated joints bag: cut inside the first record, and cut at a record boundary.
    let l = Layout::new();
    let scene = l.robot("../meshes/m.stl", "");
    let full = l.path("scene/full.mcap");
    joints_bag(&full);
    let bytes = std::fs::read(&full).expect("read");
    for (name, len) in [
        ("bag cut at 20 bytes", 20usize),
        ("bag cut at 60%", bytes.len() * 6 / 10),
    ] {
        let cut = l.write("scene/joints.mcap", &bytes[..len]);
        let before = l.hashes();
        let o = record(
            &scene,
            &l.path("scene/out.mcap"),
            &["--joints", cut.to_str().expect("utf8")],
        );
        if len == 20 {
            judge(
                name,
                &l,
                &before,
                &o,
                Expect::Error(&["joints.mcap", "truncated"]),
            );
        } else {
            // Messages before the cut are kept: a usable (shorter) joint stream.
            judge(name, &l, &before, &o, Expect::Ok);
        }
    }

    // A directory as the scene: the cause once, and the file first.
    let l = Layout::new();
    let before = l.hashes();
    let o = check(&l.scene_dir);
    judge(
        "directory scene",
        &l,
        &before,
        &o,
        Expect::Error(&["scene", "directory"]),
    );
    if !report_only() {
        assert_eq!(o.stderr.matches("directory").count(), 1, "{}", o.stderr);
    }

    // Errors start with the file, then the key; YAML errors give the place.
    let l = Layout::new();
    let scene = l.scene(&with(SCENE, "dt: 0.02", "dt: -1"));
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "negative dt",
        &l,
        &before,
        &o,
        Expect::Error(&["solver.dt"]),
    );
    let first = o.stderr.lines().next().unwrap_or("");
    let starts = first.starts_with(&format!("drape: error: {}: solver.dt", scene.display()));
    if report_only() && !starts {
        eprintln!("FAIL error starts with the file, then the key: {first}");
    } else {
        assert!(starts, "{first}");
    }
    let scene = l.scene(&with(SCENE, "pins:", "materal: {}\n    pins:"));
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "misspelled key",
        &l,
        &before,
        &o,
        Expect::Error(&["scene.yaml", "materal", "line"]),
    );
    let scene = l.scene("\u{0}\u{1}binary");
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "binary scene",
        &l,
        &before,
        &o,
        Expect::Error(&["scene.yaml"]),
    );
    let scene = l.write("scene/latin1.yaml", b"name: caf\xe9\n");
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "not UTF-8",
        &l,
        &before,
        &o,
        Expect::Error(&["latin1.yaml", "UTF-8"]),
    );
}

// ---------------------------------------------------------------- signals end every phase

/// SIGTERM while the scene is still being built and its shirt sewn (before any frame is
/// recorded) ends the run at once, with status 130 and no output left behind.
#[test]
fn a_signal_during_build_and_sewing_ends_the_run() {
    let l = Layout::new();
    let shirt = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/shirt.yaml");
    let out = l.path("scene/out.mcap");
    let mut child = Command::new(binary())
        .args(["record", "--quiet", "--scene"])
        .arg(&shirt)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn drape");
    std::thread::sleep(Duration::from_millis(200));
    let sent = Instant::now();
    let pid = libc::pid_t::try_from(child.id()).expect("pid");
    assert_eq!(unsafe { libc::kill(pid, libc::SIGTERM) }, 0);
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        if sent.elapsed() > KILL_AFTER {
            let _ = child.kill();
            panic!("drape ignored SIGTERM during build");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    assert!(
        sent.elapsed() < BUDGET,
        "took {:?} after SIGTERM",
        sent.elapsed()
    );
    if report_only() {
        eprintln!("signal during build: {status} after {:?}", sent.elapsed());
        return;
    }
    assert_eq!(status.code(), Some(130), "{status}");
    assert!(!out.exists());
    let left: Vec<_> = std::fs::read_dir(&l.scene_dir)
        .expect("dir")
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().contains(".partial"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

// ---------------------------------------------------------------- outputs

fn os(args: &[&str]) -> Vec<std::ffi::OsString> {
    args.iter().map(std::ffi::OsString::from).collect()
}

fn run(args: &[std::ffi::OsString]) -> Outcome {
    let a: Vec<&std::ffi::OsStr> = args.iter().map(|x| x.as_os_str()).collect();
    drape(&a)
}

fn run_limited(args: &[std::ffi::OsString], file_size: u64) -> Outcome {
    let a: Vec<&std::ffi::OsStr> = args.iter().map(|x| x.as_os_str()).collect();
    drape_limited(&a, Some(file_size))
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf8 path")
}

/// `scene/s.yaml`: a sweep over the tiny scene (`scene/scene.yaml`) into `scene/out`.
fn sweep_yaml(l: &Layout, body: &str) -> PathBuf {
    l.scene(SCENE);
    l.write(
        "scene/s.yaml",
        format!("name: s\nscene: scene.yaml\nout: out\n{body}"),
    )
}

/// A bag of the tiny scene, recorded by drape (`scene/b.mcap`).
fn tiny_bag(l: &Layout) -> PathBuf {
    let scene = l.scene(SCENE);
    let bag = l.path("scene/b.mcap");
    let o = record(&scene, &bag, &[]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    bag
}

/// Staging files (`.partial`, `.tmp`) left anywhere under the layout.
fn staging_left(l: &Layout) -> Vec<PathBuf> {
    fn walk(d: &Path, out: &mut Vec<PathBuf>) {
        let Ok(rd) = std::fs::read_dir(d) else { return };
        for e in rd.flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if name.contains(".partial") || name.contains(".tmp") || name.ends_with(".part") {
                out.push(p.clone());
            }
            if p.is_dir() && !p.is_symlink() {
                walk(&p, out);
            }
        }
    }
    let mut out = Vec::new();
    walk(&l.root, &mut out);
    out
}

#[test]
fn outputs_never_overwrite_inputs() {
    let l = Layout::new();
    let bag = tiny_bag(&l);
    let scene = l.path("scene/scene.yaml");
    let sweep = sweep_yaml(&l, "");
    let out = l.path("scene/out.mcap");
    let gif = l.path("scene/b.gif");
    std::fs::hard_link(&bag, &gif).expect("hard link");
    let manifest = l.symlink(&scene, "scene/m.yaml");
    let cases: Vec<(&str, Vec<std::ffi::OsString>, PathBuf)> = vec![
        (
            "record --summary = scene",
            os(&[
                "record",
                "--quiet",
                "--scene",
                s(&scene),
                "--out",
                s(&out),
                "--summary",
                s(&scene),
            ]),
            scene.clone(),
        ),
        (
            "record --summary = --out",
            os(&[
                "record",
                "--quiet",
                "--scene",
                s(&scene),
                "--out",
                s(&out),
                "--summary",
                s(&out),
            ]),
            out.clone(),
        ),
        (
            "render --out = its bag",
            os(&["render", s(&bag), "--out", s(&bag)]),
            bag.clone(),
        ),
        (
            "render --out = a hard link of its bag",
            os(&["render", s(&bag), "--out", s(&gif)]),
            gif.clone(),
        ),
        (
            "emit slurm --script = the sweep file",
            os(&["sweep", "emit", "slurm", s(&sweep), "--script", s(&sweep)]),
            sweep.clone(),
        ),
        (
            "emit k8s --manifest = the sweep file",
            os(&["sweep", "emit", "k8s", s(&sweep), "--manifest", s(&sweep)]),
            sweep.clone(),
        ),
        (
            "emit k8s --manifest = a symlink to the scene",
            os(&[
                "sweep",
                "emit",
                "k8s",
                s(&sweep),
                "--manifest",
                s(&manifest),
            ]),
            manifest.clone(),
        ),
    ];
    for (name, args, named) in cases {
        let before = l.hashes();
        let o = run(&args);
        judge(
            name,
            &l,
            &before,
            &o,
            Expect::Error(&[s(&named), "refusing to overwrite"]),
        );
        assert!(report_only() || !out.exists(), "{name}: wrote the bag");
    }
    assert!(staging_left(&l).is_empty(), "{:?}", staging_left(&l));

    // A sweep whose output folder holds its own scene as plan.json (a hard link) or its sweep
    // file as manifest.csv (a symlink).
    std::fs::create_dir_all(l.path("scene/out")).expect("mkdir");
    std::fs::hard_link(&scene, l.path("scene/out/plan.json")).expect("hard link");
    let before = l.hashes();
    let o = run(&os(&["sweep", "run", s(&sweep), "--index", "0", "--quiet"]));
    judge(
        "plan.json = scene",
        &l,
        &before,
        &o,
        Expect::Error(&["plan.json", "refusing to overwrite"]),
    );
    std::fs::remove_file(l.path("scene/out/plan.json")).expect("rm");
    let o = run(&os(&["sweep", "run", s(&sweep), "--index", "0", "--quiet"]));
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    l.symlink(&sweep, "scene/out/manifest.csv");
    let before = l.hashes();
    let o = run(&os(&["sweep", "collect", s(&l.path("scene/out"))]));
    judge(
        "manifest.csv = sweep file",
        &l,
        &before,
        &o,
        Expect::Error(&["manifest.csv", "refusing to overwrite"]),
    );
    assert!(staging_left(&l).is_empty(), "{:?}", staging_left(&l));
}

#[test]
fn a_full_disk_leaves_nothing_under_the_final_name() {
    let l = Layout::new();
    let bag = tiny_bag(&l);
    let scene = l.path("scene/scene.yaml");
    let sweep = sweep_yaml(&l, "");
    let png = l.path("scene/t.png");
    let gif = l.path("scene/t.gif");
    let summary = l.path("scene/summary.json");
    let out = l.path("scene/out.mcap");
    let cases: Vec<(&str, Vec<std::ffi::OsString>, u64, PathBuf)> = vec![
        (
            "PNG",
            os(&["render", s(&bag), "--out", s(&png)]),
            2000,
            png.clone(),
        ),
        (
            "GIF",
            os(&["render", s(&bag), "--out", s(&gif)]),
            2000,
            gif.clone(),
        ),
        // The GIF's last bytes (trailer and flush) fail: a limit just under its full size.
        (
            "GIF trailer",
            os(&["render", s(&bag), "--out", s(&gif), "--size", "8x8"]),
            0,
            gif.clone(),
        ),
        (
            "--summary",
            os(&[
                "record",
                "--quiet",
                "--scene",
                s(&scene),
                "--out",
                "/dev/null",
                "--summary",
                s(&summary),
            ]),
            100,
            summary.clone(),
        ),
        (
            "bag",
            os(&["record", "--quiet", "--scene", s(&scene), "--out", s(&out)]),
            4000,
            out.clone(),
        ),
        (
            "sweep plan.json",
            os(&["sweep", "run", s(&sweep), "--index", "0", "--quiet"]),
            64,
            l.path("scene/out/plan.json"),
        ),
        (
            "emit script",
            os(&[
                "sweep",
                "emit",
                "slurm",
                s(&sweep),
                "--out",
                s(&l.path("scene/o2")),
                "--script",
                s(&l.path("scene/x.sh")),
            ]),
            400,
            l.path("scene/x.sh"),
        ),
    ];
    for (name, args, mut limit, target) in cases {
        if limit == 0 {
            // Measure the full size, then allow one byte less.
            let o = run(&args);
            assert_eq!(o.code, Some(0), "{name}: {}", o.stderr);
            limit = std::fs::metadata(&target).expect("written").len() - 1;
            std::fs::remove_file(&target).expect("rm");
        }
        let before = l.hashes();
        let o = run_limited(&args, limit);
        judge(name, &l, &before, &o, Expect::Error(&[s(&target)]));
        assert!(
            report_only() || !target.exists(),
            "{name}: {} left",
            target.display()
        );
        assert!(
            staging_left(&l).is_empty(),
            "{name}: {:?}",
            staging_left(&l)
        );
    }
}

// ---------------------------------------------------------------- scheduler files

/// Documents in a YAML text, and the `kind` of each.
fn yaml_kinds(text: &str) -> Vec<String> {
    use serde::Deserialize;
    serde_yaml_ng::Deserializer::from_str(text)
        .map(|d| {
            let v = serde_yaml_ng::Value::deserialize(d).expect("YAML");
            v.get("kind")
                .and_then(|k| k.as_str())
                .unwrap_or("")
                .to_string()
        })
        .collect()
}

#[test]
fn names_and_paths_cannot_inject_into_scheduler_files() {
    let l = Layout::new();
    let script = l.path("scene/x.sh");
    let manifest = l.path("scene/x.yaml");
    // Names that would put a live shell line into the script or a second document (a Pod)
    // into the manifest are refused when the sweep is read, by every command.
    for (name, text) in [
        ("backtick and newline", "\"a`touch /tmp/pwned`\\nb\""),
        ("second document", "\"a\\n---\\nkind: Pod\\n\""),
        ("shell operators", "\"a; rm -rf ~\""),
    ] {
        let sweep = sweep_yaml(&l, "");
        let sweep = l.write(
            "scene/s.yaml",
            std::fs::read_to_string(&sweep)
                .expect("read")
                .replace("name: s", &format!("name: {text}")),
        );
        for args in [
            os(&["sweep", "plan", s(&sweep)]),
            os(&["sweep", "emit", "slurm", s(&sweep), "--script", s(&script)]),
            os(&[
                "sweep",
                "emit",
                "k8s",
                s(&sweep),
                "--manifest",
                s(&manifest),
            ]),
        ] {
            let before = l.hashes();
            let o = run(&args);
            judge(name, &l, &before, &o, Expect::Error(&["s.yaml", "name"]));
            assert!(report_only() || (!script.exists() && !manifest.exists()));
        }
    }
    // Paths and options with a newline (an `#SBATCH` line of their own) or characters an
    // `#SBATCH` line cannot carry are refused, naming the option.
    let sweep = sweep_yaml(&l, "");
    let nl_out = l.path("scene/o\n#SBATCH --mem=1T");
    for (name, args, key) in [
        (
            "out with a newline",
            os(&[
                "sweep",
                "emit",
                "slurm",
                s(&sweep),
                "--out",
                s(&nl_out),
                "--script",
                s(&script),
            ]),
            "out",
        ),
        (
            "partition with a newline",
            os(&[
                "sweep",
                "emit",
                "slurm",
                s(&sweep),
                "--partition",
                "p\n#SBATCH --mem=1T",
                "--script",
                s(&script),
            ]),
            "--partition",
        ),
        (
            "sbatch with a command substitution",
            os(&[
                "sweep",
                "emit",
                "slurm",
                s(&sweep),
                "--sbatch=--comment=$(id)",
                "--script",
                s(&script),
            ]),
            "--sbatch",
        ),
        (
            "k8s out with a newline",
            os(&[
                "sweep",
                "emit",
                "k8s",
                s(&sweep),
                "--out",
                "/data/o\n---\nkind: Pod",
                "--manifest",
                s(&manifest),
            ]),
            "--out",
        ),
        (
            "k8s image with a newline",
            os(&[
                "sweep",
                "emit",
                "k8s",
                s(&sweep),
                "--image",
                "x\nkind: Pod",
                "--manifest",
                s(&manifest),
            ]),
            "--image",
        ),
    ] {
        let before = l.hashes();
        let o = run(&args);
        judge(name, &l, &before, &o, Expect::Error(&[key]));
        assert!(
            report_only() || (!script.exists() && !manifest.exists()),
            "{name}"
        );
    }
    assert!(report_only() || !l.path("scene/o\n#SBATCH --mem=1T").exists());

    // Valid but awkward values: the script passes `bash -n` with one `exec` line, the
    // manifest is exactly one document, a Job, with the values intact.
    let sweep = l.write(
        "scene/s.yaml",
        "name: my.sweep-1\nscene: scene.yaml\nout: out\ngrid:\n  duration: [0.1, 0.2]\n",
    );
    let before = l.hashes();
    let o = run(&os(&[
        "sweep",
        "emit",
        "slurm",
        s(&sweep),
        "--script",
        s(&script),
        "--drape",
        "/opt/it's here/drape",
    ]));
    judge("valid slurm", &l, &before, &o, Expect::Ok);
    let text = std::fs::read_to_string(&script).expect("script");
    let check = Command::new("bash")
        .arg("-n")
        .arg(&script)
        .output()
        .expect("bash");
    assert!(
        check.status.success(),
        "bash -n: {}",
        String::from_utf8_lossy(&check.stderr)
    );
    let live: Vec<&str> = text
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .collect();
    assert_eq!(live.len(), 3, "{text}");
    assert!(
        live[2].starts_with("exec '/opt/it'\\''s here/drape' sweep run "),
        "{text}"
    );
    assert!(text.contains("#SBATCH --array=0-1\n"), "{text}");
    let image = "reg.example/drape:1 # not: a comment\"'";
    let before = l.hashes();
    let o = run(&os(&[
        "sweep",
        "emit",
        "k8s",
        s(&sweep),
        "--manifest",
        s(&manifest),
        "--image",
        image,
        "--pvc",
        "a: b",
    ]));
    judge("valid k8s", &l, &before, &o, Expect::Ok);
    let text = std::fs::read_to_string(&manifest).expect("manifest");
    assert_eq!(yaml_kinds(&text), ["Job"], "{text}");
    let job: serde_yaml_ng::Value = serde_yaml_ng::from_str(&text).expect("one document");
    let c = &job["spec"]["template"]["spec"]["containers"][0];
    assert_eq!(c["image"].as_str(), Some(image));
    assert_eq!(job["spec"]["completions"].as_u64(), Some(2));
}

// ---------------------------------------------------------------- unbounded sweeps

#[test]
fn sweeps_are_bounded_before_any_work() {
    let l = Layout::new();
    let list = |n: usize| format!("[{}]", vec!["0.1"; n].join(", "));
    let big = "x".repeat(5000);
    for (name, body, key) in [
        (
            "samples 1e9",
            "samples: 1000000000\n".to_string(),
            "samples",
        ),
        (
            "samples u64::MAX",
            "samples: 18446744073709551615\n".to_string(),
            "samples",
        ),
        (
            "a 1e9 grid",
            format!(
                "grid:\n  duration: {}\n  solver.dt: {}\n  cloths[0].material.stretch: {}\n",
                list(1000),
                list(1000),
                list(1000)
            ),
            "grid",
        ),
        (
            "1e5 jobs of a large scene document",
            format!("samples: 100000\ngrid:\n  name: [\"{big}\"]\n"),
            "grid",
        ),
    ] {
        let sweep = sweep_yaml(&l, &body);
        for args in [
            os(&["sweep", "plan", s(&sweep)]),
            os(&["sweep", "run", s(&sweep), "--index", "0", "--quiet"]),
            os(&["sweep", "emit", "k8s", s(&sweep)]),
        ] {
            let before = l.hashes();
            let o = run(&args);
            judge(
                name,
                &l,
                &before,
                &o,
                Expect::Error(&["s.yaml", key, "jobs"]),
            );
        }
        assert!(
            report_only() || !l.path("scene/out/plan.json").exists(),
            "{name}"
        );
    }
    // The largest sweep allowed: one job of it runs without building the plan in memory
    // (the child's address space is limited), and its plan file streams to disk.
    let sweep = sweep_yaml(
        &l,
        "samples: 100000\nrandom:\n  duration: { uniform: [0.1, 0.12] }\n",
    );
    let before = l.hashes();
    let o = run(&os(&[
        "sweep",
        "run",
        s(&sweep),
        "--index",
        "99999",
        "--quiet",
    ]));
    judge("one job of 1e5", &l, &before, &o, Expect::Ok);
    let plan = std::fs::read_to_string(l.path("scene/out/plan.json")).expect("plan");
    let plan: serde_json::Value = serde_json::from_str(&plan).expect("plan is JSON");
    assert_eq!(plan["job_count"].as_u64(), Some(100_000));
    assert_eq!(plan["jobs"].as_array().map(Vec::len), Some(100_000));
    assert!(l.path("scene/out/jobs/099999.json").is_file());
    // And the whole of it is checked, job by job, within the budget of a large input.
    let before = l.hashes();
    let a = os(&["sweep", "plan", s(&sweep)]);
    let a: Vec<&std::ffi::OsStr> = a.iter().map(|x| x.as_os_str()).collect();
    let o = drape_with(&a, None, LARGE_BUDGET * SLACK);
    judge_within(
        "plan of 1e5 jobs",
        &l,
        &before,
        &o,
        Expect::Ok,
        LARGE_BUDGET,
    );
}

// ---------------------------------------------------------------- crafted bags

/// An MCAP file of a header and one chunk (`compression` "zstd" or "") whose content is
/// `content` and whose declared uncompressed size is `declared`; no summary, no footer.
fn crafted_bag(content: &[u8], declared: u64, compression: &str) -> Vec<u8> {
    let record = |op: u8, body: &[u8]| {
        let mut r = vec![op];
        r.extend((body.len() as u64).to_le_bytes());
        r.extend(body);
        r
    };
    let string = |s: &str| {
        let mut b = (s.len() as u32).to_le_bytes().to_vec();
        b.extend(s.as_bytes());
        b
    };
    let data = if compression == "zstd" {
        zstd::bulk::compress(content, 3).expect("zstd")
    } else {
        content.to_vec()
    };
    let mut chunk = Vec::new();
    chunk.extend(0u64.to_le_bytes());
    chunk.extend(1u64.to_le_bytes());
    chunk.extend(declared.to_le_bytes());
    chunk.extend(0u32.to_le_bytes());
    chunk.extend(string(compression));
    chunk.extend((data.len() as u64).to_le_bytes());
    chunk.extend(&data);
    let mut header = string("ros2");
    header.extend(string("hostile"));
    let mut f = b"\x89MCAP0\r\n".to_vec();
    f.extend(record(0x01, &header));
    f.extend(record(0x06, &chunk));
    f
}

/// A message record header declaring `len` bytes, then a few bytes of it.
fn message_head(len: u64) -> Vec<u8> {
    let mut c = vec![0x05];
    c.extend(len.to_le_bytes());
    c.extend([0u8; 22]);
    c
}

#[test]
fn lengths_inside_compressed_chunks_are_checked_before_allocating() {
    let l = Layout::new();
    let scene = l.robot("package://pkg/meshes/m.stl", "");
    for (name, bytes, want) in [
        (
            "2^40-byte record in a zstd chunk",
            crafted_bag(&message_head(1 << 40), 31, "zstd"),
            "but only 22",
        ),
        (
            "2^40-byte record in a zstd chunk declaring 2^41 bytes",
            crafted_bag(&message_head(1 << 40), 1 << 41, "zstd"),
            "more than the",
        ),
        (
            "200 MiB record cut short in a zstd chunk declaring 2^41 bytes",
            crafted_bag(&message_head(200 << 20), 1 << 41, "zstd"),
            "ends after",
        ),
        (
            "2^40-byte record in an uncompressed chunk",
            crafted_bag(&message_head(1 << 40), 31, ""),
            "but only 22",
        ),
    ] {
        let bag = l.write("scene/crafted.mcap", &bytes);
        let png = l.path("scene/x.png");
        let before = l.hashes();
        let o = run(&os(&["render", s(&bag), "--out", s(&png)]));
        judge(
            name,
            &l,
            &before,
            &o,
            Expect::Error(&["crafted.mcap", "chunk 0", want]),
        );
        let o = record(&scene, &l.path("scene/out.mcap"), &["--joints", s(&bag)]);
        judge(
            name,
            &l,
            &before,
            &o,
            Expect::Error(&["crafted.mcap", "chunk 0", want]),
        );
        assert!(report_only() || !png.exists());
    }
    assert!(crafted_bag(&message_head(1 << 40), 31, "zstd").len() < 300);
}

// ---------------------------------------------------------------- sweep inputs

#[test]
fn sweep_inputs_follow_the_input_rules() {
    let l = Layout::new();
    let zero = Path::new("/dev/zero");
    let fifo = l.fifo("scene/f.yaml");
    // The sweep file itself.
    for (p, what) in [(fifo.as_path(), "FIFO"), (zero, "character device")] {
        let before = l.hashes();
        let o = run(&os(&["sweep", "plan", s(p)]));
        judge("sweep file", &l, &before, &o, Expect::Error(&[s(p), what]));
        let o = run(&os(&["sweep", "run", s(p), "--index", "0"]));
        judge("sweep file", &l, &before, &o, Expect::Error(&[s(p), what]));
    }
    // Its scene.
    for (p, what) in [(fifo.as_path(), "FIFO"), (zero, "character device")] {
        l.scene(SCENE);
        let sweep = l.write("scene/s.yaml", format!("name: s\nscene: {}\n", s(p)));
        let before = l.hashes();
        let o = run(&os(&["sweep", "plan", s(&sweep)]));
        judge(
            "scene",
            &l,
            &before,
            &o,
            Expect::Error(&["s.yaml", "scene", s(p), what]),
        );
    }
    // The output folder's plan and job records, under collect.
    let sweep = sweep_yaml(&l, "samples: 2\n");
    let o = run(&os(&["sweep", "run", s(&sweep), "--index", "0", "--quiet"]));
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    let out = l.path("scene/out");
    std::fs::remove_file(out.join("jobs/000000.json")).expect("rm");
    l.symlink(zero, "scene/out/jobs/000000.json");
    l.fifo("scene/out/jobs/000001.json");
    let before = l.hashes();
    let o = run(&os(&["sweep", "collect", s(&out)]));
    judge("job records", &l, &before, &o, Expect::Ok);
    std::fs::rename(out.join("plan.json"), out.join("plan.old")).expect("mv");
    l.symlink(zero, "scene/out/plan.json");
    let before = l.hashes();
    let o = run(&os(&["sweep", "collect", s(&out)]));
    judge(
        "plan.json",
        &l,
        &before,
        &o,
        Expect::Error(&["plan.json", "character device"]),
    );
}

// ---------------------------------------------------------------- limits and extents

#[test]
fn joint_limits_are_finite_ordered_and_not_negative() {
    for (name, limit, attribute) in [
        (
            "lower NaN",
            r#"lower="nan" upper="1" effort="1" velocity="1""#,
            "lower",
        ),
        (
            "lower above upper",
            r#"lower="2" upper="1" effort="1" velocity="1""#,
            "lower",
        ),
        (
            "negative velocity",
            r#"lower="-1" upper="1" effort="1" velocity="-3""#,
            "velocity",
        ),
        (
            "infinite effort",
            r#"lower="-1" upper="1" effort="inf" velocity="1""#,
            "effort",
        ),
        (
            "upper 1e300",
            r#"lower="-1" upper="1e300" effort="1" velocity="1""#,
            "upper",
        ),
    ] {
        let l = Layout::new();
        l.robot("package://pkg/meshes/m.stl", "");
        let text = std::fs::read_to_string(l.path("scene/pkg/urdf/robot.urdf"))
            .expect("urdf")
            .replace(r#"lower="-1" upper="1" effort="1" velocity="1""#, limit);
        l.write("scene/pkg/urdf/robot.urdf", text);
        let scene = l.path("scene/scene.yaml");
        let before = l.hashes();
        let want = ["robot.urdf", "joint `j`", &format!("<limit {attribute}=")];
        let o = check(&scene);
        judge(name, &l, &before, &o, Expect::Error(&want));
        let o = record(&scene, &l.path("scene/out.mcap"), &[]);
        judge(name, &l, &before, &o, Expect::Error(&want));
    }
}

/// A Collada square of half-width `half` (m) at the origin.
fn square_dae(half: &str) -> String {
    format!(
        r##"<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries><geometry id="g"><mesh>
    <source id="p"><float_array id="pa" count="12">-{half} -{half} 0 {half} -{half} 0 {half} {half} 0 -{half} {half} 0</float_array>
      <technique_common><accessor source="#pa" count="4" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles count="2"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2 0 2 3</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n"><instance_geometry url="#g"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>"##
    )
}

#[test]
fn mesh_extents_and_scales_are_bounded() {
    let stl_far = TETRA.replacen("vertex 0.1 0 0", "vertex 3.4e38 0 0", 1);
    for (name, file, body, scale, want) in [
        (
            "Collada floor at 1e20 m",
            "far.dae",
            square_dae("1e20"),
            "1 1 1",
            "beyond",
        ),
        (
            "STL vertex at 3.4e38",
            "far.stl",
            stl_far,
            "1 1 1",
            "beyond",
        ),
        (
            "scale 1e30",
            "m2.stl",
            TETRA.to_string(),
            "1e30 1 1",
            "scale",
        ),
        (
            "scale 1e-320",
            "m2.stl",
            TETRA.to_string(),
            "1 1e-320 1",
            "scale",
        ),
    ] {
        let l = Layout::new();
        l.write(&format!("scene/pkg/meshes/{file}"), &body);
        let mesh = format!(r#"package://pkg/meshes/{file}" scale="{scale}"#);
        let scene = l.robot(&mesh, "");
        let before = l.hashes();
        let o = check(&scene);
        judge(
            name,
            &l,
            &before,
            &o,
            Expect::Error(&[file, "link `arm`", want]),
        );
    }
    // Within the bounds: a 100 km floor and a millimetre scale load.
    let l = Layout::new();
    l.write("scene/pkg/meshes/floor.dae", square_dae("1e5"));
    let scene = l.robot(
        r#"package://pkg/meshes/floor.dae" scale="0.001 0.001 0.001"#,
        "",
    );
    let before = l.hashes();
    judge("valid extents", &l, &before, &check(&scene), Expect::Ok);
}

// ---------------------------------------------------------------- node start-up

#[test]
fn malformed_remaps_are_errors_before_the_node_starts() {
    let l = Layout::new();
    // A parameters file that does not exist: a remap that slipped through would fail on it
    // instead of starting a DDS participant.
    let params = l.path("scene/none.yaml");
    for (name, remap, want) in [
        ("empty namespace token", "__ns:=/a//b", "no empty token"),
        ("relative namespace", "__ns:=a", "starts with `/`"),
        ("trailing slash", "__ns:=/a/", "trailing"),
        (
            "namespace token with a digit first",
            "__ns:=/a/9b",
            "tokens",
        ),
        ("node name with a slash", "__node:=a/b", "node name"),
        ("empty node name", "__node:=", "node name"),
    ] {
        let before = l.hashes();
        let o = run(&os(&[
            "node",
            "--params",
            s(&params),
            "--ros-args",
            "-r",
            remap,
        ]));
        judge(name, &l, &before, &o, Expect::Error(&[remap, want]));
    }
}

// ---------------------------------------------------------------- render memory

/// A bag of `frames` cloth frames (two triangles each, moving) at 30 Hz.
fn long_bag(path: &Path, frames: u64) {
    use drape::ros::msg::{Marker, Point};
    let mut bag = BagWriter::create(path).expect("bag");
    let t = bag
        .add_topic::<Marker>("/drape/mesh", Distro::Jazzy, None)
        .expect("topic");
    for k in 0..frames {
        let z = 1.0 + 0.1 * (k as f64 * 0.01).sin();
        let p = |x: f64, y: f64| Point { x, y, z };
        let m = Marker {
            r#type: Marker::TRIANGLE_LIST,
            points: vec![
                p(0., 0.),
                p(0.2, 0.),
                p(0.2, 0.2),
                p(0., 0.),
                p(0.2, 0.2),
                p(0., 0.2),
            ],
            ..Marker::default()
        };
        bag.write(t, k * 33_333_333, &m).expect("write");
    }
    bag.finish().expect("finish");
}

#[test]
fn render_memory_does_not_grow_with_frames() {
    let l = Layout::new();
    let bag = l.path("scene/long.mcap");
    long_bag(&bag, 12_000);
    // Held whole, these 12,000 tiles of 96x96 would take 330 MB (the child may use 200 MB).
    let gif = l.path("scene/long.gif");
    let before = l.hashes();
    let a = os(&["render", s(&bag), "--out", s(&gif), "--size", "96x96"]);
    let a: Vec<&std::ffi::OsStr> = a.iter().map(|x| x.as_os_str()).collect();
    let o = drape_with(&a, None, LARGE_BUDGET * SLACK);
    judge_within(
        "12,000-frame GIF",
        &l,
        &before,
        &o,
        Expect::Ok,
        LARGE_BUDGET,
    );
    let bytes = std::fs::read(&gif).unwrap_or_default();
    let frames = bytes.windows(2).filter(|w| w == &[0x21, 0xF9]).count();
    assert!(report_only() || frames >= 12_000, "{frames} frame headers");
    // Two bags side by side, and a strip and the last frame as PNG sheets.
    for (k, args) in [
        vec![
            "render",
            s(&bag),
            s(&bag),
            "--size",
            "32x32",
            "--frames",
            "50",
            "--out",
        ],
        vec!["render", s(&bag), "--frames", "8", "--out"],
        vec!["render", s(&bag), "--at", "300,1,100", "--out"],
        vec!["render", s(&bag), "--out"],
    ]
    .into_iter()
    .enumerate()
    {
        let out = l.path(&format!(
            "scene/t{k}.{}",
            if k == 0 { "gif" } else { "png" }
        ));
        let before = l.hashes();
        let mut args = os(&args);
        args.push(out.clone().into_os_string());
        let o = run(&args);
        judge("long bag", &l, &before, &o, Expect::Ok);
    }
    let png = l.path("scene/big.png");
    // A sheet of more tiles than it may hold is refused before any is drawn.
    let before = l.hashes();
    let o = run(&os(&[
        "render",
        s(&bag),
        "--out",
        s(&png),
        "--frames",
        "1000000",
    ]));
    judge(
        "huge sheet",
        &l,
        &before,
        &o,
        Expect::Error(&["tiles", "--frames"]),
    );
}

// ---------------------------------------------------------------- collect and job locks

/// The manifest's entries by index: (status, error).
fn manifest(out: &Path) -> Vec<(String, String)> {
    std::fs::read_to_string(out.join("manifest.jsonl"))
        .expect("manifest")
        .lines()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).expect("json line");
            (
                v["status"].as_str().unwrap_or("").to_string(),
                v["error"].as_str().unwrap_or("").to_string(),
            )
        })
        .collect()
}

fn edit_json(path: &Path, f: impl FnOnce(&mut serde_json::Value)) {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).expect("read")).expect("json");
    f(&mut v);
    std::fs::write(path, serde_json::to_string(&v).expect("json")).expect("write");
}

#[test]
fn collect_verifies_what_it_reads() {
    let l = Layout::new();
    let sweep = sweep_yaml(&l, "samples: 5\n");
    let out = l.path("scene/out");
    for i in 0..5 {
        let o = run(&os(&[
            "sweep",
            "run",
            s(&sweep),
            "--index",
            &i.to_string(),
            "--quiet",
        ]));
        assert_eq!(o.code, Some(0), "{}", o.stderr);
    }
    let rec = |i: usize| out.join(format!("jobs/{i:06}.json"));
    // Job 1's record claims job 2's index; job 2's names a bag far outside the sweep; job 3's
    // bag is corrupted in place at the same size; job 4's record is not a record.
    edit_json(&rec(1), |v| v["index"] = 2.into());
    edit_json(&rec(2), |v| v["bag"] = "../../../../etc/passwd".into());
    let bag3 = out.join("jobs/000003.mcap");
    let mut bytes = std::fs::read(&bag3).expect("bag");
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0xff;
    std::fs::write(&bag3, &bytes).expect("write");
    std::fs::write(rec(4), "{ not json").expect("write");
    let before = l.hashes();
    let o = run(&os(&["sweep", "collect", s(&out)]));
    judge("collect", &l, &before, &o, Expect::Ok);
    let m = manifest(&out);
    let want = [
        ("ok", ""),
        ("failed", "claims job 2"),
        ("failed", "../../../../etc/passwd"),
        ("ok", ""),
        ("failed", "not a job record"),
    ];
    for (i, (status, why)) in want.iter().enumerate() {
        assert_eq!(m[i].0, *status, "job {i}: {:?}", m[i]);
        assert!(m[i].1.contains(why), "job {i}: {:?}", m[i]);
    }
    // With --verify the corrupted bag is found.
    let o = run(&os(&["sweep", "collect", s(&out), "--verify"]));
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    let m = manifest(&out);
    assert_eq!(m[3].0, "failed");
    assert!(m[3].1.contains("SHA-256"), "{:?}", m[3]);
    assert_eq!(m[0].0, "ok");
    // A rerun of the corrupted job redoes it instead of skipping it.
    let o = run(&os(&["sweep", "run", s(&sweep), "--index", "3", "--quiet"]));
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert_ne!(
        std::fs::read(&bag3).expect("bag"),
        bytes,
        "job 3 was skipped"
    );
    // A local rerun redoes every job that is not done, a bag changed in place included.
    let bag0 = out.join("jobs/000000.mcap");
    let mut b0 = std::fs::read(&bag0).expect("bag");
    let mid = b0.len() / 2;
    b0[mid] ^= 0xff;
    std::fs::write(&bag0, &b0).expect("write");
    let o = run(&os(&["sweep", "run", s(&sweep), "--local", "--quiet"]));
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    let o = run(&os(&["sweep", "collect", s(&out), "--verify"]));
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(
        manifest(&out).iter().all(|(st, _)| st == "ok"),
        "{:?}",
        manifest(&out)
    );

    // A plan listing a job three times, or with a wrong job count, is refused.
    let plan = out.join("plan.json");
    let good = std::fs::read_to_string(&plan).expect("plan");
    edit_json(&plan, |v| {
        let j0 = v["jobs"][0].clone();
        v["jobs"] = serde_json::Value::Array(vec![j0.clone(), j0.clone(), j0]);
        v["job_count"] = 3.into();
    });
    let before = l.hashes();
    let o = run(&os(&["sweep", "collect", s(&out)]));
    judge(
        "plan with a repeated job",
        &l,
        &before,
        &o,
        Expect::Error(&["plan.json", "once"]),
    );
    std::fs::write(&plan, &good).expect("write");
    edit_json(&plan, |v| v["job_count"] = 7.into());
    let before = l.hashes();
    let o = run(&os(&["sweep", "collect", s(&out)]));
    judge(
        "plan with a wrong count",
        &l,
        &before,
        &o,
        Expect::Error(&["plan.json", "job_count"]),
    );
}

#[test]
fn one_job_runs_once_at_a_time() {
    use std::os::unix::io::AsRawFd;
    let l = Layout::new();
    let sweep = sweep_yaml(&l, "samples: 2\n");
    let out = l.path("scene/out");
    std::fs::create_dir_all(out.join("jobs")).expect("mkdir");
    // This process stands for a first attempt still running: it holds job 0's lock.
    let lock = std::fs::File::create(out.join("jobs/000000.lock")).expect("lock");
    assert_eq!(
        unsafe { libc::flock(lock.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) },
        0
    );
    let before = l.hashes();
    let o = run(&os(&["sweep", "run", s(&sweep), "--index", "0", "--quiet"]));
    judge(
        "second attempt",
        &l,
        &before,
        &o,
        Expect::Error(&["job 0", "already running", "000000.lock"]),
    );
    assert!(report_only() || !out.join("jobs/000000.json").exists());
    // Another job runs meanwhile, and job 0 runs once the lock is released.
    let o = run(&os(&["sweep", "run", s(&sweep), "--index", "1", "--quiet"]));
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    drop(lock);
    let o = run(&os(&["sweep", "run", s(&sweep), "--index", "0", "--quiet"]));
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(out.join("jobs/000000.mcap").is_file());
}

// ---------------------------------------------------------------- large meshes, NaN frames

/// A Collada file whose node `n{depth}` instances `n{depth-1}` twice, down to `n0`, which
/// places an eight-triangle geometry (or nothing): 2^depth copies.
fn instancing_bomb(depth: usize, geometry: bool) -> String {
    let mut nodes = String::from(if geometry {
        r##"<node id="n0"><instance_geometry url="#g"/></node>"##
    } else {
        r##"<node id="n0"/>"##
    })
    .to_string();
    for k in 1..=depth {
        nodes.push_str(&format!(
            r##"<node id="n{k}"><instance_node url="#n{p}"/><instance_node url="#n{p}"/></node>"##,
            p = k - 1
        ));
    }
    format!(
        r##"<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <library_geometries><geometry id="g"><mesh>
    <source id="p"><float_array id="pa" count="9">0 0 0 0.1 0 0 0 0.1 0</float_array>
      <technique_common><accessor source="#pa" count="3" stride="3"/></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles count="8"><input semantic="VERTEX" source="#v" offset="0"/><p>{tris}</p></triangles>
  </mesh></geometry></library_geometries>
  <library_nodes>{nodes}</library_nodes>
  <library_visual_scenes><visual_scene id="s"><node id="top"><instance_node url="#n{depth}"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>"##,
        tris = "0 1 2 ".repeat(8)
    )
}

#[test]
fn meshes_are_bounded_after_instancing() {
    for (name, text, want) in [
        (
            "2^30 instanced triangles",
            instancing_bomb(30, true),
            "instance",
        ),
        (
            "2^30 empty node visits",
            instancing_bomb(30, false),
            "nodes",
        ),
    ] {
        let l = Layout::new();
        l.write("scene/pkg/meshes/bomb.dae", &text);
        let scene = l.robot("package://pkg/meshes/bomb.dae", "");
        let before = l.hashes();
        let o = check(&scene);
        judge(
            name,
            &l,
            &before,
            &o,
            Expect::Error(&["bomb.dae", "link `arm`", want]),
        );
    }
    // A binary STL of 2,000,001 triangles (100 MB, within the mesh file cap) is refused from
    // its header, before any triangle is built.
    let l = Layout::new();
    let stl = l.sparse("scene/pkg/meshes/big.stl", 84 + 50 * 2_000_001);
    {
        use std::io::{Seek, SeekFrom, Write};
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .open(&stl)
            .expect("open");
        f.seek(SeekFrom::Start(80)).expect("seek");
        f.write_all(&2_000_001u32.to_le_bytes()).expect("write");
    }
    let scene = l.robot("package://pkg/meshes/big.stl", "");
    let before = l.hashes();
    let o = check(&scene);
    judge(
        "2,000,001-triangle STL",
        &l,
        &before,
        &o,
        Expect::Error(&["big.stl", "2000001 triangles"]),
    );
}

#[test]
fn a_non_finite_cloth_frame_is_an_error_not_a_blank_picture() {
    use drape::ros::msg::{Marker, Point};
    let l = Layout::new();
    let bag = l.path("scene/nan.mcap");
    let mut w = BagWriter::create(&bag).expect("bag");
    let t = w
        .add_topic::<Marker>("/drape/mesh", Distro::Jazzy, None)
        .expect("topic");
    for k in 0..3u64 {
        let z = if k == 2 { f64::NAN } else { 1.0 };
        let p = |x: f64, y: f64| Point { x, y, z };
        let m = Marker {
            r#type: Marker::TRIANGLE_LIST,
            points: vec![p(0., 0.), p(0.2, 0.), p(0.2, 0.2)],
            ..Marker::default()
        };
        w.write(t, k * 33_333_333, &m).expect("write");
    }
    w.finish().expect("finish");
    for out in ["scene/nan.png", "scene/nan.gif"] {
        let out = l.path(out);
        let before = l.hashes();
        let o = run(&os(&["render", s(&bag), "--out", s(&out)]));
        judge(
            "NaN frame",
            &l,
            &before,
            &o,
            Expect::Error(&["nan.mcap", "0.067 s", "non-finite"]),
        );
        assert!(report_only() || !out.exists());
    }
    // Frames before it still render.
    let out = l.path("scene/first.png");
    let before = l.hashes();
    let o = run(&os(&["render", s(&bag), "--out", s(&out), "--at", "0"]));
    judge("finite frame of the same bag", &l, &before, &o, Expect::Ok);
}

// ---------------------------------------------------------------- size of what a scene builds

/// A scene of one garment whose panels are `panels` (YAML flow mappings), without seams, sewn
/// for no time.
fn garment_scene(edge_length: &str, panels: &[String]) -> String {
    let mut text = String::from(
        "name: NAMEXYZ\nduration: 0.04\neffects: [stretch, shear]\n\
         solver: { integrator: implicit, dt: 0.02 }\ngarments:\n  - name: shirt\n",
    );
    text += &format!("    edge_length: {edge_length}\n");
    text += "    sewing: { close_time: 0, max_time: 0.02 }\n    panels:\n";
    for p in panels {
        text += &format!("      - {p}\n");
    }
    text
}

/// A square panel of side `side` (m) named `name`.
fn square_panel(name: &str, side: f64) -> String {
    format!("{{ name: {name}, outline: [[0, 0], [{side}, 0], [{side}, {side}], [0, {side}]] }}")
}

/// Cloth that would take gigabytes (a grid, many panels, a long outline, self-contact on a cloth
/// far thinner than its thickness, massless vertices) is refused from the scene file, naming the
/// key, before anything is built.
#[test]
fn cloth_size_is_bounded_before_any_work() {
    let grid = |from: &str, to: &str| with(SCENE, from, to);
    scene_case(
        "2000x2000 grid",
        &grid("resolution: [4, 4]", "resolution: [2000, 2000]"),
        "cloths[0].grid.resolution",
    );
    // Two grids of 60,000 vertices: each under the cap, together over it.
    let two = format!(
        "{}  - name: second\n    grid: {{ size: [1, 1], resolution: [300, 200] }}\n",
        grid("resolution: [4, 4]", "resolution: [300, 200]")
    );
    scene_case(
        "two grids over the cap together",
        &two,
        "cloths[1].grid.resolution",
    );
    // Twelve 0.66 m panels at 1 cm edges, about 11,400 vertices each: the ninth passes the cap.
    let panels: Vec<String> = (0..12)
        .map(|k| square_panel(&format!("p{k}"), 0.66))
        .collect();
    scene_case(
        "12 panels over the cap together",
        &garment_scene("0.01", &panels),
        "garments[0].panels[8].outline",
    );
    let circle = |n: usize| {
        let pts: Vec<String> = (0..n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                format!("[{:.9}, {:.9}]", 0.1 * a.cos(), 0.1 * a.sin())
            })
            .collect();
        format!("{{ name: round, outline: [{}] }}", pts.join(", "))
    };
    scene_case(
        "outline of 20,000 points",
        &garment_scene("0.03", &[circle(20_000)]),
        "garments[0].panels[0].outline",
    );
    // Found while dressing (after validation): the message still starts with the file.
    let attach = with(
        &garment_scene("0.03", &[square_panel("p", 0.3)]),
        "    panels:",
        "    attach: [ { link: hand, point: [0, 0, 0], radius: 0.1 } ]\n    panels:",
    );
    scene_case(
        "garment attached without a robot",
        &attach,
        "garments[0].attach[0]",
    );
    scene_case(
        "garment edge_length 1e-9",
        &garment_scene("1e-9", &[square_panel("p", 0.3)]),
        "garments[0].edge_length",
    );
    let self_contact = format!("{SCENE}collision: {{ self_collision: true }}\n");
    scene_case(
        "1e-9 m cloth with self-collision",
        &with(&self_contact, "size: [0.2, 0.2]", "size: [1e-9, 1e-9]"),
        "cloths[0].grid.size[0]",
    );
    scene_case(
        "grid.size 1e-300",
        &grid("size: [0.2, 0.2]", "size: [1e-300, 0.2]"),
        "cloths[0].grid.size[0]",
    );
    scene_case(
        "density 1e-310",
        &grid("pins:", "material: { density: 1e-310 }\n    pins:"),
        "cloths[0].material.density",
    );
    // A 0.1 mm cloth (edges above the floor) with the default 5 mm thickness: self-contact
    // would hold every vertex against every other.
    scene_case(
        "thickness 500 edges with self-collision",
        &with(&self_contact, "size: [0.2, 0.2]", "size: [3e-5, 3e-5]"),
        "cloths[0].material.thickness",
    );
    scene_case(
        "obstacle mesh scale 1e-320",
        &format!("{SCENE}obstacles:\n  - {{ name: m, shape: {{ type: mesh, path: pkg/meshes/m.stl, scale: [1, 1e-320, 1] }} }}\n"),
        "obstacles[0].shape.scale[1]",
    );
}

/// Inside the bounds: a cloth at the edge floor with a thinner thickness self-collides, and a
/// panel with a few hundred outline points meshes, both within the budget of any case.
#[test]
fn small_cloth_and_detailed_outlines_within_the_bounds_run() {
    let l = Layout::new();
    let floor = format!(
        "{}collision: {{ self_collision: true }}\n",
        with(
            &with(SCENE, "size: [0.2, 0.2]", "size: [3e-5, 3e-5]"),
            "pins:",
            "material: { thickness: 1e-5 }\n    pins:"
        )
    );
    let scene = l.scene(&floor);
    let before = l.hashes();
    judge(
        "cloth at the edge floor",
        &l,
        &before,
        &check(&scene),
        Expect::Ok,
    );
    let o = record(&scene, &l.path("scene/out.mcap"), &[]);
    judge(
        "cloth at the edge floor, recorded",
        &l,
        &before,
        &o,
        Expect::Ok,
    );
    let pts: Vec<String> = (0..300)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 300.0;
            format!("[{:.9}, {:.9}]", 0.1 * a.cos(), 0.1 * a.sin())
        })
        .collect();
    let round = format!("{{ name: round, outline: [{}] }}", pts.join(", "));
    let scene = l.scene(&garment_scene("0.02", &[round]));
    let before = l.hashes();
    judge(
        "outline of 300 points",
        &l,
        &before,
        &check(&scene),
        Expect::Ok,
    );
}

/// The largest grid a scene may have, with every effect and self-collision, is checked and a
/// frame of it recorded within the budget and the memory of a large input.
#[test]
fn a_grid_at_the_vertex_cap_runs_in_the_memory_of_a_large_input() {
    let l = Layout::new();
    let text = with(
        &with(
            &with(
                SCENE,
                "effects: [gravity, stretch, shear]",
                "effects: [gravity, stretch, shear, skip_one, bending, twist, damping]",
            ),
            "size: [0.2, 0.2], resolution: [4, 4]",
            "size: [1.0, 1.0], resolution: [316, 316]",
        ),
        "pins:",
        "material: { skip_one: 10, twist: 0.0001, thickness: 0.0007 }\n    pins:",
    );
    let text = with(&text, "duration: 0.1", "duration: 0.02");
    let scene = l.scene(&format!("{text}collision: {{ self_collision: true }}\n"));
    let out = l.path("scene/out.mcap");
    for (name, args) in [
        ("check at the cap", os(&["check", "--scene", s(&scene)])),
        (
            "record at the cap",
            os(&["record", "--quiet", "--scene", s(&scene), "--out", s(&out)]),
        ),
    ] {
        let before = l.hashes();
        let a: Vec<&std::ffi::OsStr> = args.iter().map(|x| x.as_os_str()).collect();
        let o = drape_large(&a);
        judge_within(name, &l, &before, &o, Expect::Ok, LARGE_BUDGET);
    }
    assert!(report_only() || out.is_file());
}
