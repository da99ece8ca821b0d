//! Integration and incremental-clustering benchmark on a `SORPCLD1` file.
//!
//! ```text
//! cargo run --release -p sornav-semantic-map --example bench_integrate -- FILE [REPS]
//! ```
//! Integrates every frame with label evidence into a fresh map (0.05 m,
//! household labels), runs incremental clustering after each frame, repeats
//! `REPS` times (default 5) on one thread, and prints one JSON line of
//! medians: `input, frames, points, integrate_ms_per_frame,
//! cluster_ms_per_frame, points_per_s, voxels, clusters, heap_bytes`.

use std::process::ExitCode;
use std::time::Instant;

use sornav_semantic_map::pcld::read_sorpcld;
use sornav_semantic_map::{LabelSet, MapConfig, SemanticMap};

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else {
        eprintln!("usage: bench_integrate FILE [REPS]");
        return ExitCode::from(2);
    };
    let reps: usize = match args.get(1).map(|s| s.parse()) {
        None => 5,
        Some(Ok(n)) if n > 0 => n,
        Some(_) => {
            eprintln!("REPS must be a positive integer");
            return ExitCode::from(2);
        }
    };
    let frames = match read_sorpcld(path) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("{path}: {e}");
            return ExitCode::FAILURE;
        }
    };
    let points: usize = frames.iter().map(|f| f.points.len()).sum();
    let n = frames.len().max(1) as f64;
    let (mut integ, mut clus, mut pps) = (Vec::new(), Vec::new(), Vec::new());
    let (mut voxels, mut clusters, mut heap) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..reps {
        let mut map = match SemanticMap::new(MapConfig::default(), LabelSet::household()) {
            Ok(m) => m,
            Err(e) => {
                eprintln!("{e}");
                return ExitCode::FAILURE;
            }
        };
        let (mut ti, mut tc) = (0.0f64, 0.0f64);
        for f in &frames {
            let t0 = Instant::now();
            let stats = map.integrate_points(&f.origin, &f.points);
            let t1 = Instant::now();
            std::hint::black_box(map.update_clusters());
            let t2 = Instant::now();
            if let Err(e) = stats {
                eprintln!("{e}");
                return ExitCode::FAILURE;
            }
            ti += (t1 - t0).as_secs_f64();
            tc += (t2 - t1).as_secs_f64();
        }
        integ.push(ti * 1e3 / n);
        clus.push(tc * 1e3 / n);
        pps.push(points as f64 / ti.max(1e-12));
        voxels.push(map.voxel_count() as f64);
        clusters.push(map.cluster_count() as f64);
        heap.push(map.heap_bytes() as f64);
    }
    // Side figure (stderr, not part of the JSON contract): clustering every
    // object voxel from scratch, as one update after all frames.
    let mut scratch = Vec::new();
    let mut object_voxels = 0;
    for _ in 0..reps {
        let Ok(mut map) = SemanticMap::new(MapConfig::default(), LabelSet::household()) else {
            break;
        };
        for f in &frames {
            let _ = map.integrate_points(&f.origin, &f.points);
        }
        object_voxels = map.object_voxel_count();
        let t = Instant::now();
        std::hint::black_box(map.update_clusters());
        scratch.push(t.elapsed().as_secs_f64() * 1e3);
    }
    eprintln!(
        "from-scratch clustering of all {} object voxels: median {:.3} ms",
        object_voxels,
        median(&mut scratch)
    );
    let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    eprintln!(
        "min over {reps} reps: integrate {:.4} ms/frame, cluster {:.4} ms/frame",
        min(&integ),
        min(&clus)
    );
    let input = std::path::Path::new(path)
        .file_name()
        .map_or_else(|| path.clone(), |s| s.to_string_lossy().into_owned());
    println!(
        "{{\"input\":\"{}\",\"frames\":{},\"points\":{},\"integrate_ms_per_frame\":{:.4},\"cluster_ms_per_frame\":{:.4},\"points_per_s\":{:.0},\"voxels\":{},\"clusters\":{},\"heap_bytes\":{}}}",
        input.replace('\\', "\\\\").replace('"', "\\\""),
        frames.len(),
        points,
        median(&mut integ),
        median(&mut clus),
        median(&mut pps),
        median(&mut voxels),
        median(&mut clusters),
        median(&mut heap),
    );
    ExitCode::SUCCESS
}
