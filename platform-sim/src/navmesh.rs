//! Recast-style multi-layer walkable height field.
//!
//! Building a [`NavMesh`] from a [`Scene`]:
//!
//! 1. **Rasterise** every triangle into a grid of square columns of side
//!    `cell_size` (0.05 m). Each triangle is clipped to each column it overlaps
//!    (Sutherland-Hodgman against the column's four sides) and contributes a
//!    solid span `[z_min, z_max]`, flagged walkable when its up-facing slope is
//!    at most `max_slope_deg` (45 deg).
//! 2. **Merge** overlapping spans of a column; the merged top keeps the walkable
//!    flag when a walkable surface lies within `max_step` of the top (so stair
//!    risers merge with their treads). Non-walkable spans whose top is within
//!    `max_step` above a walkable span become walkable (Recast's
//!    "low hanging obstacles" filter: kerbs, thresholds).
//! 3. **Open spans**: the top of a walkable solid span is a walking surface when
//!    the free space up to the next solid span is at least `agent_height` and
//!    no downward-facing surface lies on it (the underside of a closed object
//!    standing there). Cells are half-open: geometry exactly on a cell's upper
//!    border belongs to the next cell.
//! 4. **Connect** 4-neighbouring open spans whose floors differ by at most
//!    `max_step` and whose shared free space is at least `agent_height`
//!    (mutual connections only, so the graph is undirected). Several walking
//!    surfaces may exist in one column (floors of a multi-storey house), and
//!    stairs connect them.
//! 5. **Erode** by `agent_radius`: a multi-source Dijkstra (octile metric) from
//!    the border spans (fewer than four connections) removes every span closer
//!    than the radius to a border, like Recast's `rcErodeWalkableArea`.
//! 6. **Islands** (connected components) smaller than `min_region_area` are
//!    dropped.
//! 7. **Floor**: a span is floor when its surface is the top of a floor or
//!    staircase instance (or of an object at most [`THIN_COVER`] thick on
//!    one, a carpet); an island is on the floor when it holds a floor span.
//!    Islands on furniture (bed tops, large tables) and object surfaces
//!    reached by a low step (a hearth) stay walkable for `is_navigable`
//!    queries but are never used to place agents
//!    ([`NavMesh::is_floor_span`], [`NavMesh::is_floor_region`]).
//!
//! Reference: M. Mononen, *Recast Navigation* (2009), whose parameters Habitat
//! uses for its navmesh (step 0.2 m, slope 45 deg).

use std::collections::BinaryHeap;
use std::path::Path;

use nalgebra::{Point2, Point3};
use serde::{Deserialize, Serialize};

use crate::scene::{InstanceKind, Scene};
use crate::{NavError, SceneError};

/// Parameters of the walkable height field (defaults: Habitat's ObjectNav agent).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct NavMeshConfig {
    /// Side of a grid column in metres (0.05).
    pub cell_size: f64,
    /// Free height an agent needs above the floor, metres (0.88).
    pub agent_height: f64,
    /// Agent radius: walkable spans keep at least this distance to obstacles (0.18).
    pub agent_radius: f64,
    /// Largest height step between neighbouring spans, metres (0.2).
    pub max_step: f64,
    /// Steepest walkable surface, degrees (45).
    pub max_slope_deg: f64,
    /// Islands with less walkable area (m^2) are discarded (1.0).
    pub min_region_area: f64,
    /// Largest vertical distance between a query point and a walking surface
    /// for the point to be on that surface (0.5, Habitat's `is_navigable`).
    pub vertical_tolerance: f64,
}

impl Default for NavMeshConfig {
    fn default() -> Self {
        NavMeshConfig {
            cell_size: 0.05,
            agent_height: 0.88,
            agent_radius: 0.18,
            max_step: 0.2,
            max_slope_deg: 45.0,
            min_region_area: 1.0,
            vertical_tolerance: 0.5,
        }
    }
}

