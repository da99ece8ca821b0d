//! [`MultiLevelMap`]: one occupancy grid, frontier set and G_F per floor,
//! joined by stairs.
//!
//! ```text
//!  level 1  ──────────────┐ portal        frontiers of level 1
//!  (z = 2.8)   ░░░░░░░░░░░│·              (own grid, own G_F)
//!                    ____/  stair: walkable steps (surface map),
//!                ___/       path + length + stair cost up / down
//!  level 0  ____/ portal
//!  (z = 0)  ──────────────────────────    frontiers of level 0
//! ```
//!
//! * **Surfaces**: every return goes into the walkable-surface map (a
//!   multi-layer height field per 0.1 m column: the top of a run of
//!   returns is a surface when seen from above or when the run is a riser,
//!   and when the robot fits above it).
//! * **Levels** are floors: level 0 at the first pose, further levels when
//!   the robot stands on flat ground at least `min_level_separation` from
//!   every known floor, or when a flat area of `min_level_area` is seen
//!   over a stair. Each level has its own [`FrontierMap`] at its floor
//!   height; a scan is integrated into the grid of the level the robot
//!   stands on (on a stair, only into the surface map).
//! * **Stairs** ([`Stair`]) are extracted from the surface map; each end on
//!   a known level is a *portal* node of that level's G_F (paths and costs
//!   to it are kept up to date incrementally like any node's); the open end
//!   of a partly seen stair is a frontier (a *stair frontier*).
//! * **G_F** ([`MultiLevelMap::frontier_graph`]) joins the levels: nodes of
//!   one level keep their level's edges; nodes on different levels are
//!   joined through the portals by the cheapest chain of level paths and
//!   stairs (all-pairs over the few portals, Floyd–Warshall), each stair
//!   adding its 3-D path length plus `stair_cost_up` or `stair_cost_down`.
//!
//! With `allow_stairs = false` there is one level and no surface map: the
//! map behaves exactly as a single [`FrontierMap`] (robots that cannot
//! climb, 2-D users).
//!
//! # Limits
//! Two nodes of one level are joined only through that level's grid (a
//! detour over two stairs is not searched); a level's grid is built only
//! from scans taken on it; ramps count as stairs only while they rise at
//! most a step height per surface column; elevators are not modelled.

use std::collections::BTreeMap;

use nalgebra::{Point2, Point3, Vector2};
use serde::{Deserialize, Serialize};

use crate::cell::cell_of;
use crate::graph::pair;
use crate::stairs::{OffLevelColumns, Params, Stair, WalkedStep, extract};
use crate::surface::SurfaceMap;
use crate::{
    AnchorNode, Cell, CellState, Edge, FrontierError, FrontierGraph, FrontierId, FrontierMap,
    FrontierMapConfig, FrontierNode, LevelId, NodeId, UpdateStats,
};

/// Frontier ids of stair frontiers start here (level `0xFFFF` of the id
/// space; ids of level `l` start at `l << 40`).
pub const STAIR_FRONTIER_BASE: u64 = 0xFFFF << 40;

/// A floor of a [`MultiLevelMap`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Level {
    /// Its id (0: the floor of the first pose).
    pub id: LevelId,
    /// World height of its floor (m).
    pub floor_z: f64,
}

/// Where a point is in a multi-level map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Location {
    /// On the floor of a level.
    Level(LevelId),
    /// On the walkable surface of a stair (index into
    /// [`MultiLevelMap::stairs`]).
    Stair(usize),
}

/// A directed way between two hubs (or a node and a hub).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
struct Way {
    cost: f64,
    reverse_cost: f64,
    length: f64,
    path: Vec<Point3<f64>>,
}

impl Way {
    fn reversed(&self) -> Way {
        Way {
            cost: self.reverse_cost,
            reverse_cost: self.cost,
            length: self.length,
            path: self.path.iter().rev().copied().collect(),
        }
    }

    fn from_edge(e: &Edge, start: NodeId) -> Option<Way> {
        Some(Way {
            cost: e.cost_from(start)?,
            reverse_cost: e.cost_from(if start == e.from { e.to } else { e.from })?,
            length: e.length,
            path: e.path_from(start)?,
        })
    }
}

/// A node's level (`None` off every level) and its ways to the hubs.
type Access = (Option<LevelId>, Vec<(usize, Way)>);

/// A hub of the inter-level graph: a portal (stair end on a level) or the
/// open end of a partly seen stair.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Hub {
    level: Option<LevelId>,
    portal: Option<u32>,
    position: Point3<f64>,
}

/// All-pairs cheapest ways between hubs.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
struct Hubs {
    hubs: Vec<Hub>,
    /// Direct ways (i, j) -> way.
    direct: BTreeMap<(usize, usize), Way>,
    /// Cheapest cost i -> j (row-major, INFINITY when none).
    cost: Vec<f64>,
    /// Next hub on the cheapest way i -> j (usize::MAX when none).
    next: Vec<usize>,
    /// Stair frontiers: id -> (hub of the open end, stair index).
    stair_frontiers: BTreeMap<FrontierId, (usize, usize)>,
}

impl Hubs {
    fn solve(&mut self) {
        let n = self.hubs.len();
        self.cost = vec![f64::INFINITY; n * n];
        self.next = vec![usize::MAX; n * n];
        for i in 0..n {
            self.cost[i * n + i] = 0.0;
            self.next[i * n + i] = i;
        }
        for (&(i, j), w) in &self.direct {
            if w.cost < self.cost[i * n + j] {
                self.cost[i * n + j] = w.cost;
                self.next[i * n + j] = j;
            }
        }
        for k in 0..n {
            for i in 0..n {
                let ik = self.cost[i * n + k];
                if !ik.is_finite() {
                    continue;
                }
                for j in 0..n {
                    let c = ik + self.cost[k * n + j];
                    if c < self.cost[i * n + j] {
                        self.cost[i * n + j] = c;
                        self.next[i * n + j] = self.next[i * n + k];
                    }
                }
            }
        }
    }

    fn cost(&self, i: usize, j: usize) -> f64 {
        self.cost[i * self.hubs.len() + j]
    }

    /// The way i -> j along the cheapest chain (cost, reverse cost, length,
    /// path).
    fn way(&self, i: usize, j: usize) -> Option<Way> {
        let n = self.hubs.len();
        if !self.cost(i, j).is_finite() {
            return None;
        }
        let mut w = Way {
            path: vec![self.hubs[i].position],
            ..Way::default()
        };
        let mut a = i;
        while a != j {
            let b = self.next[a * n + j];
            let d = self.direct.get(&(a, b))?;
            append(&mut w, d);
            a = b;
        }
        Some(w)
    }
}

