//! Progress along a path and stuck detection.

use std::collections::VecDeque;
use std::time::Duration;

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

/// Remaining distance to the waypoint, measured along the path when one is
/// given.
///
/// With a path `p_0 .. p_k`: the robot is projected onto the nearest point of
/// the polyline; the remaining distance is the arc length from that point to
/// `p_k` plus `|p_k - waypoint|`. Without a path (or with a single point) it
/// is the straight-line distance to the waypoint.
///
/// # Complexity
/// `O(k)` for `k` path segments.
pub fn remaining_distance(
    position: &Point3<f64>,
    waypoint: &Point3<f64>,
    path: Option<&[Point3<f64>]>,
) -> f64 {
    let Some(path) = path.filter(|p| p.len() >= 2) else {
        return nalgebra::distance(position, waypoint);
    };
    let last = path[path.len() - 1];
    let tail = nalgebra::distance(&last, waypoint);
    // Arc length after each vertex, then the best projection.
    let mut after = 0.0;
    let mut best = (f64::INFINITY, 0.0);
    for i in (0..path.len() - 1).rev() {
        let (a, b) = (path[i], path[i + 1]);
        let ab = b - a;
        let len2 = ab.norm_squared();
        let t = if len2 > 0.0 {
            ((position - a).dot(&ab) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let q = a + ab * t;
        let dist = nalgebra::distance(position, &q);
        let remaining = after + (1.0 - t) * len2.sqrt();
        if dist < best.0 {
            best = (dist, remaining);
        }
        after += len2.sqrt();
    }
    best.1 + tail
}

/// Sliding-window stuck detector.
///
/// Feed it the remaining distance at successive times. Let `b(t)` be the
/// smallest remaining distance recorded at or before `t`. At time `now`,
/// once at least `window` has passed since the first record, the robot is
/// stuck when `b(now - window) - b(now) <= min_progress`: it got no more than
/// `min_progress` metres closer during the last `window`.
///
/// Times that go backwards are treated as equal to the latest time.
///
/// # Complexity
/// Amortised `O(1)` per record; memory is the number of records inside one
/// window.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StuckDetector {
    window: Duration,
    min_progress: f64,
    /// `(time, best remaining so far)`, oldest first; the front is the latest
    /// record at or before `now - window` once the window is full.
    samples: VecDeque<(Duration, f64)>,
    first: Option<Duration>,
}

impl StuckDetector {
    /// A detector for "at most `min_progress` metres within `window`".
    pub fn new(window: Duration, min_progress: f64) -> Self {
        Self {
            window,
            min_progress,
            samples: VecDeque::new(),
            first: None,
        }
    }

    /// Records the remaining distance at `now` and returns the progress made
    /// during the last window if the robot is stuck, else `None`.
    pub fn record(&mut self, now: Duration, remaining: f64) -> Option<f64> {
        let now = self.samples.back().map_or(now, |&(t, _)| t.max(now));
        let best = self
            .samples
            .back()
            .map_or(remaining, |&(_, b)| b.min(remaining));
        self.samples.push_back((now, best));
        let first = *self.first.get_or_insert(now);
        let horizon = now.checked_sub(self.window)?;
        if horizon < first {
            return None;
        }
        while self.samples.len() >= 2 && self.samples[1].0 <= horizon {
            self.samples.pop_front();
        }
        let progress = self.samples[0].1 - best;
        (progress <= self.min_progress).then_some(progress)
    }

    /// Forgets all records (a new path or waypoint).
    pub fn reset(&mut self) {
        self.samples.clear();
        self.first = None;
    }
}
