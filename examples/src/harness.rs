//! The evaluation harness behind `sornav-sim`: scenes, episodes, variants,
//! parallel runs with resume and sharding, and the output directory.
//!
//! An evaluation is described by an [`EvalConfig`] (everything that decides
//! the results; written to `run.json`) and run with [`RunOptions`] (how:
//! jobs, shard, output directory). Every (variant, episode) pair is one
//! work item; results are appended to `episodes.jsonl` as they finish, so a
//! run that is interrupted resumes where it stopped, and shards of one
//! evaluation ([`RunOptions::shard`]) are combined by [`merge`].

use std::collections::{BTreeSet, HashSet};
use std::fs::{File, OpenOptions};
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sornav::supervisor::LlmConfig;
use sornav::supervisor::llm::transport::{
    EndpointError, HttpTransport, RecordingTransport, ReplayTransport, Transport, check_endpoint,
};
use sornav::{AgentConfig, AgentError, BoxedPolicy, PolicyConfig, Variant};
use sornav_platform_sim::episodes::{GeneratorConfig, HabitatDataset, generate_episodes};
use sornav_platform_sim::{
    CameraConfig, Episode, NoisePreset, Oracle, RunConfig, Simulator, run_episode,
};

use crate::adapter::{AdapterConfig, ConfigFactory, EpisodeTrace, SornavPolicy};
use crate::figures::FigureError;
use crate::output::{self, OutputError};
use crate::record::EpisodeRecord;
use crate::report::{self, ReportError};
use crate::scenes::{SceneSource, SceneSpecError};
use crate::topdown::{self, TopDownMap};

/// Errors of an evaluation.
#[derive(Debug, thiserror::Error)]
pub enum HarnessError {
    /// A scene could not be used.
    #[error(transparent)]
    Scene(#[from] SceneSpecError),
    /// A file could not be read or written.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The system's message.
        message: String,
    },
    /// `episodes.jsonl` or `run.json` is malformed.
    #[error("{path}, line {line}: {message}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// Line number (1-based; 0 for a whole-file problem).
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// `episodes.jsonl` was written before floors were recorded (a
    /// `cross_floor` outcome, no `floors_between`): refused, since the
    /// failure cause of its cross-floor episodes was not recorded.
    #[error(
        "{path}, line {line}: written by an older sornav-sim (cross-floor recorded as an outcome, no floor levels); its results cannot be mixed with the current metrics: re-run into a new --out (or with --fresh)"
    )]
    LegacyRecords {
        /// The file.
        path: PathBuf,
        /// Line number (1-based).
        line: usize,
    },
    /// The output directory holds a different evaluation.
    #[error(
        "{0} holds results of a different evaluation (run.json differs); use another --out, or --fresh to discard them"
    )]
    DifferentRun(PathBuf),
    /// Invalid settings.
    #[error("invalid settings: {0}")]
    Config(String),
    /// The LLM endpoint failed the startup check.
    #[error(transparent)]
    LlmEndpoint(#[from] EndpointError),
    /// Episode generation or reading failed.
    #[error("episodes of {scene}: {message}")]
    Episodes {
        /// The scene.
        scene: String,
        /// Why.
        message: String,
    },
    /// The agent could not be configured.
    #[error(transparent)]
    Agent(#[from] AgentError),
    /// Writing the report failed.
    #[error(transparent)]
    Report(#[from] ReportError),
    /// The output directory is locked by another run, or a file of it could
    /// not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// Two episodes of one scene share an episode id (results are keyed
    /// by variant, scene and episode id).
    #[error(
        "episodes of {scene}: episode id '{episode_id}' appears more than once; results are keyed by it, so ids must be unique per scene"
    )]
    DuplicateEpisode {
        /// The scene.
        scene: String,
        /// The repeated id.
        episode_id: String,
    },
    /// The settings leave no episode to run.
    #[error("no episode to run: {0}")]
    NoEpisodes(String),
    /// Every episode that was started failed before it could run (for
    /// example, no navigable start): nothing was recorded.
    #[error("all {failed} episodes failed to start (first: {first}); nothing was recorded")]
    AllFailed {
        /// How many were started.
        failed: usize,
        /// The first failure.
        first: String,
    },
}

fn io_err(path: &Path, e: impl std::fmt::Display) -> HarnessError {
    HarnessError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Where episodes come from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum EpisodeSource {
    /// Generated per scene following Habitat's dataset procedure.
    Generate {
        /// Episodes per target category present in a scene.
        per_category: usize,
        /// At most this many episodes per scene (spread over the
        /// categories), when set.
        per_scene: Option<usize>,
    },
    /// A Habitat ObjectNav JSON(.gz) file; its episodes' scene ids are
    /// matched to the loaded scenes by name.
    File {
        /// The file.
        path: PathBuf,
    },
}

/// The LLM policy of the `sornav` variant (and of `no-target-gate`, its
/// ablation, so that the two differ only in the target gate).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LlmSettings {
    /// Client configuration (base URL, model, timeout, ...).
    pub config: LlmConfig,
    /// Append every exchange to this JSONL file.
    pub record: Option<PathBuf>,
    /// Answer from this recording instead of the network.
    pub replay: Option<PathBuf>,
}

