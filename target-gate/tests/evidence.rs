//! The two recursions and the success condition.

use proptest::prelude::*;
use sornav_target_gate::{Evidence, GateConfig, success};

/// Closed forms of the recursions: `s_t` is the number of ones so far, `m_t`
/// the length of the trailing run of zeros.
fn closed_form(z: &[bool]) -> (u32, u32) {
    let s = z.iter().filter(|&&z| z).count() as u32;
    let m = z.iter().rev().take_while(|&&z| !z).count() as u32;
    (s, m)
}

proptest! {
    #[test]
    fn recursions_match_closed_form(z in proptest::collection::vec(any::<bool>(), 0..200)) {
        let mut e = Evidence::default();
        for (t, &zt) in z.iter().enumerate() {
            // Direct transcription of the two equations.
            let expected = Evidence {
                support: e.support + u32::from(zt),
                misses: if zt { 0 } else { e.misses + 1 },
            };
            e.observe(zt);
            prop_assert_eq!(e, expected);
            prop_assert_eq!((e.support, e.misses), closed_form(&z[..=t]));
        }
    }

    #[test]
    fn qualification_matches_definition(
        z in proptest::collection::vec(any::<bool>(), 0..60),
        n_obs in 1u32..6,
        n_miss in 0u32..8,
        b_nav in any::<bool>(),
    ) {
        let cfg = GateConfig { n_obs, n_miss, ..GateConfig::default() };
        let mut e = Evidence::default();
        for &zt in &z {
            e.observe(zt);
        }
        let (s, m) = closed_form(&z);
        prop_assert_eq!(e.qualifies(&cfg), s >= n_obs && m <= n_miss);
        prop_assert_eq!(e.expired(&cfg), m > n_miss);
        prop_assert_eq!(success(&e, b_nav, &cfg), b_nav && s >= n_obs && m <= n_miss);
    }
}

#[test]
fn success_truth_table_at_defaults() {
    let cfg = GateConfig::default();
    // (s, m, b_nav) -> success, around the boundaries N_obs = 3, N_miss = 5.
    let table = [
        (0, 0, true, false),
        (2, 0, true, false),
        (3, 0, true, true),
        (3, 0, false, false),
        (3, 5, true, true),
        (3, 6, true, false),
        (4, 5, false, false),
        (9, 0, true, true),
        (9, 6, true, false),
        (2, 6, false, false),
    ];
    for (s, m, b, expected) in table {
        let e = Evidence {
            support: s,
            misses: m,
        };
        assert_eq!(success(&e, b, &cfg), expected, "s={s} m={m} b_nav={b}");
    }
    // Exhaustively: every combination in a box around the thresholds.
    for s in 0..8 {
        for m in 0..9 {
            for b in [false, true] {
                let e = Evidence {
                    support: s,
                    misses: m,
                };
                assert_eq!(success(&e, b, &cfg), s >= 3 && m <= 5 && b);
            }
        }
    }
}

#[test]
fn counters_saturate() {
    let mut e = Evidence {
        support: u32::MAX,
        misses: u32::MAX,
    };
    e.observe(false);
    assert_eq!(e.misses, u32::MAX);
    e.observe(true);
    assert_eq!((e.support, e.misses), (u32::MAX, 0));
}

#[test]
fn defaults_are_the_papers() {
    let cfg = GateConfig::default();
    assert_eq!((cfg.n_min, cfg.n_obs, cfg.n_miss), (10, 3, 5));
    assert!(!cfg.negative_evidence);
    assert!(cfg.validate().is_ok());
    assert!(GateConfig { n_obs: 0, ..cfg }.validate().is_err());
    assert!(
        GateConfig {
            verify_window: 0,
            ..cfg
        }
        .validate()
        .is_err()
    );
    // Partial TOML/JSON configs fill in defaults.
    let partial: GateConfig = serde_json::from_str(r#"{"n_obs": 4}"#).unwrap();
    assert_eq!(partial, GateConfig { n_obs: 4, ..cfg });
}
