//! `sornav-robot`: the SOR-Nav agent on an AgileX Scout Mini with the CMU
//! autonomy stack, over ROS 2 (pure Rust: ros2-client + RustDDS).
//!
//! ```text
//! sornav-robot --config scout_mini.toml [--target "find the toilet"] [--domain-id N]
//! sornav-robot --print-config      # the committed example configuration
//! ```
//!
//! Loads the Scout TOML, subscribes to the CMU stack's odometry, registered
//! scan, terrain map, the labelled `/semantic_scan` and `/sornav/target`,
//! runs the agent at the configured control rate (1 Hz) and publishes
//! `/way_point`, `/joy` (autonomy mode), `/sornav/status`,
//! `/sornav/markers` and `/sornav/path`. New requests on `/sornav/target`
//! start a new search with the maps kept. Ctrl-C holds the robot, publishes
//! `/stop = 2` and exits. See docs/ROBOT.md.

#![forbid(unsafe_code)]

use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::time::Duration;

use clap::Parser;
use sornav_examples::ros;
use sornav_platform_scout::config::ScoutConfig;
use sornav_platform_scout::node::RobotNode;

/// Command line.
#[derive(Debug, Parser)]
#[command(
    version,
    about = "SOR-Nav on a Scout Mini with the CMU autonomy stack (ROS 2)"
)]
struct Args {
    /// Robot configuration (TOML); default: the committed Scout Mini example.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Target to search at start (overrides `initial_target`).
    #[arg(long)]
    target: Option<String>,
    /// ROS domain id (overrides `ROS_DOMAIN_ID`, which overrides
    /// `ros.domain_id`).
    #[arg(long)]
    domain_id: Option<u16>,
    /// Print the example configuration and exit.
    #[arg(long)]
    print_config: bool,
    /// Print the status JSON every this many seconds (0: never; at most
    /// one day).
    #[arg(long, default_value_t = 5.0, value_parser = parse_status_every)]
    status_every_s: f64,
}

/// Longest accepted `--status-every-s`: one day.
const MAX_STATUS_EVERY_S: f64 = 86_400.0;

/// `--status-every-s`: finite, in `[0, MAX_STATUS_EVERY_S]` (`inf` and
/// `1e300` panicked converting to a duration once the node was up).
fn parse_status_every(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|e| format!("{e}"))?;
    if !(0.0..=MAX_STATUS_EVERY_S).contains(&v) {
        return Err(format!(
            "{v}: need a number of seconds from 0 (never) to {MAX_STATUS_EVERY_S}"
        ));
    }
    Ok(v)
}

/// mimalloc instead of the system allocator: the node runs for hours with
/// several DDS threads and clouds of varying size, and glibc's per-thread
/// arenas kept freed memory (the robot soak in the README: a flat heap of
/// about 145 MB under valgrind's massif, but resident memory growing about
/// 3-4 MiB a minute with the system allocator; flat with mimalloc).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    if let Err(e) = run() {
        eprintln!("sornav-robot: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    ros::init_logging();
    let args = Args::parse();
    if args.print_config {
        print!("{}", ScoutConfig::EXAMPLE);
        return Ok(());
    }
    let mut config = match &args.config {
        Some(path) => ScoutConfig::from_toml_file(path).map_err(|e| e.to_string())?,
        None => ScoutConfig::from_toml(ScoutConfig::EXAMPLE).map_err(|e| e.to_string())?,
    };
    if let Some(t) = args.target {
        config.initial_target = Some(t);
    }
    // --domain-id, else ROS_DOMAIN_ID, else the configuration's
    config
        .apply_ros_domain_id_env(std::env::var("ROS_DOMAIN_ID").ok().as_deref())
        .map_err(|e| e.to_string())?;
    if let Some(d) = args.domain_id {
        config.ros.domain_id = d;
    }
    config.validate().map_err(|e| e.to_string())?;
    let stop = ros::stop_on_ctrl_c().map_err(|e| e.to_string())?;
    let mut robot = RobotNode::new(config).map_err(|e| e.to_string())?;
    tracing::info!("sornav-robot running; Ctrl-C to stop");
    let every = (args.status_every_s > 0.0).then(|| Duration::from_secs_f64(args.status_every_s));
    let mut last_print = robot.now();
    robot.start();
    while !stop.load(Ordering::SeqCst) {
        robot.spin_once();
        if let Some(every) = every
            && robot.now().saturating_sub(last_print) >= every
        {
            last_print = robot.now();
            let status = robot.bridge().status(last_print);
            eprintln!("{}", serde_json::to_string(&status).unwrap_or_default());
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    tracing::info!("stopping: holding the robot and publishing /stop = 2");
    robot.shutdown(Duration::from_millis(500));
    let status = robot.bridge().status(robot.now());
    println!("{}", serde_json::to_string(&status).unwrap_or_default());
    Ok(())
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::Args;

    /// Issue 21: `--status-every-s inf` (or 1e300) panicked after the DDS
    /// node was up; such values are now argument errors, found before any
    /// DDS participant exists.
    #[test]
    fn status_interval_must_be_a_finite_bounded_number() {
        for bad in ["inf", "1e300", "nan", "-1", "86400.5", "soon"] {
            assert!(
                Args::try_parse_from(["sornav-robot", "--status-every-s", bad]).is_err(),
                "{bad} accepted"
            );
        }
        for good in ["0", "5", "0.25", "86400"] {
            let a = Args::try_parse_from(["sornav-robot", "--status-every-s", good]).unwrap();
            assert_eq!(a.status_every_s, good.parse::<f64>().unwrap());
        }
        assert_eq!(
            Args::try_parse_from(["sornav-robot"])
                .unwrap()
                .status_every_s,
            5.0
        );
    }
}