/// Everything that decides an evaluation's results (`run.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EvalConfig {
    /// Scenes, in order.
    pub scenes: Vec<SceneSource>,
    /// Sweet Home 3D model directory.
    pub models: Option<PathBuf>,
    /// Episodes.
    pub episodes: EpisodeSource,
    /// Target categories.
    pub categories: Vec<String>,
    /// Variants, in table order.
    pub variants: Vec<String>,
    /// Seed of scene generation, episode generation and sensor noise.
    pub seed: u64,
    /// Camera (resolution, field of view, depth range, sensor noise rates
    /// in `camera.noise`).
    pub camera: CameraConfig,
    /// Name of the sensor-noise preset whose rates `camera.noise` holds
    /// (`sornav-sim --noise`; see [`NoisePreset`]), or [`CUSTOM_NOISE`]
    /// for rates read from a file (`--noise-config`). Absent (and not
    /// written to `run.json`) for a noiseless run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise_preset: Option<String>,
    /// Episode rules (500 actions, 120 s).
    pub run: RunConfig,
    /// Agent command -> action adapter.
    pub adapter: AdapterConfig,
    /// Base agent configuration (variants change policy and ordering).
    pub agent: AgentConfig,
    /// LLM policy for the `sornav` (and `no-target-gate`) variant, when set.
    pub llm: Option<LlmSettings>,
    /// Top-down maps: the first this many episodes of every variant, plus
    /// up to this many episodes in which the agent relocated.
    pub maps: usize,
    /// Failure analysis: when positive, the map of every failed episode of
    /// an agent variant is saved in `maps/failures/`, and the report shows
    /// up to this many of them per variant and failure class (see
    /// [`crate::failure_analysis`]); 0 saves none. Absent from older `run.json` files: the
    /// default, [`DEFAULT_FAILURE_MAPS`].
    #[serde(default = "default_failure_maps")]
    pub failure_maps: usize,
}

/// Examples per failure class in the report's failure analysis, by default
/// ([`EvalConfig::failure_maps`]).
pub const DEFAULT_FAILURE_MAPS: usize = 3;

fn default_failure_maps() -> usize {
    DEFAULT_FAILURE_MAPS
}

/// Most parallel jobs a run accepts ([`RunOptions::jobs`]): each job is a
/// thread with its own simulator state, and far more threads than cores only
/// add memory and contention (`--jobs 100000` spawned thousands of threads
/// and never progressed).
pub const MAX_JOBS: usize = 256;

/// How to run an evaluation (not part of its results).
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Output directory.
    pub out: PathBuf,
    /// Parallel jobs (episodes in flight).
    pub jobs: usize,
    /// Run only work items `i` of `n` (`i < n`).
    pub shard: Option<(usize, usize)>,
    /// Discard earlier results in `out`.
    pub fresh: bool,
    /// Show a progress bar.
    pub progress: bool,
    /// Set (for example by a SIGINT handler) to stop: episodes not yet
    /// started are not started, the ones running finish and are recorded,
    /// and the report of what finished is written
    /// ([`RunOutcome::interrupted`]).
    pub stop: Option<Arc<AtomicBool>>,
}

impl RunOptions {
    /// Checks the options.
    ///
    /// # Errors
    /// [`HarnessError::Config`] for `jobs` outside `1..=`[`MAX_JOBS`] or a
    /// shard `i/n` without `i < n`.
    pub fn validate(&self) -> Result<(), HarnessError> {
        if !(1..=MAX_JOBS).contains(&self.jobs) {
            return Err(HarnessError::Config(format!(
                "jobs = {}: need 1 to {MAX_JOBS} (MAX_JOBS)",
                self.jobs
            )));
        }
        if let Some((i, n)) = self.shard
            && (n == 0 || i >= n)
        {
            return Err(HarnessError::Config(format!("shard {i}/{n}: need i < n")));
        }
        Ok(())
    }
}

/// What a run did.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    /// Work items of this run (after sharding).
    pub items: usize,
    /// Items already done before this run (resume).
    pub skipped: usize,
    /// Items run and recorded now.
    pub ran: usize,
    /// Items that failed to start (logged, not recorded).
    pub failed: usize,
    /// Items not started because the run was stopped
    /// ([`RunOptions::stop`]); run again to resume them.
    pub not_started: usize,
    /// Whether the run was stopped before every item was started.
    pub interrupted: bool,
    /// Wall time of this run (s).
    pub wall_s: f64,
    /// The report.
    pub report: PathBuf,
}

/// The agent variants by name (`oracle` is the simulator's own).
pub const VARIANTS: [&str; 7] = [
    "sornav",
    "no-gate",
    "nearest-frontier",
    "semantic-ranking",
    "single-floor",
    "no-target-gate",
    "oracle",
];

impl EvalConfig {
    /// Checks the settings.
    ///
    /// # Errors
    /// [`HarnessError::Config`] naming the problem.
    pub fn validate(&self) -> Result<(), HarnessError> {
        let bad = |m: String| Err(HarnessError::Config(m));
        if self.scenes.is_empty() {
            return bad("no scenes".into());
        }
        if self.variants.is_empty() {
            return bad("no variants".into());
        }
        for v in &self.variants {
            if Variant::from_name(v).is_none() {
                return bad(format!(
                    "unknown variant '{v}' (known: {})",
                    VARIANTS.join(", ")
                ));
            }
        }
        let unique: BTreeSet<&String> = self.variants.iter().collect();
        if unique.len() != self.variants.len() {
            return bad("a variant is listed twice".into());
        }
        let names: BTreeSet<String> = self.scenes.iter().map(SceneSource::name).collect();
        if names.len() != self.scenes.len() {
            return bad("two scenes have the same name".into());
        }
        if self.categories.is_empty() {
            return bad("no target categories".into());
        }
        if let EpisodeSource::Generate {
            per_category,
            per_scene,
        } = &self.episodes
            && (*per_category == 0 || *per_scene == Some(0))
        {
            return bad("episodes per category / scene must be positive".into());
        }
        self.camera
            .validate()
            .map_err(|e| HarnessError::Config(format!("camera: {e}")))?;
        self.check_noise_preset()?;
        self.run
            .validate()
            .map_err(|e| HarnessError::Config(format!("episode rules: {e}")))?;
        for v in &self.variants {
            if let Some(variant) = Variant::from_name(v)
                && variant != Variant::Oracle
            {
                self.agent
                    .clone()
                    .with_variant(variant)
                    .and_then(|c| c.validate())
                    .map_err(|e| HarnessError::Config(format!("agent configuration: {e}")))?;
            }
        }
        Ok(())
    }
}

