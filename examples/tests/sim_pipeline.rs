//! The simulator pipeline end to end: the full SOR-Nav agent on procedural
//! houses through platform-sim's ObjectNav protocol, and the evaluation
//! harness (outputs, resume, shards and merge).

use std::path::{Path, PathBuf};

use sornav_examples::adapter::{AdapterConfig, ConfigFactory, SornavPolicy};
use sornav_examples::harness::{self, EvalConfig, RunOptions};
use sornav_platform_sim::episodes::{GeneratorConfig, generate_episodes};
use sornav_platform_sim::procedural::ProceduralConfig;
use sornav_platform_sim::{
    CameraConfig, Outcome, RunConfig, Scene, SimConfig, Simulator, run_episode,
};

mod common;

fn small_camera() -> CameraConfig {
    CameraConfig {
        width: 160,
        height: 120,
        ..CameraConfig::default()
    }
}

fn one_floor_house(seed: u64) -> Simulator {
    let scene = Scene::procedural(
        seed,
        &ProceduralConfig {
            floors: Some(1),
            ..ProceduralConfig::default()
        },
    )
    .unwrap();
    Simulator::new(
        scene,
        SimConfig {
            camera: small_camera(),
            ..SimConfig::default()
        },
    )
    .unwrap()
}

/// The full agent finds its targets in a small one-floor house within the
/// action budget, and every decision log follows Algorithm 1's ordering.
#[test]
fn full_agent_succeeds_in_a_small_procedural_house() {
    let sim = one_floor_house(3);
    let episodes = generate_episodes(
        &sim,
        &GeneratorConfig {
            episodes_per_category: 1,
            categories: vec!["bed".into(), "toilet".into(), "chair".into()],
            seed: 5,
            ..GeneratorConfig::default()
        },
    )
    .unwrap();
    assert!(episodes.len() >= 2, "the house has beds, toilets or chairs");
    let factory = ConfigFactory {
        config: sornav_examples::adapter::sim_agent_config(),
        policy: None,
    };
    let mut policy = SornavPolicy::new(&factory, AdapterConfig::default());
    let interval = sornav_examples::adapter::sim_agent_config()
        .supervisor
        .interval_s;
    let mut successes = 0;
    for e in &episodes {
        let r = run_episode(&sim, e, &mut policy, &RunConfig::default()).unwrap();
        let trace = policy.take_trace();
        assert!(r.actions <= 500);
        assert!(trace.decisions.decisions() > 0);
        trace
            .decisions
            .check_algorithm1(interval)
            .unwrap_or_else(|v| panic!("episode {}: {v}", e.episode_id));
        if r.success {
            successes += 1;
            assert_eq!(trace.agent_end, "stop");
            assert!(r.spl > 0.0 && r.spl <= 1.0);
        }
        // STOP is only ever called on a confirmed target or an exhausted search.
        if r.outcome != Outcome::StepLimit {
            assert!(
                matches!(trace.agent_end.as_str(), "stop" | "exhausted"),
                "{}",
                trace.agent_end
            );
        }
    }
    assert_eq!(
        successes,
        episodes.len(),
        "every same-floor target is found"
    );
}

fn tiny_eval(variants: &[&str]) -> EvalConfig {
    EvalConfig {
        seed: 3,
        maps: 1,
        ..common::small_eval(
            &[40, 41],
            2,
            &["bed", "chair", "toilet"],
            variants,
            150,
            None,
        )
    }
}

fn temp_dir(tag: &str) -> PathBuf {
    common::temp_dir("sim-test", tag)
}

fn options(out: &Path, shard: Option<(usize, usize)>) -> RunOptions {
    common::options(out, 2, shard, false)
}

/// Deterministic part of a record (no timings).
fn outcome_of(
    r: &sornav_examples::record::EpisodeRecord,
) -> (String, String, String, bool, u64, usize) {
    (
        r.variant.clone(),
        r.result.scene_id.clone(),
        r.result.episode_id.clone(),
        r.result.success,
        (r.result.spl * 1e9).round() as u64,
        r.result.actions,
    )
}

