//! Runs DDS tests inside a private network namespace that holds only `lo`, so no discovery
//! multicast can leave through a real interface (`ip` from iproute2, as root).
//!
//! A test calls [`enter`] first: outside a namespace it creates `drape-<pid>-<n>`, re-runs
//! just this test (`<test exe> --exact NAME`) inside it, deletes the namespace (also when the
//! child fails) and reports the child's result; inside, it checks that `lo` is the only
//! interface and lets the test body run.

#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Set in the child to the namespace it runs in.
pub const ENV: &str = "DRAPE_TEST_NETNS";

/// A network namespace with only `lo` (up, multicast on), deleted on drop.
pub struct Netns {
    name: String,
}

fn ip(args: &[&str]) -> Result<(), String> {
    let out = Command::new("ip")
        .args(args)
        .output()
        .map_err(|e| format!("cannot run `ip` (install iproute2): {e}"))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "`ip {}` failed: {} (DDS tests need root to create a network namespace)",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

impl Netns {
    pub fn create() -> Result<Netns, String> {
        static N: AtomicUsize = AtomicUsize::new(0);
        let name = format!(
            "drape-{}-{}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        );
        ip(&["netns", "add", &name])?;
        let ns = Netns { name };
        ip(&["-n", &ns.name, "link", "set", "lo", "up"])?;
        ip(&["-n", &ns.name, "link", "set", "lo", "multicast", "on"])?;
        Ok(ns)
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// `program` run inside the namespace.
    pub fn command(&self, program: impl AsRef<Path>) -> Command {
        let mut c = Command::new("ip");
        c.args(["netns", "exec", &self.name]).arg(program.as_ref());
        c
    }
}

impl Drop for Netns {
    fn drop(&mut self) {
        if let Err(e) = ip(&["netns", "del", &self.name]) {
            eprintln!("warning: {e}");
        }
    }
}

/// Interfaces this process sees (from /sys/class/net, which `ip netns exec` remounts).
pub fn interfaces() -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir("/sys/class/net")
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// Returns true when the caller is inside a private namespace and should run its body; false
/// after running `test` (the test function's name) in a fresh namespace, panicking if it failed.
pub fn enter(test: &str) -> bool {
    if std::env::var_os(ENV).is_some() {
        let ifs = interfaces();
        assert_eq!(
            ifs,
            ["lo"],
            "refusing to start DDS: this namespace has interfaces {ifs:?}, not only lo"
        );
        return true;
    }
    let ns = Netns::create().unwrap_or_else(|e| panic!("{test}: {e}"));
    let exe = std::env::current_exe().expect("test executable path");
    let status = ns
        .command(&exe)
        .args([test, "--exact", "--nocapture", "--test-threads=1"])
        .env(ENV, ns.name())
        .stdin(Stdio::null())
        .status()
        .unwrap_or_else(|e| panic!("{test}: cannot run in netns {}: {e}", ns.name()));
    drop(ns);
    assert!(
        status.success(),
        "{test} failed inside its network namespace ({status})"
    );
    false
}
