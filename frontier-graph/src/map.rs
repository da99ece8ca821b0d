//! [`FrontierMap`]: the grid, the frontiers and G_F, kept up to date together.

use nalgebra::{Point2, Point3};
use rustc_hash::{FxHashMap, FxHashSet};
use serde::{Deserialize, Serialize};

use crate::CellState;
use crate::cell::cell_of;
use crate::components::Components;
use crate::frontier::Detector;
use crate::graph::pair;
use crate::grid::GridDelta;
use crate::search::{ExtractedPath, Scratch, dijkstra, extract_path};
use crate::{
    AnchorNode, Cell, Edge, FrontierError, FrontierGraph, FrontierId, FrontierMapConfig, LevelId,
    NodeId, OccupancyGrid,
};

/// Relative tolerance when deciding whether a new path may be shorter.
const EPS: f64 = 1e-9;

/// What one [`FrontierMap::update`] changed.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct UpdateStats {
    /// Cells whose occupancy state changed.
    pub cells_changed: usize,
    /// Cells that became traversable.
    pub cells_gained: usize,
    /// Cells that stopped being traversable.
    pub cells_lost: usize,
    /// Frontier nodes created.
    pub frontiers_added: usize,
    /// Frontier nodes removed.
    pub frontiers_removed: usize,
}

/// What one graph refresh ([`FrontierMap::frontier_graph`]) recomputed.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RefreshStats {
    /// Node pairs whose edge had to be recomputed.
    pub pairs_recomputed: usize,
    /// Shortest-path searches run (one per recomputed row).
    pub rows_recomputed: usize,
    /// Whether the lower-bound search from newly traversable cells ran.
    pub gain_search: bool,
    /// Cell visits of all shortest-path searches of the refresh (the
    /// refresh's work, about one per cell a search labels; targets in
    /// another component cost none).
    #[serde(default)]
    pub cells_settled: usize,
}

/// Changes accumulated since the last graph refresh.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
struct Pending {
    gained: Vec<Cell>,
    lost: Vec<Cell>,
    added: FxHashSet<FrontierId>,
    full: bool,
}

/// Occupancy grid + incremental frontiers + the frontier decision graph G_F.
///
/// Feed it scans with [`update`](Self::update), then ask for the graph at the
/// robot's current pose with [`frontier_graph`](Self::frontier_graph). See the
/// crate documentation for an example.
///
/// Serialisable (for checkpoints); deserialisation validates the data and
/// rejects inconsistent files with an error.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(try_from = "MapData")]
pub struct FrontierMap {
    cfg: FrontierMapConfig,
    grid: OccupancyGrid,
    graph: FrontierGraph,
    next_id: u64,
    pending: Pending,
    last_refresh: RefreshStats,
    /// The level this map is (0 for a stand-alone map).
    #[serde(default)]
    level: LevelId,
    /// Stair portals requested by [`crate::MultiLevelMap`] (id -> position).
    #[serde(default)]
    portal_targets: std::collections::BTreeMap<u32, Point2<f64>>,
    #[serde(skip)]
    scratch: Scratch,
    /// Search buffers of the extra row-search threads.
    #[serde(skip)]
    spare: Vec<Scratch>,
    #[serde(skip)]
    components: Components,
    /// Whether some node may lie in another component than others: set
    /// when a search ends without settling one of its targets, cleared
    /// when the labels show every node in one component. Only then are the
    /// component labels maintained (O(N) per change of the traversable
    /// layer), and the searches skip unreachable targets.
    #[serde(skip)]
    islands: bool,
}

/// Unvalidated deserialised form of [`FrontierMap`].
#[derive(Deserialize)]
struct MapData {
    cfg: FrontierMapConfig,
    grid: OccupancyGrid,
    graph: FrontierGraph,
    next_id: u64,
    pending: Pending,
    last_refresh: RefreshStats,
    #[serde(default)]
    level: LevelId,
    #[serde(default)]
    portal_targets: std::collections::BTreeMap<u32, Point2<f64>>,
}

impl TryFrom<MapData> for FrontierMap {
    type Error = FrontierError;

    fn try_from(d: MapData) -> Result<Self, FrontierError> {
        d.cfg.validate()?;
        let bad = |m: &str| Err(FrontierError::InvalidConfig(format!("malformed map: {m}")));
        if d.grid.config() != &d.cfg.grid {
            return bad("grid configuration differs from the map configuration");
        }
        for (id, node) in &d.graph.frontiers {
            if node.id != *id || id.0 > d.next_id || node.cells.is_empty() {
                return bad("inconsistent frontier node");
            }
            for c in &node.cells {
                let ok = d
                    .grid
                    .index(*c)
                    .is_some_and(|i| d.grid.frontier[i] && d.grid.segment[i] == id.0);
                if !ok {
                    return bad("frontier node cells disagree with the grid");
                }
            }
        }
        for e in d.graph.edges.values() {
            if !e.cost.is_finite() || !e.length.is_finite() || e.path.is_empty() {
                return bad("non-finite or empty edge");
            }
        }
        Ok(Self {
            cfg: d.cfg,
            grid: d.grid,
            graph: d.graph,
            next_id: d.next_id,
            pending: d.pending,
            last_refresh: d.last_refresh,
            level: d.level,
            portal_targets: d.portal_targets,
            scratch: Scratch::default(),
            spare: Vec::new(),
            components: Components::default(),
            islands: false,
        })
    }
}

