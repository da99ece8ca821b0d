//! Paired comparison of two evaluations (`sornav-sim compare DIR_A DIR_B`):
//! the same episodes run by two variants or two versions.
//!
//! Episodes are paired by (scene id, episode id); the comparison is refused
//! when the two sets of episodes differ. For SR and SPL it gives the
//! difference A - B of the means, a 95 % percentile bootstrap interval
//! over episodes, and the discordant pairs (A succeeded and B failed, and
//! the reverse), overall and by floors between start and goal (0, 1, 2+,
//! from A's records).
//!
//! # Bootstrap
//! [`BOOTSTRAP_RESAMPLES`] (10 000) resamples of the n pairs, drawn with
//! replacement with a ChaCha8 generator seeded with [`BOOTSTRAP_SEED`]
//! (the same draws for SR and SPL, and for every split); each resample's
//! mean difference is computed and the interval is
//! `[v[r], v[R - 1 - r]]` of the sorted means `v` with
//! `r = round(0.025 (R - 1))`, symmetric so that swapping A and B negates
//! it exactly. The interval is widened to contain the point estimate when
//! it would not (possible only for tiny, very skewed samples). Identical
//! runs give a zero difference with a zero-width interval.
//!
//! Reference: B. Efron and R. J. Tibshirani, *An Introduction to the
//! Bootstrap* (1993), ch. 13 (percentile intervals).

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::figures::FigureError;
use crate::harness::{self, HarnessError};
use crate::record::EpisodeRecord;
use crate::summary::{FLOOR_BINS, floor_bin};

/// Resamples of the bootstrap.
pub const BOOTSTRAP_RESAMPLES: usize = 10_000;
/// Seed of the bootstrap's generator.
pub const BOOTSTRAP_SEED: u64 = 0x5EED_C0DE;

/// Why a comparison failed.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// Reading an evaluation failed.
    #[error(transparent)]
    Harness(#[from] HarnessError),
    /// The variant to compare is not (unambiguously) in a directory.
    #[error("{dir}: {message}")]
    Variant {
        /// The directory.
        dir: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The two runs do not hold the same episodes.
    #[error(
        "the runs hold different episodes: {only_a} only in A (e.g. {example_a}), {only_b} only in B (e.g. {example_b}); compare runs of the same episodes"
    )]
    DifferentEpisodes {
        /// Episodes only in A.
        only_a: usize,
        /// Episodes only in B.
        only_b: usize,
        /// One of them (`scene/episode`), or `-`.
        example_a: String,
        /// One of them, or `-`.
        example_b: String,
    },
    /// No episode to compare.
    #[error("no episodes to compare")]
    Empty,
    /// Writing the outputs failed.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The system's message.
        message: String,
    },
    /// The figure could not be drawn.
    #[error(transparent)]
    Figure(#[from] FigureError),
}

/// Difference A - B of a per-episode metric.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Difference {
    /// Mean of A minus mean of B.
    pub estimate: f64,
    /// 95 % percentile bootstrap interval.
    pub ci95: (f64, f64),
}

/// The paired comparison of a set of episodes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PairedStats {
    /// Pairs.
    pub episodes: u64,
    /// SR of A.
    pub success_rate_a: f64,
    /// SR of B.
    pub success_rate_b: f64,
    /// SPL of A.
    pub spl_a: f64,
    /// SPL of B.
    pub spl_b: f64,
    /// SR(A) - SR(B).
    pub success_rate_diff: Difference,
    /// SPL(A) - SPL(B).
    pub spl_diff: Difference,
    /// Pairs where A succeeded and B failed.
    pub a_only_success: u64,
    /// Pairs where B succeeded and A failed.
    pub b_only_success: u64,
}

/// A split of the comparison by floors between start and goal.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FloorSplit {
    /// `0`, `1` or `2+`.
    pub floors: String,
    /// The comparison on those episodes.
    pub stats: PairedStats,
}

/// The result of [`compare`] (`compare.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// Directory of A.
    pub dir_a: PathBuf,
    /// Variant of A.
    pub variant_a: String,
    /// Directory of B.
    pub dir_b: PathBuf,
    /// Variant of B.
    pub variant_b: String,
    /// Bootstrap resamples.
    pub resamples: usize,
    /// Bootstrap seed.
    pub seed: u64,
    /// All paired episodes.
    pub overall: PairedStats,
    /// By floors between start and goal (0, 1, 2+).
    pub by_floors: Vec<FloorSplit>,
}

/// Mean of `values` (0 for none), summed left to right.
fn mean(values: &[f64]) -> f64 {
    if values.is_empty() {
        0.0
    } else {
        values.iter().sum::<f64>() / values.len() as f64
    }
}