impl NavMeshConfig {
    /// Checks every field for range and finiteness.
    ///
    /// # Errors
    /// [`SceneError::Config`] naming the first invalid field.
    pub fn validate(&self) -> Result<(), SceneError> {
        let pos = |v: f64, f: &'static str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(SceneError::Config {
                    field: f,
                    message: format!("must be finite and > 0, got {v}"),
                })
            }
        };
        pos(self.cell_size, "cell_size")?;
        pos(self.agent_height, "agent_height")?;
        pos(self.vertical_tolerance, "vertical_tolerance")?;
        let nonneg = |v: f64, f: &'static str| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(SceneError::Config {
                    field: f,
                    message: format!("must be finite and >= 0, got {v}"),
                })
            }
        };
        nonneg(self.agent_radius, "agent_radius")?;
        nonneg(self.max_step, "max_step")?;
        nonneg(self.min_region_area, "min_region_area")?;
        if !(self.max_slope_deg.is_finite() && (0.0..90.0).contains(&self.max_slope_deg)) {
            return Err(SceneError::Config {
                field: "max_slope_deg",
                message: "must be in [0, 90)".into(),
            });
        }
        Ok(())
    }
}

/// Largest grid (columns) a height field may allocate: a 250 m x 250 m
/// footprint at 0.05 m; larger scenes need a coarser `cell_size`.
pub const MAX_COLUMNS: usize = 25_000_000;

/// Objects at most this thick (m) on a floor (carpets, thresholds, lamp
/// bases) still count as floor surface for [`NavMesh::is_floor_span`].
pub const THIN_COVER: f32 = 0.05;

/// Index of a walkable span in a [`NavMesh`].
pub type SpanId = u32;
const NONE: u32 = u32::MAX;

/// A walking surface in one grid column.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Span {
    /// Height of the walking surface.
    pub floor: f32,
    /// Height of the next solid surface above (`f32::INFINITY` if none).
    pub ceiling: f32,
    /// Connected neighbour spans in directions -x, +y, +x, -y (`u32::MAX` = none).
    pub neighbours: [SpanId; 4],
    /// Connected component (island) index.
    pub region: u32,
}

/// Grid offsets of the four directions used by [`Span::neighbours`].
pub const DIRS: [(i32, i32); 4] = [(-1, 0), (0, 1), (1, 0), (0, -1)];

/// Multi-layer walkable height field of a scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct NavMesh {
    config: NavMeshConfig,
    origin: [f64; 2],
    width: usize,
    height: usize,
    /// `col_start[c]..col_start[c + 1]` are the spans of column c.
    col_start: Vec<u32>,
    spans: Vec<Span>,
    span_col: Vec<u32>,
    region_area: Vec<f64>,
    /// Per span: its walking surface is the top of a floor or staircase, or
    /// of an object at most [`THIN_COVER`] above one.
    #[serde(default)]
    span_ground: Vec<bool>,
    /// Per region: whether it contains a floor or staircase surface
    /// (see [`NavMesh::is_floor_region`]).
    #[serde(default)]
    region_floor: Vec<bool>,
    /// Floors of the height field, computed on first use
    /// (see [`crate::levels`]).
    #[serde(skip)]
    pub(crate) levels: std::sync::OnceLock<crate::levels::Levels>,
}

#[derive(Clone, Copy)]
struct Solid {
    col: u32,
    zmin: f32,
    zmax: f32,
    walkable: bool,
    /// The top surface belongs to a downward-facing triangle (underside of a
    /// closed object resting on it).
    down_top: bool,
    /// Height of the highest floor or staircase surface in the solid
    /// (`-inf` without one).
    ground_z: f32,
}

/// Clips a 3-D polygon against `coord[axis] <= c` (keep = true) or `>= c`.
fn clip_axis(poly: &[[f64; 3]], axis: usize, c: f64, keep_below: bool, out: &mut Vec<[f64; 3]>) {
    out.clear();
    let n = poly.len();
    for i in 0..n {
        let (p, q) = (poly[i], poly[(i + 1) % n]);
        let s = if keep_below { 1.0 } else { -1.0 };
        let (dp, dq) = (s * (p[axis] - c), s * (q[axis] - c));
        if dp <= 0.0 {
            out.push(p);
        }
        if (dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0) {
            let t = dp / (dp - dq);
            out.push([
                p[0] + (q[0] - p[0]) * t,
                p[1] + (q[1] - p[1]) * t,
                p[2] + (q[2] - p[2]) * t,
            ]);
        }
    }
}