impl FrontierMap {
    /// An empty map (everything unknown, no frontier).
    ///
    /// # Errors
    /// [`FrontierError::InvalidConfig`] if `cfg` is invalid.
    pub fn new(cfg: FrontierMapConfig) -> Result<Self, FrontierError> {
        Self::for_level(cfg, LevelId(0))
    }

    /// The map of level `level` of a multi-level map: frontier ids start at
    /// `level << 40` so that ids of different levels never collide.
    pub(crate) fn for_level(cfg: FrontierMapConfig, level: LevelId) -> Result<Self, FrontierError> {
        cfg.validate()?;
        Ok(Self {
            grid: OccupancyGrid::new(cfg.grid.clone())?,
            cfg,
            graph: FrontierGraph::default(),
            next_id: u64::from(level.0) << 40,
            pending: Pending::default(),
            last_refresh: RefreshStats::default(),
            level,
            portal_targets: std::collections::BTreeMap::new(),
            scratch: Scratch::default(),
            spare: Vec::new(),
            components: Components::default(),
            islands: false,
        })
    }

    /// The level of this map (0 for a stand-alone map).
    pub fn level(&self) -> LevelId {
        self.level
    }

    /// Sets the stair portals (id, position) of this level; portals whose
    /// snapped cell changed get their rows recomputed at the next refresh.
    pub(crate) fn set_portals(&mut self, portals: std::collections::BTreeMap<u32, Point2<f64>>) {
        self.portal_targets = portals;
    }

    /// Sets level and height of the frontier nodes. Every node, not only
    /// the added ones: a segment dissolved and re-created identical keeps
    /// its id (it is not "added") but is rebuilt with level 0. O(F).
    fn stamp_nodes(&mut self) {
        let (level, z) = (self.level, self.cfg.grid.floor_z);
        for n in self.graph.frontiers.values_mut() {
            n.level = level;
            n.z = z;
        }
    }

    /// The configuration.
    pub fn config(&self) -> &FrontierMapConfig {
        &self.cfg
    }

    /// The occupancy / traversability grid.
    pub fn grid(&self) -> &OccupancyGrid {
        &self.grid
    }

    /// The graph as of the last [`frontier_graph`](Self::frontier_graph) call
    /// (frontier nodes are always current; edges and robot as of that call).
    pub fn graph(&self) -> &FrontierGraph {
        &self.graph
    }

    /// Statistics of the last graph refresh.
    pub fn last_refresh(&self) -> &RefreshStats {
        &self.last_refresh
    }