/// Percentile bootstrap of the means of several per-pair series (see the
/// module docs); every series sees the same resamples.
///
/// # Complexity
/// O(R n) for R resamples of n pairs, plus O(R log R) per series.
pub fn bootstrap(series: &[&[f64]], resamples: usize, seed: u64) -> Vec<Difference> {
    let n = series.first().map_or(0, |s| s.len());
    let estimates: Vec<f64> = series.iter().map(|s| mean(s)).collect();
    if n == 0 || resamples == 0 {
        return estimates
            .iter()
            .map(|&e| Difference {
                estimate: e,
                ci95: (e, e),
            })
            .collect();
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut means = vec![Vec::with_capacity(resamples); series.len()];
    let mut idx = vec![0usize; n];
    for _ in 0..resamples {
        for i in &mut idx {
            *i = rng.random_range(0..n);
        }
        for (s, m) in series.iter().zip(means.iter_mut()) {
            m.push(idx.iter().map(|&i| s[i]).sum::<f64>() / n as f64);
        }
    }
    let r = (0.025 * (resamples - 1) as f64).round() as usize;
    means
        .into_iter()
        .zip(estimates)
        .map(|(mut m, e)| {
            m.sort_by(f64::total_cmp);
            Difference {
                estimate: e,
                ci95: (m[r].min(e), m[resamples - 1 - r].max(e)),
            }
        })
        .collect()
}

/// The paired statistics of `pairs` (A's record, B's record).
pub fn paired_stats(
    pairs: &[(&EpisodeRecord, &EpisodeRecord)],
    resamples: usize,
    seed: u64,
) -> PairedStats {
    let s = |r: &EpisodeRecord| f64::from(u8::from(r.result.success));
    let (mut sa, mut sb, mut pa, mut pb, mut ds, mut dp) =
        (vec![], vec![], vec![], vec![], vec![], vec![]);
    for (a, b) in pairs {
        sa.push(s(a));
        sb.push(s(b));
        pa.push(a.result.spl);
        pb.push(b.result.spl);
        ds.push(s(a) - s(b));
        dp.push(a.result.spl - b.result.spl);
    }
    let d = bootstrap(&[&ds, &dp], resamples, seed);
    PairedStats {
        episodes: pairs.len() as u64,
        success_rate_a: mean(&sa),
        success_rate_b: mean(&sb),
        spl_a: mean(&pa),
        spl_b: mean(&pb),
        success_rate_diff: d[0],
        spl_diff: d[1],
        a_only_success: pairs
            .iter()
            .filter(|(a, b)| a.result.success && !b.result.success)
            .count() as u64,
        b_only_success: pairs
            .iter()
            .filter(|(a, b)| !a.result.success && b.result.success)
            .count() as u64,
    }
}

/// The records of `variant` in `dir` (or of its only / first variant).
fn load(dir: &Path, variant: Option<&str>) -> Result<(String, Vec<EpisodeRecord>), CompareError> {
    let records = harness::read_records(&dir.join("episodes.jsonl"))?;
    let variants: Vec<String> = records
        .iter()
        .map(|r| r.variant.clone())
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    let chosen = match variant {
        Some(v) if variants.iter().any(|x| x == v) => v.to_owned(),
        Some(v) => {
            return Err(CompareError::Variant {
                dir: dir.to_path_buf(),
                message: format!("no records of variant '{v}' (has: {})", variants.join(", ")),
            });
        }
        None if variants.len() == 1 => variants[0].clone(),
        None if variants.is_empty() => {
            return Err(CompareError::Variant {
                dir: dir.to_path_buf(),
                message: "no records".into(),
            });
        }
        None => {
            return Err(CompareError::Variant {
                dir: dir.to_path_buf(),
                message: format!(
                    "several variants ({}); choose one with --variant-a / --variant-b",
                    variants.join(", ")
                ),
            });
        }
    };
    let mine = records
        .into_iter()
        .filter(|r| r.variant == chosen)
        .collect();
    Ok((chosen, mine))
}

/// Compares variant `variant_a` of `dir_a` with `variant_b` of `dir_b`
/// (each may be omitted when the directory holds one variant).
///
/// # Errors
/// [`CompareError`] when a directory cannot be read, the variant is
/// ambiguous or missing, or the episode sets differ.
///
/// # Complexity
/// O(n log n + R n) for n episodes and R resamples (times 4 with the
/// splits).
pub fn compare(
    dir_a: &Path,
    variant_a: Option<&str>,
    dir_b: &Path,
    variant_b: Option<&str>,
) -> Result<Comparison, CompareError> {
    let (va, ra) = load(dir_a, variant_a)?;
    let (vb, rb) = load(dir_b, variant_b)?;
    let key = |r: &EpisodeRecord| (r.result.scene_id.clone(), r.result.episode_id.clone());
    let ma: BTreeMap<_, &EpisodeRecord> = ra.iter().map(|r| (key(r), r)).collect();
    let mb: BTreeMap<_, &EpisodeRecord> = rb.iter().map(|r| (key(r), r)).collect();
    let only_a: Vec<_> = ma.keys().filter(|k| !mb.contains_key(*k)).collect();
    let only_b: Vec<_> = mb.keys().filter(|k| !ma.contains_key(*k)).collect();
    if !only_a.is_empty() || !only_b.is_empty() {
        let ex = |v: &[&(String, String)]| {
            v.first()
                .map_or("-".to_owned(), |k| format!("{}/{}", k.0, k.1))
        };
        return Err(CompareError::DifferentEpisodes {
            only_a: only_a.len(),
            only_b: only_b.len(),
            example_a: ex(&only_a),
            example_b: ex(&only_b),
        });
    }
    if ma.is_empty() {
        return Err(CompareError::Empty);
    }
    let pairs: Vec<(&EpisodeRecord, &EpisodeRecord)> =
        ma.iter().map(|(k, a)| (*a, mb[k])).collect();
    Ok(Comparison {
        dir_a: dir_a.to_path_buf(),
        variant_a: va,
        dir_b: dir_b.to_path_buf(),
        variant_b: vb,
        resamples: BOOTSTRAP_RESAMPLES,
        seed: BOOTSTRAP_SEED,
        overall: paired_stats(&pairs, BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED),
        by_floors: split_by_floors(&pairs, BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED),
    })
}

/// The comparison split by floors between start and goal (A's records).
pub fn split_by_floors(
    pairs: &[(&EpisodeRecord, &EpisodeRecord)],
    resamples: usize,
    seed: u64,
) -> Vec<FloorSplit> {
    FLOOR_BINS
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let mine: Vec<_> = pairs
                .iter()
                .copied()
                .filter(|(a, _)| floor_bin(a.result.floors_between) == i)
                .collect();
            FloorSplit {
                floors: b.2.to_owned(),
                stats: paired_stats(&mine, resamples, seed),
            }
        })
        .collect()
}

