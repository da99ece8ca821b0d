//! ObjectNav metrics (Habitat's definitions) and the failure taxonomy.
//!
//! * **Success**: the agent called STOP with geodesic distance to the nearest
//!   goal view point at most 0.1 m (Habitat).
//! * **Success within 1 m**: the agent called STOP within 1.0 m of a goal
//!   object (the paper's boundary; distance from the agent's body, a vertical
//!   segment from the feet to camera height, to the object's bounds).
//! * **SPL** = S l / max(p, l) with l the start's geodesic distance to the
//!   nearest view point and p the executed path length (Anderson et al. 2018).
//! * **Soft SPL** = max(0, 1 - d_T / d_0) l / max(p, l) with d_T the final
//!   and d_0 the initial geodesic distance to the nearest view point
//!   (habitat-lab's `SoftSPL`).
//! * **Failure taxonomy** (the cause), mutually exclusive and checked in this
//!   order: step limit, wall-clock timeout, false stop (STOP away from every
//!   goal object), other (STOP near an object but not at a view point).
//! * **Floors**, recorded apart from the cause: the start's and the goal's
//!   level, the floors between them and the cross-floor flag
//!   (`floors_between >= 1`), defined in [`crate::levels`]. A cross-floor
//!   episode fails for one of the causes above like any other.
//!
//! Records written before the floors existed (with a `cross_floor`
//! outcome) do not deserialise into [`EpisodeResult`]: the cause of those
//! failures was not recorded.

use serde::{Deserialize, Serialize};

/// How an episode ended, for the failure taxonomy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Habitat success.
    Success,
    /// Failed by running out of actions.
    StepLimit,
    /// Failed by running out of wall-clock time.
    Timeout,
    /// STOP called away from every goal object (beyond the 1 m boundary).
    FalseStop,
    /// Any other failure (STOP within 1 m of an object but not at a view point).
    Other,
}

impl Outcome {
    /// The serialised name (`success`, `step_limit`, `timeout`,
    /// `false_stop`, `other`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Success => "success",
            Self::StepLimit => "step_limit",
            Self::Timeout => "timeout",
            Self::FalseStop => "false_stop",
            Self::Other => "other",
        }
    }
}

/// How an episode's loop ended (input of [`classify`]): exactly one of
/// STOP, the action budget or the wall-clock budget.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// The policy called STOP.
    Stopped {
        /// Habitat success: STOP within the success distance of a view point.
        success: bool,
        /// STOP within the object distance of a goal object.
        near_object: bool,
    },
    /// The action budget ran out.
    StepLimit,
    /// The wall-clock budget ran out.
    Timeout,
}

/// SPL of one episode: `success * l / max(p, l)`; 0 when `l` is not positive
/// or anything is non-finite.
pub fn spl(success: bool, shortest: f64, path: f64) -> f64 {
    if !success {
        return 0.0;
    }
    path_efficiency(shortest, path)
}

/// `l / max(p, l)` in [0, 1] (0 for invalid input).
fn path_efficiency(shortest: f64, path: f64) -> f64 {
    if !(shortest.is_finite() && path.is_finite() && shortest > 0.0 && path >= 0.0) {
        return 0.0;
    }
    (shortest / path.max(shortest)).clamp(0.0, 1.0)
}

/// Soft SPL of one episode (habitat-lab): `max(0, 1 - d_end / d_start) * l / max(p, l)`.
pub fn soft_spl(dtg_end: f64, dtg_start: f64, shortest: f64, path: f64) -> f64 {
    if !(dtg_start > 0.0 && dtg_start.is_finite()) {
        return 0.0;
    }
    let soft = if dtg_end.is_finite() {
        (1.0 - dtg_end / dtg_start).max(0.0)
    } else {
        0.0
    };
    soft * path_efficiency(shortest, path)
}

