//! `sornav-simbot`: a simulated Scout Mini with the CMU autonomy stack's
//! topics, for dry runs of `sornav-robot` without hardware.
//!
//! It loads a platform-sim scene (a seeded procedural house), stands a
//! robot in it, and over ROS 2 (RustDDS, loopback only):
//!
//! * publishes `/state_estimation` (`nav_msgs/Odometry`, the LiDAR frame in
//!   `map`), `/semantic_scan` (`x y z label`, a panoramic depth + semantic
//!   render labelled with the robot's default vocabulary), `/registered_scan`
//!   (the same returns, PCL's padded XYZI) and `/terrain_map` (returns
//!   within 5 m, 0.1 m voxels, intensity = height above the floor), best
//!   effort;
//! * follows the latest `/way_point` along the scene's NavMesh path, like
//!   the CMU local planner: only in autonomy mode (a `/joy` with
//!   `axes[2] < -0.1`, the CMU gotcha) and not while `/stop >= 1`.
//!
//! Run it with `sornav-robot` in one private network namespace (see
//! docs/ROBOT.md):
//! ```text
//! unshare --net sh -c 'ip link set lo up; sornav-simbot --seed 3 & sornav-robot --target tv'
//! ```

#![forbid(unsafe_code)]

#[path = "simbot/world.rs"]
mod world;

use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use clap::Parser;
use sornav::AgentConfig;
use sornav_examples::ros;
use sornav_platform_scout::contract::{Qos, Topics};
use sornav_platform_scout::msg::{
    Header, Int8, Joy, Odometry, Point, PointCloud2, PointStamped, Pose, PoseWithCovariance,
    Quaternion, Time, TwistWithCovariance,
};
use sornav_platform_scout::node;
use sornav_platform_scout::pointcloud::{encode_xyzi, encode_xyzl};
use sornav_platform_sim::{ProceduralConfig, Scene};

use world::World;

/// Command line.
#[derive(Debug, Parser)]
#[command(
    version,
    about = "Simulated Scout Mini + CMU stack topics for sornav-robot dry runs"
)]
struct Args {
    /// Procedural house seed.
    #[arg(long, default_value_t = 3)]
    seed: u64,
    /// Floors of the house.
    #[arg(long, default_value_t = 1)]
    floors: u32,
    /// Most rooms per floor.
    #[arg(long, default_value_t = 4)]
    max_rooms: u32,
    /// ROS domain id.
    #[arg(long, default_value_t = 0)]
    domain_id: u16,
    /// Start position `x,y` (default: the middle of the walkable area).
    #[arg(long, value_parser = parse_xy)]
    start: Option<[f64; 2]>,
    /// Forward speed (m/s).
    #[arg(long, default_value_t = 0.8)]
    speed: f64,
    /// LiDAR height above the floor (m); the odometry frame.
    #[arg(long, default_value_t = 0.55)]
    sensor_height: f64,
    /// Pixels per 90-degree face, `WxH`.
    #[arg(long, default_value = "96x72", value_parser = parse_wh)]
    resolution: (u32, u32),
    /// LiDAR / camera range (m).
    #[arg(long, default_value_t = 8.0)]
    range: f64,
    /// Scans per second.
    #[arg(long, default_value_t = 4.0)]
    scan_hz: f64,
    /// Stop after this many seconds (default: until Ctrl-C).
    #[arg(long)]
    duration_s: Option<f64>,
    /// Print the scene's objects of the robot vocabulary as JSON and exit.
    #[arg(long)]
    list_objects: bool,
}

fn parse_xy(s: &str) -> Result<[f64; 2], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>().map_err(|e| e.to_string()))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x, y] if x.is_finite() && y.is_finite() => Ok([x, y]),
        _ => Err("expected x,y".into()),
    }
}

fn parse_wh(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once('x').ok_or("expected WxH")?;
    let (w, h) = (
        w.parse::<u32>().map_err(|e| e.to_string())?,
        h.parse::<u32>().map_err(|e| e.to_string())?,
    );
    if (8..=1024).contains(&w) && (8..=1024).contains(&h) {
        Ok((w, h))
    } else {
        Err("width and height must be in 8..=1024".into())
    }
}

