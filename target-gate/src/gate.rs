//! The target gate: tracking plus the verification protocol.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::{
    AbandonReason, CandidateReport, CandidateTracker, GateCommand, GateConfig, GateError,
    GateEvent, NeverVisible, ObjectId, PathCost, Phase, RejectReason, Selection, StraightLine,
    Visibility, success,
};

/// Confirms a target of one requested category.
///
/// Call [`update`](Self::update) (or
/// [`update_with_visibility`](Self::update_with_visibility), or
/// [`update_with`](Self::update_with) to choose among candidates by path
/// cost) once per sensor frame with the map's cluster snapshot, follow the [`command`](Self::command)
/// (navigate to the candidate, then face it), and report the navigation
/// result with [`on_arrived`](Self::on_arrived) or
/// [`on_approach_failed`](Self::on_approach_failed).
///
/// Confirmation requires `s_t >= N_obs`, `m_t <= N_miss` and `b_nav = 1`,
/// where `b_nav` is set by a detection in a frame *after* arrival was reported
/// (the platform reached the neighbourhood and turned toward the cluster). A
/// candidate that is not seen again within
/// [`GateConfig::verify_window`] updates, or whose approach fails, is
/// rejected and cannot be re-selected for [`GateConfig::reject_cooldown`]
/// updates.
///
/// While a candidate is being approached or verified, a better candidate does
/// not displace it (no dithering); it is dropped only by rejection, expiry or
/// a split of its cluster.
///
/// # Complexity
/// Each update is dominated by the tracker: `O((r + n) log n)` for `r`
/// reports and `n` tracked candidates, plus, while searching, one path-cost
/// call per qualifying candidate tied on the largest support
/// ([`CandidateTracker::best_by`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TargetGate<C> {
    tracker: CandidateTracker<C>,
    phase: Phase,
    #[serde(default)]
    last_selection: Option<Selection>,
}

impl<C: PartialEq> TargetGate<C> {
    /// A gate for category `target`.
    ///
    /// # Errors
    /// [`GateError::InvalidConfig`] when `config` is invalid.
    pub fn new(target: C, config: GateConfig) -> Result<Self, GateError> {
        Ok(Self {
            tracker: CandidateTracker::new(target, config)?,
            phase: Phase::Search,
            last_selection: None,
        })
    }

    /// The candidate tracker.
    pub fn tracker(&self) -> &CandidateTracker<C> {
        &self.tracker
    }

    /// The protocol phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The last candidate selection (made at each update while searching):
    /// the choice and its path-cost call counts. `None` before the first
    /// selection.
    pub fn last_selection(&self) -> Option<&Selection> {
        self.last_selection.as_ref()
    }

    /// Whether the target is confirmed.
    pub fn is_confirmed(&self) -> bool {
        matches!(self.phase, Phase::Confirmed { .. })
    }

    /// What the system should do now.
    pub fn command(&self) -> GateCommand {
        let centre_of = |object: ObjectId| self.tracker.track(object).map(|t| t.centre);
        match self.phase {
            Phase::Search => GateCommand::Search,
            Phase::Approach { object } => match centre_of(object) {
                Some(centre) => GateCommand::NavToObject { object, centre },
                None => GateCommand::Search,
            },
            Phase::Verify { object, .. } => match centre_of(object) {
                Some(centre) => GateCommand::Verify { object, centre },
                None => GateCommand::Search,
            },
            Phase::Confirmed { object, centre } => GateCommand::Stop { object, centre },
        }
    }

    /// One update without negative evidence information (see
    /// [`update_with_visibility`](Self::update_with_visibility)).
    ///
    /// # Errors
    /// [`GateError::NonFinite`] when `robot` is not finite; nothing is
    /// changed then.
    pub fn update(
        &mut self,
        reports: &[CandidateReport<C>],
        robot: &Point3<f64>,
    ) -> Result<Vec<GateEvent>, GateError> {
        self.update_with_visibility(reports, robot, &NeverVisible)
    }

