//! A short run of every fuzz target (about 3 s each, two at a time, each
//! input in a worker process with the time and memory bounds): any crash
//! fails, with the crashing input printed as hex and saved.

use std::sync::Mutex;
use std::time::Duration;

use sornav_fuzz::{run, targets};

#[test]
fn every_target_runs_clean_for_a_few_seconds() {
    let crashes_dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-crashes");
    let options = run::Options {
        duration: Duration::from_secs(3),
        seed: 21,
        worker_exe: Some(env!("CARGO_BIN_EXE_sornav-fuzz").into()),
        crashes: Some(crashes_dir.clone()),
        ..run::Options::default()
    };
    let queue = Mutex::new(targets::all());
    let reports = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| {
                loop {
                    let Some(t) = queue.lock().unwrap().pop() else {
                        return;
                    };
                    let report = run::run(&t, &options).expect("the runner works");
                    reports.lock().unwrap().push(report);
                }
            });
        }
    });
    let reports = reports.into_inner().unwrap();
    assert_eq!(reports.len(), targets::all().len());
    let mut failed = Vec::new();
    for r in &reports {
        println!(
            "{:16} {:>8} inputs {:>9.0} /s  {} crashes  corpus {}",
            r.target, r.inputs, r.inputs_per_s, r.crashes, r.corpus
        );
        assert!(
            r.inputs >= r.seeds as u64,
            "{}: not even the seeds ran",
            r.target
        );
        for c in &r.crash_list {
            println!(
                "CRASH {} {:?}: {}\n  saved: {:?}\n  input: {}",
                r.target, c.kind, c.message, c.file, c.hex
            );
            failed.push(r.target.clone());
        }
    }
    assert!(
        failed.is_empty(),
        "crashes in {failed:?} (saved under {})",
        crashes_dir.display()
    );
}
