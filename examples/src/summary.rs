//! Aggregate figures of an evaluation: one [`VariantSummary`] per variant
//! (the fields GUIDE.md section 5 requires and more), success against the
//! initial geodesic distance and by floors between start and goal, with
//! Wilson intervals.
//!
//! Floors come from the simulator's navmesh levels
//! ([`sornav_platform_sim::levels`]): `floors_between` is the number of
//! floor-to-floor transitions between the start's level and the level of
//! the goal view point nearest to it; an episode is cross-floor when it is
//! at least 1. The failure classes (`step_limit`, `timeout`, `false_stop`,
//! `other`) are the cause, for cross-floor episodes too.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use sornav::supervisor::LlmStats;
use sornav_platform_sim::{EpisodeResult, Outcome, Summary};

use crate::histogram::Histogram;
use crate::record::EpisodeRecord;

/// The outcome classes in report order with their labels: success, then
/// the failure causes (exclusive, in the order the simulator tests them).
pub const OUTCOME_CLASSES: [(Outcome, &str); 5] = [
    (Outcome::Success, "success"),
    (Outcome::StepLimit, "step limit"),
    (Outcome::Timeout, "timeout"),
    (Outcome::FalseStop, "false stop"),
    (Outcome::Other, "other"),
];

/// The initial-distance bins of the success-vs-distance analysis (m).
pub const DISTANCE_BINS: [(f64, f64, &str); 4] = [
    (0.0, 5.0, "0-5 m"),
    (5.0, 10.0, "5-10 m"),
    (10.0, 15.0, "10-15 m"),
    (15.0, f64::INFINITY, ">=15 m"),
];

/// The floors-between bins: (least, most (`None`: no bound), label).
pub const FLOOR_BINS: [(usize, Option<usize>, &str); 3] =
    [(0, Some(0), "0"), (1, Some(1), "1"), (2, None, "2+")];

/// Index of the [`FLOOR_BINS`] bin of `floors_between`.
pub fn floor_bin(floors_between: usize) -> usize {
    floors_between.min(FLOOR_BINS.len() - 1)
}

/// Wilson score interval of a binomial proportion (`k` successes out of
/// `n`) at normal quantile `z` (1.96 for 95 %). `(0, 1)` when `n == 0`.
///
/// # Notes
/// E. B. Wilson, "Probable inference, the law of succession, and
/// statistical inference", JASA 22(158), 1927. Unlike the normal
/// approximation it stays inside [0, 1] and is sensible at 0 and n.
pub fn wilson(k: u64, n: u64, z: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let n_f = n as f64;
    let p = (k.min(n)) as f64 / n_f;
    let z2 = z * z;
    let denom = 1.0 + z2 / n_f;
    let centre = (p + z2 / (2.0 * n_f)) / denom;
    let half = z * (p * (1.0 - p) / n_f + z2 / (4.0 * n_f * n_f)).sqrt() / denom;
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

/// Success against the initial geodesic distance, same-floor episodes only.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DistanceBin {
    /// Bin label (`0-5 m`, ...).
    pub bin: String,
    /// Episodes in the bin.
    pub episodes: u64,
    /// Successes.
    pub successes: u64,
    /// Success rate (0 when empty).
    pub success_rate: f64,
    /// Wilson 95 % interval of the success rate.
    pub ci95: (f64, f64),
    /// Mean SPL.
    pub spl: f64,
}

/// SR and SPL of the episodes with a number of floors between start and
/// goal (a [`FLOOR_BINS`] bin).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FloorBin {
    /// Bin label: `0`, `1` or `2+` floors between start and goal.
    pub floors: String,
    /// Episodes in the bin.
    pub episodes: u64,
    /// Successes.
    pub successes: u64,
    /// Success rate (0 when empty).
    pub success_rate: f64,
    /// Wilson 95 % interval of the success rate.
    pub ci95: (f64, f64),
    /// Mean SPL (0 when empty).
    pub spl: f64,
}

