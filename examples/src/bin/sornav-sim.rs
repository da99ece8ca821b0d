//! `sornav-sim`: runs SOR-Nav and the baselines on the CPU simulator and
//! writes `summary.json`, `episodes.jsonl`, `report.md` and figures.
//!
//! With no arguments it runs the main job: the full system on a built-in set
//! of procedural houses. See `sornav-sim --help` and the README.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use clap::{Args, Parser, Subcommand};
use sornav::supervisor::LlmLatency;
use sornav::supervisor::llm::transport::ReplayTransport;
use sornav::tsp::RouteObjective;
use sornav::{AgentConfig, PolicyConfig};
use sornav_examples::adapter::{AdapterConfig, sim_agent_config};
use sornav_examples::harness::{
    self, EpisodeSource, EvalConfig, LlmSettings, RunOptions, VARIANTS,
};
use sornav_examples::scenes::parse_scene_spec;
use sornav_examples::summary::summarize;
use sornav_examples::{compare, report};
use sornav_platform_sim::{CameraConfig, NoiseConfig, NoisePreset, RunConfig};

/// Run ObjectNav evaluations of SOR-Nav and its baselines on the CPU
/// simulator (procedural houses, Sweet Home 3D homes, glTF scenes).
#[derive(Debug, Parser)]
#[command(name = "sornav-sim", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    run: RunArgs,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Merge the output directories of shards (`--shard i/n` runs) of one
    /// evaluation into one report.
    Merge {
        /// Output directory of the merged evaluation.
        #[arg(long)]
        out: PathBuf,
        /// The shards' output directories.
        #[arg(required = true)]
        shards: Vec<PathBuf>,
    },
    /// Paired comparison of two runs of the same episodes: SR and SPL
    /// differences A - B with 95 % bootstrap intervals (10 000 resamples,
    /// fixed seed) and discordant pairs, overall and by floors between start
    /// and goal. Prints the table and writes compare.json, compare.md and
    /// figures/paired_difference.png.
    Compare {
        /// Output directory of run A.
        dir_a: PathBuf,
        /// Output directory of run B (may be DIR_A with another variant).
        dir_b: PathBuf,
        /// Variant of A (needed when DIR_A holds several).
        #[arg(long, value_name = "NAME")]
        variant_a: Option<String>,
        /// Variant of B (needed when DIR_B holds several).
        #[arg(long, value_name = "NAME")]
        variant_b: Option<String>,
        /// Where to write the outputs (default DIR_A/compare-A-vs-B).
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
    },
}

