//! Criterion benches of the hot paths: point integration, depth-image
//! integration, incremental cluster update and from-scratch clustering.
//!
//! Point benches use the standard `SORPCLD1` inputs from
//! `shared/tools/pcld-gen/make-inputs` (directory `$SORNAV_PCLD_DIR`,
//! default `/tmp/sornav-pcld`) and are skipped with a message when absent;
//! the depth-image bench is synthetic and always runs.
//!
//! ```text
//! cargo bench -p sornav-semantic-map --bench hot_paths
//! ```
#![allow(missing_docs)]

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use nalgebra::Point3;
use sornav_semantic_map::pcld::{PointFrame, read_sorpcld};
use sornav_semantic_map::{
    DepthFrame, DepthOptions, LabelId, LabelSet, MapConfig, PinholeCamera, SemanticMap,
    optical_pose,
};

fn load(name: &str) -> Option<Vec<PointFrame>> {
    let dir = std::env::var_os("SORNAV_PCLD_DIR")
        .map_or_else(|| PathBuf::from("/tmp/sornav-pcld"), PathBuf::from);
    match read_sorpcld(dir.join(name)) {
        Ok(f) if !f.is_empty() => Some(f),
        _ => {
            eprintln!("SKIPPED {name}: run shared/tools/pcld-gen/make-inputs first");
            None
        }
    }
}

fn new_map() -> SemanticMap {
    SemanticMap::new(MapConfig::default(), LabelSet::household()).expect("default config")
}

/// Map after integrating and clustering frames `..k`.
fn warm_map(frames: &[PointFrame], k: usize) -> SemanticMap {
    let mut map = new_map();
    for f in &frames[..k] {
        map.integrate_points(&f.origin, &f.points)
            .expect("finite origin");
        map.update_clusters();
    }
    map
}

fn point_benches(c: &mut Criterion) {
    for (name, file) in [
        ("640x480", "room_depth_640x480.bin"),
        ("160x120", "room_depth_160x120.bin"),
        ("livox20k", "livox_mid360_20k.bin"),
    ] {
        let Some(frames) = load(file) else { continue };
        let k = frames.len() / 2;
        let base = warm_map(&frames, k);
        let f = &frames[k];
        c.bench_function(&format!("integrate_points/{name}"), |b| {
            b.iter_batched(
                || base.clone(),
                |mut map| black_box(map.integrate_points(&f.origin, &f.points)),
                BatchSize::LargeInput,
            )
        });
        c.bench_function(&format!("update_clusters/{name}"), |b| {
            b.iter_batched(
                || {
                    let mut map = base.clone();
                    let _ = map.integrate_points(&f.origin, &f.points);
                    map
                },
                |mut map| black_box(map.update_clusters()),
                BatchSize::LargeInput,
            )
        });
        if name == "640x480" {
            let mut all = new_map();
            for f in &frames {
                let _ = all.integrate_points(&f.origin, &f.points);
            }
            c.bench_function("cluster_from_scratch/640x480", |b| {
                b.iter_batched(
                    || all.clone(),
                    |mut map| black_box(map.update_clusters()),
                    BatchSize::LargeInput,
                )
            });
        }
    }
}

fn depth_bench(c: &mut Criterion) {
    // A 640x480 view of a wall 3 m ahead; left third labelled chair.
    let cam = PinholeCamera::from_hfov(640, 480, 79f64.to_radians());
    let pose = optical_pose(&Point3::new(0.0, 0.0, 0.88), 0.3, 0.1);
    let n = 640 * 480;
    let depth: Vec<f32> = (0..n).map(|i| 3.0 + (i % 640) as f32 * 1e-3).collect();
    let labels: Vec<LabelId> = (0..n)
        .map(|i| {
            if i % 640 < 213 {
                LabelId(10)
            } else {
                LabelId(1)
            }
        })
        .collect();
    let frame = DepthFrame {
        camera: &cam,
        pose: &pose,
        depth: &depth,
        labels: &labels,
    };
    let mut map = new_map();
    let opts = DepthOptions::default();
    c.bench_function("integrate_depth/640x480_synthetic", |b| {
        b.iter(|| black_box(map.integrate_depth(&frame, &opts)))
    });
}

criterion_group! {
    // The macro-generated group function cannot carry a doc comment.
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    targets = point_benches, depth_bench
}
criterion_main!(benches);
