//! Decision latency of the commonsense supervisor (no target in the issue;
//! recorded for the simulator's `decision_ms` budget).
//!
//! ```text
//! cargo run --release -p sornav-supervisor --example bench_supervisor
//! ```
//!
//! Prints one JSON line: medians over 15 repetitions of 2,000 decisions each,
//! for a snapshot of 15 local objects and K = 10 candidates of 10 objects.
//! `commonsense_decide_nb_us_p50` times the same decision over the embedded
//! table's counts as the naive-Bayes prior shipped before (same run).

use std::time::Instant;

use nalgebra::Point3;
use sornav_supervisor::{
    ActiveMissionKind, Candidate, CandidateObject, ClusterCandidate, CommonsenseConfig,
    CommonsensePolicy, ContextObject, ContextPolicy, CooccurrencePrior, MissionState, PriorModel,
    RegionContext, RegionSnapshot, Situation, StepInput, Supervisor, SupervisorConfig,
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
    let mut naive_bayes = CooccurrencePrior::embedded().clone();
    naive_bayes.config.model = PriorModel::NaiveBayes;
    naive_bayes.logistic.clear();
    let time_decisions = |mut policy: CommonsensePolicy<'_>| {
        let mut relocations = 0usize;
        let mut us = Vec::with_capacity(REPS);
        for _ in 0..REPS {
            let t = Instant::now();
            for _ in 0..N {
                relocations += usize::from(
                    std::hint::black_box(policy.decide(&snapshot, &situation))
                        .relocation()
                        .is_some(),
                );
            }
            us.push(t.elapsed().as_secs_f64() * 1e6 / N as f64);
        }
        (median(us), relocations)
    };
    // The posterior alone, over the snapshot's 11 contexts (local + 10
    // candidates): the per-model cost whatever the decision.
    let contexts: Vec<Vec<&str>> = std::iter::once(
        snapshot
            .local_context
            .iter()
            .map(|o| o.label.as_str())
            .collect(),
    )
    .chain(
        snapshot
            .candidates
            .iter()
            .map(|c| c.context.iter().map(|o| o.label.as_str()).collect()),
    )
    .collect();
    let time_posteriors = |prior: &CooccurrencePrior| {
        let mut us = Vec::with_capacity(REPS);
        for _ in 0..REPS {
            let t = Instant::now();
            for _ in 0..N {
                for c in &contexts {
                    std::hint::black_box(prior.posterior("toilet", c.iter().copied()));
                }
            }
            us.push(t.elapsed().as_secs_f64() * 1e6 / N as f64);
        }
        median(us)
    };
    let posterior_us = time_posteriors(CooccurrencePrior::embedded());
    let posterior_nb_us = time_posteriors(&naive_bayes);
    let (policy_us, relocations) = time_decisions(CommonsensePolicy::default());
    let (nb_us, relocations_nb) = time_decisions(
        CommonsensePolicy::new(&naive_bayes, CommonsenseConfig::default()).expect("valid config"),
    );
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
            "commonsense_decide_us_p50": policy_us,
            "commonsense_decide_nb_us_p50": nb_us,
            "posterior_11_contexts_us_p50": posterior_us,
            "posterior_11_contexts_nb_us_p50": posterior_nb_us,
            "relocations_nb": relocations_nb,
            "supervisor_step_us_p50": median(step_us),
            "relocations": relocations,
        })
    );
}
