//! Stairs: chains of walkable steps joining levels, extracted from the
//! walkable-surface map.
//!
//! # Algorithm
//! 1. Every walkable surface of every column is a *node*; a node within
//!    `level_tolerance` of a level's floor is *on* that level, the others
//!    are *off-level* (treads, landings, furniture tops, floors of levels
//!    not yet known).
//! 2. Two nodes of 8-neighbouring columns are *step-connected* when their
//!    heights differ by at most the robot's step height, or, both
//!    off-level, by at most `max_stair_column_rise` *inside a flight*: the
//!    columns before and after the pair, in the same direction, rise (or
//!    descend) on by a step at most each (a column's top is the highest
//!    tread in it, so on a stair whose treads are shallower than a column
//!    neighbours differ by several risers; a chair seat beside a counter
//!    has flat neighbours and stays a jump); so are two nodes
//!    two columns apart in one of the 8 directions when the column between
//!    them holds no surface at all (a riser or tread edge the camera did
//!    not resolve: seen from above at a grazing angle, a stair shows its
//!    treads with unobserved columns between them). Off-level nodes
//!    are grouped into step-connected components (union-find); a component
//!    is *attached* to a level when one of its nodes is step-connected to a
//!    node on that level (a *foot*). Two more kinds of feet: a surface the
//!    robot's own feet moved onto from the level (`WalkedStep`: a
//!    flight's first column may rise two sub-steps from the floor, more
//!    than a step, when its bottom sub-step is narrower than a column),
//!    and, for a component that rises at least `min_stair_rise` from a
//!    level, a node within `max_stair_column_rise` of its floor facing it
//!    across at most `GAP_FOOT_COLUMNS` (3) unobserved columns (seen from
//!    the floor beside it, a flight's first treads lie at a grazing
//!    angle).
//! 3. A node is *walkable* when no column within the robot radius holds
//!    only surfaces more than two step heights away from it (a wall top, a
//!    drop-off) and at least half of those columns hold a surface within
//!    two step heights: the robot's footprint is supported (walls,
//!    railings and drop-offs beside a stair erode it; a few unobserved
//!    columns do not).
//! 4. An attached component gives a **stair** for each pair of its levels
//!    adjacent in height that a walkable chain joins (the shortest one from
//!    a foot on the lower level to a foot on the upper one, by Dijkstra
//!    over 3-D step lengths; one stairwell may join several floors), and a
//!    *partly seen* stair wherever it climbs or descends at least
//!    `min_stair_rise` over walkable nodes beyond its levels: below the
//!    lowest, above the highest, and from both sides of a pair not joined
//!    yet (its far end is the walkable node farthest in height in that
//!    direction; exploring it reveals more). A *sighted* flight needs less:
//!    when the component's surfaces, walkable or not, reach
//!    `min_sighting_rise` beyond the level, any walkable tread above the
//!    level's tolerance is an open end (a flight seen from its side shows
//!    its treads' edges step by step, but the footprint test passes only
//!    on the first treads, whose tops the camera sees; standing there
//!    shows the rest). The reach also counts the flight beyond unobserved
//!    columns: a flight seen from its foot shows its first treads, the
//!    rest hides behind their risers, and what was seen of it from
//!    elsewhere is a separate component; a surface within 2 m of a top
//!    tread bordering unobserved columns, with nothing seen on the line
//!    between and at most 45° above it, counts. A
//!    sheer drop is never step-connected, so it stays an obstacle; furniture
//!    tops are not attached (their edge is higher than a step).
//! 5. Inside attached components, a flat area of walkable nodes (wall
//!    tops seen from below are lines a column or two wide, never
//!    walkable) of at least `min_level_area`
//!    at least `min_level_separation` away from every known floor is a new
//!    level (the floor at the top or bottom of a stair). Level 0 is where
//!    the robot started, which may be a stair's half landing: until its
//!    mapped floor reaches `min_level_area`, a new level needs only
//!    `min_stair_rise` from it (the floors half a storey above and below a
//!    landing are levels).
//!
//! # Complexity
//! Run when the surface map has changed: O(T log C) to bring the set of C
//! off-level columns up to date for the T columns the updates touched
//! (`OffLevelColumns`; O(mapped columns) when the levels changed), then
//! O(S log S) for the S off-level surfaces (step 1 starts from them only;
//! union-find and Dijkstra are near-linear) plus O(W r^2) for the
//! footprint test of the W surfaces of attached components (r = robot
//! radius in columns). On a 30 m x 30 m two-floor house this is ~0.1-1 ms
//! where a scan of every mapped column took 5-10 ms per refresh.
//!
//! # Limits
//! Ramps steeper than a step per column are not stairs (gentle ramps are:
//! any step-connected chain is); spiral stairs work while their walkable
//! width survives the erosion; elevators and ladders are not modelled.

use std::cmp::Reverse;
use std::collections::{BTreeMap, BTreeSet, BinaryHeap};

use nalgebra::Point3;
use petgraph::unionfind::UnionFind;
use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};

use crate::LevelId;
use crate::search::DIRS as DIRS8;
use crate::surface::{ColumnKey, SurfaceMap};

/// One end of a [`Stair`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StairEnd {
    /// The level this end reaches; `None` for the unexplored end of a
    /// partly seen stair.
    pub level: Option<LevelId>,
    /// Where the end is: a point of the level's floor next to the first
    /// step (at the height of the floor surface mapped there, within the
    /// level tolerance of the level's nominal height), or the last walkable
    /// step seen.
    pub position: Point3<f64>,
}

/// A stair of a [`crate::MultiLevelMap`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stair {
    /// The lower end.
    pub lower: StairEnd,
    /// The upper end.
    pub upper: StairEnd,
    /// Walkable 3-D polyline from `lower` to `upper` (one point per surface
    /// column, at the surface's height).
    pub path: Vec<Point3<f64>>,
    /// Length of `path` (m, 3-D).
    pub length: f64,
    /// Walkable surface columns of the stair with their heights (sorted).
    pub(crate) columns: Vec<(ColumnKey, f32)>,
}

impl Stair {
    /// Whether both ends reach a level.
    pub fn is_complete(&self) -> bool {
        self.lower.level.is_some() && self.upper.level.is_some()
    }

    /// The unexplored end of a partly seen stair.
    pub fn open_end(&self) -> Option<&StairEnd> {
        if self.lower.level.is_none() {
            Some(&self.lower)
        } else if self.upper.level.is_none() {
            Some(&self.upper)
        } else {
            None
        }
    }

    /// Whether `p` stands on the stair's walkable surface: a walkable
    /// column of the stair (or one of its 8 neighbours) whose surface is
    /// within `dz` of `p.z`.
    pub(crate) fn supports(&self, key: ColumnKey, z: f64, dz: f64) -> bool {
        (-1..=1).any(|dx| {
            (-1..=1).any(|dy| {
                let k = (key.0 + dx, key.1 + dy);
                let a = self.columns.partition_point(|c| c.0 < k);
                self.columns[a..]
                    .iter()
                    .take_while(|c| c.0 == k)
                    .any(|c| (f64::from(c.1) - z).abs() <= dz)
            })
        })
    }
}

/// Robot and level parameters of an extraction.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Params {
    /// Step height: a stair's first tread is within it of the floor.
    pub step: f32,
    /// Largest height difference of step-connected off-level neighbours
    /// (at least `step`).
    pub column_rise: f32,
    pub clearance: f32,
    pub radius: f64,
    pub level_tolerance: f32,
    pub min_level_separation: f64,
    pub min_level_area: f64,
    pub min_stair_rise: f64,
    pub min_sighting_rise: f64,
    /// Level 0 (the first pose's floor) has at least `min_level_area` of
    /// mapped floor. Until then it may be a stair's landing: new levels
    /// need only `min_stair_rise` from it, not `min_level_separation`.
    pub first_level_established: bool,
}

/// A move of the robot's feet between two surface columns at different
/// heights (column, feet height at each end), recorded as the robot went:
/// proof that the two surfaces are joined whatever the map shows between
/// them. A column's top is its highest tread, so the first column of a
/// flight whose bottom sub-step is narrower than a column rises more than
/// a step from the floor beside it, and the flight stays unattached until
/// the robot has walked onto it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct WalkedStep {
    /// Column and feet height before the move.
    pub from: (ColumnKey, f32),
    /// Column and feet height after it.
    pub to: (ColumnKey, f32),
}

