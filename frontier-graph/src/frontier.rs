//! Incremental frontier detection, segmentation and PCA splitting
//! (after FUEL: Zhou et al., "FUEL: Fast UAV Exploration using Incremental
//! Frontier Structure and Hierarchical Planning", RA-L 2021).

use nalgebra::{Point2, Vector2};
use rustc_hash::{FxHashMap, FxHashSet};
use std::collections::BTreeMap;

use crate::grid::{CellState, GridDelta};
use crate::search::DIRS;
use crate::{Cell, FrontierConfig, FrontierId, FrontierNode, OccupancyGrid};

/// 4-neighbourhood (the straight moves) and 8-neighbourhood.
const N4: [(i32, i32); 4] = [DIRS[0], DIRS[1], DIRS[2], DIRS[3]];
const N8: [(i32, i32); 8] = DIRS;

/// The frontier definition: `cell` is traversable and at least one of its
/// 4-neighbours is [`CellState::Unknown`] (cells outside the grid are unknown).
///
/// # Complexity
/// O(1).
pub fn is_frontier_cell(grid: &OccupancyGrid, cell: Cell) -> bool {
    grid.is_traversable(cell)
        && N4
            .iter()
            .any(|&(dx, dy)| grid.state(cell.offset(dx, dy)) == CellState::Unknown)
}

/// Whether the frontier cells `a` and `a + (dx, dy)` (8-neighbours) belong
/// to one segment: a straight neighbour always; a diagonal one when either
/// side cell is traversable, so that the robot walks from one to the other
/// in two straight moves. Two frontier cells that touch only at a corner
/// between a non-traversable cell and an unknown one (the jamb of a doorway
/// seen from both sides, say) lie on different sides of the gap and may be
/// in different traversable components: one segment over both could have its
/// viewpoint on the side the robot cannot reach, and the reachable half
/// would never be explored. Every segment therefore lies in one
/// 4-connected traversable component.
///
/// # Complexity
/// O(1).
fn linked(grid: &OccupancyGrid, a: Cell, dx: i32, dy: i32) -> bool {
    dx == 0
        || dy == 0
        || grid.is_traversable(a.offset(dx, 0))
        || grid.is_traversable(a.offset(0, dy))
}

/// Node ids created and removed by one frontier update.
#[derive(Debug, Default, Clone)]
pub(crate) struct FrontierChanges {
    pub added: Vec<FrontierId>,
    pub removed: Vec<FrontierId>,
}

/// Maintains frontier flags, segments and nodes.
pub(crate) struct Detector<'a> {
    pub grid: &'a mut OccupancyGrid,
    pub nodes: &'a mut BTreeMap<FrontierId, FrontierNode>,
    pub next_id: &'a mut u64,
    pub cfg: &'a FrontierConfig,
}