/// Appends way `b` to `a` (costs and lengths add, paths join).
fn append(a: &mut Way, b: &Way) {
    a.cost += b.cost;
    a.reverse_cost += b.reverse_cost;
    a.length += b.length;
    let skip = usize::from(
        matches!((a.path.last(), b.path.first()), (Some(p), Some(q)) if (p - q).norm() < 1e-9),
    );
    a.path.extend(b.path.iter().skip(skip).copied());
}

/// Height (m) within which a point on the last steps of a stair counts as
/// near the floor the stair reaches (for [`MultiLevelMap::is_traversable`]).
const STAIR_EXIT: f64 = 0.6;

/// A multi-level frontier map: floors, stairs, and G_F across them. See
/// the module documentation of [`crate::levels`] for the model.
///
/// # Example
/// ```
/// use nalgebra::Point3;
/// use sornav_frontier_graph::{FrontierMapConfig, MultiLevelMap};
///
/// let mut map = MultiLevelMap::new(FrontierMapConfig::default())?;
/// // A scan of a flat floor around the robot.
/// let feet = Point3::new(0.0, 0.0, 0.0);
/// let eye = Point3::new(0.0, 0.0, 0.88);
/// let points: Vec<_> = (0..400)
///     .map(|k| {
///         let a = f64::from(k) * std::f64::consts::TAU / 400.0;
///         Point3::new(2.0 * a.cos(), 2.0 * a.sin(), 0.0)
///     })
///     .collect();
/// map.update(&feet, &eye, &points)?;
/// assert_eq!(map.levels().count(), 1);
/// let graph = map.frontier_graph(&feet)?;
/// assert!(!graph.is_empty());
/// # Ok::<(), sornav_frontier_graph::FrontierError>(())
/// ```
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MultiLevelMap {
    cfg: FrontierMapConfig,
    maps: Vec<FrontierMap>,
    surfaces: SurfaceMap,
    /// The surface columns stair extraction starts from (a cache; a
    /// restored map recomputes it at its first extraction).
    #[serde(skip)]
    off_level: OffLevelColumns,
    stairs: Vec<Stair>,
    /// Portal ids by (level, cell); rebuilt lazily (a restored map gives
    /// its portals new ids, which only costs one refresh of their rows).
    #[serde(skip)]
    portal_ids: BTreeMap<(LevelId, Cell), u32>,
    next_portal: u32,
    /// Recomputed by every [`MultiLevelMap::frontier_graph`].
    #[serde(skip)]
    hubs: Hubs,
    graph: FrontierGraph,
    /// `graph` is the composed multi-level graph (otherwise level 0's is
    /// current).
    composed: bool,
    /// Level 0's mapped floor has reached `min_level_area` (until then it
    /// may be a stair landing the robot started on; see `stairs`).
    #[serde(default)]
    first_level_established: bool,
    /// Surface columns mapped at the last check of level 0's area: the
    /// O(columns) check reruns only after the map grew by a tenth, so it
    /// costs amortised O(1) per new column.
    #[serde(skip)]
    first_level_checked: usize,
    /// Moves of the robot's feet between columns at different heights
    /// (oldest first, at most [`MAX_WALKED_STEPS`]): stair extraction
    /// attaches a flight the robot walked onto (see [`WalkedStep`]).
    #[serde(default)]
    walked: Vec<WalkedStep>,
    /// The feet of the last pose the robot's move is measured from (see
    /// `record_walked_step`).
    #[serde(skip)]
    walk_anchor: Option<Point3<f64>>,
    /// A step was recorded since the last stair extraction.
    #[serde(skip)]
    walked_changed: bool,
}

/// Most walked steps a [`MultiLevelMap`] keeps (the oldest go first).
const MAX_WALKED_STEPS: usize = 1024;

/// Longest horizontal move (m) between two poses that counts as one step
/// of the robot's feet.
const MAX_WALKED_STEP_M: f64 = 0.5;

