//! The mission executor.

use std::collections::VecDeque;
use std::time::Duration;

use crate::{
    Admission, Clock, ExecError, ExecutorConfig, ExecutorEvent, FailureReason, Mission, MissionId,
    MissionKind, MissionOutcome, MissionStatus, MotionStack, PathValidity, RefusalReason,
    RobotPose, StuckDetector, admit, arrived, remaining_distance,
};

/// What [`Executor::submit`] did with a mission.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Submission {
    /// A new mission started (possibly pre-empting the previous one, whose
    /// `Preempted` outcome is queued).
    Started(MissionId),
    /// The active mission has the same kind and target. Same id, and the
    /// timeout keeps running. If the waypoint, path or look-at point changed,
    /// the mission is re-dispatched and the stuck window restarts (progress is
    /// measured along the new path); an identical re-submission changes
    /// nothing, so a supervisor repeating its decision every cycle does not
    /// mask a stuck robot.
    Updated(MissionId),
    /// The active mission keeps running.
    Refused {
        /// The active mission.
        active: MissionId,
        /// Why.
        reason: RefusalReason,
    },
}

impl Submission {
    /// The id of the mission now active because of this submission, if any.
    pub fn id(&self) -> Option<MissionId> {
        match *self {
            Submission::Started(id) | Submission::Updated(id) => Some(id),
            Submission::Refused { .. } => None,
        }
    }
}

/// The active mission and its monitors.
#[derive(Debug, Clone)]
struct Active {
    id: MissionId,
    mission: Mission,
    started_at: Duration,
    stuck: StuckDetector,
}

/// Runs one mission at a time on a platform's [`MotionStack`], timed by a
/// [`Clock`].
///
/// Lifecycle of every admitted mission: `Active -> Reached | Failed(reason) |
/// Preempted`, with exactly one [`ExecutorEvent::Finished`] per mission.
///
/// * [`submit`](Self::submit) applies the pre-emption rules ([`admit`]).
/// * [`tick`](Self::tick), once per control step, checks in this order:
///   arrival ([`arrived`]), path invalidated (caller's [`PathValidity`]),
///   timeout, stuck ([`StuckDetector`] on [`remaining_distance`]). The first
///   that holds ends the mission.
/// * Completing a `Relocate` also emits [`ExecutorEvent::ExploreFromRegion`]
///   so the supervisor plans global exploration from the new region; it is
///   never a task completion ([`MissionOutcome::is_target_arrival`]).
///
/// The motion stack is told to [`cancel`](MotionStack::cancel) whenever the
/// active mission ends, except when a newly dispatched mission replaces it.
///
/// # Complexity
/// `submit` is `O(1)` plus the dispatch; `tick` is `O(k)` for a path of `k`
/// segments (amortised `O(1)` for stuck detection).
#[derive(Debug)]
pub struct Executor<M, C> {
    config: ExecutorConfig,
    motion: M,
    clock: C,
    active: Option<Active>,
    next_id: u64,
    events: VecDeque<ExecutorEvent>,
}

impl<M: MotionStack, C: Clock> Executor<M, C> {
    /// An idle executor.
    ///
    /// # Errors
    /// [`ExecError::InvalidConfig`] when `config` is invalid.
    pub fn new(config: ExecutorConfig, motion: M, clock: C) -> Result<Self, ExecError> {
        config.validate()?;
        Ok(Self {
            config,
            motion,
            clock,
            active: None,
            next_id: 0,
            events: VecDeque::new(),
        })
    }

    /// The parameters.
    pub fn config(&self) -> &ExecutorConfig {
        &self.config
    }

    /// The motion stack.
    pub fn motion(&self) -> &M {
        &self.motion
    }

    /// The motion stack, mutably (for platforms that step it).
    pub fn motion_mut(&mut self) -> &mut M {
        &mut self.motion
    }

    /// The clock.
    pub fn clock(&self) -> &C {
        &self.clock
    }

    /// The clock, mutably (to advance a [`SimClock`](crate::SimClock)).
    pub fn clock_mut(&mut self) -> &mut C {
        &mut self.clock
    }

    /// The active mission.
    pub fn active(&self) -> Option<(MissionId, &Mission)> {
        self.active.as_ref().map(|a| (a.id, &a.mission))
    }

    /// Takes the queued events, oldest first.
    pub fn drain_events(&mut self) -> Vec<ExecutorEvent> {
        self.events.drain(..).collect()
    }

    fn stuck_detector(&self) -> StuckDetector {
        StuckDetector::new(
            Duration::from_secs_f64(self.config.stuck_window_s),
            self.config.stuck_progress_m,
        )
    }

    fn finish(&mut self, active: Active, status: MissionStatus, now: Duration) {
        self.events
            .push_back(ExecutorEvent::Finished(MissionOutcome {
                id: active.id,
                kind: active.mission.kind,
                status,
                at: now,
            }));
    }