impl NavMesh {
    /// Builds the walkable height field of `scene`.
    ///
    /// # Errors
    /// [`SceneError::Config`] for an invalid configuration;
    /// [`SceneError::Invalid`] when the grid would exceed [`MAX_COLUMNS`].
    ///
    /// # Complexity
    /// O(C + S log S) where C is the number of (triangle, column) overlaps and
    /// S the number of solid spans; erosion and islands are O(S log S).
    pub fn build(scene: &Scene, config: &NavMeshConfig) -> Result<NavMesh, SceneError> {
        config.validate()?;
        let cs = config.cell_size;
        let b = scene.bounds();
        let cells = ((b.max.x - b.min.x) / cs + 3.0) * ((b.max.y - b.min.y) / cs + 3.0);
        if !(cells.is_finite() && cells <= MAX_COLUMNS as f64) {
            return Err(SceneError::Invalid(format!(
                "scene footprint {:.0} x {:.0} m needs {cells:.0} columns at {cs} m (limit {MAX_COLUMNS})",
                b.max.x - b.min.x,
                b.max.y - b.min.y
            )));
        }
        let origin = [b.min.x - cs, b.min.y - cs];
        let width = (((b.max.x - origin[0]) / cs).ceil() as usize + 2).max(1);
        let height = (((b.max.y - origin[1]) / cs).ceil() as usize + 2).max(1);
        let cos_slope = config.max_slope_deg.to_radians().cos();
        let verts = scene.vertices();
        let ground_instance: Vec<bool> = scene
            .instances()
            .iter()
            .map(|i| matches!(i.kind, InstanceKind::Floor | InstanceKind::Stairs))
            .collect();
        let tri_inst = scene.triangle_instances();

        // 1. rasterise
        let mut solids: Vec<Solid> = Vec::new();
        let mut a = Vec::with_capacity(8);
        let mut bb = Vec::with_capacity(8);
        for (ti, t) in scene.triangles().iter().enumerate() {
            let ground = tri_inst
                .get(ti)
                .and_then(|&i| ground_instance.get(i as usize))
                .copied()
                .unwrap_or(false);
            let p: [[f64; 3]; 3] = t.map(|i| verts[i as usize].map(f64::from));
            let e1 = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
            let e2 = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
            let n = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            let nl = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let walkable = nl > 0.0 && n[2] / nl >= cos_slope;
            let down = nl > 0.0 && n[2] / nl <= -cos_slope;
            let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
            for q in &p {
                x0 = x0.min(q[0]);
                x1 = x1.max(q[0]);
                y0 = y0.min(q[1]);
                y1 = y1.max(q[1]);
            }
            let cx0 = ((x0 - origin[0]) / cs).floor().max(0.0) as usize;
            let cx1 = (((x1 - origin[0]) / cs).floor() as usize).min(width - 1);
            let cy0 = ((y0 - origin[1]) / cs).floor().max(0.0) as usize;
            let cy1 = (((y1 - origin[1]) / cs).floor() as usize).min(height - 1);
            for cy in cy0..=cy1 {
                let ylo = origin[1] + cy as f64 * cs;
                clip_axis(&p, 1, ylo, false, &mut a);
                clip_axis(&a, 1, ylo + cs, true, &mut bb);
                // half-open cells: geometry lying on the upper border belongs to the next cell
                if bb.is_empty() || bb.iter().all(|q| q[1] >= ylo + cs - 1e-9) {
                    continue;
                }
                let row = bb.clone();
                for cx in cx0..=cx1 {
                    let xlo = origin[0] + cx as f64 * cs;
                    clip_axis(&row, 0, xlo, false, &mut a);
                    clip_axis(&a, 0, xlo + cs, true, &mut bb);
                    if bb.is_empty() || bb.iter().all(|q| q[0] >= xlo + cs - 1e-9) {
                        continue;
                    }
                    let (mut zmin, mut zmax) = (f64::MAX, f64::MIN);
                    for q in &bb {
                        zmin = zmin.min(q[2]);
                        zmax = zmax.max(q[2]);
                    }
                    solids.push(Solid {
                        col: (cy * width + cx) as u32,
                        zmin: zmin as f32,
                        zmax: zmax as f32,
                        walkable,
                        down_top: down,
                        ground_z: if ground {
                            zmax as f32
                        } else {
                            f32::NEG_INFINITY
                        },
                    });
                }
            }
        }

        // 2. merge spans per column
        solids.sort_unstable_by(|a, b| a.col.cmp(&b.col).then(a.zmin.total_cmp(&b.zmin)));
        let step = config.max_step as f32;
        let mut merged: Vec<Solid> = Vec::with_capacity(solids.len() / 2);
        for mut s in solids {
            // A surface lying within THIN_COVER above the one below it
            // rests on it: the top of a carpet (its top and bottom faces
            // are separate solids in a cell inside its outline) keeps the
            // ground height of the floor under it.
            if let Some(cur) = merged.last()
                && cur.col == s.col
                && s.zmin <= cur.zmax + THIN_COVER
            {
                s.ground_z = s.ground_z.max(cur.ground_z);
            }
            if let Some(cur) = merged.last_mut()
                && cur.col == s.col
                && s.zmin <= cur.zmax + 1e-3
            {
                if s.zmax > cur.zmax + step {
                    cur.walkable = s.walkable;
                } else if (s.zmax - cur.zmax).abs() <= step {
                    cur.walkable |= s.walkable;
                }
                if s.zmax > cur.zmax + 1e-3 {
                    cur.down_top = s.down_top;
                } else if (s.zmax - cur.zmax).abs() <= 1e-3 {
                    cur.down_top |= s.down_top;
                }
                cur.ground_z = cur.ground_z.max(s.ground_z);
                cur.zmax = cur.zmax.max(s.zmax);
                continue;
            }
            merged.push(s);
        }
        // low hanging obstacles
        for i in 1..merged.len() {
            let (prev, cur) = (merged[i - 1], merged[i]);
            if prev.col == cur.col && prev.walkable && !cur.walkable && cur.zmax - prev.zmax <= step
            {
                merged[i].walkable = true;
            }
        }

        // 3. open spans
        let ncols = width * height;
        let mut col_start = vec![0u32; ncols + 1];
        let mut spans: Vec<Span> = Vec::new();
        let mut span_col: Vec<u32> = Vec::new();
        let mut span_ground: Vec<bool> = Vec::new();
        let ah = config.agent_height as f32;
        let mut i = 0;
        for (c, start) in col_start.iter_mut().enumerate().take(ncols) {
            *start = spans.len() as u32;
            while i < merged.len() && (merged[i].col as usize) == c {
                let s = merged[i];
                let ceil = if i + 1 < merged.len() && merged[i + 1].col == s.col {
                    merged[i + 1].zmin
                } else {
                    f32::INFINITY
                };
                if s.walkable && !s.down_top && ceil - s.zmax >= ah {
                    spans.push(Span {
                        floor: s.zmax,
                        ceiling: ceil,
                        neighbours: [NONE; 4],
                        region: 0,
                    });
                    span_col.push(c as u32);
                    span_ground.push(s.zmax - s.ground_z <= THIN_COVER);
                }
                i += 1;
            }
        }
        col_start[ncols] = spans.len() as u32;
        let mut nm = NavMesh {
            config: config.clone(),
            origin,
            width,
            height,
            col_start,
            spans,
            span_col,
            region_area: Vec::new(),
            span_ground,
            region_floor: Vec::new(),
            levels: std::sync::OnceLock::new(),
        };
        nm.connect();
        nm.erode();
        nm.drop_small_islands();
        // scenes without any floor or staircase instance (unlabelled meshes):
        // every region counts as floor
        let labelled = ground_instance.iter().any(|&g| g);
        nm.label_floor_regions(labelled);
        Ok(nm)
    }

