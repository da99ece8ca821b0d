//! The LLM policy against a loopback OpenAI-compatible server (std
//! `TcpListener` on 127.0.0.1:0): every documented outcome.
#![cfg(feature = "llm")]

use std::net::TcpListener;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::thread;
use std::time::{Duration, Instant};

use serde_json::Value;
use sornav_supervisor::llm::transport::{
    HttpTransport, RecordingTransport, ReplayTransport, Transport,
};
use sornav_supervisor::llm::{LlmFailure, LlmStats};
use sornav_supervisor::{
    Candidate, CandidateObject, ContextObject, ContextPolicy, LlmConfig, LlmPolicy, PolicyAction,
    RegionSnapshot, Situation,
};
use sornav_test_support::chat_server::{ChatServer as Server, Handler, completion, serve};

fn fixed(status: u16, content: &str) -> Arc<Handler> {
    let body = if status == 200 {
        completion(content)
    } else {
        content.to_owned()
    };
    Arc::new(move |_| (status, body.clone(), Duration::ZERO))
}

fn config(server: &Server) -> LlmConfig {
    LlmConfig {
        base_url: server.base_url.clone(),
        model: "test-model".into(),
        api_key_env: None,
        timeout_s: 5.0,
        min_interval_s: 0.0,
        use_env_proxy: false,
        ..LlmConfig::default()
    }
}

fn snapshot() -> RegionSnapshot {
    RegionSnapshot {
        target: "toilet".into(),
        local_context: ["bed", "wardrobe", "nightstand"]
            .map(|l| ContextObject::new(l, 120.0))
            .to_vec(),
        candidates: vec![
            Candidate {
                floor: 0,
                cluster_id: 7,
                distance_m: 6.5,
                context: vec![
                    CandidateObject::new("sink", 50.0, 2.0),
                    CandidateObject::new("bathtub", 90.0, 3.0),
                ],
            },
            Candidate {
                floor: 0,
                cluster_id: 9,
                distance_m: 14.0,
                context: vec![CandidateObject::new("couch", 300.0, 1.0)],
            },
        ],
    }
}

fn at(mission_id: u64, elapsed_s: f64) -> Situation {
    Situation {
        mission_id,
        elapsed_s,
    }
}

fn decide_once(
    handler: Arc<Handler>,
) -> (
    sornav_supervisor::PolicyDecision,
    Option<LlmFailure>,
    LlmStats,
    Server,
) {
    let server = serve(handler);
    let mut policy = LlmPolicy::http(config(&server)).unwrap();
    let d = policy.decide(&snapshot(), &at(1, 0.0));
    (d, policy.last_failure().cloned(), policy.stats(), server)
}

#[test]
fn relocation_answer_is_followed_and_request_is_compact_strict_json() {
    let (d, failure, stats, server) = decide_once(fixed(
        200,
        r#"{"action":"relocate_cluster","cluster_id":7,"reason":"sink and bathtub suggest a bathroom"}"#,
    ));
    assert_eq!(d.action, PolicyAction::RelocateCluster { cluster_id: 7 });
    assert!(d.reason.contains("bathroom"), "{}", d.reason);
    assert_eq!(failure, None);
    assert_eq!(stats.requests, 1);
    let req = &server.requests.lock().unwrap()[0];
    assert_eq!(req["model"], "test-model");
    assert_eq!(req["temperature"], 0.0);
    assert_eq!(req["response_format"]["type"], "json_schema");
    assert_eq!(req["response_format"]["json_schema"]["strict"], true);
    let user: Value =
        serde_json::from_str(req["messages"][1]["content"].as_str().unwrap()).unwrap();
    assert_eq!(user["target"], "toilet");
    assert_eq!(user["candidates"][1]["context"][0]["label"], "sofa");
    assert_eq!(user["candidates"][0]["cluster_id"], 7);
    assert_eq!(
        user.as_object().unwrap().len(),
        3,
        "only target, local_context, candidates"
    );
}