/// The figures of one variant (GUIDE.md section 5; rates are fractions).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VariantSummary {
    /// Variant name.
    pub variant: String,
    /// Episodes.
    pub episodes: u64,
    /// Habitat success rate.
    pub success_rate: f64,
    /// Wilson 95 % interval of the success rate.
    pub success_rate_ci95: (f64, f64),
    /// Mean SPL.
    pub spl: f64,
    /// Mean soft SPL.
    pub soft_spl: f64,
    /// Success within 1 m of the object (the paper's boundary).
    pub success_rate_1m: f64,
    /// Wilson 95 % interval of `success_rate_1m`.
    pub success_rate_1m_ci95: (f64, f64),
    /// Mean final geodesic distance to the nearest view point (m), over
    /// episodes where it is defined.
    pub dtg_m: f64,
    /// Failed by the action budget.
    pub step_limit_rate: f64,
    /// Failed by the wall-clock budget.
    pub timeout_rate: f64,
    /// Failed by STOP away from every goal object.
    pub false_stop_rate: f64,
    /// Fraction of cross-floor episodes (goal on another navmesh level than
    /// the start; a flag apart from the failure classes).
    pub cross_floor_rate: f64,
    /// Cross-floor episodes.
    pub cross_floor_episodes: u64,
    /// Success rate on cross-floor episodes (0 when none).
    pub cross_floor_success_rate: f64,
    /// Other failures (STOP within 1 m but not at a view point).
    pub other_rate: f64,
    /// Mean actions per episode.
    pub mean_actions: f64,
    /// Mean blocked forward moves per episode.
    pub mean_collisions: f64,
    /// Blocked forward moves per metre travelled (all episodes' collisions
    /// over their summed path length; 0 without any path): with
    /// `mean_missions`, the measure of thrashing.
    #[serde(default)]
    pub collisions_per_m: f64,
    /// Mean missions the platform adopted per episode (a re-dispatch with a
    /// new waypoint counts): how often the agent changed its mind.
    #[serde(default)]
    pub mean_missions: f64,
    /// Mean frontiers per episode given up after exploration missions had
    /// reached their place three times (re-dispatches of the same goal
    /// under new frontier ids, cut off).
    #[serde(default)]
    pub mean_revisit_exclusions: f64,
    /// Fraction of episodes with at least one relocation.
    pub relocation_rate: f64,
    /// Mean relocations per episode.
    pub mean_relocations: f64,
    /// Fraction of episodes the agent ended because nothing was left to
    /// explore.
    pub exhausted_rate: f64,
    /// Same-floor episodes.
    pub same_floor_episodes: u64,
    /// Success rate on same-floor episodes.
    pub same_floor_success_rate: f64,
    /// Sum of the episodes' wall times (s).
    pub wall_s: f64,
    /// Episodes per second of episode wall time (one job).
    pub episodes_per_s: f64,
    /// Mean wall time per episode (s).
    pub episode_wall_s_mean: f64,
    /// Longest episode (s).
    pub episode_wall_s_max: f64,
    /// Decision latency (observe + step), median over all actions (ms).
    pub decision_ms_p50: f64,
    /// Decision latency, 99th percentile (ms).
    pub decision_ms_p99: f64,
    /// Time per action outside the agent (render + simulator), median (ms).
    pub frame_ms_p50: f64,
    /// Agent errors recorded.
    pub agent_errors: u64,
    /// Same-floor success by initial geodesic distance.
    pub distance_bins: Vec<DistanceBin>,
    /// SR / SPL by floors between start and goal (0, 1, 2+).
    pub by_floors: Vec<FloorBin>,
    /// Episodes per outcome class.
    pub outcomes: BTreeMap<String, u64>,
    /// The LLM policy's figures, when the variant asked a model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub llm: Option<LlmSummary>,
}

/// What the LLM policy did over a variant's episodes: are its decisions
/// usable, how fast and how costly.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LlmSummary {
    /// Episodes whose agent asked a model.
    pub episodes: u64,
    /// Policy evaluations (`decide` calls: rate-limited, cached and pending
    /// ones included).
    pub calls: u64,
    /// HTTP requests sent (a json_object retry counts).
    pub requests: u64,
    /// Valid answers used.
    pub valid: u64,
    /// Valid answers over valid answers plus fallbacks (0 without any).
    pub valid_rate: f64,
    /// Answers that fell back to exploring.
    pub fallbacks: u64,
    /// Fallbacks by cause (`timeout`, `transport`, `http_status`,
    /// `invalid_answer`, ...).
    pub fallbacks_by_cause: BTreeMap<String, u64>,
    /// Asynchronous answers dropped because they no longer fitted.
    pub dropped_late_answers: u64,
    /// Answers served from the cache.
    pub cache_hits: u64,
    /// Exchange latency, median (ms; 0 without any).
    pub latency_ms_p50: f64,
    /// Exchange latency, 99th percentile (ms).
    pub latency_ms_p99: f64,
    /// Prompt tokens reported by the server, summed.
    pub prompt_tokens: u64,
    /// Completion tokens reported by the server, summed.
    pub completion_tokens: u64,
    /// Mean prompt tokens per request (0 without any).
    pub prompt_tokens_per_request: f64,
    /// Whether the server needed the json_object fallback.
    pub json_object_fallback: bool,
    /// Wall time spent waiting for answers due in simulated time (s).
    pub waited_s: f64,
}