    fn column_spans(&self, col: usize) -> std::ops::Range<usize> {
        self.col_start[col] as usize..self.col_start[col + 1] as usize
    }

    fn neighbour_col(&self, col: usize, d: usize) -> Option<usize> {
        let (x, y) = ((col % self.width) as i64, (col / self.width) as i64);
        let (nx, ny) = (x + i64::from(DIRS[d].0), y + i64::from(DIRS[d].1));
        if nx < 0 || ny < 0 || nx >= self.width as i64 || ny >= self.height as i64 {
            None
        } else {
            Some(ny as usize * self.width + nx as usize)
        }
    }

    /// 4. connections (mutual only).
    fn connect(&mut self) {
        let step = self.config.max_step as f32;
        let ah = self.config.agent_height as f32;
        for s in 0..self.spans.len() {
            let col = self.span_col[s] as usize;
            let me = self.spans[s];
            for d in 0..4 {
                let mut best = NONE;
                let mut best_dz = f32::MAX;
                if let Some(nc) = self.neighbour_col(col, d) {
                    for n in self.column_spans(nc) {
                        let o = self.spans[n];
                        let dz = (o.floor - me.floor).abs();
                        let gap = o.ceiling.min(me.ceiling) - o.floor.max(me.floor);
                        if dz <= step && gap >= ah && dz < best_dz {
                            best = n as u32;
                            best_dz = dz;
                        }
                    }
                }
                self.spans[s].neighbours[d] = best;
            }
        }
        for s in 0..self.spans.len() {
            for d in 0..4 {
                let n = self.spans[s].neighbours[d];
                if n != NONE && self.spans[n as usize].neighbours[(d + 2) % 4] != s as u32 {
                    self.spans[s].neighbours[d] = NONE;
                }
            }
        }
    }