/// What [`extract`] found.
#[derive(Debug, Clone, Default)]
pub(crate) struct Extraction {
    pub stairs: Vec<Stair>,
    /// Heights of new levels (flat areas over stairs).
    pub new_levels: Vec<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    On(usize),
    Off(usize),
}

/// The level whose floor is nearest to `z` within `tolerance`, if any.
fn level_of(z: f32, levels: &[f64], tolerance: f32) -> Option<usize> {
    let z = f64::from(z);
    levels
        .iter()
        .enumerate()
        .filter(|(_, h)| (z - **h).abs() <= f64::from(tolerance))
        .min_by(|a, b| (z - a.1).abs().total_cmp(&(z - b.1).abs()))
        .map(|(l, _)| l)
}

/// Whether column `k` holds a surface on no level.
fn has_off_level(map: &SurfaceMap, k: ColumnKey, levels: &[f64], p: &Params) -> bool {
    map.surfaces(k, p.clearance)
        .any(|z| level_of(z, levels, p.level_tolerance).is_none())
}

/// The columns that hold an off-level surface (a tread, a landing, a
/// furniture top, a floor of a level not known yet): the only columns an
/// extraction starts from. Kept up to date from the columns each update
/// touched, and recomputed from scratch when the levels change, so that
/// an extraction costs O(off-level surfaces), not O(mapped columns).
#[derive(Debug, Clone, Default)]
pub(crate) struct OffLevelColumns {
    /// Floor heights, level tolerance and clearance the set is valid for;
    /// `None` when it must be recomputed.
    valid_for: Option<(Vec<f64>, f32, f32)>,
    /// The columns, sorted (extraction order is deterministic).
    cols: BTreeSet<ColumnKey>,
    /// The column table of the last extraction: the columns it read.
    last: Option<ColumnTable>,
    /// Whether an extraction may differ from the last one: the set
    /// changed, or a column the last extraction read received returns.
    stale: bool,
}

impl OffLevelColumns {
    /// Forces a recomputation at the next [`update`](Self::update).
    pub(crate) fn invalidate(&mut self) {
        self.valid_for = None;
        self.stale = true;
    }

    /// Whether [`extract`] may give another result than last time. When
    /// not, the last extraction still holds: it reads only the off-level
    /// columns and the columns within its margin of them, none of which
    /// changed.
    pub(crate) fn stale(&self) -> bool {
        self.stale || self.last.is_none()
    }

    /// Brings the set up to date after returns fell in the columns
    /// `touched`: O(touched log C) while the levels are the same, O(mapped
    /// columns) when they changed.
    pub(crate) fn update(
        &mut self,
        map: &SurfaceMap,
        touched: &[ColumnKey],
        levels: &[f64],
        p: &Params,
    ) {
        let valid = self
            .valid_for
            .as_ref()
            .is_some_and(|(l, tolerance, clearance)| {
                l.as_slice() == levels
                    && *tolerance == p.level_tolerance
                    && *clearance == p.clearance
            });
        if valid {
            for &k in touched {
                let changed = if has_off_level(map, k, levels, p) {
                    self.cols.insert(k)
                } else {
                    self.cols.remove(&k)
                };
                self.stale |= changed || self.last.as_ref().is_none_or(|t| t.covers(k));
            }
        } else {
            self.stale = true;
            self.cols = map
                .columns
                .keys()
                .copied()
                .filter(|&k| has_off_level(map, k, levels, p))
                .collect();
            self.valid_for = Some((levels.to_vec(), p.level_tolerance, p.clearance));
        }
    }
}

/// Dense tables of at most this many columns (a 400 m x 400 m box at the
/// default 0.1 m columns); larger boxes are indexed by a hash map.
const MAX_DENSE_COLUMNS: i64 = 1 << 24;

/// Table slot of a column without surfaces.
const NO_SURFACE: u32 = u32::MAX;
/// Table slot of a column not looked up (never read after construction).
const UNSEEN: u32 = u32::MAX - 1;

/// The walkable surfaces (clearance applied) of the columns around the
/// off-level ones, computed once per extraction: the step connection looks
/// at every off-level node's 8 neighbours (and the columns beyond), the
/// footprint test at a disk around it.
#[derive(Debug, Clone)]
struct ColumnTable {
    /// Box of the table (inclusive min, dimensions).
    min: ColumnKey,
    dims: (i64, i64),
    /// Slot of each column of the box ([`NO_SURFACE`], [`UNSEEN`]), when
    /// the box is small enough for a dense array.
    dense: Vec<u32>,
    /// Slot of each column, otherwise.
    sparse: FxHashMap<ColumnKey, u32>,
    /// Per slot: first index into `zs`, surface count, index of the
    /// column's first off-level node (`u32::MAX`: none).
    slots: Vec<(u32, u32, u32)>,
    zs: Vec<f32>,
}

impl ColumnTable {
    /// The columns of `map` within `margin` of an off-level node, in a
    /// box that reaches `reach` columns beyond the off-level nodes (the
    /// columns between are looked up on demand, [`fill`](Self::fill)).
    ///
    /// # Complexity
    /// O(B + N m²) for B columns in the box (dense) and N off-level nodes
    /// with margin m.
    fn new(
        map: &SurfaceMap,
        off: &[(ColumnKey, f32)],
        clearance: f32,
        margin: i32,
        reach: i32,
    ) -> Self {
        let (mut lo, mut hi) = ((i32::MAX, i32::MAX), (i32::MIN, i32::MIN));
        for &(k, _) in off {
            lo = (lo.0.min(k.0), lo.1.min(k.1));
            hi = (hi.0.max(k.0), hi.1.max(k.1));
        }
        let m = i64::from(margin.max(reach));
        let min = (i64::from(lo.0) - m, i64::from(lo.1) - m);
        let dims = (
            (i64::from(hi.0) + m - min.0 + 1).max(0),
            (i64::from(hi.1) + m - min.1 + 1).max(0),
        );
        let dense_ok = dims.0.saturating_mul(dims.1) <= MAX_DENSE_COLUMNS;
        // Within i32: column keys are bounded by MAX_CELL_COORD, far below
        // i32::MAX minus any margin.
        #[allow(clippy::cast_possible_truncation)]
        let mut t = Self {
            min: (min.0 as i32, min.1 as i32),
            dims,
            dense: Vec::new(),
            sparse: FxHashMap::default(),
            slots: Vec::new(),
            zs: Vec::new(),
        };
        if dense_ok {
            #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
            let n = (dims.0 * dims.1) as usize;
            t.dense = vec![UNSEEN; n];
        }
        // Every column within the margin of an off-level node, looked up
        // once (the off-level nodes come column by column).
        let mut last = None;
        for &(k, _) in off {
            if last == Some(k) {
                continue;
            }
            last = Some(k);
            for dy in -margin..=margin {
                for dx in -margin..=margin {
                    t.fill((k.0 + dx, k.1 + dy), map, clearance);
                }
            }
        }
        // Off-level nodes are listed column by column: the first of each.
        for (n, &(k, _)) in off.iter().enumerate().rev() {
            if let Some(id) = t.slot(k) {
                #[allow(clippy::cast_possible_truncation)]
                {
                    t.slots[id].2 = n as u32;
                }
            }
        }
        t
    }

    /// Looks column `k` up in `map` unless done already.
    fn fill(&mut self, k: ColumnKey, map: &SurfaceMap, clearance: f32) {
        let Some(i) = self.position(k) else { return };
        let seen = match i {
            Some(i) => self.dense[i] != UNSEEN,
            None => self.sparse.contains_key(&k),
        };
        if seen {
            return;
        }
        let start = self.zs.len();
        if let Some(c) = map.columns.get(&k) {
            self.zs.extend(c.surfaces(clearance));
        }
        let id = if self.zs.len() == start {
            NO_SURFACE
        } else {
            // Counts are bounded by the map's size (below 2^32 columns).
            #[allow(clippy::cast_possible_truncation)]
            let slot = (start as u32, (self.zs.len() - start) as u32, u32::MAX);
            #[allow(clippy::cast_possible_truncation)]
            let id = self.slots.len() as u32;
            self.slots.push(slot);
            id
        };
        match i {
            Some(i) => self.dense[i] = id,
            None => {
                self.sparse.insert(k, id);
            }
        }
    }

