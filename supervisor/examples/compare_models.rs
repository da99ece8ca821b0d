//! Model selection for the commonsense prior: tempered naive Bayes (the
//! shipped model, several tempering exponents) against L2-regularised
//! logistic regression over object-presence features (Newton / IRLS with a
//! dense Cholesky solve from faer).
//!
//! ```text
//! cargo run --release -p sornav-supervisor --example compare_models -- ../shared/data/hm3d-sem-stats
//! ```
//!
//! Selection uses 5-fold cross-validation over **train** scenes only; the val
//! column is reported for information (it must not drive the choice).
//! Prints a Markdown table to stderr and one JSON line to stdout.

use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;
use std::process::ExitCode;

use faer::Mat;
use faer::linalg::solvers::Solve;
use sornav_supervisor::{
    CooccurrencePrior, Hm3dRegion, Hm3dStats, OBJECTNAV_CATEGORIES, PriorBuildConfig, Split,
    roc_auc,
};

const FOLDS: usize = 5;

/// A fitted scorer: `P(g | labels)`.
trait Scorer {
    fn score(&self, g: &str, labels: &BTreeSet<String>) -> f64;
}

struct NaiveBayes(CooccurrencePrior);

impl Scorer for NaiveBayes {
    fn score(&self, g: &str, labels: &BTreeSet<String>) -> f64 {
        let others = labels.iter().map(String::as_str).filter(|l| *l != g);
        self.0
            .posterior(g, others)
            .map_or(f64::NAN, |p| p.probability)
    }
}

/// One logistic model per target over binary presence features.
struct Logistic {
    vocab: BTreeMap<String, usize>,
    weights: BTreeMap<String, Vec<f64>>, // [intercept, w_1..w_p]
}

fn sigmoid(z: f64) -> f64 {
    1.0 / (1.0 + (-z).exp())
}

impl Logistic {
    fn features(&self, g: &str, labels: &BTreeSet<String>) -> Vec<usize> {
        labels
            .iter()
            .filter(|l| l.as_str() != g)
            .filter_map(|l| self.vocab.get(l).map(|i| i + 1))
            .collect()
    }

    fn fit(train: &[&Hm3dRegion], lambda: f64) -> Self {
        let mut counts: BTreeMap<String, u64> = BTreeMap::new();
        for r in train {
            for l in &r.labels {
                *counts.entry(l.clone()).or_default() += 1;
            }
        }
        let vocab: BTreeMap<String, usize> = counts
            .into_iter()
            .filter(|(_, n)| *n >= PriorBuildConfig::default().min_regions)
            .enumerate()
            .map(|(i, (l, _))| (l, i))
            .collect();
        let mut model = Logistic {
            vocab,
            weights: BTreeMap::new(),
        };
        let p = model.vocab.len() + 1;
        for g in OBJECTNAV_CATEGORIES {
            let rows: Vec<(Vec<usize>, f64)> = train
                .iter()
                .map(|r| {
                    (
                        model.features(g, &r.labels),
                        f64::from(u8::from(r.labels.contains(g))),
                    )
                })
                .collect();
            let mut w = vec![0.0; p];
            for _ in 0..25 {
                let mut h = Mat::<f64>::zeros(p, p);
                let mut grad = Mat::<f64>::zeros(p, 1);
                for (feats, y) in &rows {
                    let z = w[0] + feats.iter().map(|&j| w[j]).sum::<f64>();
                    let mu = sigmoid(z);
                    let s = (mu * (1.0 - mu)).max(1e-9);
                    let all: Vec<usize> = std::iter::once(0).chain(feats.iter().copied()).collect();
                    for &a in &all {
                        grad[(a, 0)] += mu - y;
                        for &b in &all {
                            h[(a, b)] += s;
                        }
                    }
                }
                for j in 1..p {
                    h[(j, j)] += lambda;
                    grad[(j, 0)] += lambda * w[j];
                }
                h[(0, 0)] += 1e-6;
                let Ok(llt) = h.llt(faer::Side::Lower) else {
                    break;
                };
                llt.solve_in_place(&mut grad);
                let mut step = 0.0f64;
                for (j, wj) in w.iter_mut().enumerate() {
                    *wj -= grad[(j, 0)];
                    step = step.max(grad[(j, 0)].abs());
                }
                if step < 1e-8 {
                    break;
                }
            }
            model.weights.insert(g.to_owned(), w);
        }
        model
    }
}

impl Scorer for Logistic {
    fn score(&self, g: &str, labels: &BTreeSet<String>) -> f64 {
        let w = &self.weights[g];
        sigmoid(w[0] + self.features(g, labels).iter().map(|&j| w[j]).sum::<f64>())
    }
}

/// Mean AUC over the six targets, and per target.
fn evaluate(scored: &BTreeMap<&str, Vec<(f64, bool)>>) -> (f64, Vec<f64>) {
    let per: Vec<f64> = OBJECTNAV_CATEGORIES
        .iter()
        .map(|g| roc_auc(&scored[g]).unwrap_or(f64::NAN))
        .collect();
    (per.iter().sum::<f64>() / per.len() as f64, per)
}

fn score_into(
    model: &dyn Scorer,
    regions: &[&Hm3dRegion],
    out: &mut BTreeMap<&'static str, Vec<(f64, bool)>>,
) {
    for g in OBJECTNAV_CATEGORIES {
        let v = out.entry(g).or_default();
        for r in regions {
            v.push((model.score(g, &r.labels), r.labels.contains(g)));
        }
    }
}

