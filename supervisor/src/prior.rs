//! The commonsense prior: how likely a target category is present in a region
//! given the objects observed there, derived from HM3D-Semantics train scenes.
//!
//! # Model
//! A smoothed, evidence-tempered naive-Bayes model over *observed* labels.
//! For target `g` and the set `L` of known, distinct labels observed in a
//! region (`g` itself excluded), with `N` train regions, `n_g` regions holding
//! `g`, `n_l` holding `l`, `n_gl` holding both and Laplace smoothing `a`:
//!
//! ```text
//! llr(l)  = ln((n_gl + a) / (n_g + 2a)) - ln((n_l - n_gl + a) / (N - n_g + 2a))
//! logit   = ln((n_g + a) / (N - n_g + a)) + sum_{l in L} llr(l) / |L|^beta
//! P(g | L) = 1 / (1 + exp(-logit))
//! ```
//!
//! Only present labels count: an object not (yet) seen is missing evidence,
//! not evidence of absence. The tempering exponent `beta` (0.5) damps the
//! over-confidence of naive Bayes with many correlated labels; it was chosen
//! by 5-fold cross-validation over train scenes (mean ROC AUC 0.893 against
//! 0.886 for plain naive Bayes, `beta = 0`, and 0.870 for the mean
//! log-likelihood ratio, `beta = 1`). L2-regularised logistic regression
//! ranks fully annotated regions slightly better but treats every unseen
//! label as absent, so on the robot's partial views (3 objects seen) it
//! declares false conflicts in 16-36 % of the regions holding the target,
//! against 0.7 % here (`examples/compare_models.rs`, table in the README).
//! The held-out val AUC is in the README and reproduced by
//! `examples/prior_auc.rs`.
//!
//! When `g` itself is among the observed labels the posterior is 1.
//!
//! # Data
//! The embedded table ([`CooccurrencePrior::embedded`]) is
//! `data/hm3d_cooccurrence_prior.json`, regenerated exactly by
//! `cargo run -p sornav-supervisor --example build_prior -- ../shared/data/hm3d-sem-stats`.
//! Derived from HM3D-Semantics, Yadav et al. 2023.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::OnceLock;

use serde::{Deserialize, Serialize};

use crate::error::SupervisorError;
use crate::hm3d::{Hm3dRegion, Split};
use crate::label::{OBJECTNAV_CATEGORIES, normalize_label};

/// Attribution stored in the derived table.
pub const ATTRIBUTION: &str = "Derived from HM3D-Semantics v0.2 region statistics (HM3D-Semantics, Yadav et al. 2023; matterport/habitat-matterport-3dresearch), train scenes only; used under the Matterport academic terms.";

/// Additional targets with a row in the table: the MP3D ObjectNav
/// categories that exist in the HM3D vocabulary.
pub const MP3D_EXTRA_TARGETS: [&str; 13] = [
    "table",
    "picture",
    "cabinet",
    "cushion",
    "chest of drawers",
    "sink",
    "stool",
    "towel",
    "shower",
    "bathtub",
    "counter",
    "fireplace",
    "clothes",
];

const EMBEDDED_JSON: &str = include_str!("../data/hm3d_cooccurrence_prior.json");

/// Settings for deriving a prior from HM3D regions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PriorBuildConfig {
    /// A label enters the vocabulary when it occurs in at least this many
    /// train regions (rarer labels give unreliable ratios).
    pub min_regions: u64,
    /// Laplace smoothing `a`.
    pub smoothing: f64,
    /// Evidence tempering exponent `beta`.
    pub evidence_exponent: f64,
}

impl Default for PriorBuildConfig {
    fn default() -> Self {
        Self {
            min_regions: 15,
            smoothing: 1.0,
            evidence_exponent: 0.5,
        }
    }
}

/// Counts for one target category.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TargetRow {
    /// Train regions holding the target, `n_g`.
    pub regions: u64,
    /// For each vocabulary label, train regions holding both, `n_gl` (zero
    /// entries omitted).
    pub cooccurrence: BTreeMap<String, u64>,
}

/// The derived co-occurrence table and its naive-Bayes posterior.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CooccurrencePrior {
    /// Where the figures come from.
    pub attribution: String,
    /// Number of train scenes used.
    pub train_scenes: u64,
    /// Number of train regions `N`.
    pub train_regions: u64,
    /// Build settings.
    pub config: PriorBuildConfig,
    /// Vocabulary: label -> train regions holding it, `n_l`.
    pub labels: BTreeMap<String, u64>,
    /// Target rows.
    pub targets: BTreeMap<String, TargetRow>,
}