impl MultiLevelMap {
    /// An empty map. Level 0 is created at the first pose (at
    /// `cfg.grid.floor_z` when stairs are not allowed).
    ///
    /// # Errors
    /// [`FrontierError::InvalidConfig`] if `cfg` is invalid.
    pub fn new(cfg: FrontierMapConfig) -> Result<Self, FrontierError> {
        cfg.validate()?;
        Ok(Self {
            surfaces: SurfaceMap::new(cfg.levels.surface_resolution),
            cfg,
            maps: Vec::new(),
            off_level: OffLevelColumns::default(),
            stairs: Vec::new(),
            portal_ids: BTreeMap::new(),
            next_portal: 0,
            hubs: Hubs::default(),
            graph: FrontierGraph::default(),
            composed: false,
            first_level_established: false,
            first_level_checked: 0,
            walked: Vec::new(),
            walk_anchor: None,
            walked_changed: false,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &FrontierMapConfig {
        &self.cfg
    }

    /// The levels, by id.
    pub fn levels(&self) -> impl ExactSizeIterator<Item = Level> + '_ {
        self.maps.iter().map(|m| Level {
            id: m.level(),
            floor_z: m.config().grid.floor_z,
        })
    }

    /// The single-level map of `level`.
    pub fn level_map(&self, level: LevelId) -> Option<&FrontierMap> {
        self.maps.get(usize::from(level.0))
    }

    /// The stairs found so far (as of the last
    /// [`frontier_graph`](Self::frontier_graph)).
    pub fn stairs(&self) -> &[Stair] {
        &self.stairs
    }

    /// The level whose floor is within `robot_level_tolerance` of `z`
    /// (the nearest one).
    pub fn level_at(&self, z: f64) -> Option<LevelId> {
        let tol = self.cfg.levels.robot_level_tolerance;
        self.levels()
            .filter(|l| (l.floor_z - z).abs() <= tol)
            .min_by(|a, b| (a.floor_z - z).abs().total_cmp(&(b.floor_z - z).abs()))
            .map(|l| l.id)
    }

    /// The level a thing at height `z` belongs to: the highest level whose
    /// floor is at most `robot_level_tolerance` above `z` (an object on a
    /// floor, a table top, a ceiling lamp: the floor below it). `None`
    /// below every floor.
    pub fn level_containing(&self, z: f64) -> Option<LevelId> {
        let tol = self.cfg.levels.robot_level_tolerance;
        self.levels()
            .filter(|l| l.floor_z <= z + tol)
            .max_by(|a, b| a.floor_z.total_cmp(&b.floor_z))
            .map(|l| l.id)
    }

    /// The walkable surface heights (m, ascending) of the surface column
    /// containing the horizontal position `(x, y)`: tops of runs of returns
    /// seen from above (or risers), with the robot's height free above.
    /// Empty where nothing was seen or stairs are not allowed.
    pub fn surfaces_at(&self, x: f64, y: f64) -> Vec<f64> {
        self.surfaces
            .key(x, y)
            .map(|k| {
                self.surfaces
                    .surfaces(k, self.clearance())
                    .map(f64::from)
                    .collect()
            })
            .unwrap_or_default()
    }

    /// Where `p` is: on a level's floor, on a stair, or `None` (neither).
    pub fn locate(&self, p: &Point3<f64>) -> Option<Location> {
        if let Some(l) = self.level_at(p.z) {
            // On a stair's first (or last) treads: within the level's
            // tolerance of its floor but raised above (or below) it, on a
            // stair's surface. The stair, not the level: the level's grid
            // takes a tread within the step height for floor, and a path
            // planned on it goes back to the stair's portal at its foot
            // first (the robot stepped up and down the first tread until
            // the action budget ran out).
            if let Some(si) = self.low_tread(l, p) {
                return Some(Location::Stair(si));
            }
            return Some(Location::Level(l));
        }
        let key = self.surfaces.key(p.x, p.y)?;
        if let Some(si) = self.stairs.iter().position(|s| s.supports(key, p.z, 0.35)) {
            return Some(Location::Stair(si));
        }
        // Off the eroded stair columns (the robot's centre near a stair's
        // edge, a step not seen yet under the camera): the stair whose
        // path passes nearest, within the robot's reach.
        let reach = self.cfg.grid.robot_radius + 0.3;
        self.stairs
            .iter()
            .enumerate()
            .filter_map(|(si, s)| {
                s.path
                    .iter()
                    .filter(|q| (q.z - p.z).abs() <= 0.45)
                    .map(|q| (q.xy() - p.xy()).norm())
                    .min_by(f64::total_cmp)
                    .filter(|d| *d <= reach)
                    .map(|d| (si, d))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(si, _)| Location::Stair(si))
    }

    /// The stair whose walkable surface holds `p` (within `TREAD_DZ` of
    /// its height) when `p` is more than `TREAD_DZ` off the floor of level
    /// `l`; see [`Self::locate`].
    fn low_tread(&self, l: LevelId, p: &Point3<f64>) -> Option<usize> {
        let level = self.levels().find(|x| x.id == l)?;
        if (p.z - level.floor_z).abs() <= TREAD_DZ {
            return None;
        }
        let key = self.surfaces.key(p.x, p.y)?;
        self.stairs
            .iter()
            .position(|s| s.supports(key, p.z, TREAD_DZ))
    }

    /// Whether the robot can stand at `p`: a traversable cell of the level
    /// at `p.z`, a cell not known occupied within `portal_radius` of a
    /// stair end on a level within 0.6 m of `p.z` (the approach to the
    /// first step inside the obstacle inflation of the steps, and the way
    /// off the last steps onto a floor not mapped yet), or the walkable
    /// surface of a stair.
    pub fn is_traversable(&self, p: &Point3<f64>) -> bool {
        if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
            return false;
        }
        // The level at the point's height, or (the last steps of a stair
        // reach it) a level within `STAIR_EXIT` of it.
        let tol = self.cfg.levels.robot_level_tolerance.max(STAIR_EXIT);
        for l in self.levels().filter(|l| (l.floor_z - p.z).abs() <= tol) {
            let Some(m) = self.level_map(l.id) else {
                continue;
            };
            let Ok(c) = m.grid().cell_of(&p.xy()) else {
                continue;
            };
            let on_floor = (l.floor_z - p.z).abs() <= self.cfg.levels.robot_level_tolerance;
            if on_floor && m.grid().is_traversable(c) {
                return true;
            }
            let near_end = self.stairs.iter().any(|s| {
                [&s.lower, &s.upper].iter().any(|e| {
                    e.level == Some(l.id)
                        && (e.position.xy() - p.xy()).norm() <= self.cfg.levels.portal_radius + 0.3
                })
            });
            if near_end && m.grid().state(c) != CellState::Occupied {
                return true;
            }
        }
        self.surfaces
            .key(p.x, p.y)
            .is_some_and(|k| self.stairs.iter().any(|s| s.supports(k, p.z, 0.35)))
    }

    fn check(p: &Point3<f64>, what: &'static str, res: f64) -> Result<(), FrontierError> {
        if !p.z.is_finite() {
            return Err(FrontierError::NonFinite { what, index: 0 });
        }
        cell_of(&p.xy(), res, what, 0).map(|_| ())
    }

    fn add_level(&mut self, floor_z: f64) -> Result<LevelId, FrontierError> {
        let id = LevelId(
            u16::try_from(self.maps.len())
                .map_err(|_| FrontierError::InvalidConfig("more than 65 535 levels".into()))?,
        );
        if id.0 == 0xFFFF {
            return Err(FrontierError::InvalidConfig(
                "more than 65 534 levels".into(),
            ));
        }
        let mut cfg = self.cfg.clone();
        cfg.grid.floor_z = floor_z;
        // The home node is the first pose, on level 0 only.
        cfg.graph.home = cfg.graph.home && id.0 == 0;
        self.maps.push(FrontierMap::for_level(cfg, id)?);
        Ok(id)
    }

    fn ensure_first_level(&mut self, robot: &Point3<f64>) -> Result<(), FrontierError> {
        if self.maps.is_empty() {
            let z = if self.cfg.levels.allow_stairs {
                robot.z
            } else {
                self.cfg.grid.floor_z
            };
            self.add_level(z)?;
        }
        Ok(())
    }

    /// Whether the ground around `feet` is flat at the feet's height: at
    /// least 70 % of the surface columns within 0.6 m have a surface within
    /// `level_tolerance` of it, or (a forward-looking camera at the foot of
    /// a stair sees the floor ahead, not under itself) the flat columns
    /// within 1.5 m cover at least half of `min_level_area`.
    fn flat_at(&self, feet: &Point3<f64>) -> bool {
        let res = self.surfaces.resolution;
        let Some(k) = self.surfaces.key(feet.x, feet.y) else {
            return false;
        };
        let (near, far) = (0.6 / res, 1.5 / res);
        // Small: surface_resolution >= 0.02.
        #[allow(clippy::cast_possible_truncation)]
        let ri = far.ceil() as i32;
        let clearance = self.clearance();
        let tol = self.cfg.levels.level_tolerance;
        let (mut total, mut flat_near, mut flat_far) = (0usize, 0usize, 0usize);
        for dy in -ri..=ri {
            for dx in -ri..=ri {
                let d2 = f64::from(dx * dx + dy * dy);
                if d2 > far * far {
                    continue;
                }
                let flat = self
                    .surfaces
                    .surfaces((k.0 + dx, k.1 + dy), clearance)
                    .any(|z| (f64::from(z) - feet.z).abs() <= tol);
                flat_far += usize::from(flat);
                if d2 <= near * near {
                    total += 1;
                    flat_near += usize::from(flat);
                }
            }
        }
        #[allow(clippy::cast_precision_loss)]
        let area = flat_far as f64 * res * res;
        flat_near * 10 >= total * 7 || area >= 0.5 * self.cfg.levels.min_level_area
    }

    fn clearance(&self) -> f32 {
        // Robot heights are validated finite; f32 is plenty.
        #[allow(clippy::cast_possible_truncation)]
        let c = self.cfg.grid.robot_height as f32;
        c
    }

    /// Integrates one scan: the robot's feet (a point on the surface it
    /// stands on), the sensor origin and the world returns. Returns go to
    /// the surface map, and to the occupancy grid of the level the robot
    /// stands on (none while it is on a stair). A robot standing on flat
    /// ground at least `min_level_separation` away from every known floor
    /// starts a new level there.
    ///
    /// # Errors
    /// As [`FrontierMap::update`] (non-finite or out-of-range coordinates,
    /// a grid above its cell budget); nothing is modified then.
    ///
    /// # Complexity
    /// That of [`FrontierMap::update`] on one level, plus O(P) for the
    /// surface map.
    pub fn update(
        &mut self,
        feet: &Point3<f64>,
        origin: &Point3<f64>,
        points: &[Point3<f64>],
    ) -> Result<UpdateStats, FrontierError> {
        self.update_with_voids(feet, origin, points, &[])
    }

    /// As [`update`](Self::update), plus the scan's voids (see
    /// [`FrontierMap::update_with_voids`]): positions where a ray crossed
    /// the floor the robot stands on within range and returned nothing.
    /// They go to the occupancy grid of the robot's level as drop-offs,
    /// never to the surface map (they are not surfaces), and are ignored
    /// while the robot stands on no level.
    ///
    /// # Errors
    /// As [`update`](Self::update), and for a non-finite or out-of-range
    /// void; nothing is modified then.
    ///
    /// # Complexity
    /// That of [`update`](Self::update) for P + V returns on the grid.
    pub fn update_with_voids(
        &mut self,
        feet: &Point3<f64>,
        origin: &Point3<f64>,
        points: &[Point3<f64>],
        voids: &[Point2<f64>],
    ) -> Result<UpdateStats, FrontierError> {
        let res = self.cfg.grid.resolution;
        crate::map::check_voids(voids, res)?;
        Self::check(feet, "pose", res)?;
        Self::check(origin, "origin", res)?;
        for (index, p) in points.iter().enumerate() {
            if !p.z.is_finite() {
                return Err(FrontierError::NonFinite {
                    what: "point",
                    index,
                });
            }
            cell_of(&p.xy(), res, "point", index)?;
        }
        self.ensure_first_level(feet)?;
        self.record_walked_step(feet);
        if !self.cfg.levels.allow_stairs {
            let stats = self.maps[0].update_with_voids(origin, points, voids)?;
            if self.cfg.levels.detect_stairs {
                self.surfaces
                    .integrate(origin, points, self.cfg.grid.max_range);
            }
            return Ok(stats);
        }
        let level = match self.level_at(feet.z) {
            Some(l) => Some(l),
            None => {
                // A new floor under the robot?
                let far = self
                    .levels()
                    .all(|l| (l.floor_z - feet.z).abs() >= self.cfg.levels.min_level_separation);
                self.surfaces
                    .integrate(origin, points, self.cfg.grid.max_range);
                if far && self.flat_at(feet) {
                    Some(self.add_level(feet.z)?)
                } else {
                    // A floor seen from the stair (a flat area over it) may
                    // be a new level under the robot's feet.
                    self.refresh_stairs()?;
                    self.level_at(feet.z)
                }
            }
        };
        let stats = match level {
            Some(l) => self.maps[usize::from(l.0)].update_with_voids(origin, points, voids)?,
            None => UpdateStats::default(),
        };
        if level.is_some() {
            self.surfaces
                .integrate(origin, points, self.cfg.grid.max_range);
        }
        Ok(stats)
    }

    /// Records a contact on the level the robot stands on: the robot at
    /// `feet` was stopped by an obstacle at `point` (horizontal position)
    /// that its sensor did not show. See [`FrontierMap::contact`]. Returns
    /// the level, or `None` (nothing recorded) when the robot stands on no
    /// level (on a stair: its treads are not in a level's grid) or the
    /// level's map already explains the contact.
    ///
    /// # Errors
    /// As [`FrontierMap::contact`]; nothing is modified then.
    ///
    /// # Complexity
    /// That of [`FrontierMap::contact`].
    pub fn contact(
        &mut self,
        feet: &Point3<f64>,
        point: &Point2<f64>,
    ) -> Result<Option<LevelId>, FrontierError> {
        let res = self.cfg.grid.resolution;
        Self::check(feet, "pose", res)?;
        cell_of(point, res, "contact", 0)?;
        let Some(level) = self.level_at(feet.z) else {
            return Ok(None);
        };
        Ok(self.maps[usize::from(level.0)]
            .contact(feet, point)?
            .map(|_| level))
    }

    /// Recomputes every level's frontier segmentation from scratch, marks
    /// every edge for recomputation and forces a stair extraction at the
    /// next [`frontier_graph`](Self::frontier_graph) (the non-incremental
    /// reference, and for benchmarks).
    ///
    /// # Complexity
    /// That of [`FrontierMap::rebuild`] on every level; the next refresh
    /// then costs one search per node and level plus the extraction.
    pub fn rebuild(&mut self) {
        for m in &mut self.maps {
            m.rebuild();
        }
        self.surfaces.mark_dirty();
        self.off_level.invalidate();
    }

    /// Re-extracts the stairs when the surfaces changed; creates the levels
    /// found over them.
    fn refresh_stairs(&mut self) -> Result<(), FrontierError> {
        let walked = std::mem::take(&mut self.walked_changed);
        if !self.surfaces.take_dirty() && !walked {
            return Ok(());
        }
        let columns = self.surfaces.columns.len();
        let due = !self.first_level_established
            && columns > self.first_level_checked + self.first_level_checked / 10;
        if due {
            self.first_level_checked = columns;
        }
        if due && self.first_level_area() >= self.cfg.levels.min_level_area {
            // The levels found so far stay; later ones need the full
            // separation from level 0, which may change what is extracted.
            self.first_level_established = true;
            self.off_level.invalidate();
        }
        let lc = &self.cfg.levels;
        #[allow(clippy::cast_possible_truncation)]
        let params = Params {
            step: self.cfg.grid.step_height as f32,
            column_rise: lc.max_stair_column_rise.max(self.cfg.grid.step_height) as f32,
            clearance: self.clearance(),
            radius: self.cfg.grid.robot_radius,
            level_tolerance: lc.level_tolerance as f32,
            min_level_separation: lc.min_level_separation,
            min_level_area: lc.min_level_area,
            min_stair_rise: lc.min_stair_rise,
            min_sighting_rise: lc.min_stair_sighting_rise,
            first_level_established: self.first_level_established,
        };
        let floors: Vec<f64> = self.levels().map(|l| l.floor_z).collect();
        let touched = self.surfaces.take_touched();
        self.off_level
            .update(&self.surfaces, &touched, &floors, &params);
        if !self.off_level.stale() && !walked {
            // Nothing the last extraction read has changed.
            return Ok(());
        }
        let mut found = extract(
            &self.surfaces,
            &mut self.off_level,
            &floors,
            &self.walked,
            &params,
        );
        if !found.new_levels.is_empty() && self.cfg.levels.allow_stairs {
            for h in found.new_levels.clone() {
                self.add_level(h)?;
            }
            let floors: Vec<f64> = self.levels().map(|l| l.floor_z).collect();
            self.off_level.update(&self.surfaces, &[], &floors, &params);
            found = extract(
                &self.surfaces,
                &mut self.off_level,
                &floors,
                &self.walked,
                &params,
            );
        }
        self.stairs = found.stairs;
        Ok(())
    }

    /// Records the move of the robot's feet from the last anchor pose to
    /// `feet` as a [`WalkedStep`] when it changed columns and height (by
    /// more than half the level tolerance, at most the largest column
    /// rise of a flight) within [`MAX_WALKED_STEP_M`]; a longer move (a
    /// jump of the pose) only moves the anchor, as does a recorded step.
    /// A robot that climbs slowly accumulates the height over several
    /// poses. O(1) amortised.
    fn record_walked_step(&mut self, feet: &Point3<f64>) {
        let Some(anchor) = self.walk_anchor else {
            self.walk_anchor = Some(*feet);
            return;
        };
        let horizontal = (feet.xy() - anchor.xy()).norm();
        if horizontal > MAX_WALKED_STEP_M {
            self.walk_anchor = Some(*feet);
            return;
        }
        let lc = &self.cfg.levels;
        let dz = (feet.z - anchor.z).abs();
        if dz <= 0.5 * lc.level_tolerance {
            return;
        }
        self.walk_anchor = Some(*feet);
        let rise = lc.max_stair_column_rise.max(self.cfg.grid.step_height);
        let ends = (
            self.surfaces.key(anchor.x, anchor.y),
            self.surfaces.key(feet.x, feet.y),
        );
        let (Some(a), Some(b)) = ends else {
            return;
        };
        if a == b || dz > rise {
            return;
        }
        // Heights are stored as the surface map stores them.
        #[allow(clippy::cast_possible_truncation)]
        let step = WalkedStep {
            from: (a, anchor.z as f32),
            to: (b, feet.z as f32),
        };
        if self.walked.contains(&step) {
            return;
        }
        if self.walked.len() >= MAX_WALKED_STEPS {
            self.walked.remove(0);
        }
        self.walked.push(step);
        self.walked_changed = true;
    }

    /// Mapped floor area (m²) of level 0: surface columns with a surface
    /// within `level_tolerance` of its floor. O(mapped columns); only run
    /// until it first reaches `min_level_area`.
    fn first_level_area(&self) -> f64 {
        let Some(z0) = self.maps.first().map(|m| m.config().grid.floor_z) else {
            return 0.0;
        };
        let (clearance, tol) = (self.clearance(), self.cfg.levels.level_tolerance);
        let flat = self
            .surfaces
            .columns
            .keys()
            .filter(|&&k| {
                self.surfaces
                    .surfaces(k, clearance)
                    .any(|z| (f64::from(z) - z0).abs() <= tol)
            })
            .count();
        let res = self.surfaces.resolution;
        flat as f64 * res * res
    }

    /// Whether level `level`'s grid has a traversable cell within
    /// `portal_radius` of `p` (the floor around a stair end was mapped).
    fn mapped_near(&self, level: LevelId, p: &Point3<f64>) -> bool {
        let Some(m) = self.maps.get(usize::from(level.0)) else {
            return false;
        };
        let grid = m.grid();
        let res = self.cfg.grid.resolution;
        let r = self.cfg.levels.portal_radius;
        // Bounded: portal_radius / resolution is validated small.
        #[allow(clippy::cast_possible_truncation)]
        let n = (r / res).ceil() as i32;
        let Ok(c) = grid.cell_of(&p.xy()) else {
            return false;
        };
        (-n..=n).any(|dy| {
            (-n..=n).any(|dx| {
                f64::from(dx * dx + dy * dy) * res * res <= r * r
                    && grid.is_traversable(c.offset(dx, dy))
            })
        })
    }

    fn portal_id(&mut self, level: LevelId, p: &Point3<f64>) -> Option<u32> {
        let cell = cell_of(&p.xy(), self.cfg.grid.resolution, "portal", 0).ok()?;
        let next = &mut self.next_portal;
        Some(*self.portal_ids.entry((level, cell)).or_insert_with(|| {
            *next += 1;
            *next - 1
        }))
    }

    /// Brings G_F up to date for the robot's feet at `robot` and returns
    /// it: the frontiers of every level and the open ends of partly seen
    /// stairs, with path costs across stairs (see the module
    /// documentation). With one level and no stair this is exactly the
    /// level's [`FrontierMap::frontier_graph`].
    ///
    /// # Errors
    /// [`FrontierError::NonFinite`] / [`FrontierError::OutOfRange`] for a
    /// bad pose.
    ///
    /// # Complexity
    /// The levels' incremental refreshes, plus O(S log S) for the stair
    /// extraction when the surfaces changed, plus O(H³ + V² A²) to join V
    /// nodes with A portals each through H hubs.
    pub fn frontier_graph(&mut self, robot: &Point3<f64>) -> Result<&FrontierGraph, FrontierError> {
        let res = self.cfg.grid.resolution;
        Self::check(robot, "pose", res)?;
        self.ensure_first_level(robot)?;
        let xy = robot.xy();
        if !self.cfg.levels.allow_stairs {
            if self.cfg.levels.detect_stairs {
                self.refresh_stairs()?;
            }
            self.composed = false;
            return self.maps[0].frontier_graph(&xy);
        }
        self.refresh_stairs()?;
        let location = self.locate(robot);
        if self.maps.len() == 1 && self.stairs.is_empty() {
            self.composed = false;
            return self.maps[0].frontier_graph(&xy);
        }
        // Portals.
        let mut hubs = Hubs::default();
        let mut per_level: Vec<BTreeMap<u32, Point2<f64>>> = vec![BTreeMap::new(); self.maps.len()];
        let mut stair_hubs: Vec<(usize, usize)> = Vec::new();
        let stairs = self.stairs.clone();
        for (si, s) in stairs.iter().enumerate() {
            let mut ends = [usize::MAX; 2];
            for (k, e) in [&s.lower, &s.upper].into_iter().enumerate() {
                let portal = match e.level {
                    Some(l) => self.portal_id(l, &e.position),
                    None => None,
                };
                if let (Some(l), Some(id)) = (e.level, portal) {
                    per_level[usize::from(l.0)].insert(id, e.position.xy());
                }
                ends[k] = hubs.hubs.len();
                hubs.hubs.push(Hub {
                    level: e.level,
                    portal,
                    position: e.position,
                });
                // An open end, or an end on a level whose floor around it
                // was never mapped (a floor found from the stair, not yet
                // stood on): exploring it means going there.
                let unmapped = e.level.is_some_and(|l| !self.mapped_near(l, &e.position));
                if e.level.is_none() || unmapped {
                    hubs.stair_frontiers.insert(
                        stair_frontier_id(&self.surfaces, &e.position),
                        (ends[k], si),
                    );
                }
            }
            let (up, down) = (
                self.cfg.levels.stair_cost_up,
                self.cfg.levels.stair_cost_down,
            );
            let way = Way {
                cost: s.length + up,
                reverse_cost: s.length + down,
                length: s.length,
                path: s.path.clone(),
            };
            hubs.direct.insert((ends[0], ends[1]), way.clone());
            hubs.direct.insert((ends[1], ends[0]), way.reversed());
            stair_hubs.push((ends[0], ends[1]));
        }
        // Level refreshes.
        let robot_level = match location {
            Some(Location::Level(l)) => Some(l),
            _ => None,
        };
        for (l, portals) in per_level.into_iter().enumerate() {
            let m = &mut self.maps[l];
            m.set_portals(portals);
            let here = robot_level == Some(m.level());
            m.refresh(here.then_some(&xy));
        }
        // Same-level portal-to-portal ways.
        let n = hubs.hubs.len();
        for i in 0..n {
            for j in 0..n {
                let (Some(a), Some(b)) = (&hubs.hubs[i].portal, &hubs.hubs[j].portal) else {
                    continue;
                };
                let (Some(la), Some(lb)) = (hubs.hubs[i].level, hubs.hubs[j].level) else {
                    continue;
                };
                if i == j || la != lb {
                    continue;
                }
                let g = &self.maps[usize::from(la.0)].graph();
                if let Some(w) = g
                    .edge(NodeId::Portal(*a), NodeId::Portal(*b))
                    .and_then(|e| Way::from_edge(e, NodeId::Portal(*a)))
                    && hubs.direct.get(&(i, j)).is_none_or(|d| w.cost < d.cost)
                {
                    hubs.direct.insert((i, j), w);
                }
            }
        }
        hubs.solve();
        self.hubs = hubs;
        self.compose(robot, location, &stairs);
        self.composed = true;
        Ok(&self.graph)
    }

    /// Ways from a node of level `level`'s graph to every portal hub of
    /// that level.
    fn level_access(&self, level: LevelId, node: NodeId) -> Vec<(usize, Way)> {
        let g = &self.maps[usize::from(level.0)].graph();
        self.hubs
            .hubs
            .iter()
            .enumerate()
            .filter(|(_, h)| h.level == Some(level))
            .filter_map(|(i, h)| {
                let e = g.edge(node, NodeId::Portal(h.portal?))?;
                Some((i, Way::from_edge(e, node)?))
            })
            .collect()
    }

    /// Ways from a point on stair `si` (nearest path point to `p`) to its
    /// two end hubs.
    fn stair_access(&self, si: usize, p: &Point3<f64>) -> Vec<(usize, Way)> {
        let s = &self.stairs[si];
        let Some((k, _)) = s
            .path
            .iter()
            .enumerate()
            .min_by(|a, b| (a.1 - p).norm().total_cmp(&(b.1 - p).norm()))
        else {
            return Vec::new();
        };
        let span = (s.upper.position.z - s.lower.position.z).abs().max(1e-9);
        let frac_up = ((s.upper.position.z - p.z) / span).clamp(0.0, 1.0);
        let (up, down) = (
            self.cfg.levels.stair_cost_up,
            self.cfg.levels.stair_cost_down,
        );
        let mk = |pts: Vec<Point3<f64>>, climb: f64, descend: f64| {
            let mut path = vec![*p];
            path.extend(pts);
            let length = path.windows(2).map(|w| (w[1] - w[0]).norm()).sum::<f64>();
            Way {
                cost: length + climb,
                reverse_cost: length + descend,
                length,
                path,
            }
        };
        let to_lower = mk(
            s.path[..=k].iter().rev().copied().collect(),
            down * (1.0 - frac_up),
            up * (1.0 - frac_up),
        );
        let to_upper = mk(s.path[k..].to_vec(), up * frac_up, down * frac_up);
        self.hubs
            .hubs
            .iter()
            .enumerate()
            .filter_map(|(i, h)| {
                if (h.position - s.lower.position).norm() < 1e-9 {
                    Some((i, to_lower.clone()))
                } else if (h.position - s.upper.position).norm() < 1e-9 {
                    Some((i, to_upper.clone()))
                } else {
                    None
                }
            })
            .collect()
    }

    /// A robot neither on a floor nor on a recognised stair (between the
    /// steps the map resolved, over an unobserved tread): a straight way
    /// to the nearest hub within `portal_radius + 1` m, so that it can
    /// rejoin the graph.
    fn nearest_hub_access(&self, p: &Point3<f64>) -> Vec<(usize, Way)> {
        let reach = self.cfg.levels.portal_radius + 1.0;
        self.hubs
            .hubs
            .iter()
            .enumerate()
            .map(|(i, h)| (i, (h.position - p).norm()))
            .filter(|&(_, d)| d <= reach)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, d)| {
                vec![(
                    i,
                    Way {
                        cost: d,
                        reverse_cost: d,
                        length: d,
                        path: vec![*p, self.hubs.hubs[i].position],
                    },
                )]
            })
            .unwrap_or_default()
    }

