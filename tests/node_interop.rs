//! Interop with a different DDS implementation: `drape node` (RustDDS) and a Python peer on
//! Eclipse Cyclone DDS (tests/py/node_interop.py) in one private network namespace. The peer
//! drives the robot with /joint_states and checks ~/mesh and ~/points rates, the cloth
//! following the arm, ~/obstacles, /diagnostics, a bad joint state warned about on /rosout and
//! counted, and ~/reset. The node runs on ROS_DOMAIN_ID=7 with ROS_LOCALHOST_ONLY=1. Then the node gets SIGTERM and must exit
//! cleanly and quickly, without error lines.
//!
//! Skipped (loudly) only when `cyclonedds` cannot be imported and DRAPE_REQUIRE_INTEROP is
//! unset; `.ci/run` installs it.
#![cfg(feature = "ros")]

#[path = "support/netns.rs"]
mod netns;

use std::io::Read;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn cyclonedds_available() -> bool {
    Command::new("python3")
        .args(["-c", "import cyclonedds.domain"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

#[test]
fn cyclone_python_peer_drives_the_node() {
    if std::env::var_os(netns::ENV).is_none() && !cyclonedds_available() {
        if std::env::var_os("DRAPE_REQUIRE_INTEROP").is_some() {
            panic!("DRAPE_REQUIRE_INTEROP is set but python3 cannot import cyclonedds");
        }
        eprintln!(
            "\n*** SKIPPED cyclone_python_peer_drives_the_node: python3 cannot import cyclonedds \
             (pip install -r tests/py/requirements.txt) ***\n"
        );
        return;
    }
    if !netns::enter("cyclone_python_peer_drives_the_node") {
        return;
    }
    let root = env!("CARGO_MANIFEST_DIR");
    let mut node = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(["node", "--ros-args", "--params-file"])
        .arg(format!("{root}/config/node.yaml"))
        .args(["-p", "service_mapping:=cyclone", "-p", "publish_rate:=20.0"])
        .env("ROS_DISTRO", "jazzy")
        // Exercise the networking conventions: a non-default domain, loopback only.
        .env("ROS_DOMAIN_ID", "7")
        .env("ROS_LOCALHOST_ONLY", "1")
        .env("RUST_LOG", "warn")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start drape node");
    let mut stderr = node.stderr.take().expect("node stderr");
    let log = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stderr.read_to_string(&mut s);
        s
    });
    let py = Command::new("python3")
        .arg(format!("{root}/tests/py/node_interop.py"))
        .args(["--rate", "20", "--seconds", "4"])
        .env("ROS_DOMAIN_ID", "7")
        .status();
    let stop_at = Instant::now();
    let _ = Command::new("kill")
        .args(["-TERM", &node.id().to_string()])
        .status();
    let status = loop {
        if let Some(s) = node.try_wait().expect("wait for node") {
            break s;
        }
        if stop_at.elapsed() > Duration::from_secs(10) {
            let _ = node.kill();
            panic!("node ignored SIGTERM for 10 s");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let shutdown = stop_at.elapsed();
    let log = log.join().unwrap_or_default();
    eprintln!("node stderr:\n{log}\nnode exited {status} {shutdown:?} after SIGTERM");
    let py = py.expect("run python3 tests/py/node_interop.py");
    assert!(
        py.success(),
        "the Cyclone DDS peer reported failures ({py})"
    );
    assert!(status.success(), "node exit status {status}");
    assert!(
        shutdown < Duration::from_secs(3),
        "shutdown took {shutdown:?}"
    );
    let errors: Vec<&str> = log.lines().filter(|l| l.contains("ERROR")).collect();
    assert!(errors.is_empty(), "error lines from the node: {errors:?}");
}
