//! The wall-clock budget of `run_episode`: counted from the first
//! observation to the last action, setup excluded; a policy that sleeps in
//! `act` times out, and its late action is discarded.

use std::sync::OnceLock;
use std::time::Duration;

use sornav_platform_sim::metrics::Outcome;
use sornav_platform_sim::{
    Action, Episode, Observation, Oracle, Policy, RunConfig, SimConfig, Simulator, run_episode,
};

mod common;

/// A one-floor house and one of its episodes (same floor as its goal).
fn setup() -> &'static (Simulator, Episode) {
    static S: OnceLock<(Simulator, Episode)> = OnceLock::new();
    S.get_or_init(|| {
        let sim = Simulator::new(common::house(2, 1), SimConfig::default()).unwrap();
        let e = common::one_episode_per_category(&sim)
            .into_iter()
            .find(|e| e.cross_floor == Some(false))
            .expect("a same-floor episode");
        (sim, e)
    })
}

fn budget(seconds: f64) -> RunConfig {
    RunConfig {
        wall_clock_s: seconds,
        ..RunConfig::default()
    }
}

/// Sleeps `nap` in every `act`, then turns (or follows an oracle).
struct Sleepy {
    nap: Duration,
    calls: usize,
}

impl Policy for Sleepy {
    fn needs_frames(&self) -> bool {
        false
    }
    fn act(&mut self, _obs: &Observation<'_>) -> Action {
        self.calls += 1;
        std::thread::sleep(self.nap);
        Action::TurnLeft
    }
}

#[test]
fn sleeping_in_act_times_out() {
    let (sim, e) = setup();
    let mut p = Sleepy {
        nap: Duration::from_millis(30),
        calls: 0,
    };
    let r = run_episode(sim, e, &mut p, &budget(0.05)).unwrap();
    assert_eq!(r.outcome, Outcome::Timeout, "{r:?}");
    // act returned at ~30 ms (within budget: executed) and at ~60 ms (late:
    // discarded)
    assert_eq!(p.calls, 2);
    assert_eq!(r.actions, 1);
    assert!(r.timed_s > 0.05, "{}", r.timed_s);
    assert!(r.wall_s >= r.timed_s);
    assert!(!r.success);
    // the same policy with a generous budget runs into the action limit
    let mut p = Sleepy {
        nap: Duration::ZERO,
        calls: 0,
    };
    let r = run_episode(sim, e, &mut p, &budget(60.0)).unwrap();
    assert_eq!(r.outcome, Outcome::StepLimit);
    assert_eq!(r.actions, RunConfig::default().max_actions);
}

/// The oracle, but it dozes off before calling STOP.
struct LateOracle {
    inner: Oracle,
    nap: Duration,
}

impl Policy for LateOracle {
    fn reset(&mut self, sim: &Simulator, episode: &Episode) {
        self.inner.reset(sim, episode);
    }
    fn needs_frames(&self) -> bool {
        false
    }
    fn act(&mut self, obs: &Observation<'_>) -> Action {
        let a = self.inner.act(obs);
        if a == Action::Stop {
            std::thread::sleep(self.nap);
        }
        a
    }
}

#[test]
fn a_late_stop_is_discarded() {
    let (sim, e) = setup();
    // on time, the oracle succeeds
    let mut p = LateOracle {
        inner: Oracle::new(),
        nap: Duration::ZERO,
    };
    let on_time = run_episode(sim, e, &mut p, &budget(5.0)).unwrap();
    assert!(on_time.success, "{on_time:?}");
    // the STOP returns after the budget (the nap alone exceeds it): not
    // executed, timeout
    let cfg = budget(2.0 * on_time.timed_s + 0.1);
    let mut p = LateOracle {
        inner: Oracle::new(),
        nap: Duration::from_secs_f64(cfg.wall_clock_s + 0.05),
    };
    let late = run_episode(sim, e, &mut p, &cfg).unwrap();
    assert_eq!(late.outcome, Outcome::Timeout, "{late:?}");
    assert!(!late.success && !late.success_1m);
    // every action but the discarded STOP (fewer if the machine is slow)
    assert!(late.actions < on_time.actions);
    assert!(late.timed_s > cfg.wall_clock_s);
}

/// Setup (here a slow `reset`) is not counted against the budget, but is in
/// `wall_s`.
struct SlowReset;

impl Policy for SlowReset {
    fn reset(&mut self, _sim: &Simulator, _episode: &Episode) {
        std::thread::sleep(Duration::from_millis(200));
    }
    fn needs_frames(&self) -> bool {
        false
    }
    fn act(&mut self, _obs: &Observation<'_>) -> Action {
        Action::Stop
    }
}

#[test]
fn setup_is_not_counted() {
    let (sim, e) = setup();
    let r = run_episode(sim, e, &mut SlowReset, &budget(0.1)).unwrap();
    assert_eq!(r.outcome, Outcome::FalseStop, "{r:?}");
    assert_eq!(r.actions, 1);
    assert!(r.wall_s >= 0.2, "{}", r.wall_s);
    assert!(r.timed_s <= 0.1, "{}", r.timed_s);
}
