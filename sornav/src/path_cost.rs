//! Path costs of target candidates on the multi-level frontier map: the
//! target gate's tie-break between candidates of equal support (an object
//! upstairs is approached over the stairs, so a nearer-looking one on the
//! robot's floor may win).

use std::cell::RefCell;

use nalgebra::{Point2, Point3};
use sornav_frontier_graph::{Cell, MultiLevelMap, OccupancyGrid};
use sornav_target_gate::PathCost;

/// How far (m, horizontally) from a candidate's centre a traversable cell
/// of its level is looked for. An object's own cells are occupied (and
/// inflated by the robot radius), so the nearest free cell of a large
/// object (a bed, a sofa) is a metre or more from its centre.
pub(crate) const GOAL_SEARCH_RADIUS_M: f64 = 2.5;

/// [`PathCost`] of a candidate centre on a [`MultiLevelMap`]: the length
/// (sum of segment lengths, m) of the map's executable path from the
/// robot's feet to the traversable cell of the object's level nearest to
/// the centre ([`goal_point`]); `None` when the object is below every
/// level, no traversable cell lies within [`GOAL_SEARCH_RADIUS_M`], or no
/// path is known.
///
/// # Complexity
/// Each call: `O((r / res)²)` for the goal cell plus one
/// [`MultiLevelMap::path`] (a grid search on a shared level, one per portal
/// otherwise). The gate calls it only for qualifying candidates that tie on
/// the largest support, and only while searching.
pub(crate) struct MapPathCost<'a> {
    // `MultiLevelMap::path` reuses search scratch space, hence `&mut`.
    map: RefCell<&'a mut MultiLevelMap>,
    feet: Point3<f64>,
}

impl<'a> MapPathCost<'a> {
    /// Path costs from the robot's `feet` on `map`.
    pub(crate) fn new(map: &'a mut MultiLevelMap, feet: Point3<f64>) -> Self {
        Self {
            map: RefCell::new(map),
            feet,
        }
    }
}

impl PathCost for MapPathCost<'_> {
    fn path_cost(&self, centre: &Point3<f64>) -> Option<f64> {
        let mut map = self.map.borrow_mut();
        let goal = goal_point(&map, centre)?;
        let edge = map.path(&self.feet, &goal).ok()??;
        Some(path_length(&edge.path))
    }
}

/// The point a candidate centred at `centre` is reached at: the
/// traversable cell nearest to the centre (horizontally, within
/// [`GOAL_SEARCH_RADIUS_M`]) on the grid of the object's level (the floor
/// below it, [`MultiLevelMap::level_containing`]), at that floor's height.
pub(crate) fn goal_point(map: &MultiLevelMap, centre: &Point3<f64>) -> Option<Point3<f64>> {
    let level = map.level_containing(centre.z)?;
    let level_map = map.level_map(level)?;
    let grid = level_map.grid();
    let cell = nearest_traversable(grid, &centre.xy(), GOAL_SEARCH_RADIUS_M)?;
    let c = grid.cell_center(cell);
    Some(Point3::new(c.x, c.y, level_map.config().grid.floor_z))
}

/// The traversable cell whose centre is nearest to `p` within `radius`
/// (ties: smaller cell), searched in rings of growing Chebyshev distance
/// until no farther ring can hold a nearer cell.
///
/// # Complexity
/// `O((d / res)²)` for the distance `d <= radius` of the answer.
fn nearest_traversable(grid: &OccupancyGrid, p: &Point2<f64>, radius: f64) -> Option<Cell> {
    let res = grid.resolution();
    let c = grid.cell_of(p).ok()?;
    // Bounded: radius is a small constant and res > 0 (validated).
    #[allow(clippy::cast_possible_truncation)]
    let rings = (radius / res).ceil().clamp(0.0, 10_000.0) as i32;
    let mut best: Option<(f64, Cell)> = None;
    for k in 0..=rings {
        for dy in -k..=k {
            let edge = dy == -k || dy == k;
            let mut dx = -k;
            while dx <= k {
                let n = c.offset(dx, dy);
                if grid.is_traversable(n) {
                    let d = (grid.cell_center(n) - p).norm();
                    if d <= radius && best.is_none_or(|(bd, bc)| (d, n) < (bd, bc)) {
                        best = Some((d, n));
                    }
                }
                // Inner rows of the ring: only its two ends.
                dx += if edge || dx == k { 1 } else { 2 * k };
            }
        }
        // Cells of ring k + 1 are at least (k + 0.5) res from p (strict:
        // a cell there at exactly that distance could win the tie).
        if best.is_some_and(|(d, _)| d < (f64::from(k) + 0.5) * res) {
            break;
        }
    }
    best.map(|(_, cell)| cell)
}

