//! Golden cases a person would agree with, and properties of the
//! commonsense policy.

use proptest::prelude::*;
use sornav_supervisor::{
    Candidate, CandidateObject, CommonsenseConfig, CommonsensePolicy, ContextObject, ContextPolicy,
    NeverRelocate, PolicyAction, RegionSnapshot, Situation,
};

const NOW: Situation = Situation {
    mission_id: 1,
    elapsed_s: 0.0,
};

fn ctx(labels: &[&str]) -> Vec<ContextObject> {
    labels
        .iter()
        .map(|l| ContextObject::new(*l, 150.0))
        .collect()
}

fn cand(id: u64, d: f64, labels: &[&str]) -> Candidate {
    Candidate {
        floor: 0,
        cluster_id: id,
        distance_m: d,
        context: labels
            .iter()
            .map(|l| CandidateObject::new(*l, 150.0, 2.0))
            .collect(),
    }
}

fn snap(target: &str, local: &[&str], candidates: Vec<Candidate>) -> RegionSnapshot {
    RegionSnapshot {
        target: target.into(),
        local_context: ctx(local),
        candidates,
    }
}

/// A bedroom seen well enough for a conflict: with the observed-subset
/// logistic prior, three bedroom objects alone leave `P(toilet) = 0.06`
/// (HM3D regions with a bed hold a toilet more often than naive Bayes
/// claimed), above the 0.05 conflict threshold; a fourth settles it.
const BEDROOM: &[&str] = &["bed", "wardrobe", "nightstand", "pillow"];

fn bathroom_and_kitchen() -> Vec<Candidate> {
    vec![
        cand(1, 8.0, &["sink", "bathtub", "towel"]),
        cand(2, 5.0, &["refrigerator", "stove", "microwave"]),
    ]
}

#[test]
fn toilet_amid_bedroom_is_a_conflict_and_goes_to_the_bathroom() {
    let mut p = CommonsensePolicy::default();
    let s = snap("toilet", BEDROOM, bathroom_and_kitchen());
    assert!(p.assess(&s).conflict, "{}", p.assess(&s).reason);
    let d = p.decide(&s, &NOW);
    assert_eq!(
        d.action,
        PolicyAction::RelocateCluster { cluster_id: 1 },
        "{}",
        d.reason
    );
    assert!(d.reason.contains("conflict"));
}

#[test]
fn toilet_amid_sink_and_bathtub_is_no_conflict() {
    let mut p = CommonsensePolicy::default();
    let s = snap("toilet", &["sink", "bathtub"], bathroom_and_kitchen());
    assert!(!p.assess(&s).conflict);
    assert_eq!(p.decide(&s, &NOW).action, PolicyAction::ContinueExplore);
    // Even with more bathroom evidence (enough objects): still no conflict.
    let s = snap(
        "toilet",
        &["sink", "bathtub", "towel", "mirror"],
        bathroom_and_kitchen(),
    );
    assert!(!p.assess(&s).conflict);
}

#[test]
fn empty_or_tiny_context_is_no_conflict() {
    let mut p = CommonsensePolicy::default();
    for local in [&[][..], &["bed"][..], &["bed", "wardrobe"][..]] {
        let s = snap("toilet", local, bathroom_and_kitchen());
        let d = p.decide(&s, &NOW);
        assert_eq!(
            d.action,
            PolicyAction::ContinueExplore,
            "{local:?}: {}",
            d.reason
        );
    }
    // Objects with too little support are no evidence either.
    let mut s = snap("toilet", BEDROOM, bathroom_and_kitchen());
    for o in &mut s.local_context {
        o.support = 3.0;
    }
    assert_eq!(p.decide(&s, &NOW).action, PolicyAction::ContinueExplore);
}

#[test]
fn mixed_evidence_keeps_exploring() {
    let p = CommonsensePolicy::default();
    // A bedroom with an en-suite sink and mirror.
    let s = snap("toilet", &["bed", "sink", "mirror"], bathroom_and_kitchen());
    assert!(!p.assess(&s).conflict, "{}", p.assess(&s).reason);
}

#[test]
fn tv_in_a_bathroom_conflicts_and_goes_to_the_living_room() {
    let mut p = CommonsensePolicy::default();
    let s = snap(
        "tv_monitor",
        &["toilet", "sink", "bathtub", "towel"],
        vec![
            cand(3, 12.0, &["couch", "coffee table", "rug"]),
            cand(4, 4.0, &["toilet paper", "shower"]),
        ],
    );
    assert_eq!(
        p.decide(&s, &NOW).action,
        PolicyAction::RelocateCluster { cluster_id: 3 }
    );
}

#[test]
fn conflict_without_a_better_candidate_keeps_exploring() {
    let mut p = CommonsensePolicy::default();
    let s = snap(
        "toilet",
        BEDROOM,
        vec![cand(5, 3.0, &["bed", "dresser", "pillow"])],
    );
    assert!(p.assess(&s).conflict);
    let d = p.decide(&s, &NOW);
    assert_eq!(d.action, PolicyAction::ContinueExplore);
    assert!(d.reason.contains("margin"), "{}", d.reason);
}

