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
    /// The drawn file could not be put in place.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
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

use crate::summary::{DISTANCE_BINS, FLOOR_BINS, OUTCOME_CLASSES, VariantSummary, wilson};

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

/// One bar of [`grouped_bars`]: value and optional interval (both in %).
type Bar = (f64, Option<(f64, f64)>);

/// Grouped bars: one group per label, one bar per series (name, bars),
/// with error bars where an interval is given.
fn grouped_bars(
    path: &Path,
    caption: &str,
    labels: &[&str],
    series: &[(String, Vec<Bar>)],
    y: std::ops::Range<f64>,
    y_desc: &str,
) -> Result<(), FigureError> {
    register_font();
    let root = BitMapBackend::new(path, (900, 480)).into_drawing_area();
    let mut chart = frame(&root, caption, labels, y, y_desc)?;
    let width = 0.8 / series.len().max(1) as f64;
    for (k, (name, bars)) in series.iter().enumerate() {
        let c = colour(k);
        let x0 = |m: usize| m as f64 + 0.1 + k as f64 * width + 0.5 * width - 0.5 * width * 0.9;
        chart
            .draw_series(bars.iter().enumerate().map(|(m, (v, _))| {
                Rectangle::new([(x0(m), 0.0), (x0(m) + width * 0.9, *v)], c.filled())
            }))
            .map_err(FigureError::draw)?
            .label(name.clone())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], c.filled()));
        chart
            .draw_series(bars.iter().enumerate().filter_map(|(m, (v, ci))| {
                let (lo, hi) = (*ci)?;
                Some(ErrorBar::new_vertical(
                    x0(m) + width * 0.45,
                    lo,
                    *v,
                    hi,
                    BLACK.stroke_width(1),
                    6,
                ))
            }))
            .map_err(FigureError::draw)?;
    }
    legend(&mut chart, 0.9, 13)?;
    root.present().map_err(FigureError::draw)
}

fn pct_ci(ci: (f64, f64)) -> Option<(f64, f64)> {
    Some((100.0 * ci.0, 100.0 * ci.1))
}

/// Grouped bars of SR, SPL, soft SPL and SR@1m (%) per variant, with
/// Wilson 95 % error bars on the rates (SR, SR@1m).
///
/// # Errors
/// [`FigureError`] when `summaries` is empty or drawing fails.
pub fn metrics_bars(path: &Path, summaries: &[VariantSummary]) -> Result<(), FigureError> {
    if summaries.is_empty() {
        return Err(FigureError::Empty("metrics chart"));
    }
    let series: Vec<(String, Vec<Bar>)> = summaries
        .iter()
        .map(|v| {
            (
                format!("{} (n={})", v.variant, v.episodes),
                vec![
                    (100.0 * v.success_rate, pct_ci(v.success_rate_ci95)),
                    (100.0 * v.spl, None),
                    (100.0 * v.soft_spl, None),
                    (100.0 * v.success_rate_1m, pct_ci(v.success_rate_1m_ci95)),
                ],
            )
        })
        .collect();
    grouped_bars(
        path,
        "Success and path efficiency per variant (Wilson 95 % CI on rates)",
        &["SR", "SPL", "soft SPL", "SR@1m"],
        &series,
        0.0..100.0,
        "%",
    )
}

