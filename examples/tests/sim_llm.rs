//! `sornav-sim --llm`: the LLM context policy against a loopback
//! OpenAI-compatible server (std `TcpListener` on 127.0.0.1), recorded, and
//! re-run offline from the recording with identical results.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use serde_json::{Value, json};
use sornav::supervisor::{LlmConfig, LlmLatency};
use sornav_examples::harness::{self, EvalConfig, LlmSettings};
use sornav_test_support::chat_server;

mod common;

/// The model: relocate to the first candidate offered, else keep exploring.
fn answer(request: &Value) -> String {
    let snapshot: Option<Value> = request["messages"]
        .as_array()
        .and_then(|m| m.last())
        .and_then(|m| m["content"].as_str())
        .and_then(|c| serde_json::from_str(c).ok());
    let first = snapshot
        .as_ref()
        .and_then(|s| s["candidates"].as_array())
        .and_then(|c| c.first())
        .and_then(|c| c["id"].as_u64());
    let content = match first {
        Some(id) => json!({"action": "relocate_cluster", "cluster_id": id, "reason": "test model"}),
        None => json!({"action": "continue_explore", "cluster_id": null, "reason": "none"}),
    };
    chat_server::completion(&content.to_string())
}

fn serve() -> (String, Arc<AtomicUsize>) {
    // A model that takes a little while: asynchronous answers arrive some
    // steps after their question.
    let server = chat_server::serve(Arc::new(|body| {
        (200, answer(body), Duration::from_millis(40))
    }));
    (server.base_url, server.hits)
}

fn eval(llm: LlmSettings) -> EvalConfig {
    EvalConfig {
        seed: 1,
        ..common::small_eval(
            &[52],
            3,
            &["toilet", "bed", "tv_monitor"],
            &["sornav"],
            120,
            Some(llm),
        )
    }
}

fn dir(tag: &str) -> PathBuf {
    common::temp_dir("llm", tag)
}

#[test]
fn llm_policy_records_and_replays_bit_for_bit() {
    let (url, hits) = serve();
    let recording = dir("rec").with_extension("jsonl");
    let config = LlmConfig {
        base_url: url.clone(),
        model: "fake".into(),
        api_key_env: None,
        min_interval_s: 2.0,
        // Asynchronous (the default), the latency in simulated time.
        latency: LlmLatency::Measured,
        ..LlmConfig::default()
    };
    assert!(config.asynchronous);
    let live = eval(LlmSettings {
        config: config.clone(),
        record: Some(recording.clone()),
        replay: None,
    });
    let out_live = dir("live");
    let options = |out: &PathBuf| common::options(out, 1, None, true);
    harness::run(&live, &options(&out_live)).unwrap();
    let asked = hits.load(Ordering::SeqCst);
    assert!(asked > 0, "the policy asked the model");
    let recorded = std::fs::read_to_string(&recording).unwrap();
    assert_eq!(
        recorded.lines().count(),
        asked,
        "every exchange is recorded"
    );
    let live_records = harness::read_records(&out_live.join("episodes.jsonl")).unwrap();
    let relocations: usize = live_records.iter().map(|r| r.relocations.len()).sum();
    assert!(relocations > 0, "the model's relocations are executed");
    assert!(live_records.iter().any(|r| {
        r.decisions
            .runs()
            .iter()
            .any(|d| d.action == "relocate" && d.reason.contains("test model"))
    }));

    // Offline: the same evaluation from the recording, no network.
    let replay = eval(LlmSettings {
        config,
        record: None,
        replay: Some(recording.clone()),
    });
    let out_replay = dir("replay");
    harness::run(&replay, &options(&out_replay)).unwrap();
    assert_eq!(
        hits.load(Ordering::SeqCst),
        asked,
        "replay never reaches the server"
    );
    let replayed = harness::read_records(&out_replay.join("episodes.jsonl")).unwrap();
    let key = |r: &sornav_examples::record::EpisodeRecord| {
        (
            (r.result.scene_id.clone(), r.result.episode_id.clone()),
            r.result.success,
            r.result.actions,
            r.result.path_length_m.to_bits(),
            r.relocations.clone(),
            r.decisions.clone(),
        )
    };
    let mut a: Vec<_> = live_records.iter().map(key).collect();
    let mut b: Vec<_> = replayed.iter().map(key).collect();
    a.sort_by(|x, y| x.0.cmp(&y.0));
    b.sort_by(|x, y| x.0.cmp(&y.0));
    assert_eq!(a, b, "the replayed evaluation is identical");
    // The LLM's figures are reported, the same in the replay (latencies are
    // recorded with the exchanges).
    let llm = |dir: &PathBuf| -> Value {
        let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
        serde_json::from_str::<Value>(&text).unwrap()["llm"].clone()
    };
    let (l, r) = (llm(&out_live), llm(&out_replay));
    assert_eq!(l["requests"].as_u64(), Some(asked as u64), "{l}");
    assert_eq!(l["valid_rate"], 1.0, "{l}");
    assert!(l["latency_ms_p50"].as_f64().unwrap() >= 40.0, "{l}");
    for k in [
        "requests",
        "valid",
        "fallbacks",
        "latency_ms_p50",
        "latency_ms_p99",
        "prompt_tokens",
    ] {
        assert_eq!(l[k], r[k], "{k}: {l} vs {r}");
    }
    let report = std::fs::read_to_string(out_live.join("report.md")).unwrap();
    assert!(
        report.contains("| LLM requests | valid answers (%) |"),
        "{report}"
    );
    for p in [out_live, out_replay, recording] {
        let _ = std::fs::remove_dir_all(&p);
        let _ = std::fs::remove_file(&p);
    }
}

