//! `AgentConfig`: the TOML example parses, round-trips, and bad values are
//! typed errors.

use proptest::prelude::*;
use sornav::{AgentConfig, ConfigError, FrontierOrdering, PolicyConfig, Variant};

const EXAMPLE: &str = include_str!("../config/agent.example.toml");

#[test]
fn example_parses_to_the_paper_defaults() {
    let config = AgentConfig::from_toml(EXAMPLE).expect("example parses");
    assert_eq!(config, AgentConfig::default());
    assert_eq!(config.semantic_map.resolution, 0.05);
    assert_eq!(config.frontier.grid.resolution, 0.05);
    assert_eq!(config.cluster.n_min, 10);
    assert_eq!(config.gate.n_obs, 3);
    assert_eq!(config.gate.n_miss, 5);
    assert_eq!(config.cluster.rho_c, 25.0);
    assert_eq!(config.cluster.eta, 0.1);
    assert_eq!(config.cluster.top_k, 10);
    assert_eq!((config.cluster.r_s, config.cluster.r_r), (10.0, 10.0));
    assert_eq!(config.horizon.rule.radius, 5.0);
    assert_eq!(config.horizon.rule.leg_ratio, 2.0);
    assert_eq!(config.supervisor.interval_s, 1.0);
    assert_eq!((config.depth.min_depth, config.depth.max_depth), (0.5, 5.0));
    assert_eq!(config.frontier.grid.robot_radius, 0.18);
}

#[test]
fn default_round_trips_through_toml() {
    let config = AgentConfig::default();
    let text = config.to_toml().unwrap();
    assert_eq!(AgentConfig::from_toml(&text).unwrap(), config);
}

#[test]
fn every_agent_variant_is_valid_and_round_trips() {
    for v in Variant::ALL {
        assert_eq!(Variant::from_name(v.name()), Some(v));
        match AgentConfig::for_variant(v) {
            Ok(config) => {
                config.validate().unwrap();
                let back = AgentConfig::from_toml(&config.to_toml().unwrap()).unwrap();
                assert_eq!(back, config, "{}", v.name());
            }
            Err(e) => {
                assert_eq!(v, Variant::Oracle);
                assert!(matches!(e, ConfigError::NotAnAgentVariant(..)));
            }
        }
    }
    let nearest = AgentConfig::for_variant(Variant::NearestFrontier).unwrap();
    assert_eq!(nearest.ordering, FrontierOrdering::Nearest);
    assert_eq!(nearest.policy, PolicyConfig::NeverRelocate);
}

#[test]
fn unknown_fields_and_bad_values_are_errors() {
    let unknown = format!("{EXAMPLE}\nspeed_of_light = 3\n");
    assert!(matches!(
        AgentConfig::from_toml(&unknown),
        Err(ConfigError::Toml(_))
    ));
    let bad_voxel = "[semantic_map]\nresolution = 0.1\n";
    assert!(matches!(
        AgentConfig::from_toml(bad_voxel),
        Err(ConfigError::Inconsistent {
            parameter: "voxel size",
            ..
        })
    ));
    let bad_k = "[cluster]\ntop_k = 5\n";
    assert!(matches!(
        AgentConfig::from_toml(bad_k),
        Err(ConfigError::Inconsistent { parameter: "K", .. })
    ));
    let wide = "[cluster]\nr_s = 2.0\n";
    assert!(matches!(
        AgentConfig::from_toml(wide),
        Err(ConfigError::Inconsistent {
            parameter: "R_s",
            ..
        })
    ));
    let footprint = "footprint_free_radius_m = -1.0\n";
    assert!(matches!(
        AgentConfig::from_toml(footprint),
        Err(ConfigError::Component { .. })
    ));
    let standoff = "[approach]\nmin_standoff_m = 0.5\nstandoff_m = 0.4\n";
    assert!(matches!(
        AgentConfig::from_toml(standoff),
        Err(ConfigError::Component {
            component: "approach",
            ..
        })
    ));
    let bad_rho = "[cluster]\nrho_c = -1.0\n";
    assert!(matches!(
        AgentConfig::from_toml(bad_rho),
        Err(ConfigError::Component {
            component: "cluster",
            ..
        })
    ));
    // Every supervisor and depth-window field is checked here, not first
    // when the agent is built.
    for (component, doc) in [
        ("supervisor", "[supervisor]\nregion_dwell_s = -1.0\n"),
        ("supervisor", "[supervisor]\ninterval_s = -0.5\n"),
        ("depth", "[depth]\nstride = 0\n"),
        ("depth", "[depth]\nmin_depth = 3.0\nmax_depth = 2.0\n"),
        // Issue 21: these validated, then panicked ("overflow when adding
        // duration to instant") or never returned.
        (
            "horizon",
            "[horizon.solver.time_budget]\nsecs = 9223372036854775807\nnanos = 0\n",
        ),
        ("horizon", "[horizon.solver]\nkicks_per_pair = 1e300\n"),
        // The stop-in-view rule.
        ("approach", "[approach]\nmax_reach_m = 0.0\n"),
        ("approach", "[approach]\nmax_reach_m = inf\n"),
        ("approach", "[approach]\nmin_visible_share = 1.5\n"),
        ("approach", "[approach]\nmin_visible_share = nan\n"),
        ("approach", "[approach]\nvfov_margin_deg = 90.0\n"),
        ("approach", "[approach]\nview_arrival_m = 0.0\n"),
        ("approach", "[approach]\nstop_in_view_attempts = 17\n"),
        ("approach", "[approach]\nmin_box_samples = 0\n"),
        ("approach", "[approach]\nmin_box_samples = 28\n"),
        // Roomy waypoints.
        ("approach", "[approach]\nclearance_margin_m = -0.1\n"),
        ("approach", "[approach]\nclearance_margin_m = nan\n"),
        ("approach", "[approach]\nclearance_margin_m = 1.5\n"),
        ("approach", "[approach]\nroomy_standoff_m = -1.0\n"),
        ("approach", "[approach]\nroomy_standoff_m = inf\n"),
        ("approach", "[approach]\nroomy_standoff_m = 1000.0\n"),
    ] {
        match AgentConfig::from_toml(doc) {
            Err(ConfigError::Component { component: c, .. }) => assert_eq!(c, component, "{doc}"),
            other => panic!("{doc}: expected a {component} error, got {other:?}"),
        }
    }
    let mut dwell = AgentConfig::default();
    dwell.supervisor.region_dwell_s = f64::NAN;
    assert!(matches!(
        dwell.validate(),
        Err(ConfigError::Component {
            component: "supervisor",
            ..
        })
    ));
    let nan = "[gate]\nn_obs = 0\n";
    assert!(AgentConfig::from_toml(nan).is_err());
    let dup = "[[labels]]\nid = 1\nname = \"wall\"\n[[labels]]\nid = 1\nname = \"floor\"\n";
    assert!(matches!(
        AgentConfig::from_toml(dup),
        Err(ConfigError::Labels(_))
    ));
    let missing = std::path::Path::new("/nonexistent/agent.toml");
    assert!(matches!(
        AgentConfig::from_toml_file(missing),
        Err(ConfigError::Toml(sornav::TomlError::Io { .. }))
    ));
}