/// [`EvalConfig::noise_preset`] of rates read from a file.
pub const CUSTOM_NOISE: &str = "custom";

impl EvalConfig {
    /// The noise label agrees with the rates: a preset's name goes with
    /// exactly its rates, [`CUSTOM_NOISE`] with any active rates, and no
    /// label with no noise (so `run.json` never names rates it did not use).
    fn check_noise_preset(&self) -> Result<(), HarnessError> {
        let rates = &self.camera.noise;
        match self.noise_preset.as_deref() {
            None if rates.is_active() => Err(HarnessError::Config(
                "camera.noise has active rates but no noise_preset names them".into(),
            )),
            None | Some(CUSTOM_NOISE) => Ok(()),
            Some(name) => {
                let preset = NoisePreset::from_name(name)
                    .map_err(|e| HarnessError::Config(e.to_string()))?;
                if preset.config() == *rates {
                    Ok(())
                } else {
                    Err(HarnessError::Config(format!(
                        "noise preset '{name}' does not match camera.noise (use '{CUSTOM_NOISE}' for other rates)"
                    )))
                }
            }
        }
    }
}

/// A scene ready for episodes.
struct LoadedScene {
    name: String,
    sim: Arc<Simulator>,
    episodes: Vec<Episode>,
}

/// One (scene, episode, variant) run.
#[derive(Debug, Clone, Copy)]
struct WorkItem {
    scene: usize,
    episode: usize,
    variant: usize,
}

/// The episode-generator seed of a scene: the evaluation seed mixed with
/// the scene's name (FNV-1a), so that every scene gets its own episodes and
/// adding scenes does not change the others'.
pub fn generator_seed(seed: u64, scene: &str) -> u64 {
    scene.bytes().fold(seed ^ 0x9e37_79b9_7f4a_7c15, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The episodes of one scene.
fn scene_episodes(
    config: &EvalConfig,
    sim: &Simulator,
    name: &str,
    from_file: &[Episode],
) -> Result<Vec<Episode>, HarnessError> {
    let wanted: HashSet<&str> = config.categories.iter().map(String::as_str).collect();
    match &config.episodes {
        EpisodeSource::File { .. } => Ok(from_file
            .iter()
            .filter(|e| {
                sornav_platform_sim::episodes::habitat::scene_stem(&e.scene_id) == name
                    || e.scene_id == name
            })
            .filter(|e| wanted.contains(e.object_category.as_str()))
            .cloned()
            .collect()),
        EpisodeSource::Generate {
            per_category,
            per_scene,
        } => {
            let generator = GeneratorConfig {
                categories: config.categories.clone(),
                episodes_per_category: *per_category,
                seed: generator_seed(config.seed, name),
                ..GeneratorConfig::default()
            };
            let mut all =
                generate_episodes(sim, &generator).map_err(|e| HarnessError::Episodes {
                    scene: name.to_owned(),
                    message: e.to_string(),
                })?;
            if let Some(cap) = per_scene {
                // Round robin over the categories, in generation order.
                let mut by_cat: Vec<Vec<Episode>> = Vec::new();
                for e in all.drain(..) {
                    match by_cat
                        .iter_mut()
                        .find(|v| v[0].object_category == e.object_category)
                    {
                        Some(v) => v.push(e),
                        None => by_cat.push(vec![e]),
                    }
                }
                all = round_robin(&by_cat, *cap);
            }
            Ok(all)
        }
    }
}

/// Up to `cap` items taken from `groups` in rounds: the first of every
/// group (in order), then the second of every group, and so on.
pub(crate) fn round_robin<T: Clone>(groups: &[Vec<T>], cap: usize) -> Vec<T> {
    let mut out = Vec::new();
    let mut round = 0;
    while out.len() < cap && groups.iter().any(|g| g.len() > round) {
        for g in groups {
            if out.len() < cap
                && let Some(x) = g.get(round)
            {
                out.push(x.clone());
            }
        }
        round += 1;
    }
    out
}

/// Whether a line of `episodes.jsonl` is a complete record of the format
/// before floors were recorded (a `cross_floor` outcome or no
/// `floors_between`).
fn is_legacy_record(line: &str) -> bool {
    let Ok(serde_json::Value::Object(m)) = serde_json::from_str::<serde_json::Value>(line) else {
        return false;
    };
    m.contains_key("episode_id")
        && m.contains_key("outcome")
        && (m.get("outcome").and_then(|o| o.as_str()) == Some("cross_floor")
            || !m.contains_key("floors_between"))
}

/// Longest line accepted in `episodes.jsonl`: a record is a few KB (an
/// LLM reason is capped), so a longer line is not a record, and reading
/// it whole (a file of zeros, a device) would exhaust memory.
pub const MAX_RECORD_LINE_BYTES: usize = 16 << 20;

enum RecordLineError {
    Io(std::io::Error),
    /// Line `line` (1-based) exceeds [`MAX_RECORD_LINE_BYTES`].
    TooLong {
        line: usize,
    },
}

/// The lines of `reader` (without their line ends), each at most
/// [`MAX_RECORD_LINE_BYTES`] long.
fn record_lines(mut reader: impl BufRead) -> Result<Vec<String>, RecordLineError> {
    let mut lines = Vec::new();
    loop {
        let mut buf = Vec::new();
        let n = (&mut reader)
            .take(MAX_RECORD_LINE_BYTES as u64 + 1)
            .read_until(b'\n', &mut buf)
            .map_err(RecordLineError::Io)?;
        if n == 0 {
            return Ok(lines);
        }
        if buf.last() == Some(&b'\n') {
            buf.pop();
            if buf.last() == Some(&b'\r') {
                buf.pop();
            }
        } else if n > MAX_RECORD_LINE_BYTES {
            return Err(RecordLineError::TooLong {
                line: lines.len() + 1,
            });
        }
        let line = String::from_utf8(buf).map_err(|e| {
            RecordLineError::Io(std::io::Error::new(std::io::ErrorKind::InvalidData, e))
        })?;
        lines.push(line);
    }
}

/// Reads `episodes.jsonl` (missing file: no records).
///
/// Records written before floors were recorded (with a `cross_floor`
/// outcome, without `floors_between`) are refused with
/// [`HarnessError::LegacyRecords`] (for resume and `merge` alike): the
/// cause of their cross-floor failures was never recorded, so they cannot
/// be converted.
///
/// # Errors
/// [`HarnessError::Io`], [`HarnessError::LegacyRecords`], or
/// [`HarnessError::Malformed`] with the line number; a truncated last line
/// (an interrupted write) is dropped with a warning instead.
pub fn read_records(path: &Path) -> Result<Vec<EpisodeRecord>, HarnessError> {
    let file = match File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(io_err(path, e)),
    };
    let lines = record_lines(BufReader::new(file)).map_err(|e| match e {
        RecordLineError::Io(e) => io_err(path, e),
        RecordLineError::TooLong { line } => HarnessError::Malformed {
            path: path.to_path_buf(),
            line,
            message: format!(
                "a line longer than {MAX_RECORD_LINE_BYTES} bytes (not a record file?)"
            ),
        },
    })?;
    let mut out = Vec::with_capacity(lines.len());
    let last = lines.len();
    for (i, line) in lines.iter().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        match serde_json::from_str::<EpisodeRecord>(line) {
            Ok(r) => out.push(r),
            Err(_) if is_legacy_record(line) => {
                return Err(HarnessError::LegacyRecords {
                    path: path.to_path_buf(),
                    line: i + 1,
                });
            }
            Err(e) if i + 1 == last => {
                tracing::warn!("{}: dropping a truncated last line ({e})", path.display());
            }
            Err(e) => {
                return Err(HarnessError::Malformed {
                    path: path.to_path_buf(),
                    line: i + 1,
                    message: e.to_string(),
                });
            }
        }
    }
    Ok(out)
}

