//! Camera throughput: 640x480 depth + semantic frames on an OBJ mesh.
//!
//! ```text
//! RAYON_NUM_THREADS=1 cargo run --release -p sornav-platform-sim --example bench_render -- \
//!     [/tmp/sornav-pcld/house_tess40.obj | procedural[:SEED]] [width height]
//! ```
//! Inputs come from `../shared/tools/pcld-gen/make-inputs` (the OBJ's
//! `g label_<id>` groups carry the labels). The camera follows the same 30-pose
//! trajectory through the house as the peer figures (camera 0.88 m, HFOV 79 deg).
//! `procedural[:SEED]` renders instead the procedural house of `bench_episodes`
//! (default configuration, seed 1 unless given) from 30 poses on its floor
//! (see `procedural`).
//! 5 repetitions of the 30 frames, the median is printed as one JSON line:
//! `{"mesh","triangles","width","height","frames","ms_per_frame","rays_per_s"}`.
//! Run it with `RAYON_NUM_THREADS=1` for the one-core figure.

use std::time::Instant;

use nalgebra::Point3;
use sornav_platform_sim::render::{Bvh, Camera, CameraConfig, CameraPose};
use sornav_platform_sim::{NavMesh, NavMeshConfig, ProceduralConfig, Scene, SpanId};

/// Vertices, triangles and one label per triangle.
type LabelledMesh = (Vec<[f32; 3]>, Vec<[u32; 3]>, Vec<u32>);

/// Reads vertices, faces and `g label_<id>` groups of an OBJ file.
fn load_obj(path: &str) -> Result<LabelledMesh, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let (mut v, mut f, mut labels) = (Vec::new(), Vec::new(), Vec::new());
    let mut label = 0u32;
    for (n, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        let bad = || format!("{path} line {}: cannot parse `{line}`", n + 1);
        match it.next() {
            Some("v") => {
                let c: Vec<f32> = it
                    .take(3)
                    .map(str::parse)
                    .collect::<Result<_, _>>()
                    .map_err(|_| bad())?;
                v.push(<[f32; 3]>::try_from(c).map_err(|_| bad())?);
            }
            Some("g") => {
                label = it
                    .next()
                    .and_then(|g| g.strip_prefix("label_"))
                    .and_then(|l| l.parse().ok())
                    .unwrap_or(0);
            }
            Some("f") => {
                let idx: Vec<u32> = it
                    .map(|t| {
                        t.split('/')
                            .next()
                            .and_then(|i| i.parse::<u32>().ok())
                            .filter(|i| *i > 0)
                            .map(|i| i - 1)
                    })
                    .collect::<Option<_>>()
                    .ok_or_else(bad)?;
                // Fan-triangulate polygons.
                for k in 1..idx.len().saturating_sub(1) {
                    f.push([idx[0], idx[k], idx[k + 1]]);
                    labels.push(label);
                }
            }
            _ => {}
        }
    }
    Ok((v, f, labels))
}

/// The benchmark trajectory of the peer figures: a loop through the house's
/// door gaps with a sinusoidal look-around, `n` poses.
fn trajectory(n: usize, height: f64) -> Vec<CameraPose> {
    let wp = [
        (3.5, 1.5),
        (5.0, 3.0),
        (6.0, 4.0),
        (8.0, 2.5),
        (10.5, 5.5),
        (7.5, 5.5),
        (6.0, 4.0),
        (4.5, 4.0),
        (3.0, 4.5),
        (3.8, 6.2),
        (4.5, 8.0),
    ];
    let mut cum = vec![0.0f64; wp.len()];
    for i in 1..wp.len() {
        cum[i] = cum[i - 1] + f64::hypot(wp[i].0 - wp[i - 1].0, wp[i].1 - wp[i - 1].1);
    }
    (0..n)
        .map(|k| {
            let s = cum[wp.len() - 1] * k as f64 / (n.max(2) - 1) as f64;
            let mut i = 1;
            while i < wp.len() - 1 && cum[i] < s {
                i += 1;
            }
            let a = (s - cum[i - 1]) / (cum[i] - cum[i - 1]);
            let x = wp[i - 1].0 + a * (wp[i].0 - wp[i - 1].0);
            let y = wp[i - 1].1 + a * (wp[i].1 - wp[i - 1].1);
            let heading = f64::atan2(wp[i].1 - wp[i - 1].1, wp[i].0 - wp[i - 1].0);
            CameraPose {
                position: Point3::new(x, y, height),
                yaw: heading + 0.6 * (0.7 * k as f64).sin(),
                pitch: 0.0,
            }
        })
        .collect()
}

