//! Occupancy / traversability grid: clamped log-odds, 2D ray carving and
//! incremental inflation by the robot radius.

use nalgebra::{Point2, Point3};
use std::collections::BTreeSet;

use serde::{Deserialize, Serialize};

use crate::cell::{cell_center, cell_of, scaled_cell_of};
use crate::raycast::{Ray, RayOrigin, traverse};
use crate::{Cell, FrontierError, GridConfig};

/// Occupancy state of a cell, from its clamped log-odds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum CellState {
    /// Never observed, or evidence inconclusive (log-odds strictly between the
    /// free and occupied thresholds). Cells outside the grid are unknown.
    Unknown,
    /// Log-odds at most [`GridConfig::free_threshold`].
    Free,
    /// Log-odds at least [`GridConfig::occupied_threshold`].
    Occupied,
}

/// What an update changed, in cells (each cell listed once per list).
#[derive(Debug, Clone, Default)]
pub(crate) struct GridDelta {
    /// Cells whose [`CellState`] changed.
    pub state_changed: Vec<Cell>,
    /// Cells that became traversable.
    pub gained: Vec<Cell>,
    /// Cells that stopped being traversable.
    pub lost: Vec<Cell>,
}

/// A growable 2D occupancy grid for one floor level.
///
/// Each cell stores clamped log-odds (so one spurious return cannot wall off
/// a doorway that was seen free many times) and the number of occupied cells
/// within the robot radius. A cell is *traversable* when it is
/// [`CellState::Free`] and no occupied cell lies within the robot radius of its
/// centre: the traversable set is the free space eroded by the robot disk,
/// i.e. the distance transform of the obstacles thresholded at the robot
/// radius. The per-cell obstacle counter is that thresholded distance
/// transform maintained incrementally: an occupancy flip touches only the
/// O(r²) cells of one disk.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(try_from = "GridData")]
pub struct OccupancyGrid {
    cfg: GridConfig,
    /// Global cell of index 0.
    min: Cell,
    width: usize,
    height: usize,
    log_odds: Vec<f32>,
    occ_count: Vec<u16>,
    trav: Vec<bool>,
    /// Frontier flag per cell (maintained by the frontier module).
    pub(crate) frontier: Vec<bool>,
    /// Frontier segment id per cell, 0 = none (maintained by the frontier module).
    pub(crate) segment: Vec<u64>,
    /// Scratch marks (always all zero between operations).
    #[serde(skip)]
    mark: Vec<u8>,
    /// Scratch list of the cells a scan carved, in the order the rays
    /// first reached them (see [`carve`]): kept between scans, at least
    /// as long as the grid has cells once a scan has run.
    #[serde(skip)]
    carved: Vec<u32>,
    /// Offsets of the inflation disk.
    disk: Vec<(i32, i32)>,
    /// Contact cells: where the robot's body was stopped by something its
    /// sensor did not show (glass, an edge with nothing beyond). They hold
    /// the clamp's upper log-odds for good: no later miss clears them.
    #[serde(default)]
    contacts: BTreeSet<Cell>,
    /// Identifies the traversable layer's content: a fresh process-wide
    /// value whenever it changes (or the grid is resized or loaded), so
    /// caches derived from it (search components) know when they are stale.
    #[serde(skip, default = "fresh_version")]
    trav_version: u64,
}

/// A process-wide unique [`OccupancyGrid::trav_version`].
fn fresh_version() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

/// Unvalidated deserialised form of [`OccupancyGrid`].
#[derive(Deserialize)]
struct GridData {
    cfg: GridConfig,
    min: Cell,
    width: usize,
    height: usize,
    log_odds: Vec<f32>,
    occ_count: Vec<u16>,
    trav: Vec<bool>,
    frontier: Vec<bool>,
    segment: Vec<u64>,
    #[serde(default)]
    contacts: BTreeSet<Cell>,
}

impl TryFrom<GridData> for OccupancyGrid {
    type Error = FrontierError;

