//! Held-out evaluation of the prior: ROC AUC of `P(target | other objects)`
//! for target presence in HM3D val regions.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::hm3d::{Hm3dRegion, Split};
use crate::prior::CooccurrencePrior;

/// Area under the ROC curve of `scores` (score, is positive): the probability
/// that a random positive outranks a random negative, ties counting one half
/// (Mann-Whitney U / (P N)).
///
/// # Returns
/// `None` without at least one positive and one negative, or with a NaN
/// score.
///
/// # Algorithm
/// Sort by score, give tied scores their mean rank, sum positive ranks.
///
/// # Complexity
/// O(n log n).
///
/// # Examples
/// ```
/// use sornav_supervisor::roc_auc;
/// assert_eq!(roc_auc(&[(0.9, true), (0.1, false)]), Some(1.0));
/// assert_eq!(roc_auc(&[(0.5, true), (0.5, false)]), Some(0.5));
/// ```
pub fn roc_auc(scores: &[(f64, bool)]) -> Option<f64> {
    if scores.iter().any(|(s, _)| s.is_nan()) {
        return None;
    }
    let positives = scores.iter().filter(|(_, y)| *y).count();
    let negatives = scores.len() - positives;
    if positives == 0 || negatives == 0 {
        return None;
    }
    let mut sorted: Vec<(f64, bool)> = scores.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut rank_sum = 0.0;
    let mut i = 0;
    while i < sorted.len() {
        let mut j = i;
        while j < sorted.len() && sorted[j].0 == sorted[i].0 {
            j += 1;
        }
        // ranks i+1 ..= j, mean (i + 1 + j) / 2
        let mean_rank = (i + 1 + j) as f64 / 2.0;
        rank_sum += mean_rank * sorted[i..j].iter().filter(|(_, y)| *y).count() as f64;
        i = j;
    }
    let p = positives as f64;
    Some((rank_sum - p * (p + 1.0) / 2.0) / (p * negatives as f64))
}

/// AUC of one target category.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TargetAuc {
    /// Regions holding the target.
    pub positives: usize,
    /// Regions without it.
    pub negatives: usize,
    /// ROC AUC (`None` when one class is empty).
    pub auc: Option<f64>,
}

/// ROC AUC per target of the prior's posterior on the regions of `split`.
/// Each region is scored from its *other* labels (the target's own label is
/// removed, since observing it is what the target gate is for).
///
/// # Complexity
/// O(t R (m log V + log R)) for t targets, R regions of m labels.
pub fn evaluate_prior<'a>(
    prior: &CooccurrencePrior,
    regions: impl IntoIterator<Item = &'a Hm3dRegion>,
    split: Split,
    targets: &[&str],
) -> BTreeMap<String, TargetAuc> {
    let regions: Vec<&Hm3dRegion> = regions.into_iter().filter(|r| r.split == split).collect();
    let mut out = BTreeMap::new();
    for &g in targets {
        let mut scores = Vec::with_capacity(regions.len());
        for r in &regions {
            let present = r.labels.contains(g);
            let others = r.labels.iter().map(String::as_str).filter(|l| *l != g);
            if let Some(post) = prior.posterior(g, others) {
                scores.push((post.probability, present));
            }
        }
        let positives = scores.iter().filter(|(_, y)| *y).count();
        out.insert(
            g.to_owned(),
            TargetAuc {
                positives,
                negatives: scores.len() - positives,
                auc: roc_auc(&scores),
            },
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn brute(scores: &[(f64, bool)]) -> Option<f64> {
        let pos: Vec<f64> = scores.iter().filter(|s| s.1).map(|s| s.0).collect();
        let neg: Vec<f64> = scores.iter().filter(|s| !s.1).map(|s| s.0).collect();
        if pos.is_empty() || neg.is_empty() {
            return None;
        }
        let mut w = 0.0;
        for p in &pos {
            for q in &neg {
                w += if p > q {
                    1.0
                } else if p == q {
                    0.5
                } else {
                    0.0
                };
            }
        }
        Some(w / (pos.len() * neg.len()) as f64)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        #[test]
        fn auc_matches_pairwise_reference(v in prop::collection::vec((0u8..8, any::<bool>()), 0..40)) {
            let scores: Vec<(f64, bool)> = v.iter().map(|&(s, y)| (f64::from(s) / 4.0, y)).collect();
            let fast = roc_auc(&scores);
            let slow = brute(&scores);
            prop_assert_eq!(fast.is_some(), slow.is_some());
            if let (Some(a), Some(b)) = (fast, slow) {
                prop_assert!((a - b).abs() < 1e-12);
                prop_assert!((0.0..=1.0).contains(&a));
            }
        }
    }

    #[test]
    fn nan_scores_are_rejected() {
        assert_eq!(roc_auc(&[(f64::NAN, true), (0.0, false)]), None);
    }
}