    /// Builds the composed graph.
    fn compose(&mut self, robot: &Point3<f64>, location: Option<Location>, stairs: &[Stair]) {
        let res = self.cfg.grid.resolution;
        let mut g = FrontierGraph::default();
        // Nodes: (id, level, access ways).
        let robot_level = match location {
            Some(Location::Level(l)) => Some(l),
            _ => None,
        };
        let robot_anchor_level = robot_level
            .or_else(|| self.level_containing(robot.z))
            .unwrap_or(LevelId(0));
        let robot_cell = robot_level.and_then(|l| {
            self.maps[usize::from(l.0)]
                .graph()
                .robot
                .as_ref()
                .and_then(|a| a.cell)
        });
        g.robot = Some(AnchorNode {
            position: robot.xy(),
            cell: robot_cell,
            level: robot_anchor_level,
            z: robot.z,
        });
        g.home = self.maps[0].graph().home.clone();
        let mut access: BTreeMap<NodeId, Access> = BTreeMap::new();
        access.insert(
            NodeId::Robot,
            match location {
                Some(Location::Level(l)) => (Some(l), self.level_access(l, NodeId::Robot)),
                Some(Location::Stair(si)) => (None, self.stair_access(si, robot)),
                None => (None, self.nearest_hub_access(robot)),
            },
        );
        if g.home.is_some() {
            access.insert(
                NodeId::Home,
                (
                    Some(LevelId(0)),
                    self.level_access(LevelId(0), NodeId::Home),
                ),
            );
        }
        for m in &self.maps {
            for n in m.graph().nodes() {
                g.frontiers.insert(n.id, n.clone());
                access.insert(
                    NodeId::Frontier(n.id),
                    (
                        Some(m.level()),
                        self.level_access(m.level(), NodeId::Frontier(n.id)),
                    ),
                );
            }
        }
        for (&id, &(hub, si)) in &self.hubs.stair_frontiers {
            let h = &self.hubs.hubs[hub];
            let s = &stairs[si];
            let level = h
                .level
                .or(s.lower.level)
                .or(s.upper.level)
                .unwrap_or(LevelId(0));
            // The end on a floor not mapped yet is explored from a step off
            // the stair onto that floor (standing on the last steps the
            // robot is not on the floor yet).
            let target = if h.level.is_some() {
                step_off(s, &h.position)
            } else {
                h.position
            };
            let Ok(cell) = cell_of(&target.xy(), res, "stair", 0) else {
                continue;
            };
            g.frontiers.insert(
                id,
                FrontierNode {
                    id,
                    cells: vec![cell],
                    centroid: target.xy(),
                    axis: Vector2::new(1.0, 0.0),
                    extent: res,
                    viewpoint: target.xy(),
                    viewpoint_cell: cell,
                    level,
                    z: target.z,
                },
            );
            let d = (target - h.position).norm();
            access.insert(
                NodeId::Frontier(id),
                (
                    None,
                    vec![(
                        hub,
                        Way {
                            cost: d,
                            reverse_cost: d,
                            length: d,
                            path: if d > 0.0 {
                                vec![target, h.position]
                            } else {
                                vec![h.position]
                            },
                        },
                    )],
                ),
            );
        }
        // Edges.
        let ids: Vec<NodeId> = access.keys().copied().collect();
        for (ai, &a) in ids.iter().enumerate() {
            for &b in &ids[ai + 1..] {
                let (la, wa) = &access[&a];
                let (lb, wb) = &access[&b];
                if la.is_some() && la == lb {
                    let l = la.unwrap_or_default();
                    if let Some(e) = self.maps[usize::from(l.0)].graph().edge(a, b) {
                        g.edges.insert(pair(a, b), e.clone());
                    }
                    continue;
                }
                // Cheapest a -> b through the hubs.
                let mut best: Option<(f64, usize, usize)> = None;
                for (p, w1) in wa {
                    for (q, w2) in wb {
                        let c = w1.cost + self.hubs.cost(*p, *q) + w2.reverse_cost;
                        if c.is_finite() && best.is_none_or(|b| c < b.0) {
                            best = Some((c, *p, *q));
                        }
                    }
                }
                let Some((_, p, q)) = best else { continue };
                let (Some(w1), Some(w2)) = (
                    wa.iter().find(|w| w.0 == p).map(|w| &w.1),
                    wb.iter().find(|w| w.0 == q).map(|w| &w.1),
                ) else {
                    continue;
                };
                let Some(mid) = self.hubs.way(p, q) else {
                    continue;
                };
                let mut way = w1.clone();
                append(&mut way, &mid);
                append(&mut way, &w2.reversed());
                let (from, to) = pair(a, b);
                let way = if from == a { way } else { way.reversed() };
                g.edges.insert(
                    (from, to),
                    Edge {
                        from,
                        to,
                        bbox: bbox(&way.path, res),
                        path: way.path,
                        length: way.length,
                        cost: way.cost,
                        reverse_cost: way.reverse_cost,
                    },
                );
            }
        }
        self.graph = g;
    }