    /// Diagonal neighbour of `s` through directions `d` then `(d + 1) % 4`,
    /// present only when both orthogonal routes reach the same span.
    pub(crate) fn diagonal(&self, s: usize, d: usize) -> Option<usize> {
        let e = (d + 1) % 4;
        let a = self.spans[s].neighbours[d];
        let b = self.spans[s].neighbours[e];
        if a == NONE || b == NONE {
            return None;
        }
        let via_a = self.spans[a as usize].neighbours[e];
        let via_b = self.spans[b as usize].neighbours[d];
        (via_a != NONE && via_a == via_b).then_some(via_a as usize)
    }

    /// 5. erosion by the agent radius.
    fn erode(&mut self) {
        let r = self.config.agent_radius;
        if r <= 0.0 || self.spans.is_empty() {
            return;
        }
        let cs = self.config.cell_size;
        let mut dist = vec![f64::INFINITY; self.spans.len()];
        let mut heap = BinaryHeap::new();
        for (s, sp) in self.spans.iter().enumerate() {
            if sp.neighbours.contains(&NONE) {
                dist[s] = 0.5 * cs;
                heap.push(HeapItem(0.5 * cs, s as u32));
            }
        }
        while let Some(HeapItem(d, s)) = heap.pop() {
            let s = s as usize;
            if d > dist[s] || d >= r {
                continue;
            }
            for (n, w) in self.moves(s) {
                let nd = d + w;
                if nd < dist[n] {
                    dist[n] = nd;
                    heap.push(HeapItem(nd, n as u32));
                }
            }
        }
        let keep: Vec<bool> = dist.iter().map(|&d| d >= r).collect();
        self.retain(&keep);
    }

    /// The spans of areas at least three cells wide (a morphological
    /// opening of the walkable surface: erosion by the 4-neighbour cross,
    /// dilation by the 3 x 3 square): a span is kept when it, one of its
    /// neighbours or one of its diagonal neighbours has all four
    /// neighbours. Strips one or two cells wide (a 0.40-0.45 m gap between
    /// two pieces of furniture) are left out: the agent's 0.25 m moves at
    /// headings 30 deg apart, without sliding, cannot follow them.
    ///
    /// # Complexity
    /// O(S).
    pub fn wide_spans(&self) -> Vec<bool> {
        let core: Vec<bool> = self
            .spans
            .iter()
            .map(|sp| !sp.neighbours.contains(&NONE))
            .collect();
        (0..self.spans.len())
            .map(|s| {
                core[s]
                    || self.spans[s]
                        .neighbours
                        .iter()
                        .any(|&n| n != NONE && core[n as usize])
                    || (0..4).any(|d| self.diagonal(s, d).is_some_and(|n| core[n]))
            })
            .collect()
    }

    /// Horizontal octile moves from span `s`: (neighbour, horizontal length).
    fn moves(&self, s: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let cs = self.config.cell_size;
        let orth = self.spans[s]
            .neighbours
            .into_iter()
            .filter(|&n| n != NONE)
            .map(move |n| (n as usize, cs));
        let diag = (0..4)
            .filter_map(move |d| self.diagonal(s, d))
            .map(move |n| (n, cs * std::f64::consts::SQRT_2));
        orth.chain(diag)
    }

    /// Moves with their 3-D lengths (used by geodesic queries).
    pub(crate) fn moves_3d(&self, s: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let f = self.spans[s].floor;
        self.moves(s).map(move |(n, h)| {
            let dz = f64::from(self.spans[n].floor - f);
            (n, (h * h + dz * dz).sqrt())
        })
    }

