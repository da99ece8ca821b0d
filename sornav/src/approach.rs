//! Placing a `NAV_TO_OBJECT` waypoint next to a target candidate.

use nalgebra::{Point2, Point3};
use sornav_frontier_graph::{FrontierError, LevelId, MultiLevelMap};

use crate::config::ApproachConfig;

/// A waypoint (on its level's floor) and the executable path to it.
pub(crate) type Approach = (Point3<f64>, Vec<Point3<f64>>);

/// Horizontal distance from `p` to the rectangle `[lo, hi]` (0 inside).
pub(crate) fn distance_to_box(p: &Point2<f64>, lo: &Point2<f64>, hi: &Point2<f64>) -> f64 {
    let dx = (lo.x - p.x).max(0.0).max(p.x - hi.x);
    let dy = (lo.y - p.y).max(0.0).max(p.y - hi.y);
    dx.hypot(dy)
}

/// Whether the segment from `p` to the nearest point of the box `[lo, hi]`
/// crosses no occupied cell outside the box (the object's own cells, and
/// one cell around them, do not count).
pub(crate) fn line_of_sight(
    grid: &sornav_frontier_graph::OccupancyGrid,
    p: &Point2<f64>,
    lo: &Point2<f64>,
    hi: &Point2<f64>,
) -> bool {
    let q = Point2::new(p.x.clamp(lo.x, hi.x), p.y.clamp(lo.y, hi.y));
    let res = grid.resolution();
    let n = ((q - p).norm() / (res / 2.0)).ceil() as usize;
    (0..=n).all(|i| {
        let s = p + (q - p) * (i as f64 / n.max(1) as f64);
        if distance_to_box(&s, lo, hi) <= res {
            return true;
        }
        grid.cell_of(&s)
            .is_ok_and(|c| grid.state(c) != sornav_frontier_graph::CellState::Occupied)
    })
}