/// Makes `episodes.jsonl` end at a line boundary before records are
/// appended to it: a truncated last line (an interrupted write, which
/// [`read_records`] drops) is cut off, and a complete last record that only
/// lacks its newline gets one. Otherwise the first appended record would be
/// glued to that line and the file would no longer read.
fn repair_tail(path: &Path) -> Result<(), HarnessError> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(io_err(path, e)),
    };
    let start = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
    let tail = &bytes[start..];
    if tail.is_empty() {
        return Ok(());
    }
    let complete = serde_json::from_slice::<EpisodeRecord>(tail).is_ok();
    if !complete {
        tracing::warn!(
            "{}: cutting off a truncated last line before appending",
            path.display()
        );
    }
    let mut file = OpenOptions::new()
        .append(complete)
        .write(true)
        .open(path)
        .map_err(|e| io_err(path, e))?;
    let result = if complete {
        file.write_all(b"\n")
    } else {
        file.set_len(u64::try_from(start).unwrap_or(u64::MAX))
    };
    result.map_err(|e| io_err(path, e))
}

/// Reads `dir/run.json`.
fn read_run_file(dir: &Path) -> Result<EvalConfig, HarnessError> {
    let path = dir.join("run.json");
    let text = std::fs::read_to_string(&path).map_err(|e| io_err(&path, e))?;
    serde_json::from_str(&text).map_err(|e| HarnessError::Malformed {
        path,
        line: 0,
        message: e.to_string(),
    })
}

/// Whether two configurations describe the same evaluation. Compared
/// through JSON: floating-point fields round-trip exactly.
fn same_run(a: &EvalConfig, b: &EvalConfig) -> bool {
    serde_json::to_value(a).ok() == serde_json::to_value(b).ok()
}

/// Checks or writes `run.json`.
fn check_run_file(dir: &Path, config: &EvalConfig, fresh: bool) -> Result<(), HarnessError> {
    let path = dir.join("run.json");
    let jsonl = dir.join("episodes.jsonl");
    if fresh {
        for f in [&path, &jsonl] {
            if f.exists() {
                std::fs::remove_file(f).map_err(|e| io_err(f, e))?;
            }
        }
        let maps = dir.join("maps");
        if maps.exists() {
            std::fs::remove_dir_all(&maps).map_err(|e| io_err(&maps, e))?;
        }
    }
    if path.exists() {
        if !same_run(&read_run_file(dir)?, config) {
            return Err(HarnessError::DifferentRun(dir.to_path_buf()));
        }
        return Ok(());
    }
    let text = serde_json::to_string_pretty(config).map_err(|e| io_err(&path, e))?;
    Ok(output::write_file(&path, text.as_bytes())?)
}