impl Detector<'_> {
    /// Updates the frontier structure after a grid change (FUEL-style: only
    /// cells whose frontier status can have changed are re-tested, and only the
    /// connected components touching them are re-segmented; untouched segments
    /// keep their ids).
    ///
    /// # Complexity
    /// O(D + A log A) for D re-tested cells and A cells in affected components.
    pub fn update(&mut self, delta: &GridDelta) -> FrontierChanges {
        let mut dirty: FxHashSet<Cell> = FxHashSet::default();
        for &c in &delta.state_changed {
            dirty.insert(c);
            for (dx, dy) in N4 {
                dirty.insert(c.offset(dx, dy));
            }
        }
        dirty.extend(delta.gained.iter().copied());
        dirty.extend(delta.lost.iter().copied());
        let mut dirty: Vec<Cell> = dirty.into_iter().collect();
        dirty.sort_unstable();
        // A cell whose traversability changed can link or unlink the
        // diagonal frontier cells around it (see `linked`): their segments
        // are re-segmented even when no frontier flag changes.
        let mut relink: Vec<Cell> = delta
            .gained
            .iter()
            .chain(&delta.lost)
            .flat_map(|c| N8.iter().map(move |&(dx, dy)| c.offset(dx, dy)))
            .collect();
        relink.sort_unstable();
        relink.dedup();
        self.retest_with(&dirty, &relink, FxHashMap::default(), Vec::new())
    }

    /// Recomputes everything from scratch (fresh ids for all segments that
    /// are not identical to a previous one).
    ///
    /// # Complexity
    /// O(N + F log F) for N grid cells and F frontier cells.
    pub fn rebuild(&mut self) -> FrontierChanges {
        // Only traversable cells can be frontier cells: clear every flag and
        // re-test those.
        self.grid.frontier.iter_mut().for_each(|f| *f = false);
        let cells: Vec<Cell> = (0..self.grid.cell_count())
            .filter(|&i| self.grid.trav_at(i))
            .map(|i| self.grid.cell_at(i))
            .collect();
        let mut stash = FxHashMap::default();
        let mut removed = Vec::new();
        for (id, node) in std::mem::take(self.nodes) {
            for c in &node.cells {
                if let Some(i) = self.grid.index(*c) {
                    self.grid.segment[i] = 0;
                }
            }
            removed.push(id);
            stash.insert(node.cells, id);
        }
        let mut ch = self.retest_with(&cells, &[], stash, removed);
        ch.added.sort_unstable();
        ch
    }

    /// Re-tests the frontier flags of `dirty` and re-segments every
    /// component touching a changed flag or a cell of `relink` (frontier
    /// cells whose links may have changed).
    fn retest_with(
        &mut self,
        dirty: &[Cell],
        relink: &[Cell],
        mut stash: FxHashMap<Vec<Cell>, FrontierId>,
        mut removed: Vec<FrontierId>,
    ) -> FrontierChanges {
        let mut seeds: Vec<Cell> = Vec::new();
        for &c in dirty {
            let Some(i) = self.grid.index(c) else {
                continue;
            };
            let now = is_frontier_cell(self.grid, c);
            if now == self.grid.frontier[i] {
                if now && self.grid.segment[i] == 0 {
                    // Full rebuild: flags already set but unsegmented.
                    seeds.push(c);
                }
                continue;
            }
            self.grid.frontier[i] = now;
            if now {
                seeds.push(c);
            } else {
                let s = self.grid.segment[i];
                if s != 0 {
                    self.dissolve(FrontierId(s), &mut seeds, &mut stash, &mut removed);
                }
                for (dx, dy) in N8 {
                    seeds.push(c.offset(dx, dy));
                }
            }
        }
        for &c in relink {
            let Some(i) = self.grid.index(c) else {
                continue;
            };
            if !self.grid.frontier[i] {
                continue;
            }
            let s = self.grid.segment[i];
            if s != 0 {
                self.dissolve(FrontierId(s), &mut seeds, &mut stash, &mut removed);
            }
            seeds.push(c);
        }
        // Re-segment every component reachable from the seeds.
        let mut visited: FxHashSet<Cell> = FxHashSet::default();
        let mut created: Vec<FrontierId> = Vec::new();
        let mut k = 0;
        while k < seeds.len() {
            let s = seeds[k];
            k += 1;
            if visited.contains(&s) || !self.is_flagged(s) {
                continue;
            }
            let mut comp = vec![s];
            visited.insert(s);
            let mut q = 0;
            while q < comp.len() {
                let c = comp[q];
                q += 1;
                if let Some(i) = self.grid.index(c) {
                    let seg = self.grid.segment[i];
                    if seg != 0 {
                        self.dissolve(FrontierId(seg), &mut seeds, &mut stash, &mut removed);
                    }
                }
                for (dx, dy) in N8 {
                    let n = c.offset(dx, dy);
                    if self.is_flagged(n) && linked(self.grid, c, dx, dy) && visited.insert(n) {
                        comp.push(n);
                    }
                }
            }
            comp.sort_unstable();
            let mut pieces = Vec::new();
            split(
                comp,
                self.grid.resolution(),
                self.cfg.max_extent,
                &mut pieces,
            );
            for cells in pieces {
                if cells.len() < self.cfg.min_cells {
                    continue;
                }
                let id = stash.remove(&cells).unwrap_or_else(|| {
                    *self.next_id += 1;
                    FrontierId(*self.next_id)
                });
                for c in &cells {
                    if let Some(i) = self.grid.index(*c) {
                        self.grid.segment[i] = id.0;
                    }
                }
                let node = make_node(id, cells, self.grid.resolution());
                self.nodes.insert(id, node);
                created.push(id);
            }
        }
        // Ids both dissolved and re-created (identical segments) persist.
        let created_set: FxHashSet<FrontierId> = created.iter().copied().collect();
        let removed_set: FxHashSet<FrontierId> = removed.iter().copied().collect();
        FrontierChanges {
            added: created
                .into_iter()
                .filter(|id| !removed_set.contains(id))
                .collect(),
            removed: removed
                .into_iter()
                .filter(|id| !created_set.contains(id))
                .collect(),
        }
    }

    fn is_flagged(&self, c: Cell) -> bool {
        self.grid.index(c).is_some_and(|i| self.grid.frontier[i])
    }

    fn dissolve(
        &mut self,
        id: FrontierId,
        seeds: &mut Vec<Cell>,
        stash: &mut FxHashMap<Vec<Cell>, FrontierId>,
        removed: &mut Vec<FrontierId>,
    ) {
        let Some(node) = self.nodes.remove(&id) else {
            return;
        };
        for c in &node.cells {
            if let Some(i) = self.grid.index(*c) {
                self.grid.segment[i] = 0;
            }
        }
        seeds.extend(node.cells.iter().copied());
        removed.push(id);
        stash.insert(node.cells, id);
    }
}