    /// Whether column `k` was looked up (lies within the margin of an
    /// off-level node).
    fn covers(&self, k: ColumnKey) -> bool {
        match self.position(k) {
            Some(Some(i)) => self.dense[i] != UNSEEN,
            Some(None) => self.sparse.contains_key(&k),
            None => false,
        }
    }

    /// `Some(Some(dense index))` or `Some(None)` (sparse) for a column in
    /// the box, `None` outside it.
    #[inline]
    fn position(&self, k: ColumnKey) -> Option<Option<usize>> {
        let (x, y) = (
            i64::from(k.0) - i64::from(self.min.0),
            i64::from(k.1) - i64::from(self.min.1),
        );
        if x < 0 || y < 0 || x >= self.dims.0 || y >= self.dims.1 {
            return None;
        }
        if self.dense.is_empty() {
            return Some(None);
        }
        // In the box, whose area fits the dense array.
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        Some(Some((y * self.dims.0 + x) as usize))
    }

    #[inline]
    fn slot(&self, k: ColumnKey) -> Option<usize> {
        let id = match self.position(k)? {
            Some(i) => self.dense[i],
            None => *self.sparse.get(&k)?,
        };
        (id < UNSEEN).then_some(id as usize)
    }

    /// The surfaces of column `k` (none outside the box).
    #[inline]
    fn surfaces(&self, k: ColumnKey) -> &[f32] {
        self.slot(k).map_or(&[], |id| {
            let (start, len, _) = self.slots[id];
            &self.zs[start as usize..(start + len) as usize]
        })
    }

    /// The off-level node of surface `z` of column `k`.
    #[inline]
    fn off_node(&self, off: &[(ColumnKey, f32)], k: ColumnKey, z: f32) -> Option<usize> {
        let first = self.slots[self.slot(k)?].2;
        if first == u32::MAX {
            return None;
        }
        off[first as usize..]
            .iter()
            .take_while(|(c, _)| *c == k)
            .position(|(_, z2)| z2.to_bits() == z.to_bits())
            .map(|n| first as usize + n)
    }
}

/// The surface nodes of the map as the extraction sees them: on a level,
/// or off-level with an index into the off-level node list.
struct Nodes<'a> {
    levels: &'a [f64],
    p: &'a Params,
    off: &'a [(ColumnKey, f32)],
    table: ColumnTable,
}

impl Nodes<'_> {
    /// The surfaces of the columns step-connection looks at from `k`, with
    /// their nodes: in each of the 8 directions the neighbouring column,
    /// or the column two away when the one between holds no surface. One
    /// column lookup per column looked at.
    fn linked(&self, k: ColumnKey) -> impl Iterator<Item = (ColumnKey, f32, Kind)> + '_ {
        DIRS8.into_iter().flat_map(move |(dx, dy)| {
            let near = (k.0 + dx, k.1 + dy);
            let zs = self.table.surfaces(near);
            let (key, zs) = if zs.is_empty() {
                let far = (k.0 + 2 * dx, k.1 + 2 * dy);
                (far, self.table.surfaces(far))
            } else {
                (near, zs)
            };
            zs.iter()
                .filter_map(move |&z| self.kind(key, z).map(|kind| (key, z, kind)))
        })
    }

    /// Whether node `(k, z)` and its neighbour `(n, z2)` (`kind` is the
    /// neighbour's) are step-connected: within a step, or, both off-level
    /// in neighbouring columns, within `column_rise` in the middle of a
    /// flight, where the columns before and after them rise (or descend)
    /// in the same direction by at most a step each. Columns whose treads
    /// are shallower than a column differ by several risers on a steep
    /// stair; a chair seat beside a counter, or a footstool beside a chair,
    /// has flat neighbours and stays a jump. Symmetric in the two nodes.
    fn step_connected(&self, k: ColumnKey, z: f32, n: ColumnKey, z2: f32, kind: Kind) -> bool {
        let p = self.p;
        let jump = z2 - z;
        if jump.abs() <= p.step {
            return true;
        }
        let d = (n.0 - k.0, n.1 - k.1);
        if matches!(kind, Kind::On(_))
            || jump.abs() > p.column_rise
            || d.0.abs() > 1
            || d.1.abs() > 1
        {
            return false;
        }
        let min_rise = 0.5 * p.level_tolerance;
        let rises = |a: f32, b: f32| {
            let r = (b - a) * jump.signum();
            r >= min_rise && r <= p.step
        };
        let before = self.table.surfaces((k.0 - d.0, k.1 - d.1));
        let after = self.table.surfaces((n.0 + d.0, n.1 + d.1));
        before.iter().any(|&zb| rises(zb, z)) && after.iter().any(|&za| rises(z2, za))
    }

    /// The node of the surface in column `k` nearest to the feet height
    /// `z`, within the level tolerance, with the column and the surface's
    /// height; `None` when the column holds no such surface (or lies
    /// outside the table's box: nowhere near an off-level node).
    fn walked_node(
        &mut self,
        map: &SurfaceMap,
        (k, z): (ColumnKey, f32),
    ) -> Option<(Kind, ColumnKey, f32)> {
        self.table.fill(k, map, self.p.clearance);
        let s = nearest_within(self.table.surfaces(k), z, self.p.level_tolerance)?;
        self.kind(k, s).map(|kind| (kind, k, s))
    }

    /// The node of surface `z` of column `k`.
    fn kind(&self, k: ColumnKey, z: f32) -> Option<Kind> {
        match level_of(z, self.levels, self.p.level_tolerance) {
            Some(l) => Some(Kind::On(l)),
            None => self.table.off_node(self.off, k, z).map(Kind::Off),
        }
    }
}

