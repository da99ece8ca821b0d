//! Soak of the robot pipeline: `sornav-robot` against `sornav-simbot` over
//! real DDS for a fixed time, one robot process throughout (maps never
//! reset), targets requested one after another in a cycle over the goal
//! categories of the house, with the resident memory of both processes and
//! the robot's counters sampled at a fixed interval.
//!
//! Writes one CSV row per sample (`elapsed_s, robot_rss_kib,
//! simbot_rss_kib, requests, confirmed, observations, objects, frontiers,
//! rejected, missing_samples`) to `--csv` and prints one JSON line at the
//! end: requests, confirmations, searches that ran out of their budget,
//! memory at the first and last sample and its maximum, rejected messages,
//! estimated lost samples, and whether Ctrl-C stopped the robot cleanly.
//!
//! DDS must stay on loopback: run it inside a private network namespace
//! (it refuses to start otherwise), after building the binaries:
//!
//! ```text
//! cargo build --release -p sornav-examples --bins --example soak_robot
//! unshare --net sh -c 'ip link set lo up && exec target/release/examples/soak_robot --minutes 30 --csv soak_robot.csv'
//! ```

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use clap::Parser;
use sornav_platform_scout::bridge::{NodeState, Status};
use sornav_platform_scout::config::ScoutConfig;
use sornav_platform_scout::contract::Qos;
use sornav_platform_scout::msg::RosString;
use sornav_platform_scout::node;

/// Goal categories cycled through, in this order, when the house has them.
const GOALS: [&str; 6] = ["toilet", "tv_monitor", "bed", "sofa", "chair", "plant"];

#[derive(Parser, Debug)]
#[command(
    about = "Soak of sornav-robot against sornav-simbot (run in a private network namespace)"
)]
struct Args {
    /// Run time (minutes).
    #[arg(long, default_value_t = 30.0)]
    minutes: f64,
    /// The simulated house's seed.
    #[arg(long, default_value_t = 2)]
    seed: u64,
    /// Sampling interval (s).
    #[arg(long, default_value_t = 10.0)]
    interval_s: f64,
    /// Budget of one search (s); a search still running then counts as
    /// timed out and the next target is requested.
    #[arg(long, default_value_t = 150.0)]
    budget_s: f64,
    /// The simulated robot's speed (m/s).
    #[arg(long, default_value_t = 1.5)]
    speed: f64,
    /// Private ROS domain id.
    #[arg(long, default_value_t = 173)]
    domain_id: u16,
    /// Folder of `sornav-robot` and `sornav-simbot` (default: the parent of
    /// this example's folder, i.e. `target/release`).
    #[arg(long)]
    bin_dir: Option<PathBuf>,
    /// CSV of the samples.
    #[arg(long, default_value = "soak_robot.csv")]
    csv: PathBuf,
    /// Folder for the two programs' logs (default: the system's temp dir).
    #[arg(long)]
    log_dir: Option<PathBuf>,
}

/// Kills the children on every exit path.
struct Children(Vec<Child>);

impl Drop for Children {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// Resident memory (KiB) of a process, from `/proc`.
fn rss_kib(pid: u32) -> Option<u64> {
    let text = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    text.lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
}

fn request(category: &str) -> String {
    match category {
        "tv_monitor" => "find the television".to_owned(),
        c => format!("find the {c}"),
    }
}

/// The goal categories of the house, in [`GOALS`] order.
fn house_goals(simbot: &Path, seed: u64) -> Result<Vec<String>, String> {
    let out = Command::new(simbot)
        .args(["--seed", &seed.to_string(), "--list-objects"])
        .output()
        .map_err(|e| format!("run {}: {e}", simbot.display()))?;
    if !out.status.success() {
        return Err(format!("{} --list-objects failed", simbot.display()));
    }
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).map_err(|e| format!("--list-objects: {e}"))?;
    let present: Vec<&str> = v["objects"]
        .as_array()
        .map(|a| a.iter().filter_map(|o| o["category"].as_str()).collect())
        .unwrap_or_default();
    Ok(GOALS
        .iter()
        .filter(|g| present.contains(g))
        .map(|g| (*g).to_owned())
        .collect())
}