    /// Keeps the spans flagged in `keep`, remapping ids and connections.
    fn retain(&mut self, keep: &[bool]) {
        let mut remap = vec![NONE; self.spans.len()];
        let mut next = 0u32;
        for (s, &k) in keep.iter().enumerate() {
            if k {
                remap[s] = next;
                next += 1;
            }
        }
        let mut spans = Vec::with_capacity(next as usize);
        let mut span_col = Vec::with_capacity(next as usize);
        let mut span_ground = Vec::with_capacity(next as usize);
        for (s, sp) in self.spans.iter().enumerate() {
            if keep[s] {
                span_ground.push(self.span_ground.get(s).copied().unwrap_or(false));
                let mut sp = *sp;
                for n in &mut sp.neighbours {
                    if *n != NONE {
                        *n = remap[*n as usize];
                    }
                }
                spans.push(sp);
                span_col.push(self.span_col[s]);
            }
        }
        let mut col_start = vec![0u32; self.width * self.height + 1];
        for &c in &span_col {
            col_start[c as usize + 1] += 1;
        }
        for c in 0..self.width * self.height {
            col_start[c + 1] += col_start[c];
        }
        self.spans = spans;
        self.span_col = span_col;
        self.span_ground = span_ground;
        self.col_start = col_start;
    }

    /// 6. islands: label components and drop small ones.
    fn drop_small_islands(&mut self) {
        let cell_area = self.config.cell_size * self.config.cell_size;
        let labels = self.label_components();
        let mut area = vec![0.0; labels.1];
        for &l in &labels.0 {
            area[l as usize] += cell_area;
        }
        let keep: Vec<bool> = labels
            .0
            .iter()
            .map(|&l| area[l as usize] >= self.config.min_region_area)
            .collect();
        self.retain(&keep);
        let (labels, n) = self.label_components();
        let mut region_area = vec![0.0; n];
        for (s, &l) in labels.iter().enumerate() {
            self.spans[s].region = l;
            region_area[l as usize] += cell_area;
        }
        self.region_area = region_area;
    }

    /// Step 7, floor regions: a region is on the floor when one of its spans
    /// is the top of a floor or staircase instance (all regions, and all
    /// spans, when `labelled` is false).
    fn label_floor_regions(&mut self, labelled: bool) {
        if !labelled {
            self.span_ground.iter_mut().for_each(|g| *g = true);
        }
        let mut floor = vec![!labelled; self.region_area.len()];
        for (sp, &g) in self.spans.iter().zip(&self.span_ground) {
            if g {
                floor[sp.region as usize] = true;
            }
        }
        self.region_floor = floor;
    }

    fn label_components(&self) -> (Vec<u32>, usize) {
        let mut label = vec![NONE; self.spans.len()];
        let mut n = 0u32;
        let mut stack = Vec::new();
        for s in 0..self.spans.len() {
            if label[s] != NONE {
                continue;
            }
            label[s] = n;
            stack.push(s);
            while let Some(c) = stack.pop() {
                for nb in self.spans[c].neighbours {
                    if nb != NONE && label[nb as usize] == NONE {
                        label[nb as usize] = n;
                        stack.push(nb as usize);
                    }
                }
            }
            n += 1;
        }
        (label, n as usize)
    }

