//! Issue 20, the perception-noise track: `sornav-sim --noise PRESET`
//! reaches the simulator's camera and is recorded in `run.json`; a bad
//! preset name is a clear error; a noiseless run's `run.json` is unchanged.

#[allow(dead_code)] // the run-option helpers are for the other test binaries
mod common;

use sornav_examples::harness::{EvalConfig, HarnessError};
use sornav_platform_sim::episodes::{GeneratorConfig, generate_episodes};
use sornav_platform_sim::{CameraConfig, NoiseConfig, NoisePreset};

fn sim_cli(out: &std::path::Path) -> std::process::Command {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_sornav-sim"));
    c.args([
        "--scenes",
        "procedural:1",
        "--episodes-per-scene",
        "1",
        "--variants",
        "oracle",
        "--max-actions",
        "10",
        "--width",
        "64",
        "--height",
        "48",
        "--maps",
        "0",
        "--jobs",
        "1",
        "--quiet",
        "--out",
    ])
    .arg(out);
    c
}

#[test]
fn detector_preset_is_recorded_and_corrupts_the_frames() {
    let dir = common::temp_dir("noise", "detector");
    let run = sim_cli(&dir)
        .args(["--noise", "detector"])
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let text = std::fs::read_to_string(dir.join("run.json")).unwrap();
    let config: EvalConfig = serde_json::from_str(&text).unwrap();
    assert_eq!(config.noise_preset.as_deref(), Some("detector"));
    assert_eq!(config.camera.noise, NoisePreset::Detector.config());
    let raw: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(raw["camera"]["noise"]["missed_detection_rate"], 0.3);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["noise"], "detector");

    // The same pose and frame seed, with and without the recorded rates.
    let noisy = config.scenes[0].simulator(None, &config.camera).unwrap();
    let clean_camera = CameraConfig {
        noise: NoiseConfig::default(),
        ..config.camera.clone()
    };
    let clean = config.scenes[0].simulator(None, &clean_camera).unwrap();
    let episodes = generate_episodes(
        &clean,
        &GeneratorConfig {
            categories: config.categories.clone(),
            episodes_per_category: 1,
            seed: 5,
            ..GeneratorConfig::default()
        },
    )
    .unwrap();
    let agent = clean.spawn(&episodes[0]).unwrap();
    let (a, b) = (
        clean.observe_frame(&agent, 7),
        noisy.observe_frame(&agent, 7),
    );
    assert_eq!(a.depth.len(), b.depth.len());
    assert_ne!(a.depth, b.depth, "depth noise and dropped returns");
    assert_eq!(
        noisy.observe_frame(&agent, 7).depth,
        b.depth,
        "noise is deterministic per frame seed"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_noise_settings_are_clear_errors() {
    let dir = common::temp_dir("noise", "bad");
    let bad = sim_cli(&dir).args(["--noise", "lidar"]).output().unwrap();
    assert_eq!(bad.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&bad.stderr);
    assert!(
        stderr.contains("unknown noise preset 'lidar' (known: off, detector)"),
        "{stderr}"
    );
    let file = dir.with_extension("toml");
    std::fs::write(&file, "missed_detection_rate = 1.5\n").unwrap();
    let out_of_range = sim_cli(&dir)
        .arg("--noise-config")
        .arg(&file)
        .output()
        .unwrap();
    assert_eq!(out_of_range.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out_of_range.stderr);
    assert!(stderr.contains("noise.missed_detection_rate"), "{stderr}");
    let both = sim_cli(&dir)
        .args(["--noise", "detector", "--noise-config"])
        .arg(&file)
        .output()
        .unwrap();
    assert_eq!(both.status.code(), Some(2));
    assert!(!dir.join("run.json").exists());
    let _ = std::fs::remove_file(&file);
}

#[test]
fn noise_label_and_rates_must_agree() {
    let noiseless = common::small_eval(&[40], 1, &["bed"], &["sornav"], 10, None);
    noiseless.validate().unwrap();
    let json = serde_json::to_value(&noiseless).unwrap();
    assert!(
        json.get("noise_preset").is_none(),
        "a noiseless run.json is unchanged"
    );
    let mislabelled = EvalConfig {
        noise_preset: Some("detector".into()),
        ..noiseless.clone()
    };
    assert!(
        matches!(mislabelled.validate(), Err(HarnessError::Config(m)) if m.contains("does not match"))
    );
    let unlabelled = EvalConfig {
        camera: CameraConfig {
            noise: NoisePreset::Detector.config(),
            ..noiseless.camera.clone()
        },
        ..noiseless.clone()
    };
    assert!(unlabelled.validate().is_err());
    let labelled = EvalConfig {
        noise_preset: Some("detector".into()),
        ..unlabelled
    };
    labelled.validate().unwrap();
    let no_target_gate = EvalConfig {
        variants: vec!["sornav".into(), "no-target-gate".into()],
        ..noiseless
    };
    no_target_gate.validate().unwrap();
}
