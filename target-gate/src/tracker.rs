//! Per-candidate tracking: evidence updates, expiry, rejection marks and
//! best-candidate selection.

use std::collections::{BTreeMap, BTreeSet};

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::{
    CandidateReport, Evidence, GateConfig, GateError, ObjectId, PathCost, Selection, StraightLine,
    Visibility,
};

/// Everything the gate knows about one candidate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Track {
    /// The candidate's cluster id.
    pub object: ObjectId,
    /// `s_t` and `m_t`.
    pub evidence: Evidence,
    /// Last reported cluster centre.
    pub centre: Point3<f64>,
    /// Last reported voxel count.
    pub voxels: u32,
    /// Update index at which tracking started.
    pub first_seen: u64,
    /// Update index of the last supporting observation.
    pub last_detected: u64,
}

/// What one update did to each candidate.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct UpdateSummary {
    /// Update index (1 for the first update).
    pub update: u64,
    /// Candidates with `z_t = 1` (including newly tracked ones).
    pub detected: Vec<ObjectId>,
    /// Candidates with `z_t = 0`.
    pub missed: Vec<ObjectId>,
    /// Candidates that started being tracked.
    pub started: Vec<ObjectId>,
    /// Candidates removed because `m_t > N_miss`.
    pub expired: Vec<ObjectId>,
    /// Reports rejected as malformed (non-finite centre) or duplicated within
    /// the update; they carry no evidence either way.
    pub rejected_reports: u32,
}

/// Tracks the evidence `(s_t, m_t)` of every candidate of one requested
/// category, keyed by [`ObjectId`].
///
/// How a report becomes `z_t` for a candidate at one update:
///
/// | report of the candidate at this update | tracked? | effect |
/// |---|---|---|
/// | valid (category `g`, `>= N_min` voxels) and detected | no | start tracking, `z = 1` |
/// | valid and detected | yes | `z = 1` |
/// | valid, not detected, in view and negative evidence on | yes | `z = 0` |
/// | valid, not detected, otherwise | yes | no evidence (counters unchanged) |
/// | invalid (other category, `< N_min` voxels) or absent | yes | `z = 0` |
/// | malformed or duplicate | any | rejected and counted, no evidence |
///
/// A candidate whose `m_t` exceeds `N_miss` expires (is removed). The
/// "no evidence" row is what keeps a candidate alive while the robot looks
/// elsewhere; with negative evidence on, looking at its location without
/// detecting it does count against it.
///
/// # Complexity
/// An update costs `O((r + n) log n)` for `r` reports and `n` tracked
/// candidates; selection is `O(n)` plus one path-cost call per candidate
/// tied on the largest support ([`best_by`](Self::best_by)).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CandidateTracker<C> {
    target: C,
    config: GateConfig,
    tracks: BTreeMap<ObjectId, Track>,
    /// Rejection marks: id -> first update index at which it may be selected
    /// again. Kept apart from the tracks so that a mark survives the
    /// candidate's expiry and re-detection.
    rejected: BTreeMap<ObjectId, u64>,
    update: u64,
}

impl<C: PartialEq> CandidateTracker<C> {
    /// A tracker for candidates of category `target`.
    ///
    /// # Errors
    /// [`GateError::InvalidConfig`] when `config` is invalid.
    pub fn new(target: C, config: GateConfig) -> Result<Self, GateError> {
        config.validate()?;
        Ok(Self {
            target,
            config,
            tracks: BTreeMap::new(),
            rejected: BTreeMap::new(),
            update: 0,
        })
    }

    /// The requested category `g`.
    pub fn target(&self) -> &C {
        &self.target
    }

    /// The parameters.
    pub fn config(&self) -> &GateConfig {
        &self.config
    }

    /// Number of updates applied so far.
    pub fn updates(&self) -> u64 {
        self.update
    }

    /// The tracked candidates, ordered by id.
    pub fn tracks(&self) -> impl Iterator<Item = &Track> {
        self.tracks.values()
    }

    /// One tracked candidate.
    pub fn track(&self, object: ObjectId) -> Option<&Track> {
        self.tracks.get(&object)
    }

    pub(crate) fn parts_mut(
        &mut self,
    ) -> (&mut BTreeMap<ObjectId, Track>, &mut BTreeMap<ObjectId, u64>) {
        (&mut self.tracks, &mut self.rejected)
    }

