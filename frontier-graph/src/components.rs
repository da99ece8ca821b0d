//! Connected components of the traversable cells, so that a shortest-path
//! search never looks for a target it cannot reach.
//!
//! A search with targets stops when all of them are settled; one target in
//! another component keeps it running until the source's whole component is
//! exhausted (on a 900 m² floor: 10⁵ cells, tens of milliseconds). Labelling
//! the components first makes the test "can the source reach this target"
//! O(1), and the unreachable targets are dropped before the search.
//!
//! Components are 4-connected: a diagonal move needs both straight
//! neighbours traversable (no corner cutting, see [`crate::search`]), so its
//! two ends are also joined through a straight neighbour, and two cells are
//! in one component exactly when a search from one settles the other.

use petgraph::unionfind::UnionFind;

use crate::OccupancyGrid;

/// Component labels of one grid's traversable cells, recomputed lazily when
/// the grid's traversable layer changed.
///
/// Stored as horizontal *runs* (maximal spans of traversable cells in one
/// row) joined by union-find: a run touches the runs of the rows above and
/// below whose column spans overlap it. A map has far fewer runs than
/// cells, so a recomputation costs one pass over the traversable flags plus
/// near-constant work per run, and a lookup is a binary search.
#[derive(Debug, Clone, Default)]
pub(crate) struct Components {
    /// Runs `[start, end)` in dense indices, in row-major order.
    runs: Vec<(u32, u32)>,
    /// Component label (1-based) of each run.
    labels: Vec<u32>,
    /// [`OccupancyGrid::trav_version`] the runs were computed for.
    version: Option<u64>,
}

impl Components {
    /// Brings the labels up to date with `grid` (a no-op when the
    /// traversable layer has not changed since the last call).
    ///
    /// # Complexity
    /// O(N + R α(R)) for N allocated grid cells and R runs when the layer
    /// changed, O(1) otherwise.
    pub(crate) fn refresh(&mut self, grid: &OccupancyGrid) -> &Self {
        if self.version == Some(grid.trav_version()) {
            return self;
        }
        let trav = grid.trav_layer();
        let w = grid.dims().0.max(1);
        self.runs.clear();
        // Runs of the previous row: indices into `self.runs`.
        let mut prev = 0..0;
        let mut links: Vec<(usize, usize)> = Vec::new();
        for (y, row) in trav.chunks(w).enumerate() {
            let first = self.runs.len();
            // Rows are mostly unknown: skip all-false blocks quickly.
            let mut x = 0;
            while x < row.len() {
                if !row[x] {
                    let skip = row[x..].iter().position(|&t| t).unwrap_or(row.len() - x);
                    x += skip;
                    continue;
                }
                let len = row[x..].iter().position(|&t| !t).unwrap_or(row.len() - x);
                // Dense indices fit in u32 (the grid caps width and height at 2^16).
                #[allow(clippy::cast_possible_truncation)]
                self.runs
                    .push(((y * w + x) as u32, (y * w + x + len) as u32));
                x += len;
            }
            // 4-connected overlap with the previous row's runs (two pointers).
            let here = first..self.runs.len();
            let (mut a, mut b) = (prev.start, here.start);
            let col = |v: u32| v as usize % w;
            while a < prev.end && b < here.end {
                let (pa, pb) = (self.runs[a], self.runs[b]);
                let (a0, a1) = (col(pa.0), col(pa.1 - 1));
                let (b0, b1) = (col(pb.0), col(pb.1 - 1));
                if a0 <= b1 && b0 <= a1 {
                    links.push((a, b));
                }
                if a1 < b1 {
                    a += 1;
                } else {
                    b += 1;
                }
            }
            prev = here;
        }
        let mut uf = UnionFind::<usize>::new(self.runs.len());
        for (a, b) in links {
            uf.union(a, b);
        }
        let mut root_label = vec![0u32; self.runs.len()];
        let mut next = 0u32;
        self.labels.clear();
        for r in 0..self.runs.len() {
            let root = uf.find_mut(r);
            if root_label[root] == 0 {
                next += 1;
                root_label[root] = next;
            }
            self.labels.push(root_label[root]);
        }
        self.version = Some(grid.trav_version());
        self
    }