    /// The graph as of the last [`frontier_graph`](Self::frontier_graph).
    pub fn graph(&self) -> &FrontierGraph {
        if self.composed || self.maps.is_empty() {
            &self.graph
        } else {
            self.maps[0].graph()
        }
    }

    /// Whether `id` is the open end of a partly seen stair.
    pub fn is_stair_frontier(&self, id: FrontierId) -> bool {
        id.0 >= STAIR_FRONTIER_BASE
    }

    /// The cheapest executable path from `from` to `to` (feet positions),
    /// over stairs when they are on different levels; each point is snapped
    /// to its level's nearest traversable cell within the snap radius.
    /// `Ok(None)` when no path is known. The edge has `from = to =
    /// NodeId::Robot`.
    ///
    /// # Errors
    /// [`FrontierError::NonFinite`] / [`FrontierError::OutOfRange`].
    ///
    /// # Complexity
    /// One grid search on a shared level; otherwise one per portal of the
    /// two levels, plus the hub table lookups.
    pub fn path(
        &mut self,
        from: &Point3<f64>,
        to: &Point3<f64>,
    ) -> Result<Option<Edge>, FrontierError> {
        let res = self.cfg.grid.resolution;
        Self::check(from, "from", res)?;
        Self::check(to, "to", res)?;
        if self.maps.is_empty() {
            return Ok(None);
        }
        if !self.cfg.levels.allow_stairs {
            return self.maps[0].path(&from.xy(), &to.xy());
        }
        let (lf, lt) = (self.locate(from), self.locate(to));
        if let (Some(Location::Level(a)), Some(Location::Level(b))) = (lf, lt)
            && a == b
        {
            return self.maps[usize::from(a.0)].path(&from.xy(), &to.xy());
        }
        let access = |me: &mut Self,
                      loc: Option<Location>,
                      p: &Point3<f64>|
         -> Result<Vec<(usize, Way)>, FrontierError> {
            Ok(match loc {
                Some(Location::Level(l)) => {
                    let mut out = Vec::new();
                    // Each portal at the traversable cell it snapped to.
                    let m = &me.maps[usize::from(l.0)];
                    let portals: Vec<(usize, Point3<f64>)> = me
                        .hubs
                        .hubs
                        .iter()
                        .enumerate()
                        .filter(|(_, h)| h.level == Some(l))
                        .filter_map(|(i, h)| {
                            let cell = m.graph().portals.get(&h.portal?)?.cell?;
                            let c = m.grid().cell_center(cell);
                            Some((i, Point3::new(c.x, c.y, h.position.z)))
                        })
                        .collect();
                    for (i, q) in portals {
                        if let Some(e) = me.maps[usize::from(l.0)].path(&p.xy(), &q.xy())? {
                            out.push((
                                i,
                                Way {
                                    cost: e.cost,
                                    reverse_cost: e.cost,
                                    length: e.length,
                                    path: e.path,
                                },
                            ));
                        }
                    }
                    if out.is_empty() {
                        // A point at a stair's end on a floor not mapped
                        // around it (a stair frontier): reached from the
                        // stair directly.
                        let reach = me.cfg.levels.portal_radius + 0.3;
                        for (i, h) in me.hubs.hubs.iter().enumerate() {
                            let d = (h.position - p).norm();
                            if h.level == Some(l) && d <= reach {
                                out.push((
                                    i,
                                    Way {
                                        cost: d,
                                        reverse_cost: d,
                                        length: d,
                                        path: vec![*p, h.position],
                                    },
                                ));
                            }
                        }
                    }
                    out
                }
                Some(Location::Stair(si)) if si < me.stairs.len() => me.stair_access(si, p),
                _ => Vec::new(),
            })
        };
        let wa = access(self, lf, from)?;
        let wb = access(self, lt, to)?;
        let mut best: Option<(f64, usize, usize)> = None;
        for (p, w1) in &wa {
            for (q, w2) in &wb {
                let c = w1.cost + self.hubs.cost(*p, *q) + w2.reverse_cost;
                if c.is_finite() && best.is_none_or(|b| c < b.0) {
                    best = Some((c, *p, *q));
                }
            }
        }
        let Some((_, p, q)) = best else {
            return Ok(None);
        };
        let (Some(w1), Some(w2)) = (
            wa.iter().find(|w| w.0 == p).map(|w| &w.1),
            wb.iter().find(|w| w.0 == q).map(|w| &w.1),
        ) else {
            return Ok(None);
        };
        let Some(mid) = self.hubs.way(p, q) else {
            return Ok(None);
        };
        let mut way = w1.clone();
        append(&mut way, &mid);
        append(&mut way, &w2.reversed());
        Ok(Some(Edge {
            from: NodeId::Robot,
            to: NodeId::Robot,
            bbox: bbox(&way.path, res),
            path: way.path,
            length: way.length,
            cost: way.cost,
            reverse_cost: way.reverse_cost,
        }))
    }
}