/// splitmix64: a deterministic shuffle without extra dependencies.
fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The robot's situation: only `k` of a region's objects observed. For each
/// val region with at least `k` other known labels, `k` of them are drawn
/// (seeded). Returns (mean AUC, P(conflict | target present),
/// P(conflict | target absent)) with conflict = `P < threshold`.
fn partial_observation(
    model: &dyn Scorer,
    val: &[&Hm3dRegion],
    vocab: &BTreeSet<String>,
    k: usize,
    threshold: f64,
) -> (f64, f64, f64) {
    let mut scored: BTreeMap<&'static str, Vec<(f64, bool)>> = BTreeMap::new();
    let mut state = 0x5EED_u64;
    for g in OBJECTNAV_CATEGORIES {
        let v = scored.entry(g).or_default();
        for r in val {
            let mut others: Vec<&String> = r
                .labels
                .iter()
                .filter(|l| l.as_str() != g && vocab.contains(*l))
                .collect();
            if others.len() < k {
                continue;
            }
            for i in (1..others.len()).rev() {
                let j = (splitmix(&mut state) % (i as u64 + 1)) as usize;
                others.swap(i, j);
            }
            let seen: BTreeSet<String> = others[..k].iter().map(|l| (*l).clone()).collect();
            v.push((model.score(g, &seen), r.labels.contains(g)));
        }
    }
    let (auc, _) = evaluate(&scored);
    let all: Vec<&(f64, bool)> = scored.values().flatten().collect();
    let rate = |present: bool| {
        let group: Vec<_> = all.iter().filter(|(_, y)| *y == present).collect();
        group.iter().filter(|(p, _)| *p < threshold).count() as f64 / group.len().max(1) as f64
    };
    (auc, rate(true), rate(false))
}

fn main() -> ExitCode {
    let Some(dir) = std::env::args_os().nth(1).map(PathBuf::from) else {
        eprintln!("usage: compare_models <hm3d-sem-stats folder>");
        return ExitCode::from(2);
    };
    let stats = match Hm3dStats::read_dir(&dir) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    let train: Vec<&Hm3dRegion> = stats.split(Split::Train).collect();
    let val: Vec<&Hm3dRegion> = stats.split(Split::Val).collect();
    let scenes: Vec<&str> = train
        .iter()
        .map(|r| r.scene.as_str())
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    let fold_of = |scene: &str| scenes.binary_search(&scene).unwrap_or(0) % FOLDS;

    type Fit = Box<dyn Fn(&[&Hm3dRegion]) -> Box<dyn Scorer>>;
    let nb = |beta: f64| -> Fit {
        Box::new(move |rs: &[&Hm3dRegion]| {
            let cfg = PriorBuildConfig {
                evidence_exponent: beta,
                ..PriorBuildConfig::default()
            };
            let prior = CooccurrencePrior::build(rs.iter().copied(), cfg).expect("train regions");
            Box::new(NaiveBayes(prior)) as Box<dyn Scorer>
        })
    };
    let lr = |lambda: f64| -> Fit {
        Box::new(move |rs: &[&Hm3dRegion]| Box::new(Logistic::fit(rs, lambda)) as Box<dyn Scorer>)
    };
    let models: Vec<(String, Fit)> = vec![
        ("naive Bayes, beta = 0".into(), nb(0.0)),
        ("naive Bayes, beta = 0.5 (shipped)".into(), nb(0.5)),
        ("naive Bayes, beta = 1".into(), nb(1.0)),
        ("logistic regression, lambda = 1".into(), lr(1.0)),
        ("logistic regression, lambda = 3".into(), lr(3.0)),
        ("logistic regression, lambda = 10".into(), lr(10.0)),
    ];
    let threshold = sornav_supervisor::CommonsenseConfig::default().conflict_max_posterior;
    let vocab: BTreeSet<String> = CooccurrencePrior::embedded()
        .labels
        .keys()
        .cloned()
        .collect();
    eprintln!(
        "| model | train 5-fold CV mean AUC | val mean AUC | val AUC {} | val, 3 objects seen: mean AUC | conflict rate, target present | conflict rate, target absent |",
        OBJECTNAV_CATEGORIES.join(" / ")
    );
    eprintln!("|---|---|---|---|---|---|---|");
    let mut json = serde_json::Map::new();
    for (name, fit) in &models {
        let mut cv = BTreeMap::new();
        for f in 0..FOLDS {
            let (inner, outer): (Vec<&Hm3dRegion>, Vec<&Hm3dRegion>) =
                train.iter().partition(|r| fold_of(&r.scene) != f);
            let model = fit(&inner);
            score_into(model.as_ref(), &outer, &mut cv);
        }
        let (cv_mean, _) = evaluate(&cv);
        let mut held = BTreeMap::new();
        let full = fit(&train);
        score_into(full.as_ref(), &val, &mut held);
        let (val_mean, per) = evaluate(&held);
        let per_txt: Vec<String> = per.iter().map(|a| format!("{a:.3}")).collect();
        let (p_auc, fc_present, fc_absent) =
            partial_observation(full.as_ref(), &val, &vocab, 3, threshold);
        eprintln!(
            "| {name} | {cv_mean:.3} | {val_mean:.3} | {} | {p_auc:.3} | {fc_present:.3} | {fc_absent:.3} |",
            per_txt.join(" / ")
        );
        json.insert(
            name.clone(),
            serde_json::json!({
                "cv_mean_auc": cv_mean, "val_mean_auc": val_mean, "val_partial3_mean_auc": p_auc,
                "val_partial3_conflict_rate_present": fc_present, "val_partial3_conflict_rate_absent": fc_absent,
            }),
        );
    }
    println!("{}", serde_json::Value::Object(json));
    ExitCode::SUCCESS
}
