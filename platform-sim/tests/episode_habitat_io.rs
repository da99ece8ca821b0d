//! Habitat ObjectNav JSON(.gz) reader/writer on the real `val_mini` files.

use std::path::{Path, PathBuf};

use serde_json::Value;
use sornav_platform_sim::agent::wrap_angle;
use sornav_platform_sim::episodes::{
    HabitatDataset, point_from_habitat, point_to_habitat, yaw_from_habitat, yaw_to_habitat,
};

fn files() -> Option<Vec<PathBuf>> {
    let dir = sornav_test_support::shared_data("objectnav-val-mini")?;
    let mut f: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    f.sort();
    assert!(
        f.len() >= 9,
        "expected the 9 val_mini files, found {}",
        f.len()
    );
    Some(f)
}

/// Numeric-tolerant structural equality (integers written as floats compare equal).
fn same(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => x.as_f64() == y.as_f64(),
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| same(p, q))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same(v, w)))
        }
        _ => a == b,
    }
}

fn raw_json(path: &Path) -> Value {
    use std::io::Read;
    let mut s = String::new();
    flate2::read::GzDecoder::new(std::fs::File::open(path).unwrap())
        .read_to_string(&mut s)
        .unwrap();
    serde_json::from_str(&s).unwrap()
}

#[test]
fn every_val_mini_file_parses_and_round_trips_losslessly() {
    let Some(files) = files() else { return };
    let out = std::env::temp_dir().join(format!("sornav-episode-io-{}", std::process::id()));
    let mut total_episodes = 0;
    for f in &files {
        let data = HabitatDataset::read(f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        // Every field of the file survives: compare the JSON trees.
        let written = out.join(f.file_name().unwrap());
        data.write(&written).unwrap();
        assert!(
            same(&raw_json(f), &raw_json(&written)),
            "{} changed in the round trip",
            f.display()
        );
        let again = HabitatDataset::read(&written).unwrap();
        assert_eq!(data, again);
        // Conversion to the z-up frame resolves every episode's goals.
        let eps = data
            .to_episodes()
            .unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert_eq!(eps.len(), data.episodes.len());
        for e in &eps {
            assert!(
                !e.goals.is_empty(),
                "{}: episode {} without goals",
                f.display(),
                e.episode_id
            );
            assert!(e.goals.iter().all(|g| g.category == e.object_category));
            assert!(e.geodesic_distance.is_some_and(|d| d > 0.0));
            assert!(e.goals.iter().any(|g| !g.view_points.is_empty()));
        }
        // z-up -> Habitat -> z-up is lossless for the fields we use.
        if !eps.is_empty() {
            let back = HabitatDataset::from_episodes(&eps, &[])
                .to_episodes()
                .unwrap();
            assert_eq!(back.len(), eps.len());
            for (a, b) in eps.iter().zip(&back) {
                assert_eq!(a.episode_id, b.episode_id);
                assert_eq!(a.object_category, b.object_category);
                assert!((a.start_position - b.start_position).norm() < 1e-12);
                assert!(angle_diff(a.start_yaw, b.start_yaw) < 1e-9);
                assert_eq!(a.goals.len(), b.goals.len());
                for (g, h) in a.goals.iter().zip(&b.goals) {
                    assert_eq!(g.object_id, h.object_id);
                    assert!((g.position - h.position).norm() < 1e-12);
                    assert_eq!(g.view_points.len(), h.view_points.len());
                    for (v, w) in g.view_points.iter().zip(&h.view_points) {
                        assert!((v.position - w.position).norm() < 1e-12);
                        assert!(angle_diff(v.yaw, w.yaw) < 1e-9);
                    }
                }
            }
        }
        total_episodes += eps.len();
    }
    assert!(total_episodes >= 150, "only {total_episodes} episodes");
    std::fs::remove_dir_all(&out).ok();
}

fn angle_diff(a: f64, b: f64) -> f64 {
    wrap_angle(a - b).abs()
}

#[test]
fn split_and_content_layout_round_trips() {
    let Some(files) = files() else { return };
    // Build a split from the two HM3D v1 scene files, write it in
    // habitat-lab's layout and read it back through the split file.
    let mut merged = HabitatDataset::read(
        files
            .iter()
            .find(|f| f.ends_with("hm3d_v1_val_mini.json.gz"))
            .unwrap(),
    )
    .unwrap();
    assert!(
        merged.episodes.is_empty(),
        "the split file holds no episodes"
    );
    for f in files.iter().filter(|f| {
        let n = f.file_name().unwrap().to_str().unwrap();
        n.starts_with("hm3d_v1_val_mini_") && !n.contains("single")
    }) {
        merged.merge(HabitatDataset::read(f).unwrap());
    }
    assert_eq!(merged.episodes.len(), 30);
    let dir = std::env::temp_dir().join(format!("sornav-split-{}", std::process::id()));
    let written = merged.write_split(&dir, "val_mini").unwrap();
    assert_eq!(written.len(), 3, "split file + two content files");
    let back = HabitatDataset::read_split(&dir.join("val_mini.json.gz")).unwrap();
    assert_eq!(back.episodes.len(), merged.episodes.len());
    let a = merged.to_episodes().unwrap();
    let mut b = back.to_episodes().unwrap();
    b.sort_by_key(|e| {
        a.iter()
            .position(|x| x.episode_id == e.episode_id && x.scene_id == e.scene_id)
    });
    assert_eq!(a, b);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn frames_convert_with_a_proper_rotation() {
    // Habitat's forward (-z) is +y here; up (+y) is +z; right (+x) stays +x.
    assert_eq!(
        point_from_habitat([0.0, 0.0, -1.0]).coords,
        nalgebra::Vector3::new(0.0, 1.0, 0.0)
    );
    assert_eq!(
        point_from_habitat([0.0, 1.0, 0.0]).coords,
        nalgebra::Vector3::new(0.0, 0.0, 1.0)
    );
    assert_eq!(
        point_to_habitat(&point_from_habitat([1.5, -2.0, 3.25])),
        [1.5, -2.0, 3.25]
    );
    // Identity rotation looks along Habitat's -z = +y here (yaw 90 deg).
    let yaw = yaw_from_habitat([0.0, 0.0, 0.0, 1.0]).unwrap();
    assert!((yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    for k in -12..12 {
        let y = f64::from(k) * 0.5;
        let back = yaw_from_habitat(yaw_to_habitat(y)).unwrap();
        assert!(angle_diff(y, back) < 1e-12);
    }
    assert!(yaw_from_habitat([0.0, 0.0, 0.0, 0.0]).is_none());
    assert!(yaw_from_habitat([f64::NAN, 0.0, 0.0, 1.0]).is_none());
}

#[test]
fn malformed_files_are_typed_errors() {
    let dir = std::env::temp_dir().join(format!("sornav-bad-ep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("bad.json");
    std::fs::write(&p, "{\"episodes\": [{\"episode_id\": 3}]}").unwrap();
    assert!(matches!(
        HabitatDataset::read(&p),
        Err(sornav_platform_sim::episodes::EpisodeError::Json { .. })
    ));
    let gz = dir.join("trunc.json.gz");
    std::fs::write(&gz, [0x1f, 0x8b, 8, 0, 0]).unwrap();
    assert!(HabitatDataset::read(&gz).is_err());
    assert!(HabitatDataset::read(&dir.join("missing.json")).is_err());
    // An episode whose goals are nowhere.
    std::fs::write(
        &p,
        r#"{"episodes":[{"episode_id":"1","scene_id":"a/b.glb","start_position":[0,0,0],"start_rotation":[0,0,0,1],"object_category":"bed","info":{"geodesic_distance":2.0},"goals":[]}]}"#,
    )
    .unwrap();
    let d = HabitatDataset::read(&p).unwrap();
    assert!(matches!(
        d.to_episodes(),
        Err(sornav_platform_sim::episodes::EpisodeError::MissingGoals { .. })
    ));
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 21: a small `.json.gz` decompressed without bound (a 1.5 MB file
/// took 1.65 GB). A file inflating to one byte more than the limit is
/// refused, naming the limit, after reading at most that many bytes; one at
/// the limit is read.
#[test]
fn decompression_is_bounded() {
    use sornav_platform_sim::episodes::{EpisodeError, MAX_EPISODE_FILE_BYTES};
    use std::io::Write;
    let dir = std::env::temp_dir().join(format!("sornav-gz-bomb-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let gz = |name: &str, text_len: usize| {
        let path = dir.join(name);
        let mut enc = flate2::write::GzEncoder::new(
            std::fs::File::create(&path).unwrap(),
            flate2::Compression::fast(),
        );
        let head = br#"{"episodes":[]}"#;
        enc.write_all(head).unwrap();
        let spaces = vec![b' '; 1 << 20];
        let mut left = text_len - head.len();
        while left > 0 {
            let n = left.min(spaces.len());
            enc.write_all(&spaces[..n]).unwrap();
            left -= n;
        }
        enc.finish().unwrap();
        path
    };
    let bomb = gz("bomb.json.gz", MAX_EPISODE_FILE_BYTES + 1);
    assert!(std::fs::metadata(&bomb).unwrap().len() < 2 << 20);
    let began = std::time::Instant::now();
    match HabitatDataset::read(&bomb) {
        Err(e @ EpisodeError::TooLarge { limit, .. }) => {
            assert_eq!(limit, MAX_EPISODE_FILE_BYTES);
            assert!(e.to_string().contains("MAX_EPISODE_FILE_BYTES"), "{e}");
        }
        other => panic!("expected TooLarge, got {other:?}"),
    }
    assert!(began.elapsed() < std::time::Duration::from_secs(10));
    let at_limit = gz("at_limit.json.gz", MAX_EPISODE_FILE_BYTES);
    assert!(HabitatDataset::read(&at_limit).unwrap().episodes.is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}