/// A point this far (m) off its level's floor, on a stair surface within
/// this height, stands on a tread ([`MultiLevelMap::locate`]).
const TREAD_DZ: f64 = 0.05;

/// How far (m) past a stair's end the robot steps onto a floor not mapped
/// yet.
const STEP_OFF: f64 = 0.4;

/// The point `STEP_OFF` past the end `end` of `s`, along the direction in
/// which the stair's path leaves it (horizontal, at the end's height).
fn step_off(s: &Stair, end: &Point3<f64>) -> Point3<f64> {
    let n = s.path.len();
    if n < 2 {
        return *end;
    }
    let lower = (s.lower.position - end).norm() <= (s.upper.position - end).norm();
    let (last, before) = if lower {
        (s.path[0], s.path[1.min(n - 1)])
    } else {
        (s.path[n - 1], s.path[n - 2])
    };
    let mut dir = (last - before).xy();
    // Use the last 0.5 m of the path for a stable direction.
    for k in 2..n {
        if dir.norm() >= 0.5 {
            break;
        }
        let q = if lower { s.path[k] } else { s.path[n - 1 - k] };
        dir = (last - q).xy();
    }
    let len = dir.norm();
    if len < 1e-6 {
        return *end;
    }
    let d = dir / len * STEP_OFF;
    Point3::new(end.x + d.x, end.y + d.y, end.z)
}