    /// Rebuilds a grid from stored data, rejecting inconsistent files (wrong
    /// layer sizes, invalid configuration, non-finite log-odds, a
    /// traversability or inflation layer that does not match the log-odds).
    fn try_from(d: GridData) -> Result<Self, FrontierError> {
        let mut g = OccupancyGrid::new(d.cfg)?;
        let n = d
            .width
            .checked_mul(d.height)
            .ok_or_else(|| FrontierError::InvalidConfig("grid dimensions overflow".into()))?;
        let bad = |m: &str| Err(FrontierError::InvalidConfig(format!("malformed grid: {m}")));
        if n as u64 > g.cfg.max_cells || d.width > 0xFFFF || d.height > 0xFFFF {
            return bad("more cells than max_cells or a side above 65535 cells");
        }
        if [
            d.log_odds.len(),
            d.occ_count.len(),
            d.trav.len(),
            d.frontier.len(),
            d.segment.len(),
        ]
        .iter()
        .any(|&l| l != n)
        {
            return bad("layer sizes differ from width * height");
        }
        let lim = i64::from(crate::MAX_CELL_COORD);
        if i64::from(d.min.x).abs() >= lim
            || i64::from(d.min.y).abs() >= lim
            || i64::from(d.min.x) + d.width as i64 >= lim
            || i64::from(d.min.y) + d.height as i64 >= lim
        {
            return bad("bounds outside the numeric range");
        }
        let (lo, hi) = (g.cfg.log_odds_min, g.cfg.log_odds_max);
        if d.log_odds
            .iter()
            .any(|l| !l.is_finite() || f64::from(*l) < lo - 1e-6 || f64::from(*l) > hi + 1e-6)
        {
            return bad("log-odds outside the clamp range");
        }
        let in_grid = |c: &Cell| {
            let (x, y) = (i64::from(c.x - d.min.x), i64::from(c.y - d.min.y));
            (0..d.width as i64).contains(&x) && (0..d.height as i64).contains(&y)
        };
        if !d.contacts.iter().all(|c| {
            in_grid(c)
                && f64::from(
                    d.log_odds[(c.y - d.min.y) as usize * d.width + (c.x - d.min.x) as usize],
                ) >= hi - 1e-6
        }) {
            return bad("contact cell outside the grid or below the clamp's upper log-odds");
        }
        g.contacts = d.contacts;
        g.min = d.min;
        g.width = d.width;
        g.height = d.height;
        g.log_odds = d.log_odds;
        g.occ_count = vec![0; n];
        g.trav = vec![false; n];
        g.frontier = d.frontier;
        g.segment = d.segment;
        g.mark = vec![0; n];
        g.trav_version = fresh_version();
        // Recompute the derived layers and check them against the file.
        for i in 0..n {
            if g.state_at(i) == CellState::Occupied {
                let c = g.cell_at(i);
                for k in 0..g.disk.len() {
                    let (dx, dy) = g.disk[k];
                    if let Some(j) = g.index(c.offset(dx, dy)) {
                        g.occ_count[j] = g.occ_count[j].saturating_add(1);
                    }
                }
            }
        }
        for i in 0..n {
            g.trav[i] = g.state_at(i) == CellState::Free && g.occ_count[i] == 0;
        }
        if g.occ_count != d.occ_count || g.trav != d.trav {
            return bad("inflation or traversability layer inconsistent with log-odds");
        }
        let margin_ok = (0..n).filter(|&i| g.trav[i]).all(|i| {
            let (x, y) = (i % g.width, i / g.width);
            x >= 2 && y >= 2 && x + 2 < g.width && y + 2 < g.height
        });
        if !margin_ok {
            return bad("traversable cell on the grid margin");
        }
        Ok(g)
    }
}

const MARK_MISS: u8 = 1;
const MARK_HIT: u8 = 2;
const MARK_CAND: u8 = 4;