    /// Every frontier cell (including those of segments dropped for being
    /// smaller than [`crate::FrontierConfig::min_cells`]), in row-major order.
    pub fn frontier_cells(&self) -> impl Iterator<Item = Cell> + '_ {
        self.grid
            .frontier
            .iter()
            .enumerate()
            .filter(|(_, f)| **f)
            .map(|(i, _)| self.grid.cell_at(i))
    }

    /// Integrates one scan taken from sensor position `origin` (world, m).
    ///
    /// Sensor model, per return `p` (heights relative to
    /// [`crate::GridConfig::floor_z`]):
    /// * in the obstacle band `[step_height, robot_height]`, or a drop-off
    ///   deeper than `drop_off_depth` below the floor: the cells on the 2D ray
    ///   from the origin are misses, the return's cell a hit;
    /// * a floor return (below `step_height`): the whole ray including the
    ///   return's cell is a miss;
    /// * above the robot: misses up to where the 3D ray leaves the robot's
    ///   height band (nothing if the sensor itself is above it);
    /// * beyond `max_range` (3D): misses up to the range, no hit.
    ///
    /// Each cell is updated once per scan (hit wins over miss), log-odds are
    /// clamped. Then obstacle inflation, traversability and frontiers are
    /// updated incrementally inside the touched region.
    ///
    /// # Errors
    /// [`FrontierError::NonFinite`] / [`FrontierError::OutOfRange`] for bad
    /// coordinates, [`FrontierError::GridTooLarge`] when the grid would exceed
    /// its cell budget. On error nothing is modified.
    ///
    /// # Complexity
    /// O(P · L + C · r² + A log A): P returns with rays of L cells, C cells
    /// whose occupancy flips (robot radius r cells), A cells in frontier
    /// components touched by the update.
    pub fn update(
        &mut self,
        origin: &Point3<f64>,
        points: &[Point3<f64>],
    ) -> Result<UpdateStats, FrontierError> {
        let delta = self.grid.integrate(origin, points)?;
        Ok(self.apply(&delta))
    }

    /// As [`update`](Self::update), plus *voids*: horizontal positions
    /// where a sensor ray crossed the floor's height within the sensor's
    /// range and returned nothing, so that no floor is there (the edge of a
    /// terrace or mezzanine with nothing below in range, a hole in a
    /// mesh). Each void is a drop-off: the cells on the 2D ray from the
    /// origin are misses, its cell a hit, exactly as for a return deeper
    /// than `drop_off_depth` below the floor at that position (beyond
    /// `max_range`: misses up to the range, no hit). Without voids a floor
    /// edge over nothing stays a frontier for ever: nothing the sensor can
    /// return ever shows what is beyond it.
    ///
    /// # Errors
    /// As [`update`](Self::update); a non-finite or out-of-range void is
    /// [`FrontierError::NonFinite`] / [`FrontierError::OutOfRange`] with
    /// `what = "void"`. Nothing is modified then.
    ///
    /// # Complexity
    /// That of [`update`](Self::update) for P + V returns.
    pub fn update_with_voids(
        &mut self,
        origin: &Point3<f64>,
        points: &[Point3<f64>],
        voids: &[Point2<f64>],
    ) -> Result<UpdateStats, FrontierError> {
        if voids.is_empty() {
            return self.update(origin, points);
        }
        check_voids(voids, self.grid.resolution())?;
        // A return just below the drop-off depth at the void's position.
        let g = &self.cfg.grid;
        let z = g.floor_z - g.drop_off_depth - 0.01;
        let mut all = Vec::with_capacity(points.len() + voids.len());
        all.extend_from_slice(points);
        all.extend(voids.iter().map(|v| Point3::new(v.x, v.y, z)));
        self.update(origin, &all)
    }

    /// Records a contact: the robot standing at `feet` was stopped by an
    /// obstacle at `point` (horizontal position) that its sensor did not
    /// show (glass, an edge with nothing visible beyond it). The point's
    /// cell becomes occupied and stays so whatever later scans show; the
    /// map's inflation, traversability and frontiers follow as after
    /// [`update`](Self::update), so frontiers reached only through the
    /// contact become unreachable.
    ///
    /// A contact the map already explains — an occupied cell within the
    /// robot radius of the segment from `feet` to `point`, the disc the
    /// body sweeps (a door jamb or a table leg the robot grazed: the map
    /// knows it, the body's shape met it first) — is not recorded:
    /// `Ok(None)`. Else the update's statistics.
    ///
    /// # Errors
    /// As [`update`](Self::update) for non-finite or out-of-range
    /// coordinates, [`FrontierError::ContactOutOfReach`] for a point
    /// farther than [`crate::MAX_CONTACT_REACH_M`] from `feet`; nothing is
    /// modified then.
    ///
    /// # Complexity
    /// That of [`update`](Self::update) for one return, plus O((L + r) r)
    /// for a segment of L cells and the robot radius r (cells).
    pub fn contact(
        &mut self,
        feet: &Point3<f64>,
        point: &Point2<f64>,
    ) -> Result<Option<UpdateStats>, FrontierError> {
        let res = self.grid.resolution();
        let from = feet.xy();
        Self::check_pose(&from, "feet", res)?;
        Self::check_pose(point, "contact", res)?;
        let distance = (point - from).norm();
        if distance > crate::MAX_CONTACT_REACH_M {
            return Err(FrontierError::ContactOutOfReach {
                distance,
                limit: crate::MAX_CONTACT_REACH_M,
            });
        }
        let r = self.cfg.grid.robot_radius;
        let (a, b) = (self.grid.cell_of(&from)?, self.grid.cell_of(point)?);
        // Bounded by GridConfig::validate (<= 200 cells).
        #[allow(clippy::cast_possible_truncation)]
        let ri = (r / res).ceil() as i32;
        let ab = point - from;
        let len2 = ab.norm_squared();
        let swept = |c: Cell| {
            let q = self.grid.cell_center(c);
            let t = if len2 > 0.0 {
                ((q - from).dot(&ab) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (from + ab * t - q).norm() <= r + 1e-9
        };
        let explained = (a.y.min(b.y) - ri..=a.y.max(b.y) + ri).any(|y| {
            (a.x.min(b.x) - ri..=a.x.max(b.x) + ri).any(|x| {
                let c = Cell::new(x, y);
                self.grid.state(c) == CellState::Occupied && swept(c)
            })
        });
        if explained {
            return Ok(None);
        }
        let delta = self.grid.contact(feet, point)?;
        Ok(Some(self.apply(&delta)))
    }

    /// Frontiers and pending graph work after a grid change.
    fn apply(&mut self, delta: &GridDelta) -> UpdateStats {
        let changes = Detector {
            grid: &mut self.grid,
            nodes: &mut self.graph.frontiers,
            next_id: &mut self.next_id,
            cfg: &self.cfg.frontier,
        }
        .update(delta);
        self.stamp_nodes();
        for id in &changes.removed {
            self.pending.added.remove(id);
        }
        self.pending.added.extend(changes.added.iter().copied());
        self.pending.gained.extend(delta.gained.iter().copied());
        self.pending.lost.extend(delta.lost.iter().copied());
        UpdateStats {
            cells_changed: delta.state_changed.len(),
            cells_gained: delta.gained.len(),
            cells_lost: delta.lost.len(),
            frontiers_added: changes.added.len(),
            frontiers_removed: changes.removed.len(),
        }
    }

    /// Recomputes the frontier segmentation from scratch and marks every edge
    /// for recomputation at the next [`frontier_graph`](Self::frontier_graph)
    /// call (used as the non-incremental reference and by benchmarks).
    ///
    /// # Complexity
    /// O(N + F log F) for N grid cells and F frontier cells; the next
    /// refresh then costs one search per node.
    pub fn rebuild(&mut self) {
        let changes = Detector {
            grid: &mut self.grid,
            nodes: &mut self.graph.frontiers,
            next_id: &mut self.next_id,
            cfg: &self.cfg.frontier,
        }
        .rebuild();
        self.stamp_nodes();
        self.graph.edges.clear();
        self.pending = Pending {
            full: true,
            added: changes.added.into_iter().collect(),
            ..Pending::default()
        };
    }

    /// Snaps a position to the nearest traversable cell within the snap radius
    /// (ties broken by cell order).
    ///
    /// # Complexity
    /// O((r / resolution)²) for snap radius r.
    fn snap(&self, p: &Point2<f64>) -> Option<Cell> {
        self.snap_within(p, self.cfg.graph.snap_radius)
    }

    /// [`snap`](Self::snap) within `radius` (m, at most 10).
    fn snap_within(&self, p: &Point2<f64>, radius: f64) -> Option<Cell> {
        let res = self.grid.resolution();
        let c = cell_of(p, res, "pose", 0).ok()?;
        if self.grid.is_traversable(c) {
            return Some(c);
        }
        let radius = radius.clamp(0.0, 10.0);
        // Bounded by the clamp (<= 10 m).
        #[allow(clippy::cast_possible_truncation)]
        let r = (radius / res).ceil() as i32;
        let mut best: Option<(f64, Cell)> = None;
        for dy in -r..=r {
            for dx in -r..=r {
                let n = c.offset(dx, dy);
                if !self.grid.is_traversable(n) {
                    continue;
                }
                let d = (self.grid.cell_center(n) - p).norm();
                if d <= radius + 1e-12 && best.is_none_or(|(bd, bc)| (d, n) < (bd, bc)) {
                    best = Some((d, n));
                }
            }
        }
        best.map(|b| b.1)
    }

    fn check_pose(p: &Point2<f64>, what: &'static str, res: f64) -> Result<(), FrontierError> {
        cell_of(p, res, what, 0).map(|_| ())
    }

    /// The source cell and displacement of a node.
    fn anchor(&self, id: NodeId) -> Option<(Cell, f64)> {
        let g = &self.graph;
        match id {
            NodeId::Robot => g.robot.as_ref().and_then(|a| {
                a.cell
                    .map(|c| (c, (self.grid.cell_center(c) - a.position).norm()))
            }),
            NodeId::Home => g.home.as_ref().and_then(|a| {
                a.cell
                    .map(|c| (c, (self.grid.cell_center(c) - a.position).norm()))
            }),
            NodeId::Frontier(f) => g
                .frontiers
                .get(&f)
                .map(|n| (n.viewpoint_cell, (n.viewpoint - n.centroid).norm())),
            NodeId::Portal(p) => g.portals.get(&p).and_then(|a| a.cell.map(|c| (c, 0.0))),
        }
    }

    /// Brings G_F up to date for the robot at `robot` and returns it.
    ///
    /// The home node is placed at the first pose ever given (when enabled).
    /// Only *rows* that may have changed are recomputed, each with one
    /// early-terminating Dijkstra search over the traversable grid:
    /// * rows of new nodes, and of the robot/home when their cell moved;
    /// * pairs whose stored path uses a cell that stopped being traversable,
    ///   either on the path or as a side cell of a diagonal step (diagonal
    ///   moves need both straight neighbours);
    /// * pairs `(a, b)` that the newly traversable cells might shorten: a new
    ///   path either crosses a newly traversable cell or takes a diagonal step
    ///   one of them enabled, so it visits the set `G` of those cells and
    ///   their traversable 8-neighbours. One multi-source search from `G`
    ///   gives `d(a, G)` for every node, and the pair is recomputed only if
    ///   `d(a, G) + d(G, b) < length(a, b)` (a sound lower bound).
    ///
    /// Flagged pairs are covered greedily by rows (the node with most flagged
    /// pairs first), and each search stops once its row's flagged targets are
    /// settled. The result equals a rebuild from scratch (costs exactly;
    /// paths up to ties).
    ///
    /// # Errors
    /// [`FrontierError::NonFinite`] / [`FrontierError::OutOfRange`] for a bad
    /// pose; nothing is modified then.
    ///
    /// # Complexity
    /// O(R · N) for R recomputed rows over N traversable cells, plus
    /// O(V² + E · L) for the change tests (V nodes, E edges of L path cells
    /// near lost cells).
    pub fn frontier_graph(&mut self, robot: &Point2<f64>) -> Result<&FrontierGraph, FrontierError> {
        Self::check_pose(robot, "pose", self.grid.resolution())?;
        self.refresh(Some(robot));
        Ok(&self.graph)
    }

    /// [`frontier_graph`](Self::frontier_graph) with the robot on this
    /// level (`Some`) or elsewhere (`None`: no robot node, no home node is
    /// created). The pose must have been checked.
    pub(crate) fn refresh(&mut self, robot: Option<&Point2<f64>>) {
        let res = self.grid.resolution();
        let mut pending = std::mem::take(&mut self.pending);
        let mut stats = RefreshStats::default();
        let mut saw_islands = false;
        let (level, z) = (self.level, self.cfg.grid.floor_z);

        // Anchors.
        if let Some(robot) = robot
            && self.cfg.graph.home
            && self.graph.home.is_none()
        {
            self.graph.home = Some(AnchorNode {
                position: *robot,
                cell: None,
                level,
                z,
            });
        }
        let mut fresh: Vec<NodeId> = Vec::new();
        let robot_cell = robot.and_then(|r| self.snap(r));
        let old_robot = match robot {
            Some(r) => self.graph.robot.replace(AnchorNode {
                position: *r,
                cell: robot_cell,
                level,
                z,
            }),
            None => self.graph.robot.take(),
        };
        if old_robot.as_ref().and_then(|a| a.cell) != robot_cell || old_robot.is_none() {
            fresh.push(NodeId::Robot);
        }
        // Portals: dropped, moved or new.
        let targets = std::mem::take(&mut self.portal_targets);
        self.graph.portals.retain(|id, _| targets.contains_key(id));
        for (&id, p) in &targets {
            let cell = self.snap_within(p, self.cfg.levels.portal_radius);
            let node = AnchorNode {
                position: *p,
                cell,
                level,
                z,
            };
            match self.graph.portals.insert(id, node) {
                Some(old) if old.cell == cell => {}
                _ => fresh.push(NodeId::Portal(id)),
            }
        }
        self.portal_targets = targets;
        if let Some(home) = self.graph.home.as_ref().map(|h| h.position) {
            let hc = self.snap(&home);
            let h = self
                .graph
                .home
                .as_mut()
                .map(|h| std::mem::replace(&mut h.cell, hc));
            if h.flatten() != hc {
                fresh.push(NodeId::Home);
            }
        }
        fresh.extend(
            pending
                .added
                .iter()
                .filter(|f| self.graph.frontiers.contains_key(f))
                .map(|&f| NodeId::Frontier(f)),
        );

        // Current nodes with their source cells.
        let nodes: Vec<(NodeId, Cell, f64)> = self
            .graph
            .node_ids()
            .filter_map(|id| self.anchor(id).map(|(c, d)| (id, c, d)))
            .collect();
        let slot: FxHashMap<NodeId, usize> =
            nodes.iter().enumerate().map(|(k, n)| (n.0, k)).collect();

        // Drop edges of vanished or moved nodes.
        let fresh_set: FxHashSet<NodeId> = fresh.iter().copied().collect();
        self.graph.edges.retain(|&(a, b), _| {
            slot.contains_key(&a)
                && slot.contains_key(&b)
                && !fresh_set.contains(&a)
                && !fresh_set.contains(&b)
        });

        // Flag pairs.
        let v = nodes.len();
        let mut flagged = vec![false; v * v];
        let flag = |a: usize, b: usize, f: &mut Vec<bool>| {
            if a != b {
                f[a * v + b] = true;
                f[b * v + a] = true;
            }
        };
        if pending.full {
            for a in 0..v {
                for b in a + 1..v {
                    flag(a, b, &mut flagged);
                }
            }
        } else {
            for id in &fresh {
                if let Some(&a) = slot.get(id) {
                    for b in 0..v {
                        flag(a, b, &mut flagged);
                    }
                }
            }
            // Paths crossing lost cells.
            pending.lost.sort_unstable();
            pending.lost.dedup();
            if !pending.lost.is_empty() {
                let lost: FxHashSet<Cell> = pending.lost.iter().copied().collect();
                let (mut lo, mut hi) = (pending.lost[0], pending.lost[0]);
                for c in &pending.lost {
                    lo = Cell::new(lo.x.min(c.x), lo.y.min(c.y));
                    hi = Cell::new(hi.x.max(c.x), hi.y.max(c.y));
                }
                for (key, e) in &self.graph.edges {
                    // Side cells of diagonal steps lie within one cell of the bbox.
                    let (elo, ehi) = (e.bbox.0.offset(-1, -1), e.bbox.1.offset(1, 1));
                    if elo.x > hi.x || elo.y > hi.y || ehi.x < lo.x || ehi.y < lo.y {
                        continue;
                    }
                    if path_crosses(e, &lost, res) {
                        flag(slot[&key.0], slot[&key.1], &mut flagged);
                    }
                }
            }
            // Pairs a newly traversable region might shorten.
            // A new path either crosses a gained cell or takes a diagonal step
            // that a gained side cell enabled; both endpoints of such a step
            // are 8-neighbours of the gained cell. So sources = gained cells
            // and their traversable 8-neighbours.
            let mut gained: Vec<usize> = Vec::with_capacity(pending.gained.len() * 3);
            for &c in &pending.gained {
                for (dx, dy) in crate::search::DIRS.iter().copied().chain([(0, 0)]) {
                    if let Some(i) = self.grid.index(c.offset(dx, dy))
                        && self.grid.trav_at(i)
                    {
                        gained.push(i);
                    }
                }
            }
            gained.sort_unstable();
            gained.dedup();
            // Only nodes in a component of a gained cell can gain a path.
            let comp = self.islands.then(|| self.components.refresh(&self.grid));
            let label = |i: usize| comp.map_or(1, |c| c.label(i));
            let mut labels: Vec<u32> = gained.iter().map(|&i| label(i)).collect();
            labels.sort_unstable();
            labels.dedup();
            let targets: Vec<usize> = nodes
                .iter()
                .filter_map(|n| self.grid.index(n.1))
                .filter(|&i| labels.binary_search(&label(i)).is_ok())
                .collect();
            if !targets.is_empty() && v > 1 {
                stats.gain_search = true;
                stats.cells_settled += dijkstra(&self.grid, &mut self.scratch, &gained, &targets);
                saw_islands |= self.scratch.missed(&targets);
                let lb: Vec<Option<f64>> = nodes
                    .iter()
                    .map(|n| {
                        self.grid
                            .index(n.1)
                            .filter(|&i| labels.binary_search(&label(i)).is_ok())
                            .and_then(|i| self.scratch.settled(i))
                            .map(|d| d * res)
                    })
                    .collect();
                for a in 0..v {
                    let Some(la) = lb[a] else { continue };
                    for b in a + 1..v {
                        let Some(lb_b) = lb[b] else { continue };
                        let old = self
                            .graph
                            .edges
                            .get(&pair(nodes[a].0, nodes[b].0))
                            .map_or(f64::INFINITY, |e| e.length);
                        if la + lb_b < old * (1.0 - EPS) - EPS {
                            flag(a, b, &mut flagged);
                        }
                    }
                }
            }
        }

        // Cover flagged pairs with rows, greedily.
        let mut count: Vec<usize> = (0..v)
            .map(|a| flagged[a * v..(a + 1) * v].iter().filter(|f| **f).count())
            .collect();
        let w = self.cfg.graph.displacement_weight;
        // Ties (all pairs flagged after a rebuild) are broken by a sweep along
        // the principal axis of the node cells: rows processed late then only
        // need targets close by, which early termination exploits.
        let sweep = sweep_rank(&nodes);
        let mut plan: Vec<RowPlan> = Vec::new();
        while let Some((a, &ca)) = count
            .iter()
            .enumerate()
            .max_by_key(|(k, c)| (**c, usize::MAX - sweep[*k]))
        {
            if ca == 0 {
                break;
            }
            let row: Vec<usize> = (0..v).filter(|&b| flagged[a * v + b]).collect();
            for &b in &row {
                flagged[a * v + b] = false;
                flagged[b * v + a] = false;
                count[b] -= 1;
            }
            count[a] = 0;
            stats.rows_recomputed += 1;
            stats.pairs_recomputed += row.len();
            plan.push(RowPlan { source: a, row });
        }
        // The rows are independent searches over the same grid: run them
        // (in parallel when asked), then store their edges in plan order.
        let comp = self.islands.then(|| self.components.refresh(&self.grid));
        let threads = self.cfg.graph.row_threads().min(plan.len()).max(1);
        let results: Vec<RowResult> = if threads == 1 {
            plan.iter()
                .map(|r| run_row(&self.grid, comp, &nodes, r, &mut self.scratch))
                .collect()
        } else {
            if self.spare.len() < threads - 1 {
                self.spare.resize_with(threads - 1, Scratch::default);
            }
            let (grid, nodes, plan) = (&self.grid, &nodes, &plan);
            let next = std::sync::atomic::AtomicUsize::new(0);
            let work = |s: &mut Scratch| {
                let mut out = Vec::new();
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(r) = plan.get(k) else { break };
                    out.push((k, run_row(grid, comp, nodes, r, s)));
                }
                out
            };
            let mut done: Vec<(usize, RowResult)> = std::thread::scope(|sc| {
                let handles: Vec<_> = self.spare[..threads - 1]
                    .iter_mut()
                    .map(|s| sc.spawn(|| work(s)))
                    .collect();
                let mut all = work(&mut self.scratch);
                for h in handles {
                    match h.join() {
                        Ok(part) => all.extend(part),
                        // A worker can only fail by a bug: re-raise it here.
                        Err(e) => std::panic::resume_unwind(e),
                    }
                }
                all
            });
            done.sort_unstable_by_key(|(k, _)| *k);
            done.into_iter().map(|(_, r)| r).collect()
        };
        for (r, result) in plan.iter().zip(results) {
            stats.cells_settled += result.visits;
            saw_islands |= result.missed;
            let (ida, _, da) = nodes[r.source];
            for (&b, found) in r.row.iter().zip(result.found) {
                let (idb, _, db) = nodes[b];
                let key = pair(ida, idb);
                match found {
                    Some((length, (mut path, bbox))) => {
                        if key.0 != ida {
                            path.reverse();
                        }
                        let cost = length + w * (da + db);
                        self.graph.edges.insert(
                            key,
                            Edge {
                                from: key.0,
                                to: key.1,
                                path: lift(&path, z),
                                length,
                                cost,
                                reverse_cost: cost,
                                bbox,
                            },
                        );
                    }
                    None => {
                        self.graph.edges.remove(&key);
                    }
                }
            }
        }
        // The robot's displacement changes with its pose even on the same cell.
        if w > 0.0 {
            for n in &nodes {
                if n.0 != NodeId::Robot {
                    continue;
                }
                for (other, _, dother) in &nodes {
                    if let Some(e) = self.graph.edges.get_mut(&pair(NodeId::Robot, *other)) {
                        e.cost = e.length + w * (n.2 + dother);
                        e.reverse_cost = e.cost;
                    }
                }
            }
        }
        pending.gained.clear();
        pending.lost.clear();
        pending.added.clear();
        pending.full = false;
        self.pending = pending;
        self.last_refresh = stats;
        self.islands = if self.islands {
            // Still needed while the nodes span several components.
            let comp = self.components.refresh(&self.grid);
            let mut node_labels = nodes
                .iter()
                .filter_map(|n| self.grid.index(n.1))
                .map(|i| comp.label(i))
                .filter(|&l| l != 0);
            let first = node_labels.next();
            node_labels.any(|l| Some(l) != first)
        } else {
            saw_islands
        };
    }

    /// Shortest executable path between two world points, each snapped to
    /// the nearest traversable cell within [`crate::GraphConfig::snap_radius`].
    /// `Ok(None)` when either point has no traversable cell nearby or they
    /// are not connected. The returned edge has `from = to = NodeId::Robot`
    /// (it is not part of G_F); `cost == length`.
    ///
    /// # Errors
    /// [`FrontierError::NonFinite`] / [`FrontierError::OutOfRange`].
    ///
    /// # Complexity
    /// O(N) for N traversable cells closer to `from` than `to` is.
    pub fn path(
        &mut self,
        from: &Point2<f64>,
        to: &Point2<f64>,
    ) -> Result<Option<Edge>, FrontierError> {
        let res = self.grid.resolution();
        Self::check_pose(from, "from", res)?;
        Self::check_pose(to, "to", res)?;
        let (Some(a), Some(b)) = (self.snap(from), self.snap(to)) else {
            return Ok(None);
        };
        let (Some(ia), Some(ib)) = (self.grid.index(a), self.grid.index(b)) else {
            return Ok(None);
        };
        if self.islands {
            let comp = self.components.refresh(&self.grid);
            if comp.label(ia) == 0 || comp.label(ia) != comp.label(ib) {
                return Ok(None);
            }
        }
        dijkstra(&self.grid, &mut self.scratch, &[ia], &[ib]);
        self.islands |= self.scratch.missed(&[ib]);
        let Some(d) = self.scratch.settled(ib) else {
            return Ok(None);
        };
        let z = self.cfg.grid.floor_z;
        Ok(
            extract_path(&self.grid, &self.scratch, ib).map(|(path, bbox)| Edge {
                from: NodeId::Robot,
                to: NodeId::Robot,
                path: lift(&path, z),
                length: d * res,
                cost: d * res,
                reverse_cost: d * res,
                bbox,
            }),
        )
    }
}

