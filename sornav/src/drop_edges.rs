//! Drop edges: where the robot saw *through* its floor (a stairwell going
//! down, a mezzanine's edge) without seeing what lies just below.
//!
//! A return deeper than the grid's `drop_off_depth` under the floor of the
//! level the robot stands on came through a hole: where its ray passed that
//! depth, nothing stood above it, so there is no floor there (the
//! occupancy grid marks that crossing as a drop-off). From a distance a
//! level camera sees through a stairwell only the far wall or the floor
//! below, never the treads right under the edge: a stair going down stays
//! unrecognised, the floor is declared exhausted, and a target one floor
//! down is never found. Standing at the edge and looking down shows the
//! treads (the stair map then extracts the flight).
//!
//! Where such a ray passed the floor's own height is the *edge* it saw:
//! no floor there (the floor, if any, ends before it). [`DropEdges`]
//! keeps, per level and per [`DROP_EDGE_BIN_M`] bin of these edge points,
//! the smallest 3-D distance from an edge point to the return behind it
//! and where the sensor stood when the bin was first seen (the near side,
//! where the floor is). A bin is *unseen* while that distance exceeds
//! [`DROP_SEEN_GAP_M`]: what lies under the edge was only seen from afar.
//! A view down from the edge brings returns close to their crossings and
//! the bin becomes seen.

use std::collections::BTreeMap;

use nalgebra::{Point2, Point3};
use sornav_frontier_graph::LevelId;

/// Side (m) of the bins drop crossings are kept in: a robot's width.
pub(crate) const DROP_EDGE_BIN_M: f64 = 0.5;

/// Radius (m) around a drop edge within which a traversable place to look
/// into it from is sought, and within which other edges count as looked
/// into with it.
pub(crate) const DROP_LOOK_RADIUS_M: f64 = 1.2;

/// A bin is seen once a return lay within this 3-D distance (m) of its
/// crossing: the surface just under the edge (a stair's first treads lie
/// within a metre of it) was in view.
pub(crate) const DROP_SEEN_GAP_M: f64 = 1.0;

/// One bin of drop crossings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DropEdge {
    /// The first edge point recorded in the bin (where a ray passed the
    /// floor's height).
    pub(crate) at: Point3<f64>,
    /// Where the sensor stood (horizontally) when that ray was cast.
    pub(crate) from: Point2<f64>,
    /// Smallest distance (m) from an edge point of the bin to its return.
    pub(crate) min_gap: f64,
    /// Deepest return (m under the floor) seen through the bin.
    pub(crate) max_depth: f64,
}

impl DropEdge {
    /// Whether what lies under this edge was seen from close.
    pub(crate) fn seen(&self) -> bool {
        self.min_gap <= DROP_SEEN_GAP_M
    }
}

/// The drop edges seen so far, per level (see the module documentation).
#[derive(Debug, Clone, Default)]
pub(crate) struct DropEdges {
    bins: BTreeMap<(LevelId, i64, i64), DropEdge>,
    /// Edges the robot went to look into, per level.
    looked: Vec<(LevelId, Point2<f64>)>,
}

impl DropEdges {
    /// Records the drop edges of one scan taken from sensor `origin` by a
    /// robot standing on `level`, whose floor is at `floor_z`: every
    /// return of `points` deeper than `drop_depth` under the floor, at the
    /// point where its ray passed the floor's height. Non-finite points are
    /// skipped. Returns how many returns were drop-offs.
    ///
    /// # Complexity
    /// O(P log B) for P points and B bins.
    pub(crate) fn record(
        &mut self,
        level: LevelId,
        origin: &Point3<f64>,
        points: &[Point3<f64>],
        floor_z: f64,
        drop_depth: f64,
    ) -> usize {
        let depth_z = floor_z - drop_depth;
        if !(origin.coords.iter().all(|v| v.is_finite()) && depth_z.is_finite())
            || origin.z <= depth_z
        {
            return 0;
        }
        let mut n = 0;
        for p in points {
            if !p.coords.iter().all(|v| v.is_finite()) || p.z >= depth_z {
                continue;
            }
            let d = p - origin;
            // d.z < 0: p is below the depth, the origin above it. The edge
            // point is where the ray passed the floor's height (the sensor
            // may be under it: then the ray started below the floor).
            let t = ((floor_z - origin.z) / d.z).max(0.0);
            let edge = origin + d * t;
            let gap = (p - edge).norm();
            let key = (
                level,
                (edge.x / DROP_EDGE_BIN_M).floor() as i64,
                (edge.y / DROP_EDGE_BIN_M).floor() as i64,
            );
            let at = Point3::new(edge.x, edge.y, floor_z);
            let e = self.bins.entry(key).or_insert(DropEdge {
                at,
                from: origin.xy(),
                min_gap: f64::INFINITY,
                max_depth: 0.0,
            });
            e.min_gap = e.min_gap.min(gap);
            e.max_depth = e.max_depth.max(floor_z - p.z);
            n += 1;
        }
        n
    }

    /// Marks the edge at `at` of `level` looked into: edges within
    /// [`DROP_LOOK_RADIUS_M`] of it are no longer [`unseen`](Self::unseen).
    pub(crate) fn mark_looked(&mut self, level: LevelId, at: &Point3<f64>) {
        self.looked.push((level, at.xy()));
    }