impl LlmSummary {
    /// The figures of `records` that carry LLM counters (`None` when none
    /// does).
    ///
    /// # Complexity
    /// O(total requests · log) for the latency quantiles.
    pub fn of(records: &[&EpisodeRecord]) -> Option<Self> {
        let mut total = LlmStats::default();
        let mut episodes = 0;
        for stats in records.iter().filter_map(|r| r.llm.as_ref()) {
            total.merge(stats);
            episodes += 1;
        }
        if episodes == 0 {
            return None;
        }
        let quantile = |q| total.latency_quantile_ms(q).map_or(0.0, |ms| ms as f64);
        Some(Self {
            episodes,
            calls: total.calls,
            requests: total.requests,
            valid: total.answers,
            valid_rate: total.valid_rate().unwrap_or(0.0),
            fallbacks: total.failures,
            fallbacks_by_cause: total.failures_by_cause.clone(),
            dropped_late_answers: total.dropped_late_answers,
            cache_hits: total.cache_hits,
            latency_ms_p50: quantile(0.5),
            latency_ms_p99: quantile(0.99),
            prompt_tokens: total.prompt_tokens,
            completion_tokens: total.completion_tokens,
            prompt_tokens_per_request: if total.requests == 0 {
                0.0
            } else {
                total.prompt_tokens as f64 / total.requests as f64
            },
            json_object_fallback: total.json_object_fallback,
            waited_s: total.waited_ms as f64 / 1e3,
        })
    }
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = values.fold((0.0, 0u64), |(s, n), v| (s + v, n + 1));
    if n == 0 { 0.0 } else { s / n as f64 }
}