/// Mean, unit principal axis (closed-form eigenvector of the 2x2
/// covariance), and projections of cell centres on it.
///
/// # Complexity
/// O(n) for n cells.
fn pca(cells: &[Cell], res: f64) -> (Point2<f64>, Vector2<f64>, Vec<f64>) {
    let n = cells.len() as f64;
    let pts: Vec<Vector2<f64>> = cells
        .iter()
        .map(|c| Vector2::new((f64::from(c.x) + 0.5) * res, (f64::from(c.y) + 0.5) * res))
        .collect();
    let mean = pts.iter().sum::<Vector2<f64>>() / n;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in &pts {
        let d = p - mean;
        sxx += d.x * d.x;
        sxy += d.x * d.y;
        syy += d.y * d.y;
    }
    // Principal eigenvector of the 2x2 covariance in closed form.
    let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let axis = Vector2::new(theta.cos(), theta.sin());
    let proj = pts.iter().map(|p| (p - mean).dot(&axis)).collect();
    (Point2::from(mean), axis, proj)
}

/// Splits `cells` (sorted) in two at the centroid along the principal axis
/// while the extent exceeds `max_extent`.
///
/// # Complexity
/// O(n log(n)) for n cells (each level is linear, halves shrink).
fn split(cells: Vec<Cell>, res: f64, max_extent: f64, out: &mut Vec<Vec<Cell>>) {
    let (_, _, proj) = pca(&cells, res);
    let (lo, hi) = proj
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &p| {
            (a.min(p), b.max(p))
        });
    if cells.len() < 2 || hi - lo + res <= max_extent {
        out.push(cells);
        return;
    }
    let (mut left, mut right) = (Vec::new(), Vec::new());
    for (c, p) in cells.into_iter().zip(proj) {
        if p < 0.0 {
            left.push(c);
        } else {
            right.push(c);
        }
    }
    if left.is_empty() || right.is_empty() {
        // Cannot happen for a positive extent; never loop.
        out.extend([left, right].into_iter().filter(|v| !v.is_empty()));
        return;
    }
    split(left, res, max_extent, out);
    split(right, res, max_extent, out);
}

/// Builds a node: centroid, axis, extent and viewpoint (the cell of the
/// segment closest to the centroid; segment cells are traversable).
///
/// # Complexity
/// O(n) for n cells.
fn make_node(id: FrontierId, cells: Vec<Cell>, res: f64) -> FrontierNode {
    let (centroid, axis, proj) = pca(&cells, res);
    let (lo, hi) = proj
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &p| {
            (a.min(p), b.max(p))
        });
    let center = |c: &Cell| Point2::new((f64::from(c.x) + 0.5) * res, (f64::from(c.y) + 0.5) * res);
    let mut best = cells[0];
    let mut best_d = f64::INFINITY;
    for c in &cells {
        let d = (center(c) - centroid).norm_squared();
        if d < best_d {
            best_d = d;
            best = *c;
        }
    }
    FrontierNode {
        id,
        centroid,
        axis,
        extent: hi - lo + res,
        viewpoint: center(&best),
        viewpoint_cell: best,
        cells,
        level: crate::LevelId(0),
        z: 0.0,
    }
}