    /// Dispatches the active mission; on refusal by the motion stack the
    /// mission fails at once.
    fn dispatch_active(&mut self, now: Duration) {
        let Some(active) = self.active.as_ref() else {
            return;
        };
        if let Err(e) = self.motion.dispatch(&active.mission) {
            self.motion.cancel();
            if let Some(active) = self.active.take() {
                self.finish(
                    active,
                    MissionStatus::Failed(FailureReason::DispatchFailed(e.0)),
                    now,
                );
            }
        }
    }

    /// Offers a mission; the pre-emption rules ([`admit`]) decide whether it
    /// starts, updates the active one, pre-empts it, or is refused.
    ///
    /// # Errors
    /// [`ExecError::InvalidMission`] for non-finite coordinates or an empty
    /// path; nothing changes then.
    pub fn submit(&mut self, mission: Mission) -> Result<Submission, ExecError> {
        mission.validate()?;
        let now = self.clock.now();
        let admission = admit(self.active.as_ref().map(|a| &a.mission.kind), &mission.kind);
        let submission = match admission {
            Admission::Refuse(reason) => {
                let active = self.active.as_ref().map_or(MissionId(0), |a| a.id);
                return Ok(Submission::Refused { active, reason });
            }
            Admission::Update => {
                let stuck = self.stuck_detector();
                let Some(active) = self.active.as_mut() else {
                    return Err(ExecError::InvalidMission("no active mission to update"));
                };
                if active.mission == mission {
                    // A repeated decision: nothing to re-dispatch, and the
                    // stuck window keeps running.
                    return Ok(Submission::Updated(active.id));
                }
                active.mission = mission;
                active.stuck = stuck;
                Submission::Updated(active.id)
            }
            Admission::Start | Admission::Preempt => {
                let id = MissionId(self.next_id);
                self.next_id += 1;
                if let Some(old) = self.active.take() {
                    self.finish(old, MissionStatus::Preempted { by: Some(id) }, now);
                }
                self.active = Some(Active {
                    id,
                    mission,
                    started_at: now,
                    stuck: self.stuck_detector(),
                });
                Submission::Started(id)
            }
        };
        self.dispatch_active(now);
        Ok(submission)
    }

    /// Ends the active mission as `Preempted { by: None }` (for example when
    /// target verification rejects the candidate being approached) and
    /// cancels the motion. Returns the cancelled mission's id.
    pub fn cancel(&mut self) -> Option<MissionId> {
        let active = self.active.take()?;
        let id = active.id;
        self.motion.cancel();
        let now = self.clock.now();
        self.finish(active, MissionStatus::Preempted { by: None }, now);
        Some(id)
    }

    /// Monitors the active mission at the robot's current `pose`; `validity`
    /// tells whether the map still considers the mission's path executable.
    /// Returns the outcome when the mission ended at this tick (it is also
    /// queued as an event).
    ///
    /// # Errors
    /// [`ExecError::InvalidPose`] for a non-finite pose; nothing changes then.
    pub fn tick(
        &mut self,
        pose: &RobotPose,
        validity: &dyn PathValidity,
    ) -> Result<Option<MissionOutcome>, ExecError> {
        if !pose.is_finite() {
            return Err(ExecError::InvalidPose);
        }
        let now = self.clock.now();
        let Some(active) = self.active.as_mut() else {
            return Ok(None);
        };
        let kind_config = *self.config.for_kind(&active.mission.kind);
        let status = if arrived(pose, &active.mission, &kind_config.arrival) {
            Some(MissionStatus::Reached)
        } else if !validity.still_valid(&active.mission) {
            Some(MissionStatus::Failed(FailureReason::PathInvalidated))
        } else {
            let elapsed = now.saturating_sub(active.started_at);
            let timed_out = kind_config
                .timeout_s
                .is_some_and(|t| elapsed >= Duration::from_secs_f64(t));
            if timed_out {
                Some(MissionStatus::Failed(FailureReason::Timeout { elapsed }))
            } else {
                let remaining = remaining_distance(
                    &pose.position,
                    &active.mission.waypoint,
                    active.mission.path.as_deref(),
                );
                active
                    .stuck
                    .record(now, remaining)
                    .map(|progress_m| MissionStatus::Failed(FailureReason::Stuck { progress_m }))
            }
        };
        let Some(status) = status else {
            return Ok(None);
        };
        let Some(active) = self.active.take() else {
            return Ok(None);
        };
        self.motion.cancel();
        let outcome = MissionOutcome {
            id: active.id,
            kind: active.mission.kind,
            status,
            at: now,
        };
        self.events
            .push_back(ExecutorEvent::Finished(outcome.clone()));
        if let (MissionKind::Relocate { cluster }, MissionStatus::Reached) =
            (outcome.kind, &outcome.status)
        {
            self.events.push_back(ExecutorEvent::ExploreFromRegion {
                after: outcome.id,
                cluster,
                position: pose.position,
            });
        }
        Ok(Some(outcome))
    }
}