/// The outcome of an episode.
///
/// Success and a stop near the object exist only for a STOP
/// ([`Termination::Stopped`]). Whether the goal is on another floor is no
/// cause: it is recorded apart ([`EpisodeResult::cross_floor`]).
pub fn classify(t: Termination) -> Outcome {
    match t {
        Termination::Stopped { success: true, .. } => Outcome::Success,
        Termination::StepLimit => Outcome::StepLimit,
        Termination::Timeout => Outcome::Timeout,
        Termination::Stopped {
            near_object: false, ..
        } => Outcome::FalseStop,
        Termination::Stopped { .. } => Outcome::Other,
    }
}

/// Per-episode result of [`crate::run::run_episode`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpisodeResult {
    /// Episode id.
    pub episode_id: String,
    /// Scene id.
    pub scene_id: String,
    /// Target category.
    pub object_category: String,
    /// Habitat success (STOP within 0.1 m geodesic of a view point).
    pub success: bool,
    /// STOP within 1.0 m of a goal object.
    pub success_1m: bool,
    /// SPL.
    pub spl: f64,
    /// Soft SPL.
    pub soft_spl: f64,
    /// Geodesic distance to the nearest view point at the start (m).
    pub start_geodesic_m: f64,
    /// Geodesic distance to the nearest view point at the end (m);
    /// `None` when the agent ended on a part of the surface with no route to a goal.
    pub dtg_m: Option<f64>,
    /// Executed path length (m).
    pub path_length_m: f64,
    /// Actions taken (STOP included).
    pub actions: usize,
    /// Blocked forward moves.
    pub collisions: usize,
    /// Level of the start ([`crate::levels`]; 0 is the lowest floor).
    pub start_level: usize,
    /// Level of the goal view point nearest to the start.
    pub goal_level: usize,
    /// `|goal_level - start_level|`: floor-to-floor transitions between
    /// start and goal.
    pub floors_between: usize,
    /// Whether the goal is on another level than the start
    /// (`floors_between >= 1`); recorded apart from the outcome.
    pub cross_floor: bool,
    /// How the episode ended (the cause of a failure).
    pub outcome: Outcome,
    /// Wall-clock time of the whole [`crate::run::run_episode`] call (s),
    /// setup and scoring included.
    pub wall_s: f64,
    /// Wall-clock time counted against the budget (s): from the first
    /// observation to the end of the last action (see
    /// [`crate::run::run_episode`]).
    #[serde(default)]
    pub timed_s: f64,
    /// Median time of one step (render + policy + bookkeeping), ms.
    pub step_ms_p50: f64,
}

/// Aggregate of many episodes (means; rates are fractions in [0, 1]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Number of episodes.
    pub episodes: usize,
    /// Habitat success rate.
    pub success_rate: f64,
    /// Success rate within 1 m of the object.
    pub success_rate_1m: f64,
    /// Mean SPL.
    pub spl: f64,
    /// Mean soft SPL.
    pub soft_spl: f64,
    /// Mean final distance to goal over episodes with a finite one (m).
    pub dtg_m: f64,
    /// Fraction of cross-floor episodes (a flag, not a failure class).
    pub cross_floor_rate: f64,
    /// Fraction ending in each failure class: step-limit failures.
    pub step_limit_rate: f64,
    /// Timeouts.
    pub timeout_rate: f64,
    /// False stops.
    pub false_stop_rate: f64,
    /// Other failures.
    pub other_rate: f64,
    /// Mean actions per episode.
    pub mean_actions: f64,
    /// Mean collisions per episode.
    pub mean_collisions: f64,
}