/// A traversable waypoint on `level` within `[min_standoff_m, standoff_m]`
/// of the object's horizontal bounds `(lo, hi)` that the robot (feet at
/// `robot`, on any level) can reach, with its executable path (over stairs
/// when the object is on another level).
///
/// # Algorithm
/// Points on a `sample_step_m` lattice around the bounds are kept when
/// their distance to the bounds is in `[min_standoff_m, standoff_m]` and
/// their grid cell is traversable (free, outside the inflated obstacles).
/// With `line_of_sight`, the points that see the bounds on the occupancy
/// grid ([`line_of_sight`]) are used when there are any. The
/// `max_path_queries` candidates nearest to the robot (Euclidean) are
/// tried with the frontier map's exact shortest path (through the level's
/// grid and the stairs); the one with the shortest path wins. `Ok(None)`
/// when none is reachable or the level is unknown.
///
/// # Complexity
/// O(S) for S lattice samples plus `max_path_queries` shortest-path
/// searches (each O(N) in the traversable cells).
pub(crate) fn approach_waypoint(
    map: &mut MultiLevelMap,
    robot: Point3<f64>,
    level: LevelId,
    (lo, hi): (Point2<f64>, Point2<f64>),
    config: &ApproachConfig,
) -> Result<Option<Approach>, FrontierError> {
    let Some(level_map) = map.level_map(level) else {
        return Ok(None);
    };
    let floor = level_map.config().grid.floor_z;
    let step = config.sample_step_m;
    let reach = config.standoff_m;
    let nx = ((hi.x - lo.x + 2.0 * reach) / step)
        .ceil()
        .clamp(0.0, 4000.0) as usize;
    let ny = ((hi.y - lo.y + 2.0 * reach) / step)
        .ceil()
        .clamp(0.0, 4000.0) as usize;
    let grid = level_map.grid();
    let mut samples = Vec::new();
    for i in 0..=nx {
        for j in 0..=ny {
            let p = Point2::new(
                lo.x - reach + i as f64 * step,
                lo.y - reach + j as f64 * step,
            );
            let d = distance_to_box(&p, &lo, &hi);
            if d > reach || d < config.min_standoff_m {
                continue;
            }
            let Ok(cell) = grid.cell_of(&p) else {
                continue;
            };
            if grid.is_traversable(cell) {
                samples.push(p);
            }
        }
    }
    if config.line_of_sight {
        let seeing: Vec<Point2<f64>> = samples
            .iter()
            .copied()
            .filter(|p| line_of_sight(grid, p, &lo, &hi))
            .collect();
        if !seeing.is_empty() {
            samples = seeing;
        }
    }
    let robot2 = robot.xy();
    samples.sort_by(|a, b| (a - robot2).norm().total_cmp(&(b - robot2).norm()));
    samples.truncate(config.max_path_queries);
    let mut best: Option<(f64, Point3<f64>, Vec<Point3<f64>>)> = None;
    for p in samples {
        let p = Point3::new(p.x, p.y, floor);
        if let Some(edge) = map.path(&robot, &p)?
            && best.as_ref().is_none_or(|(len, _, _)| edge.length < *len)
        {
            best = Some((edge.length, p, edge.path));
        }
    }
    Ok(best.map(|(_, p, path)| (p, path)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;
    use proptest::prelude::*;
    use sornav_frontier_graph::FrontierMapConfig;

    /// A closed 8 m x 6 m room scanned from the origin, with a box
    /// obstacle `(lo, hi)`.
    fn room_with_box(lo: Point2<f64>, hi: Point2<f64>) -> MultiLevelMap {
        let mut map = MultiLevelMap::new(FrontierMapConfig::default()).unwrap();
        let mut points = Vec::new();
        for k in 0..1440 {
            let t = f64::from(k) * std::f64::consts::PI / 720.0;
            let (c, s) = (t.cos(), t.sin());
            let tx = if c.abs() > 1e-9 {
                4.0 / c.abs()
            } else {
                f64::INFINITY
            };
            let ty = if s.abs() > 1e-9 {
                3.0 / s.abs()
            } else {
                f64::INFINITY
            };
            // First hit of the box by slab intersection.
            let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
            for (d, l, h) in [(c, lo.x, hi.x), (s, lo.y, hi.y)] {
                if d.abs() < 1e-12 {
                    if l > 0.0 || h < 0.0 {
                        t0 = f64::INFINITY;
                    }
                } else {
                    let (a, b) = (l / d, h / d);
                    t0 = t0.max(a.min(b));
                    t1 = t1.min(a.max(b));
                }
            }
            let hit_box = (t0 <= t1 && t0 > 0.0).then_some(t0 + 0.01);
            let r = hit_box.unwrap_or(f64::INFINITY).min(tx.min(ty));
            points.push(Point3::new(r * c, r * s, 0.5));
        }
        map.update(&Point3::origin(), &Point3::new(0.0, 0.0, 0.5), &points)
            .unwrap();
        map
    }

    fn grid(map: &MultiLevelMap) -> &sornav_frontier_graph::OccupancyGrid {
        map.level_map(LevelId(0)).unwrap().grid()
    }

    #[test]
    fn line_of_sight_is_blocked_by_occupied_cells_only() {
        // Occluder seen from the origin; the target box lies behind it.
        let (blo, bhi) = (Point2::new(1.5, -0.5), Point2::new(1.7, 0.5));
        let map = room_with_box(blo, bhi);
        let (lo, hi) = (Point2::new(2.5, -0.2), Point2::new(2.9, 0.2));
        let grid = grid(&map);
        assert!(!line_of_sight(grid, &Point2::new(1.2, 0.0), &lo, &hi));
        assert!(line_of_sight(grid, &Point2::new(2.6, 1.2), &lo, &hi));
        // The occluder's own cells never block a view of the occluder.
        assert!(line_of_sight(grid, &Point2::new(1.2, 0.0), &blo, &bhi));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(16))]

        /// The waypoint is traversable, within the standoff of the object,
        /// reached by an executable path from the robot; with unlimited
        /// path queries it has the brute-force shortest path over all
        /// lattice samples, and limited queries never beat that.
        #[test]
        fn waypoint_is_valid_and_matches_brute_force(
            x in 1.5f64..3.0,
            y in -2.0f64..1.5,
            w in 0.2f64..0.8,
            h in 0.2f64..0.8,
        ) {
            let (lo, hi) = (Point2::new(x, y), Point2::new(x + w, y + h));
            let mut map = room_with_box(lo, hi);
            let robot = Point3::origin();
            let config = ApproachConfig::default();
            let unlimited = ApproachConfig { max_path_queries: usize::MAX, ..config };
            let limited = approach_waypoint(&mut map, robot, LevelId(0), (lo, hi), &config).unwrap();
            let best = approach_waypoint(&mut map, robot, LevelId(0), (lo, hi), &unlimited).unwrap();
            let (Some((p, path)), Some((q, _))) = (limited, best) else {
                return Err(TestCaseError::fail("the object's near side is free"));
            };
            prop_assert!(distance_to_box(&p.xy(), &lo, &hi) <= config.standoff_m + 1e-9);
            let cell = grid(&map).cell_of(&p.xy()).unwrap();
            prop_assert!(grid(&map).is_traversable(cell));
            prop_assert!((path[0] - robot).norm() <= 0.1);
            prop_assert!((path[path.len() - 1] - p).norm() <= 0.1);
            // Brute force: every lattice sample, exact path length.
            let step = config.sample_step_m;
            let reach = config.standoff_m;
            let mut brute = f64::INFINITY;
            let nx = ((w + 2.0 * reach) / step).ceil() as usize;
            let ny = ((h + 2.0 * reach) / step).ceil() as usize;
            for i in 0..=nx {
                for j in 0..=ny {
                    let s = Point2::new(lo.x - reach + i as f64 * step, lo.y - reach + j as f64 * step);
                    if distance_to_box(&s, &lo, &hi) > reach {
                        continue;
                    }
                    let c = grid(&map).cell_of(&s).unwrap();
                    if !grid(&map).is_traversable(c) {
                        continue;
                    }
                    // The room holds no other obstacle: every sample sees the box.
                    prop_assert!(line_of_sight(grid(&map), &s, &lo, &hi));
                    if let Some(e) = map.path(&robot, &Point3::new(s.x, s.y, 0.0)).unwrap() {
                        brute = brute.min(e.length);
                    }
                }
            }
            let len = |p: &Point3<f64>, map: &mut MultiLevelMap| map.path(&robot, p).unwrap().unwrap().length;
            prop_assert!((len(&q, &mut map) - brute).abs() < 1e-9);
            prop_assert!(len(&p, &mut map) >= brute - 1e-9);
        }
    }
}