/// Checks the LLM endpoint of `config` before a run
/// ([`check_endpoint`]): reachable, serving the model. Nothing to check
/// without an LLM policy or when replaying a recording.
///
/// # Errors
/// [`HarnessError::LlmEndpoint`] saying what is wrong.
pub fn check_llm(config: &EvalConfig) -> Result<(), HarnessError> {
    match &config.llm {
        Some(settings) if settings.replay.is_none() => {
            let models = check_endpoint(&settings.config)?;
            tracing::info!(
                "LLM endpoint {} answers (models: {})",
                settings.config.base_url,
                if models.is_empty() {
                    "not listed".to_owned()
                } else {
                    models.join(", ")
                }
            );
            Ok(())
        }
        _ => Ok(()),
    }
}

/// The transport of the LLM policy (HTTP, recording or replay).
fn llm_transport(settings: &LlmSettings) -> Result<Arc<dyn Transport>, HarnessError> {
    if let Some(replay) = &settings.replay {
        let t = ReplayTransport::open(replay).map_err(|e| io_err(replay, e))?;
        return Ok(Arc::new(t));
    }
    let http = HttpTransport::from_config(&settings.config).map_err(AgentError::from)?;
    match &settings.record {
        Some(path) => Ok(Arc::new(
            RecordingTransport::new(http, path).map_err(|e| io_err(path, e))?,
        )),
        None => Ok(Arc::new(http)),
    }
}

/// The agent factory of an agent variant.
fn factory(
    config: &EvalConfig,
    variant: Variant,
    llm: Option<&Arc<dyn Transport>>,
) -> Result<ConfigFactory, HarnessError> {
    let mut agent = config
        .agent
        .clone()
        .with_variant(variant)
        .map_err(AgentError::from)?;
    let mut policy: Option<Box<dyn Fn() -> Result<BoxedPolicy, AgentError> + Send + Sync>> = None;
    if matches!(variant, Variant::Sornav | Variant::NoTargetGate)
        && let (Some(settings), Some(transport)) = (&config.llm, llm)
    {
        agent.policy = PolicyConfig::Llm(settings.config.clone());
        let (c, t) = (settings.config.clone(), Arc::clone(transport));
        policy = Some(Box::new(move || {
            let p = sornav::supervisor::LlmPolicy::with_transport(c.clone(), Arc::clone(&t))?;
            Ok(Box::new(p) as BoxedPolicy)
        }));
    }
    Ok(ConfigFactory {
        config: agent,
        policy,
    })
}

/// Builds the top-down map of a finished episode.
fn topdown(
    sim: &Simulator,
    episode: &Episode,
    record: &EpisodeRecord,
    trace: &EpisodeTrace,
    snapshot: Option<sornav::AgentSnapshot>,
) -> TopDownMap {
    let (occupancy, frontier_cells, final_yaw) = match &snapshot {
        Some(s) => {
            let res = s.occupancy.resolution as f32;
            let cells = s
                .frontiers
                .iter()
                .flat_map(|f| f.cells.iter())
                .map(|c| [(c.x as f32 + 0.5) * res, (c.y as f32 + 0.5) * res])
                .collect();
            (s.occupancy.clone(), cells, s.pose.map_or(0.0, |p| p.yaw))
        }
        None => Default::default(),
    };
    TopDownMap {
        title: format!(
            "{} / {} #{}: {} ({}, {} actions)",
            record.variant,
            record.result.scene_id,
            record.result.episode_id,
            record.result.object_category,
            record.result.outcome.name(),
            record.result.actions
        ),
        occupancy,
        frontier_cells,
        trajectory: trace.trajectory.iter().map(|p| [p[0], p[1]]).collect(),
        relocations: trace.relocations.iter().map(|r| (r.1, r.2)).collect(),
        goals: episode
            .goals
            .iter()
            .filter_map(|g| {
                u32::try_from(g.object_id)
                    .ok()
                    .and_then(|id| sim.scene().instance(id))
            })
            .map(|i| {
                (
                    [i.bounds.min.x as f32, i.bounds.min.y as f32],
                    [i.bounds.max.x as f32, i.bounds.max.y as f32],
                )
            })
            .collect(),
        view_points: episode
            .view_point_positions()
            .iter()
            .map(|p| [p.x as f32, p.y as f32])
            .collect(),
        verified: trace
            .verifications
            .iter()
            .map(|v| [v.1[0], v.1[1]])
            .collect(),
        final_yaw,
        success: record.result.success,
    }
}