/// One row of a refresh: the node slot searched from and the node slots
/// whose edges to it are recomputed.
struct RowPlan {
    source: usize,
    row: Vec<usize>,
}

/// The outcome of one row: per target slot of its [`RowPlan`], the length
/// (m) and path of the edge, `None` when there is no path.
struct RowResult {
    found: Vec<Option<(f64, ExtractedPath)>>,
    /// Cell visits of the search.
    visits: usize,
    /// Whether the search left a target unsettled (another component).
    missed: bool,
}

/// Searches one row: one early-terminating search from the row's source
/// cell to its targets in the same component (`comp`, when maintained).
fn run_row(
    grid: &OccupancyGrid,
    comp: Option<&Components>,
    nodes: &[(NodeId, Cell, f64)],
    r: &RowPlan,
    s: &mut Scratch,
) -> RowResult {
    let res = grid.resolution();
    let none = || RowResult {
        found: vec![None; r.row.len()],
        visits: 0,
        missed: false,
    };
    let Some(src) = grid.index(nodes[r.source].1) else {
        return none();
    };
    // Targets in other components have no path: no search for them.
    let label = |i: usize| comp.map_or(1, |c| c.label(i));
    let home = label(src);
    let index = |b: usize| {
        grid.index(nodes[b].1)
            .filter(|&t| label(t) == home && home != 0)
    };
    let targets: Vec<usize> = r.row.iter().filter_map(|&b| index(b)).collect();
    if targets.is_empty() {
        return none();
    }
    let visits = dijkstra(grid, s, &[src], &targets);
    let missed = s.missed(&targets);
    let found = r
        .row
        .iter()
        .map(|&b| {
            let t = index(b)?;
            let d = s.settled(t)?;
            Some((d * res, extract_path(grid, s, t)?))
        })
        .collect();
    RowResult {
        found,
        visits,
        missed,
    }
}