#[derive(Debug, Args)]
struct RunArgs {
    /// Scenes (repeatable): `procedural:N`, `procedural-shuffled:N`, a Sweet
    /// Home 3D `.xml` / `.sh3d` file or a directory of them, a `.glb` /
    /// `.gltf`. Default: `procedural:25`.
    #[arg(long = "scenes", value_name = "SPEC")]
    scenes: Vec<String>,
    /// Sweet Home 3D model directory (default
    /// `../shared/data/sh3d-homes/models` when present).
    #[arg(long, value_name = "DIR")]
    models: Option<PathBuf>,
    /// Episodes per scene, spread over the target categories present
    /// (default 4 for the main job; unlimited when
    /// `--episodes-per-category` is given).
    #[arg(long, value_name = "N")]
    episodes_per_scene: Option<usize>,
    /// Generated episodes per target category present in a scene
    /// (default 1, or 20 per category when only this is given).
    #[arg(long, value_name = "N")]
    episodes_per_category: Option<usize>,
    /// Habitat ObjectNav JSON(.gz) episodes instead of generating; their
    /// scene ids are matched to the `--scenes` by name.
    #[arg(long, value_name = "FILE")]
    episodes: Option<PathBuf>,
    /// Target categories (comma-separated; default: HM3D's six).
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    categories: Vec<String>,
    /// Variants (comma-separated): sornav, no-gate, nearest-frontier,
    /// semantic-ranking, single-floor, no-target-gate (the first detection
    /// confirms the target), oracle. Default: sornav.
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    variants: Vec<String>,
    /// Seed of scenes, episodes and sensor noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Parallel jobs (default: the machine's cores).
    #[arg(long, value_name = "J")]
    jobs: Option<usize>,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "out/sornav-sim")]
    out: PathBuf,
    /// Sensor-noise preset: `off` (default, a perfect sensor) or
    /// `detector` (an open-vocabulary detector on a structured-light depth
    /// camera: depth noise, dropped returns, boundary label flips, missed
    /// objects, false-positive blobs). The rates and their sources are in
    /// the platform-sim README; they are recorded in run.json.
    #[arg(long, value_name = "PRESET", value_parser = parse_noise)]
    noise: Option<NoisePreset>,
    /// Sensor-noise rates from a TOML file (the fields of
    /// `sornav_platform_sim::NoiseConfig`; missing fields are off) instead
    /// of a preset; recorded in run.json as preset `custom`.
    #[arg(long, value_name = "FILE", conflicts_with = "noise")]
    noise_config: Option<PathBuf>,
    /// Sensor width in pixels (Habitat: 640).
    #[arg(long, value_name = "W", default_value_t = 640)]
    width: u32,
    /// Sensor height in pixels (Habitat: 480).
    #[arg(long, value_name = "H", default_value_t = 480)]
    height: u32,
    /// OpenAI-compatible endpoint (base URL up to `/v1`) for the `sornav`
    /// variant's LLM policy, instead of the embedded commonsense policy.
    /// Checked before the run (reachable, serving `--llm-model`). The
    /// `--llm-*` flags override only what they name: the other settings
    /// come from `[policy]` of `--config` (when it is `kind = "llm"`) or
    /// the defaults.
    #[arg(long, value_name = "URL")]
    llm: Option<String>,
    /// Model name (default `gpt-4o-mini`; with `--llm-replay`, the
    /// recording's).
    #[arg(long, value_name = "NAME")]
    llm_model: Option<String>,
    /// Environment variable holding the API key (default `OPENAI_API_KEY`;
    /// unset sends no key).
    #[arg(long, value_name = "VAR")]
    llm_key_env: Option<String>,
    /// Request timeout of the LLM policy, seconds (default 60).
    #[arg(long, value_name = "S")]
    llm_timeout: Option<f64>,
    /// Token budget of an answer (default 128).
    #[arg(long, value_name = "N")]
    llm_max_tokens: Option<u32>,
    /// Asynchronous decisions (`--llm-async`, `--llm-async=false`; default
    /// true): the agent keeps exploring while the model thinks.
    #[arg(long, value_name = "BOOL", num_args = 0..=1, default_missing_value = "true")]
    llm_async: Option<bool>,
    /// When an asynchronous answer takes effect, in simulated time:
    /// `measured` (its measured latency, recorded; the default) or
    /// `fixed:S` (S seconds whatever it took; results independent of the
    /// machine and server speed).
    #[arg(long, value_name = "measured|fixed:S", value_parser = parse_latency)]
    llm_latency: Option<LlmLatency>,
    /// Record every LLM exchange to this JSONL file.
    #[arg(long, value_name = "FILE")]
    llm_record: Option<PathBuf>,
    /// Replay LLM answers from a recording (offline, bit-for-bit; no URL
    /// needed, the model name and token budget are the recording's).
    #[arg(long, value_name = "FILE")]
    llm_replay: Option<PathBuf>,
    /// Run only shard `i` of `n` (`--shard 3/16`): work items k with
    /// k mod n = i. Combine the shards with `sornav-sim merge`.
    #[arg(long, value_name = "i/n", value_parser = parse_shard)]
    shard: Option<(usize, usize)>,
    /// Agent configuration (TOML, `sornav::AgentConfig`); variants change
    /// its policy and frontier ordering.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// What the route through the frontiers minimises: `latency` (the
    /// default: frontiers reached early) or `path_length` (the paper's
    /// TSP). Overrides only `[horizon] objective` of `--config` or the
    /// defaults; recorded in run.json's agent block.
    #[arg(long, value_name = "latency|path_length", value_parser = parse_route)]
    route: Option<RouteObjective>,
    /// Top-down maps: the first N episodes of every variant, plus up to N
    /// episodes with relocations.
    #[arg(long, value_name = "N", default_value_t = 4)]
    maps: usize,
    /// Failure analysis: save the map of every failed episode in
    /// `maps/failures/` and show up to N per variant and failure class in
    /// the report (0: none).
    #[arg(long, value_name = "N", default_value_t = harness::DEFAULT_FAILURE_MAPS)]
    failure_maps: usize,
    /// Action budget per episode.
    #[arg(long, default_value_t = 500)]
    max_actions: usize,
    /// Wall-clock budget per episode (s).
    #[arg(long, default_value_t = 120.0)]
    wall_clock: f64,
    /// Discard results already in `--out` instead of resuming.
    #[arg(long)]
    fresh: bool,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

