//! Placing a `NAV_TO_OBJECT` waypoint next to a target candidate.

use nalgebra::{Point2, Point3};
use sornav_frontier_graph::{CellState, FrontierError, LevelId, MultiLevelMap, OccupancyGrid};
use sornav_semantic_map::SemanticMap;

use crate::config::ApproachConfig;
use crate::view::{FLOOR_TOLERANCE_M, ObjectView, Sight, ViewRule, Viewer, distance_to_box};

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
    /// Clear view points only ([`Sight::Clear`]): `Ok(None)` when there
    /// is none.
    RequireClear,
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

/// The lattice offsets (in steps of `step`) within `radius` of a lattice
/// point, the point itself excluded, and the largest offset along an axis.
fn lattice_disc(step: f64, radius: f64) -> (Vec<(i32, i32)>, usize) {
    let r = (radius.max(0.0) / step).min(16.0);
    let m = r.floor() as i32;
    let mut out = Vec::new();
    for di in -m..=m {
        for dj in -m..=m {
            if (di, dj) != (0, 0) && f64::from(di * di + dj * dj) <= r * r + 1e-9 {
                out.push((di, dj));
            }
        }
    }
    (out, m.unsigned_abs() as usize)
}

/// Whether no occupied cell of `grid` has its centre within `clearance`
/// of `p` (the waypoint is *roomy*, see
/// [`ApproachConfig::clearance_margin_m`]); always when `clearance` is
/// no more than the grid's robot radius (no margin).
///
/// # Complexity
/// O((clearance / resolution)²).
fn roomy(grid: &OccupancyGrid, p: &Point2<f64>, clearance: f64) -> bool {
    if clearance <= grid.config().robot_radius {
        // No margin: every traversable waypoint is roomy.
        return true;
    }
    let Ok(c) = grid.cell_of(p) else {
        return false;
    };
    let res = grid.resolution();
    // Bounded: the clearance is validated (radius <= 200 cells, margin <= 1 m).
    #[allow(clippy::cast_possible_truncation)]
    let k = (clearance / res).ceil().clamp(0.0, 1000.0) as i32;
    let r2 = clearance * clearance;
    (-k..=k).all(|dy| {
        (-k..=k).all(|dx| {
            let cell = c.offset(dx, dy);
            (grid.cell_center(cell) - p).norm_squared() > r2
                || grid.state(cell) != CellState::Occupied
        })
    })
}

/// The sight of the object from the poses of a square lattice, each
/// judged once: `None` where the robot cannot stand (an untraversable
/// cell, a raised surface).
struct SightLattice<'a> {
    map: &'a MultiLevelMap,
    /// The level's occupancy grid.
    grid: &'a OccupancyGrid,
    target: &'a ApproachTarget<'a>,
    rule: ViewRule,
    /// Lattice point (0, 0).
    origin: Point2<f64>,
    /// Feet height (the level's floor).
    floor: f64,
    step: f64,
    /// Points per axis.
    n: (usize, usize),
    sights: Vec<Option<Option<Sight>>>,
}

