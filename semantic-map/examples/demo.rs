//! Runnable demo of the semantic map: builds persistent object clusters and
//! prints them.
//!
//! ```text
//! cargo run --release -p sornav-semantic-map --example demo            # synthetic room, depth camera
//! cargo run --release -p sornav-semantic-map --example demo -- FILE    # a SORPCLD1 point-cloud file
//! ```
//! Without an argument it renders a labelled 6 x 5 m room (bed, table, two
//! chairs, tv, plant) with the paper's camera (640x480, HFOV 79 deg, 0.88 m,
//! depth 0.5-5 m) doing the 12-turn start scan from two places, integrates
//! each depth + label image, updates the clusters after every frame and
//! prints them. With a file it integrates that file's frames instead.

use std::process::ExitCode;
use std::time::Instant;

use nalgebra::{Point3, Vector3};
use sornav_semantic_map::pcld::read_sorpcld;
use sornav_semantic_map::{
    DepthFrame, DepthOptions, IntegrationStats, LabelId, LabelSet, MapConfig, MapError,
    PinholeCamera, SemanticMap, optical_pose,
};

/// An axis-aligned labelled box of the synthetic room.
struct Solid {
    min: Vector3<f64>,
    max: Vector3<f64>,
    label: LabelId,
}

fn room() -> Vec<Solid> {
    let b = |min: [f64; 3], max: [f64; 3], label: u16| Solid {
        min: Vector3::from(min),
        max: Vector3::from(max),
        label: LabelId(label),
    };
    vec![
        b([0.0, 0.0, -0.1], [6.0, 5.0, 0.0], 2), // floor
        b([0.0, 0.0, 2.6], [6.0, 5.0, 2.7], 3),  // ceiling
        b([-0.1, 0.0, 0.0], [0.0, 5.0, 2.6], 1), // walls
        b([6.0, 0.0, 0.0], [6.1, 5.0, 2.6], 1),
        b([0.0, -0.1, 0.0], [6.0, 0.0, 2.6], 1),
        b([0.0, 5.0, 0.0], [6.0, 5.1, 2.6], 1),
        b([0.3, 3.0, 0.0], [2.3, 4.8, 0.5], 12),  // bed
        b([3.5, 1.0, 0.0], [4.7, 1.8, 0.75], 11), // table
        b([3.0, 1.2, 0.0], [3.4, 1.6, 0.9], 10),  // chair
        b([4.8, 1.2, 0.0], [5.2, 1.6, 0.9], 10),  // chair
        b([5.85, 3.0, 1.0], [6.0, 4.2, 1.7], 15), // tv
        b([0.3, 0.3, 0.0], [0.6, 0.6, 1.2], 16),  // plant
    ]
}

/// Nearest entry distance of the ray `o + t d` into `s` (slab test).
fn hit(s: &Solid, o: &Vector3<f64>, d: &Vector3<f64>) -> Option<f64> {
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for i in 0..3 {
        if d[i].abs() < 1e-12 {
            if o[i] < s.min[i] || o[i] > s.max[i] {
                return None;
            }
            continue;
        }
        let (a, b) = ((s.min[i] - o[i]) / d[i], (s.max[i] - o[i]) / d[i]);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    (t0 <= t1 && t0 > 0.0).then_some(t0)
}

fn synthetic(map: &mut SemanticMap) -> Result<(usize, IntegrationStats), MapError> {
    let cam = PinholeCamera::from_hfov(640, 480, 79f64.to_radians());
    let solids = room();
    let mut total = IntegrationStats::default();
    let mut frames = 0;
    let (mut depth, mut labels) = (Vec::new(), Vec::new());
    for (x, y) in [(3.0, 2.6), (2.0, 1.8)] {
        for turn in 0..12 {
            let pose = optical_pose(
                &Point3::new(x, y, 0.88),
                f64::from(turn) * 30f64.to_radians(),
                0.0,
            );
            let rot = pose.rotation.to_rotation_matrix();
            let o = pose.translation.vector;
            depth.clear();
            labels.clear();
            for v in 0..cam.height {
                for u in 0..cam.width {
                    // Ray per unit z-depth: t along it is the z-depth.
                    let d = rot
                        * Vector3::new(
                            (f64::from(u) - cam.cx) / cam.fx,
                            (f64::from(v) - cam.cy) / cam.fy,
                            1.0,
                        );
                    let best = solids
                        .iter()
                        .filter_map(|s| hit(s, &o, &d).map(|t| (t, s.label)))
                        .min_by(|a, b| a.0.total_cmp(&b.0));
                    let (t, l) = best.unwrap_or((f64::INFINITY, LabelId(0)));
                    depth.push(t as f32);
                    labels.push(l);
                }
            }
            let frame = DepthFrame {
                camera: &cam,
                pose: &pose,
                depth: &depth,
                labels: &labels,
            };
            total.accumulate(&map.integrate_depth(&frame, &DepthOptions::default())?);
            map.update_clusters();
            frames += 1;
        }
    }
    Ok((frames, total))
}

fn main() -> ExitCode {
    let labels = LabelSet::household();
    let mut map = match SemanticMap::new(MapConfig::default(), labels.clone()) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    };
    let start = Instant::now();
    let result = match std::env::args().nth(1) {
        Some(path) => read_sorpcld(&path)
            .map_err(|e| format!("{path}: {e}"))
            .and_then(|frames| {
                let mut total = IntegrationStats::default();
                for f in &frames {
                    let s = map
                        .integrate_points(&f.origin, &f.points)
                        .map_err(|e| e.to_string())?;
                    total.accumulate(&s);
                    map.update_clusters();
                }
                Ok((frames.len(), total))
            }),
        None => synthetic(&mut map).map_err(|e| e.to_string()),
    };
    let (frames, stats) = match result {
        Ok(r) => r,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    };
    println!(
        "{frames} frames, {} points: {} fused, {} rejected ({} non-finite, {} out of range, {} out of bounds) in {:.2} s",
        stats.points,
        stats.accepted,
        stats.rejected(),
        stats.rejected_non_finite,
        stats.rejected_range,
        stats.rejected_bounds,
        start.elapsed().as_secs_f64()
    );
    println!(
        "{} voxels in {} blocks, {} object voxels, {} clusters, {:.1} MB",
        map.voxel_count(),
        map.block_count(),
        map.object_voxel_count(),
        map.cluster_count(),
        map.heap_bytes() as f64 / 1e6
    );
    println!(
        "\n{:>5}  {:<8} {:>7}  {:>22}  {:>17}  {:>4}",
        "id", "label", "support", "centre (m)", "size (m)", "obs"
    );
    for c in map.clusters() {
        let name = labels
            .name(c.label)
            .map_or_else(|| c.label.to_string(), str::to_owned);
        let e = c.bounds.extents();
        println!(
            "{:>5}  {:<8} {:>7}  ({:>6.2},{:>6.2},{:>5.2})  {:>4.2}x{:>4.2}x{:>4.2}  {:>4}",
            c.id.to_string(),
            name,
            c.support,
            c.centre.x,
            c.centre.y,
            c.centre.z,
            e.x,
            e.y,
            e.z,
            c.observations
        );
    }
    ExitCode::SUCCESS
}
