//! PNG figures of an evaluation (plotters, with an embedded DejaVu font so
//! that no system font is needed).

use std::sync::Once;

/// Why a figure could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// Nothing to draw.
    #[error("nothing to draw in the {0}")]
    Empty(&'static str),
    /// The drawing backend failed (for example, the file cannot be written).
    #[error("drawing failed: {0}")]
    Draw(String),
}

impl FigureError {
    pub(crate) fn draw<E: std::fmt::Display>(e: E) -> Self {
        Self::Draw(e.to_string())
    }
}

/// Registers the embedded DejaVu Sans as plotters' `sans-serif` (once).
pub fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The embedded font is valid TrueType; a failure would only lose labels.
        let _ = plotters::style::register_font(
            "sans-serif",
            plotters::style::FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

use std::path::Path;

use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use sornav_platform_sim::Outcome;

use crate::summary::{DISTANCE_BINS, VariantSummary};

const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

fn colour(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

pub(crate) type Chart<'a, 'b> =
    ChartContext<'a, BitMapBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// A 900 x 480 chart with a caption and its mesh: one slot per label on x
/// (slot `i` is `[i, i + 1)`, `labels[i]` at its centre, no vertical grid
/// lines) and `y`, described by `y_desc`, on the vertical axis.
fn frame<'a, 'b>(
    root: &'a DrawingArea<BitMapBackend<'b>, plotters::coord::Shift>,
    caption: &str,
    labels: &[&str],
    y: std::ops::Range<f64>,
    y_desc: &str,
) -> Result<Chart<'a, 'b>, FigureError> {
    root.fill(&WHITE).map_err(FigureError::draw)?;
    let mut chart = ChartBuilder::on(root)
        .caption(caption, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(48)
        .build_cartesian_2d(0.0..labels.len() as f64, y)
        .map_err(FigureError::draw)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(2 * labels.len() + 1)
        .x_label_formatter(&|x| {
            if (x - x.floor() - 0.5).abs() > 1e-6 {
                return String::new();
            }
            let i = x.floor() as usize;
            labels.get(i).map_or(String::new(), |l| (*l).to_owned())
        })
        .y_desc(y_desc)
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(FigureError::draw)?;
    Ok(chart)
}

/// The legend box, upper right, on a white background of `opacity`, with
/// `font_size` labels.
pub(crate) fn legend<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    opacity: f64,
    font_size: u32,
) -> Result<(), FigureError> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(opacity))
        .border_style(BLACK)
        .label_font(("sans-serif", font_size))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(FigureError::draw)
}

/// Grouped bars of SR, SPL, soft SPL and SR@1m (%) per variant.
///
/// # Errors
/// [`FigureError`] when `summaries` is empty or drawing fails.
pub fn metrics_bars(path: &Path, summaries: &[VariantSummary]) -> Result<(), FigureError> {
    if summaries.is_empty() {
        return Err(FigureError::Empty("metrics chart"));
    }
    register_font();
    type Metric = (&'static str, fn(&VariantSummary) -> f64);
    let metrics: [Metric; 4] = [
        ("SR", |v| v.success_rate),
        ("SPL", |v| v.spl),
        ("soft SPL", |v| v.soft_spl),
        ("SR@1m", |v| v.success_rate_1m),
    ];
    let root = BitMapBackend::new(path, (900, 480)).into_drawing_area();
    let n = summaries.len() as f64;
    let labels: Vec<&str> = metrics.iter().map(|m| m.0).collect();
    let mut chart = frame(
        &root,
        "Success and path efficiency per variant",
        &labels,
        0.0..100.0,
        "%",
    )?;
    let width = 0.8 / n;
    for (k, v) in summaries.iter().enumerate() {
        let c = colour(k);
        chart
            .draw_series(metrics.iter().enumerate().map(|(m, (_, f))| {
                let x0 = m as f64 + 0.1 + k as f64 * width + 0.5 * width - 0.5 * width * 0.9;
                Rectangle::new([(x0, 0.0), (x0 + width * 0.9, 100.0 * f(v))], c.filled())
            }))
            .map_err(FigureError::draw)?
            .label(format!("{} (n={})", v.variant, v.episodes))
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], c.filled()));
    }
    legend(&mut chart, 0.9, 13)?;
    root.present().map_err(FigureError::draw)
}