/// The stable id of the stair frontier at `p`: the column and the height
/// (quarter metres) of the open end, packed below [`STAIR_FRONTIER_BASE`].
fn stair_frontier_id(s: &SurfaceMap, p: &Point3<f64>) -> FrontierId {
    let (x, y) = s.key(p.x, p.y).unwrap_or((0, 0));
    // Packing: the low 16 bits of each column coordinate and 8 of the height.
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let packed = (u64::from(x as u16) << 24)
        | (u64::from(y as u16) << 8)
        | u64::from((p.z / 0.25).round() as i8 as u8);
    FrontierId(STAIR_FRONTIER_BASE + packed)
}

/// Bounding box of a path's cells (for [`Edge`]).
fn bbox(path: &[Point3<f64>], res: f64) -> (Cell, Cell) {
    let cells: Vec<Cell> = path
        .iter()
        .filter_map(|p| cell_of(&p.xy(), res, "path", 0).ok())
        .collect();
    let lo = cells
        .iter()
        .fold(cells.first().copied().unwrap_or(Cell::new(0, 0)), |a, c| {
            Cell::new(a.x.min(c.x), a.y.min(c.y))
        });
    let hi = cells
        .iter()
        .fold(cells.first().copied().unwrap_or(Cell::new(0, 0)), |a, c| {
            Cell::new(a.x.max(c.x), a.y.max(c.y))
        });
    (lo, hi)
}
