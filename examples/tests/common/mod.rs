//! Helpers shared by the evaluation-harness tests.

use std::path::{Path, PathBuf};

use sornav_examples::adapter::{AdapterConfig, sim_agent_config};
use sornav_examples::harness::{EpisodeSource, EvalConfig, LlmSettings, RunOptions};
use sornav_examples::scenes::SceneSource;
use sornav_platform_sim::{CameraConfig, RunConfig, Scene, SimConfig, Simulator};

/// A small evaluation of `variants` (simulator agent configuration, 96 x 72
/// camera) on the procedural houses `scene_seeds`: one episode per target
/// category of `categories`, at most `per_scene` per house, `max_actions`
/// actions each. Evaluation seed 0 and no maps: callers set `seed`,
/// `maps` and `failure_maps` by struct update.
pub fn small_eval(
    scene_seeds: &[u64],
    per_scene: usize,
    categories: &[&str],
    variants: &[&str],
    max_actions: usize,
    llm: Option<LlmSettings>,
) -> EvalConfig {
    EvalConfig {
        scenes: scene_seeds
            .iter()
            .map(|&seed| SceneSource::Procedural {
                seed,
                shuffled: false,
            })
            .collect(),
        models: None,
        episodes: EpisodeSource::Generate {
            per_category: 1,
            per_scene: Some(per_scene),
        },
        categories: categories.iter().map(|c| (*c).to_owned()).collect(),
        variants: variants.iter().map(|v| (*v).to_owned()).collect(),
        seed: 0,
        camera: CameraConfig {
            width: 96,
            height: 72,
            ..CameraConfig::default()
        },
        noise_preset: None,
        run: RunConfig {
            max_actions,
            ..RunConfig::default()
        },
        adapter: AdapterConfig::default(),
        agent: sim_agent_config(),
        llm,
        maps: 0,
        failure_maps: 0,
    }
}

/// A fresh (removed if present) path `sornav-<prefix>-<tag>-<pid>` in the
/// temporary directory.
pub fn temp_dir(prefix: &str, tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sornav-{prefix}-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Run options without a progress bar.
pub fn options(out: &Path, jobs: usize, shard: Option<(usize, usize)>, fresh: bool) -> RunOptions {
    RunOptions {
        out: out.to_path_buf(),
        jobs,
        shard,
        fresh,
        progress: false,
        stop: None,
    }
}

/// Runs the `sornav-sim` binary with `args`, `--out out` and `--quiet`;
/// panics with its stderr unless it succeeds; returns its stdout.
#[allow(dead_code)] // not every test binary runs the CLI
pub fn sornav_sim_ok<S: AsRef<std::ffi::OsStr>>(args: &[S], out: &Path) -> String {
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_sornav-sim"))
        .args(args)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .output()
        .expect("sornav-sim runs");
    assert!(
        run.status.success(),
        "sornav-sim {:?}: {}",
        args.iter()
            .map(|a| a.as_ref().to_owned())
            .collect::<Vec<_>>(),
        String::from_utf8_lossy(&run.stderr)
    );
    String::from_utf8_lossy(&run.stdout).into_owned()
}

/// The simulator of `scene` with a 160 x 120 camera (the evaluations'
/// fast sensing), all else default.
#[allow(dead_code)] // not every test binary builds simulators itself
pub fn simulator_160x120(scene: Scene) -> Simulator {
    Simulator::new(
        scene,
        SimConfig {
            camera: CameraConfig {
                width: 160,
                height: 120,
                ..CameraConfig::default()
            },
            ..SimConfig::default()
        },
    )
    .expect("a 160 x 120 simulator")
}