/// Extracts stairs and new levels from `map` given the floor heights of the
/// known levels (index = level id) and the map's off-level columns (up to
/// date for `levels`).
pub(crate) fn extract(
    map: &SurfaceMap,
    off_columns: &mut OffLevelColumns,
    levels: &[f64],
    walked: &[WalkedStep],
    p: &Params,
) -> Extraction {
    let res = map.resolution;
    // 1. Off-level nodes, in column then height order.
    let mut off: Vec<(ColumnKey, f32)> = Vec::new();
    for &k in &off_columns.cols {
        for z in map.surfaces(k, p.clearance) {
            if level_of(z, levels, p.level_tolerance).is_none() {
                off.push((k, z));
            }
        }
    }
    // 3. (below) tests a disk of this radius (columns) around each node.
    let r = p.radius / res;
    // Bounded: radius is at most 200 grid cells (GridConfig) and the
    // surface resolution at least 0.02 m.
    #[allow(clippy::cast_possible_truncation)]
    let ri = r.ceil() as i32;
    let table = ColumnTable::new(map, &off, p.clearance, ri.max(2), GAP_FOOT_COLUMNS);
    off_columns.stale = false;
    if off.is_empty() {
        off_columns.last = Some(table);
        return Extraction::default();
    }
    let mut nodes = Nodes {
        levels,
        p,
        off: &off,
        table,
    };
    // 2. Components and attachments.
    let mut uf = UnionFind::<usize>::new(off.len());
    // (node, level, on-level column, that column's surface height)
    let mut feet: Vec<Foot> = Vec::new();
    for (i, &(k, z)) in off.iter().enumerate() {
        for (n, z2, kind) in nodes.linked(k) {
            if !nodes.step_connected(k, z, n, z2, kind) {
                continue;
            }
            match kind {
                Kind::Off(j) => {
                    uf.union(i, j);
                }
                Kind::On(l) => feet.push((i, l, n, z2)),
            }
        }
    }
    // 2a. Feet the robot walked: a level's surface and an off-level one
    // joined by a move of the robot's feet.
    for w in walked {
        match (nodes.walked_node(map, w.from), nodes.walked_node(map, w.to)) {
            (Some((Kind::On(l), k, zl)), Some((Kind::Off(i), _, _)))
            | (Some((Kind::Off(i), _, _)), Some((Kind::On(l), k, zl))) => {
                feet.push((i, l, k, zl));
            }
            _ => {}
        }
    }
    let mut comps: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for i in 0..off.len() {
        comps.entry(uf.find(i)).or_default().push(i);
    }
    let mut comp_feet: BTreeMap<usize, Vec<Foot>> = BTreeMap::new();
    for f in feet {
        comp_feet.entry(uf.find(f.0)).or_default().push(f);
    }
    // 2a'. Flights seen from their foot across unobserved columns.
    for (root, members) in &comps {
        if !comp_feet.contains_key(root) {
            let found = gap_feet(&mut nodes, map, members);
            if !found.is_empty() {
                comp_feet.insert(*root, found);
            }
        }
    }
    // 2b. How far each attached component's flight is sighted across
    // unobserved columns (only where its own surfaces fall short).
    let mut sighted: FxHashMap<usize, (f32, f32)> = FxHashMap::default();
    for (root, members) in &comps {
        let Some(cf) = comp_feet.get(root) else {
            continue;
        };
        let (lo, hi) = members
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &i| {
                (a.min(off[i].1), b.max(off[i].1))
            });
        let (lowest, highest) = cf
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), f| {
                (a.min(levels[f.1]), b.max(levels[f.1]))
            });
        let up = f64::from(hi) - lowest < p.min_sighting_rise;
        let down = highest - f64::from(lo) < p.min_sighting_rise;
        if up || down {
            let ext = gap_sighting(
                &mut nodes.table,
                map,
                &off,
                members,
                p,
                (lo, hi),
                (up, down),
            );
            sighted.insert(*root, ext);
        }
    }
    // 3. Walkable nodes (footprint supported).
    let disk: Vec<(i32, i32)> = (-ri..=ri)
        .flat_map(|dy| (-ri..=ri).map(move |dx| (dx, dy)))
        .filter(|&(dx, dy)| f64::from(dx * dx + dy * dy) <= r * r + 1e-9)
        .collect();
    let supported = |k: ColumnKey, z: f32| {
        let mut held = 0;
        for &(dx, dy) in &disk {
            let column = nodes.table.surfaces((k.0 + dx, k.1 + dy));
            if !column.is_empty() {
                if !column.iter().any(|z2| (z2 - z).abs() <= 2.0 * p.step) {
                    return false;
                }
                held += 1;
            }
        }
        2 * held >= disk.len()
    };
    let cell_area = res * res;
    let mut out = Extraction::default();
    for (root, members) in &comps {
        let Some(cf) = comp_feet.get(root) else {
            continue;
        };
        // 3-4. Walkable chain.
        let walk: FxHashMap<(ColumnKey, u32), usize> = members
            .iter()
            .filter(|&&i| supported(off[i].0, off[i].1))
            .map(|&i| ((off[i].0, off[i].1.to_bits()), i))
            .collect();
        let mut zs: Vec<f32> = members.iter().map(|&i| off[i].1).collect();
        zs.sort_unstable_by(f32::total_cmp);
        // 5. New levels: flat walkable areas far from every floor (the
        // tops of walls seen from below, a network of lines a column or
        // two wide at the ceiling's height, are never walkable).
        let mut flat: Vec<f32> = walk.values().map(|&i| off[i].1).collect();
        flat.sort_unstable_by(f32::total_cmp);
        let mut a = 0;
        for b in 0..flat.len() {
            while flat[b] - flat[a] > 2.0 * p.level_tolerance {
                a += 1;
            }
            let count = b - a + 1;
            if count as f64 * cell_area >= p.min_level_area {
                let h = f64::from(flat[(a + b) / 2]);
                let far = levels.iter().enumerate().all(|(l, z)| {
                    let gap = if l == 0 && !p.first_level_established {
                        p.min_stair_rise
                    } else {
                        p.min_level_separation
                    };
                    (z - h).abs() >= gap
                }) && out
                    .new_levels
                    .iter()
                    .all(|l| (l - h).abs() >= p.min_level_separation);
                if far {
                    out.new_levels.push(h);
                }
            }
        }
        if walk.is_empty() {
            continue;
        }
        let mut attached: Vec<usize> = cf.iter().map(|f| f.1).collect();
        attached.sort_unstable();
        attached.dedup();
        attached.sort_by(|&a, &b| levels[a].total_cmp(&levels[b]));
        // One stair per pair of levels adjacent in height (a stairwell
        // can join several floors); where the pair is not joined by a
        // walkable chain, a partly seen stair from each side; and the
        // partly seen continuations below the lowest and above the
        // highest level.
        // How far the component's surfaces (walkable or not) reach above
        // and below: a flight seen from the side shows few walkable treads
        // but many step-connected ones.
        let (lo, hi) = zs
            .first()
            .zip(zs.last())
            .map_or((0.0, 0.0), |(a, b)| (f64::from(*a), f64::from(*b)));
        let (lo, hi) = sighted.get(root).map_or((lo, hi), |&(l, h)| {
            (lo.min(f64::from(l)), hi.max(f64::from(h)))
        });
        let depth = edge_depth(&off, &walk, &nodes);
        let run = |start: usize, goal: Option<usize>, dir: f32| {
            let reach = if dir > 0.0 {
                hi - levels[start]
            } else {
                levels[start] - lo
            };
            let min_rise = if reach >= p.min_sighting_rise {
                // Sighted: any walkable tread above the level's tolerance.
                f64::from(p.level_tolerance)
            } else {
                p.min_stair_rise
            };
            chain(
                &off, &walk, &depth, &nodes, cf, levels, start, goal, dir, map, min_rise,
            )
        };
        for w in attached.windows(2) {
            match run(w[0], Some(w[1]), 1.0) {
                Some(stair) => out.stairs.push(stair),
                None => out.stairs.extend(
                    [run(w[0], None, 1.0), run(w[1], None, -1.0)]
                        .into_iter()
                        .flatten(),
                ),
            }
        }
        let (lowest, highest) = (attached[0], attached[attached.len() - 1]);
        out.stairs.extend(
            [run(lowest, None, -1.0), run(highest, None, 1.0)]
                .into_iter()
                .flatten(),
        );
    }
    off_columns.last = Some(nodes.table);
    out.stairs.sort_by(|a, b| {
        (a.lower.position.x, a.lower.position.y, a.lower.position.z)
            .partial_cmp(&(b.lower.position.x, b.lower.position.y, b.lower.position.z))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    out
}

/// Steepest rise per metre (45°) of a flight sighted across unobserved
/// columns.
const GAP_SLOPE: f32 = 1.0;
/// Farthest (m) a flight's continuation is looked for across unobserved
/// columns.
const GAP_REACH_M: f64 = 2.0;
/// At most this many nodes per component and direction start the
/// sighting: its highest (lowest) treads that border unobserved columns.
const GAP_SOURCES: usize = 16;

/// The lowest and highest surfaces that the flight of one component
/// (`members`, whose own surfaces span `(lo, hi)`) reaches across
/// unobserved columns, looking up and/or down as `dirs` says.
///
/// A flight seen from its foot shows its first treads; the treads beyond
/// them are hidden by their own risers (from a camera at knee height) and
/// the turn of a winding stair, while parts of the flight further on, seen
/// from elsewhere, are separate components. From a tread at the
/// component's top (bottom) that borders a column without surfaces, a
/// surface of another off-level node within [`GAP_REACH_M`] counts as the
/// same flight when every column on the straight line between them holds
/// no surface (nothing seen there) and it rises (descends) at most
/// [`GAP_SLOPE`] per metre plus a step. The result only decides whether the
/// component is a *sighted* flight whose highest walkable tread is an open
/// end: standing there shows whether it is one. Furniture beside a low
/// attached surface is rarely behind unobserved columns only, and a visit
/// resolves it (the columns between get observed).
///
/// Every column it reads is looked up in `table`, so that the skip of
/// unchanged extractions notices when they change.
///
/// # Complexity
/// O(s (g + n) + s c g) for s ≤ [`GAP_SOURCES`] sources per direction, g
/// = the reach in columns, n off-level nodes within it and c candidates
/// that would extend the reach (each checks a line of ≤ g columns);
/// O(log N) per column row for the N off-level nodes.
fn gap_sighting(
    table: &mut ColumnTable,
    map: &SurfaceMap,
    off: &[(ColumnKey, f32)],
    members: &[usize],
    p: &Params,
    (lo, hi): (f32, f32),
    (up, down): (bool, bool),
) -> (f32, f32) {
    let res = map.resolution;
    // The reach in columns is small: at most 2 m at ≥ 0.02 m columns.
    #[allow(clippy::cast_possible_truncation)]
    let g = (GAP_REACH_M / res).ceil() as i32;
    let empty = |t: &mut ColumnTable, k: ColumnKey| {
        t.fill(k, map, p.clearance);
        t.surfaces(k).is_empty()
    };
    let mut out = (lo, hi);
    for (dir, wanted) in [(1.0_f32, up), (-1.0, down)] {
        if !wanted {
            continue;
        }
        let edge = if dir > 0.0 { hi } else { lo };
        let mut sources: Vec<(ColumnKey, f32)> = members
            .iter()
            .map(|&i| off[i])
            .filter(|&(_, z)| (edge - z) * dir <= p.step)
            .filter(|&(k, _)| {
                DIRS8
                    .into_iter()
                    .any(|(dx, dy)| empty(table, (k.0 + dx, k.1 + dy)))
            })
            .collect();
        sources.sort_by(|a, b| (b.1 * dir).total_cmp(&(a.1 * dir)).then(a.0.cmp(&b.0)));
        sources.truncate(GAP_SOURCES);
        let mut best = edge;
        for (k, z) in sources {
            for dx in -g..=g {
                let x = k.0 + dx;
                let a = off.partition_point(|c| c.0 < (x, k.1 - g));
                let b = off.partition_point(|c| c.0 <= (x, k.1 + g));
                for &(k2, z2) in &off[a..b] {
                    let rise = (z2 - z) * dir;
                    if (z2 - best) * dir <= 0.0 || rise <= 0.0 {
                        continue;
                    }
                    let (ddx, ddy) = (k2.0 - k.0, k2.1 - k.1);
                    let n = ddx.abs().max(ddy.abs());
                    let d = res * f64::from(ddx * ddx + ddy * ddy).sqrt();
                    #[allow(clippy::cast_possible_truncation)]
                    let max_rise = GAP_SLOPE * d as f32 + p.step;
                    if n < 2 || d > GAP_REACH_M || rise > max_rise {
                        continue;
                    }
                    let unseen_between = (1..n).all(|t| {
                        let f = f64::from(t) / f64::from(n);
                        // Between two columns: rounding stays in i32.
                        #[allow(clippy::cast_possible_truncation)]
                        let c = (
                            k.0 + (f64::from(ddx) * f).round() as i32,
                            k.1 + (f64::from(ddy) * f).round() as i32,
                        );
                        empty(table, c)
                    });
                    if unseen_between {
                        best = z2;
                    }
                }
            }
        }
        if dir > 0.0 {
            out.1 = best;
        } else {
            out.0 = best;
        }
    }
    out
}

/// Farthest (columns) from a level's floor that a flight's first tread is
/// looked for across unobserved columns ([`gap_feet`]).
const GAP_FOOT_COLUMNS: i32 = 3;

/// The feet of an unattached component (`members`) that is a flight seen
/// from its foot: its own surfaces rise (descend) at least
/// `min_stair_rise` beyond a level (as a partly seen stair must), and one of its nodes within the
/// largest column rise of that level's floor faces, in one of the 8
/// directions, a surface on the level at most [`GAP_FOOT_COLUMNS`]
/// columns away with only columns without surfaces between. From the
/// floor beside a flight, a camera at the robot's height sees the treads
/// rising away but often not the first one or two, whose tops lie at a
/// grazing angle (and, on a winding flight, behind the wall of its turn);
/// a column between a floor and a furniture top is rarely unobserved
/// while the furniture also rises as far as a flight.
///
/// Every column it reads is looked up in the table (see [`gap_sighting`]).
///
/// # Complexity
/// O(m) for the m members, plus O(8 [`GAP_FOOT_COLUMNS`]) column lookups
/// for each member near a level.
fn gap_feet(nodes: &mut Nodes<'_>, map: &SurfaceMap, members: &[usize]) -> Vec<Foot> {
    let (p, off, levels) = (nodes.p, nodes.off, nodes.levels);
    let (lo, hi) = members
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &i| {
            (a.min(off[i].1), b.max(off[i].1))
        });
    let mut out = Vec::new();
    for &i in members {
        let (k, z) = off[i];
        for (l, &h) in levels.iter().enumerate() {
            // The flight rises away from level l (dir +1) or descends
            // from it (-1).
            let dir = if f64::from(z) > h { 1.0 } else { -1.0 };
            let above = (f64::from(z) - h) * dir;
            let reach = if dir > 0.0 {
                f64::from(hi) - h
            } else {
                h - f64::from(lo)
            };
            if above > f64::from(p.column_rise) || reach < p.min_stair_rise {
                continue;
            }
            for (dx, dy) in DIRS8 {
                for n in 2..=GAP_FOOT_COLUMNS {
                    let c = (k.0 + n * dx, k.1 + n * dy);
                    let between_unseen = (1..n).all(|t| {
                        let b = (k.0 + t * dx, k.1 + t * dy);
                        nodes.table.fill(b, map, p.clearance);
                        nodes.table.surfaces(b).is_empty()
                    });
                    if !between_unseen {
                        break;
                    }
                    nodes.table.fill(c, map, p.clearance);
                    let on = nodes.table.surfaces(c).iter().copied().find(|&zc| {
                        level_of(zc, levels, p.level_tolerance) == Some(l)
                            && (z - zc).abs() <= p.column_rise
                    });
                    if let Some(zc) = on {
                        if climbs_on(nodes, map, k, z, (-dx, -dy), dir as f32) {
                            out.push((i, l, c, zc));
                        }
                        break;
                    }
                }
            }
        }
    }
    out
}