/// Success rate by floors between start and goal (0, 1, 2+), with Wilson
/// 95 % intervals, per variant (empty bins are drawn empty).
///
/// # Errors
/// [`FigureError`] when `summaries` is empty or drawing fails.
pub fn success_by_floors(path: &Path, summaries: &[VariantSummary]) -> Result<(), FigureError> {
    if summaries.is_empty() {
        return Err(FigureError::Empty("success-by-floors chart"));
    }
    let labels: Vec<String> = FLOOR_BINS
        .iter()
        .map(|b| format!("{} floors between", b.2))
        .collect();
    let labels: Vec<&str> = labels.iter().map(String::as_str).collect();
    let series: Vec<(String, Vec<Bar>)> = summaries
        .iter()
        .map(|v| {
            let bars = v
                .by_floors
                .iter()
                .map(|b| {
                    if b.episodes == 0 {
                        (0.0, None)
                    } else {
                        (100.0 * b.success_rate, pct_ci(b.ci95))
                    }
                })
                .collect();
            (v.variant.clone(), bars)
        })
        .collect();
    grouped_bars(
        path,
        "Success by floors between start and goal (Wilson 95 % CI)",
        &labels,
        &series,
        0.0..100.0,
        "success rate %",
    )
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

/// The share of each outcome class (%) per variant, as grouped bars with
/// Wilson 95 % error bars, and the share of cross-floor episodes (a flag
/// apart from the outcome).
///
/// # Errors
/// [`FigureError`] when `summaries` is empty or drawing fails.
pub fn failure_composition(path: &Path, summaries: &[VariantSummary]) -> Result<(), FigureError> {
    if summaries.is_empty() {
        return Err(FigureError::Empty("failure chart"));
    }
    let mut labels: Vec<&str> = OUTCOME_CLASSES.iter().map(|c| c.1).collect();
    labels.push("cross-floor episodes");
    let series: Vec<(String, Vec<Bar>)> = summaries
        .iter()
        .map(|v| {
            let n = v.episodes;
            let share = |k: u64| {
                (
                    100.0 * k as f64 / n.max(1) as f64,
                    pct_ci(wilson(k, n, 1.96)),
                )
            };
            let mut bars: Vec<Bar> = OUTCOME_CLASSES
                .iter()
                .map(|(o, _)| share(v.outcomes.get(o.name()).copied().unwrap_or(0)))
                .collect();
            bars.push(share(v.cross_floor_episodes));
            (format!("{} (n={n})", v.variant), bars)
        })
        .collect();
    grouped_bars(
        path,
        "Outcomes per variant (Wilson 95 % CI)",
        &labels,
        &series,
        0.0..100.0,
        "% of episodes",
    )
}

/// The paired differences A - B of SR and SPL (percentage points) overall
/// and by floors between start and goal, with their 95 % bootstrap
/// intervals ([`crate::compare`]).
///
/// # Errors
/// [`FigureError`] when drawing fails.
pub fn paired_difference(
    path: &Path,
    comparison: &crate::compare::Comparison,
) -> Result<(), FigureError> {
    let mut groups = vec![("all".to_owned(), &comparison.overall)];
    groups.extend(
        comparison
            .by_floors
            .iter()
            .map(|f| (format!("{} floors", f.floors), &f.stats)),
    );
    let labels: Vec<String> = groups
        .iter()
        .map(|(l, s)| format!("{l} (n={})", s.episodes))
        .collect();
    let labels: Vec<&str> = labels.iter().map(String::as_str).collect();
    let bar = |d: &crate::compare::Difference, n: u64| -> Bar {
        if n == 0 {
            (0.0, None)
        } else {
            (
                100.0 * d.estimate,
                Some((100.0 * d.ci95.0, 100.0 * d.ci95.1)),
            )
        }
    };
    let series: Vec<(String, Vec<Bar>)> = vec![
        (
            "SR A - B".to_owned(),
            groups
                .iter()
                .map(|(_, s)| bar(&s.success_rate_diff, s.episodes))
                .collect(),
        ),
        (
            "SPL A - B".to_owned(),
            groups
                .iter()
                .map(|(_, s)| bar(&s.spl_diff, s.episodes))
                .collect(),
        ),
    ];
    let extreme = series
        .iter()
        .flat_map(|(_, b)| b.iter())
        .flat_map(|(v, ci)| [v.abs(), ci.map_or(0.0, |c| c.0.abs().max(c.1.abs()))])
        .fold(5.0f64, f64::max);
    let y = (extreme * 1.15).min(100.0);
    grouped_bars(
        path,
        &format!(
            "Paired difference {} - {} (95 % bootstrap CI)",
            comparison.variant_a, comparison.variant_b
        ),
        &labels,
        &series,
        -y..y,
        "percentage points",
    )
}