fn main() -> Result<(), String> {
    let args = Args::parse();
    if !sornav_test_support::netns::only_loopback() {
        return Err(format!(
            "refusing to start DDS: this network namespace has interfaces {:?} besides lo; \
             run inside `unshare --net sh -c 'ip link set lo up && exec ...'`",
            sornav_test_support::netns::interfaces()
        ));
    }
    if !(args.minutes > 0.0 && args.interval_s > 0.0 && args.budget_s > 0.0) {
        return Err("--minutes, --interval-s and --budget-s must be positive".into());
    }
    let bin_dir = match &args.bin_dir {
        Some(d) => d.clone(),
        None => std::env::current_exe()
            .map_err(|e| e.to_string())?
            .parent()
            .and_then(Path::parent)
            .ok_or("cannot locate the binaries' folder; pass --bin-dir")?
            .to_owned(),
    };
    let (robot_bin, simbot_bin) = (bin_dir.join("sornav-robot"), bin_dir.join("sornav-simbot"));
    let goals = house_goals(&simbot_bin, args.seed)?;
    if goals.len() < 2 {
        return Err(format!(
            "house {} has fewer than two goal categories: {goals:?}",
            args.seed
        ));
    }
    let log_dir = args.log_dir.clone().unwrap_or_else(std::env::temp_dir);
    std::fs::create_dir_all(&log_dir).map_err(|e| e.to_string())?;
    let log =
        |name: &str| std::fs::File::create(log_dir.join(name)).map_err(|e| format!("{name}: {e}"));

    let mut config = ScoutConfig::from_toml(ScoutConfig::EXAMPLE).map_err(|e| e.to_string())?;
    config.ros.domain_id = args.domain_id;
    config.rates.control_hz = 2.0;
    config.validate().map_err(|e| e.to_string())?;
    let config_path = log_dir.join("soak_robot.toml");
    std::fs::write(&config_path, config.to_toml().map_err(|e| e.to_string())?)
        .map_err(|e| e.to_string())?;

    let simbot = Command::new(&simbot_bin)
        .args(["--seed", &args.seed.to_string()])
        .args(["--domain-id", &args.domain_id.to_string()])
        .args(["--speed", &args.speed.to_string()])
        .env("RUST_LOG", "warn")
        .stdout(Stdio::null())
        .stderr(log("soak_simbot.log")?)
        .spawn()
        .map_err(|e| format!("spawn {}: {e}", simbot_bin.display()))?;
    let robot = Command::new(&robot_bin)
        .arg("--config")
        .arg(&config_path)
        .args(["--status-every-s", "0"])
        .env("RUST_LOG", "warn")
        .stdout(Stdio::null())
        .stderr(log("soak_robot.log")?)
        .spawn()
        .map_err(|e| format!("spawn {}: {e}", robot_bin.display()))?;
    let (robot_pid, simbot_pid) = (robot.id(), simbot.id());
    let mut children = Children(vec![robot, simbot]);

    let ctx = node::loopback_context(args.domain_id).map_err(|e| e.to_string())?;
    let mut n = node::ros_node(&ctx, "/", "soak_operator").map_err(|e| e.to_string())?;
    let target_pub = node::publisher::<RosString>(&mut n, "/sornav/target", Qos::COMMAND)
        .map_err(|e| e.to_string())?;
    let status_sub = node::subscription::<RosString>(&mut n, "/sornav/status", Qos::COMMAND)
        .map_err(|e| e.to_string())?;

    let mut csv = std::fs::File::create(&args.csv).map_err(|e| e.to_string())?;
    writeln!(
        csv,
        "elapsed_s,robot_rss_kib,simbot_rss_kib,requests,confirmed,observations,objects,frontiers,rejected,missing_samples"
    )
    .map_err(|e| e.to_string())?;

    let t0 = Instant::now();
    let end = Duration::from_secs_f64(args.minutes * 60.0);
    let budget = Duration::from_secs_f64(args.budget_s);
    let interval = Duration::from_secs_f64(args.interval_s);
    let mut last: Option<Status> = None;
    let (mut requests, mut confirmed, mut timed_out, mut exhausted) = (0u64, 0u64, 0u64, 0u64);
    let mut search_s: Vec<f64> = Vec::new();
    let mut rss: Vec<(u64, u64)> = Vec::new();
    let mut next_sample = Duration::ZERO;
    let mut goal = 0usize;
    // The current search: request, its start, the confirmations before it,
    // the last time it was (re-)sent.
    let mut search: Option<(String, Instant, usize, Option<Instant>)> = None;
    while t0.elapsed() < end {
        if let Some(status) = children
            .0
            .iter_mut()
            .find_map(|c| c.try_wait().ok().flatten())
        {
            return Err(format!("a child exited during the soak: {status}"));
        }
        for s in node::drain(&status_sub, 1000).0 {
            if let Ok(st) = serde_json::from_str::<Status>(&s.data) {
                last = Some(st);
            }
        }
        let confirmations = last.as_ref().map_or(0, |s| s.confirmed.len());
        let (req, started, before, sent) = search.get_or_insert_with(|| {
            let r = request(&goals[goal % goals.len()]);
            goal += 1;
            requests += 1;
            (r, Instant::now(), confirmations, None)
        });
        let requested = last
            .as_ref()
            .is_some_and(|s| s.request.as_deref() == Some(req.as_str()));
        if !requested
            && n.subscription_count("/sornav/target") > 0
            && sent.is_none_or(|t| t.elapsed() > Duration::from_secs(2))
        {
            target_pub
                .publish(RosString { data: req.clone() })
                .map_err(|e| e.to_string())?;
            *sent = Some(Instant::now());
        }
        let state = last.as_ref().map(|s| s.state);
        if requested && confirmations > *before && state == Some(NodeState::Confirmed) {
            confirmed += 1;
            search_s.push(started.elapsed().as_secs_f64());
            search = None;
        } else if requested
            && matches!(
                state,
                Some(NodeState::Exhausted | NodeState::FloorExhausted)
            )
            && started.elapsed() > Duration::from_secs(10)
        {
            exhausted += 1;
            search = None;
        } else if started.elapsed() > budget {
            timed_out += 1;
            search = None;
        }
        if t0.elapsed() >= next_sample {
            next_sample += interval;
            let (r, s) = (
                rss_kib(robot_pid).unwrap_or(0),
                rss_kib(simbot_pid).unwrap_or(0),
            );
            rss.push((r, s));
            let st = last.as_ref();
            let missing: u64 = st.map_or(0, |s| s.streams.values().map(|v| v.lost).sum());
            writeln!(
                csv,
                "{:.0},{r},{s},{requests},{confirmed},{},{},{},{},{missing}",
                t0.elapsed().as_secs_f64(),
                st.and_then(|s| s.agent.as_ref())
                    .map_or(0, |a| a.observations),
                st.map_or(0, |s| s.objects),
                st.map_or(0, |s| s.frontiers),
                st.map_or(0, |s| s.bridge.rejected_messages),
            )
            .map_err(|e| e.to_string())?;
            csv.flush().map_err(|e| e.to_string())?;
        }
        std::thread::sleep(Duration::from_millis(100));
    }

    // Ctrl-C: the robot must stop cleanly.
    let robot = children.0.remove(0);
    let _ = Command::new("kill")
        .args(["-INT", &robot_pid.to_string()])
        .status();
    let exit = robot.wait_with_output().map_err(|e| e.to_string())?;
    let st = last.as_ref();
    let max = |f: fn(&(u64, u64)) -> u64| rss.iter().map(f).max().unwrap_or(0);
    search_s.sort_by(f64::total_cmp);
    let median = search_s.get(search_s.len() / 2).copied();
    println!(
        "{}",
        serde_json::json!({
            "minutes": args.minutes,
            "seed": args.seed,
            "goals": goals,
            "requests": requests,
            "confirmed": confirmed,
            "exhausted": exhausted,
            "timed_out": timed_out,
            "unfinished": requests - confirmed - exhausted - timed_out,
            "search_s_p50": median,
            "robot_rss_kib": {
                "first": rss.first().map(|r| r.0),
                "last": rss.last().map(|r| r.0),
                "max": max(|r| r.0),
            },
            "simbot_rss_kib": {
                "first": rss.first().map(|r| r.1),
                "last": rss.last().map(|r| r.1),
                "max": max(|r| r.1),
            },
            "observations": st.and_then(|s| s.agent.as_ref()).map(|a| a.observations),
            "rejected_messages": st.map(|s| s.bridge.rejected_messages),
            "rejections": st.map(|s| s.rejections.clone()),
            "missing_samples": st.map(|s| s.streams.values().map(|v| v.lost).sum::<u64>()),
            "silences": st.map(|s| s.streams.values().map(|v| v.silences).sum::<u64>()),
            "robot_exit_ok": exit.status.success(),
            "csv": args.csv,
        })
    );
    Ok(())
}
