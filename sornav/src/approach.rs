//! Placing a `NAV_TO_OBJECT` waypoint next to a target candidate.

use nalgebra::{Point2, Point3};
use sornav_frontier_graph::{FrontierError, LevelId, MultiLevelMap};
use sornav_semantic_map::SemanticMap;

use crate::config::ApproachConfig;
use crate::view::{FLOOR_TOLERANCE_M, ObjectView, Viewer, distance_to_box};

/// A waypoint (on its level's floor) and the executable path to it.
pub(crate) type Approach = (Point3<f64>, Vec<Point3<f64>>);

/// Which candidates [`approach_waypoint`] may return.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ViewDemand {
    /// View points first (see [`approach_waypoint`]); any traversable
    /// sample within the standoff when there is none.
    Prefer,
    /// View points only: `Ok(None)` when there is none.
    Require,
}

/// Whether a surface the robot could stand on at `p`'s column lies above
/// its floor (`p.z`) by more than [`FLOOR_TOLERANCE_M`] and below a
/// table's height: a hearth, a platform, a step — not a view point.
fn raised(map: &MultiLevelMap, p: &Point3<f64>) -> bool {
    map.surfaces_at(p.x, p.y)
        .iter()
        .any(|&z| z > p.z + FLOOR_TOLERANCE_M && z < p.z + 0.5)
}

/// The object to approach and how the robot will see it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ApproachTarget<'a> {
    /// The object's observed voxels.
    pub object: &'a ObjectView,
    /// The semantic map: its observed voxels hide what lies behind them.
    pub voxels: &'a SemanticMap,
    /// The robot's sensor.
    pub viewer: Viewer,
    /// The mission's arrival radius (m): the robot stops up to this far
    /// from the waypoint.
    pub arrival_radius_m: f64,
    /// Whether the waypoint must be a view point.
    pub demand: ViewDemand,
}