impl Summary {
    /// Means over `results` (all zeros for none).
    ///
    /// # Complexity
    /// O(n).
    pub fn of(results: &[EpisodeResult]) -> Summary {
        let n = results.len();
        let mean = |f: &dyn Fn(&EpisodeResult) -> f64| {
            if n == 0 {
                0.0
            } else {
                results.iter().map(f).sum::<f64>() / n as f64
            }
        };
        let rate = |o: Outcome| mean(&|r| f64::from(u8::from(r.outcome == o)));
        let dtgs: Vec<f64> = results.iter().filter_map(|r| r.dtg_m).collect();
        Summary {
            episodes: n,
            success_rate: mean(&|r| f64::from(u8::from(r.success))),
            success_rate_1m: mean(&|r| f64::from(u8::from(r.success_1m))),
            spl: mean(&|r| r.spl),
            soft_spl: mean(&|r| r.soft_spl),
            dtg_m: if dtgs.is_empty() {
                0.0
            } else {
                dtgs.iter().sum::<f64>() / dtgs.len() as f64
            },
            cross_floor_rate: mean(&|r| f64::from(u8::from(r.cross_floor))),
            step_limit_rate: rate(Outcome::StepLimit),
            timeout_rate: rate(Outcome::Timeout),
            false_stop_rate: rate(Outcome::FalseStop),
            other_rate: rate(Outcome::Other),
            mean_actions: mean(&|r| r.actions as f64),
            mean_collisions: mean(&|r| r.collisions as f64),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// SPL is in [0, 1], and equals 1 exactly for successes along a
        /// shortest path (p <= l, up to rounding).
        #[test]
        fn spl_is_bounded_and_one_only_for_shortest_successes(success in any::<bool>(), l in 0.0f64..50.0, extra in 0.0f64..50.0) {
            let p = l + extra;
            let s = spl(success, l, p);
            prop_assert!((0.0..=1.0).contains(&s));
            if s == 1.0 {
                prop_assert!(success && extra <= 1e-12 * l.max(1.0));
            }
            if success && extra == 0.0 && l > 0.0 {
                prop_assert_eq!(s, 1.0);
            }
            let soft = soft_spl(extra, l + 1.0, l, p);
            prop_assert!((0.0..=1.0).contains(&soft));
        }
    }

    #[test]
    fn outcome_name_is_the_serde_name() {
        for o in [
            Outcome::Success,
            Outcome::StepLimit,
            Outcome::Timeout,
            Outcome::FalseStop,
            Outcome::Other,
        ] {
            assert_eq!(
                serde_json::to_value(o).unwrap(),
                serde_json::Value::from(o.name())
            );
        }
    }

    #[test]
    fn legacy_cross_floor_outcome_is_refused() {
        assert!(serde_json::from_str::<Outcome>("\"cross_floor\"").is_err());
    }

    #[test]
    fn cross_floor_rate_counts_the_flag_not_an_outcome() {
        let r = |cross_floor, outcome| EpisodeResult {
            episode_id: "e".into(),
            scene_id: "s".into(),
            object_category: "bed".into(),
            success: outcome == Outcome::Success,
            success_1m: false,
            spl: 0.0,
            soft_spl: 0.0,
            start_geodesic_m: 1.0,
            dtg_m: None,
            path_length_m: 0.0,
            actions: 1,
            collisions: 0,
            start_level: 0,
            goal_level: usize::from(cross_floor),
            floors_between: usize::from(cross_floor),
            cross_floor,
            outcome,
            wall_s: 0.0,
            timed_s: 0.0,
            step_ms_p50: 0.0,
        };
        let s = Summary::of(&[
            r(true, Outcome::StepLimit),
            r(true, Outcome::Success),
            r(false, Outcome::StepLimit),
            r(false, Outcome::FalseStop),
        ]);
        assert_eq!(s.cross_floor_rate, 0.5);
        assert_eq!(s.step_limit_rate, 0.5);
        assert_eq!(s.success_rate, 0.25);
        assert_eq!(s.false_stop_rate, 0.25);
    }

    #[test]
    fn taxonomy_order() {
        let stop = |success, near_object| Termination::Stopped {
            success,
            near_object,
        };
        assert_eq!(classify(stop(true, true)), Outcome::Success);
        assert_eq!(classify(stop(true, false)), Outcome::Success);
        assert_eq!(classify(Termination::StepLimit), Outcome::StepLimit);
        assert_eq!(classify(Termination::Timeout), Outcome::Timeout);
        assert_eq!(classify(stop(false, false)), Outcome::FalseStop);
        assert_eq!(classify(stop(false, true)), Outcome::Other);
        assert_eq!(spl(true, f64::NAN, 1.0), 0.0);
        assert_eq!(soft_spl(f64::INFINITY, 3.0, 3.0, 3.0), 0.0);
    }
}