impl OccupancyGrid {
    /// An empty grid (every cell unknown).
    ///
    /// # Errors
    /// [`FrontierError::InvalidConfig`] if `cfg` is invalid.
    pub fn new(cfg: GridConfig) -> Result<Self, FrontierError> {
        cfg.validate()?;
        let r = cfg.robot_radius / cfg.resolution;
        // Bounded by GridConfig::validate (<= 200 cells).
        #[allow(clippy::cast_possible_truncation)]
        let ri = r.ceil() as i32;
        let mut disk = Vec::new();
        for dy in -ri..=ri {
            for dx in -ri..=ri {
                if f64::from(dx * dx + dy * dy) <= r * r + 1e-9 {
                    disk.push((dx, dy));
                }
            }
        }
        Ok(Self {
            cfg,
            min: Cell::new(0, 0),
            width: 0,
            height: 0,
            log_odds: Vec::new(),
            occ_count: Vec::new(),
            trav: Vec::new(),
            frontier: Vec::new(),
            segment: Vec::new(),
            mark: Vec::new(),
            carved: Vec::new(),
            disk,
            contacts: BTreeSet::new(),
            trav_version: fresh_version(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &GridConfig {
        &self.cfg
    }

    /// Cell edge length (m).
    pub fn resolution(&self) -> f64 {
        self.cfg.resolution
    }

    /// Inclusive bounds `(min, max)` of the allocated cells, `None` while empty.
    pub fn bounds(&self) -> Option<(Cell, Cell)> {
        (self.width > 0).then(|| {
            (
                self.min,
                self.min
                    .offset(self.width as i32 - 1, self.height as i32 - 1),
            )
        })
    }

    /// Number of allocated cells.
    pub fn cell_count(&self) -> usize {
        self.width * self.height
    }

    /// Allocated width and height (cells).
    pub fn dims(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The cell containing world point `p`.
    ///
    /// # Errors
    /// For non-finite or out-of-range coordinates.
    pub fn cell_of(&self, p: &Point2<f64>) -> Result<Cell, FrontierError> {
        cell_of(p, self.cfg.resolution, "point", 0)
    }

    /// Whether every cell the segment `a -> b` passes through (both end
    /// cells included, in order; Amanatides & Woo traversal) satisfies
    /// `pass`: e.g. a line of sight that only some cells may block.
    ///
    /// # Errors
    /// For non-finite or out-of-range end points.
    ///
    /// # Complexity
    /// O(L) for a segment crossing L cells.
    ///
    /// # Example
    /// ```
    /// use nalgebra::Point2;
    /// use sornav_frontier_graph::{Cell, GridConfig, OccupancyGrid};
    /// let grid = OccupancyGrid::new(GridConfig::default()).unwrap(); // 5 cm cells
    /// let mut cells = Vec::new();
    /// let (a, b) = (Point2::new(0.01, 0.01), Point2::new(0.12, 0.06));
    /// assert!(grid.segment_all(&a, &b, |c| { cells.push(c); true }).unwrap());
    /// // 4-connected, from the start cell to the end cell.
    /// assert_eq!(cells.first(), Some(&Cell::new(0, 0)));
    /// assert_eq!(cells.last(), Some(&Cell::new(2, 1)));
    /// assert_eq!(cells.len(), 4);
    /// assert!(!grid.segment_all(&a, &b, |c| c.x < 2).unwrap());
    /// assert!(grid.segment_all(&a, &Point2::new(f64::NAN, 0.0), |_| true).is_err());
    /// ```
    pub fn segment_all(
        &self,
        a: &Point2<f64>,
        b: &Point2<f64>,
        mut pass: impl FnMut(Cell) -> bool,
    ) -> Result<bool, FrontierError> {
        self.cell_of(a)?;
        self.cell_of(b)?;
        let mut all = true;
        traverse(a, b, self.cfg.resolution, |c| {
            all = all && pass(c);
        });
        Ok(all)
    }

    /// World centre of `cell`.
    pub fn cell_center(&self, cell: Cell) -> Point2<f64> {
        cell_center(cell, self.cfg.resolution)
    }

    /// Dense index of `cell`, `None` outside the allocated area.
    #[inline]
    pub(crate) fn index(&self, c: Cell) -> Option<usize> {
        let x = i64::from(c.x) - i64::from(self.min.x);
        let y = i64::from(c.y) - i64::from(self.min.y);
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            None
        } else {
            Some(y as usize * self.width + x as usize)
        }
    }

    /// Cell of a dense index.
    #[inline]
    pub(crate) fn cell_at(&self, i: usize) -> Cell {
        self.min
            .offset((i % self.width) as i32, (i / self.width) as i32)
    }

    /// Clamped log-odds of `cell` (0 outside the grid).
    pub fn log_odds(&self, cell: Cell) -> f64 {
        self.index(cell)
            .map_or(0.0, |i| f64::from(self.log_odds[i]))
    }

    /// Occupancy state of `cell`.
    pub fn state(&self, cell: Cell) -> CellState {
        self.index(cell)
            .map_or(CellState::Unknown, |i| self.state_at(i))
    }

    #[inline]
    pub(crate) fn state_at(&self, i: usize) -> CellState {
        self.classify(self.log_odds[i])
    }

    #[inline]
    fn classify(&self, l: f32) -> CellState {
        let l = f64::from(l);
        if l >= self.cfg.occupied_threshold {
            CellState::Occupied
        } else if l <= self.cfg.free_threshold {
            CellState::Free
        } else {
            CellState::Unknown
        }
    }

    /// Whether the robot can stand on `cell`: free and no occupied cell within
    /// the robot radius.
    pub fn is_traversable(&self, cell: Cell) -> bool {
        self.index(cell).is_some_and(|i| self.trav[i])
    }

    #[inline]
    pub(crate) fn trav_at(&self, i: usize) -> bool {
        self.trav[i]
    }

    /// Changes whenever the traversability layer changes (see the field).
    pub(crate) fn trav_version(&self) -> u64 {
        self.trav_version
    }

    /// The traversability layer (row-major, `dims().0` columns).
    pub(crate) fn trav_layer(&self) -> &[bool] {
        &self.trav
    }

    /// Grows the allocated area to contain `[lo, hi]` (inclusive), keeping
    /// every stored value.
    fn ensure(&mut self, lo: Cell, hi: Cell) -> Result<(), FrontierError> {
        if self.width > 0 {
            let (min, max) = self.bounds().unwrap_or((lo, hi));
            if lo.x >= min.x && lo.y >= min.y && hi.x <= max.x && hi.y <= max.y {
                return Ok(());
            }
        }
        // Grow with slack so that an exploring robot reallocates rarely.
        let slack = 64 + (self.width.max(self.height) / 4) as i32;
        let (nmin, nmax) = match self.bounds() {
            None => (lo.offset(-slack, -slack), hi.offset(slack, slack)),
            Some((min, max)) => (
                Cell::new(
                    if lo.x < min.x { lo.x - slack } else { min.x },
                    if lo.y < min.y { lo.y - slack } else { min.y },
                ),
                Cell::new(
                    if hi.x > max.x { hi.x + slack } else { max.x },
                    if hi.y > max.y { hi.y + slack } else { max.y },
                ),
            ),
        };
        let w = (i64::from(nmax.x) - i64::from(nmin.x) + 1) as u64;
        let h = (i64::from(nmax.y) - i64::from(nmin.y) + 1) as u64;
        // Searches index cells with u32 (65 535² < 2³²).
        if w.saturating_mul(h) > self.cfg.max_cells || w > 0xFFFF || h > 0xFFFF {
            return Err(FrontierError::GridTooLarge {
                requested: w.saturating_mul(h),
                limit: self.cfg.max_cells,
            });
        }
        let (w, h) = (w as usize, h as usize);
        let mut log_odds = vec![0.0f32; w * h];
        let mut occ_count = vec![0u16; w * h];
        let mut trav = vec![false; w * h];
        let mut frontier = vec![false; w * h];
        let mut segment = vec![0u64; w * h];
        let dx = (self.min.x - nmin.x) as usize;
        let dy = (self.min.y - nmin.y) as usize;
        for y in 0..self.height {
            let src = y * self.width..(y + 1) * self.width;
            let dst0 = (y + dy) * w + dx;
            let dst = dst0..dst0 + self.width;
            log_odds[dst.clone()].copy_from_slice(&self.log_odds[src.clone()]);
            occ_count[dst.clone()].copy_from_slice(&self.occ_count[src.clone()]);
            trav[dst.clone()].copy_from_slice(&self.trav[src.clone()]);
            frontier[dst.clone()].copy_from_slice(&self.frontier[src.clone()]);
            segment[dst].copy_from_slice(&self.segment[src]);
        }
        self.min = nmin;
        self.width = w;
        self.height = h;
        self.log_odds = log_odds;
        self.occ_count = occ_count;
        self.trav = trav;
        self.frontier = frontier;
        self.segment = segment;
        self.mark = vec![0; w * h];
        self.trav_version = fresh_version();
        Ok(())
    }

    /// Records a contact: the robot at `origin` (its body centre, at any
    /// height) was stopped by an obstacle at `point` that the sensor did
    /// not show. The point's cell becomes occupied for good (later scans
    /// never clear it) and the cells between are free, as for a return in
    /// the obstacle band; inflation, traversability and the returned delta
    /// follow as for [`Self::integrate`].
    ///
    /// # Errors
    /// As [`Self::integrate`] for non-finite or out-of-range coordinates.
    ///
    /// # Complexity
    /// O(L + r² + log K) for a ray of L cells, robot radius r (cells) and K
    /// contacts.
    pub(crate) fn contact(
        &mut self,
        origin: &Point3<f64>,
        point: &Point2<f64>,
    ) -> Result<GridDelta, FrontierError> {
        let cell = cell_of(point, self.cfg.resolution, "contact", 0)?;
        let z = self.cfg.floor_z + 0.5 * (self.cfg.step_height + self.cfg.robot_height);
        let from = Point3::new(origin.x, origin.y, z);
        let inserted = self.contacts.insert(cell);
        let delta = self.integrate(&from, &[Point3::new(point.x, point.y, z)]);
        if delta.is_err() && inserted {
            self.contacts.remove(&cell);
        }
        delta
    }

    /// The contact cells ([`crate::FrontierMap::contact`]), in cell order.
    pub fn contacts(&self) -> impl ExactSizeIterator<Item = Cell> + '_ {
        self.contacts.iter().copied()
    }

    /// Integrates one scan: `points` are world returns seen from the sensor at
    /// `origin`. See [`crate::FrontierMap::update`] for the sensor model.
    ///
    /// Every input is validated before anything is modified.
    ///
    /// # Complexity
    /// O(P · L + C · r²) for P points, rays of L cells, C cells whose
    /// occupancy flips and robot radius r (cells), plus O(cells) when the grid
    /// grows.
    pub(crate) fn integrate(
        &mut self,
        origin: &Point3<f64>,
        points: &[Point3<f64>],
    ) -> Result<GridDelta, FrontierError> {
        let res = self.cfg.resolution;
        if !origin.z.is_finite() {
            return Err(FrontierError::NonFinite {
                what: "origin",
                index: 0,
            });
        }
        let o2 = origin.xy();
        let oc = cell_of(&o2, res, "origin", 0)?;
        let floor_top = self.cfg.floor_z + self.cfg.step_height;
        let band_top = self.cfg.floor_z + self.cfg.robot_height;
        let drop = self.cfg.floor_z - self.cfg.drop_off_depth;
        // (the carved ray, whether its end cell is a hit); the origin's
        // cell-unit coordinates are shared by every ray.
        let start = RayOrigin::new(&o2, res);
        let mut rays: Vec<(Ray, bool)> = Vec::with_capacity(points.len());
        let (mut lo, mut hi) = (oc, oc);
        for (index, p) in points.iter().enumerate() {
            if !p.z.is_finite() {
                return Err(FrontierError::NonFinite {
                    what: "point",
                    index,
                });
            }
            cell_of(&p.xy(), res, "point", index)?;
            let d = p - origin;
            let len = d.norm();
            let mut t = 1.0f64;
            let mut hit;
            if p.z > band_top {
                // Above the robot: only the part of the ray inside the band
                // says something about the robot's free space.
                hit = false;
                t = if origin.z > band_top {
                    0.0
                } else if d.z > 0.0 {
                    ((band_top - origin.z) / d.z).clamp(0.0, 1.0)
                } else {
                    1.0
                };
            } else {
                hit = p.z >= floor_top || p.z < drop;
            }
            if len > self.cfg.max_range {
                t = t.min(self.cfg.max_range / len);
                hit = false;
            }
            let end = Point2::new(o2.x + t * d.x, o2.y + t * d.y);
            let (scaled, ec) = scaled_cell_of(&end, res, "point", index)?;
            lo = Cell::new(lo.x.min(ec.x), lo.y.min(ec.y));
            hi = Cell::new(hi.x.max(ec.x), hi.y.max(ec.y));
            // `Ray::new(&o2, &end, res)`, without flooring again.
            rays.push((start.ray_to(scaled, ec), hit));
        }
        let pad = self.disk.iter().map(|d| d.0.abs()).max().unwrap_or(0) + 2;
        self.ensure(lo.offset(-pad, -pad), hi.offset(pad, pad))?;

        // Collect the scan's cells once each, in the order the rays first
        // reach them; a hit wins over a miss. A ray's end cell is its last
        // (the only one a hit marks), and its cells stay inside the box of
        // its end cells, which `ensure` allocated: the walk follows dense
        // indices.
        let origin_index = self.index(oc).ok_or(FrontierError::OutOfRange {
            what: "origin",
            x: o2.x,
            y: o2.y,
        })?;
        // Every cell is carved at most once: room for all of them.
        let mut carved = std::mem::take(&mut self.carved);
        if carved.len() < self.mark.len() {
            carved.resize(self.mark.len(), 0);
        }
        let carved_count = carve(&mut self.mark, self.width, origin_index, rays, &mut carved);
        let touched = &carved[..carved_count];

        let mut delta = GridDelta::default();
        let mut cand: Vec<usize> = Vec::new();
        let (lmin, lmax) = (self.cfg.log_odds_min, self.cfg.log_odds_max);
        for &i in touched {
            let i = i as usize;
            let m = self.mark[i];
            // Keep a candidate bit another cell's inflation disk may have set.
            self.mark[i] &= MARK_CAND;
            let inc = if m & MARK_HIT != 0 {
                self.cfg.log_odds_hit
            } else {
                self.cfg.log_odds_miss
            };
            let old = self.state_at(i);
            let l = if !self.contacts.is_empty() && self.contacts.contains(&self.cell_at(i)) {
                lmax
            } else {
                (f64::from(self.log_odds[i]) + inc).clamp(lmin, lmax)
            };
            // Log-odds are small (clamped), f32 is plenty.
            #[allow(clippy::cast_possible_truncation)]
            {
                self.log_odds[i] = l as f32;
            }
            let new = self.state_at(i);
            if new == old {
                continue;
            }
            let c = self.cell_at(i);
            delta.state_changed.push(c);
            if self.mark[i] & MARK_CAND == 0 {
                self.mark[i] |= MARK_CAND;
                cand.push(i);
            }
            let was_occ = old == CellState::Occupied;
            let is_occ = new == CellState::Occupied;
            if was_occ != is_occ {
                for k in 0..self.disk.len() {
                    let (dx, dy) = self.disk[k];
                    let Some(j) = self.index(c.offset(dx, dy)) else {
                        continue;
                    };
                    let before = self.occ_count[j];
                    self.occ_count[j] = if is_occ {
                        before.saturating_add(1)
                    } else {
                        before.saturating_sub(1)
                    };
                    if (before == 0) != (self.occ_count[j] == 0) && self.mark[j] & MARK_CAND == 0 {
                        self.mark[j] |= MARK_CAND;
                        cand.push(j);
                    }
                }
            }
        }
        for &i in &cand {
            self.mark[i] = 0;
            let t = self.state_at(i) == CellState::Free && self.occ_count[i] == 0;
            if t != self.trav[i] {
                self.trav[i] = t;
                if delta.gained.is_empty() && delta.lost.is_empty() {
                    self.trav_version = fresh_version();
                }
                let c = self.cell_at(i);
                if t {
                    delta.gained.push(c);
                } else {
                    delta.lost.push(c);
                }
            }
        }
        self.carved = carved;
        Ok(delta)
    }
}

/// Marks the cells of a scan's rays, all starting at the dense index
/// `origin_index` of a grid `width` cells wide whose `mark` layer is
/// clear of miss and hit bits: every cell a ray passes gets
/// [`MARK_MISS`], a hit ray's end cell [`MARK_HIT`] instead. Writes the
/// cells to the front of `carved` (at least `mark.len()` long) in the
/// order the rays first reach them (each once) and returns their number.
/// The rays' cells lie in the allocated grid (the caller grew it to their
/// ends).
///
/// # Performance
/// A function of its own, not inlined into [`OccupancyGrid::integrate`],
/// and with no call that returns inside the walk (a slice of room for
/// every cell, where a `Vec` push may call the allocator): the walk loop
/// (every move of every ray, ~30 per ray at 5 cm) keeps the ray's state
/// in registers instead of reloading it from the stack at each move.
///
/// # Complexity
/// O(R · L) for R rays of L cells.
#[inline(never)]
fn carve(
    mark: &mut [u8],
    width: usize,
    origin_index: usize,
    rays: Vec<(Ray, bool)>,
    carved: &mut [u32],
) -> usize {
    let mut n = 0;
    for (ray, hit) in rays {
        let (sx, sy) = ray.direction();
        // Row offsets fit: the grid is at most 0xFFFF cells wide.
        let (dx, dy) = (sx as isize, sy as isize * width as isize);
        let end_index = ray.walk(
            origin_index,
            |i| i.wrapping_add_signed(dx),
            |i| i.wrapping_add_signed(dy),
            |i| {
                if mark[i] == 0 {
                    mark[i] = MARK_MISS;
                    // Below 0xFFFF² < 2³² cells; each cell once, so `n`
                    // stays below `mark.len()`.
                    #[allow(clippy::cast_possible_truncation)]
                    {
                        carved[n] = i as u32;
                    }
                    n += 1;
                }
            },
        );
        // The end cell was first marked as a miss (and queued if new):
        // a hit overrides that.
        if hit {
            mark[end_index] = MARK_HIT;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Differential: [`carve`] marks and lists the cells of a scan's
        /// rays as a cell-by-cell [`traverse`] of each ray with a
        /// first-reach list (the reference): the same cells in the same
        /// order, each once, a hit ray's end cell marked as a hit, every
        /// other listed cell as a miss.
        #[test]
        fn carve_matches_a_traverse_per_ray(
            (ox, oy) in (2.0f64..4.0, 2.0f64..4.0),
            ends in prop::collection::vec((0.05f64..5.95, 0.05f64..5.95, any::<bool>()), 0..40),
        ) {
            let res = 0.1;
            // A 60 x 60 grid over [0, 6)², its cell (0, 0) at index 0.
            let width = 60;
            let origin = Point2::new(ox, oy);
            let start = RayOrigin::new(&origin, res);
            let rays: Vec<(Ray, bool)> = ends
                .iter()
                .map(|&(x, y, hit)| {
                    let end = Point2::new(x, y);
                    let (scaled, cell) = scaled_cell_of(&end, res, "end", 0).unwrap();
                    (start.ray_to(scaled, cell), hit)
                })
                .collect();
            let index = |c: Cell| c.y as usize * width + c.x as usize;
            let mut mark = vec![0u8; width * width];
            let mut carved = vec![0u32; width * width];
            let origin_index = index(Cell::new((ox / res).floor() as i32, (oy / res).floor() as i32));
            let n = carve(&mut mark, width, origin_index, rays, &mut carved);

            let mut want_mark = vec![0u8; width * width];
            let mut want = Vec::new();
            for &(x, y, hit) in &ends {
                let end = Point2::new(x, y);
                let mut last = 0;
                traverse(&origin, &end, res, |c| {
                    let i = index(c);
                    if want_mark[i] == 0 {
                        want_mark[i] = MARK_MISS;
                        want.push(i as u32);
                    }
                    last = i;
                });
                if hit {
                    want_mark[last] = MARK_HIT;
                }
            }
            prop_assert_eq!(&carved[..n], &want[..]);
            prop_assert_eq!(mark, want_mark);
        }
    }
}