impl VariantSummary {
    /// The summary of `records` (all of one variant).
    pub fn of(variant: &str, records: &[&EpisodeRecord]) -> Self {
        let n = records.len() as u64;
        let nf = n.max(1) as f64;
        let count =
            |f: &dyn Fn(&EpisodeRecord) -> bool| records.iter().filter(|r| f(r)).count() as u64;
        let rate = |k: u64| k as f64 / nf;
        let successes = count(&|r| r.result.success);
        // The simulator's own means. Bit-identical to left-to-right sums
        // from +0.0 divided by the count: its sums add in the same order and
        // start from -0.0, which differs only when every term is -0.0, and no
        // metric of `run_episode` is ever -0.0.
        let results: Vec<EpisodeResult> = records.iter().map(|r| r.result.clone()).collect();
        let sim = Summary::of(&results);
        let mut decision = Histogram::new();
        let mut frame = Histogram::new();
        for r in records {
            decision.merge(&r.decision_ms);
            frame.merge(&r.frame_ms);
        }
        let mut outcomes = BTreeMap::new();
        for r in records {
            *outcomes
                .entry(r.result.outcome.name().to_owned())
                .or_insert(0) += 1;
        }
        let same_floor: Vec<&&EpisodeRecord> =
            records.iter().filter(|r| !r.result.cross_floor).collect();
        let distance_bins = DISTANCE_BINS
            .iter()
            .map(|&(lo, hi, label)| {
                let in_bin: Vec<&&&EpisodeRecord> = same_floor
                    .iter()
                    .filter(|r| r.result.start_geodesic_m >= lo && r.result.start_geodesic_m < hi)
                    .collect();
                let k = in_bin.iter().filter(|r| r.result.success).count() as u64;
                let m = in_bin.len() as u64;
                DistanceBin {
                    bin: label.to_owned(),
                    episodes: m,
                    successes: k,
                    success_rate: if m == 0 { 0.0 } else { k as f64 / m as f64 },
                    ci95: wilson(k, m, 1.96),
                    spl: mean(in_bin.iter().map(|r| r.result.spl)),
                }
            })
            .collect();
        let by_floors = FLOOR_BINS
            .iter()
            .enumerate()
            .map(|(i, &(_, _, label))| {
                let in_bin: Vec<&&EpisodeRecord> = records
                    .iter()
                    .filter(|r| floor_bin(r.result.floors_between) == i)
                    .collect();
                let k = in_bin.iter().filter(|r| r.result.success).count() as u64;
                let m = in_bin.len() as u64;
                FloorBin {
                    floors: label.to_owned(),
                    episodes: m,
                    successes: k,
                    success_rate: if m == 0 { 0.0 } else { k as f64 / m as f64 },
                    ci95: wilson(k, m, 1.96),
                    spl: mean(in_bin.iter().map(|r| r.result.spl)),
                }
            })
            .collect();
        let cross: Vec<&&EpisodeRecord> = records.iter().filter(|r| r.result.cross_floor).collect();
        let wall_s: f64 = records.iter().map(|r| r.result.wall_s).sum();
        let sf = same_floor.len() as u64;
        Self {
            variant: variant.to_owned(),
            episodes: n,
            success_rate: sim.success_rate,
            success_rate_ci95: wilson(successes, n, 1.96),
            spl: sim.spl,
            soft_spl: sim.soft_spl,
            success_rate_1m: sim.success_rate_1m,
            success_rate_1m_ci95: wilson(count(&|r| r.result.success_1m), n, 1.96),
            dtg_m: sim.dtg_m,
            step_limit_rate: sim.step_limit_rate,
            timeout_rate: sim.timeout_rate,
            false_stop_rate: sim.false_stop_rate,
            cross_floor_rate: sim.cross_floor_rate,
            cross_floor_episodes: cross.len() as u64,
            cross_floor_success_rate: if cross.is_empty() {
                0.0
            } else {
                cross.iter().filter(|r| r.result.success).count() as f64 / cross.len() as f64
            },
            other_rate: sim.other_rate,
            mean_actions: sim.mean_actions,
            mean_collisions: sim.mean_collisions,
            collisions_per_m: {
                let path: f64 = records.iter().map(|r| r.result.path_length_m).sum();
                let collisions: usize = records.iter().map(|r| r.result.collisions).sum();
                if path > 0.0 {
                    collisions as f64 / path
                } else {
                    0.0
                }
            },
            mean_missions: mean(records.iter().map(|r| r.missions as f64)),
            mean_revisit_exclusions: mean(records.iter().map(|r| r.revisit_exclusions as f64)),
            relocation_rate: rate(count(&|r| !r.relocations.is_empty())),
            mean_relocations: mean(records.iter().map(|r| r.relocations.len() as f64)),
            exhausted_rate: rate(count(&|r| r.agent_end == "exhausted")),
            same_floor_episodes: sf,
            same_floor_success_rate: if sf == 0 {
                0.0
            } else {
                same_floor.iter().filter(|r| r.result.success).count() as f64 / sf as f64
            },
            wall_s,
            episodes_per_s: if wall_s > 0.0 { n as f64 / wall_s } else { 0.0 },
            episode_wall_s_mean: mean(records.iter().map(|r| r.result.wall_s)),
            episode_wall_s_max: records.iter().map(|r| r.result.wall_s).fold(0.0, f64::max),
            decision_ms_p50: decision.quantile(0.5).unwrap_or(0.0),
            decision_ms_p99: decision.quantile(0.99).unwrap_or(0.0),
            frame_ms_p50: frame.quantile(0.5).unwrap_or(0.0),
            agent_errors: records.iter().map(|r| r.errors.len() as u64).sum(),
            distance_bins,
            by_floors,
            outcomes,
            llm: LlmSummary::of(records),
        }
    }
}