impl SightLattice<'_> {
    /// The sight from lattice point `(i, j)` (`None`: no standing there).
    fn sight(&mut self, i: usize, j: usize) -> Option<Sight> {
        let k = i * self.n.1 + j;
        if let Some(sight) = self.sights[k] {
            return sight;
        }
        let p = Point3::new(
            self.origin.x + i as f64 * self.step,
            self.origin.y + j as f64 * self.step,
            self.floor,
        );
        let standable = self
            .grid
            .cell_of(&p.xy())
            .is_ok_and(|c| self.grid.is_traversable(c))
            && !raised(self.map, &p);
        let t = self.target;
        let sight = standable.then(|| t.object.sight(t.voxels, &p, &t.viewer, &self.rule));
        self.sights[k] = Some(sight);
        sight
    }

    /// Whether every standable lattice pose at the `disc` offsets from
    /// `(i, j)` is a clear view point (offsets off the lattice are not
    /// judged: the lattice extends the disc beyond the samples).
    fn settled(&mut self, i: usize, j: usize, disc: &[(i32, i32)]) -> bool {
        disc.iter().all(|&(di, dj)| {
            let (Some(a), Some(b)) = (
                i.checked_add_signed(di as isize),
                j.checked_add_signed(dj as isize),
            ) else {
                return true;
            };
            a >= self.n.0 || b >= self.n.1 || self.sight(a, b).is_none_or(|s| s == Sight::Clear)
        })
    }
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
/// With `line_of_sight` (or a demand for view points) the samples are
/// ranked in tiers:
/// 1. *settled* clear view points ([`ObjectView::sight`], on the floor
///    rather than on a raised surface): every standable lattice pose
///    within `arrival_radius_m` of them is a clear view point too, so
///    that the robot sees the object clearly wherever within the arrival
///    radius it stops; and whose reach stays within `max_reach_m` less
///    `arrival_radius_m`, so that any such stop is still within reach;
/// 2. the other settled clear view points (within `max_reach_m`);
/// 3. and 4. the same for the other clear view points;
/// 5. and 6. the same for glimpses (not with
///    [`ViewDemand::RequireClear`]);
/// 7. with [`ViewDemand::Prefer`] only, every sample.
///
/// Each of tiers 1 to 6 is split in three: *roomy* samples (no occupied
/// cell within the robot radius plus
/// [`ApproachConfig::clearance_margin_m`]) first, then roomy samples
/// beyond the standoff, up to [`ApproachConfig::roomy_standoff_m`], then
/// *snug* samples within the standoff: a settled clear view point in a
/// gap the inflated map only just admits ranks after a roomy one farther
/// out (tiers 1, 2, the roomy 1, 2 beyond the standoff, then the snug 1,
/// 2; and so on). Samples beyond the standoff lie on the same lattice,
/// which extends by whole steps, so the samples within it do not move.
///
/// In each tier in turn, the `max_path_queries` candidates nearest to the
/// robot (Euclidean) are tried with the frontier map's exact shortest path
/// (through the level's grid and the stairs); the one with the shortest
/// path wins, and later tiers are tried only when no candidate of a tier
/// is reachable. `Ok(None)` when none is reachable or the level is
/// unknown.
///
/// # Complexity
/// O(S' (P + 27) L + S c²) for S' lattice poses (the samples and the
/// lattice within the arrival radius around them, each judged once), S
/// samples, c the clearance in cells, P <= 48
/// object points and L voxels per line of sight, plus `max_path_queries`
/// shortest-path searches per tier tried (each O(N) in the traversable
/// cells).
pub(crate) fn approach_waypoint(
    map: &mut MultiLevelMap,
    robot: Point3<f64>,
    level: LevelId,
    target: &ApproachTarget<'_>,
    config: &ApproachConfig,
) -> Result<Option<Approach>, FrontierError> {
    let ApproachTarget {
        object,
        viewer,
        arrival_radius_m,
        demand,
        ..
    } = *target;
    let Some(level_map) = map.level_map(level) else {
        return Ok(None);
    };
    let floor = level_map.config().grid.floor_z;
    let (lo, hi) = object.footprint();
    let step = config.sample_step_m;
    let window = config.standoff_m;
    // Roomy samples beyond the standoff: whole lattice steps, so that the
    // lattice (and the samples within the standoff) stay where they are.
    let extra = ((config.roomy_standoff_m - window) / step)
        .ceil()
        .clamp(0.0, 200.0);
    let reach = window + extra * step;
    let nx = ((hi.x - lo.x + 2.0 * reach) / step)
        .ceil()
        .clamp(0.0, 4000.0) as usize;
    let ny = ((hi.y - lo.y + 2.0 * reach) / step)
        .ceil()
        .clamp(0.0, 4000.0) as usize;
    let grid = level_map.grid();
    // The sight lattice extends the samples by the arrival disc's margin
    // `m`; samples are computed from its origin so that a sample and its
    // lattice pose are the same point to the bit.
    let (disc, m) = lattice_disc(step, arrival_radius_m);
    let origin = Point2::new(
        lo.x - reach - m as f64 * step,
        lo.y - reach - m as f64 * step,
    );
    let mut samples = Vec::new();
    for i in 0..=nx {
        for j in 0..=ny {
            let p = Point2::new(
                origin.x + (i + m) as f64 * step,
                origin.y + (j + m) as f64 * step,
            );
            let d = distance_to_box(&p, &lo, &hi);
            let extended = d > window;
            if (extended && d > config.roomy_standoff_m) || d < config.min_standoff_m {
                continue;
            }
            let Ok(cell) = grid.cell_of(&p) else {
                continue;
            };
            if grid.is_traversable(cell) {
                samples.push((i, j, Point3::new(p.x, p.y, floor), extended));
            }
        }
    }
    let mut tiers = Vec::with_capacity(7);
    if config.line_of_sight || demand != ViewDemand::Prefer {
        let rule = config.view_rule();
        let margin = rule.max_reach_m - arrival_radius_m.max(0.0);
        let mut lattice = SightLattice {
            map,
            grid,
            target,
            rule,
            origin,
            floor,
            step,
            n: (nx + 1 + 2 * m, ny + 1 + 2 * m),
            sights: vec![None; (nx + 1 + 2 * m) * (ny + 1 + 2 * m)],
        };
        let clearance = grid.config().robot_radius + config.clearance_margin_m;
        // ranked[6 * (0 settled clear, 1 clear, 2 glimpse) + 2 * (0 roomy
        // within the standoff, 1 roomy beyond it, 2 snug within it) +
        // beyond the reach margin]; snug samples beyond the standoff are
        // not used.
        let mut ranked: [Vec<Point3<f64>>; 18] = Default::default();
        for &(i, j, p, extended) in &samples {
            let room = if roomy(grid, &p.xy(), clearance) {
                usize::from(extended)
            } else if extended {
                continue;
            } else {
                2
            };
            let (i, j) = (i + m, j + m);
            let kind = match lattice.sight(i, j) {
                None | Some(Sight::Hidden) => continue,
                Some(Sight::Glimpse) => 2,
                Some(Sight::Clear) => usize::from(!lattice.settled(i, j, &disc)),
            };
            let far = usize::from(object.reach(&p, viewer.eye_height) > margin);
            ranked[6 * kind + 2 * room + far].push(p);
        }
        let keep = if demand == ViewDemand::RequireClear {
            12
        } else {
            18
        };
        tiers.extend(ranked.into_iter().take(keep));
    }
    if demand == ViewDemand::Prefer {
        tiers.push(
            samples
                .into_iter()
                .filter(|s| !s.3)
                .map(|(_, _, p, _)| p)
                .collect(),
        );
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
    use sornav_frontier_graph::Cell;

    fn grid(map: &MultiLevelMap) -> &sornav_frontier_graph::OccupancyGrid {
        map.level_map(LevelId(0)).unwrap().grid()
    }

    /// The approach target of `object` on `voxels` seen by the level camera,
    /// with a 0.3 m arrival radius.
    fn target_of<'a>(
        object: &'a ObjectView,
        voxels: &'a SemanticMap,
        demand: ViewDemand,
    ) -> ApproachTarget<'a> {
        ApproachTarget {
            object,
            voxels,
            viewer: LEVEL,
            arrival_radius_m: 0.3,
            demand,
        }
    }

    /// Brute force over the lattice: the shortest path from `robot` to a
    /// sample within the standoff that `keep` accepts.
    /// The lattice's origin (see [`approach_waypoint`]): the samples'
    /// first corner less the margin of the 0.3 m arrival disc.
    fn lattice_origin(lo: &Point2<f64>, config: &ApproachConfig) -> Point2<f64> {
        let step = config.sample_step_m;
        let window = config.standoff_m;
        let extra = ((config.roomy_standoff_m - window) / step).ceil().max(0.0);
        let reach = window + extra * step;
        let m = lattice_disc(step, 0.3).1 as f64;
        // As approach_waypoint computes it, operation for operation.
        Point2::new(lo.x - reach - m * step, lo.y - reach - m * step)
    }

    fn brute_force(
        map: &mut MultiLevelMap,
        robot: Point3<f64>,
        (lo, hi): (Point2<f64>, Point2<f64>),
        config: &ApproachConfig,
        keep: impl Fn(&Point3<f64>, bool) -> bool,
    ) -> f64 {
        let step = config.sample_step_m;
        let window = config.standoff_m;
        let extra = ((config.roomy_standoff_m - window) / step).ceil().max(0.0);
        let reach = window + extra * step;
        let m = lattice_disc(step, 0.3).1;
        let origin = lattice_origin(&lo, config);
        let mut brute = f64::INFINITY;
        let nx = ((hi.x - lo.x + 2.0 * reach) / step).ceil() as usize;
        let ny = ((hi.y - lo.y + 2.0 * reach) / step).ceil() as usize;
        for i in 0..=nx {
            for j in 0..=ny {
                let s = Point2::new(
                    origin.x + (i + m) as f64 * step,
                    origin.y + (j + m) as f64 * step,
                );
                let d = distance_to_box(&s, &lo, &hi);
                let extended = d > window;
                if (extended && d > config.roomy_standoff_m) || d < config.min_standoff_m {
                    continue;
                }
                let c = grid(map).cell_of(&s).unwrap();
                let p = Point3::new(s.x, s.y, 0.0);
                if !grid(map).is_traversable(c) || !keep(&p, extended) {
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
        #![proptest_config(ProptestConfig::with_cases(32))]

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
            let target = target_of(&view, &voxels, ViewDemand::Prefer);
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
            let brute = brute_force(&mut map, robot, (lo, hi), &config, |_, extended| !extended);
            let len = |p: &Point3<f64>, map: &mut MultiLevelMap| map.path(&robot, p).unwrap().unwrap().length;
            prop_assert!((len(&q, &mut map) - brute).abs() < 1e-9);
            prop_assert!(len(&p, &mut map) >= brute - 1e-9);
        }

        /// A required view point is one ([`ObjectView::seen_from`]), and
        /// with unlimited queries it is the brute-force nearest (by path)
        /// of the first reachable tier: settled clear view points, roomy
        /// ones within the standoff and the reach less the arrival radius,
        /// the other roomy ones, the same for roomy ones beyond the
        /// standoff (up to `roomy_standoff_m`), then for snug ones within
        /// it; then the same for the other clear view points and for
        /// glimpses. A required clear view point is the nearest of the
        /// first twelve tiers, or none.
        #[test]
        fn required_view_point_is_seen_and_matches_brute_force(
            x in 1.5f64..3.0,
            y in -2.0f64..1.5,
            w in 0.2f64..0.8,
            h in 0.2f64..0.8,
            z in 0.0f64..1.2,
            k in 1usize..=27,
            beyond in prop_oneof![Just(0.0f64), 0.0f64..0.4],
        ) {
            let mut map = room_with_box(Point2::new(x, y), Point2::new(x + w, y + h));
            let (voxels, keys) = voxel_map(&[solid(x, y, z, x + w, y + h, z + 0.3)]);
            let view = ObjectView::new(&keys[0], voxels.resolution()).unwrap();
            let (lo, hi) = view.footprint();
            let robot = Point3::origin();
            let config = ApproachConfig {
                max_path_queries: usize::MAX,
                min_box_samples: k,
                roomy_standoff_m: if beyond > 0.0 { ApproachConfig::default().standoff_m + beyond } else { 0.0 },
                ..ApproachConfig::default()
            };
            let rule = config.view_rule();
            let arrival = 0.3;
            let sight = |p: &Point3<f64>| view.sight(&voxels, p, &LEVEL, &rule);
            let near = |p: &Point3<f64>| view.reach(p, LEVEL.eye_height) <= rule.max_reach_m - arrival;
            // Settled: every traversable pose of the sample lattice within
            // the arrival radius is clear too (the room has no raised
            // surface).
            // Neighbours are computed as the lattice computes its poses
            // (origin + index * step), so that a sight ray grazing a voxel
            // edge is judged at the same point.
            let origin = lattice_origin(&lo, &config);
            let settled = |p: &Point3<f64>| {
                let r = (arrival / config.sample_step_m).floor() as i32;
                let index = |c: f64, o: f64| ((c - o) / config.sample_step_m).round() as i32;
                let (pi, pj) = (index(p.x, origin.x), index(p.y, origin.y));
                (-r..=r).all(|di| {
                    (-r..=r).all(|dj| {
                        let (a, b) = (f64::from(di), f64::from(dj));
                        let q = Point3::new(
                            origin.x + f64::from(pi + di) * config.sample_step_m,
                            origin.y + f64::from(pj + dj) * config.sample_step_m,
                            p.z,
                        );
                        (a * a + b * b).sqrt() * config.sample_step_m > arrival + 1e-9
                            || !grid(&map).is_traversable(grid(&map).cell_of(&q.xy()).unwrap())
                            || sight(&q) == Sight::Clear
                    })
                })
            };
            // Roomy: every occupied cell of the grid (brute force over
            // its bounds) farther than the clearance.
            let occupied: Vec<Point2<f64>> = {
                let g = grid(&map);
                let (a, b) = g.bounds().unwrap();
                (a.y..=b.y)
                    .flat_map(|y| (a.x..=b.x).map(move |x| Cell::new(x, y)))
                    .filter(|&c| g.state(c) == CellState::Occupied)
                    .map(|c| g.cell_center(c))
                    .collect()
            };
            let clearance = grid(&map).config().robot_radius + config.clearance_margin_m;
            let roomy = |p: &Point3<f64>| occupied.iter().all(|q| (q - p.xy()).norm() > clearance);
            let mut tiers: Vec<f64> = Vec::new();
            for (s, settle) in [
                (Sight::Clear, Some(true)),
                (Sight::Clear, Some(false)),
                (Sight::Glimpse, None),
            ] {
                // (roomy, beyond the standoff): roomy within, roomy beyond,
                // snug within; snug beyond is never used.
                for (r, e) in [(true, false), (true, true), (false, false)] {
                    for n in [true, false] {
                        tiers.push(brute_force(&mut map.clone(), robot, (lo, hi), &config, |p, extended| {
                            sight(p) == s
                                && settle.is_none_or(|t| settled(p) == t)
                                && roomy(p) == r
                                && extended == e
                                && near(p) == n
                        }));
                    }
                }
            }
            for (demand, depth) in [(ViewDemand::Require, 18), (ViewDemand::RequireClear, 12)] {
                let target = ApproachTarget {
                    object: &view,
                    voxels: &voxels,
                    viewer: LEVEL,
                    arrival_radius_m: arrival,
                    demand,
                };
                let found = approach_waypoint(&mut map, robot, LevelId(0), &target, &config).unwrap();
                let want = tiers[..depth].iter().copied().find(|t| t.is_finite());
                match (found, want) {
                    (None, None) => {}
                    (Some((p, _)), Some(want)) => {
                        prop_assert!(view.seen_from(&voxels, &p, &LEVEL, &rule));
                        if demand == ViewDemand::RequireClear {
                            prop_assert_eq!(sight(&p), Sight::Clear);
                        }
                        let len = map.path(&robot, &p).unwrap().unwrap().length;
                        prop_assert!((len - want).abs() < 1e-9, "{} vs {}", len, want);
                    }
                    (found, want) => {
                        return Err(TestCaseError::fail(format!("{found:?} vs {want:?}")));
                    }
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
        let target = target_of(&view, &voxels, ViewDemand::Require);
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

    /// Two posts make a gap the inflated map only just admits, straight
    /// between the robot and the object: with a clearance margin the
    /// waypoint is a roomy one beside the gap, without one the gap's own
    /// sample (the nearer) is taken.
    #[test]
    fn a_roomy_waypoint_wins_over_a_snug_gap() {
        use sornav_frontier_graph::FrontierMapConfig;
        let mut map = MultiLevelMap::new(FrontierMapConfig::default()).unwrap();
        // Free floor all around (returns on the floor), then two posts
        // 0.42 m apart (centres), on the line from the robot to the object.
        let mut floor = Vec::new();
        for k in 0..720 {
            let t = f64::from(k) * std::f64::consts::PI / 360.0;
            floor.push(Point3::new(3.9 * t.cos(), 3.9 * t.sin(), 0.0));
        }
        let posts = [(1.6, 0.2), (1.6, -0.25)];
        let origin = Point3::new(0.0, 0.0, 0.88);
        map.update(&Point3::origin(), &origin, &floor).unwrap();
        for _ in 0..4 {
            let hits: Vec<Point3<f64>> =
                posts.iter().map(|&(x, y)| Point3::new(x, y, 0.5)).collect();
            map.update(&Point3::origin(), &origin, &hits).unwrap();
        }
        let (voxels, keys) = voxel_map(&[solid(2.2, -0.15, 0.3, 2.5, 0.15, 0.7)]);
        let view = ObjectView::new(&keys[0], voxels.resolution()).unwrap();
        let target = target_of(&view, &voxels, ViewDemand::Prefer);
        let g = grid(&map);
        let gap = Point2::new(1.6, -0.03);
        assert!(
            g.is_traversable(g.cell_of(&gap).unwrap()),
            "the gap is passable on the map"
        );
        assert!(!roomy(g, &gap, g.config().robot_radius + 0.05));
        let robot = Point3::origin();
        let pick = |margin: f64, map: &mut MultiLevelMap| {
            let config = ApproachConfig {
                line_of_sight: true,
                min_standoff_m: 0.4,
                standoff_m: 0.7,
                roomy_standoff_m: 0.85,
                clearance_margin_m: margin,
                ..ApproachConfig::default()
            };
            approach_waypoint(map, robot, LevelId(0), &target, &config)
                .unwrap()
                .unwrap()
                .0
        };
        let snug = pick(0.0, &mut map);
        let roomy_pick = pick(0.05, &mut map);
        let g = grid(&map);
        let clearance = g.config().robot_radius + 0.05;
        assert!(
            !roomy(g, &snug.xy(), clearance),
            "without a margin the snug gap wins: {snug:?}"
        );
        assert!(roomy(g, &roomy_pick.xy(), clearance), "{roomy_pick:?}");
    }
}