/// Loads every scene of `config` (in parallel on `pool`) with its episodes
/// (from the episode file or generated), and checks them: episode ids unique
/// per scene, at least one episode, a warning for a target category without
/// any.
///
/// # Errors
/// Those of loading a scene or its episodes,
/// [`HarnessError::DuplicateEpisode`] and [`HarnessError::NoEpisodes`].
fn load_scenes(
    config: &EvalConfig,
    pool: &rayon::ThreadPool,
) -> Result<Vec<LoadedScene>, HarnessError> {
    let from_file: Vec<Episode> = match &config.episodes {
        EpisodeSource::File { path } => HabitatDataset::read(path)
            .and_then(|d| d.to_episodes())
            .map_err(|e| io_err(path, e))?,
        EpisodeSource::Generate { .. } => Vec::new(),
    };
    let scenes: Vec<LoadedScene> = pool.install(|| {
        config
            .scenes
            .par_iter()
            .map(|source| {
                let name = source.name();
                let sim = source.simulator(config.models.as_deref(), &config.camera)?;
                let episodes = scene_episodes(config, &sim, &name, &from_file)?;
                Ok(LoadedScene {
                    name,
                    sim: Arc::new(sim),
                    episodes,
                })
            })
            .collect::<Result<Vec<_>, HarnessError>>()
    })?;
    for scene in &scenes {
        let mut ids = HashSet::new();
        if let Some(e) = scene.episodes.iter().find(|e| !ids.insert(&e.episode_id)) {
            return Err(HarnessError::DuplicateEpisode {
                scene: scene.name.clone(),
                episode_id: e.episode_id.clone(),
            });
        }
    }
    let with_episodes: HashSet<&str> = scenes
        .iter()
        .flat_map(|s| s.episodes.iter().map(|e| e.object_category.as_str()))
        .collect();
    if with_episodes.is_empty() {
        return Err(HarnessError::NoEpisodes(no_episode_reason(
            config, &scenes, &from_file,
        )));
    }
    for c in &config.categories {
        if !with_episodes.contains(c.as_str()) {
            tracing::warn!("target category '{c}' has no episode in any scene (misspelt?)");
        }
    }
    Ok(scenes)
}

/// The work items (scene, episode, variant) in a fixed order, kept to
/// `options.shard`, and the (scene, episode) pairs whose maps are saved:
/// the first `config.maps` episodes of the shard.
fn work_items(
    config: &EvalConfig,
    options: &RunOptions,
    scenes: &[LoadedScene],
) -> (Vec<WorkItem>, HashSet<(usize, usize)>) {
    let mut items = Vec::new();
    for (s, scene) in scenes.iter().enumerate() {
        for e in 0..scene.episodes.len() {
            for v in 0..config.variants.len() {
                items.push(WorkItem {
                    scene: s,
                    episode: e,
                    variant: v,
                });
            }
        }
    }
    if let Some((i, n)) = options.shard {
        items = items
            .into_iter()
            .enumerate()
            .filter(|(k, _)| k % n == i)
            .map(|(_, w)| w)
            .collect();
    }
    // Maps: the first `maps` episodes (in order) of every variant that
    // this shard runs.
    let map_episodes: HashSet<(usize, usize)> = items
        .iter()
        .map(|w| (w.scene, w.episode))
        .collect::<BTreeSet<_>>()
        .into_iter()
        .take(config.maps)
        .collect();
    (items, map_episodes)
}

