//! `sornav-robot` against `sornav-simbot` over real DDS, end to end: both
//! binaries run in one private network namespace (loopback only) on a
//! private domain id; the test, playing the operator, asks for a first
//! target, waits until the robot confirms one, then asks for a second one
//! and waits for the second confirmation, which must come from the same
//! agent (maps kept: its observation count keeps growing). Both confirmed
//! objects must lie within 1 m of a ground-truth instance of their category
//! in the procedural house, and Ctrl-C must stop the robot with `/stop = 2`.
//!
//! The targets are read from the house (`sornav-simbot --list-objects`):
//! the large goal category nearest the start, then the nearest one of
//! another category, so the test follows the generator if it changes.

use std::io::Write;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use nalgebra::Point3;
use sornav_platform_scout::bridge::{ConfirmedTarget, NodeState, Status};
use sornav_platform_scout::config::ScoutConfig;
use sornav_platform_scout::contract::Qos;
use sornav_platform_scout::msg::{Int8, RosString};
use sornav_platform_scout::node;
use sornav_platform_sim::{ProceduralConfig, Scene};
use sornav_test_support::netns;

/// A private ROS domain id.
const DOMAIN: u16 = 172;
/// Candidate houses (one floor, at most 4 rooms: the simbot's defaults).
const SEEDS: [u64; 6] = [2, 5, 4, 1, 3, 6];
/// Goal categories large enough to be seen from afar.
const GOALS: [&str; 4] = ["toilet", "tv_monitor", "bed", "sofa"];
/// Budget per target (s).
const BUDGET_S: u64 = 150;

struct Killer(Vec<Child>);

impl Drop for Killer {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

fn interrupt(child: &Child) {
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
}

/// The first seed whose house has two goal categories, with the two
/// targets: the goal object nearest the start, then the goal object of
/// another category nearest to it.
fn pick_house() -> (u64, String, String) {
    for seed in SEEDS {
        let out = Command::new(env!("CARGO_BIN_EXE_sornav-simbot"))
            .args(["--seed", &seed.to_string(), "--list-objects"])
            .output()
            .expect("run sornav-simbot --list-objects");
        assert!(out.status.success());
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let xy = |p: &serde_json::Value| (p[0].as_f64().unwrap(), p[1].as_f64().unwrap());
        let start = xy(&v["start"]);
        let objects: Vec<(String, (f64, f64))> = v["objects"]
            .as_array()
            .unwrap()
            .iter()
            .map(|o| (o["category"].as_str().unwrap().to_owned(), xy(&o["centre"])))
            .filter(|(c, _)| GOALS.contains(&c.as_str()))
            .collect();
        let d = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).hypot(a.1 - b.1);
        let Some(first) = objects
            .iter()
            .min_by(|a, b| d(a.1, start).total_cmp(&d(b.1, start)))
        else {
            continue;
        };
        if let Some(second) = objects
            .iter()
            .filter(|o| o.0 != first.0)
            .min_by(|a, b| d(a.1, first.1).total_cmp(&d(b.1, first.1)))
        {
            return (seed, first.0.clone(), second.0.clone());
        }
    }
    panic!("no candidate house has two goal categories");
}

/// The robot's log filter: its decisions (debug) and warnings.
const ROBOT_LOG: &str = "warn,sornav_platform_scout=debug";

fn log_file(dir: &std::path::Path, name: &str) -> std::fs::File {
    std::fs::File::create(dir.join(name)).expect("create a log file")
}

/// The last `n` lines of a log containing `needle`.
fn log_tail(path: &std::path::Path, needle: &str, n: usize) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let lines: Vec<&str> = text.lines().filter(|l| l.contains(needle)).collect();
    lines[lines.len().saturating_sub(n)..].join("\n")
}

fn request(category: &str) -> String {
    match category {
        "tv_monitor" => "find the television".to_owned(),
        c => format!("find the {c}"),
    }
}