#[test]
fn continue_answer_keeps_exploring() {
    let (d, failure, _, _) = decide_once(fixed(200, r#"{"action":"continue_explore"}"#));
    assert_eq!(d.action, PolicyAction::ContinueExplore);
    assert_eq!(failure, None);
}

#[test]
fn invalid_json_falls_back_to_exploring() {
    let (d, failure, stats, _) = decide_once(fixed(
        200,
        r#"{"action": "relocate_cluster", "cluster_id": 7"#,
    ));
    assert_eq!(d.action, PolicyAction::ContinueExplore);
    assert!(
        matches!(failure, Some(LlmFailure::InvalidAnswer(_))),
        "{failure:?}"
    );
    assert_eq!(stats.failures, 1);
}

#[test]
fn unknown_cluster_id_falls_back_to_exploring() {
    let (d, failure, _, _) = decide_once(fixed(
        200,
        r#"{"action":"relocate_cluster","cluster_id":42,"reason":"x"}"#,
    ));
    assert_eq!(d.action, PolicyAction::ContinueExplore);
    assert_eq!(failure, Some(LlmFailure::UnknownCluster(42)));
}

#[test]
fn extra_fields_are_rejected() {
    let (d, failure, _, _) = decide_once(fixed(
        200,
        r#"{"action":"relocate_cluster","cluster_id":7,"reason":"x","confidence":0.9}"#,
    ));
    assert_eq!(d.action, PolicyAction::ContinueExplore);
    assert!(
        matches!(failure, Some(LlmFailure::InvalidAnswer(_))),
        "{failure:?}"
    );
}

#[test]
fn http_500_falls_back_to_exploring() {
    let (d, failure, _, _) = decide_once(fixed(500, r#"{"error":{"message":"boom"}}"#));
    assert_eq!(d.action, PolicyAction::ContinueExplore);
    assert!(
        matches!(failure, Some(LlmFailure::HttpStatus { status: 500, .. })),
        "{failure:?}"
    );
}

#[test]
fn slow_server_times_out_and_explores() {
    let server = serve(Arc::new(|_| {
        (
            200,
            completion(r#"{"action":"relocate_cluster","cluster_id":7,"reason":"late"}"#),
            Duration::from_secs(6),
        )
    }));
    let mut policy = LlmPolicy::http(LlmConfig {
        timeout_s: 0.3,
        ..config(&server)
    })
    .unwrap();
    let t = Instant::now();
    let d = policy.decide(&snapshot(), &at(1, 0.0));
    // Far below the server's 6 s (a generous margin for a loaded machine).
    assert!(t.elapsed() < Duration::from_secs(4), "{:?}", t.elapsed());
    assert_eq!(d.action, PolicyAction::ContinueExplore);
    assert_eq!(policy.last_failure(), Some(&LlmFailure::Timeout));
}

#[test]
fn server_rejecting_json_schema_gets_json_object() {
    let server = serve(Arc::new(|body: &Value| {
        if body["response_format"]["type"] == "json_schema" {
            (
                400,
                r#"{"error":{"message":"response_format json_schema is not supported"}}"#
                    .to_owned(),
                Duration::ZERO,
            )
        } else {
            (
                200,
                completion(r#"{"action":"relocate_cluster","cluster_id":7,"reason":"bathroom"}"#),
                Duration::ZERO,
            )
        }
    }));
    let mut policy = LlmPolicy::http(config(&server)).unwrap();
    let d = policy.decide(&snapshot(), &at(1, 0.0));
    assert_eq!(d.action, PolicyAction::RelocateCluster { cluster_id: 7 });
    assert!(policy.stats().json_object_fallback);
    assert_eq!(server.hits.load(Ordering::SeqCst), 2);
    // The fallback sticks: a new snapshot costs a single json_object request.
    let mut other = snapshot();
    other.local_context.push(ContextObject::new("lamp", 30.0));
    let d = policy.decide(&other, &at(1, 10.0));
    assert_eq!(d.action, PolicyAction::RelocateCluster { cluster_id: 7 });
    assert_eq!(server.hits.load(Ordering::SeqCst), 3);
    assert_eq!(
        server.requests.lock().unwrap()[2]["response_format"]["type"],
        "json_object"
    );
}

#[test]
fn identical_snapshots_hit_the_cache_and_rate_limit_holds() {
    let server = serve(fixed(
        200,
        r#"{"action":"relocate_cluster","cluster_id":7,"reason":"r"}"#,
    ));
    let mut policy = LlmPolicy::http(LlmConfig {
        min_interval_s: 5.0,
        ..config(&server)
    })
    .unwrap();
    let first = policy.decide(&snapshot(), &at(1, 0.0));
    let second = policy.decide(&snapshot(), &at(1, 1.0));
    assert_eq!(first.action, second.action);
    assert!(second.reason.starts_with("cached"));
    assert_eq!(server.hits.load(Ordering::SeqCst), 1);
    // A different snapshot within 5 s is rate limited, after 5 s it is asked.
    let mut other = snapshot();
    other.local_context.pop();
    let d = policy.decide(&other, &at(1, 2.0));
    assert_eq!(d.action, PolicyAction::ContinueExplore);
    assert!(d.reason.contains("rate limit"));
    assert_eq!(server.hits.load(Ordering::SeqCst), 1);
    policy.decide(&other, &at(1, 5.5));
    assert_eq!(server.hits.load(Ordering::SeqCst), 2);
    let stats = policy.stats();
    assert_eq!(
        (stats.cache_hits, stats.rate_limited, stats.answers),
        (1, 1, 2)
    );
    // A restarted clock (new episode) does not keep the policy muted.
    let mut third = snapshot();
    third.target = "bed".into();
    policy.decide(&third, &at(2, 0.0));
    assert_eq!(server.hits.load(Ordering::SeqCst), 3);
}

#[test]
fn disabled_policy_never_asks() {
    let server = serve(fixed(
        200,
        r#"{"action":"relocate_cluster","cluster_id":7}"#,
    ));
    let mut policy = LlmPolicy::http(LlmConfig {
        enabled: false,
        ..config(&server)
    })
    .unwrap();
    let d = policy.decide(&snapshot(), &at(1, 0.0));
    assert_eq!(d.action, PolicyAction::ContinueExplore);
    assert_eq!(policy.last_failure(), Some(&LlmFailure::Disabled));
    assert_eq!(server.hits.load(Ordering::SeqCst), 0);
}

#[test]
fn unreachable_server_falls_back() {
    // Bind then drop to get a closed loopback port.
    let port = TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let mut policy = LlmPolicy::http(LlmConfig {
        base_url: format!("http://127.0.0.1:{port}/v1"),
        api_key_env: None,
        use_env_proxy: false,
        timeout_s: 2.0,
        ..LlmConfig::default()
    })
    .unwrap();
    let d = policy.decide(&snapshot(), &at(1, 0.0));
    assert_eq!(d.action, PolicyAction::ContinueExplore);
    assert!(
        matches!(policy.last_failure(), Some(LlmFailure::Transport(_))),
        "{:?}",
        policy.last_failure()
    );
}

fn wait_answer(
    policy: &mut LlmPolicy,
    s: &RegionSnapshot,
    situation: Situation,
) -> sornav_supervisor::PolicyDecision {
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let d = policy.decide(s, &situation);
        if !d.reason.contains("pending") && !d.reason.contains("request sent") {
            return d;
        }
        assert!(Instant::now() < deadline, "no asynchronous answer");
        thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn asynchronous_mode_never_blocks_and_delivers() {
    let server = serve(Arc::new(|_| {
        (
            200,
            completion(r#"{"action":"relocate_cluster","cluster_id":7,"reason":"bathroom"}"#),
            Duration::from_secs(3),
        )
    }));
    let mut policy = LlmPolicy::http(LlmConfig {
        asynchronous: true,
        ..config(&server)
    })
    .unwrap();
    let t = Instant::now();
    let d = policy.decide(&snapshot(), &at(1, 0.0));
    // Far below the server's 3 s (a generous margin for a loaded machine).
    assert!(
        t.elapsed() < Duration::from_millis(1500),
        "blocked for {:?}",
        t.elapsed()
    );
    assert_eq!(d.action, PolicyAction::ContinueExplore);
    assert!(policy.is_pending());
    let d = wait_answer(&mut policy, &snapshot(), at(1, 0.5));
    assert_eq!(d.action, PolicyAction::RelocateCluster { cluster_id: 7 });
    assert!(!policy.is_pending());
}

#[test]
fn asynchronous_late_answer_is_dropped_when_the_mission_changed() {
    let server = serve(Arc::new(|_| {
        (
            200,
            completion(r#"{"action":"relocate_cluster","cluster_id":7,"reason":"bathroom"}"#),
            Duration::from_millis(200),
        )
    }));
    let mut policy = LlmPolicy::http(LlmConfig {
        asynchronous: true,
        ..config(&server)
    })
    .unwrap();
    policy.decide(&snapshot(), &at(1, 0.0));
    // Let the answer arrive, then ask in a new mission (e.g. a relocation started
    // and ended): the answer to the old question must not be used.
    let deadline = Instant::now() + Duration::from_secs(10);
    while server.answered() == 0 {
        assert!(Instant::now() < deadline, "the server never answered");
        thread::sleep(Duration::from_millis(20));
    }
    thread::sleep(Duration::from_millis(300)); // the client reads it
    let mut changed = snapshot();
    changed.local_context.push(ContextObject::new("lamp", 40.0));
    let d = policy.decide(&changed, &at(2, 0.6));
    assert_eq!(policy.stats().dropped_late_answers, 1);
    // The drop is followed by a fresh request for the current situation.
    assert_eq!(d.action, PolicyAction::ContinueExplore);
    assert!(policy.is_pending());
    let d = wait_answer(&mut policy, &changed, at(2, 1.0));
    assert_eq!(d.action, PolicyAction::RelocateCluster { cluster_id: 7 });
    assert_eq!(server.hits.load(Ordering::SeqCst), 2);
}

#[test]
fn record_then_replay_offline_bit_for_bit() {
    let dir = std::env::temp_dir().join(format!("sornav-supervisor-replay-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("exchanges.jsonl");
    let _ = std::fs::remove_file(&path);
    let counter = Arc::new(AtomicUsize::new(0));
    let c2 = Arc::clone(&counter);
    let server = serve(Arc::new(move |_| {
        // Alternating answers so that the sequence matters.
        let n = c2.fetch_add(1, Ordering::SeqCst);
        let content = match n % 3 {
            0 => r#"{"action":"relocate_cluster","cluster_id":7,"reason":"a"}"#,
            1 => r#"{"action":"continue_explore","cluster_id":null,"reason":"b"}"#,
            _ => r#"{"action":"relocate_cluster","cluster_id":99,"reason":"c"}"#,
        };
        (200, completion(content), Duration::ZERO)
    }));
    let cfg = config(&server);
    let snapshots: Vec<RegionSnapshot> = (0..4)
        .map(|i| {
            let mut s = snapshot();
            s.local_context
                .push(ContextObject::new("lamp", f64::from(i)));
            s
        })
        .collect();
    let recorded: Vec<_> = {
        let http = HttpTransport::new(&cfg.base_url, None, Duration::from_secs(5), false);
        let rec: Arc<dyn Transport> = Arc::new(RecordingTransport::new(http, &path).unwrap());
        let mut policy = LlmPolicy::with_transport(cfg.clone(), rec).unwrap();
        snapshots
            .iter()
            .map(|s| policy.decide(s, &at(1, 0.0)))
            .collect()
    };
    drop(server);
    let replay: Arc<dyn Transport> = Arc::new(ReplayTransport::open(&path).unwrap());
    let mut policy = LlmPolicy::with_transport(cfg, replay).unwrap();
    let replayed: Vec<_> = snapshots
        .iter()
        .map(|s| policy.decide(s, &at(1, 0.0)))
        .collect();
    assert_eq!(recorded, replayed);
    assert_eq!(
        recorded[0].action,
        PolicyAction::RelocateCluster { cluster_id: 7 }
    );
    assert_eq!(recorded[2].action, PolicyAction::ContinueExplore);
    // Not in the recording: falls back.
    let mut unseen = snapshot();
    unseen.target = "bed".into();
    assert_eq!(
        policy.decide(&unseen, &at(1, 0.0)).action,
        PolicyAction::ContinueExplore
    );
    assert!(matches!(
        policy.last_failure(),
        Some(LlmFailure::Transport(_))
    ));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A transport answering whatever the test scripted (no network).
struct Canned(String);

impl Transport for Canned {
    fn post(
        &self,
        _body: &str,
    ) -> Result<
        sornav_supervisor::llm::transport::HttpReply,
        sornav_supervisor::llm::transport::TransportError,
    > {
        Ok(sornav_supervisor::llm::transport::HttpReply {
            status: 200,
            body: completion(&self.0),
        })
    }
}

mod properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(128))]

        #[test]
        fn llm_policy_never_returns_a_cluster_outside_the_candidates(
            id in 0u64..20,
            action in prop_oneof![Just("relocate_cluster"), Just("continue_explore"), Just("fly")],
            ids in prop::collection::btree_set(0u64..20, 0..6),
            garbage in any::<bool>(),
        ) {
            let content = if garbage {
                format!(r#"{{"action":"{action}","cluster_id":{id}"#)
            } else {
                format!(r#"{{"action":"{action}","cluster_id":{id},"reason":"r"}}"#)
            };
            let mut policy = LlmPolicy::with_transport(
                LlmConfig { min_interval_s: 0.0, ..LlmConfig::default() },
                Arc::new(Canned(content)),
            ).unwrap();
            let mut s = snapshot();
            s.candidates = ids.iter().map(|&k| Candidate { floor: 0, cluster_id: k, distance_m: 1.0, context: vec![] }).collect();
            let d = policy.decide(&s, &at(1, 0.0));
            if let Some(k) = d.relocation() {
                prop_assert!(s.candidate(k).is_some());
                prop_assert!(!garbage && action == "relocate_cluster" && k == id);
            }
            prop_assert!(!d.reason.is_empty());
        }
    }
}