/// Exit status of a run stopped by Ctrl-C (128 + SIGINT, as shells report).
const EXIT_INTERRUPTED: i32 = 130;

fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let (i, n) = s.split_once('/').ok_or("expected i/n, e.g. 0/4")?;
    let i: usize = i.trim().parse().map_err(|_| "i is not a number")?;
    let n: usize = n.trim().parse().map_err(|_| "n is not a number")?;
    if n == 0 || i >= n {
        return Err(format!("need 0 <= i < n, got {i}/{n}"));
    }
    Ok((i, n))
}

fn parse_noise(s: &str) -> Result<NoisePreset, String> {
    NoisePreset::from_name(s).map_err(|e| e.to_string())
}

/// The noise rates of a run and the label recorded with them (`None` for
/// a noiseless run, so its run.json is unchanged).
fn noise_settings(a: &RunArgs) -> Result<(NoiseConfig, Option<String>), String> {
    if let Some(path) = &a.noise_config {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("--noise-config {}: {e}", path.display()))?;
        let rates: NoiseConfig =
            toml::from_str(&text).map_err(|e| format!("--noise-config {}: {e}", path.display()))?;
        rates
            .validate()
            .map_err(|e| format!("--noise-config {}: {e}", path.display()))?;
        return Ok((rates, Some(harness::CUSTOM_NOISE.to_owned())));
    }
    match a.noise.unwrap_or_default() {
        NoisePreset::Off => Ok((NoiseConfig::default(), None)),
        p => Ok((p.config(), Some(p.name().to_owned()))),
    }
}

fn parse_latency(s: &str) -> Result<LlmLatency, String> {
    match LlmLatency::parse(s) {
        Ok(LlmLatency::Arrival) => Err(
            "arrival (wall-clock) latency would make results depend on the machine: use measured or fixed:S"
                .into(),
        ),
        Ok(l) => Ok(l),
        Err(e) => Err(e.to_string()),
    }
}

/// `--route`: `latency` or `path_length` (`[horizon] objective`'s names).
fn parse_route(s: &str) -> Result<RouteObjective, String> {
    match s {
        "latency" => Ok(RouteObjective::Latency),
        "path_length" => Ok(RouteObjective::PathLength),
        other => Err(format!(
            "unknown route objective '{other}' (latency or path_length)"
        )),
    }
}