fn sim() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_sornav-sim"))
}

const SMALL: [&str; 12] = [
    "--scenes",
    "procedural:2",
    "--episodes-per-scene",
    "1",
    "--categories",
    "bed",
    "--width",
    "96",
    "--height",
    "72",
    "--max-actions",
    "60",
];

/// A wrong URL or model name stops the run before any episode, with a
/// message saying what is wrong and a nonzero exit status.
#[test]
fn cli_checks_the_endpoint_before_running() {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let out = dir("cli-dead");
    // Exit status 2 and the message on stderr.
    let refused = |llm: &[&str]| -> String {
        let run = sim()
            .args(SMALL)
            .args(llm)
            .arg("--out")
            .arg(&out)
            .arg("--quiet")
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
        assert_eq!(run.status.code(), Some(2), "{stderr}");
        stderr
    };
    let stderr = refused(&["--llm", &format!("http://127.0.0.1:{port}/v1")]);
    assert!(stderr.contains("cannot reach the LLM endpoint"), "{stderr}");
    assert!(!out.join("summary.json").exists(), "nothing ran");

    let server = chat_server::serve_with_models(
        Arc::new(|body| (200, answer(body), Duration::ZERO)),
        Some(vec!["qwen2.5-0.5b".into()]),
    );
    let stderr = refused(&["--llm", &server.base_url, "--llm-model", "qwen-typo"]);
    assert!(
        stderr.contains("does not serve the model 'qwen-typo'") && stderr.contains("qwen2.5-0.5b"),
        "{stderr}"
    );
    assert_eq!(server.hits(), 0);
    let _ = std::fs::remove_dir_all(&out);
}

