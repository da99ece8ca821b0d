//! The per-episode decision log: every decision of the agent, with runs of
//! identical consecutive decisions merged so that a 500-action episode stays
//! a few kilobytes.

use serde::{Deserialize, Serialize};
use sornav::{Decision, DecisionAction, DecisionStep};

/// A run of identical consecutive decisions (same rule, action, mission and
/// reason).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoggedDecision {
    /// Clock reading of the first decision of the run (s).
    pub t: f64,
    /// Clock reading of the last decision of the run (s).
    pub until: f64,
    /// Decisions in the run.
    pub count: u32,
    /// The Algorithm 1 rule that decided.
    pub step: DecisionStep,
    /// What was done.
    pub action: DecisionAction,
    /// The mission dispatched or kept.
    pub mission: Option<u64>,
    /// Why.
    pub reason: String,
}

/// The decision log of one episode.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct DecisionLog(pub Vec<LoggedDecision>);

impl DecisionLog {
    /// Appends decisions, merging each into the last run when identical.
    pub fn extend(&mut self, decisions: impl IntoIterator<Item = Decision>) {
        for d in decisions {
            let t = d.at.as_secs_f64();
            let mission = d.mission.map(|m| m.0);
            if let Some(last) = self.0.last_mut()
                && last.step == d.step
                && last.action == d.action
                && last.mission == mission
                && last.reason == d.reason
            {
                last.until = t;
                last.count += 1;
                continue;
            }
            self.0.push(LoggedDecision {
                t,
                until: t,
                count: 1,
                step: d.step,
                action: d.action,
                mission,
                reason: d.reason,
            });
        }
    }

    /// Total number of decisions (runs expanded).
    pub fn decisions(&self) -> u64 {
        self.0.iter().map(|d| u64::from(d.count)).sum()
    }

    /// The runs.
    pub fn runs(&self) -> &[LoggedDecision] {
        &self.0
    }
}

/// A violation of Algorithm 1's ordering found in a decision log.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("decision at t = {t} s: {rule}")]
pub struct OrderViolation {
    /// Clock reading of the offending decision (s).
    pub t: f64,
    /// The rule it breaks.
    pub rule: &'static str,
}

