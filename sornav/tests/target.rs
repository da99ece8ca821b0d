//! Free-text target requests map onto the category vocabulary.

use proptest::prelude::*;
use sornav::supervisor::OBJECTNAV_CATEGORIES;
use sornav::{AgentError, Vocabulary};

fn vocabulary() -> Vocabulary {
    Vocabulary::new([
        "chair", "table", "bed", "sofa", "toilet", "tv", "plant", "cabinet",
    ])
}

#[test]
fn requests_from_the_issue_and_synonyms() {
    let v = vocabulary();
    let cases = [
        ("find the television", "tv_monitor"),
        ("tv_monitor", "tv_monitor"),
        ("TV", "tv_monitor"),
        ("Could you find me a TV monitor?", "tv_monitor"),
        ("go to the couch", "sofa"),
        ("Navigate to the nearest potted plant.", "plant"),
        ("I need a toilet!", "toilet"),
        ("look for an office chair", "chair"),
        ("find the chair next to the bed", "chair"),
        ("beds", "bed"),
        ("find cabinets", "cabinet"),
        ("the dining table", "table"),
    ];
    for (request, category) in cases {
        let target = v
            .resolve(request)
            .unwrap_or_else(|e| panic!("{request}: {e}"));
        assert_eq!(target.category, category, "{request}");
        assert_eq!(target.request, request);
    }
}

#[test]
fn unknown_requests_are_typed_errors() {
    let v = vocabulary();
    for request in [
        "",
        "   ",
        "find the",
        "find the spaceship",
        "go home",
        "wall",
        "door",
    ] {
        match v.resolve(request) {
            Err(AgentError::UnknownTarget { request: r, known }) => {
                assert_eq!(r, request);
                assert!(known.contains("tv_monitor"));
            }
            other => panic!("{request:?}: {other:?}"),
        }
    }
}

const PREFIXES: [&str; 8] = [
    "",
    "find the ",
    "please find a ",
    "go to the ",
    "Can you locate my ",
    "search for the nearest ",
    "navigate towards some ",
    "where is the ",
];
const SUFFIXES: [&str; 5] = ["", ".", "?", ", please", "!"];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Every ObjectNav category, wrapped in request phrasing and in any
    /// letter case, resolves to itself.
    #[test]
    fn phrased_categories_resolve(
        c in 0usize..OBJECTNAV_CATEGORIES.len(),
        p in 0usize..PREFIXES.len(),
        s in 0usize..SUFFIXES.len(),
        upper in proptest::collection::vec(any::<bool>(), 40),
    ) {
        let category = OBJECTNAV_CATEGORIES[c];
        let raw = format!("{}{}{}", PREFIXES[p], category, SUFFIXES[s]);
        let request: String = raw
            .chars()
            .zip(upper.iter().cycle())
            .map(|(ch, &u)| if u { ch.to_ascii_uppercase() } else { ch })
            .collect();
        let target = vocabulary().resolve(&request).unwrap();
        prop_assert_eq!(target.category, category);
    }

    /// Any string: never a panic; a success always names a category of
    /// the vocabulary, and resolution is idempotent on that category.
    #[test]
    fn arbitrary_requests_resolve_into_the_vocabulary(request in "\\PC{0,40}") {
        let v = vocabulary();
        if let Ok(target) = v.resolve(&request) {
            prop_assert!(v.contains(&target.category));
            prop_assert_eq!(v.resolve(&target.category).unwrap().category, target.category);
        }
    }
}
