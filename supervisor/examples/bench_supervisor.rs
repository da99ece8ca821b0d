//! Decision latency of the commonsense supervisor (no target in the issue;
//! recorded for the simulator's `decision_ms` budget).
//!
//! ```text
//! cargo run --release -p sornav-supervisor --example bench_supervisor
//! ```
//!
//! Prints one JSON line: medians over 15 repetitions of 2,000 decisions each,
//! for a snapshot of 15 local objects and K = 10 candidates of 10 objects.

use std::time::Instant;

use nalgebra::Point3;
use sornav_supervisor::{
    ActiveMissionKind, Candidate, CandidateObject, ClusterCandidate, CommonsensePolicy,
    ContextObject, ContextPolicy, MissionState, RegionContext, RegionSnapshot, Situation,
    StepInput, Supervisor, SupervisorConfig,
};

const LABELS: [&str; 20] = [
    "bed",
    "wardrobe",
    "nightstand",
    "lamp",
    "pillow",
    "curtain",
    "mirror",
    "picture",
    "chair",
    "table",
    "sink",
    "bathtub",
    "towel",
    "couch",
    "tv",
    "refrigerator",
    "stove",
    "shelf",
    "plant",
    "rug",
];

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn region() -> RegionContext {
    RegionContext {
        local_context: (0..15)
            .map(|i| ContextObject::new(LABELS[i % 8], 50.0 + i as f64))
            .collect(),
        clusters: (0..14u64)
            .map(|k| ClusterCandidate {
                candidate: Candidate {
                    floor: 0,
                    cluster_id: k,
                    distance_m: 3.0 + k as f64 * 2.5,
                    context: (0..10)
                        .map(|j| {
                            CandidateObject::new(
                                LABELS[(k as usize * 3 + j) % LABELS.len()],
                                40.0,
                                1.0 + j as f64 * 0.5,
                            )
                        })
                        .collect(),
                },
                u_geo: 10.0 - k as f64 * 0.5,
                waypoint: Point3::new(k as f64, 0.0, 0.0),
            })
            .collect(),
    }
}

fn main() {
    const REPS: usize = 15;
    const N: usize = 2000;
    let ctx = region();
    let snapshot = RegionSnapshot {
        target: "toilet".into(),
        local_context: ctx.local_context.clone(),
        candidates: ctx
            .clusters
            .iter()
            .take(10)
            .map(|c| c.candidate.clone())
            .collect(),
    };
    let situation = Situation {
        mission_id: 1,
        elapsed_s: 0.0,
    };
    let mut policy = CommonsensePolicy::default();
    let mut relocations = 0usize;
    let mut policy_us = Vec::with_capacity(REPS);
    for _ in 0..REPS {
        let t = Instant::now();
        for _ in 0..N {
            relocations += usize::from(
                std::hint::black_box(policy.decide(&snapshot, &situation))
                    .relocation()
                    .is_some(),
            );
        }
        policy_us.push(t.elapsed().as_secs_f64() * 1e6 / N as f64);
    }
    let mut step_us = Vec::with_capacity(REPS);
    let input = StepInput {
        target: "toilet",
        target_accepted: None,
        mission: MissionState {
            id: 1,
            kind: ActiveMissionKind::Idle,
        },
        first_frontier: Some(Point3::origin()),
    };
    let mut sup: Supervisor<_, f64> =
        Supervisor::new(CommonsensePolicy::default(), SupervisorConfig::default())
            .expect("valid config");
    for r in 0..REPS {
        let t = Instant::now();
        for i in 0..N {
            let now = (r * N + i) as f64 * 2.0;
            std::hint::black_box(sup.step(now, &input, || ctx.clone()).expect("finite clock"));
        }
        step_us.push(t.elapsed().as_secs_f64() * 1e6 / N as f64);
    }
    println!(
        "{}",
        serde_json::json!({
            "bench": "supervisor",
            "local_objects": 15,
            "candidates": 10,
            "objects_per_candidate": 10,
            "commonsense_decide_us_p50": median(policy_us),
            "supervisor_step_us_p50": median(step_us),
            "relocations": relocations,
        })
    );
}