fn pct(x: f64) -> String {
    format!("{:+.1}", 100.0 * x)
}

impl Comparison {
    /// The markdown table (also printed by `sornav-sim compare`).
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "# Paired comparison: A = {} ({}) vs B = {} ({})\n",
            self.variant_a,
            self.dir_a.display(),
            self.variant_b,
            self.dir_b.display()
        );
        let _ = writeln!(
            s,
            "Episodes paired by (scene, episode). Differences A - B in percentage points with 95 % percentile bootstrap intervals over episodes ({} resamples, seed {:#x}). Discordant pairs: A succeeded and B failed / B succeeded and A failed. Floors between start and goal from the simulator's navmesh levels.\n",
            self.resamples, self.seed
        );
        let _ = writeln!(
            s,
            "| episodes | floors between | n | SR A % | SR B % | SR A - B [95% CI] | SPL A % | SPL B % | SPL A - B [95% CI] | A only success | B only success |\n|---|---|---|---|---|---|---|---|---|---|---|"
        );
        let mut row = |label: &str, st: &PairedStats| {
            let _ = writeln!(
                s,
                "| {label} | {} | {} | {:.1} | {:.1} | {} [{}, {}] | {:.1} | {:.1} | {} [{}, {}] | {} | {} |",
                if label == "all" { "any" } else { label },
                st.episodes,
                100.0 * st.success_rate_a,
                100.0 * st.success_rate_b,
                pct(st.success_rate_diff.estimate),
                pct(st.success_rate_diff.ci95.0),
                pct(st.success_rate_diff.ci95.1),
                100.0 * st.spl_a,
                100.0 * st.spl_b,
                pct(st.spl_diff.estimate),
                pct(st.spl_diff.ci95.0),
                pct(st.spl_diff.ci95.1),
                st.a_only_success,
                st.b_only_success
            );
        };
        row("all", &self.overall);
        for f in &self.by_floors {
            row(&f.floors, &f.stats);
        }
        s
    }

    /// Writes `compare.json`, `compare.md` and `figures/paired_difference.png`
    /// into `out`; returns the markdown's path.
    ///
    /// # Errors
    /// [`CompareError::Io`] or [`CompareError::Figure`].
    pub fn write(&self, out: &Path) -> Result<PathBuf, CompareError> {
        let io = |path: &Path, e: &dyn std::fmt::Display| CompareError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let figs = out.join("figures");
        std::fs::create_dir_all(&figs).map_err(|e| io(&figs, &e))?;
        let json = out.join("compare.json");
        let text = serde_json::to_string_pretty(self).map_err(|e| io(&json, &e))?;
        crate::output::write_file(&json, text.as_bytes()).map_err(|e| io(&json, &e))?;
        crate::output::replace_with(&figs.join("paired_difference.png"), |tmp| {
            crate::figures::paired_difference(tmp, self)
        })?;
        let md = out.join("compare.md");
        let text = format!(
            "{}\n![paired differences](figures/paired_difference.png)\n",
            self.markdown()
        );
        crate::output::write_file(&md, text.as_bytes()).map_err(|e| io(&md, &e))?;
        Ok(md)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use sornav_platform_sim::Outcome;

    fn record(id: usize, success: bool, spl: f64, floors: usize) -> EpisodeRecord {
        let outcome = if success {
            Outcome::Success
        } else {
            Outcome::StepLimit
        };
        crate::record::test_record(&id.to_string(), outcome, spl, floors)
    }

    fn runs() -> impl Strategy<Value = Vec<(bool, f64, bool, f64, usize)>> {
        prop::collection::vec(
            (
                any::<bool>(),
                0.0f64..=1.0,
                any::<bool>(),
                0.0f64..=1.0,
                0usize..4,
            ),
            1..40,
        )
    }

    fn build(v: &[(bool, f64, bool, f64, usize)]) -> (Vec<EpisodeRecord>, Vec<EpisodeRecord>) {
        let a = v
            .iter()
            .enumerate()
            .map(|(i, e)| record(i, e.0, e.1, e.4))
            .collect();
        let b = v
            .iter()
            .enumerate()
            .map(|(i, e)| record(i, e.2, e.3, e.4))
            .collect();
        (a, b)
    }

    fn pairs<'a>(
        a: &'a [EpisodeRecord],
        b: &'a [EpisodeRecord],
    ) -> Vec<(&'a EpisodeRecord, &'a EpisodeRecord)> {
        a.iter().zip(b).collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        #[test]
        fn interval_contains_the_estimate(v in runs()) {
            let (a, b) = build(&v);
            let st = paired_stats(&pairs(&a, &b), 500, 7);
            for d in [st.success_rate_diff, st.spl_diff] {
                prop_assert!(d.ci95.0 <= d.estimate && d.estimate <= d.ci95.1, "{d:?}");
                prop_assert!(d.ci95.0 >= -1.0 && d.ci95.1 <= 1.0);
            }
            prop_assert_eq!(st.a_only_success + st.b_only_success,
                v.iter().filter(|e| e.0 != e.2).count() as u64);
        }

        #[test]
        fn identical_runs_differ_by_zero(v in runs()) {
            let (a, _) = build(&v);
            let st = paired_stats(&pairs(&a, &a), 500, 7);
            for d in [st.success_rate_diff, st.spl_diff] {
                prop_assert_eq!(d.estimate, 0.0);
                prop_assert_eq!(d.ci95, (0.0, 0.0));
            }
            prop_assert_eq!((st.a_only_success, st.b_only_success), (0, 0));
        }

        #[test]
        fn swapping_negates_everything(v in runs()) {
            let (a, b) = build(&v);
            let ab = paired_stats(&pairs(&a, &b), 500, 7);
            let ba = paired_stats(&pairs(&b, &a), 500, 7);
            for (x, y) in [(ab.success_rate_diff, ba.success_rate_diff), (ab.spl_diff, ba.spl_diff)] {
                prop_assert_eq!(x.estimate, -y.estimate);
                prop_assert_eq!(x.ci95, (-y.ci95.1, -y.ci95.0));
            }
            prop_assert_eq!((ab.a_only_success, ab.b_only_success), (ba.b_only_success, ba.a_only_success));
            prop_assert_eq!((ab.success_rate_a, ab.spl_a), (ba.success_rate_b, ba.spl_b));
            let (fa, fb) = (split_by_floors(&pairs(&a, &b), 200, 7), split_by_floors(&pairs(&b, &a), 200, 7));
            for (x, y) in fa.iter().zip(&fb) {
                prop_assert_eq!(x.stats.episodes, y.stats.episodes);
                prop_assert_eq!(x.stats.success_rate_diff.estimate, -y.stats.success_rate_diff.estimate);
            }
            prop_assert_eq!(fa.iter().map(|f| f.stats.episodes).sum::<u64>(), v.len() as u64);
        }
    }

    #[test]
    fn bootstrap_of_a_known_difference() {
        // 30 of 100 pairs: A succeeded, B failed; the rest tie.
        let d: Vec<f64> = (0..100).map(|i| f64::from(u8::from(i < 30))).collect();
        let r = bootstrap(&[&d], BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED)[0];
        assert!((r.estimate - 0.3).abs() < 1e-12);
        // normal approximation: 0.3 +- 1.96 sqrt(0.21 / 100) = [0.21, 0.39]
        assert!(
            (r.ci95.0 - 0.21).abs() < 0.03 && (r.ci95.1 - 0.39).abs() < 0.03,
            "{r:?}"
        );
        assert_eq!(bootstrap(&[&[]], 10, 1)[0].ci95, (0.0, 0.0));
    }
}
