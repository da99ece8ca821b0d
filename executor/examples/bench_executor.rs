//! Times the executor's per-step monitoring and prints one JSON line of
//! medians.
//!
//! `cargo run --release -p sornav-executor --example bench_executor`
//!
//! * `tick_us_path500`: one `Executor::tick` on a mission with a 500-point
//!   path (arrival, validity, timeout, projection onto the path, stuck
//!   window).
//! * `tick_us_nopath`: the same without a path.
//! * `submit_us`: one pre-empting `submit` (rule check, outcome, dispatch).

use std::time::{Duration, Instant};

use nalgebra::Point3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sornav_executor::{
    AlwaysValid, Executor, ExecutorConfig, FrontierId, Mission, MissionKind, MotionError,
    MotionStack, RobotPose, SimClock,
};

struct Null;
impl MotionStack for Null {
    fn dispatch(&mut self, _m: &Mission) -> Result<(), MotionError> {
        Ok(())
    }
    fn cancel(&mut self) {}
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let path: Vec<Point3<f64>> = (0..500)
        .map(|i| Point3::new(i as f64 * 0.2, (i as f64 * 0.1).sin(), 0.0))
        .collect();
    let waypoint = path[path.len() - 1];
    let poses: Vec<RobotPose> = (0..2000)
        .map(|_| {
            RobotPose::new(
                Point3::new(
                    rng.random_range(0.0..90.0),
                    rng.random_range(-2.0..2.0),
                    0.0,
                ),
                rng.random_range(-3.0..3.0),
            )
        })
        .collect();
    let config = ExecutorConfig {
        explore: sornav_executor::KindConfig {
            timeout_s: None,
            ..ExecutorConfig::default().explore
        },
        stuck_window_s: 1e6,
        ..ExecutorConfig::default()
    };
    let run = |with_path: bool| {
        let mut exec =
            Executor::new(config, Null, SimClock::new(Duration::from_millis(100))).unwrap();
        let mut m = Mission::new(
            MissionKind::Explore {
                frontier: FrontierId(0),
            },
            waypoint,
        );
        if with_path {
            m = m.with_path(path.clone());
        }
        exec.submit(m).unwrap();
        let start = Instant::now();
        for p in &poses {
            exec.clock_mut().advance(1);
            std::hint::black_box(exec.tick(p, &AlwaysValid).unwrap());
        }
        start.elapsed().as_secs_f64() * 1e6 / poses.len() as f64
    };
    let mut with_path = Vec::new();
    let mut without = Vec::new();
    let mut submit = Vec::new();
    for _ in 0..7 {
        with_path.push(run(true));
        without.push(run(false));
        let mut exec =
            Executor::new(config, Null, SimClock::new(Duration::from_millis(100))).unwrap();
        let start = Instant::now();
        for i in 0..2000u64 {
            let m = Mission::new(
                MissionKind::Explore {
                    frontier: FrontierId(i),
                },
                waypoint,
            );
            std::hint::black_box(exec.submit(m).unwrap());
            if i % 64 == 0 {
                exec.drain_events();
            }
        }
        submit.push(start.elapsed().as_secs_f64() * 1e6 / 2000.0);
    }
    println!(
        "{{\"bench\":\"executor\",\"tick_us_path500\":{:.3},\"tick_us_nopath\":{:.3},\"submit_us\":{:.3}}}",
        median(with_path),
        median(without),
        median(submit)
    );
}
