//! Habitat agent motion on a procedural house's walkable height field.

use std::sync::OnceLock;

use nalgebra::Point3;
use proptest::prelude::*;
use sornav_platform_sim::agent::{Action, Agent, AgentConfig, wrap_angle};
use sornav_platform_sim::{NavMesh, Simulator};

mod common;

fn sim() -> &'static Simulator {
    static SIM: OnceLock<Simulator> = OnceLock::new();
    SIM.get_or_init(|| common::simulator(common::house(11, 2), 64, 48))
}

fn span_point(nav: &NavMesh, pick: f64) -> Point3<f64> {
    let s = ((pick * nav.span_count() as f64) as usize).min(nav.span_count() - 1);
    nav.span_center(s as u32)
}

fn action(k: u8) -> Action {
    // Mostly forward moves, so that walks reach walls, doors and stairs.
    match k % 8 {
        0 => Action::TurnLeft,
        1 => Action::TurnRight,
        2 => Action::LookUp,
        3 => Action::LookDown,
        _ => Action::MoveForward,
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Whatever the actions, the agent stays on the navigable surface, moves
    /// exactly one step or not at all, and blocked moves are collisions.
    #[test]
    fn agent_never_leaves_the_navigable_set(pick in 0.0f64..1.0, yaw in -3.2f64..3.2, actions in prop::collection::vec(any::<u8>(), 1..150)) {
        let sim = sim();
        let nav = sim.nav();
        let mut agent = Agent::spawn(nav, &span_point(nav, pick), yaw, AgentConfig::default()).unwrap();
        for k in actions {
            let before = agent.position();
            let out = agent.step(nav, action(k));
            let p = agent.position();
            prop_assert!(nav.is_navigable(&p), "left the surface at {:?}", p);
            prop_assert_eq!(nav.span_at(&p), Some(agent.span()));
            if out.collided {
                prop_assert_eq!(p, before);
            }
            let horizontal = (p.xy() - before.xy()).norm();
            prop_assert!(horizontal < 1e-9 || (horizontal - 0.25).abs() < 1e-9, "moved {}", horizontal);
            // Steps between neighbouring spans are at most 0.2 m; a 0.25 m
            // move crosses at most 6 columns.
            prop_assert!((p.z - before.z).abs() <= 6.0 * 0.2 + 1e-6);
            prop_assert!((out.moved - (p - before).norm()).abs() < 1e-9);
        }
    }

    /// Twelve turns of 30 deg (either way) restore the heading; GPS and
    /// compass do not change while turning.
    #[test]
    fn twelve_turns_restore_the_heading(pick in 0.0f64..1.0, yaw in -10.0f64..10.0, left in any::<bool>()) {
        let sim = sim();
        let nav = sim.nav();
        let mut agent = Agent::spawn(nav, &span_point(nav, pick), yaw, AgentConfig::default()).unwrap();
        let (y0, gps0) = (agent.yaw(), agent.gps());
        let turn = if left { Action::TurnLeft } else { Action::TurnRight };
        for _ in 0..12 {
            agent.step(nav, turn);
        }
        prop_assert!(wrap_angle(agent.yaw() - y0).abs() < 1e-9);
        prop_assert!(agent.compass().abs() < 1e-9);
        prop_assert_eq!(agent.gps(), gps0);
    }
}

#[test]
fn forward_moves_follow_the_heading_and_walls_block() {
    let sim = sim();
    let nav = sim.nav();
    // Find a start from which forward moves succeed, then walk until blocked.
    let start = nav.span_center(nav.span_count() as u32 / 2);
    let mut agent = Agent::spawn(nav, &start, 0.3, AgentConfig::default()).unwrap();
    let mut moved = 0;
    let mut collided = false;
    for _ in 0..400 {
        let before = agent.position();
        let out = agent.step(nav, Action::MoveForward);
        if out.collided {
            collided = true;
            assert_eq!(
                agent.position(),
                before,
                "no sliding: a blocked move leaves the agent in place"
            );
            break;
        }
        let d = agent.position() - before;
        assert!(
            (d.y.atan2(d.x) - 0.3).abs() < 1e-9,
            "moves along the heading"
        );
        moved += 1;
    }
    assert!(collided, "walking straight ends at a wall");
    // GPS reports the straight-line walk in the start frame (x forward).
    let gps = agent.gps();
    assert!(
        (gps.x - 0.25 * f64::from(moved)).abs() < 1e-6 && gps.y.abs() < 1e-6,
        "gps {gps:?} after {moved} moves"
    );
    // Looking up and down is clamped to +-60 deg.
    for _ in 0..5 {
        agent.step(nav, Action::LookUp);
    }
    assert!((agent.pitch() - 60f64.to_radians()).abs() < 1e-12);
}

#[test]
fn bad_starts_are_typed_errors() {
    let sim = sim();
    let nav = sim.nav();
    let p = nav.span_center(0);
    assert!(
        Agent::spawn(
            nav,
            &Point3::new(f64::NAN, 0.0, 0.0),
            0.0,
            AgentConfig::default()
        )
        .is_err()
    );
    assert!(
        Agent::spawn(
            nav,
            &Point3::new(p.x, p.y, p.z + 50.0),
            0.0,
            AgentConfig::default()
        )
        .is_err()
    );
    assert!(Agent::spawn(nav, &p, f64::INFINITY, AgentConfig::default()).is_err());
    assert!(
        Agent::spawn(
            nav,
            &p,
            0.0,
            AgentConfig {
                forward_step: -1.0,
                ..AgentConfig::default()
            }
        )
        .is_err()
    );
}
