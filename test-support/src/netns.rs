//! Running DDS tests and dry runs inside a private network namespace.
//!
//! DDS discovers peers by multicast on every interface it is allowed to use.
//! Besides restricting participants to loopback
//! (`sornav_platform_scout::node::loopback_context`), every test
//! that starts a participant runs inside a fresh network namespace whose
//! only interface is `lo`, so nothing can leave the machine even if the
//! restriction had a bug:
//!
//! ```no_run
//! #[test]
//! fn talks_over_dds() {
//!     if !sornav_test_support::netns::isolate("talks_over_dds") {
//!         return; // the isolated child ran (and passed), or isolation is unavailable
//!     }
//!     // Here: inside `unshare --net` with only `lo` up.
//! }
//! ```
//!
//! [`isolate`] re-executes the current test binary as
//! `unshare --net sh -c 'ip link set lo up && exec "$0" "$@"' <binary> --exact <test> --nocapture`
//! with [`CHILD_ENV`] set, checks that the child ran exactly that test and
//! passed, and returns `false`; in the child it checks
//! `/proc/self/net/dev` lists only `lo` and returns `true`. When namespaces
//! are unavailable (no `unshare`, not permitted) the test is skipped with a
//! message, and fails when `CI` is `true`.

use std::process::Command;

use crate::in_ci;

/// Set to `1` in the re-executed child.
pub const CHILD_ENV: &str = "SORNAV_NETNS_CHILD";

/// The network interfaces of this process's namespace (from
/// `/proc/self/net/dev`; `None` when it cannot be read).
pub fn interfaces() -> Option<Vec<String>> {
    let text = std::fs::read_to_string("/proc/self/net/dev").ok()?;
    Some(
        text.lines()
            .skip(2)
            .filter_map(|l| l.split(':').next())
            .map(|n| n.trim().to_owned())
            .filter(|n| !n.is_empty())
            .collect(),
    )
}

/// Whether this process sees no interface but `lo`.
pub fn only_loopback() -> bool {
    interfaces().is_some_and(|i| i.iter().all(|n| n == "lo"))
}

/// Whether `unshare --net` works here (root or user namespaces).
pub fn namespaces_available() -> bool {
    Command::new("unshare")
        .args(["--net", "sh", "-c", "ip link set lo up"])
        .output()
        .is_ok_and(|o| o.status.success())
}

fn skip(reason: &str) -> bool {
    if in_ci() {
        panic!(
            "cannot isolate a DDS test in a network namespace: {reason} (CI=true: failing, not skipping)"
        );
    }
    eprintln!("SKIPPED: DDS test needs a private network namespace: {reason}");
    false
}

/// Runs the calling test in a private network namespace; see the [module
/// docs](self). `test` is the test's name as libtest filters it (the path
/// inside the test binary, e.g. `waypoint_over_loopback` or
/// `tests::waypoint_over_loopback`).
///
/// Returns `true` in the isolated child (run the test body), `false` in the
/// parent after the child passed, or when skipped.
///
/// # Panics
/// When the child fails or did not run exactly one test, when the child
/// sees an interface other than `lo`, or when isolation is unavailable and
/// `CI` is true.
pub fn isolate(test: &str) -> bool {
    if std::env::var(CHILD_ENV).as_deref() == Ok("1") {
        assert!(
            only_loopback(),
            "refusing to start DDS: this namespace has interfaces {:?} besides lo",
            interfaces()
        );
        return true;
    }
    if !namespaces_available() {
        return skip("`unshare --net` is unavailable or not permitted");
    }
    let exe = match std::env::current_exe() {
        Ok(e) => e,
        Err(e) => return skip(&format!("cannot locate the test binary: {e}")),
    };
    let output = Command::new("unshare")
        .arg("--net")
        .arg("sh")
        .arg("-c")
        .arg(r#"ip link set lo up && exec "$0" "$@""#)
        .arg(&exe)
        .args(["--exact", test, "--nocapture", "--test-threads=1"])
        .env(CHILD_ENV, "1")
        .output()
        .unwrap_or_else(|e| panic!("cannot run {}: {e}", exe.display()));
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    print!("{stdout}");
    eprint!("{stderr}");
    assert!(
        output.status.success(),
        "isolated run of `{test}` failed ({})",
        output.status
    );
    assert!(
        stdout.contains("test result: ok. 1 passed"),
        "isolated run of `{test}` did not run exactly that test"
    );
    false
}
