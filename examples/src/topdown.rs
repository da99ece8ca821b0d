//! Top-down maps of single episodes, like the paper's qualitative figure:
//! the agent's explored occupancy, its frontiers, the trajectory, the
//! relocation points, the goal objects and where the agent stopped.

use std::path::Path;

use plotters::prelude::*;
use serde::{Deserialize, Serialize};
use sornav::OccupancyRaster;

use crate::figures::{FigureError, legend, register_font};

/// Side of the maps in `maps/` (pixels).
pub const MAP_SIZE: u32 = 720;

/// Side of the failure maps in `maps/failures/` (pixels): smaller, since
/// every failed episode gets one.
pub const FAILURE_MAP_SIZE: u32 = 480;

/// The sub-directory of `maps/` that holds the map of every failed episode
/// (when the evaluation's `failure_maps` is positive).
pub const FAILURES_DIR: &str = "failures";

/// The file name of the map of `variant` on one episode:
/// `variant__scene__episode.png`, with every character other than ASCII
/// letters, digits, `-` and `_` replaced by `_`.
pub fn file_name(variant: &str, scene: &str, episode_id: &str) -> String {
    format!(
        "{}__{}__{}.png",
        safe(variant),
        safe(scene),
        safe(episode_id)
    )
}

/// File-name-safe text.
fn safe(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Everything drawn on one top-down map (world x/y, metres).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TopDownMap {
    /// Title line.
    pub title: String,
    /// The agent's occupancy grid at the end of the episode.
    pub occupancy: OccupancyRaster,
    /// Frontier cells at the end of the episode.
    pub frontier_cells: Vec<[f32; 2]>,
    /// Feet positions, in order.
    pub trajectory: Vec<[f32; 2]>,
    /// Relocations: (robot position, relocation waypoint).
    pub relocations: Vec<([f32; 2], [f32; 2])>,
    /// Goal objects' horizontal bounds (min, max).
    pub goals: Vec<([f32; 2], [f32; 2])>,
    /// Goal view points.
    pub view_points: Vec<[f32; 2]>,
    /// Candidate centres the agent verified.
    pub verified: Vec<[f32; 2]>,
    /// Final heading (radians), drawn at the last trajectory point.
    pub final_yaw: f64,
    /// Whether the episode succeeded (colours the end marker).
    pub success: bool,
}

impl TopDownMap {
    /// Bounds of everything drawn, with a margin.
    fn extent(&self) -> Option<((f64, f64), (f64, f64))> {
        let mut xs: Vec<f64> = Vec::new();
        let mut ys: Vec<f64> = Vec::new();
        let mut add = |p: [f32; 2]| {
            if p[0].is_finite() && p[1].is_finite() {
                xs.push(f64::from(p[0]));
                ys.push(f64::from(p[1]));
            }
        };
        for p in &self.trajectory {
            add(*p);
        }
        for (a, b) in &self.goals {
            add(*a);
            add(*b);
        }
        for (a, b) in &self.relocations {
            add(*a);
            add(*b);
        }
        let o = &self.occupancy;
        if o.width > 0 && o.height > 0 && o.resolution > 0.0 {
            add([o.origin.x as f32, o.origin.y as f32]);
            add([
                (o.origin.x + o.width as f64 * o.resolution) as f32,
                (o.origin.y + o.height as f64 * o.resolution) as f32,
            ]);
        }
        let fold = |v: &[f64]| {
            v.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                    (lo.min(x), hi.max(x))
                })
        };
        if xs.is_empty() {
            return None;
        }
        let (x0, x1) = fold(&xs);
        let (y0, y1) = fold(&ys);
        // Square extent so that metres look the same on both axes.
        let side = (x1 - x0).max(y1 - y0) + 2.0;
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        Some((
            (cx - side / 2.0, cx + side / 2.0),
            (cy - side / 2.0, cy + side / 2.0),
        ))
    }

    /// Draws the map as a PNG of `size` x `size` pixels.
    ///
    /// # Errors
    /// [`FigureError`] when there is nothing to draw or the file cannot be
    /// written.
    pub fn save_png(&self, path: &Path, size: u32) -> Result<(), FigureError> {
        register_font();
        let ((x0, x1), (y0, y1)) = self.extent().ok_or(FigureError::Empty("top-down map"))?;
        let root = BitMapBackend::new(path, (size, size + 30)).into_drawing_area();
        root.fill(&WHITE).map_err(FigureError::draw)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.title, ("sans-serif", 16))
            .margin(8)
            .x_label_area_size(28)
            .y_label_area_size(36)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(FigureError::draw)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("x (m)")
            .y_desc("y (m)")
            .label_style(("sans-serif", 11))
            .draw()
            .map_err(FigureError::draw)?;

        // Occupancy: free light grey, occupied dark grey, unknown white.
        let o = &self.occupancy;
        let half = o.resolution / 2.0;
        let free = RGBColor(222, 222, 222);
        let occupied = RGBColor(70, 70, 70);
        let cells = (0..o.height).flat_map(|r| (0..o.width).map(move |c| (r, c)));
        chart
            .draw_series(cells.filter_map(|(r, c)| {
                let colour = match o.cells.get(r * o.width + c)? {
                    1 => free,
                    2 => occupied,
                    _ => return None,
                };
                let x = o.origin.x + c as f64 * o.resolution;
                let y = o.origin.y + r as f64 * o.resolution;
                Some(Rectangle::new(
                    [(x - half, y - half), (x + half, y + half)],
                    colour.filled(),
                ))
            }))
            .map_err(FigureError::draw)?;
        let frontier = RGBColor(80, 160, 255);
        chart
            .draw_series(self.frontier_cells.iter().map(|p| {
                let (x, y) = (f64::from(p[0]), f64::from(p[1]));
                Rectangle::new(
                    [(x - half, y - half), (x + half, y + half)],
                    frontier.filled(),
                )
            }))
            .map_err(FigureError::draw)?
            .label("frontier")
            .legend(move |(x, y)| Rectangle::new([(x, y - 4), (x + 8, y + 4)], frontier.filled()));

        // Goals: view points (green dots) and object bounds (green boxes).
        let goal = RGBColor(0, 150, 60);
        chart
            .draw_series(self.view_points.iter().map(|p| {
                Circle::new(
                    (f64::from(p[0]), f64::from(p[1])),
                    1,
                    goal.mix(0.35).filled(),
                )
            }))
            .map_err(FigureError::draw)?;
        chart
            .draw_series(self.goals.iter().map(|(a, b)| {
                Rectangle::new(
                    [
                        (f64::from(a[0]), f64::from(a[1])),
                        (f64::from(b[0]), f64::from(b[1])),
                    ],
                    goal.stroke_width(2),
                )
            }))
            .map_err(FigureError::draw)?
            .label("goal object")
            .legend(move |(x, y)| {
                Rectangle::new([(x, y - 4), (x + 8, y + 4)], goal.stroke_width(2))
            });

        // Trajectory.
        let path = RGBColor(200, 30, 30);
        chart
            .draw_series(LineSeries::new(
                self.trajectory
                    .iter()
                    .map(|p| (f64::from(p[0]), f64::from(p[1]))),
                path.stroke_width(2),
            ))
            .map_err(FigureError::draw)?
            .label("trajectory")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 10, y)], path.stroke_width(2)));
        if let Some(s) = self.trajectory.first() {
            chart
                .draw_series([Circle::new(
                    (f64::from(s[0]), f64::from(s[1])),
                    5,
                    BLACK.filled(),
                )])
                .map_err(FigureError::draw)?
                .label("start")
                .legend(|(x, y)| Circle::new((x + 4, y), 4, BLACK.filled()));
        }

        // Relocations: an arrow from where it was decided to the waypoint.
        let reloc = RGBColor(150, 0, 200);
        for (a, b) in &self.relocations {
            let (a, b) = (
                (f64::from(a[0]), f64::from(a[1])),
                (f64::from(b[0]), f64::from(b[1])),
            );
            chart
                .draw_series([PathElement::new([a, b], reloc.stroke_width(2))])
                .map_err(FigureError::draw)?;
            chart
                .draw_series([TriangleMarker::new(b, 7, reloc.filled())])
                .map_err(FigureError::draw)?;
        }
        if !self.relocations.is_empty() {
            chart
                .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
                .map_err(FigureError::draw)?
                .label("relocation")
                .legend(move |(x, y)| TriangleMarker::new((x + 4, y), 5, reloc.filled()));
        }
        let check = RGBColor(255, 140, 0);
        chart
            .draw_series(
                self.verified.iter().map(|p| {
                    Cross::new((f64::from(p[0]), f64::from(p[1])), 6, check.stroke_width(2))
                }),
            )
            .map_err(FigureError::draw)?;

        // End pose with its heading (target view).
        if let Some(e) = self.trajectory.last() {
            let e = (f64::from(e[0]), f64::from(e[1]));
            let tip = (
                e.0 + 0.8 * self.final_yaw.cos(),
                e.1 + 0.8 * self.final_yaw.sin(),
            );
            let colour = if self.success { goal } else { path };
            chart
                .draw_series([PathElement::new([e, tip], colour.stroke_width(3))])
                .map_err(FigureError::draw)?;
            chart
                .draw_series([Circle::new(e, 5, colour.filled())])
                .map_err(FigureError::draw)?
                .label(if self.success { "end (success)" } else { "end" })
                .legend(move |(x, y)| Circle::new((x + 4, y), 4, colour.filled()));
        }
        legend(&mut chart, 0.85, 11)?;
        root.present().map_err(FigureError::draw)?;
        Ok(())
    }
}