impl DecisionLog {
    /// Checks the log against Algorithm 1's ordering:
    ///
    /// 1. **target first**: STOP comes last, right after the target was
    ///    verified (`TargetVerification`) or after moves to a view point
    ///    of the verified target (`StopInView`); a verification itself
    ///    follows an approach (`TargetAccepted`);
    /// 2. **an active relocation is kept**: every later decision about a
    ///    relocation mission is `RelocationActive` (never re-evaluated by
    ///    the policy or the rate limit);
    /// 3. **rate limit**: `RateLimited` only within `interval_s` of the
    ///    last policy evaluation (or region-dwell decision);
    /// 4. **region dwell** only after a relocation.
    ///
    /// # Errors
    /// The first [`OrderViolation`].
    pub fn check_algorithm1(&self, interval_s: f64) -> Result<(), OrderViolation> {
        let eps = 1e-9;
        let mut relocation_missions = std::collections::BTreeSet::new();
        let mut last_policy: Option<f64> = None;
        let mut accepted = false;
        let mut verified = false;
        let runs = &self.0;
        for (i, d) in runs.iter().enumerate() {
            let fail = |rule| Err(OrderViolation { t: d.t, rule });
            match d.step {
                DecisionStep::TargetConfirmed => {
                    if !verified {
                        return fail("STOP without a verification");
                    }
                    if i + 1 != runs.len() {
                        return fail("decisions after STOP");
                    }
                }
                DecisionStep::StopInView => {
                    if !verified {
                        return fail("a move to a view point before the target was verified");
                    }
                }
                DecisionStep::TargetVerification => {
                    if !accepted {
                        return fail("verification without an approach");
                    }
                    verified = true;
                }
                DecisionStep::TargetAccepted => accepted = true,
                DecisionStep::RelocationActive => {}
                DecisionStep::RateLimited => {
                    if d.mission.is_some_and(|m| relocation_missions.contains(&m)) {
                        return fail("an active relocation was rate-limited instead of kept");
                    }
                    match last_policy {
                        Some(t) if d.until - t < interval_s - eps => {}
                        _ => return fail("rate limit outside the supervisor interval"),
                    }
                }
                DecisionStep::RegionDwell => {
                    if relocation_missions.is_empty() {
                        return fail("region dwell without a relocation");
                    }
                    if d.mission.is_some_and(|m| relocation_missions.contains(&m)) {
                        return fail("an active relocation was replaced by the region dwell");
                    }
                    last_policy = Some(d.until);
                }
                DecisionStep::PolicyEvaluated => {
                    if d.action != "relocate"
                        && d.mission.is_some_and(|m| relocation_missions.contains(&m))
                    {
                        return fail("an active relocation was re-evaluated by the policy");
                    }
                    if d.action == "relocate"
                        && let Some(m) = d.mission
                    {
                        relocation_missions.insert(m);
                    }
                    last_policy = Some(d.until);
                }
            }
            if !matches!(
                d.step,
                DecisionStep::TargetVerification
                    | DecisionStep::TargetConfirmed
                    | DecisionStep::StopInView
            ) {
                verified = verified && d.step == DecisionStep::TargetVerification;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(t: f64, step: DecisionStep, action: &str, mission: Option<u64>) -> LoggedDecision {
        LoggedDecision {
            t,
            until: t,
            count: 1,
            step,
            action: action.parse().unwrap(),
            mission,
            reason: String::new(),
        }
    }

    #[test]
    fn a_well_ordered_log_passes() {
        use DecisionStep::*;
        let log = DecisionLog(vec![
            run(0.0, PolicyEvaluated, "explore", Some(1)),
            run(0.5, RateLimited, "continue", Some(1)),
            run(1.0, PolicyEvaluated, "relocate", Some(2)),
            run(1.5, RelocationActive, "continue", Some(2)),
            run(8.0, RegionDwell, "explore", Some(3)),
            run(8.5, RateLimited, "continue", Some(3)),
            run(9.0, RegionDwell, "continue", Some(3)),
            run(30.0, PolicyEvaluated, "explore", Some(3)),
            run(9.5, TargetAccepted, "nav_to_object", Some(4)),
            run(12.0, TargetVerification, "verify", None),
            run(12.5, TargetConfirmed, "stop", None),
        ]);
        assert_eq!(log.check_algorithm1(1.0), Ok(()));
    }

    #[test]
    fn each_rule_is_enforced() {
        use DecisionStep::*;
        let cases = [
            (
                vec![run(0.0, TargetConfirmed, "stop", None)],
                "STOP without a verification",
            ),
            (
                vec![run(0.0, TargetVerification, "verify", None)],
                "verification without an approach",
            ),
            (
                vec![
                    run(0.0, TargetAccepted, "nav_to_object", Some(1)),
                    run(1.0, TargetVerification, "verify", None),
                    run(1.5, TargetConfirmed, "stop", None),
                    run(2.0, PolicyEvaluated, "explore", Some(2)),
                ],
                "decisions after STOP",
            ),
            (
                vec![
                    run(0.0, TargetAccepted, "nav_to_object", Some(1)),
                    run(1.0, TargetVerification, "verify", None),
                    run(1.5, PolicyEvaluated, "explore", Some(2)),
                    run(2.0, TargetConfirmed, "stop", None),
                ],
                "STOP without a verification",
            ),
            (
                vec![
                    run(0.0, PolicyEvaluated, "relocate", Some(2)),
                    run(3.0, PolicyEvaluated, "explore", Some(2)),
                ],
                "an active relocation was re-evaluated by the policy",
            ),
            (
                vec![
                    run(0.0, PolicyEvaluated, "relocate", Some(2)),
                    run(0.5, RateLimited, "continue", Some(2)),
                ],
                "an active relocation was rate-limited instead of kept",
            ),
            (
                vec![
                    run(0.0, PolicyEvaluated, "explore", Some(1)),
                    run(1.5, RateLimited, "continue", Some(1)),
                ],
                "rate limit outside the supervisor interval",
            ),
            (
                vec![run(0.0, RegionDwell, "explore", Some(1))],
                "region dwell without a relocation",
            ),
        ];
        for (log, rule) in cases {
            let err = DecisionLog(log).check_algorithm1(1.0).unwrap_err();
            assert_eq!(err.rule, rule);
        }
    }

    #[test]
    fn identical_decisions_merge_into_runs() {
        let d = |s: u64, reason: &str| Decision {
            at: std::time::Duration::from_millis(s * 500),
            step: DecisionStep::RateLimited,
            action: DecisionAction::Continue,
            mission: Some(sornav::executor::MissionId(1)),
            reason: reason.into(),
        };
        let mut log = DecisionLog::default();
        log.extend([d(0, "a"), d(1, "a"), d(2, "b"), d(3, "b"), d(4, "b")]);
        assert_eq!(log.runs().len(), 2);
        assert_eq!(log.decisions(), 5);
        assert_eq!(
            (log.runs()[1].t, log.runs()[1].until, log.runs()[1].count),
            (1.0, 2.0, 3)
        );
    }
}