/// Length of a polyline: the sum of its segment lengths.
pub(crate) fn path_length(path: &[Point3<f64>]) -> f64 {
    path.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use sornav_frontier_graph::FrontierMapConfig;

    /// A flat floor of radius 2 m seen from the origin.
    fn floor_map() -> MultiLevelMap {
        let mut map = MultiLevelMap::new(FrontierMapConfig::default()).unwrap();
        let feet = Point3::origin();
        let eye = Point3::new(0.0, 0.0, 0.88);
        let points: Vec<_> = (0..800)
            .map(|k| {
                let a = f64::from(k) * std::f64::consts::TAU / 800.0;
                let r = 0.5 + 1.5 * f64::from(k % 4) / 3.0;
                Point3::new(r * a.cos(), r * a.sin(), 0.0)
            })
            .collect();
        map.update(&feet, &eye, &points).unwrap();
        map.frontier_graph(&feet).unwrap();
        map
    }

    #[test]
    fn path_cost_on_the_floor_and_unreachable_cases() {
        let mut map = floor_map();
        let cost = MapPathCost::new(&mut map, Point3::origin());
        // A chair 1 m away on the floor: about 1 m of path.
        let c = cost.path_cost(&Point3::new(1.0, 0.0, 0.45)).unwrap();
        assert!((c - 1.0).abs() <= 0.15, "{c}");
        // A lamp hanging above the robot belongs to the floor below it.
        let c = cost.path_cost(&Point3::new(0.0, 0.0, 2.0)).unwrap();
        assert!(c <= 0.1, "{c}");
        // Far outside the mapped area, or below every floor: unreachable.
        assert_eq!(cost.path_cost(&Point3::new(30.0, 0.0, 0.4)), None);
        assert_eq!(cost.path_cost(&Point3::new(1.0, 0.0, -3.0)), None);
    }

    #[test]
    fn nearest_traversable_matches_brute_force() {
        let map = floor_map();
        let grid = map
            .level_map(sornav_frontier_graph::LevelId(0))
            .unwrap()
            .grid();
        let res = grid.resolution();
        for (x, y) in [(2.9, 0.3), (0.0, 2.6), (-1.7, -1.9), (0.2, 0.1), (4.0, 4.0)] {
            let p = Point2::new(x, y);
            let r = GOAL_SEARCH_RADIUS_M;
            let c = grid.cell_of(&p).unwrap();
            let n = (r / res).ceil() as i32;
            let mut brute: Option<(f64, Cell)> = None;
            for dy in -n..=n {
                for dx in -n..=n {
                    let q = c.offset(dx, dy);
                    let d = (grid.cell_center(q) - p).norm();
                    if grid.is_traversable(q)
                        && d <= r
                        && brute.is_none_or(|(bd, bc)| (d, q) < (bd, bc))
                    {
                        brute = Some((d, q));
                    }
                }
            }
            assert_eq!(nearest_traversable(grid, &p, r), brute.map(|b| b.1), "{p}");
        }
    }

    #[test]
    fn polyline_length() {
        let path = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(3.0, 4.0, 0.0),
            Point3::new(3.0, 4.0, 2.0),
        ];
        assert_eq!(path_length(&path), 7.0);
        assert_eq!(path_length(&path[..1]), 0.0);
    }
}