#[test]
fn an_unexplored_floor_holds_several_regions() {
    let mut p = CommonsensePolicy::default();
    let floor_up = Candidate {
        floor: 1,
        ..cand(2, 6.0, &[])
    };
    let s = snap(
        "sofa",
        &["toilet", "sink", "bathtub"],
        vec![cand(1, 3.0, &[]), floor_up],
    );
    assert!(p.assess(&s).conflict, "{}", p.assess(&s).reason);
    let d = p.decide(&s, &NOW);
    assert_eq!(
        d.action,
        PolicyAction::RelocateCluster { cluster_id: 2 },
        "{}",
        d.reason
    );
    // 1 - (1 - b)^5.67 for the sofa's base rate b, not b itself.
    let b = sornav_supervisor::CooccurrencePrior::embedded()
        .posterior("sofa", std::iter::empty::<&str>())
        .unwrap()
        .base_rate;
    let want = 1.0 - (1.0 - b).powf(sornav_supervisor::REGIONS_PER_FLOOR);
    assert!(d.reason.contains(&format!("{want:.3}")), "{}", d.reason);
}

#[test]
fn distance_discount_prefers_the_near_equivalent_candidate() {
    let mut p = CommonsensePolicy::default();
    let s = snap(
        "toilet",
        BEDROOM,
        vec![
            cand(10, 40.0, &["sink", "bathtub", "towel"]),
            cand(11, 6.0, &["sink", "bathtub", "towel"]),
        ],
    );
    assert_eq!(
        p.decide(&s, &NOW).action,
        PolicyAction::RelocateCluster { cluster_id: 11 }
    );
}

#[test]
fn unknown_target_and_invalid_input_keep_exploring() {
    let mut p = CommonsensePolicy::default();
    let s = snap("spaceship", BEDROOM, bathroom_and_kitchen());
    assert_eq!(p.decide(&s, &NOW).action, PolicyAction::ContinueExplore);
    let mut s = snap("toilet", BEDROOM, bathroom_and_kitchen());
    s.local_context[0].support = f64::NAN;
    let d = p.decide(&s, &NOW);
    assert_eq!(d.action, PolicyAction::ContinueExplore);
    assert!(d.reason.contains("invalid"));
    assert!(
        CommonsensePolicy::embedded(CommonsenseConfig {
            distance_scale_m: 0.0,
            ..CommonsenseConfig::default()
        })
        .is_err()
    );
}

const LABELS: [&str; 16] = [
    "bed",
    "wardrobe",
    "nightstand",
    "sink",
    "bathtub",
    "towel",
    "couch",
    "tv",
    "refrigerator",
    "stove",
    "chair",
    "table",
    "plant",
    "lamp",
    "toilet",
    "mystery gadget",
];
const TARGETS: [&str; 7] = [
    "chair",
    "bed",
    "plant",
    "toilet",
    "tv_monitor",
    "sofa",
    "spaceship",
];

fn arb_objects() -> impl Strategy<Value = Vec<(usize, f64, f64)>> {
    prop::collection::vec((0..LABELS.len(), 0.0..400.0f64, 0.0..15.0f64), 0..8)
}

prop_compose! {
    fn arb_snapshot()(
        target in 0..TARGETS.len(),
        local in arb_objects(),
        cands in prop::collection::vec((0u64..20, 0.0..60.0f64, arb_objects()), 0..6),
    ) -> RegionSnapshot {
        let mut seen = std::collections::BTreeSet::new();
        RegionSnapshot {
            target: TARGETS[target].into(),
            local_context: local.iter().map(|&(l, s, _)| ContextObject::new(LABELS[l], s)).collect(),
            candidates: cands
                .into_iter()
                .filter(|(id, _, _)| seen.insert(*id))
                .map(|(id, d, objs)| Candidate { floor: 0,
                    cluster_id: id,
                    distance_m: d,
                    context: objs.iter().map(|&(l, s, r)| CandidateObject::new(LABELS[l], s, r)).collect(),
                })
                .collect(),
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn policies_only_choose_offered_clusters(s in arb_snapshot()) {
        let mut cs = CommonsensePolicy::default();
        for d in [cs.decide(&s, &NOW), NeverRelocate.decide(&s, &NOW)] {
            if let Some(k) = d.relocation() {
                prop_assert!(s.candidate(k).is_some());
            }
            prop_assert!(!d.reason.is_empty());
        }
        prop_assert_eq!(NeverRelocate.decide(&s, &NOW).action, PolicyAction::ContinueExplore);
    }

    #[test]
    fn without_conflict_no_relocation_whatever_the_candidates(s in arb_snapshot()) {
        let mut p = CommonsensePolicy::default();
        if !p.assess(&s).conflict {
            prop_assert_eq!(p.decide(&s, &NOW).action, PolicyAction::ContinueExplore);
        }
    }

    #[test]
    fn relocation_beats_the_current_context_by_the_margin(s in arb_snapshot()) {
        let mut p = CommonsensePolicy::default();
        let d = p.decide(&s, &NOW);
        if let Some(k) = d.relocation() {
            let a = p.assess(&s);
            prop_assert!(a.conflict);
            let cfg = p.config().clone();
            let c = s.candidate(k).unwrap();
            let labels = c.context.iter()
                .filter(|o| o.support >= cfg.min_support && o.distance_m <= cfg.candidate_radius_m)
                .map(|o| o.label.as_str());
            let pk = sornav_supervisor::CooccurrencePrior::embedded().posterior(&s.target, labels).unwrap();
            prop_assert!(pk.probability >= a.posterior.unwrap().probability + cfg.margin);
        }
    }
}