/// The surface of `zs` nearest to `z` within `tolerance`.
fn nearest_within(zs: &[f32], z: f32, tolerance: f32) -> Option<f32> {
    zs.iter()
        .copied()
        .filter(|s| (s - z).abs() <= tolerance)
        .min_by(|a, b| (a - z).abs().total_cmp(&(b - z).abs()))
}

/// Treads a flight must climb beyond its foot, walking away from the
/// floor, to be attached across unobserved columns ([`climbs_on`]).
const GAP_FOOT_TREADS: usize = 2;

/// Whether walking from surface `z` of column `k` in direction `away`
/// (away from the floor) over at most 2 [`GAP_FOOT_COLUMNS`] + 2
/// columns, from each surface to the next column's surface within a step
/// of it, the height changes in direction `dir` (+1 up) by more than the
/// level tolerance [`GAP_FOOT_TREADS`] times and never back: a flight
/// goes on climbing away from its foot, where a furniture top (a bed's
/// base, a sofa's seat) stays flat or ends.
fn climbs_on(
    nodes: &mut Nodes<'_>,
    map: &SurfaceMap,
    k: ColumnKey,
    z: f32,
    away: (i32, i32),
    dir: f32,
) -> bool {
    let p = nodes.p;
    let (mut z, mut treads) = (z, 0);
    for t in 1..=2 * GAP_FOOT_COLUMNS + 2 {
        let c = (k.0 + t * away.0, k.1 + t * away.1);
        nodes.table.fill(c, map, p.clearance);
        let Some(next) = nearest_within(nodes.table.surfaces(c), z, p.step) else {
            return false;
        };
        let rise = (next - z) * dir;
        if rise < -p.level_tolerance {
            return false;
        }
        if rise > p.level_tolerance {
            treads += 1;
            if treads >= GAP_FOOT_TREADS {
                return true;
            }
        }
        z = next;
    }
    false
}

/// Where a stair meets a level: (off-level node, level, the adjacent
/// on-level column, that column's surface height). The stair's end point is
/// that surface, not the level's nominal floor height: the two differ by up
/// to the level tolerance, and the step from the end to the first tread is
/// only bounded from the real surface.
type Foot = (usize, usize, ColumnKey, f32);

fn point(map: &SurfaceMap, k: ColumnKey, z: f64) -> Point3<f64> {
    let (x, y) = map.center(k);
    Point3::new(x, y, z)
}

/// Walkable nodes this many columns or more from the edge of a flight's
/// walkable part cost nothing extra to cross; nearer ones cost
/// [`EDGE_COST_M`] per column short of it.
const EDGE_DEPTH: u8 = 3;
/// Extra path cost (m) per column a walkable node lies nearer than
/// [`EDGE_DEPTH`] to the edge of its flight's walkable part.
const EDGE_COST_M: f64 = 0.15;

