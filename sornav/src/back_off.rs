//! Backing off a place where the robot is stuck.
//!
//! A mission that fails as stuck before the robot left the place it was
//! dispatched from says more about that place than about the mission's
//! goal: the first move of every path planned from there is blocked by
//! something the map does not hold (the side of a stair's first tread the
//! robot stepped onto, a door jamb it stands against, a chair leg).
//! Excluding the goal then throws away a frontier that is fine, and the
//! next mission planned from the same place starts with the same blocked
//! move; once every goal is excluded so, the floor is declared exhausted
//! with most of it unseen.
//!
//! [`BackOff`] keeps the robot's most recent positions (the way it came,
//! which it has just driven, so it is passable whatever the map says) and,
//! after such a failure, the path back along them for
//! [`BACK_OFF_M`]: the agent drives it and plans again from there, keeping
//! the goal. Each place backs off once, at most [`BACK_OFF_LIMIT`] times
//! per target; beyond that a stuck mission excludes its goal as before.

use std::collections::VecDeque;

use nalgebra::Point3;
use sornav_executor::MissionId;

/// Spacing (m) of the recent positions.
const SPACING_M: f64 = 0.1;

/// Recent positions kept (a few metres of driving).
const RECENT_MAX: usize = 40;

/// How far (m) along the way it came the robot backs off.
pub(crate) const BACK_OFF_M: f64 = 0.75;

/// A back-off shorter than this (m, straight line) is not worth a mission.
const BACK_OFF_MIN_M: f64 = 0.3;

/// A mission failed "without progress" when the robot is this near (m) to
/// where it was dispatched from.
const NO_PROGRESS_M: f64 = 0.15;

/// Places within this distance (m) of an earlier back-off's start do not
/// back off again.
const SAME_PLACE_M: f64 = 0.3;

/// Back-offs per target.
pub(crate) const BACK_OFF_LIMIT: usize = 6;

/// Recent positions, mission starts and pending back-offs (see the module
/// documentation).
#[derive(Debug, Clone, Default)]
pub(crate) struct BackOff {
    /// Positions every [`SPACING_M`], oldest first.
    recent: VecDeque<Point3<f64>>,
    /// The active mission and where the robot was when it started.
    started: Option<(MissionId, Point3<f64>)>,
    /// A failure at this place asks for a back-off.
    pending: Option<Point3<f64>>,
    /// Where this target's back-offs started.
    origins: Vec<Point3<f64>>,
}

impl BackOff {
    /// Records the robot's position (kept when it is [`SPACING_M`] from
    /// the last kept one).
    ///
    /// # Complexity
    /// O(1).
    pub(crate) fn record(&mut self, position: Point3<f64>) {
        if self
            .recent
            .back()
            .is_none_or(|p| (p - position).norm() >= SPACING_M)
        {
            if self.recent.len() == RECENT_MAX {
                self.recent.pop_front();
            }
            self.recent.push_back(position);
        }
    }

    /// Notes that mission `id` is active with the robot at `position`
    /// (kept from its first call for the same mission).
    pub(crate) fn started(&mut self, id: MissionId, position: Point3<f64>) {
        if self.started.is_none_or(|(s, _)| s != id) {
            self.started = Some((id, position));
        }
    }

    /// Mission `id` failed stuck with the robot at `position`: whether a
    /// back-off is due instead of excluding the mission's goal (the robot
    /// did not leave its start, the place has not backed off before, the
    /// target's back-offs are not used up and the way back is long
    /// enough).
    pub(crate) fn on_stuck(&mut self, id: MissionId, position: &Point3<f64>) -> bool {
        let no_progress = self
            .started
            .is_some_and(|(s, p)| s == id && (p - position).norm() <= NO_PROGRESS_M);
        let due = no_progress
            && self.origins.len() < BACK_OFF_LIMIT
            && !self
                .origins
                .iter()
                .any(|o| (o - position).norm() < SAME_PLACE_M)
            && self.path(position).is_some();
        if due {
            self.pending = Some(*position);
        }
        due
    }

    /// The path of a due back-off from `position` (the robot's position
    /// first), marking it done; `None` when none is due or the robot has
    /// left the place meanwhile (the back-off is dropped then).
    pub(crate) fn take(&mut self, position: &Point3<f64>) -> Option<Vec<Point3<f64>>> {
        let origin = self.pending.take()?;
        if (origin - position).norm() >= SAME_PLACE_M {
            // The robot moved on meanwhile: no longer stuck there.
            return None;
        }
        let path = self.path(position)?;
        self.origins.push(origin);
        Some(path)
    }

    /// Whether a back-off is due.
    pub(crate) fn is_pending(&self) -> bool {
        self.pending.is_some()
    }

    /// Back-offs of the current target so far.
    #[cfg(test)]
    pub(crate) fn count(&self) -> usize {
        self.origins.len()
    }

    /// Forgets the target's back-offs (a new target).
    pub(crate) fn reset_target(&mut self) {
        self.pending = None;
        self.origins.clear();
    }