/// `--llm-*` flags override only what they name: the `[policy]` settings
/// of `--config` stay (a longer timeout and a recording combine), and a
/// recording replays without any URL, with identical results.
#[test]
fn cli_flags_keep_the_config_policy_and_replay_needs_no_url() {
    let (url, hits) = serve();
    let work = dir("cli-flags");
    std::fs::create_dir_all(&work).unwrap();
    let toml = work.join("agent.toml");
    let mut agent = sornav_examples::adapter::sim_agent_config();
    agent.policy = sornav::PolicyConfig::Llm(LlmConfig {
        base_url: url,
        model: "fake".into(),
        api_key_env: None,
        timeout_s: 77.0,
        min_interval_s: 3.0,
        max_tokens: Some(99),
        ..LlmConfig::default()
    });
    std::fs::write(&toml, agent.to_toml().unwrap()).unwrap();
    let recording = work.join("rec.jsonl");
    let live = work.join("live");
    let with = |extra: &[&std::ffi::OsStr]| -> Vec<std::ffi::OsString> {
        SMALL
            .iter()
            .map(std::ffi::OsString::from)
            .chain(extra.iter().map(|a| a.to_os_string()))
            .collect()
    };
    let flags = |file_flag: &str, file: &PathBuf| {
        with(&[
            "--config".as_ref(),
            toml.as_os_str(),
            "--llm-timeout".as_ref(),
            "90".as_ref(),
            "--llm-latency".as_ref(),
            "fixed:1.5".as_ref(),
            file_flag.as_ref(),
            file.as_os_str(),
        ])
    };
    let stdout = common::sornav_sim_ok(&flags("--llm-record", &recording), &live);
    assert!(
        stdout.contains("| LLM requests |"),
        "the table shows the LLM: {stdout}"
    );
    let run_json = |d: &PathBuf| -> Value {
        serde_json::from_str(&std::fs::read_to_string(d.join("run.json")).unwrap()).unwrap()
    };
    let settings = run_json(&live)["llm"]["config"].clone();
    assert_eq!(settings["timeout_s"], 90.0, "the flag: {settings}");
    assert_eq!(
        settings["min_interval_s"], 3.0,
        "kept from --config: {settings}"
    );
    assert_eq!(settings["max_tokens"], 99, "kept from --config: {settings}");
    assert_eq!(settings["model"], "fake");
    assert_eq!(
        settings["latency"],
        json!({"kind": "fixed", "seconds": 1.5})
    );
    let asked = hits.load(Ordering::SeqCst);
    assert!(asked > 0);

    // Replay: the recording and the same agent configuration, no URL.
    let replay = work.join("replay");
    common::sornav_sim_ok(&flags("--llm-replay", &recording), &replay);
    assert_eq!(hits.load(Ordering::SeqCst), asked, "offline");
    let records = |d: &PathBuf| {
        let mut r: Vec<_> = harness::read_records(&d.join("episodes.jsonl"))
            .unwrap()
            .into_iter()
            .map(|r| {
                // The wall time spent waiting is a measurement, not a result.
                let llm = r
                    .llm
                    .map(|l| sornav::supervisor::LlmStats { waited_ms: 0, ..l });
                (
                    r.result.scene_id,
                    r.result.episode_id,
                    r.result.actions,
                    r.decisions,
                    llm,
                )
            })
            .collect();
        r.sort_by(|a, b| (&a.0, &a.1).cmp(&(&b.0, &b.1)));
        r
    };
    assert_eq!(records(&live), records(&replay));
    // Without --config, the model name and token budget still come from
    // the recording (the requests must match it byte for byte).
    let bare = work.join("bare");
    common::sornav_sim_ok(
        &with(&[
            "--llm-replay".as_ref(),
            recording.as_os_str(),
            "--llm-async=false".as_ref(),
        ]),
        &bare,
    );
    let settings = run_json(&bare)["llm"]["config"].clone();
    assert_eq!(
        (settings["model"].clone(), settings["max_tokens"].clone()),
        (json!("fake"), json!(99))
    );
    assert_eq!(settings["asynchronous"], false, "{settings}");
    // What the recording does not carry keeps its default.
    assert_eq!(settings["timeout_s"], 60.0, "{settings}");
    let _ = std::fs::remove_dir_all(&work);
}