    /// One update: track candidates from the map snapshot `reports`, advance
    /// the protocol, and select a candidate when searching (`robot` is used to
    /// break ties by straight-line distance; see
    /// [`update_with`](Self::update_with) for path costs). `visibility`
    /// supplies negative evidence when [`GateConfig::negative_evidence`] is
    /// on.
    ///
    /// # Errors
    /// [`GateError::NonFinite`] when `robot` is not finite; nothing is
    /// changed then.
    pub fn update_with_visibility(
        &mut self,
        reports: &[CandidateReport<C>],
        robot: &Point3<f64>,
        visibility: &dyn Visibility,
    ) -> Result<Vec<GateEvent>, GateError> {
        if !(robot.x.is_finite() && robot.y.is_finite() && robot.z.is_finite()) {
            return Err(GateError::NonFinite("robot position"));
        }
        Ok(self.update_with(reports, visibility, &StraightLine::new(*robot)))
    }

    /// One update that chooses the candidate to approach by path cost: track
    /// candidates from the map snapshot `reports`, advance the protocol,
    /// and, when searching, select the best candidate by
    /// [`CandidateTracker::best_by`] (most support, then reachable, then
    /// lower `cost`, then smallest id). `cost` is asked only about
    /// qualifying candidates tied on the largest support, so a shortest-path
    /// search per call is affordable. `visibility` supplies negative
    /// evidence when [`GateConfig::negative_evidence`] is on.
    ///
    /// # Example
    /// ```
    /// use nalgebra::Point3;
    /// use sornav_target_gate::{CandidateReport, GateConfig, GateEvent, NeverVisible, ObjectId, TargetGate};
    ///
    /// let mut gate = TargetGate::new("toilet", GateConfig::default()).unwrap();
    /// let toilet = |id, centre| CandidateReport {
    ///     object: ObjectId(id), category: "toilet", voxels: 40, centre, detected: true,
    /// };
    /// // 1 is 3 m above the robot at the origin, upstairs (20 m by the stairs);
    /// // 2 is 3 m away on the robot's floor.
    /// let seen = [toilet(1, Point3::new(0.0, 0.0, 3.0)), toilet(2, Point3::new(3.0, 0.0, 0.4))];
    /// let by_path = |c: &Point3<f64>| Some(if c.z > 2.0 { 20.0 } else { 3.0 });
    /// let mut events = Vec::new();
    /// for _ in 0..3 {
    ///     events = gate.update_with(&seen, &NeverVisible, &by_path);
    /// }
    /// assert!(events.contains(&GateEvent::Selected(ObjectId(2))));
    /// assert_eq!(gate.last_selection().unwrap().queries, 2);
    /// ```
    pub fn update_with(
        &mut self,
        reports: &[CandidateReport<C>],
        visibility: &dyn Visibility,
        cost: &dyn PathCost,
    ) -> Vec<GateEvent> {
        let summary = self.tracker.update(reports, visibility);
        let mut events: Vec<GateEvent> = summary
            .started
            .iter()
            .map(|&o| GateEvent::Tracked(o))
            .chain(summary.expired.iter().map(|&o| GateEvent::Expired(o)))
            .collect();
        let expired = |o: ObjectId| summary.expired.contains(&o);
        match self.phase {
            Phase::Search | Phase::Confirmed { .. } => {}
            Phase::Approach { object } => {
                if expired(object) {
                    self.abandon(object, AbandonReason::Expired, &mut events);
                }
            }
            Phase::Verify {
                object, deadline, ..
            } => {
                let fresh = summary.detected.binary_search(&object).is_ok();
                let confirmed = fresh
                    && self
                        .tracker
                        .track(object)
                        .is_some_and(|t| success(&t.evidence, true, self.tracker.config()));
                if confirmed {
                    let centre = self.tracker.track(object).map(|t| t.centre);
                    if let Some(centre) = centre {
                        self.phase = Phase::Confirmed { object, centre };
                        events.push(GateEvent::Confirmed(object));
                    }
                } else if expired(object) || summary.update >= deadline {
                    self.reject(object, RejectReason::NotSeenOnVerification, &mut events);
                }
            }
        }
        if self.phase == Phase::Search {
            self.select(cost, &mut events);
        }
        events
    }

    fn select(&mut self, cost: &dyn PathCost, events: &mut Vec<GateEvent>) {
        let selection = self.tracker.best_by(cost);
        self.last_selection = Some(selection);
        if let Some(object) = selection.object {
            self.phase = Phase::Approach { object };
            events.push(GateEvent::Selected(object));
        }
    }

