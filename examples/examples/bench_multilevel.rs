//! Multi-level frontier map timings on rendered depth (issue 18's two-floor
//! case): a scripted walk over a two-floor house at 640x480, every frame
//! integrated by `MultiLevelMap::update` and G_F refreshed after it, then a
//! full rebuild of every level. Prints one JSON line (medians over `REPS`
//! walks): update p50/p99 (ms per frame, scan + surfaces + one level's
//! grid and frontiers), refresh p50/p99 (ms, stair extraction + level
//! graphs + the composed G_F), rebuild (ms).
//!
//! The two-floor case lives here, not in frontier-graph's
//! `bench_frontier_graph`, because it renders depth with platform-sim
//! (which frontier-graph must not depend on).
//!
//! `cargo run --release -p sornav-examples --example bench_multilevel [SEED]`

use std::time::Instant;

use nalgebra::Point3;
use sornav_examples::walk::{Walker, level_corner};
use sornav_platform_sim::{ProceduralConfig, Scene};

const REPS: usize = 3;

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

fn median(mut v: Vec<f64>) -> f64 {
    percentile(&mut v, 0.5)
}

fn main() -> Result<(), String> {
    let seed: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    // The largest two-floor house among a few seeds.
    let scene = (seed..seed + 20)
        .filter_map(|s| {
            Scene::procedural(
                s,
                &ProceduralConfig {
                    floors: Some(2),
                    ..ProceduralConfig::default()
                },
            )
            .ok()
        })
        .filter(|s| s.levels().len() >= 2)
        .max_by(|a, b| {
            let area = |s: &Scene| {
                let b = s.bounds();
                (b.max.x - b.min.x) * (b.max.y - b.min.y)
            };
            area(a).total_cmp(&area(b))
        })
        .ok_or("no two-floor house")?;
    let (Some((nav, a)), Some((_, b))) = (level_corner(&scene, 0)?, level_corner(&scene, 1)?)
    else {
        return Err("no levels".into());
    };
    let up = nav
        .path(&a, &b)
        .map_err(|e| e.to_string())?
        .ok_or("floors not connected")?;
    let (mut upd50, mut upd99, mut ref50, mut ref99, mut rebuild) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut frames = 0;
    let mut levels = 0;
    let mut stairs = 0;
    let mut frontiers = 0;
    for _ in 0..REPS {
        let mut w = Walker::new(
            &scene,
            640,
            480,
            sornav::frontier_graph::FrontierMapConfig::default(),
        )?;
        let mut refresh = Vec::new();
        let mut step = |w: &mut Walker, p: &Point3<f64>, yaw: f64| -> Result<(), String> {
            w.look(p, yaw).map_err(|e| e.to_string())?;
            refresh.push(
                w.refresh_times
                    .last()
                    .map_or(0.0, |d| d.as_secs_f64() * 1e3),
            );
            Ok(())
        };
        for k in 0..12 {
            step(&mut w, &a, f64::from(k) * std::f64::consts::TAU / 12.0)?;
        }
        for s in up.windows(2) {
            let d = s[1] - s[0];
            let len = d.xy().norm();
            if len < 1e-6 {
                continue;
            }
            let n = (len / 0.25).ceil() as usize;
            for i in 1..=n {
                step(&mut w, &(s[0] + d * (i as f64 / n as f64)), d.y.atan2(d.x))?;
            }
        }
        for k in 0..12 {
            step(&mut w, &b, f64::from(k) * std::f64::consts::TAU / 12.0)?;
        }
        let mut upd: Vec<f64> = w
            .update_times
            .iter()
            .map(|d| d.as_secs_f64() * 1e3)
            .collect();
        upd50.push(percentile(&mut upd, 0.5));
        upd99.push(percentile(&mut upd, 0.99));
        ref50.push(percentile(&mut refresh, 0.5));
        ref99.push(percentile(&mut refresh, 0.99));
        let t = Instant::now();
        w.map.rebuild();
        w.map.frontier_graph(&b).map_err(|e| e.to_string())?;
        rebuild.push(t.elapsed().as_secs_f64() * 1e3);
        frames = w.frames;
        levels = w.map.levels().count();
        stairs = w.map.stairs().len();
        frontiers = w.map.graph().len();
    }
    let bounds = scene.bounds();
    println!(
        "{{\"bench\":\"multilevel\",\"house_m\":[{:.1},{:.1}],\"frames\":{frames},\"levels\":{levels},\"stairs\":{stairs},\"frontiers\":{frontiers},\"update_ms_p50\":{:.2},\"update_ms_p99\":{:.2},\"refresh_ms_p50\":{:.2},\"refresh_ms_p99\":{:.2},\"rebuild_ms\":{:.1},\"reps\":{REPS}}}",
        bounds.max.x - bounds.min.x,
        bounds.max.y - bounds.min.y,
        median(upd50),
        median(upd99),
        median(ref50),
        median(ref99),
        median(rebuild)
    );
    Ok(())
}