    /// The unseen drop edges of `level` not looked into, nearest to `from`
    /// first (horizontally; ties by position).
    ///
    /// # Complexity
    /// O(B (log B + K)) for the B bins and K looks.
    pub(crate) fn unseen(&self, level: LevelId, from: &Point2<f64>) -> Vec<DropEdge> {
        let mut v: Vec<DropEdge> = self
            .bins
            .iter()
            .filter(|((l, _, _), e)| *l == level && !e.seen())
            .filter(|(_, e)| {
                !self
                    .looked
                    .iter()
                    .any(|(l, p)| *l == level && (p - e.at.xy()).norm() <= DROP_LOOK_RADIUS_M)
            })
            .map(|(_, e)| *e)
            .collect();
        v.sort_by(|a, b| {
            let (da, db) = ((a.at.xy() - from).norm(), (b.at.xy() - from).norm());
            da.total_cmp(&db)
                .then(a.at.x.total_cmp(&b.at.x))
                .then(a.at.y.total_cmp(&b.at.y))
        });
        v
    }

    /// Number of bins (seen or not) over all levels.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.bins.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const L0: LevelId = LevelId(0);

    /// A stairwell seen from afar with a level camera: the ray meets the
    /// far wall 2 m under the floor, far beyond where it crossed the drop
    /// depth: unseen. Looking down from the edge: seen.
    #[test]
    fn a_stairwell_seen_from_afar_is_unseen_until_looked_into() {
        let mut edges = DropEdges::default();
        let eye = Point3::new(0.0, 0.0, 0.9);
        // Passes the floor at x = 2.25 (2.4 m drop over 6 m), returns at
        // x = 6.
        let far = Point3::new(6.0, 0.0, -1.5);
        assert_eq!(edges.record(L0, &eye, &[far], 0.0, 0.3), 1);
        let unseen = edges.unseen(L0, &Point2::origin());
        assert_eq!(unseen.len(), 1);
        assert!((unseen[0].at.x - 2.25).abs() < 1e-9, "{:?}", unseen[0]);
        assert_eq!(unseen[0].at.z, 0.0);
        assert_eq!(unseen[0].from, Point2::origin());
        assert!((unseen[0].max_depth - 1.5).abs() < 1e-9);
        // From 0.45 m before the edge, looking down at a tread 0.5 m under
        // it.
        let near_eye = Point3::new(1.8, 0.0, 0.9);
        let tread = Point3::new(2.5, 0.0, -0.5);
        edges.record(L0, &near_eye, &[tread], 0.0, 0.3);
        assert!(edges.unseen(L0, &Point2::origin()).is_empty());
        // Floor returns, obstacles and bad points are no drops.
        let others = [
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, 0.5),
            Point3::new(f64::NAN, 0.0, -2.0),
        ];
        assert_eq!(edges.record(L0, &eye, &others, 0.0, 0.3), 0);
        // Another level's edges are apart.
        assert!(edges.unseen(LevelId(1), &Point2::origin()).is_empty());
        // An edge looked into is not offered again, nor are its neighbours.
        let mut other = DropEdges::default();
        // (The second edge point is (2.25, 1.125): another bin, 1.125 m
        // from the first.)
        other.record(L0, &eye, &[far, Point3::new(6.0, 3.0, -1.5)], 0.0, 0.3);
        assert_eq!(other.unseen(L0, &Point2::origin()).len(), 2);
        other.mark_looked(L0, &Point3::new(2.25, 0.0, 0.0));
        assert!(other.unseen(L0, &Point2::origin()).is_empty());
    }

    proptest! {
        /// Differential: each bin's gap is the minimum over its edge
        /// points, computed by brute force over the scan; edge points lie
        /// at the floor's height on the segment from the sensor to the
        /// return.
        #[test]
        fn bins_keep_the_smallest_gap(
            pts in prop::collection::vec((-5.0f64..5.0, -5.0f64..5.0, -3.0f64..0.5), 1..40),
            ox in -1.0f64..1.0, oy in -1.0f64..1.0,
        ) {
            let origin = Point3::new(ox, oy, 0.9);
            let points: Vec<Point3<f64>> = pts.iter().map(|&(x, y, z)| Point3::new(x, y, z)).collect();
            let mut edges = DropEdges::default();
            let n = edges.record(L0, &origin, &points, 0.0, 0.3);
            let drops: Vec<&Point3<f64>> = points.iter().filter(|p| p.z < -0.3).collect();
            prop_assert_eq!(n, drops.len());
            let mut want: BTreeMap<(i64, i64), f64> = BTreeMap::new();
            let mut deep: BTreeMap<(i64, i64), f64> = BTreeMap::new();
            for p in drops {
                let t = (0.0 - origin.z) / (p.z - origin.z);
                prop_assert!((0.0..=1.0).contains(&t));
                let c = origin + (p - origin) * t;
                prop_assert!(c.z.abs() < 1e-9);
                let key = ((c.x / DROP_EDGE_BIN_M).floor() as i64, (c.y / DROP_EDGE_BIN_M).floor() as i64);
                let g = (p - c).norm();
                let e = want.entry(key).or_insert(f64::INFINITY);
                *e = e.min(g);
                let d = deep.entry(key).or_insert(0.0);
                *d = d.max(-p.z);
            }
            prop_assert_eq!(edges.len(), want.len());
            let unseen = edges.unseen(L0, &Point2::origin());
            prop_assert_eq!(unseen.len(), want.values().filter(|g| **g > DROP_SEEN_GAP_M).count());
            for e in &unseen {
                let key = ((e.at.x / DROP_EDGE_BIN_M).floor() as i64, (e.at.y / DROP_EDGE_BIN_M).floor() as i64);
                prop_assert_eq!(Some(&e.max_depth), deep.get(&key));
            }
            for w in unseen.windows(2) {
                prop_assert!(w[0].at.xy().coords.norm() <= w[1].at.xy().coords.norm());
            }
        }
    }
}