    /// The way back from `position` along the recent positions, up to
    /// [`BACK_OFF_M`] of driving; `None` when it ends nearer than
    /// [`BACK_OFF_MIN_M`].
    ///
    /// # Complexity
    /// O(`RECENT_MAX`).
    fn path(&self, position: &Point3<f64>) -> Option<Vec<Point3<f64>>> {
        let mut path = vec![*position];
        let mut length = 0.0;
        for p in self.recent.iter().rev() {
            let last = path[path.len() - 1];
            let d = (p - last).norm();
            if d < 1e-9 {
                continue;
            }
            length += d;
            path.push(*p);
            if length >= BACK_OFF_M {
                break;
            }
        }
        let end = path[path.len() - 1];
        ((end - position).norm() >= BACK_OFF_MIN_M).then_some(path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn driven(points: &[(f64, f64)]) -> BackOff {
        let mut b = BackOff::default();
        for &(x, y) in points {
            b.record(Point3::new(x, y, 0.0));
        }
        b
    }

    #[test]
    fn a_stuck_start_backs_off_along_the_way_in_once() {
        let mut b = driven(&[(0.0, 0.0), (0.25, 0.0), (0.5, 0.0), (0.75, 0.0), (1.0, 0.0)]);
        let here = Point3::new(1.0, 0.0, 0.0);
        b.started(MissionId(3), here);
        assert!(b.on_stuck(MissionId(3), &Point3::new(1.05, 0.0, 0.0)));
        let path = b.take(&here).expect("due");
        assert_eq!(path[0], here);
        assert_eq!(path.last().copied(), Some(Point3::new(0.25, 0.0, 0.0)));
        assert!(!b.is_pending());
        // The same place does not back off twice.
        b.started(MissionId(4), here);
        assert!(!b.on_stuck(MissionId(4), &here));
        assert_eq!(b.count(), 1);
    }

    #[test]
    fn progress_or_a_short_way_in_excludes_instead() {
        let mut b = driven(&[(0.0, 0.0), (0.5, 0.0), (1.0, 0.0)]);
        b.started(MissionId(1), Point3::new(0.0, 0.0, 0.0));
        assert!(!b.on_stuck(MissionId(1), &Point3::new(1.0, 0.0, 0.0)));
        let mut short = driven(&[(0.0, 0.0), (0.1, 0.0), (0.2, 0.0)]);
        short.started(MissionId(1), Point3::new(0.2, 0.0, 0.0));
        assert!(!short.on_stuck(MissionId(1), &Point3::new(0.2, 0.0, 0.0)));
        // Another mission's start does not count.
        let mut other = driven(&[(0.0, 0.0), (0.5, 0.0), (1.0, 0.0)]);
        other.started(MissionId(1), Point3::new(1.0, 0.0, 0.0));
        assert!(!other.on_stuck(MissionId(2), &Point3::new(1.0, 0.0, 0.0)));
    }

    proptest! {
        /// The back-off path starts at the robot, visits recent positions
        /// newest first, is not much longer than `BACK_OFF_M` and ends at
        /// least `BACK_OFF_MIN_M` away; the target's back-offs are bounded
        /// and never start twice at one place.
        #[test]
        fn back_offs_retrace_the_way_in_and_are_bounded(
            steps in proptest::collection::vec((-0.3f64..0.3, -0.3f64..0.3), 1..80),
            stuck in proptest::collection::vec(0usize..80, 1..20),
        ) {
            let mut b = BackOff::default();
            let mut at = Point3::new(0.0, 0.0, 0.0);
            let mut trail = vec![at];
            b.record(at);
            let mut origins: Vec<Point3<f64>> = Vec::new();
            for (k, &(dx, dy)) in steps.iter().enumerate() {
                at += nalgebra::Vector3::new(dx, dy, 0.0);
                b.record(at);
                trail.push(at);
                if !stuck.contains(&k) {
                    continue;
                }
                let id = MissionId(k as u64);
                b.started(id, at);
                if b.on_stuck(id, &at) {
                    let path = b.take(&at).expect("due after on_stuck");
                    prop_assert_eq!(path[0], at);
                    let mut len = 0.0;
                    for w in path.windows(2) {
                        len += (w[1] - w[0]).norm();
                    }
                    // The last leg may pass BACK_OFF_M by one spacing or step.
                    prop_assert!(len < BACK_OFF_M + 0.5);
                    prop_assert!((path[path.len() - 1] - at).norm() >= BACK_OFF_MIN_M);
                    for p in &path[1..] {
                        prop_assert!(trail.iter().any(|t| (t - p).norm() < 1e-12));
                    }
                    prop_assert!(origins.iter().all(|o| (o - at).norm() >= SAME_PLACE_M));
                    origins.push(at);
                }
            }
            prop_assert!(b.count() <= BACK_OFF_LIMIT);
            prop_assert_eq!(b.count(), origins.len());
        }
    }
}