/// Runs (or resumes) an evaluation and writes its outputs.
///
/// The output directory is locked for the run ([`output::lock_dir`]);
/// `run.json` and the report are replaced atomically. The first failure to
/// write a record stops the run: no further episode is started, and the
/// error is returned. When [`RunOptions::stop`] is set, episodes not yet
/// started are left for a later run (resume), the running ones finish and
/// are recorded, and the report covers what finished.
///
/// # Errors
/// [`HarnessError`] for invalid settings or options, a locked output
/// directory, unloadable scenes, duplicate episode ids in a scene, settings
/// that leave no episode ([`HarnessError::NoEpisodes`]), a different
/// evaluation already in `out`, every started episode failing to start
/// ([`HarnessError::AllFailed`]), and I/O failures. A single episode that
/// fails to start (no navigable start) is logged, counted in
/// [`RunOutcome::failed`] and skipped.
pub fn run(config: &EvalConfig, options: &RunOptions) -> Result<RunOutcome, HarnessError> {
    config.validate()?;
    options.validate()?;
    let t0 = Instant::now();
    std::fs::create_dir_all(&options.out).map_err(|e| io_err(&options.out, e))?;
    // One writer per output directory, held until the report is written.
    let _lock = output::lock_dir(&options.out)?;
    check_run_file(&options.out, config, options.fresh)?;
    let jsonl = options.out.join("episodes.jsonl");
    let done: HashSet<(String, String, String)> = read_records(&jsonl)?
        .iter()
        .map(EpisodeRecord::key)
        .collect();

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.jobs.max(1))
        .build()
        .map_err(|e| HarnessError::Config(format!("thread pool: {e}")))?;

    // Scenes and episodes.
    let scenes = load_scenes(config, &pool)?;

    // Work items, in a fixed order; then the shard; then resume.
    let (mut items, map_episodes) = work_items(config, options, &scenes);
    let total = items.len();
    let key = |w: &WorkItem| {
        (
            config.variants[w.variant].clone(),
            scenes[w.scene].name.clone(),
            scenes[w.scene].episodes[w.episode].episode_id.clone(),
        )
    };
    items.retain(|w| !done.contains(&key(w)));
    let skipped = total - items.len();
    if skipped > 0 {
        tracing::info!(
            "{skipped} of {total} episodes already in {} (resuming; --fresh starts over)",
            jsonl.display()
        );
    }

    let transport = config.llm.as_ref().map(llm_transport).transpose()?;
    let factories: Vec<Option<ConfigFactory>> = config
        .variants
        .iter()
        .map(|v| match Variant::from_name(v) {
            Some(Variant::Oracle) | None => Ok(None),
            Some(variant) => factory(config, variant, transport.as_ref()).map(Some),
        })
        .collect::<Result<_, _>>()?;

    let maps_dir = options.out.join("maps");
    std::fs::create_dir_all(&maps_dir).map_err(|e| io_err(&maps_dir, e))?;
    let failure_maps_dir = maps_dir.join(topdown::FAILURES_DIR);
    if config.failure_maps > 0 {
        std::fs::create_dir_all(&failure_maps_dir).map_err(|e| io_err(&failure_maps_dir, e))?;
    }
    repair_tail(&jsonl)?;
    let out_file = OpenOptions::new()
        .create(true)
        .append(true)
        .open(&jsonl)
        .map_err(|e| io_err(&jsonl, e))?;
    let writer = Mutex::new(std::io::BufWriter::new(out_file));
    let relocation_maps = std::sync::atomic::AtomicUsize::new(0);
    let bar = if options.progress {
        let bar = ProgressBar::new(items.len() as u64);
        bar.set_style(
            ProgressStyle::with_template(
                "{elapsed_precise} [{bar:40}] {pos}/{len} episodes ({per_sec}, eta {eta}) {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        bar
    } else {
        ProgressBar::hidden()
    };
    let successes = AtomicUsize::new(0);
    let finished = AtomicUsize::new(0);
    let write_error: Mutex<Option<HarnessError>> = Mutex::new(None);
    // Set at the first write error: nothing more is started.
    let write_failed = AtomicBool::new(false);
    // A record or figure that cannot be written (a full disk): keep the
    // first error and start nothing more.
    let fail_write = |e: HarnessError| {
        write_failed.store(true, Ordering::Relaxed);
        write_error
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .get_or_insert(e);
    };
    let stop_requested = || {
        options
            .stop
            .as_ref()
            .is_some_and(|s| s.load(Ordering::Relaxed))
    };
    let not_started = AtomicUsize::new(0);
    let failed = AtomicUsize::new(0);
    let first_failure: Mutex<Option<String>> = Mutex::new(None);

    pool.install(|| {
        items.par_iter().for_each(|w| {
            if write_failed.load(Ordering::Relaxed) || stop_requested() {
                not_started.fetch_add(1, Ordering::Relaxed);
                bar.inc(1);
                return;
            }
            let scene = &scenes[w.scene];
            let episode = &scene.episodes[w.episode];
            let variant = &config.variants[w.variant];
            let mut run_config = config.run.clone();
            run_config.noise_seed = config.seed;
            let mut policy = factories[w.variant]
                .as_ref()
                .map(|f| SornavPolicy::new(f, config.adapter.clone()));
            let result = match policy.as_mut() {
                None => run_episode(&scene.sim, episode, &mut Oracle::new(), &run_config),
                Some(p) => run_episode(&scene.sim, episode, p, &run_config),
            };
            let result = match result {
                Ok(r) => r,
                Err(e) => {
                    let message = format!("{variant} {} #{}: {e}", scene.name, episode.episode_id);
                    tracing::warn!("{message}");
                    failed.fetch_add(1, Ordering::Relaxed);
                    first_failure
                        .lock()
                        .unwrap_or_else(std::sync::PoisonError::into_inner)
                        .get_or_insert(message);
                    bar.inc(1);
                    return;
                }
            };
            let trace = policy.as_mut().map(SornavPolicy::take_trace);
            // Every relocating episode counts toward the `config.maps`
            // relocation maps, even one that gets a map anyway.
            let relocated = trace.as_ref().is_some_and(|t| !t.relocations.is_empty())
                && relocation_maps.fetch_add(1, Ordering::Relaxed) < config.maps;
            let want_map = map_episodes.contains(&(w.scene, w.episode)) || relocated;
            // Failure analysis: every failed episode of an agent variant
            // gets a map, and the report picks its examples from them, so
            // the choice does not depend on the order episodes finish in.
            let want_failure_map = config.failure_maps > 0 && policy.is_some() && !result.success;
            // The agent's end state and the full trace only for a map.
            let snapshot = policy
                .as_ref()
                .and_then(SornavPolicy::agent)
                .filter(|_| want_map || want_failure_map)
                .map(sornav::Agent::snapshot);
            drop(policy);
            let map_trace = if want_map || want_failure_map {
                trace.clone()
            } else {
                None
            };
            let record = EpisodeRecord::new(variant, result, trace);
            if want_map || want_failure_map {
                let map = topdown(
                    &scene.sim,
                    episode,
                    &record,
                    &map_trace.unwrap_or_default(),
                    snapshot,
                );
                let name = topdown::file_name(variant, &scene.name, &episode.episode_id);
                let targets = [
                    (want_map, maps_dir.join(&name), topdown::MAP_SIZE),
                    (
                        want_failure_map,
                        failure_maps_dir.join(&name),
                        topdown::FAILURE_MAP_SIZE,
                    ),
                ];
                for (_, path, size) in targets.iter().filter(|t| t.0) {
                    match output::replace_with(path, |tmp| map.save_png(tmp, *size)) {
                        Ok(()) => {}
                        // Nothing to draw: this episode has no map.
                        Err(e @ FigureError::Empty(_)) => {
                            tracing::warn!("map {}: {e}", path.display());
                        }
                        // The file could not be written (a full disk):
                        // a write failure like a record's, which stops
                        // the run.
                        Err(e) => fail_write(io_err(path, e)),
                    }
                }
            }
            let line = serde_json::to_string(&record);
            let mut guard = writer
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            let written = line.map_err(|e| io_err(&jsonl, e)).and_then(|l| {
                writeln!(guard, "{l}")
                    .and_then(|()| guard.flush())
                    .map_err(|e| io_err(&jsonl, e))
            });
            drop(guard);
            if let Err(e) = written {
                fail_write(e);
            }
            let s = successes.fetch_add(usize::from(record.result.success), Ordering::Relaxed)
                + usize::from(record.result.success);
            let f = finished.fetch_add(1, Ordering::Relaxed) + 1;
            bar.set_message(format!("SR {:.2}", s as f64 / f as f64));
            bar.inc(1);
        });
    });
    bar.finish_and_clear();
    if let Some(e) = write_error
        .into_inner()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
    {
        return Err(e);
    }
    let (failed, not_started) = (failed.into_inner(), not_started.into_inner());
    let ran = items.len() - failed - not_started;
    if ran == 0 && failed > 0 && not_started == 0 {
        return Err(HarnessError::AllFailed {
            failed,
            first: first_failure
                .into_inner()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .unwrap_or_default(),
        });
    }
    let wall_s = t0.elapsed().as_secs_f64();
    let records = read_records(&jsonl)?;
    let report = report::write(&options.out, config, &records, Some(wall_s))?;
    Ok(RunOutcome {
        items: total,
        skipped,
        ran,
        failed,
        not_started,
        interrupted: not_started > 0,
        wall_s,
        report,
    })
}

/// Why the settings leave no episode at all, for [`HarnessError::NoEpisodes`].
fn no_episode_reason(config: &EvalConfig, scenes: &[LoadedScene], from_file: &[Episode]) -> String {
    let categories = config.categories.join(", ");
    let names: Vec<&str> = scenes.iter().map(|s| s.name.as_str()).collect();
    match &config.episodes {
        EpisodeSource::File { path } if from_file.is_empty() => {
            format!("the episode file {} holds no episodes", path.display())
        }
        EpisodeSource::File { path } => {
            let matching = from_file.iter().any(|e| {
                names.iter().any(|n| {
                    sornav_platform_sim::episodes::habitat::scene_stem(&e.scene_id) == *n
                        || e.scene_id == *n
                })
            });
            if matching {
                format!(
                    "no episode of {} for the scenes has a target category among [{categories}] (misspelt --categories?)",
                    path.display()
                )
            } else {
                format!(
                    "no episode of {} names a loaded scene (its scene ids look like '{}'; the scenes are [{}])",
                    path.display(),
                    from_file[0].scene_id,
                    names.join(", ")
                )
            }
        }
        EpisodeSource::Generate { .. } => format!(
            "no scene has a reachable instance of the target categories [{categories}] (misspelt --categories? the ObjectNav categories of HM3D are {})",
            sornav_platform_sim::category::HM3D_GOALS.join(", ")
        ),
    }
}

/// Merges the output directories of shards of one evaluation into `out`:
/// records are de-duplicated by (variant, scene, episode), maps are copied,
/// and the summary, report and figures are written for the union.
///
/// # Errors
/// [`HarnessError::DifferentRun`] when the shards' `run.json` differ (or
/// differ from one already in `out`), and I/O errors.
pub fn merge(out: &Path, shards: &[PathBuf]) -> Result<PathBuf, HarnessError> {
    if shards.is_empty() {
        return Err(HarnessError::Config(
            "merge needs at least one shard directory".into(),
        ));
    }
    let mut config: Option<EvalConfig> = None;
    let mut records = Vec::new();
    let mut seen = HashSet::new();
    for dir in shards {
        let c = read_run_file(dir)?;
        match &config {
            Some(first) if !same_run(first, &c) => {
                return Err(HarnessError::DifferentRun(dir.clone()));
            }
            Some(_) => {}
            None => config = Some(c),
        }
        for r in read_records(&dir.join("episodes.jsonl"))? {
            if seen.insert(r.key()) {
                records.push(r);
            }
        }
    }
    let config = config.ok_or_else(|| HarnessError::Config("no shard".into()))?;
    std::fs::create_dir_all(out).map_err(|e| io_err(out, e))?;
    let _lock = output::lock_dir(out)?;
    check_run_file(out, &config, false)?;
    // Keep what `out` already holds too (merging into one of the shards).
    let jsonl = out.join("episodes.jsonl");
    for r in read_records(&jsonl)? {
        if seen.insert(r.key()) {
            records.push(r);
        }
    }
    let tmp = out.join("episodes.jsonl.tmp");
    {
        let mut f = std::io::BufWriter::new(File::create(&tmp).map_err(|e| io_err(&tmp, e))?);
        for r in &records {
            let line = serde_json::to_string(r).map_err(|e| io_err(&tmp, e))?;
            writeln!(f, "{line}").map_err(|e| io_err(&tmp, e))?;
        }
        f.flush().map_err(|e| io_err(&tmp, e))?;
    }
    std::fs::rename(&tmp, &jsonl).map_err(|e| io_err(&jsonl, e))?;
    let maps = out.join("maps");
    for dir in shards {
        copy_new_files(&dir.join("maps"), &maps)?;
        copy_new_files(
            &dir.join("maps").join(topdown::FAILURES_DIR),
            &maps.join(topdown::FAILURES_DIR),
        )?;
    }
    Ok(report::write(out, &config, &records, None)?)
}

/// Copies the files (not the directories) of `from` that `to` lacks into
/// `to` (created); a missing `from` copies nothing.
fn copy_new_files(from: &Path, to: &Path) -> Result<(), HarnessError> {
    std::fs::create_dir_all(to).map_err(|e| io_err(to, e))?;
    let Ok(entries) = std::fs::read_dir(from) else {
        return Ok(());
    };
    for e in entries.flatten() {
        let target = to.join(e.file_name());
        if e.file_type().is_ok_and(|t| t.is_file()) && e.path() != target && !target.exists() {
            std::fs::copy(e.path(), &target).map_err(|err| io_err(&target, err))?;
        }
    }
    Ok(())
}
