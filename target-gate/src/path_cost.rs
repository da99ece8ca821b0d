//! Caller-provided path cost for choosing which candidate to approach.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::ObjectId;

/// The cost of reaching a candidate from where the robot is now, used to
/// choose among qualifying candidates of equal support (see
/// [`CandidateTracker::best_by`](crate::CandidateTracker::best_by)).
///
/// `path_cost(centre)` returns the cost of the executable path from the
/// robot to the candidate centred at `centre` on the reachable map (for
/// example its length in metres, over stairs when the candidate is on
/// another floor), or `None` when the candidate is not reachable on the
/// current map. A returned cost that is NaN, infinite or negative is
/// treated as `None` (unreachable) and counted in
/// [`Selection::invalid_costs`].
///
/// The tracker calls it lazily: only for qualifying candidates that tie on
/// the largest support, at most once each per selection, and not at all
/// when one candidate has the most support. An implementation may
/// therefore run a shortest-path search per call.
///
/// Closures `Fn(&Point3<f64>) -> Option<f64>` implement it;
/// [`StraightLine`] is the straight-line distance (the behaviour of
/// [`CandidateTracker::best`](crate::CandidateTracker::best), for 2-D
/// users and maps without obstacles).
///
/// # Example
/// ```
/// use nalgebra::Point3;
/// use sornav_target_gate::{PathCost, StraightLine};
///
/// // Only candidates on the ground floor (z < 2.5 m) are reachable; the
/// // cost is the horizontal distance from the robot at the origin.
/// let ground_floor = |c: &Point3<f64>| (c.z < 2.5).then(|| c.x.hypot(c.y));
/// assert_eq!(ground_floor.path_cost(&Point3::new(3.0, 4.0, 0.5)), Some(5.0));
/// assert_eq!(ground_floor.path_cost(&Point3::new(0.0, 1.0, 3.0)), None);
/// let line = StraightLine::new(Point3::origin());
/// assert_eq!(line.path_cost(&Point3::new(0.0, 1.0, 3.0)), Some(10f64.sqrt()));
/// ```
pub trait PathCost {
    /// Cost of reaching the candidate centred at `centre`; `None` when it
    /// is not reachable on the current map.
    fn path_cost(&self, centre: &Point3<f64>) -> Option<f64>;
}

impl<F> PathCost for F
where
    F: Fn(&Point3<f64>) -> Option<f64>,
{
    fn path_cost(&self, centre: &Point3<f64>) -> Option<f64> {
        self(centre)
    }
}

/// A [`PathCost`]: the straight-line (3-D Euclidean) distance from `robot`
/// to the candidate centre; every candidate is reachable. Suits 2-D users
/// and open spaces; on a map with walls or floors prefer a cost from the
/// map's shortest paths.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StraightLine {
    /// The robot's position.
    pub robot: Point3<f64>,
}

impl StraightLine {
    /// Straight-line distances from `robot`.
    pub fn new(robot: Point3<f64>) -> Self {
        Self { robot }
    }
}

impl PathCost for StraightLine {
    fn path_cost(&self, centre: &Point3<f64>) -> Option<f64> {
        Some(nalgebra::distance(&self.robot, centre))
    }
}

/// The outcome of one candidate selection
/// ([`CandidateTracker::best_by`](crate::CandidateTracker::best_by)).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Selection {
    /// The chosen candidate; `None` when no candidate qualifies.
    pub object: Option<ObjectId>,
    /// Qualifying candidates with the largest support (the ones the choice
    /// was made among).
    pub tied: u32,
    /// [`PathCost::path_cost`] calls made (0 when at most one candidate
    /// has the largest support).
    pub queries: u32,
    /// Calls that answered `None` (not reachable).
    pub unreachable: u32,
    /// Calls that answered a NaN, infinite or negative cost (treated as
    /// unreachable).
    pub invalid_costs: u32,
}