    /// The configuration used to build this height field.
    pub fn config(&self) -> &NavMeshConfig {
        &self.config
    }
    /// Walkable spans.
    pub fn spans(&self) -> &[Span] {
        &self.spans
    }
    /// Number of walkable spans.
    pub fn span_count(&self) -> usize {
        self.spans.len()
    }
    /// Grid size in columns (x, y).
    pub fn grid_size(&self) -> (usize, usize) {
        (self.width, self.height)
    }
    /// World (x, y) of the grid's minimum corner.
    pub fn origin(&self) -> Point2<f64> {
        Point2::new(self.origin[0], self.origin[1])
    }
    /// Total walkable area in m^2.
    pub fn walkable_area(&self) -> f64 {
        self.region_area.iter().sum()
    }
    /// Area (m^2) of each island, indexed by [`Span::region`].
    pub fn region_areas(&self) -> &[f64] {
        &self.region_area
    }
    /// Whether island `region` lies on the building's floor: it contains
    /// the top of a floor or staircase instance. Islands on top of furniture
    /// (a bed or a large table top can exceed `min_region_area`) are not.
    /// In scenes without any floor or staircase instance every island counts
    /// as floor. Agent poses (episode starts, view points) are sampled on
    /// floor islands only.
    pub fn is_floor_region(&self, region: u32) -> bool {
        // height fields deserialised from before this flag existed: all
        self.region_floor
            .get(region as usize)
            .copied()
            .unwrap_or(self.region_floor.is_empty())
    }
    /// Whether span `s` is floor: its walking surface is the top of a floor
    /// or staircase instance, or of an object at most [`THIN_COVER`] thick on
    /// one (a carpet), on a floor island ([`NavMesh::is_floor_region`]).
    /// Spans on furniture connected to the floor by a low step (a hearth, a
    /// shower tray) are walkable but not floor. In scenes without any floor
    /// or staircase instance every span counts as floor.
    pub fn is_floor_span(&self, s: SpanId) -> bool {
        let Some(sp) = self.spans.get(s as usize) else {
            return false;
        };
        let own = self.span_ground.get(s as usize).copied().unwrap_or(true);
        own && self.is_floor_region(sp.region)
    }
    /// Walkable area of the floor islands in m^2.
    pub fn floor_area(&self) -> f64 {
        self.region_area
            .iter()
            .enumerate()
            .filter(|&(r, _)| self.is_floor_region(r as u32))
            .map(|(_, a)| a)
            .sum()
    }
    /// The island with the largest area.
    pub fn largest_region(&self) -> Option<u32> {
        (0..self.region_area.len())
            .max_by(|&a, &b| self.region_area[a].total_cmp(&self.region_area[b]))
            .map(|r| r as u32)
    }
    /// Grid column (x, y) of span `s`.
    ///
    /// # Panics
    /// If `s` is not a span of this height field (`s >= span_count()`);
    /// span ids come from this height field's own queries
    /// ([`NavMesh::span_at`], [`NavMesh::spans`], ...).
    pub fn span_cell(&self, s: SpanId) -> (usize, usize) {
        let c = self.span_col[s as usize] as usize;
        (c % self.width, c / self.width)
    }
    /// Centre of span `s`'s walking surface.
    ///
    /// # Panics
    /// If `s` is not a span of this height field (`s >= span_count()`), as
    /// [`NavMesh::span_cell`].
    pub fn span_center(&self, s: SpanId) -> Point3<f64> {
        let (x, y) = self.span_cell(s);
        let cs = self.config.cell_size;
        Point3::new(
            self.origin[0] + (x as f64 + 0.5) * cs,
            self.origin[1] + (y as f64 + 0.5) * cs,
            f64::from(self.spans[s as usize].floor),
        )
    }

    fn column_of(&self, x: f64, y: f64) -> Option<usize> {
        let cx = ((x - self.origin[0]) / self.config.cell_size).floor();
        let cy = ((y - self.origin[1]) / self.config.cell_size).floor();
        if cx < 0.0 || cy < 0.0 || cx >= self.width as f64 || cy >= self.height as f64 {
            return None;
        }
        Some(cy as usize * self.width + cx as usize)
    }