/// The procedural house `seed` (default configuration, as `bench_episodes`)
/// and `n` poses on its floor spans (evenly spread over the span list,
/// headings turning by 2.4 rad), camera 0.88 m above the floor.
fn procedural(
    seed: u64,
    n: usize,
    config: CameraConfig,
) -> Result<(Camera, Vec<CameraPose>, usize), String> {
    let scene = Scene::procedural(seed, &ProceduralConfig::default()).map_err(|e| e.to_string())?;
    let nav = NavMesh::build(&scene, &NavMeshConfig::default()).map_err(|e| e.to_string())?;
    let floor: Vec<SpanId> = (0..nav.span_count() as SpanId)
        .filter(|s| nav.is_floor_span(*s))
        .collect();
    if floor.is_empty() {
        return Err("no floor spans".into());
    }
    let poses = (0..n)
        .map(|k| {
            let p = nav.span_center(floor[k * floor.len() / n]);
            CameraPose {
                position: Point3::new(p.x, p.y, p.z + config.mount_height),
                yaw: 2.4 * k as f64,
                pitch: 0.0,
            }
        })
        .collect();
    let triangles = scene.triangles().len();
    let camera = Camera::for_scene(&scene, config).map_err(|e| e.to_string())?;
    Ok((camera, poses, triangles))
}

/// User + system CPU time of this process in seconds (Linux `/proc`; 10 ms
/// resolution), or `None` elsewhere.
fn process_cpu_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are the
    // 12th and 13th of them (fields 14 and 15 of the whole line).
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .cloned()
        .unwrap_or_else(|| "/tmp/sornav-pcld/house_tess40.obj".into());
    let width: u32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(640);
    let height: u32 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(480);
    let config = CameraConfig {
        width,
        height,
        ..CameraConfig::default()
    };
    let (camera, poses, triangles) = if let Some(seed) = path.strip_prefix("procedural") {
        let seed = seed.trim_start_matches(':').parse().unwrap_or(1);
        procedural(seed, 30, config)?
    } else {
        let (v, f, labels) = load_obj(&path)?;
        let camera = Camera::new(
            Bvh::build(&v, &f, &labels).map_err(|e| e.to_string())?,
            config,
        )
        .map_err(|e| e.to_string())?;
        (camera, trajectory(30, 0.88), f.len())
    };
    let bvh = camera.bvh();
    eprintln!(
        "BVH: {} triangles, {} references, {} nodes, depth {}",
        bvh.triangle_count(),
        bvh.reference_count(),
        bvh.node_count(),
        bvh.depth(),
    );
    // Warm-up (and a sanity figure: fraction of pixels with a depth return).
    let valid: usize = poses
        .iter()
        .map(|p| camera.render(p, 0).valid_depth_count())
        .sum();
    eprintln!(
        "valid depth fraction {:.3}",
        valid as f64 / (poses.len() as f64 * f64::from(width * height))
    );
    let mut ms = Vec::new();
    let mut cpu_ms = Vec::new();
    for _ in 0..5 {
        let (t, c) = (Instant::now(), process_cpu_s());
        for p in &poses {
            std::hint::black_box(camera.render(p, 0));
        }
        ms.push(t.elapsed().as_secs_f64() * 1e3 / poses.len() as f64);
        if let (Some(c0), Some(c1)) = (c, process_cpu_s()) {
            cpu_ms.push((c1 - c0) * 1e3 / poses.len() as f64);
        }
    }
    cpu_ms.sort_by(f64::total_cmp);
    if let Some(c) = cpu_ms.get(cpu_ms.len() / 2) {
        // On a shared machine wall time includes waiting for the CPU; this is
        // the CPU time actually spent (all threads), for comparison.
        eprintln!(
            "median CPU time per frame {c:.3} ms ({:.0} rays per CPU-second)",
            f64::from(width * height) / (c / 1e3)
        );
    }
    ms.sort_by(f64::total_cmp);
    let med = ms[ms.len() / 2];
    let rays = f64::from(width * height) / (med / 1e3);
    println!(
        "{{\"mesh\":\"{}\",\"triangles\":{},\"width\":{width},\"height\":{height},\"frames\":{},\"ms_per_frame\":{med:.3},\"rays_per_s\":{rays:.0}}}",
        std::path::Path::new(&path)
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("?"),
        triangles,
        poses.len()
    );
    Ok(())
}