/// Same-floor success rate per initial-distance bin, with Wilson 95 %
/// intervals, per variant.
///
/// # Errors
/// [`FigureError`] when `summaries` is empty or drawing fails.
pub fn success_by_distance(path: &Path, summaries: &[VariantSummary]) -> Result<(), FigureError> {
    if summaries.is_empty() {
        return Err(FigureError::Empty("success-by-distance chart"));
    }
    register_font();
    let labels: Vec<&str> = DISTANCE_BINS.iter().map(|b| b.2).collect();
    let root = BitMapBackend::new(path, (900, 480)).into_drawing_area();
    let mut chart = frame(
        &root,
        "Same-floor success vs initial geodesic distance (Wilson 95 % CI)",
        &labels,
        0.0..100.0,
        "success rate %",
    )?;
    let n = summaries.len() as f64;
    for (k, v) in summaries.iter().enumerate() {
        let c = colour(k);
        let xs: Vec<(f64, &crate::summary::DistanceBin)> = v
            .distance_bins
            .iter()
            .enumerate()
            .filter(|(_, b)| b.episodes > 0)
            .map(|(i, b)| (i as f64 + 0.2 + 0.6 * (k as f64 + 0.5) / n, b))
            .collect();
        chart
            .draw_series(LineSeries::new(
                xs.iter().map(|(x, b)| (*x, 100.0 * b.success_rate)),
                c.stroke_width(2),
            ))
            .map_err(FigureError::draw)?
            .label(v.variant.clone())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 12, y)], c.stroke_width(2)));
        chart
            .draw_series(xs.iter().map(|(x, b)| {
                ErrorBar::new_vertical(
                    *x,
                    100.0 * b.ci95.0,
                    100.0 * b.success_rate,
                    100.0 * b.ci95.1,
                    c.stroke_width(1),
                    6,
                )
            }))
            .map_err(FigureError::draw)?;
    }
    legend(&mut chart, 0.9, 13)?;
    root.present().map_err(FigureError::draw)
}

/// Stacked bars of the outcome composition (%) per variant.
///
/// # Errors
/// [`FigureError`] when `summaries` is empty or drawing fails.
pub fn failure_composition(path: &Path, summaries: &[VariantSummary]) -> Result<(), FigureError> {
    if summaries.is_empty() {
        return Err(FigureError::Empty("failure chart"));
    }
    register_font();
    const CLASSES: [(Outcome, &str); 6] = [
        (Outcome::Success, "success"),
        (Outcome::CrossFloor, "cross-floor"),
        (Outcome::StepLimit, "step limit"),
        (Outcome::Timeout, "timeout"),
        (Outcome::FalseStop, "false stop"),
        (Outcome::Other, "other"),
    ];
    let root = BitMapBackend::new(path, (900, 480)).into_drawing_area();
    let labels: Vec<&str> = summaries.iter().map(|v| v.variant.as_str()).collect();
    let mut chart = frame(
        &root,
        "Outcome composition per variant",
        &labels,
        0.0..100.0,
        "% of episodes",
    )?;
    for (c, (key, label)) in CLASSES.iter().enumerate() {
        let colour = if *key == Outcome::Success {
            RGBColor(44, 160, 44)
        } else {
            colour(c + 2)
        };
        chart
            .draw_series(summaries.iter().enumerate().map(|(k, v)| {
                let total = v.episodes.max(1) as f64;
                let below: u64 = CLASSES[..c]
                    .iter()
                    .map(|(k2, _)| v.outcomes.get(k2.name()).copied().unwrap_or(0))
                    .sum();
                let mine = v.outcomes.get(key.name()).copied().unwrap_or(0);
                let (y0, y1) = (
                    100.0 * below as f64 / total,
                    100.0 * (below + mine) as f64 / total,
                );
                Rectangle::new(
                    [(k as f64 + 0.15, y0), (k as f64 + 0.85, y1)],
                    colour.filled(),
                )
            }))
            .map_err(FigureError::draw)?
            .label(*label)
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], colour.filled()));
    }
    legend(&mut chart, 0.9, 13)?;
    root.present().map_err(FigureError::draw)
}