    /// When `object` was rejected and its cool-down has not run out: the first
    /// update index at which it may be selected again.
    pub fn rejected_until(&self, object: ObjectId) -> Option<u64> {
        self.rejected
            .get(&object)
            .copied()
            .filter(|&until| self.update < until)
    }

    /// Whether a report is a valid candidate of the requested category.
    pub fn is_valid(&self, report: &CandidateReport<C>) -> bool {
        report.category == self.target && report.voxels >= self.config.n_min
    }

    /// Applies one update: the map's current cluster snapshot `reports` and,
    /// for negative evidence, the caller's `visibility` test (ignored unless
    /// [`GateConfig::negative_evidence`] is on).
    pub fn update(
        &mut self,
        reports: &[CandidateReport<C>],
        visibility: &dyn Visibility,
    ) -> UpdateSummary {
        self.update += 1;
        let now = self.update;
        let mut summary = UpdateSummary {
            update: now,
            ..UpdateSummary::default()
        };
        let mut seen = BTreeSet::new();
        for report in reports {
            if !seen.insert(report.object) {
                summary.rejected_reports += 1;
                continue;
            }
            if !(report.centre.x.is_finite()
                && report.centre.y.is_finite()
                && report.centre.z.is_finite())
            {
                summary.rejected_reports += 1;
                continue;
            }
            let valid = self.is_valid(report);
            match self.tracks.get_mut(&report.object) {
                Some(track) => {
                    let z = if !valid {
                        Some(false)
                    } else if report.detected {
                        Some(true)
                    } else if self.config.negative_evidence
                        && visibility.in_view(report.object, &report.centre)
                    {
                        Some(false)
                    } else {
                        None
                    };
                    if valid {
                        track.centre = report.centre;
                        track.voxels = report.voxels;
                    }
                    match z {
                        Some(true) => {
                            track.evidence.observe(true);
                            track.last_detected = now;
                            summary.detected.push(report.object);
                        }
                        Some(false) => {
                            track.evidence.observe(false);
                            summary.missed.push(report.object);
                        }
                        None => {}
                    }
                }
                None if valid && report.detected => {
                    let mut evidence = Evidence::default();
                    evidence.observe(true);
                    self.tracks.insert(
                        report.object,
                        Track {
                            object: report.object,
                            evidence,
                            centre: report.centre,
                            voxels: report.voxels,
                            first_seen: now,
                            last_detected: now,
                        },
                    );
                    summary.started.push(report.object);
                    summary.detected.push(report.object);
                }
                None => {}
            }
        }
        for (id, track) in &mut self.tracks {
            if !seen.contains(id) {
                track.evidence.observe(false);
                summary.missed.push(*id);
            }
        }
        self.rejected.retain(|_, until| now < *until);
        let config = self.config;
        self.tracks.retain(|id, track| {
            let expired = track.evidence.expired(&config);
            if expired {
                summary.expired.push(*id);
            }
            !expired
        });
        summary.detected.sort_unstable();
        summary.missed.sort_unstable();
        summary
    }

    /// Whether `object` may be selected now: tracked, `s_t >= N_obs`,
    /// `m_t <= N_miss`, and not cooling down after a rejection.
    pub fn qualifies(&self, object: ObjectId) -> bool {
        self.tracks
            .get(&object)
            .is_some_and(|t| self.track_qualifies(t))
    }

    fn track_qualifies(&self, track: &Track) -> bool {
        track.evidence.qualifies(&self.config) && self.rejected_until(track.object).is_none()
    }

    /// The best qualifying candidate: most support `s_t`, then nearest to
    /// `robot` in a straight line (Euclidean distance to the cluster
    /// centre), then smallest id. This is [`best_by`](Self::best_by) with
    /// [`StraightLine`]; on a map with walls or several floors use
    /// `best_by` with the map's path costs.
    ///
    /// # Complexity
    /// `O(n)` for `n` tracked candidates.
    ///
    /// # Errors
    /// [`GateError::NonFinite`] when `robot` has a non-finite coordinate.
    pub fn best(&self, robot: &Point3<f64>) -> Result<Option<ObjectId>, GateError> {
        if !(robot.x.is_finite() && robot.y.is_finite() && robot.z.is_finite()) {
            return Err(GateError::NonFinite("robot position"));
        }
        Ok(self.best_by(&StraightLine::new(*robot)).object)
    }

