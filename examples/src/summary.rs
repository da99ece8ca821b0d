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
use sornav_platform_sim::{EpisodeResult, Summary};

use crate::histogram::Histogram;
use crate::record::EpisodeRecord;

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