    /// The span under `p`: the walking surface in p's column whose floor is
    /// nearest to `p.z`, within `vertical_tolerance`.
    ///
    /// # Complexity
    /// O(spans in the column).
    pub fn span_at(&self, p: &Point3<f64>) -> Option<SpanId> {
        if !p.coords.iter().all(|c| c.is_finite()) {
            return None;
        }
        let col = self.column_of(p.x, p.y)?;
        self.column_spans(col)
            .map(|s| (s, (f64::from(self.spans[s].floor) - p.z).abs()))
            .filter(|&(_, dz)| dz <= self.config.vertical_tolerance)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(s, _)| s as SpanId)
    }

    /// True when an agent standing at `p` (feet position) is on the walkable
    /// surface (Habitat's `is_navigable`).
    pub fn is_navigable(&self, p: &Point3<f64>) -> bool {
        self.span_at(p).is_some()
    }

    /// Height of the walking surface at `(x, y)` nearest to `z_hint`
    /// (any vertical distance), or `None` when the column is not walkable.
    pub fn height_at(&self, x: f64, y: f64, z_hint: f64) -> Option<f64> {
        let col = self.column_of(x, y)?;
        self.column_spans(col)
            .min_by(|&a, &b| {
                (f64::from(self.spans[a].floor) - z_hint)
                    .abs()
                    .total_cmp(&(f64::from(self.spans[b].floor) - z_hint).abs())
            })
            .map(|s| f64::from(self.spans[s].floor))
    }

    /// Walking surfaces in the column containing `(x, y)`, bottom to top.
    pub fn heights_at(&self, x: f64, y: f64) -> Vec<f64> {
        self.column_of(x, y)
            .map(|c| {
                self.column_spans(c)
                    .map(|s| f64::from(self.spans[s].floor))
                    .collect()
            })
            .unwrap_or_default()
    }

    /// The span nearest to `p` (3-D distance to span centres) within
    /// `max_horizontal` metres horizontally and `vertical_tolerance` vertically.
    ///
    /// # Complexity
    /// O((max_horizontal / cell_size)^2) columns.
    pub fn nearest_span(&self, p: &Point3<f64>, max_horizontal: f64) -> Option<SpanId> {
        if !p.coords.iter().all(|c| c.is_finite()) || !max_horizontal.is_finite() {
            return None;
        }
        if let Some(s) = self.span_at(p) {
            return Some(s);
        }
        let cs = self.config.cell_size;
        let r = (max_horizontal / cs).ceil().max(0.0) as i64;
        let cx = ((p.x - self.origin[0]) / cs).floor() as i64;
        let cy = ((p.y - self.origin[1]) / cs).floor() as i64;
        let mut best: Option<(SpanId, f64)> = None;
        for y in (cy - r).max(0)..=(cy + r).min(self.height as i64 - 1) {
            for x in (cx - r).max(0)..=(cx + r).min(self.width as i64 - 1) {
                let col = y as usize * self.width + x as usize;
                for s in self.column_spans(col) {
                    let c = self.span_center(s as SpanId);
                    if (c.z - p.z).abs() > self.config.vertical_tolerance
                        || (c.xy() - p.xy()).norm() > max_horizontal
                    {
                        continue;
                    }
                    let d = (c - p).norm();
                    if best.is_none_or(|b| d < b.1) {
                        best = Some((s as SpanId, d));
                    }
                }
            }
        }
        best.map(|b| b.0)
    }

    /// Snaps `p` to the walkable surface: the centre of the nearest span
    /// within `max_horizontal` metres.
    ///
    /// # Errors
    /// [`NavError::NonFinite`] or [`NavError::NotNavigable`].
    pub fn snap(&self, p: &Point3<f64>, max_horizontal: f64) -> Result<Point3<f64>, NavError> {
        if !p.coords.iter().all(|c| c.is_finite()) {
            return Err(NavError::NonFinite);
        }
        if let Some(s) = self.span_at(p) {
            return Ok(Point3::new(
                p.x,
                p.y,
                f64::from(self.spans[s as usize].floor),
            ));
        }
        self.nearest_span(p, max_horizontal)
            .map(|s| self.span_center(s))
            .ok_or(NavError::NotNavigable {
                x: p.x,
                y: p.y,
                z: p.z,
            })
    }

    /// Writes a top-down PNG of the walkable area: one pixel per column, the
    /// highest walking surface shaded by height and island, black elsewhere.
    ///
    /// # Errors
    /// [`SceneError::Io`] when the file cannot be written.
    pub fn save_topdown_png(&self, path: &Path) -> Result<(), SceneError> {
        let (w, h) = (self.width, self.height);
        let (mut zmin, mut zmax) = (f32::MAX, f32::MIN);
        for s in &self.spans {
            zmin = zmin.min(s.floor);
            zmax = zmax.max(s.floor);
        }
        let span = (zmax - zmin).max(1e-3);
        let mut img = vec![0u8; w * h * 3];
        for col in 0..w * h {
            let r = self.column_spans(col);
            if r.is_empty() {
                continue;
            }
            let s = self.spans[r.end - 1];
            let t = (s.floor - zmin) / span;
            let hue = (s.region as usize * 47) % 256;
            // flip y so that +y is up in the image (plan view)
            let (x, y) = (col % w, col / w);
            let o = ((h - 1 - y) * w + x) * 3;
            img[o] = (80.0 + 175.0 * t) as u8;
            img[o + 1] = (200 - (hue as u32 * 100 / 256) as u8) / 2 + 100;
            img[o + 2] = (255.0 - 175.0 * t) as u8;
        }
        crate::write_rgb_png(path, w as u32, h as u32, &img).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })
    }
}

/// Min-heap item for Dijkstra (distance, span).
#[derive(Clone, Copy, PartialEq)]
pub(crate) struct HeapItem(pub f64, pub u32);
impl Eq for HeapItem {}
impl Ord for HeapItem {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
    }
}
impl PartialOrd for HeapItem {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