/// The LLM settings of a run: `[policy]` of the agent configuration when
/// it is an LLM policy (else the defaults), overridden by the `--llm-*`
/// flags given; `None` without any LLM.
fn llm_settings(a: &RunArgs, agent: &AgentConfig) -> Result<Option<LlmSettings>, String> {
    let from_config = match &agent.policy {
        PolicyConfig::Llm(c) => Some(c.clone()),
        _ => None,
    };
    if a.llm.is_none() && a.llm_replay.is_none() && from_config.is_none() {
        let named = a.llm_record.is_some()
            || a.llm_model.is_some()
            || a.llm_key_env.is_some()
            || a.llm_timeout.is_some()
            || a.llm_max_tokens.is_some()
            || a.llm_async.is_some()
            || a.llm_latency.is_some();
        if named {
            return Err("the --llm-* flags need --llm URL, --llm-replay FILE or [policy] kind = \"llm\" in --config".into());
        }
        return Ok(None);
    }
    if a.llm_record.is_some() && a.llm_replay.is_some() {
        return Err("--llm-record and --llm-replay exclude each other".into());
    }
    let mut config = from_config.unwrap_or_default();
    if let Some(url) = &a.llm {
        config.base_url = url.clone();
    }
    if let Some(replay) = &a.llm_replay {
        let recording = ReplayTransport::open(replay).map_err(|e| e.to_string())?;
        let recorded = recording.recorded_settings().ok_or_else(|| {
            format!(
                "{}: not a recording of LLM exchanges (no request in it)",
                replay.display()
            )
        })?;
        config.model = recorded.model;
        config.temperature = recorded.temperature;
        config.max_tokens = recorded.max_tokens;
    }
    if let Some(m) = &a.llm_model {
        config.model = m.clone();
    }
    if let Some(k) = &a.llm_key_env {
        config.api_key_env = Some(k.clone());
    }
    if let Some(t) = a.llm_timeout {
        config.timeout_s = t;
    }
    if let Some(n) = a.llm_max_tokens {
        config.max_tokens = Some(n);
    }
    if let Some(b) = a.llm_async {
        config.asynchronous = b;
    }
    match a.llm_latency {
        Some(l) => config.latency = l,
        // The simulator's clock is simulated: never wall-clock arrival.
        None if config.latency == LlmLatency::Arrival => config.latency = LlmLatency::Measured,
        None => {}
    }
    config
        .validate()
        .map_err(|e| format!("LLM settings: {e}"))?;
    Ok(Some(LlmSettings {
        config,
        record: a.llm_record.clone(),
        replay: a.llm_replay.clone(),
    }))
}