#[test]
fn partial_documents_take_defaults() {
    let config = AgentConfig::from_toml("[gate]\nn_obs = 5\n").unwrap();
    assert_eq!(config.gate.n_obs, 5);
    assert_eq!(config.gate.n_miss, 5);
    assert_eq!(config.cluster, AgentConfig::default().cluster);
    let policy = AgentConfig::from_toml("[policy]\nkind = \"never_relocate\"\n").unwrap();
    assert_eq!(policy.policy, PolicyConfig::NeverRelocate);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Any in-range choice of the paper's parameters survives TOML.
    #[test]
    fn paper_parameters_round_trip(
        voxel in 0.02f64..0.2,
        n_min in 1usize..50,
        n_obs in 1u32..10,
        n_miss in 0u32..20,
        rho_c in 0.0f64..100.0,
        eta in 0.0f64..2.0,
        k in 1usize..30,
        r_s in 0.0f64..30.0,
        r_r in 0.0f64..30.0,
        radius in 0.0f64..10.0,
        ratio in 0.0f64..5.0,
        variant in 0usize..4,
    ) {
        let mut c = AgentConfig::for_variant(Variant::ALL[variant]).unwrap();
        c.semantic_map.resolution = voxel;
        c.frontier.grid.resolution = voxel;
        c.cluster.n_min = n_min;
        c.gate.n_min = n_min as u32;
        c.gate.n_obs = n_obs;
        c.gate.n_miss = n_miss;
        c.cluster.rho_c = rho_c;
        c.cluster.eta = eta;
        c.cluster.top_k = k;
        c.supervisor.top_k = k;
        c.cluster.r_s = r_s;
        c.cluster.r_r = r_r;
        if let PolicyConfig::Commonsense(p) = &mut c.policy {
            p.min_support = n_min as f64;
            p.candidate_radius_m = r_s;
        }
        c.horizon.rule.radius = radius;
        c.horizon.rule.leg_ratio = ratio;
        prop_assert!(c.validate().is_ok());
        let back = AgentConfig::from_toml(&c.to_toml().unwrap()).unwrap();
        prop_assert_eq!(back, c);
    }
}

/// Agents run on worker threads (one episode per job).
#[test]
fn agent_is_send() {
    fn assert_send<T: Send>() {}
    assert_send::<sornav::Agent>();
    assert_send::<sornav::AgentSnapshot>();
}

/// `no-target-gate` is SOR-Nav with the gate's confirmation bypassed (the
/// first detection confirms) and nothing else changed.
#[test]
fn no_target_gate_confirms_on_first_sight_and_changes_nothing_else() {
    let sornav = AgentConfig::for_variant(Variant::Sornav).unwrap();
    let ablation = AgentConfig::for_variant(Variant::NoTargetGate).unwrap();
    assert_eq!(
        Variant::from_name("no-target-gate"),
        Some(Variant::NoTargetGate)
    );
    assert_eq!(
        (
            ablation.gate.n_obs,
            ablation.gate.n_miss,
            ablation.gate.verify_on_arrival
        ),
        (1, u32::MAX, false)
    );
    assert_eq!(ablation.gate.n_min, sornav.gate.n_min);
    assert_eq!(
        AgentConfig {
            gate: sornav.gate,
            ..ablation
        },
        sornav
    );
    assert!(sornav.gate.verify_on_arrival && sornav.gate.n_obs == 3);
}