    /// The component of dense index `i` (0 = not traversable or out of
    /// range). Valid after [`refresh`](Self::refresh) on the same grid.
    ///
    /// # Complexity
    /// O(log R) for R runs.
    pub(crate) fn label(&self, i: usize) -> u32 {
        let Ok(i) = u32::try_from(i) else { return 0 };
        let k = self.runs.partition_point(|r| r.0 <= i);
        match k.checked_sub(1) {
            Some(k) if i < self.runs[k].1 => self.labels[k],
            _ => 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::{Scratch, dijkstra};
    use crate::{Cell, GridConfig};
    use nalgebra::Point3;
    use proptest::prelude::*;

    /// A grid whose traversable cells follow `free`: a scan from the centre
    /// of a square room with random pillars (points at the pillar cells).
    fn grid_with_pillars(pillars: &[(i32, i32)]) -> OccupancyGrid {
        let cfg = GridConfig::default();
        let mut g = OccupancyGrid::new(cfg.clone()).expect("grid");
        let res = cfg.resolution;
        let z = cfg.floor_z + 0.5 * cfg.robot_height;
        let origin = Point3::new(0.0, 0.0, z);
        let mut points = Vec::new();
        // Room walls at ±1.5 m seen from the centre.
        for k in 0..720 {
            let a = f64::from(k) * std::f64::consts::PI / 360.0;
            let (c, s) = (a.cos(), a.sin());
            let t = (1.5 / c.abs().max(1e-9)).min(1.5 / s.abs().max(1e-9));
            points.push(Point3::new(t * c, t * s, z));
        }
        for &(x, y) in pillars {
            points.push(Point3::new(f64::from(x) * res, f64::from(y) * res, z));
        }
        g.integrate(&origin, &points).expect("integrate");
        g
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        /// Same component exactly when a search from one cell settles the
        /// other (differential against Dijkstra's reachability).
        #[test]
        fn labels_agree_with_search_reachability(
            pillars in proptest::collection::vec((-28i32..28, -28i32..28), 0..40),
            probes in proptest::collection::vec((-30i32..30, -30i32..30), 1..6),
        ) {
            let g = grid_with_pillars(&pillars);
            let mut comp = Components::default();
            comp.refresh(&g);
            let mut s = Scratch::default();
            let cells: Vec<usize> = probes
                .iter()
                .filter_map(|&(x, y)| g.index(Cell::new(x, y)))
                .filter(|&i| g.trav_at(i))
                .collect();
            for &a in &cells {
                dijkstra(&g, &mut s, &[a], &[]);
                for i in 0..g.cell_count() {
                    let reached = s.settled(i).is_some();
                    let same = g.trav_at(i) && comp.label(i) == comp.label(a);
                    prop_assert_eq!(reached, same, "cell {:?}", g.cell_at(i));
                }
            }
            for i in 0..g.cell_count() {
                prop_assert_eq!(comp.label(i) != 0, g.trav_at(i));
            }
        }
    }

    #[test]
    fn labels_follow_the_grid_version() {
        let mut g = grid_with_pillars(&[]);
        let mut comp = Components::default();
        let before = comp.refresh(&g).runs.len();
        assert!(before > 0);
        // A wall across the room splits it: two components afterwards.
        let cfg = g.config().clone();
        let z = cfg.floor_z + 0.5 * cfg.robot_height;
        let wall: Vec<Point3<f64>> = (-30..=30)
            .map(|y| Point3::new(0.0, f64::from(y) * cfg.resolution, z))
            .collect();
        g.integrate(&Point3::new(-0.5, 0.0, z), &wall)
            .expect("integrate");
        g.integrate(&Point3::new(0.5, 0.0, z), &wall)
            .expect("integrate");
        comp.refresh(&g);
        let labels: std::collections::BTreeSet<u32> = comp.labels.iter().copied().collect();
        assert!(labels.len() >= 2, "the wall splits the room: {labels:?}");
    }
}
