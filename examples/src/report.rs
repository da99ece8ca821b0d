//! The output files of an evaluation: `summary.json`, `report.md` and the
//! PNG figures (`episodes.jsonl` and the maps are written while running).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::figures::{self, FigureError};
use crate::harness::EvalConfig;
use crate::output::{self, OutputError};
use crate::record::EpisodeRecord;
use crate::summary::{DISTANCE_BINS, FLOOR_BINS, VariantSummary, summarize};

/// Why the report could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A file could not be written.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The system's message.
        message: String,
    },
    /// A figure could not be drawn.
    #[error(transparent)]
    Figure(#[from] FigureError),
    /// A file could not be written (atomically: the old one is kept).
    #[error(transparent)]
    Output(#[from] OutputError),
}

fn io(path: &Path, e: impl std::fmt::Display) -> ReportError {
    ReportError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// `summary.json`: the first variant's figures at the top level (so that
/// `jq .success_rate summary.json` works for single-variant runs), every
/// variant under `variants`, and the run's settings.
#[derive(Debug, Serialize)]
struct SummaryFile<'a> {
    #[serde(flatten)]
    primary: Option<&'a VariantSummary>,
    variants: &'a [VariantSummary],
    /// Wall time of the run that wrote the file (s); absent after a merge.
    run_wall_s: Option<f64>,
    scenes: usize,
    distinct_episodes: usize,
    width: u32,
    height: u32,
    seed: u64,
    /// The sensor-noise preset (`--noise`), absent for a noiseless run.
    #[serde(skip_serializing_if = "Option::is_none")]
    noise: Option<&'a str>,
}

fn pct(x: f64) -> String {
    format!("{:.1}", 100.0 * x)
}

/// Writes `summary.json`, `report.md` and the figures into `dir`, each
/// atomically (see [`crate::output`]); returns the report's path.
///
/// # Errors
/// [`ReportError`] for I/O and drawing failures.
pub fn write(
    dir: &Path,
    config: &EvalConfig,
    records: &[EpisodeRecord],
    run_wall_s: Option<f64>,
) -> Result<PathBuf, ReportError> {
    let summaries = summarize(records, &config.variants);
    let distinct: std::collections::BTreeSet<(&str, &str)> = records
        .iter()
        .map(|r| (r.result.scene_id.as_str(), r.result.episode_id.as_str()))
        .collect();
    let scenes: std::collections::BTreeSet<&str> =
        records.iter().map(|r| r.result.scene_id.as_str()).collect();
    let summary = SummaryFile {
        primary: summaries.first(),
        variants: &summaries,
        run_wall_s,
        scenes: scenes.len(),
        distinct_episodes: distinct.len(),
        width: config.camera.width,
        height: config.camera.height,
        seed: config.seed,
        noise: config.noise_preset.as_deref(),
    };
    let path = dir.join("summary.json");
    let text = serde_json::to_string_pretty(&summary).map_err(|e| io(&path, e))?;
    output::write_file(&path, text.as_bytes())?;

    let figs = dir.join("figures");
    std::fs::create_dir_all(&figs).map_err(|e| io(&figs, e))?;
    let mut drawn = Vec::new();
    if !summaries.is_empty() {
        let draw = |name: &str, figure: fn(&Path, &[VariantSummary]) -> Result<(), FigureError>| {
            output::replace_with(&figs.join(name), |tmp| figure(tmp, &summaries))
        };
        draw("metrics.png", figures::metrics_bars)?;
        draw("success_by_distance.png", figures::success_by_distance)?;
        draw("failures.png", figures::failure_composition)?;
        draw("success_by_floors.png", figures::success_by_floors)?;
        drawn.extend([
            "metrics.png",
            "success_by_distance.png",
            "success_by_floors.png",
            "failures.png",
        ]);
    }

    let md = markdown(config, records, &summaries, run_wall_s, &drawn, dir);
    let path = dir.join("report.md");
    output::write_file(&path, md.as_bytes())?;
    Ok(path)
}

/// The summary table printed on stdout and in the report.
pub fn table(summaries: &[VariantSummary]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| variant | episodes | SR % (95% CI) | SPL % | soft SPL % | SR@1m % | same-floor SR % | step limit % | timeout % | false stop % | other % | cross-floor episodes % | relocating episodes % | mean actions | missions / episode | collisions / m | decision ms p50 / p99 | frame ms p50 | s / episode |"
    );
    let _ = writeln!(
        s,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for v in summaries {
        let _ = writeln!(
            s,
            "| {} | {} | {} ({}-{}) | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.0} | {:.0} | {:.2} | {:.2} / {:.2} | {:.2} | {:.2} |",
            v.variant,
            v.episodes,
            pct(v.success_rate),
            pct(v.success_rate_ci95.0),
            pct(v.success_rate_ci95.1),
            pct(v.spl),
            pct(v.soft_spl),
            pct(v.success_rate_1m),
            pct(v.same_floor_success_rate),
            pct(v.step_limit_rate),
            pct(v.timeout_rate),
            pct(v.false_stop_rate),
            pct(v.other_rate),
            pct(v.cross_floor_rate),
            pct(v.relocation_rate),
            v.mean_actions,
            v.mean_missions,
            v.collisions_per_m,
            v.decision_ms_p50,
            v.decision_ms_p99,
            v.frame_ms_p50,
            v.episode_wall_s_mean,
        );
    }
    if summaries.iter().any(|v| v.llm.is_some()) {
        let _ = writeln!(
            s,
            "\n| variant | LLM requests | valid answers (%) | fallbacks by cause | dropped late | latency ms p50 / p99 | prompt tokens / request | completion tokens |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
        for v in summaries {
            let Some(l) = &v.llm else { continue };
            let causes: Vec<String> = l
                .fallbacks_by_cause
                .iter()
                .map(|(c, n)| format!("{c} {n}"))
                .collect();
            let _ = writeln!(
                s,
                "| {} | {}{} | {} ({}) | {} | {} | {:.0} / {:.0} | {:.0} | {} |",
                v.variant,
                l.requests,
                if l.json_object_fallback {
                    " (json_object)"
                } else {
                    ""
                },
                l.valid,
                pct(l.valid_rate),
                if causes.is_empty() {
                    "none".to_owned()
                } else {
                    causes.join(", ")
                },
                l.dropped_late_answers,
                l.latency_ms_p50,
                l.latency_ms_p99,
                l.prompt_tokens_per_request,
                l.completion_tokens,
            );
        }
    }
    s
}

fn markdown(
    config: &EvalConfig,
    records: &[EpisodeRecord],
    summaries: &[VariantSummary],
    run_wall_s: Option<f64>,
    figures: &[&str],
    dir: &Path,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# sornav-sim report\n");
    let scenes: std::collections::BTreeSet<&str> =
        records.iter().map(|r| r.result.scene_id.as_str()).collect();
    let _ = writeln!(
        s,
        "{} records over {} scenes; sensor {}x{} (HFOV {} deg, depth {}-{} m); {} actions max, {} s wall-clock budget; seed {}.{}\n",
        records.len(),
        scenes.len(),
        config.camera.width,
        config.camera.height,
        config.camera.hfov_deg,
        config.camera.min_depth,
        config.camera.max_depth,
        config.run.max_actions,
        config.run.wall_clock_s,
        config.seed,
        run_wall_s.map_or(String::new(), |w| format!(" This run took {w:.0} s.")),
    );
    if let Some(preset) = &config.noise_preset {
        let n = &config.camera.noise;
        let _ = writeln!(
            s,
            "Sensor noise `{preset}`: depth sigma {} z^2 m, {} % dropped returns, {} % boundary label flips, {} % of the objects in view missed per frame, a false-positive blob in {} % of the frames (radius {} of the width).\n",
            n.depth_sigma,
            100.0 * n.missing_rate,
            100.0 * n.boundary_flip_rate,
            100.0 * n.missed_detection_rate,
            100.0 * n.false_positive_rate,
            n.false_positive_radius,
        );
    }
    let _ = writeln!(
        s,
        "Success (SR) is Habitat's: STOP within 0.1 m (geodesic) of a goal view point. SR@1m: STOP within 1 m of a goal object (the paper's boundary). Rates in %, CI = Wilson 95 %. Failure classes (the cause) are exclusive, in the order step limit, timeout, false stop, other. Cross-floor is a flag apart from the cause: the goal view point nearest to the start lies on another navmesh level than the start (levels: large walkable surfaces at one height, numbered from the lowest; floors between = |goal level - start level|).\n"
    );
    let _ = writeln!(s, "## Results\n\n{}", table(summaries));
    for f in figures {
        let _ = writeln!(s, "![{f}](figures/{f})\n");
    }

    let _ = writeln!(s, "## Same-floor success by initial geodesic distance\n");
    let mut header = "| variant |".to_owned();
    for (_, _, label) in DISTANCE_BINS {
        let _ = write!(header, " {label}: SR % [95% CI] (n) / SPL % |");
    }
    let _ = writeln!(s, "{header}");
    let _ = writeln!(s, "|---|{}", "---|".repeat(DISTANCE_BINS.len()));
    for v in summaries {
        let mut row = format!("| {} |", v.variant);
        for b in &v.distance_bins {
            let _ = write!(
                row,
                " {} [{}-{}] ({}) / {} |",
                pct(b.success_rate),
                pct(b.ci95.0),
                pct(b.ci95.1),
                b.episodes,
                pct(b.spl)
            );
        }
        let _ = writeln!(s, "{row}");
    }

    let _ = writeln!(s, "\n## By floors between start and goal\n");
    let mut header = "| variant |".to_owned();
    for (_, _, label) in FLOOR_BINS {
        let _ = write!(header, " {label} floors: SR % [95% CI] (n) / SPL % |");
    }
    let _ = writeln!(s, "{header}");
    let _ = writeln!(s, "|---|{}", "---|".repeat(FLOOR_BINS.len()));
    for v in summaries {
        let mut row = format!("| {} |", v.variant);
        for b in &v.by_floors {
            let _ = write!(
                row,
                " {} [{}-{}] ({}) / {} |",
                pct(b.success_rate),
                pct(b.ci95.0),
                pct(b.ci95.1),
                b.episodes,
                pct(b.spl)
            );
        }
        let _ = writeln!(s, "{row}");
    }
    let _ = writeln!(s);
    for v in summaries {
        let mut causes = String::new();
        for r in records
            .iter()
            .filter(|r| r.variant == v.variant && r.result.cross_floor && !r.result.success)
        {
            let _ = write!(causes, "{} ", r.result.outcome.name());
        }
        let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
        for c in causes.split_whitespace() {
            *counts.entry(c).or_insert(0) += 1;
        }
        let list: Vec<String> = counts.iter().map(|(c, n)| format!("{c} {n}")).collect();
        let _ = writeln!(
            s,
            "- {}: {} cross-floor episodes, SR {} %; their failures by cause: {}",
            v.variant,
            v.cross_floor_episodes,
            pct(v.cross_floor_success_rate),
            if list.is_empty() {
                "none".to_owned()
            } else {
                list.join(", ")
            }
        );
    }

    // Where the gate acted: episodes with relocations, against the same
    // episode without the gate.
    let by_key: BTreeMap<(&str, &str, &str), &EpisodeRecord> = records
        .iter()
        .map(|r| {
            (
                (
                    r.variant.as_str(),
                    r.result.scene_id.as_str(),
                    r.result.episode_id.as_str(),
                ),
                r,
            )
        })
        .collect();
    let relocated: Vec<&EpisodeRecord> = records
        .iter()
        .filter(|r| r.variant == "sornav" && !r.relocations.is_empty())
        .collect();
    if records.iter().any(|r| r.variant == "sornav") {
        let _ = writeln!(s, "\n## Where the context gate acted\n");
        let total = records.iter().filter(|r| r.variant == "sornav").count();
        let _ = writeln!(
            s,
            "The full system relocated in {} of {} episodes.",
            relocated.len(),
            total
        );
        let mut paired = (0, 0, 0, 0); // helped, hurt, both succeeded, both failed
        let mut rows = String::new();
        for r in &relocated {
            let base = by_key.get(&(
                "no-gate",
                r.result.scene_id.as_str(),
                r.result.episode_id.as_str(),
            ));
            let verdict = match base {
                Some(b) if r.result.success && !b.result.success => {
                    paired.0 += 1;
                    "helped"
                }
                Some(b) if !r.result.success && b.result.success => {
                    paired.1 += 1;
                    "hurt"
                }
                Some(b) if r.result.success => {
                    paired.2 += 1;
                    if r.result.spl >= b.result.spl {
                        "both succeed (SPL not worse)"
                    } else {
                        "both succeed (SPL worse)"
                    }
                }
                Some(_) => {
                    paired.3 += 1;
                    "both fail"
                }
                None => "no no-gate run",
            };
            let reason = r
                .decisions
                .runs()
                .iter()
                .find(|d| d.action == "relocate")
                .map_or(String::new(), |d| d.reason.replace('|', "/"));
            let _ = writeln!(
                rows,
                "| {} | {} | {} | {} | {} | {} | {} |",
                r.result.scene_id,
                r.result.episode_id,
                r.result.object_category,
                r.relocations.len(),
                r.result.outcome.name(),
                verdict,
                reason
            );
        }
        if relocated.iter().any(|r| {
            by_key.contains_key(&(
                "no-gate",
                r.result.scene_id.as_str(),
                r.result.episode_id.as_str(),
            ))
        }) {
            let _ = writeln!(
                s,
                " Against the same episodes without the gate (`no-gate`): relocation helped in {}, hurt in {}, both succeeded in {}, both failed in {}.",
                paired.0, paired.1, paired.2, paired.3
            );
        }
        if !rows.is_empty() {
            let _ = writeln!(
                s,
                "\n| scene | episode | target | relocations | outcome | vs no-gate | first relocation reason |\n|---|---|---|---|---|---|---|\n{rows}"
            );
        }
    }

    s.push_str(&crate::failure_analysis::section(config, records, dir));

    // Maps.
    if let Ok(entries) = std::fs::read_dir(dir.join("maps")) {
        let mut maps: Vec<String> = entries
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".png"))
            .collect();
        maps.sort();
        if !maps.is_empty() {
            let _ = writeln!(
                s,
                "\n## Top-down maps\n\nThe agent's explored occupancy (light grey free, dark occupied), its remaining frontiers (blue), the trajectory (red, start black), relocations (purple arrows to the relocation waypoint), verified candidates (orange crosses), the goal objects (green boxes) with their view points (green dots), and the final pose with its heading.\n"
            );
            for m in maps {
                let _ = writeln!(s, "![{m}](maps/{m})");
            }
        }
    }
    s
}