/// A run writes the contract's outputs; a second run resumes (runs
/// nothing); two shards merged equal the full run; a different evaluation
/// in the same directory is refused.
#[test]
fn harness_outputs_resume_shards_and_merge() {
    let config = tiny_eval(&["sornav", "oracle"]);
    let full = temp_dir("full");
    let outcome = harness::run(&config, &options(&full, None)).unwrap();
    assert!(outcome.items >= 4 && outcome.ran == outcome.items);
    for f in [
        "summary.json",
        "episodes.jsonl",
        "report.md",
        "run.json",
        "figures/metrics.png",
        "figures/success_by_distance.png",
        "figures/failures.png",
        "figures/success_by_floors.png",
    ] {
        assert!(full.join(f).is_file(), "{f} missing");
    }
    assert!(
        std::fs::read_dir(full.join("maps")).unwrap().count() >= 1,
        "top-down maps"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(full.join("summary.json")).unwrap()).unwrap();
    for key in [
        "variant",
        "episodes",
        "success_rate",
        "spl",
        "soft_spl",
        "success_rate_1m",
        "dtg_m",
        "step_limit_rate",
        "timeout_rate",
        "false_stop_rate",
        "mean_actions",
        "wall_s",
        "episodes_per_s",
        "decision_ms_p50",
        "decision_ms_p99",
        "frame_ms_p50",
    ] {
        assert!(summary.get(key).is_some(), "summary.json lacks {key}");
    }
    for v in summary["variants"].as_array().unwrap() {
        for rate in [
            "success_rate",
            "spl",
            "step_limit_rate",
            "timeout_rate",
            "false_stop_rate",
        ] {
            let x = v[rate].as_f64().unwrap();
            assert!((0.0..=1.0).contains(&x), "{rate} = {x}");
        }
    }
    assert_eq!(summary["variants"][1]["variant"], "oracle");
    assert_eq!(summary["variants"][1]["success_rate"], 1.0);
    let records = harness::read_records(&full.join("episodes.jsonl")).unwrap();
    assert_eq!(records.len(), outcome.items);
    assert!(
        records
            .iter()
            .filter(|r| r.variant == "sornav")
            .all(|r| r.decisions.decisions() > 0)
    );

    // Resume: nothing left to run.
    let again = harness::run(&config, &options(&full, None)).unwrap();
    assert_eq!((again.ran, again.skipped), (0, outcome.items));

    // Shards + merge reproduce the full run.
    let (s0, s1, merged) = (temp_dir("s0"), temp_dir("s1"), temp_dir("merged"));
    let a = harness::run(&config, &options(&s0, Some((0, 2)))).unwrap();
    let b = harness::run(&config, &options(&s1, Some((1, 2)))).unwrap();
    assert_eq!(a.ran + b.ran, outcome.items);
    harness::merge(&merged, &[s0.clone(), s1.clone()]).unwrap();
    let mut want: Vec<_> = records.iter().map(outcome_of).collect();
    let mut got: Vec<_> = harness::read_records(&merged.join("episodes.jsonl"))
        .unwrap()
        .iter()
        .map(outcome_of)
        .collect();
    want.sort();
    got.sort();
    assert_eq!(got, want, "the agent and the simulator are deterministic");
    assert!(merged.join("report.md").is_file());

    // A different evaluation is refused in the same directory.
    let other = tiny_eval(&["oracle"]);
    assert!(matches!(
        harness::run(&other, &options(&full, None)),
        Err(harness::HarnessError::DifferentRun(_))
    ));
    // ... and shards of different evaluations are not merged.
    let o = temp_dir("other");
    harness::run(&other, &options(&o, None)).unwrap();
    assert!(matches!(
        harness::merge(&temp_dir("bad-merge"), &[s0.clone(), o.clone()]),
        Err(harness::HarnessError::DifferentRun(_))
    ));
    for d in [full, s0, s1, merged, o] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// A truncated last line (an interrupted run) is dropped; a malformed line
/// in the middle is an error naming the line.
#[test]
fn episode_log_damage_is_handled() {
    let config = tiny_eval(&["oracle"]);
    let dir = temp_dir("damage");
    harness::run(&config, &options(&dir, None)).unwrap();
    let path = dir.join("episodes.jsonl");
    let text = std::fs::read_to_string(&path).unwrap();
    let n = text.lines().count();
    std::fs::write(&path, format!("{text}{{\"variant\":\"ora")).unwrap();
    assert_eq!(harness::read_records(&path).unwrap().len(), n);
    // Resuming after an interrupted write: the partial line is cut off
    // before new records are appended, and every episode ends up recorded
    // once. A complete last record that lost only its newline is kept.
    let first = text.lines().next().unwrap();
    std::fs::write(&path, format!("{first}\n{{\"variant\":\"ora")).unwrap();
    harness::run(&config, &options(&dir, None)).unwrap();
    assert_eq!(harness::read_records(&path).unwrap().len(), n);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.ends_with('\n') && !text.contains("\"ora\n"));
    std::fs::write(&path, first).unwrap();
    harness::run(&config, &options(&dir, None)).unwrap();
    assert_eq!(harness::read_records(&path).unwrap().len(), n);
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, format!("not json\n{text}")).unwrap();
    match harness::read_records(&path) {
        Err(harness::HarnessError::Malformed { line, .. }) => assert_eq!(line, 1),
        other => panic!("expected a malformed-line error, got {other:?}"),
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// Invalid settings are typed errors, not panics.
#[test]
fn invalid_settings_are_refused() {
    let mut c = tiny_eval(&["sornav"]);
    c.variants = vec!["best-method".into()];
    assert!(matches!(
        c.validate(),
        Err(harness::HarnessError::Config(_))
    ));
    let mut c = tiny_eval(&["sornav", "sornav"]);
    assert!(c.validate().is_err());
    c = tiny_eval(&["sornav"]);
    c.scenes.clear();
    assert!(c.validate().is_err());
    c = tiny_eval(&["sornav"]);
    c.camera.width = 0;
    assert!(c.validate().is_err());
    c = tiny_eval(&["sornav"]);
    c.agent.gate.n_obs = 0;
    assert!(c.validate().is_err());
    let dir = temp_dir("shard");
    assert!(harness::run(&tiny_eval(&["oracle"]), &options(&dir, Some((2, 2)))).is_err());
    let _ = std::fs::remove_dir_all(dir);
}

/// The binary: bad arguments exit with status 2 and a message; `--help`
/// documents the options the issue names.
#[test]
fn cli_arguments() {
    let exe = env!("CARGO_BIN_EXE_sornav-sim");
    let help = std::process::Command::new(exe)
        .arg("--help")
        .output()
        .unwrap();
    assert!(help.status.success());
    let text = String::from_utf8_lossy(&help.stdout);
    for flag in [
        "--scenes",
        "--models",
        "--episodes-per-scene",
        "--episodes",
        "--categories",
        "--variants",
        "--seed",
        "--jobs",
        "--out",
        "--width",
        "--height",
        "--llm",
        "--llm-model",
        "--shard",
        "merge",
    ] {
        assert!(text.contains(flag), "--help lacks {flag}");
    }
    for bad in [
        vec!["--variants", "magic"],
        vec!["--shard", "3/2"],
        vec!["--scenes", "procedural:zero"],
        vec!["--llm-replay", "x.jsonl"],
        // issue 21: rules under which nothing runs, and thread counts that
        // never progressed
        vec!["--max-actions", "0"],
        vec!["--wall-clock", "0"],
        vec!["--wall-clock", "nan"],
        vec!["--jobs", "100000"],
        vec!["--jobs", "0"],
    ] {
        let out = std::process::Command::new(exe)
            .args(&bad)
            .args(["--out", "/nonexistent-sornav-dir/x"])
            .output()
            .unwrap();
        assert_eq!(
            out.status.code(),
            Some(2),
            "{bad:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(!out.stderr.is_empty());
    }
}

/// The "Failure analysis" section of a report (up to the next section).
fn failure_section(dir: &Path) -> String {
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    let start = report
        .find("## Failure analysis")
        .expect("report.md has a Failure analysis section");
    let rest = &report[start..];
    let end = rest[2..].find("\n## ").map_or(rest.len(), |e| e + 2);
    rest[..end].to_owned()
}

/// With a budget too small to succeed, every episode fails: the report's
/// failure analysis shows at most three maps per class, every map it links
/// exists, and the examples are the same whatever the number of jobs and
/// after shards are merged.
#[test]
fn failure_analysis_is_deterministic_across_jobs_and_merge() {
    let config = EvalConfig {
        seed: 3,
        failure_maps: 3,
        ..common::small_eval(
            &[40, 41, 42],
            2,
            &["bed", "chair", "toilet"],
            &["sornav"],
            20,
            None,
        )
    };
    let one = temp_dir("fail-jobs1");
    let two = temp_dir("fail-jobs2");
    harness::run(&config, &common::options(&one, 1, None, false)).unwrap();
    harness::run(&config, &common::options(&two, 2, None, false)).unwrap();
    let (s0, s1, merged) = (
        temp_dir("fail-s0"),
        temp_dir("fail-s1"),
        temp_dir("fail-merged"),
    );
    harness::run(&config, &common::options(&s0, 2, Some((0, 2)), false)).unwrap();
    harness::run(&config, &common::options(&s1, 2, Some((1, 2)), false)).unwrap();
    harness::merge(&merged, &[s0.clone(), s1.clone()]).unwrap();

    let records = harness::read_records(&one.join("episodes.jsonl")).unwrap();
    let failures = records.iter().filter(|r| !r.result.success).count();
    assert!(failures > 3, "{failures} failures: the budget forces them");
    assert_eq!(
        std::fs::read_dir(one.join("maps/failures"))
            .unwrap()
            .count(),
        failures,
        "one map per failed episode"
    );
    let section = failure_section(&one);
    // A resumed run (nothing left to run) writes the same section.
    harness::run(&config, &common::options(&one, 2, None, false)).unwrap();
    for dir in [&one, &two, &merged] {
        let s = failure_section(dir);
        assert_eq!(s, section, "{}", dir.display());
        for class in s.split("\n#### ").skip(1) {
            let links: Vec<&str> = class
                .split("](")
                .skip(1)
                .map(|l| &l[..l.find(')').unwrap()])
                .collect();
            assert!(!links.is_empty() && links.len() <= 3, "{class}");
            for l in links {
                assert!(l.starts_with("maps/failures/"), "{l}");
                assert!(dir.join(l).is_file(), "{l} missing in {}", dir.display());
            }
        }
    }
    // Six failures in three scenes of one class (at most two classes):
    // some class shows three examples, the first of each scene.
    assert!(
        section.matches("![maps/failures/").count() >= 3,
        "{section}"
    );
    // Off: no failure maps, no section.
    let off = temp_dir("fail-off");
    let config_off = EvalConfig {
        failure_maps: 0,
        ..config
    };
    harness::run(&config_off, &common::options(&off, 2, None, false)).unwrap();
    assert!(!off.join("maps/failures").exists());
    let report = std::fs::read_to_string(off.join("report.md")).unwrap();
    assert!(!report.contains("## Failure analysis"));
    for d in [one, two, s0, s1, merged, off] {
        let _ = std::fs::remove_dir_all(d);
    }
}