fn header(frame: &str) -> Header {
    Header::new(Time::now(), frame)
}

fn odometry(world: &World) -> Odometry {
    let p = world.position;
    Odometry {
        header: header("map"),
        child_frame_id: "sensor".into(),
        pose: PoseWithCovariance {
            pose: Pose {
                position: Point::new(p.x, p.y, p.z + world.sensor_height()),
                orientation: Quaternion::from_yaw(world.yaw),
            },
            covariance: [0.0; 36],
        },
        twist: TwistWithCovariance::default(),
    }
}

/// The clouds of one scan: the semantic cloud, and the registered and
/// terrain clouds when asked for (they are published at lower rates).
fn clouds(
    world: &World,
    seed: u64,
    registered: bool,
    terrain: bool,
) -> Result<(PointCloud2, Option<PointCloud2>, Option<PointCloud2>), String> {
    let returns = world.scan(seed);
    let e = |e: sornav_platform_scout::pointcloud::CloudError| e.to_string();
    let sem_rows: Vec<[f64; 4]> = returns
        .iter()
        .map(|r| [r.p[0], r.p[1], r.p[2], f64::from(r.label)])
        .collect();
    let semantic = encode_xyzl(header("map"), &sem_rows).map_err(e)?;
    let registered = if registered {
        let reg_rows: Vec<[f64; 4]> = returns
            .iter()
            .map(|r| [r.p[0], r.p[1], r.p[2], 0.0])
            .collect();
        Some(encode_xyzi(header("map"), &reg_rows).map_err(e)?)
    } else {
        None
    };
    let terrain = if terrain {
        // Returns within 5 m, one per 0.1 m voxel, intensity = height above
        // the floor under the robot.
        let floor = world.position.z;
        let mut seen = std::collections::HashSet::new();
        let ter_rows: Vec<[f64; 4]> = returns
            .iter()
            .filter(|r| (r.p[0] - world.position.x).hypot(r.p[1] - world.position.y) <= 5.0)
            .filter(|r| seen.insert(r.p.map(|c| (c * 10.0).floor() as i64)))
            .map(|r| [r.p[0], r.p[1], r.p[2], r.p[2] - floor])
            .collect();
        Some(encode_xyzi(header("map"), &ter_rows).map_err(e)?)
    } else {
        None
    };
    Ok((semantic, registered, terrain))
}

