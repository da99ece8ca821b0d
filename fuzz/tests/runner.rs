//! The runner itself: panics, hangs, failed allocations, resident memory
//! over the bound and aborts in a worker
//! process are crashes, saved, and the worker is restarted.

use std::time::Duration;

use sornav_fuzz::run::{self, CrashKind};
use sornav_fuzz::targets;

fn crash_kinds(name: &str) -> (run::Report, Vec<CrashKind>) {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-selftest");
    let target = targets::find(name).unwrap();
    let options = run::Options {
        duration: Duration::from_millis(1500),
        timeout: Duration::from_millis(1000),
        memory_mb: 128,
        worker_exe: Some(env!("CARGO_BIN_EXE_sornav-fuzz").into()),
        crashes: Some(dir),
        ..run::Options::default()
    };
    let report = run::run(&target, &options).unwrap();
    let kinds = report.crash_list.iter().map(|c| c.kind).collect();
    (report, kinds)
}

#[test]
fn worker_crashes_are_caught_saved_and_the_worker_restarts() {
    let (r, kinds) = crash_kinds("selftest-panic");
    assert_eq!(kinds, [CrashKind::Panic], "{r:?}");
    assert!(r.crash_list[0].message.contains("self-test panic"), "{r:?}");
    assert_eq!(r.workers, 1, "a caught panic keeps the worker");
    assert!(r.crash_list[0].file.as_ref().is_some_and(|f| f.is_file()));

    let (r, kinds) = crash_kinds("selftest-hang");
    assert!(kinds.contains(&CrashKind::Timeout), "{r:?}");
    assert!(r.workers >= 2, "{r:?}");
    assert!(r.inputs > r.crashes, "inputs after the hang ran: {r:?}");

    let (r, kinds) = crash_kinds("selftest-rss");
    assert_eq!(kinds, [CrashKind::Memory], "{r:?}");
    assert!(
        r.crash_list[0].message.contains("over the 128 MiB bound"),
        "{r:?}"
    );
    assert!(r.workers >= 2, "{r:?}");

    for name in ["selftest-oom", "selftest-abort"] {
        let (r, kinds) = crash_kinds(name);
        assert!(kinds.contains(&CrashKind::Died), "{name}: {r:?}");
        assert!(r.workers >= 2, "{name}: {r:?}");
        assert_eq!(r.crash_list[0].hex, "21", "{name}: the seed `!` crashed");
    }
}