/// A traversable waypoint on `level` within `[min_standoff_m, standoff_m]`
/// of the object's horizontal bounds that the robot (feet at `robot`, on
/// any level) can reach, with its executable path (over stairs when the
/// object is on another level).
///
/// # Algorithm
/// Points on a `sample_step_m` lattice around the bounds are kept when
/// their distance to the bounds is in `[min_standoff_m, standoff_m]` and
/// their grid cell is traversable (free, outside the inflated obstacles).
/// With `line_of_sight` (or [`ViewDemand::Require`]) the samples are
/// ranked in tiers:
/// 1. view points ([`ObjectView::seen_from`], on the floor rather than on
///    a raised surface) whose reach stays within
///    `max_reach_m` less `arrival_radius_m`, so that any stop within the
///    arrival radius of the waypoint is still within reach;
/// 2. the other view points (within `max_reach_m`);
/// 3. with [`ViewDemand::Prefer`] only, every sample.
///
/// In each tier in turn, the `max_path_queries` candidates nearest to the
/// robot (Euclidean) are tried with the frontier map's exact shortest path
/// (through the level's grid and the stairs); the one with the shortest
/// path wins, and later tiers are tried only when no candidate of a tier
/// is reachable. `Ok(None)` when none is reachable or the level is
/// unknown.
///
/// # Complexity
/// O(S P L) for S lattice samples, P <= 48 object points and L voxels per
/// line of sight, plus `max_path_queries` shortest-path searches (each
/// O(N) in the traversable cells).
pub(crate) fn approach_waypoint(
    map: &mut MultiLevelMap,
    robot: Point3<f64>,
    level: LevelId,
    target: &ApproachTarget<'_>,
    config: &ApproachConfig,
) -> Result<Option<Approach>, FrontierError> {
    let ApproachTarget {
        object,
        voxels,
        viewer,
        arrival_radius_m,
        demand,
    } = *target;
    let Some(level_map) = map.level_map(level) else {
        return Ok(None);
    };
    let floor = level_map.config().grid.floor_z;
    let (lo, hi) = object.footprint();
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
                samples.push(Point3::new(p.x, p.y, floor));
            }
        }
    }
    let mut tiers = Vec::with_capacity(3);
    if config.line_of_sight || demand == ViewDemand::Require {
        let rule = config.view_rule();
        let margin = rule.max_reach_m - arrival_radius_m.max(0.0);
        let (within_margin, within_reach): (Vec<_>, Vec<_>) = samples
            .iter()
            .copied()
            .filter(|p| !raised(map, p) && object.seen_from(voxels, p, &viewer, &rule))
            .partition(|p| object.reach(p, viewer.eye_height) <= margin);
        tiers.push(within_margin);
        tiers.push(within_reach);
    }
    if demand == ViewDemand::Prefer {
        tiers.push(samples);
    }
    let robot2 = robot.xy();
    for mut tier in tiers {
        tier.sort_by(|a, b| {
            (a.xy() - robot2)
                .norm()
                .total_cmp(&(b.xy() - robot2).norm())
        });
        tier.truncate(config.max_path_queries);
        let mut best: Option<(f64, Point3<f64>, Vec<Point3<f64>>)> = None;
        for p in tier {
            if let Some(edge) = map.path(&robot, &p)?
                && best.as_ref().is_none_or(|(len, _, _)| edge.length < *len)
            {
                best = Some((edge.length, p, edge.path));
            }
        }
        if let Some((_, p, path)) = best {
            return Ok(Some((p, path)));
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::tests::{LEVEL, room_with_box, solid, voxel_map};
    use proptest::prelude::*;

    fn grid(map: &MultiLevelMap) -> &sornav_frontier_graph::OccupancyGrid {
        map.level_map(LevelId(0)).unwrap().grid()
    }

    /// Brute force over the lattice: the shortest path from `robot` to a
    /// sample within the standoff that `keep` accepts.
    fn brute_force(
        map: &mut MultiLevelMap,
        robot: Point3<f64>,
        (lo, hi): (Point2<f64>, Point2<f64>),
        config: &ApproachConfig,
        keep: impl Fn(&Point3<f64>) -> bool,
    ) -> f64 {
        let step = config.sample_step_m;
        let reach = config.standoff_m;
        let mut brute = f64::INFINITY;
        let nx = ((hi.x - lo.x + 2.0 * reach) / step).ceil() as usize;
        let ny = ((hi.y - lo.y + 2.0 * reach) / step).ceil() as usize;
        for i in 0..=nx {
            for j in 0..=ny {
                let s = Point2::new(
                    lo.x - reach + i as f64 * step,
                    lo.y - reach + j as f64 * step,
                );
                let d = distance_to_box(&s, &lo, &hi);
                if d > reach || d < config.min_standoff_m {
                    continue;
                }
                let c = grid(map).cell_of(&s).unwrap();
                let p = Point3::new(s.x, s.y, 0.0);
                if !grid(map).is_traversable(c) || !keep(&p) {
                    continue;
                }
                if let Some(e) = map.path(&robot, &p).unwrap() {
                    brute = brute.min(e.length);
                }
            }
        }
        brute
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(12))]

        /// Without the view preference the waypoint is traversable, within
        /// the standoff of the object, reached by an executable path from
        /// the robot; with unlimited path queries it has the brute-force
        /// shortest path over all lattice samples, and limited queries
        /// never beat that.
        #[test]
        fn waypoint_is_valid_and_matches_brute_force(
            x in 1.5f64..3.0,
            y in -2.0f64..1.5,
            w in 0.2f64..0.8,
            h in 0.2f64..0.8,
        ) {
            let mut map = room_with_box(Point2::new(x, y), Point2::new(x + w, y + h));
            let (voxels, keys) = voxel_map(&[solid(x, y, 0.3, x + w, y + h, 0.7)]);
            let view = ObjectView::new(&keys[0], voxels.resolution()).unwrap();
            let (lo, hi) = view.footprint();
            let robot = Point3::origin();
            let config = ApproachConfig { line_of_sight: false, ..ApproachConfig::default() };
            let unlimited = ApproachConfig { max_path_queries: usize::MAX, ..config };
            let target = ApproachTarget {
                object: &view,
                voxels: &voxels,
                viewer: LEVEL,
                arrival_radius_m: 0.3,
                demand: ViewDemand::Prefer,
            };
            let limited = approach_waypoint(&mut map, robot, LevelId(0), &target, &config).unwrap();
            let best = approach_waypoint(&mut map, robot, LevelId(0), &target, &unlimited).unwrap();
            let (Some((p, path)), Some((q, _))) = (limited, best) else {
                return Err(TestCaseError::fail("the object's near side is free"));
            };
            prop_assert!(distance_to_box(&p.xy(), &lo, &hi) <= config.standoff_m + 1e-9);
            let cell = grid(&map).cell_of(&p.xy()).unwrap();
            prop_assert!(grid(&map).is_traversable(cell));
            prop_assert!((path[0] - robot).norm() <= 0.1);
            prop_assert!((path[path.len() - 1] - p).norm() <= 0.1);
            let brute = brute_force(&mut map, robot, (lo, hi), &config, |_| true);
            let len = |p: &Point3<f64>, map: &mut MultiLevelMap| map.path(&robot, p).unwrap().unwrap().length;
            prop_assert!((len(&q, &mut map) - brute).abs() < 1e-9);
            prop_assert!(len(&p, &mut map) >= brute - 1e-9);
        }

        /// A required view point is one ([`ObjectView::seen_from`]), and
        /// with unlimited queries it is the brute-force nearest (by path)
        /// of the first reachable tier: view points within the reach less
        /// the arrival radius, else all view points.
        #[test]
        fn required_view_point_is_seen_and_matches_brute_force(
            x in 1.5f64..3.0,
            y in -2.0f64..1.5,
            w in 0.2f64..0.8,
            h in 0.2f64..0.8,
            z in 0.0f64..1.2,
        ) {
            let mut map = room_with_box(Point2::new(x, y), Point2::new(x + w, y + h));
            let (voxels, keys) = voxel_map(&[solid(x, y, z, x + w, y + h, z + 0.3)]);
            let view = ObjectView::new(&keys[0], voxels.resolution()).unwrap();
            let (lo, hi) = view.footprint();
            let robot = Point3::origin();
            let config = ApproachConfig { max_path_queries: usize::MAX, ..ApproachConfig::default() };
            let rule = config.view_rule();
            let arrival = 0.3;
            let target = ApproachTarget {
                object: &view,
                voxels: &voxels,
                viewer: LEVEL,
                arrival_radius_m: arrival,
                demand: ViewDemand::Require,
            };
            let found = approach_waypoint(&mut map, robot, LevelId(0), &target, &config).unwrap();
            let seen = |p: &Point3<f64>| view.seen_from(&voxels, p, &LEVEL, &rule);
            let margin = |p: &Point3<f64>| {
                seen(p) && view.reach(p, LEVEL.eye_height) <= rule.max_reach_m - arrival
            };
            let tier1 = brute_force(&mut map, robot, (lo, hi), &config, margin);
            let tier2 = brute_force(&mut map, robot, (lo, hi), &config, |p| seen(p) && !margin(p));
            match found {
                None => prop_assert!(tier1.is_infinite() && tier2.is_infinite()),
                Some((p, _)) => {
                    prop_assert!(seen(&p));
                    let len = map.path(&robot, &p).unwrap().unwrap().length;
                    let want = if tier1.is_finite() { tier1 } else { tier2 };
                    prop_assert!((len - want).abs() < 1e-9, "{} vs {}", len, want);
                }
            }
        }
    }

    #[test]
    fn a_rule_without_view_points_finds_none_unless_preferred() {
        let mut map = room_with_box(Point2::new(2.0, -0.3), Point2::new(2.4, 0.3));
        let (voxels, keys) = voxel_map(&[solid(2.0, -0.3, 0.3, 2.4, 0.3, 0.7)]);
        let view = ObjectView::new(&keys[0], voxels.resolution()).unwrap();
        let config = ApproachConfig {
            max_reach_m: 0.01,
            ..ApproachConfig::default()
        };
        let target = ApproachTarget {
            object: &view,
            voxels: &voxels,
            viewer: LEVEL,
            arrival_radius_m: 0.3,
            demand: ViewDemand::Require,
        };
        let robot = Point3::origin();
        let required = approach_waypoint(&mut map, robot, LevelId(0), &target, &config).unwrap();
        assert!(required.is_none());
        let prefer = ApproachTarget {
            demand: ViewDemand::Prefer,
            ..target
        };
        let preferred = approach_waypoint(&mut map, robot, LevelId(0), &prefer, &config).unwrap();
        assert!(preferred.is_some());
    }
}