/// The walkable neighbours of walkable node `i`: step-connected, in the
/// 8 directions (or two columns away across a column without surfaces),
/// and the number of directions they come from.
fn walkable_neighbours(
    off: &[(ColumnKey, f32)],
    walk: &FxHashMap<(ColumnKey, u32), usize>,
    nodes: &Nodes<'_>,
    i: usize,
) -> (Vec<usize>, usize) {
    let (k, z) = off[i];
    let mut out = Vec::new();
    let mut dirs = BTreeSet::new();
    for (n, z2, kind) in nodes.linked(k) {
        if let Kind::Off(j) = kind
            && walk.contains_key(&(n, z2.to_bits()))
            && nodes.step_connected(k, z, n, z2, kind)
        {
            out.push(j);
            dirs.insert(((n.0 - k.0).signum(), (n.1 - k.1).signum()));
        }
    }
    (out, dirs.len())
}

/// How many columns each walkable node of a component lies from the edge
/// of the walkable part (0: a neighbour in some direction is not a
/// walkable tread of the flight — a wall, a railing, the floor at its
/// ends), up to [`EDGE_DEPTH`]; nodes deeper are left out. A path along
/// a flight pays [`edge_penalty`] for hugging its edge: the chain's
/// shortest path otherwise runs along the inner edge of every turn and
/// along one side of a straight flight, where the walkable columns end at
/// the robot's radius from the wall at column resolution, so that a
/// robot following it scrapes the wall.
///
/// # Complexity
/// O(W) step-connection tests for the W walkable nodes (a breadth-first
/// search from the edge, stopped at [`EDGE_DEPTH`]).
fn edge_depth(
    off: &[(ColumnKey, f32)],
    walk: &FxHashMap<(ColumnKey, u32), usize>,
    nodes: &Nodes<'_>,
) -> FxHashMap<usize, u8> {
    let mut depth: FxHashMap<usize, u8> = FxHashMap::default();
    let mut queue = std::collections::VecDeque::new();
    let mut ids: Vec<usize> = walk.values().copied().collect();
    ids.sort_unstable();
    for i in ids {
        if walkable_neighbours(off, walk, nodes, i).1 < DIRS8.len() {
            depth.insert(i, 0);
            queue.push_back(i);
        }
    }
    while let Some(i) = queue.pop_front() {
        let d = depth[&i];
        if d + 1 >= EDGE_DEPTH {
            continue;
        }
        for j in walkable_neighbours(off, walk, nodes, i).0 {
            if let std::collections::hash_map::Entry::Vacant(e) = depth.entry(j) {
                e.insert(d + 1);
                queue.push_back(j);
            }
        }
    }
    depth
}

/// The extra cost of crossing walkable node `i` (see [`edge_depth`]).
fn edge_penalty(depth: &FxHashMap<usize, u8>, i: usize) -> f64 {
    depth.get(&i).map_or(0.0, |&d| {
        EDGE_COST_M * f64::from(EDGE_DEPTH.saturating_sub(d))
    })
}

/// Dijkstra over the walkable nodes of one component from the feet on
/// `start` to the feet on `goal` (`None` when they are not joined), or,
/// without a goal level, to the node farthest from `start` in the
/// direction `dir` (+1 up, -1 down) when it rises at least `min_rise`.
#[allow(clippy::too_many_arguments)]
fn chain(
    off: &[(ColumnKey, f32)],
    walk: &FxHashMap<(ColumnKey, u32), usize>,
    depth: &FxHashMap<usize, u8>,
    nodes: &Nodes<'_>,
    feet: &[Foot],
    levels: &[f64],
    start: usize,
    goal: Option<usize>,
    dir: f32,
    map: &SurfaceMap,
    min_rise: f64,
) -> Option<Stair> {
    let node_point = |i: usize| point(map, off[i].0, f64::from(off[i].1));
    // Dijkstra state keyed by node index.
    let mut dist: FxHashMap<usize, f64> = FxHashMap::default();
    // parent: Ok(node) or Err(level column the chain starts from)
    let mut parent: FxHashMap<usize, Result<usize, (ColumnKey, f32)>> = FxHashMap::default();
    let mut heap = BinaryHeap::new();
    let key = |d: f64| Reverse(ordered(d));
    let hs = levels[start];
    // A foot need not be walkable itself: at column resolution the first
    // tread beside a door's jambs fails the footprint test though the
    // robot crosses it in one step (the chain's inner nodes are walkable).
    for &(i, l, col, zf) in feet {
        if l != start {
            continue;
        }
        let d = (node_point(i) - point(map, col, f64::from(zf))).norm();
        if dist.get(&i).is_none_or(|&old| d < old) {
            dist.insert(i, d);
            parent.insert(i, Err((col, zf)));
            heap.push((key(d), i));
        }
    }
    let goal_feet: FxHashMap<usize, (ColumnKey, f32)> = goal
        .map(|g| {
            feet.iter()
                .filter(|f| f.1 == g)
                .map(|f| (f.0, (f.2, f.3)))
                .collect()
        })
        .unwrap_or_default();
    let mut best_end: Option<(usize, f64)> = None;
    let mut reached_goal: Option<(usize, (ColumnKey, f32))> = None;
    let mut done: FxHashMap<usize, ()> = FxHashMap::default();
    while let Some((Reverse(d), i)) = heap.pop() {
        let d = d.0;
        if done.insert(i, ()).is_some() {
            continue;
        }
        if let Some(&col) = goal_feet.get(&i) {
            reached_goal = Some((i, col));
            break;
        }
        let rise = (f64::from(off[i].1) - hs) * f64::from(dir);
        let walkable = walk.contains_key(&(off[i].0, off[i].1.to_bits()));
        if !walkable {
            // an unwalkable start foot: only its walkable neighbours go on
            debug_assert!(parent.get(&i).is_some_and(Result::is_err));
        }
        if rise > 0.0
            && walkable
            && best_end
                .is_none_or(|(b, _)| rise > (f64::from(off[b].1) - hs) * f64::from(dir) + 1e-6)
        {
            best_end = Some((i, d));
        }
        let (k, z) = off[i];
        for (n, z2, kind) in nodes.linked(k) {
            let Kind::Off(j) = kind else { continue };
            if !nodes.step_connected(k, z, n, z2, kind)
                || !(walk.contains_key(&(n, z2.to_bits())) || goal_feet.contains_key(&j))
            {
                continue;
            }
            let nd = d + (node_point(j) - node_point(i)).norm() + edge_penalty(depth, j);
            if dist.get(&j).is_none_or(|&old| nd < old) {
                dist.insert(j, nd);
                parent.insert(j, Ok(i));
                heap.push((key(nd), j));
            }
        }
    }
    let (end, end_col) = match (reached_goal, goal) {
        (Some((i, col)), Some(_)) => (i, Some(col)),
        (None, Some(_)) => return None,
        _ => {
            let (i, _) = best_end?;
            if (f64::from(off[i].1) - hs).abs() < min_rise {
                return None;
            }
            (i, None)
        }
    };
    // Reconstruct.
    let mut rev = Vec::new();
    if let Some((col, zf)) = end_col {
        rev.push(point(map, col, f64::from(zf)));
    }
    let mut i = end;
    let start_col = loop {
        rev.push(node_point(i));
        match parent.get(&i) {
            Some(Ok(j)) => i = *j,
            Some(Err(col)) => break *col,
            None => return None,
        }
    };
    rev.push(point(map, start_col.0, f64::from(start_col.1)));
    rev.reverse();
    let length = rev.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let mut columns: Vec<(ColumnKey, f32)> =
        walk.keys().map(|(k, z)| (*k, f32::from_bits(*z))).collect();
    columns.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let first = rev[0];
    let last = *rev.last()?;
    let start_end = StairEnd {
        level: Some(LevelId(u16::try_from(start).ok()?)),
        position: first,
    };
    let far_end = StairEnd {
        level: match goal {
            Some(g) if end_col.is_some() => Some(LevelId(u16::try_from(g).ok()?)),
            _ => None,
        },
        position: last,
    };
    let (lower, upper, path) = if last.z >= first.z {
        (start_end, far_end, rev)
    } else {
        let mut path = rev;
        path.reverse();
        (far_end, start_end, path)
    };
    Some(Stair {
        lower,
        upper,
        path,
        length,
        columns,
    })
}