    /// The best qualifying candidate by path cost. Ranking:
    ///
    /// 1. most support `s_t`;
    /// 2. reachable (a valid cost) before unreachable;
    /// 3. lower path cost;
    /// 4. smallest id.
    ///
    /// `cost` answers for a candidate centre; `None`, NaN, infinite and
    /// negative answers all mean unreachable (the last three are counted in
    /// [`Selection::invalid_costs`]). An unreachable candidate is still
    /// chosen when it alone has the most support: reachability only breaks
    /// ties, and the caller reports a failed approach with
    /// [`TargetGate::on_approach_failed`](crate::TargetGate::on_approach_failed).
    ///
    /// # Complexity
    /// `O(n)` for `n` tracked candidates plus one `cost` call per
    /// qualifying candidate that ties on the largest support (none when one
    /// candidate has the most support).
    ///
    /// # Example
    /// ```
    /// use nalgebra::Point3;
    /// use sornav_target_gate::{CandidateReport, CandidateTracker, GateConfig, NeverVisible, ObjectId};
    ///
    /// let mut tracker = CandidateTracker::new("bed", GateConfig::default()).unwrap();
    /// let report = |id, x, z| CandidateReport {
    ///     object: ObjectId(id), category: "bed", voxels: 50,
    ///     centre: Point3::new(x, 0.0, z), detected: true,
    /// };
    /// // Two beds: one almost above the robot (upstairs), one 4 m away.
    /// let beds = [report(1, 0.5, 3.0), report(2, 4.0, 0.5)];
    /// for _ in 0..3 {
    ///     tracker.update(&beds, &NeverVisible);
    /// }
    /// // In a straight line the upstairs bed is nearer...
    /// assert_eq!(tracker.best(&Point3::origin()).unwrap(), Some(ObjectId(1)));
    /// // ...but by path (12 m over the stairs) the other one wins.
    /// let by_path = |c: &Point3<f64>| Some(if c.z > 2.0 { 12.0 } else { 4.0 });
    /// let choice = tracker.best_by(&by_path);
    /// assert_eq!(choice.object, Some(ObjectId(2)));
    /// assert_eq!(choice.queries, 2);
    /// ```
    pub fn best_by(&self, cost: &dyn PathCost) -> Selection {
        let mut selection = Selection::default();
        // Pass 1: the largest support and how many qualifying candidates
        // have it.
        let mut top: Option<(u32, ObjectId)> = None;
        for track in self.tracks.values() {
            if !self.track_qualifies(track) {
                continue;
            }
            let s = track.evidence.support;
            match top {
                Some((best, _)) if s < best => {}
                Some((best, _)) if s == best => selection.tied += 1,
                _ => {
                    top = Some((s, track.object));
                    selection.tied = 1;
                }
            }
        }
        let Some((support, first)) = top else {
            return selection;
        };
        if selection.tied == 1 {
            selection.object = Some(first);
            return selection;
        }
        // Pass 2: the tied candidates by (unreachable, cost, id); ids
        // ascend, so a strict comparison keeps the smallest on ties.
        let mut best: Option<(Option<f64>, ObjectId)> = None;
        for track in self.tracks.values() {
            if track.evidence.support != support || !self.track_qualifies(track) {
                continue;
            }
            selection.queries += 1;
            let c = match cost.path_cost(&track.centre) {
                Some(c) if c.is_finite() && c >= 0.0 => Some(c),
                Some(_) => {
                    selection.invalid_costs += 1;
                    None
                }
                None => {
                    selection.unreachable += 1;
                    None
                }
            };
            let better = match (best, c) {
                (None, _) => true,
                (Some((None, _)), Some(_)) => true,
                (Some((Some(b), _)), Some(c)) => c < b,
                (Some(_), None) => false,
            };
            if better {
                best = Some((c, track.object));
            }
        }
        selection.object = best.map(|(_, o)| o);
        selection
    }

    /// Marks `object` as rejected: it cannot be selected during the next
    /// [`GateConfig::reject_cooldown`] updates (even if it expires and is
    /// detected anew meanwhile), and its support is reset to zero, so after
    /// the cool-down it needs `N_obs` fresh detections again. Returns whether
    /// the candidate was tracked (the mark is set either way).
    pub fn reject(&mut self, object: ObjectId) -> bool {
        let until = self
            .update
            .saturating_add(u64::from(self.config.reject_cooldown));
        self.rejected.insert(object, until);
        match self.tracks.get_mut(&object) {
            Some(track) => {
                track.evidence.support = 0;
                true
            }
            None => false,
        }
    }

    /// Forgets every candidate and restarts the update count.
    pub fn clear(&mut self) {
        self.tracks.clear();
        self.rejected.clear();
        self.update = 0;
    }
}