/// The posterior for one target and one context.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Posterior {
    /// `P(target present | observed labels)`, in `[0, 1]`.
    pub probability: f64,
    /// The base rate `P(target present)` with no evidence.
    pub base_rate: f64,
    /// Distinct known labels that contributed (the target itself included).
    pub informative_labels: usize,
    /// Whether the target itself was among the labels.
    pub target_observed: bool,
}

fn sigmoid(z: f64) -> f64 {
    if z >= 0.0 {
        1.0 / (1.0 + (-z).exp())
    } else {
        let e = z.exp();
        e / (1.0 + e)
    }
}

impl CooccurrencePrior {
    /// The table shipped with the crate (parsed once).
    ///
    /// # Panics
    /// Never in practice: the embedded file is checked by the crate's tests.
    pub fn embedded() -> &'static CooccurrencePrior {
        static PRIOR: OnceLock<CooccurrencePrior> = OnceLock::new();
        PRIOR.get_or_init(|| {
            Self::from_json(EMBEDDED_JSON).expect("embedded prior table is valid (crate tests)")
        })
    }

    /// The embedded table's exact JSON text.
    pub fn embedded_json() -> &'static str {
        EMBEDDED_JSON
    }

    /// Parses and checks a table.
    ///
    /// # Errors
    /// [`SupervisorError::MalformedData`] when the JSON does not parse or the
    /// counts are inconsistent (a co-occurrence above a marginal, a marginal
    /// above `N`, a non-finite or non-positive smoothing).
    ///
    /// # Complexity
    /// O(size of the table).
    pub fn from_json(text: &str) -> Result<Self, SupervisorError> {
        let prior: Self = serde_json::from_str(text)
            .map_err(|e| SupervisorError::MalformedData(e.to_string()))?;
        prior.check()?;
        Ok(prior)
    }

    fn check(&self) -> Result<(), SupervisorError> {
        let bad = |m: String| Err(SupervisorError::MalformedData(m));
        let c = &self.config;
        if !(c.smoothing.is_finite() && c.smoothing > 0.0) {
            return bad(format!("smoothing {} must be finite and > 0", c.smoothing));
        }
        if !(c.evidence_exponent.is_finite() && c.evidence_exponent >= 0.0) {
            return bad(format!(
                "evidence exponent {} must be finite and >= 0",
                c.evidence_exponent
            ));
        }
        if self.train_regions == 0 {
            return bad("no train regions".into());
        }
        for (l, &n) in &self.labels {
            if n > self.train_regions {
                return bad(format!("label {l:?}: {n} regions > N"));
            }
        }
        for (g, row) in &self.targets {
            if row.regions > self.train_regions {
                return bad(format!("target {g:?}: {} regions > N", row.regions));
            }
            for (l, &n) in &row.cooccurrence {
                let Some(&nl) = self.labels.get(l) else {
                    return bad(format!("target {g:?}: label {l:?} outside the vocabulary"));
                };
                if n > nl || n > row.regions {
                    return bad(format!(
                        "target {g:?}, label {l:?}: co-occurrence above a marginal"
                    ));
                }
            }
        }
        Ok(())
    }

    /// Derives the table from the train regions of `regions` (val regions are
    /// ignored, whatever the caller passes).
    ///
    /// Targets: the six ObjectNav categories plus [`MP3D_EXTRA_TARGETS`] that
    /// are in the vocabulary.
    ///
    /// # Errors
    /// [`SupervisorError::MalformedData`] when there is no train region or the
    /// configuration is invalid.
    ///
    /// # Complexity
    /// O(R * (m + t m)) for R regions of at most m labels and t targets.
    pub fn build<'a>(
        regions: impl IntoIterator<Item = &'a Hm3dRegion>,
        config: PriorBuildConfig,
    ) -> Result<Self, SupervisorError> {
        let train: Vec<&Hm3dRegion> = regions
            .into_iter()
            .filter(|r| r.split == Split::Train)
            .collect();
        let scenes: BTreeSet<&str> = train.iter().map(|r| r.scene.as_str()).collect();
        let mut counts: BTreeMap<String, u64> = BTreeMap::new();
        for r in &train {
            for l in &r.labels {
                *counts.entry(l.clone()).or_default() += 1;
            }
        }
        counts.retain(|_, n| *n >= config.min_regions);
        let mut targets = BTreeMap::new();
        for g in OBJECTNAV_CATEGORIES.iter().chain(MP3D_EXTRA_TARGETS.iter()) {
            if !counts.contains_key(*g) {
                continue;
            }
            let mut row = TargetRow {
                regions: 0,
                cooccurrence: BTreeMap::new(),
            };
            for r in train.iter().filter(|r| r.labels.contains(*g)) {
                row.regions += 1;
                for l in r.labels.iter().filter(|l| counts.contains_key(*l)) {
                    *row.cooccurrence.entry(l.clone()).or_default() += 1;
                }
            }
            targets.insert((*g).to_owned(), row);
        }
        let prior = Self {
            attribution: ATTRIBUTION.to_owned(),
            train_scenes: scenes.len() as u64,
            train_regions: train.len() as u64,
            config,
            labels: counts,
            targets,
        };
        prior.check()?;
        Ok(prior)
    }

    /// The table as pretty JSON with a trailing newline (the committed form).
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).unwrap_or_default();
        s.push('\n');
        s
    }

    /// Whether `target` (any spelling) has a row.
    pub fn knows_target(&self, target: &str) -> bool {
        normalize_label(target).is_some_and(|g| self.targets.contains_key(&g))
    }

    /// `P(target present | labels)` for a region where `labels` were observed
    /// (any spelling; duplicates and unknown labels are ignored).
    ///
    /// # Returns
    /// `None` when the target has no row in the table (no knowledge).
    ///
    /// # Complexity
    /// O(m log m + m log V) for m labels and a vocabulary of V labels.
    pub fn posterior<'a>(
        &self,
        target: &str,
        labels: impl IntoIterator<Item = &'a str>,
    ) -> Option<Posterior> {
        let g = normalize_label(target)?;
        let row = self.targets.get(&g)?;
        let a = self.config.smoothing;
        let n = self.train_regions as f64;
        let ng = row.regions as f64;
        let prior_logit = ((ng + a) / (n - ng + a)).ln();
        let base_rate = sigmoid(prior_logit);
        let known: BTreeSet<String> = labels
            .into_iter()
            .filter_map(normalize_label)
            .filter(|l| self.labels.contains_key(l))
            .collect();
        if known.contains(&g) {
            return Some(Posterior {
                probability: 1.0,
                base_rate,
                informative_labels: known.len(),
                target_observed: true,
            });
        }
        let mut sum = 0.0;
        for l in &known {
            let nl = self.labels[l] as f64;
            let ngl = row.cooccurrence.get(l).copied().unwrap_or(0) as f64;
            sum += ((ngl + a) / (ng + 2.0 * a)).ln() - ((nl - ngl + a) / (n - ng + 2.0 * a)).ln();
        }
        let k = known.len();
        let logit = if k == 0 {
            prior_logit
        } else {
            prior_logit + sum / (k as f64).powf(self.config.evidence_exponent)
        };
        Some(Posterior {
            probability: sigmoid(logit),
            base_rate,
            informative_labels: k,
            target_observed: false,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_table_is_valid_and_covers_objectnav() {
        let p = CooccurrencePrior::embedded();
        for g in OBJECTNAV_CATEGORIES {
            assert!(p.knows_target(g), "{g}");
        }
        assert!(p.train_regions > 1000);
        assert_eq!(p.to_json(), CooccurrencePrior::embedded_json());
    }

    #[test]
    fn inconsistent_tables_are_rejected() {
        let mut p = CooccurrencePrior::embedded().clone();
        p.targets.get_mut("toilet").unwrap().regions = p.train_regions + 1;
        assert!(CooccurrencePrior::from_json(&p.to_json()).is_err());
        let mut p = CooccurrencePrior::embedded().clone();
        p.config.smoothing = f64::NAN;
        assert!(CooccurrencePrior::from_json(&serde_json::to_string(&p).unwrap()).is_err());
        assert!(CooccurrencePrior::from_json("{").is_err());
    }

    fn region(scene: &str, split: Split, labels: &[&str]) -> Hm3dRegion {
        Hm3dRegion {
            scene: scene.into(),
            region: 0,
            split,
            labels: labels.iter().map(|l| (*l).to_owned()).collect(),
        }
    }

    #[test]
    fn build_counts_match_a_hand_count_and_ignore_val() {
        let regions = [
            region("a", Split::Train, &["toilet", "sink", "towel"]),
            region("a", Split::Train, &["bed", "lamp"]),
            region("b", Split::Train, &["toilet", "sink"]),
            region("b", Split::Train, &["sink", "lamp", "bed"]),
            region("c", Split::Train, &["rare"]),
            // Val regions must not count at all.
            region("v", Split::Val, &["toilet", "bed", "sink", "lamp"]),
            region("v", Split::Val, &["toilet", "rare", "rare2"]),
        ];
        let config = PriorBuildConfig {
            min_regions: 2,
            ..PriorBuildConfig::default()
        };
        let p = CooccurrencePrior::build(regions.iter(), config).unwrap();
        assert_eq!((p.train_scenes, p.train_regions), (3, 5));
        // Labels in >= 2 train regions: toilet 2, sink 3, bed 2, lamp 2
        // (towel 1 and rare 1 are dropped; val counts nothing).
        let labels: Vec<(&str, u64)> = p.labels.iter().map(|(l, n)| (l.as_str(), *n)).collect();
        assert_eq!(
            labels,
            [("bed", 2), ("lamp", 2), ("sink", 3), ("toilet", 2)]
        );
        // Target rows: only ObjectNav/MP3D categories in the vocabulary.
        let targets: Vec<&str> = p.targets.keys().map(String::as_str).collect();
        assert_eq!(targets, ["bed", "sink", "toilet"]);
        let toilet = &p.targets["toilet"];
        assert_eq!(toilet.regions, 2);
        let co: Vec<(&str, u64)> = toilet
            .cooccurrence
            .iter()
            .map(|(l, n)| (l.as_str(), *n))
            .collect();
        assert_eq!(co, [("sink", 2), ("toilet", 2)]);
        let bed = &p.targets["bed"];
        assert_eq!(bed.regions, 2);
        assert_eq!(bed.cooccurrence.get("lamp"), Some(&2));
        assert_eq!(bed.cooccurrence.get("sink"), Some(&1));
        assert_eq!(bed.cooccurrence.get("toilet"), None);
        // A val-only build has nothing to learn from.
        assert!(
            CooccurrencePrior::build(regions[5..].iter(), PriorBuildConfig::default()).is_err()
        );
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]

        /// `posterior` equals a direct transcription of the module's formula
        /// on the embedded table (unknown labels, other spellings and
        /// duplicates in the input are ignored).
        #[test]
        fn posterior_matches_the_documented_formula(
            t in 0usize..6,
            picks in proptest::collection::vec(0usize..400, 0..12),
            noise in proptest::collection::vec(0usize..3, 0..4),
        ) {
            let p = CooccurrencePrior::embedded();
            let g = OBJECTNAV_CATEGORIES[t];
            let vocab: Vec<&str> = p.labels.keys().map(String::as_str).collect();
            let mut input: Vec<String> = picks
                .iter()
                .map(|&k| vocab[k % vocab.len()].to_owned())
                .collect();
            // Duplicates, another spelling, unknown and structural labels.
            input.extend(input.first().cloned());
            for &k in &noise {
                input.push(["mystery gadget", "WALL", "Door_Frame"][k].to_owned());
            }
            if let Some(first) = input.first().cloned() {
                input.push(first.to_uppercase().replace(' ', "_"));
            }
            let post = p.posterior(g, input.iter().map(String::as_str)).unwrap();

            let distinct: BTreeSet<&str> = picks.iter().map(|&k| vocab[k % vocab.len()]).collect();
            let a = p.config.smoothing;
            let n = p.train_regions as f64;
            let row = &p.targets[g];
            let ng = row.regions as f64;
            let prior_logit = ((ng + a) / (n - ng + a)).ln();
            proptest::prop_assert_eq!(post.informative_labels, distinct.len());
            if distinct.contains(g) {
                proptest::prop_assert!(post.target_observed);
                proptest::prop_assert_eq!(post.probability, 1.0);
            } else {
                let llr: f64 = distinct
                    .iter()
                    .map(|l| {
                        let nl = p.labels[*l] as f64;
                        let ngl = row.cooccurrence.get(*l).copied().unwrap_or(0) as f64;
                        ((ngl + a) / (ng + 2.0 * a)).ln() - ((nl - ngl + a) / (n - ng + 2.0 * a)).ln()
                    })
                    .sum();
                let k = distinct.len() as f64;
                let logit = if distinct.is_empty() {
                    prior_logit
                } else {
                    prior_logit + llr / k.powf(p.config.evidence_exponent)
                };
                let expected = 1.0 / (1.0 + (-logit).exp());
                proptest::prop_assert!((post.probability - expected).abs() <= 1e-12);
                proptest::prop_assert!((0.0..=1.0).contains(&post.probability));
            }
            proptest::prop_assert!((post.base_rate - 1.0 / (1.0 + (-prior_logit).exp())).abs() <= 1e-15);
        }
    }

    #[test]
    fn empty_context_gives_the_base_rate_and_unknown_target_none() {
        let p = CooccurrencePrior::embedded();
        let post = p.posterior("toilet", []).unwrap();
        assert_eq!(post.probability, post.base_rate);
        assert_eq!(post.informative_labels, 0);
        assert!(p.posterior("spaceship", ["bed"]).is_none());
        let seen = p.posterior("Toilet", ["toilet", "bed"]).unwrap();
        assert!(seen.target_observed && seen.probability == 1.0);
    }
}