    fn abandon(&mut self, object: ObjectId, reason: AbandonReason, events: &mut Vec<GateEvent>) {
        self.phase = Phase::Search;
        events.push(GateEvent::Abandoned { object, reason });
    }

    fn reject(&mut self, object: ObjectId, reason: RejectReason, events: &mut Vec<GateEvent>) {
        self.tracker.reject(object);
        self.phase = Phase::Search;
        events.push(GateEvent::Rejected { object, reason });
    }

    fn expect_approaching(&self, object: ObjectId) -> Result<(), GateError> {
        match self.phase {
            Phase::Approach { object: o } if o == object => Ok(()),
            Phase::Approach { .. } => Err(GateError::NotActive(object)),
            _ => Err(GateError::WrongPhase(self.phase.name())),
        }
    }

    /// Reports that the platform reached the candidate's neighbourhood and
    /// turned toward it (for example a `NAV_TO_OBJECT` mission reached with
    /// its heading requirement). Starts verification: a detection in one of
    /// the next [`GateConfig::verify_window`] updates confirms the target.
    /// With [`GateConfig::verify_on_arrival`] off, arrival confirms it at
    /// once.
    ///
    /// # Errors
    /// [`GateError::WrongPhase`] unless approaching, [`GateError::NotActive`]
    /// when `object` is not the candidate being approached.
    pub fn on_arrived(&mut self, object: ObjectId) -> Result<Vec<GateEvent>, GateError> {
        self.expect_approaching(object)?;
        if !self.tracker.config().verify_on_arrival {
            let mut events = vec![GateEvent::Arrived(object)];
            match self.tracker.track(object).map(|t| t.centre) {
                Some(centre) => {
                    self.phase = Phase::Confirmed { object, centre };
                    events.push(GateEvent::Confirmed(object));
                }
                None => self.abandon(object, AbandonReason::Expired, &mut events),
            }
            return Ok(events);
        }
        let now = self.tracker.updates();
        self.phase = Phase::Verify {
            object,
            arrived_at: now,
            deadline: now.saturating_add(u64::from(self.tracker.config().verify_window)),
        };
        Ok(vec![GateEvent::Arrived(object)])
    }

    /// Reports that navigation to the candidate failed (unreachable, stuck,
    /// timed out): the candidate is rejected and searching resumes.
    ///
    /// # Errors
    /// [`GateError::WrongPhase`] unless approaching, [`GateError::NotActive`]
    /// when `object` is not the candidate being approached.
    pub fn on_approach_failed(&mut self, object: ObjectId) -> Result<Vec<GateEvent>, GateError> {
        self.expect_approaching(object)?;
        let mut events = Vec::new();
        self.reject(object, RejectReason::ApproachFailed, &mut events);
        Ok(events)
    }

    /// Follows a cluster id change of the map (see
    /// [`CandidateTracker::apply_remap`]). A candidate under approach or
    /// verification follows a rename or merge; a split returns the protocol to
    /// searching (the parts are re-evaluated at the next update).
    pub fn apply_remap(&mut self, pairs: &[(ObjectId, ObjectId)]) -> Vec<GateEvent> {
        let summary = self.tracker.apply_remap(pairs);
        let mut events = Vec::new();
        let Some(object) = self.phase.object() else {
            return events;
        };
        let Some(targets) = summary.moved.get(&object) else {
            return events;
        };
        match (targets.as_slice(), &mut self.phase) {
            (&[to], phase) => {
                match phase {
                    Phase::Approach { object }
                    | Phase::Verify { object, .. }
                    | Phase::Confirmed { object, .. } => *object = to,
                    Phase::Search => {}
                }
                if to != object {
                    events.push(GateEvent::Followed { from: object, to });
                }
            }
            (_, Phase::Confirmed { .. }) => {}
            _ => self.abandon(object, AbandonReason::Split, &mut events),
        }
        events
    }

    /// Restarts the gate for a new episode (same category and parameters).
    pub fn reset(&mut self) {
        self.tracker.clear();
        self.phase = Phase::Search;
        self.last_selection = None;
    }
}