/// Total order on finite path lengths for the heap.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Ordered(f64);
impl PartialOrd for Ordered {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Eq for Ordered {}
impl Ord for Ordered {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}
fn ordered(d: f64) -> Ordered {
    Ordered(d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn params() -> Params {
        Params {
            step: 0.2,
            column_rise: 0.35,
            clearance: 0.88,
            radius: 0.18,
            level_tolerance: 0.1,
            min_level_separation: 1.5,
            min_level_area: 2.0,
            min_stair_rise: 0.5,
            min_sighting_rise: 0.8,
            first_level_established: true,
        }
    }

    /// The stairs extracted from one scan of `points` seen from `eye` (a
    /// 0.1 m surface map, a single level at 0).
    fn extract_seen(eye: &Point3<f64>, points: &[Point3<f64>], p: &Params) -> Extraction {
        let mut map = SurfaceMap::new(0.1);
        map.integrate(eye, points, 10.0);
        let mut off = OffLevelColumns::default();
        let touched = map.take_touched();
        off.update(&map, &touched, &[0.0], p);
        extract(&map, &mut off, &[0.0], &[], p)
    }

    proptest! {
        /// Updating the off-level columns from the touched columns after
        /// every batch of returns gives the set a scan of every column
        /// gives, for any returns and any change of the levels.
        #[test]
        fn incremental_off_level_columns_equal_a_full_scan(
            batches in prop::collection::vec(
                prop::collection::vec((0.0f64..3.0, 0.0f64..3.0, -0.2f64..3.0), 1..60),
                1..8,
            ),
            level_change in 0usize..8,
        ) {
            let p = params();
            let mut map = SurfaceMap::new(0.1);
            let mut cached = OffLevelColumns::default();
            let mut levels = vec![0.0];
            for (k, batch) in batches.iter().enumerate() {
                if k == level_change {
                    levels.push(1.3);
                }
                let points: Vec<Point3<f64>> =
                    batch.iter().map(|&(x, y, z)| Point3::new(x, y, z)).collect();
                map.integrate(&Point3::new(1.5, 1.5, 4.0), &points, 10.0);
                let touched = map.take_touched();
                cached.update(&map, &touched, &levels, &p);
                let mut full = OffLevelColumns::default();
                full.update(&map, &[], &levels, &p);
                prop_assert_eq!(&cached.cols, &full.cols);
            }
        }
    }

    /// A flight seen from its side: every tread's top on a 0.2 m strip
    /// along its near edge, the floor under the flight elsewhere past its
    /// first two treads (what a camera beside an open flight sees). Only
    /// the first two treads are walkable (0.36 m, under `min_stair_rise`);
    /// with eight treads the step-connected strip reaches 1.44 m, a
    /// sighted flight whose open end is the second tread; with four (0.72
    /// m, under `min_sighting_rise`) it is not a stair.
    #[test]
    fn a_flight_seen_from_its_side_is_sighted() {
        let p = params();
        let side_view = |treads: usize| {
            let mut points = Vec::new();
            for kx in 0..30 {
                for ky in 0..50 {
                    let (x, y) = (f64::from(kx) * 0.1 + 0.05, f64::from(ky) * 0.1 + 0.05);
                    let tread = if (1.0..1.0 + 0.25 * treads as f64).contains(&y) {
                        Some(((y - 1.0) / 0.25).floor() as usize + 1)
                    } else {
                        None
                    };
                    let z = match tread {
                        Some(i) if (1.0..2.0).contains(&x) && (x < 1.2 || i <= 2) => {
                            0.18 * i as f64
                        }
                        _ => 0.0,
                    };
                    points.push(Point3::new(x, y, z));
                }
            }
            extract_seen(&Point3::new(1.5, 2.5, 6.0), &points, &p)
        };
        let found = side_view(8);
        assert_eq!(found.stairs.len(), 1, "{:?}", found.stairs);
        let s = &found.stairs[0];
        assert_eq!(s.lower.level, Some(LevelId(0)));
        let open = s.open_end().expect("a partly seen stair");
        assert!((open.position.z - 0.36).abs() < 1e-4, "{:?}", open.position);
        assert!(side_view(4).stairs.is_empty());
    }

    /// A steep stair (0.107 m risers, 0.086 m treads: shallower than a
    /// column, after a first tread a column deep) sampled finely: neighbouring columns differ by up to three
    /// risers, more than a step, yet the whole flight is one stair with
    /// `max_stair_column_rise`; with the step height alone the chain breaks
    /// at the first double riser.
    #[test]
    fn a_steep_stair_with_treads_shallower_than_a_column_is_one_stair() {
        let open_end = |column_rise: f32| {
            let p = Params {
                column_rise,
                ..params()
            };
            let mut points = Vec::new();
            for kx in 0..30 {
                for ky in 0..175 {
                    let (x, y) = (f64::from(kx) * 0.1 + 0.05, f64::from(ky) * 0.02 + 0.01);
                    // a first tread a column deep (a foot needs a column
                    // within a step of the floor), then steep treads
                    let z = if (1.0..2.0).contains(&x) && y >= 1.2 {
                        (((y - 1.2) / 0.086).floor() + 2.0).min(20.0) * 0.107
                    } else if (1.0..2.0).contains(&x) && y >= 1.0 {
                        0.107
                    } else {
                        0.0
                    };
                    points.push(Point3::new(x, y, z));
                }
            }
            let found = extract_seen(&Point3::new(1.5, 0.5, 6.0), &points, &p);
            found
                .stairs
                .iter()
                .filter_map(|s| s.open_end().map(|e| e.position.z))
                .fold(0.0, f64::max)
        };
        assert!((open_end(0.35) - 2.14).abs() < 1e-4, "{}", open_end(0.35));
        assert!(open_end(0.2) < 1.0, "{}", open_end(0.2));
    }

    /// A winding stair entered through a door (the trace of a Sweet Home
    /// 3D home): its 0.11 m first tread shows only in the two columns
    /// at the winders' narrow end, beside a jamb, and the columns beside
    /// them hold two risers (0.22 m, more than a step from the floor). The
    /// first tread fails the footprint test, yet the stair starts there:
    /// a foot need not be walkable, the nodes after it must.
    #[test]
    fn a_stair_entered_beside_a_door_jamb_starts_at_its_first_tread() {
        let p = params();
        let mut points = Vec::new();
        for kx in 5..22 {
            for ky in 0..20 {
                let (x, y) = (f64::from(kx) * 0.1 + 0.05, f64::from(ky) * 0.1 + 0.05);
                let z = if ky < 10 {
                    // the floor, and a jamb beside the first tread
                    if (kx, ky) == (10, 9) { 2.09 } else { 0.0 }
                } else if kx == 9 || kx == 17 {
                    2.5 // the stairwell's walls
                } else if (10..17).contains(&kx) {
                    let riser = f64::from(ky - 9);
                    0.11 * (riser + if ky == 10 && kx >= 12 { 1.0 } else { 0.0 })
                } else {
                    continue;
                };
                points.push(Point3::new(x, y, z));
            }
        }
        let found = extract_seen(&Point3::new(1.3, 0.5, 6.0), &points, &p);
        assert_eq!(found.stairs.len(), 1, "{:?}", found.stairs);
        let s = &found.stairs[0];
        assert_eq!(s.lower.level, Some(LevelId(0)));
        // level end on the floor in front of the first tread, then the
        // first tread (0.11 m), then the flight up to its top (1.1 m)
        assert!(s.lower.position.z.abs() < 1e-6 && s.lower.position.y < 1.0);
        assert!((s.path[1].z - 0.11).abs() < 1e-4, "{:?}", s.path);
        let open = s.open_end().expect("a partly seen stair");
        assert!((open.position.z - 1.1).abs() < 1e-4, "{:?}", open.position);
    }

    /// A flight seen from its foot (the trace of a Sweet Home 3D basement):
    /// a camera at knee height sees the first two treads (0.11 and 0.22 m),
    /// not the treads behind their risers; the flight further on (two
    /// treads 0.7 m away, seen from elsewhere) is a separate component.
    /// Across the unobserved columns between them it is a sighted flight,
    /// whose open end is the second tread. When the columns between were
    /// seen (floor, say), or the far surface is steeper than a stair, it is
    /// not.
    #[test]
    fn a_flight_seen_from_its_foot_is_sighted_across_unobserved_columns() {
        let p = params();
        let foot_view = |gap: Option<f64>, far: f64| {
            let mut points = Vec::new();
            for kx in 5..22 {
                for ky in 0..20 {
                    let (x, y) = (f64::from(kx) * 0.1 + 0.05, f64::from(ky) * 0.1 + 0.05);
                    let z = if ky < 10 {
                        0.0
                    } else if kx == 9 || kx == 17 {
                        2.5 // the stairwell's walls
                    } else if !(10..17).contains(&kx) {
                        continue;
                    } else if ky < 12 {
                        0.11 * f64::from(ky - 9)
                    } else if ky < 17 {
                        match gap {
                            Some(z) => z,
                            None => continue,
                        }
                    } else if ky < 19 {
                        far + 0.11 * f64::from(ky - 17)
                    } else {
                        continue;
                    };
                    points.push(Point3::new(x, y, z));
                }
            }
            extract_seen(&Point3::new(1.3, 0.5, 6.0), &points, &p).stairs
        };
        let stairs = foot_view(None, 0.88);
        assert_eq!(stairs.len(), 1, "{stairs:?}");
        assert_eq!(stairs[0].lower.level, Some(LevelId(0)));
        let open = stairs[0].open_end().expect("a partly seen stair");
        assert!((open.position.z - 0.22).abs() < 1e-4, "{:?}", open.position);
        assert!(open.position.y > 1.1 && open.position.y < 1.2, "{open:?}");
        // the columns between seen: a low step, then a table
        assert!(foot_view(Some(0.0), 0.88).is_empty());
        // steeper than 45° across the gap: a shelf behind a step
        assert!(foot_view(None, 1.6).is_empty());
    }

    /// A straight flight 1 m wide between two walls: its path keeps to the
    /// middle of the walkable treads (every tie of the shortest chain would
    /// otherwise run along one side, where the walkable columns end at the
    /// robot's radius from the wall at column resolution).
    #[test]
    fn a_flight_path_keeps_to_the_middle() {
        let p = params();
        let mut points = Vec::new();
        for kx in 5..25 {
            for ky in 0..40 {
                let (x, y) = (f64::from(kx) * 0.1 + 0.05, f64::from(ky) * 0.1 + 0.05);
                let z = if ky < 10 {
                    0.0
                } else if kx == 9 || kx == 20 {
                    2.5 // the stairwell's walls
                } else if (10..20).contains(&kx) {
                    0.15 * (f64::from(ky - 10) / 2.5).floor() + 0.15
                } else {
                    continue;
                };
                points.push(Point3::new(x, y, z));
            }
        }
        let found = extract_seen(&Point3::new(1.5, 0.5, 6.0), &points, &p);
        assert_eq!(found.stairs.len(), 1, "{:?}", found.stairs);
        let path = &found.stairs[0].path;
        assert!(path.len() > 10, "{path:?}");
        for q in &path[1..path.len() - 1] {
            assert!((1.3..=1.7).contains(&q.x), "{q:?} in {path:?}");
        }
    }

    /// Furniture beside furniture (the trace of a Sweet Home 3D kitchen): a
    /// footstool (0.17 m), a chair seat (0.46 m) and a counter (0.74 m),
    /// each flat and wide, rise by less than `max_stair_column_rise` from
    /// one to the next, but not inside a flight: the columns before and
    /// after each jump are flat. They are not a stair.
    #[test]
    fn furniture_tops_rising_beside_each_other_are_not_a_stair() {
        let p = params();
        let mut points = Vec::new();
        for kx in 0..40 {
            for ky in 0..30 {
                let (x, y) = (f64::from(kx) * 0.1 + 0.05, f64::from(ky) * 0.1 + 0.05);
                let z = if !(1.0..2.0).contains(&y) {
                    0.0
                } else if (1.0..1.5).contains(&x) {
                    0.17
                } else if (1.5..2.0).contains(&x) {
                    0.46
                } else if (2.0..2.5).contains(&x) {
                    0.74
                } else {
                    0.0
                };
                points.push(Point3::new(x, y, z));
            }
        }
        let found = extract_seen(&Point3::new(0.5, 0.5, 6.0), &points, &p);
        assert!(found.stairs.is_empty(), "{:?}", found.stairs);
    }

    /// A straight flight 1 m wide rising 0.11 m per column from the floor
    /// (y < 1) from `first` at its first column, `gap` columns left
    /// unobserved between the floor and that first column (the flight is
    /// moved back by them), up to 1.21 m, seen from above its foot; the
    /// surface map and its off-level columns.
    fn flight_map(first: f64, gap: i32, p: &Params) -> (SurfaceMap, OffLevelColumns) {
        let mut points = Vec::new();
        for kx in 0..30 {
            for ky in 0..(24 + gap) {
                let (x, y) = (f64::from(kx) * 0.1 + 0.05, f64::from(ky) * 0.1 + 0.05);
                let z = if ky < 10 {
                    0.0
                } else if kx == 9 || kx == 20 {
                    2.5 // the stairwell's walls
                } else if !(10..20).contains(&kx) || ky < 10 + gap {
                    continue;
                } else {
                    (first + 0.11 * f64::from(ky - 10 - gap)).min(1.21)
                };
                points.push(Point3::new(x, y, z));
            }
        }
        let mut map = SurfaceMap::new(0.1);
        map.integrate(&Point3::new(1.5, 0.5, 6.0), &points, 10.0);
        let mut off = OffLevelColumns::default();
        let touched = map.take_touched();
        off.update(&map, &touched, &[0.0], p);
        (map, off)
    }

    /// The flight's first column rises 0.22 m from the floor beside it (a
    /// 0.11 m sub-step narrower than a column, the next one's top in the
    /// same column): more than a step, so the flight is not attached to
    /// the floor until the robot has walked from the floor onto it.
    #[test]
    fn a_flight_the_robot_walked_onto_is_attached() {
        let p = params();
        let (map, mut off) = flight_map(0.22, 0, &p);
        assert!(extract(&map, &mut off, &[0.0], &[], &p).stairs.is_empty());
        // walked from the floor (column (15, 8)) onto the first tread
        let walked = [WalkedStep {
            from: ((15, 8), 0.0),
            to: ((15, 10), 0.22),
        }];
        let found = extract(&map, &mut off, &[0.0], &walked, &p);
        assert_eq!(found.stairs.len(), 1, "{:?}", found.stairs);
        let s = &found.stairs[0];
        assert_eq!(s.lower.level, Some(LevelId(0)));
        let open = s.open_end().expect("a partly seen stair");
        assert!(open.position.z > 1.0, "{open:?}");
        // a step somewhere else (between two floor columns, or onto a
        // column without an off-level surface at that height) attaches
        // nothing
        for w in [
            WalkedStep {
                from: ((5, 5), 0.0),
                to: ((5, 7), 0.0),
            },
            WalkedStep {
                from: ((15, 8), 0.0),
                to: ((15, 10), 0.6),
            },
        ] {
            assert!(extract(&map, &mut off, &[0.0], &[w], &p).stairs.is_empty());
        }
    }

    /// Seen from its foot, a flight's first one or two treads may lie at a
    /// grazing angle and stay unobserved: a flight that rises far enough
    /// and starts within the largest column rise of the floor, across at
    /// most [`GAP_FOOT_COLUMNS`] unobserved columns, is attached; a
    /// furniture top as high does not rise as a flight and is not, nor is
    /// a flight farther away than that.
    #[test]
    fn a_flight_seen_across_unobserved_columns_at_its_foot_is_attached() {
        let p = params();
        for gap in [1, 2] {
            let (map, mut off) = flight_map(0.22, gap, &p);
            let found = extract(&map, &mut off, &[0.0], &[], &p);
            assert_eq!(found.stairs.len(), 1, "gap {gap}: {:?}", found.stairs);
            assert_eq!(found.stairs[0].lower.level, Some(LevelId(0)));
        }
        // too far from the floor
        let (map, mut off) = flight_map(0.22, 3, &p);
        assert!(extract(&map, &mut off, &[0.0], &[], &p).stairs.is_empty());
        // a flat top 0.3 m high across an unobserved column: no flight
        let mut points = Vec::new();
        for kx in 0..30 {
            for ky in 0..20 {
                let (x, y) = (f64::from(kx) * 0.1 + 0.05, f64::from(ky) * 0.1 + 0.05);
                let z = if ky < 10 {
                    0.0
                } else if ky == 10 || !(10..20).contains(&kx) {
                    continue;
                } else {
                    0.3
                };
                points.push(Point3::new(x, y, z));
            }
        }
        assert!(
            extract_seen(&Point3::new(1.5, 0.5, 6.0), &points, &p)
                .stairs
                .is_empty()
        );
    }
}
