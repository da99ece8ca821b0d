//! `sornav-sim --llm`: the LLM context policy against a loopback
//! OpenAI-compatible server (std `TcpListener` on 127.0.0.1), recorded, and
//! re-run offline from the recording with identical results.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use serde_json::{Value, json};
use sornav::supervisor::LlmConfig;
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
        .and_then(|c| c["cluster_id"].as_u64());
    let content = match first {
        Some(id) => json!({"action": "relocate_cluster", "cluster_id": id, "reason": "test model"}),
        None => json!({"action": "continue_explore"}),
    };
    chat_server::completion(&content.to_string())
}

fn serve() -> (String, Arc<AtomicUsize>) {
    let server = chat_server::serve(Arc::new(|body| (200, answer(body), Duration::ZERO)));
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
        ..LlmConfig::default()
    };
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
            r.result.episode_id.clone(),
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
    for p in [out_live, out_replay, recording] {
        let _ = std::fs::remove_dir_all(&p);
        let _ = std::fs::remove_file(&p);
    }
}