fn main() {
    if let Err(e) = run() {
        eprintln!("sornav-simbot: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    ros::init_logging();
    let args = Args::parse();
    let house = ProceduralConfig {
        floors: Some(args.floors),
        max_rooms_per_floor: args.max_rooms,
        ..ProceduralConfig::default()
    };
    let scene = Scene::procedural(args.seed, &house).map_err(|e| e.to_string())?;
    let vocabulary = AgentConfig::default().labels;
    let mut world = World::new(
        scene,
        &vocabulary,
        args.sensor_height,
        args.resolution.0,
        args.resolution.1,
        args.range,
        args.start,
    )?;
    if !(args.speed.is_finite() && args.speed > 0.0 && args.scan_hz > 0.0 && args.scan_hz <= 50.0) {
        return Err("speed must be positive and scan_hz in (0, 50]".into());
    }
    world.speed = args.speed;
    if args.list_objects {
        let labels = world.labels();
        let objects: Vec<serde_json::Value> = world
            .scene()
            .objects()
            .filter(|o| labels[o.id as usize] != world::UNLABELLED)
            .map(|o| {
                let c = o.bounds.center();
                serde_json::json!({"id": o.id, "category": o.category, "centre": [c.x, c.y, c.z]})
            })
            .collect();
        println!(
            "{}",
            serde_json::json!({"start": [world.position.x, world.position.y, world.position.z], "objects": objects})
        );
        return Ok(());
    }

    // Always loopback-only.
    let ctx = node::loopback_context(args.domain_id).map_err(|e| e.to_string())?;
    let mut n = node::ros_node(&ctx, "/", "sornav_simbot").map_err(|e| e.to_string())?;
    let t = Topics::default();
    let err = |e: node::NodeError| e.to_string();
    let odom_pub =
        node::publisher::<Odometry>(&mut n, &t.state_estimation, Qos::SENSOR).map_err(err)?;
    let sem_pub =
        node::publisher::<PointCloud2>(&mut n, &t.semantic_scan, Qos::SENSOR).map_err(err)?;
    let reg_pub =
        node::publisher::<PointCloud2>(&mut n, &t.registered_scan, Qos::SENSOR).map_err(err)?;
    let ter_pub =
        node::publisher::<PointCloud2>(&mut n, &t.terrain_map, Qos::SENSOR).map_err(err)?;
    // The CMU planner subscribes with ROS 2's default (reliable) QoS.
    let way_sub =
        node::subscription::<PointStamped>(&mut n, &t.way_point, Qos::COMMAND).map_err(err)?;
    let joy_sub = node::subscription::<Joy>(&mut n, &t.joy, Qos::COMMAND).map_err(err)?;
    let stop_sub = node::subscription::<Int8>(&mut n, &t.stop, Qos::COMMAND).map_err(err)?;

    let stop = ros::stop_on_ctrl_c().map_err(|e| e.to_string())?;
    tracing::info!(
        seed = args.seed,
        x = world.position.x,
        y = world.position.y,
        "simulated robot ready on domain {}",
        args.domain_id
    );
    let t0 = Instant::now();
    let dt = Duration::from_millis(50);
    let mut last_scan: Option<Instant> = None;
    let mut autonomy = false;
    let mut stopped = 0i8;
    let mut goal: Option<[f64; 3]> = None;
    let mut scans = 0u64;
    let mut last_tick = Instant::now();
    while !stop.load(Ordering::SeqCst)
        && args
            .duration_s
            .is_none_or(|d| t0.elapsed().as_secs_f64() < d)
    {
        if let Some(j) = node::latest(&joy_sub) {
            let a = j.axes.get(2).copied().unwrap_or(0.0);
            let now_auto = a < -0.1;
            if now_auto != autonomy {
                tracing::info!(autonomy = now_auto, "joystick mode");
            }
            autonomy = now_auto;
        }
        if let Some(s) = node::latest(&stop_sub) {
            stopped = s.data;
        }
        if let Some(w) = node::latest(&way_sub) {
            let g = [w.point.x, w.point.y, w.point.z];
            if goal != Some(g) {
                goal = Some(g);
                let ok = world.set_goal(g);
                tracing::info!(x = g[0], y = g[1], reachable = ok, "way point");
            }
        }
        let elapsed = last_tick.elapsed().as_secs_f64().min(0.2);
        last_tick = Instant::now();
        if autonomy && stopped < 1 {
            world.advance(elapsed);
        }
        odom_pub
            .publish(odometry(&world))
            .map_err(|e| format!("{e:?}"))?;
        if last_scan.is_none_or(|t| t.elapsed().as_secs_f64() >= 1.0 / args.scan_hz) {
            last_scan = Some(Instant::now());
            let (semantic, registered, terrain) = clouds(
                &world,
                scans,
                scans.is_multiple_of(2),
                scans.is_multiple_of(4),
            )?;
            sem_pub.publish(semantic).map_err(|e| format!("{e:?}"))?;
            if let Some(registered) = registered {
                reg_pub.publish(registered).map_err(|e| format!("{e:?}"))?;
            }
            if let Some(terrain) = terrain {
                ter_pub.publish(terrain).map_err(|e| format!("{e:?}"))?;
            }
            scans += 1;
        }
        std::thread::sleep(dt.saturating_sub(last_tick.elapsed()));
    }
    tracing::info!(
        travelled_m = world.odometer,
        scans,
        "simulated robot stopped"
    );
    Ok(())
}