/// Per-variant summaries of `records`, in the order of `variants` (variants
/// without records are left out).
pub fn summarize(records: &[EpisodeRecord], variants: &[String]) -> Vec<VariantSummary> {
    variants
        .iter()
        .filter_map(|v| {
            let mine: Vec<&EpisodeRecord> = records.iter().filter(|r| &r.variant == v).collect();
            (!mine.is_empty()).then(|| VariantSummary::of(v, &mine))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A record of one episode with `outcome`, on `floors` floors between
    /// start and goal, and LLM counters when given.
    fn record(
        outcome: sornav_platform_sim::Outcome,
        floors: usize,
        llm: Option<LlmStats>,
    ) -> EpisodeRecord {
        let mut r = crate::record::test_record("e", outcome, 0.0, floors);
        r.llm = llm;
        r
    }

    /// Issue 22: a wall-clock cut is a timeout whatever the floors.
    #[test]
    fn wall_clock_cut_is_a_timeout_on_any_floor() {
        use sornav_platform_sim::Outcome;
        let records = [
            record(Outcome::Timeout, 1, None),
            record(Outcome::Timeout, 0, None),
        ];
        let refs: Vec<&EpisodeRecord> = records.iter().collect();
        let s = VariantSummary::of("sornav", &refs);
        assert_eq!(s.timeout_rate, 1.0);
        assert_eq!(s.outcomes.get("timeout"), Some(&2));
        assert_eq!(s.cross_floor_episodes, 1);
        assert!(s.llm.is_none(), "no LLM figures without an LLM");
    }

    #[test]
    fn llm_figures_add_up_over_episodes() {
        use sornav_platform_sim::Outcome;
        let stats = |answers, failures: &[(&str, u64)], latency: Vec<u64>| LlmStats {
            requests: latency.len() as u64,
            answers,
            failures: failures.iter().map(|f| f.1).sum(),
            failures_by_cause: failures.iter().map(|&(c, n)| (c.to_owned(), n)).collect(),
            prompt_tokens: 300 * latency.len() as u64,
            completion_tokens: 20 * answers,
            latency_ms: latency,
            ..LlmStats::default()
        };
        let records = [
            record(
                Outcome::Success,
                0,
                Some(stats(3, &[("timeout", 1)], vec![100, 200, 300, 60_000])),
            ),
            record(
                Outcome::StepLimit,
                0,
                Some(stats(
                    6,
                    &[("invalid_answer", 1), ("timeout", 1)],
                    vec![100; 8],
                )),
            ),
            record(Outcome::StepLimit, 0, None),
        ];
        let refs: Vec<&EpisodeRecord> = records.iter().collect();
        let l = VariantSummary::of("sornav", &refs).llm.unwrap();
        assert_eq!(l.episodes, 2);
        assert_eq!((l.requests, l.valid, l.fallbacks), (12, 9, 3));
        assert!((l.valid_rate - 0.75).abs() < 1e-12);
        assert_eq!(l.fallbacks_by_cause.get("timeout"), Some(&2));
        assert_eq!(l.fallbacks_by_cause.get("invalid_answer"), Some(&1));
        assert_eq!((l.latency_ms_p50, l.latency_ms_p99), (100.0, 60_000.0));
        assert_eq!(l.prompt_tokens_per_request, 300.0);
        assert_eq!(l.completion_tokens, 180);
        let table = crate::report::table(&[VariantSummary::of("sornav", &refs)]);
        assert!(table.contains("| sornav | 12 | 9 (75.0) | invalid_answer 1, timeout 2 | 0 | 100 / 60000 | 300 | 180 |"), "{table}");
    }

    #[test]
    fn wilson_matches_published_values() {
        // Newcombe (1998), Statistics in Medicine 17, table I: 81/263 ->
        // 0.2553-0.3662; 15/148 -> 0.0624-0.1605; 0/20 -> 0-0.1611.
        let close =
            |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() < 1e-4 && (a.1 - b.1).abs() < 1e-4;
        assert!(close(wilson(81, 263, 1.959_964), (0.2553, 0.3662)));
        assert!(close(wilson(15, 148, 1.959_964), (0.0624, 0.1605)));
        assert!(close(wilson(0, 20, 1.959_964), (0.0, 0.1611)));
        assert_eq!(wilson(0, 0, 1.96), (0.0, 1.0));
    }

    proptest! {
        #[test]
        fn wilson_brackets_the_estimate(n in 1u64..5000, k_frac in 0.0f64..=1.0) {
            let k = (k_frac * n as f64).round() as u64;
            let (lo, hi) = wilson(k, n, 1.96);
            let p = k as f64 / n as f64;
            prop_assert!(0.0 <= lo && lo <= p + 1e-12 && p <= hi + 1e-12 && hi <= 1.0);
        }
    }
}
