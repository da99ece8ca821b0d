//! Times the gate's hot paths and prints one JSON line of medians.
//!
//! `cargo run --release -p sornav-target-gate --example bench_gate`
//!
//! * `update_us`: one `TargetGate::update` with a 200-cluster map snapshot
//!   (64 of the target category, random detections, negative evidence on).
//! * `remap_us`: one `apply_remap` of 16 merge/split pairs on 64 tracks.

use std::time::Instant;

use nalgebra::Point3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sornav_target_gate::{CandidateReport, GateConfig, ObjectId, TargetGate};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let cfg = GateConfig {
        negative_evidence: true,
        n_miss: 50,
        ..GateConfig::default()
    };
    let frames: Vec<Vec<CandidateReport<u16>>> = (0..500)
        .map(|_| {
            (0..200u64)
                .map(|i| CandidateReport {
                    object: ObjectId(i),
                    category: if i < 64 { 1 } else { (i % 40) as u16 + 2 },
                    voxels: rng.random_range(5..200),
                    centre: Point3::new(
                        rng.random_range(-20.0..20.0),
                        rng.random_range(-20.0..20.0),
                        0.5,
                    ),
                    detected: rng.random_bool(0.3),
                })
                .collect()
        })
        .collect();
    let robot = Point3::origin();
    let visible = |o: ObjectId, _: &Point3<f64>| o.0.is_multiple_of(3);

    let mut update_us = Vec::new();
    let mut remap_us = Vec::new();
    for _ in 0..7 {
        let mut gate = TargetGate::new(1u16, cfg).unwrap();
        let start = Instant::now();
        for f in &frames {
            gate.update_with_visibility(f, &robot, &visible).unwrap();
        }
        update_us.push(start.elapsed().as_secs_f64() * 1e6 / frames.len() as f64);

        let pairs: Vec<(ObjectId, ObjectId)> = (0..8u64)
            .flat_map(|i| {
                [
                    (ObjectId(2 * i), ObjectId(2 * i + 1)),
                    (ObjectId(40 + i), ObjectId(1000 + i)),
                ]
            })
            .collect();
        let reps = 200;
        let start = Instant::now();
        for _ in 0..reps {
            let mut g = gate.clone();
            g.apply_remap(&pairs);
            std::hint::black_box(&g);
        }
        remap_us.push(start.elapsed().as_secs_f64() * 1e6 / f64::from(reps));
    }
    println!(
        "{{\"bench\":\"target-gate\",\"clusters\":200,\"candidates\":64,\"update_us\":{:.2},\"remap_us\":{:.2}}}",
        median(update_us),
        median(remap_us)
    );
}