fn truth_distance(scene: &Scene, c: &ConfirmedTarget) -> f64 {
    let p = Point3::new(c.centre[0], c.centre[1], c.centre[2]);
    scene
        .objects_of(&c.category)
        .map(|o| o.bounds.distance_to(&p))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn robot_confirms_two_targets_in_a_row_against_the_simulated_robot() {
    if !netns::isolate("robot_confirms_two_targets_in_a_row_against_the_simulated_robot") {
        return;
    }
    let (seed, first_target, second_target) = pick_house();
    eprintln!("house {seed}: {first_target}, then {second_target}");
    let dir = std::env::temp_dir().join(format!("sornav-robot-e2e-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let config_path = dir.join("robot.toml");
    let mut config = ScoutConfig::from_toml(ScoutConfig::EXAMPLE).unwrap();
    config.ros.domain_id = DOMAIN;
    config.rates.control_hz = 2.0;
    config.validate().unwrap();
    std::fs::File::create(&config_path)
        .unwrap()
        .write_all(config.to_toml().unwrap().as_bytes())
        .unwrap();

    let simbot = Command::new(env!("CARGO_BIN_EXE_sornav-simbot"))
        .args([
            "--seed",
            &seed.to_string(),
            "--domain-id",
            &DOMAIN.to_string(),
            "--speed",
            "1.5",
        ])
        .env("RUST_LOG", "warn")
        .stdout(Stdio::null())
        .stderr(log_file(&dir, "simbot.log"))
        .spawn()
        .expect("spawn sornav-simbot");
    let robot = Command::new(env!("CARGO_BIN_EXE_sornav-robot"))
        .arg("--config")
        .arg(&config_path)
        .args(["--status-every-s", "0"])
        .env("RUST_LOG", ROBOT_LOG)
        .stdout(Stdio::piped())
        .stderr(log_file(&dir, "robot.log"))
        .spawn()
        .expect("spawn sornav-robot");
    let mut children = Killer(vec![robot, simbot]);

    let ctx = node::loopback_context(DOMAIN).unwrap();
    let mut n = node::ros_node(&ctx, "/", "operator").unwrap();
    let target_pub = node::publisher::<RosString>(&mut n, "/sornav/target", Qos::COMMAND).unwrap();
    let status_sub =
        node::subscription::<RosString>(&mut n, "/sornav/status", Qos::COMMAND).unwrap();
    let stop_sub = node::subscription::<Int8>(&mut n, "/stop", Qos::COMMAND).unwrap();

    let mut last: Option<Status> = None;
    let poll = |last: &mut Option<Status>| {
        for s in node::drain(&status_sub, 1000).0 {
            *last = Some(serde_json::from_str(&s.data).expect("status JSON"));
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let search =
        |request: &str, category: &str, confirmed_before: usize, last: &mut Option<Status>| {
            let t0 = Instant::now();
            let mut sent: Option<Instant> = None;
            loop {
                assert!(
                    t0.elapsed() < Duration::from_secs(BUDGET_S),
                    "{request}: not confirmed in {BUDGET_S} s; last status {last:?}\n\
                     the robot's last decisions:\n{}",
                    log_tail(&dir.join("robot.log"), "decision", 40)
                );
                poll(last);
                let requested = last
                    .as_ref()
                    .is_some_and(|s| s.request.as_deref() == Some(request));
                if !requested
                    && n.subscription_count("/sornav/target") > 0
                    && sent.is_none_or(|t| t.elapsed() > Duration::from_secs(2))
                {
                    target_pub
                        .publish(RosString {
                            data: request.into(),
                        })
                        .unwrap();
                    sent = Some(Instant::now());
                }
                if let Some(s) = last
                    && requested
                    && s.confirmed.len() > confirmed_before
                {
                    assert_eq!(s.state, NodeState::Confirmed);
                    let c = s.confirmed.last().unwrap().clone();
                    assert_eq!(c.category, category);
                    return (s.clone(), t0.elapsed());
                }
            }
        };

    let (first, t1) = search(&request(&first_target), &first_target, 0, &mut last);
    let (second, t2) = search(&request(&second_target), &second_target, 1, &mut last);
    eprintln!("confirmed: {first_target} after {t1:?}, {second_target} after {t2:?}");

    // Same agent, maps kept: the counters continue from the first search.
    let (a1, a2) = (first.agent.unwrap(), second.agent.unwrap());
    assert!(
        a2.observations > a1.observations && a2.steps > a1.steps,
        "{a1:?} -> {a2:?}"
    );
    assert_eq!(second.confirmed[0], first.confirmed[0]);
    assert_eq!(
        second.bridge.rejected_messages,
        0,
        "last error: {:?}; rejections:\n{}",
        second.last_error,
        log_tail(&dir.join("robot.log"), "rejected", 10)
    );

    // Both objects are real instances of their category.
    let house = ProceduralConfig {
        floors: Some(1),
        max_rooms_per_floor: 4,
        ..ProceduralConfig::default()
    };
    let scene = Scene::procedural(seed, &house).unwrap();
    for c in &second.confirmed {
        let d = truth_distance(&scene, c);
        assert!(
            d < 1.0,
            "{} confirmed {d:.2} m from the nearest true instance",
            c.category
        );
    }

    // Ctrl-C: hold, /stop = 2, clean exit with the final status on stdout.
    let robot = children.0.remove(0);
    interrupt(&robot);
    let t0 = Instant::now();
    let mut stops = Vec::new();
    while t0.elapsed() < Duration::from_secs(5) && !stops.iter().any(|s: &Int8| s.data == 2) {
        stops.extend(node::drain(&stop_sub, 100).0);
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = robot.wait_with_output().unwrap();
    assert!(out.status.success(), "sornav-robot exit {:?}", out.status);
    assert!(
        stops.iter().any(|s| s.data == 2),
        "Ctrl-C publishes /stop = 2: {stops:?}"
    );
    let final_status: Status =
        serde_json::from_str(String::from_utf8_lossy(&out.stdout).trim()).expect("final status");
    assert_eq!(final_status.state, NodeState::Stopped);
    assert_eq!(final_status.confirmed.len(), 2);
    let simbot = children.0.remove(0);
    interrupt(&simbot);
    assert!(simbot.wait_with_output().unwrap().status.success());
}