fn default_models() -> Option<PathBuf> {
    let p = std::env::var_os("SORNAV_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("../shared"))
        .join("data/sh3d-homes/models");
    p.is_dir().then_some(p)
}

fn eval_config(a: &RunArgs) -> Result<EvalConfig, String> {
    let specs = if a.scenes.is_empty() {
        vec!["procedural:25".to_owned()]
    } else {
        a.scenes.clone()
    };
    let mut scenes = Vec::new();
    for s in &specs {
        scenes.extend(parse_scene_spec(s, a.seed).map_err(|e| e.to_string())?);
    }
    let episodes = match &a.episodes {
        Some(path) => EpisodeSource::File { path: path.clone() },
        None => EpisodeSource::Generate {
            per_category: a
                .episodes_per_category
                .unwrap_or(if a.episodes_per_scene.is_some() {
                    20
                } else {
                    1
                }),
            per_scene: match (a.episodes_per_scene, a.episodes_per_category) {
                (Some(n), _) => Some(n),
                (None, Some(_)) => None,
                (None, None) => Some(4),
            },
        },
    };
    let categories = if a.categories.is_empty() {
        sornav_platform_sim::category::HM3D_GOALS
            .iter()
            .map(|c| (*c).to_owned())
            .collect()
    } else {
        a.categories.clone()
    };
    let variants = if a.variants.is_empty() {
        vec!["sornav".to_owned()]
    } else {
        a.variants.clone()
    };
    for v in &variants {
        if !VARIANTS.contains(&v.as_str()) {
            return Err(format!(
                "unknown variant '{v}' (known: {})",
                VARIANTS.join(", ")
            ));
        }
    }
    let mut agent = match &a.config {
        Some(path) => AgentConfig::from_toml_file(path).map_err(|e| e.to_string())?,
        None => sim_agent_config(),
    };
    if let Some(route) = a.route {
        agent.horizon.objective = route;
    }
    let llm = llm_settings(a, &agent)?;
    let (noise, noise_preset) = noise_settings(a)?;
    Ok(EvalConfig {
        scenes,
        models: a.models.clone().or_else(default_models),
        episodes,
        categories,
        variants,
        seed: a.seed,
        camera: CameraConfig {
            width: a.width,
            height: a.height,
            noise,
            ..CameraConfig::default()
        },
        noise_preset,
        run: RunConfig {
            max_actions: a.max_actions,
            wall_clock_s: a.wall_clock,
            ..RunConfig::default()
        },
        adapter: AdapterConfig::default(),
        agent,
        llm,
        maps: a.maps,
        failure_maps: a.failure_maps,
    })
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| {
                tracing_subscriber::EnvFilter::new("warn,sornav_examples=info")
            }),
        )
        .with_writer(std::io::stderr)
        .init();
    let cli = Cli::parse();
    match cli.command {
        Some(Command::Merge { out, shards }) => match harness::merge(&out, &shards) {
            Ok(report_path) => {
                let records =
                    harness::read_records(&out.join("episodes.jsonl")).unwrap_or_default();
                let config: Option<EvalConfig> = std::fs::read_to_string(out.join("run.json"))
                    .ok()
                    .and_then(|t| serde_json::from_str(&t).ok());
                if let Some(c) = config {
                    println!("{}", report::table(&summarize(&records, &c.variants)));
                }
                println!(
                    "merged {} records; report: {}",
                    records.len(),
                    report_path.display()
                );
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("sornav-sim merge: {e}");
                ExitCode::FAILURE
            }
        },
        Some(Command::Compare {
            dir_a,
            dir_b,
            variant_a,
            variant_b,
            out,
        }) => {
            let c = match compare::compare(
                &dir_a,
                variant_a.as_deref(),
                &dir_b,
                variant_b.as_deref(),
            ) {
                Ok(c) => c,
                Err(e) => {
                    eprintln!("sornav-sim compare: {e}");
                    return ExitCode::FAILURE;
                }
            };
            println!("{}", c.markdown());
            let out = out.unwrap_or_else(|| {
                dir_a.join(format!("compare-{}-vs-{}", c.variant_a, c.variant_b))
            });
            match c.write(&out) {
                Ok(md) => {
                    println!("written: {}", md.display());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("sornav-sim compare: {e}");
                    ExitCode::FAILURE
                }
            }
        }
        None => {
            let config = match eval_config(&cli.run) {
                Ok(c) => c,
                Err(e) => {
                    eprintln!("sornav-sim: {e}");
                    return ExitCode::from(2);
                }
            };
            let stop = Arc::new(AtomicBool::new(false));
            let options = RunOptions {
                out: cli.run.out.clone(),
                jobs: cli.run.jobs.unwrap_or_else(|| {
                    std::thread::available_parallelism()
                        .map_or(1, std::num::NonZero::get)
                        .min(harness::MAX_JOBS)
                }),
                shard: cli.run.shard,
                fresh: cli.run.fresh,
                progress: !cli.run.quiet,
                stop: Some(Arc::clone(&stop)),
            };
            if let Err(e) = config
                .validate()
                .and_then(|()| options.validate())
                .and_then(|()| harness::check_llm(&config))
            {
                eprintln!("sornav-sim: {e}");
                return ExitCode::from(2);
            }
            // First Ctrl-C: finish the episodes running, write the report;
            // a second one ends the process at once.
            let flag = Arc::clone(&stop);
            let handler = ctrlc::set_handler(move || {
                if flag.swap(true, Ordering::SeqCst) {
                    eprintln!("sornav-sim: interrupted again; exiting without a report");
                    std::process::exit(EXIT_INTERRUPTED);
                }
                eprintln!(
                    "sornav-sim: interrupted; finishing the episodes running (Ctrl-C again to quit at once)"
                );
            });
            if let Err(e) = handler {
                tracing::warn!(
                    "no Ctrl-C handler ({e}); an interrupt ends the run without a report"
                );
            }
            match harness::run(&config, &options) {
                Ok(outcome) => {
                    let records = harness::read_records(&options.out.join("episodes.jsonl"))
                        .unwrap_or_default();
                    println!("{}", report::table(&summarize(&records, &config.variants)));
                    println!(
                        "{} episodes run ({} already done{}) in {:.1} s; report: {}",
                        outcome.ran,
                        outcome.skipped,
                        if outcome.failed > 0 {
                            format!(", {} failed to start", outcome.failed)
                        } else {
                            String::new()
                        },
                        outcome.wall_s,
                        outcome.report.display()
                    );
                    if outcome.interrupted {
                        eprintln!(
                            "sornav-sim: interrupted: {} episodes recorded, {} not started; run the same command again to resume",
                            outcome.ran, outcome.not_started
                        );
                        return ExitCode::from(EXIT_INTERRUPTED as u8);
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("sornav-sim: {e}");
                    ExitCode::FAILURE
                }
            }
        }
    }
}
