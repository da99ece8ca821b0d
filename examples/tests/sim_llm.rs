//! `sornav-sim --llm`: the LLM context policy against a loopback
//! OpenAI-compatible server (std `TcpListener` on 127.0.0.1), recorded, and
//! re-run offline from the recording with identical results.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use serde_json::{Value, json};
use sornav::supervisor::LlmConfig;
use sornav_examples::adapter::AdapterConfig;
use sornav_examples::harness::{self, EpisodeSource, EvalConfig, LlmSettings, RunOptions};
use sornav_examples::scenes::SceneSource;
use sornav_platform_sim::{CameraConfig, RunConfig};

fn read_body(stream: &TcpStream) -> Option<Value> {
    let mut reader = BufReader::new(stream.try_clone().ok()?);
    let mut line = String::new();
    reader.read_line(&mut line).ok()?;
    let mut length = 0usize;
    loop {
        line.clear();
        reader.read_line(&mut line).ok()?;
        let l = line.trim_end();
        if l.is_empty() {
            break;
        }
        if let Some((k, v)) = l.split_once(':')
            && k.eq_ignore_ascii_case("content-length")
        {
            length = v.trim().parse().ok()?;
        }
    }
    let mut body = vec![0; length];
    reader.read_exact(&mut body).ok()?;
    serde_json::from_slice(&body).ok()
}

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
    json!({
        "id": "x", "object": "chat.completion", "model": "fake",
        "choices": [{"index": 0, "finish_reason": "stop",
                     "message": {"role": "assistant", "content": content.to_string()}}]
    })
    .to_string()
}

fn serve() -> (String, Arc<AtomicUsize>) {
    let listener = TcpListener::bind("127.0.0.1:0").expect("bind loopback");
    let url = format!("http://{}/v1", listener.local_addr().unwrap());
    let hits = Arc::new(AtomicUsize::new(0));
    let h = Arc::clone(&hits);
    std::thread::spawn(move || {
        for stream in listener.incoming() {
            let Ok(mut stream) = stream else { continue };
            let Some(body) = read_body(&stream) else {
                continue;
            };
            h.fetch_add(1, Ordering::SeqCst);
            let reply = answer(&body);
            let _ = write!(
                stream,
                "HTTP/1.1 200 OK\r\ncontent-type: application/json\r\ncontent-length: {}\r\nconnection: close\r\n\r\n{reply}",
                reply.len()
            );
        }
    });
    (url, hits)
}

fn eval(llm: LlmSettings) -> EvalConfig {
    let agent = sornav_examples::adapter::sim_agent_config();
    EvalConfig {
        scenes: vec![SceneSource::Procedural {
            seed: 52,
            shuffled: false,
        }],
        models: None,
        episodes: EpisodeSource::Generate {
            per_category: 1,
            per_scene: Some(3),
        },
        categories: vec!["toilet".into(), "bed".into(), "tv_monitor".into()],
        variants: vec!["sornav".into()],
        seed: 1,
        camera: CameraConfig {
            width: 96,
            height: 72,
            ..CameraConfig::default()
        },
        run: RunConfig {
            max_actions: 120,
            ..RunConfig::default()
        },
        adapter: AdapterConfig::default(),
        agent,
        llm: Some(llm),
        maps: 0,
    }
}

fn dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sornav-llm-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
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
    let options = |out: &PathBuf| RunOptions {
        out: out.clone(),
        jobs: 1,
        shard: None,
        fresh: true,
        progress: false,
    };
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