/// Points at height `z`.
pub(crate) fn lift(points: &[Point2<f64>], z: f64) -> Vec<Point3<f64>> {
    points.iter().map(|p| Point3::new(p.x, p.y, z)).collect()
}

/// Rank of every node along the principal axis of the node cells.
fn sweep_rank(nodes: &[(NodeId, Cell, f64)]) -> Vec<usize> {
    let n = nodes.len().max(1) as f64;
    let (mx, my) = nodes.iter().fold((0.0, 0.0), |(x, y), c| {
        (x + f64::from(c.1.x) / n, y + f64::from(c.1.y) / n)
    });
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for c in nodes {
        let (dx, dy) = (f64::from(c.1.x) - mx, f64::from(c.1.y) - my);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let (ax, ay) = (theta.cos(), theta.sin());
    let mut order: Vec<usize> = (0..nodes.len()).collect();
    let key = |k: usize| f64::from(nodes[k].1.x) * ax + f64::from(nodes[k].1.y) * ay;
    order.sort_by(|&a, &b| key(a).total_cmp(&key(b)).then(a.cmp(&b)));
    let mut rank = vec![0; nodes.len()];
    for (r, k) in order.into_iter().enumerate() {
        rank[k] = r;
    }
    rank
}

/// Whether the path of `e` depends on any cell in `cells`: a cell on the
/// path, or a side cell of a diagonal step (diagonal moves require both
/// straight neighbours, no corner cutting).
fn path_crosses(e: &Edge, cells: &FxHashSet<Cell>, res: f64) -> bool {
    let mut prev: Option<Cell> = None;
    for c in path_cells(&e.path, res) {
        if cells.contains(&c) {
            return true;
        }
        if let Some(p) = prev {
            let (dx, dy) = (c.x - p.x, c.y - p.y);
            if dx != 0
                && dy != 0
                && (cells.contains(&p.offset(dx, 0)) || cells.contains(&p.offset(0, dy)))
            {
                return true;
            }
        }
        prev = Some(c);
    }
    false
}

/// Every cell of a one-level path polyline as stored in [`Edge::path`]
/// (consecutive points differ by a multiple of one of the 8 grid
/// directions; heights are ignored), in order.
///
/// # Complexity
/// O(L) for a path of L cells (lazy iterator).
pub fn path_cells(path: &[Point3<f64>], resolution: f64) -> impl Iterator<Item = Cell> + '_ {
    let to_cell = move |p: &Point3<f64>| {
        // Path points are cell centres produced by this crate.
        #[allow(clippy::cast_possible_truncation)]
        Cell::new(
            (p.x / resolution).floor() as i32,
            (p.y / resolution).floor() as i32,
        )
    };
    let first = path.first().map(to_cell);
    first.into_iter().chain(path.windows(2).flat_map(move |w| {
        let (a, b) = (to_cell(&w[0]), to_cell(&w[1]));
        let (dx, dy) = ((b.x - a.x).signum(), (b.y - a.y).signum());
        let n = (b.x - a.x).abs().max((b.y - a.y).abs());
        (1..=n).map(move |k| a.offset(dx * k, dy * k))
    }))
}

/// Checks that every void is finite and addressable at resolution `res`.
///
/// # Errors
/// [`FrontierError::NonFinite`] / [`FrontierError::OutOfRange`] with
/// `what = "void"` and the first bad void's index.
pub(crate) fn check_voids(voids: &[Point2<f64>], res: f64) -> Result<(), FrontierError> {
    for (index, v) in voids.iter().enumerate() {
        cell_of(v, res, "void", index)?;
    }
    Ok(())
}
