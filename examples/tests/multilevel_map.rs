//! The multi-level frontier map on depth rendered by platform-sim: after a
//! scripted walk up the stairs of a two-floor house, both levels and the
//! stair joining them are in the map, built only from the rendered frames
//! and the walker's poses.

use nalgebra::{Point3, Vector3};
use sornav::frontier_graph::{FrontierMapConfig, LevelId, MultiLevelMap};
use sornav::semantic_map::{PinholeCamera, optical_pose};
use sornav_platform_sim::{
    Camera, CameraConfig, CameraPose, NavMesh, NavMeshConfig, ProceduralConfig, Scene,
};

/// Depth frame -> world points (every `stride`-th pixel).
fn points(
    camera: &PinholeCamera,
    frame: &sornav_platform_sim::Frame,
    eye: &Point3<f64>,
    yaw: f64,
    stride: usize,
) -> Vec<Point3<f64>> {
    let pose = optical_pose(eye, yaw, 0.0);
    let (w, h) = (camera.width as usize, camera.height as usize);
    let mut out = Vec::new();
    for v in (0..h).step_by(stride) {
        for u in (0..w).step_by(stride) {
            let d = f64::from(frame.depth[v * w + u]);
            if d.is_finite() && d > 0.0 {
                out.push(pose * camera.back_project(u as f64, v as f64, d));
            }
        }
    }
    out
}

struct Walker {
    camera: Camera,
    pinhole: PinholeCamera,
    mount: f64,
    map: MultiLevelMap,
    frames: usize,
}

impl Walker {
    fn new(scene: &Scene) -> Self {
        let config = CameraConfig {
            width: 160,
            height: 120,
            ..CameraConfig::default()
        };
        let pinhole = PinholeCamera::from_hfov(160, 120, config.hfov_deg.to_radians());
        let mount = config.mount_height;
        Self {
            camera: Camera::for_scene(scene, config).expect("camera"),
            pinhole,
            mount,
            map: MultiLevelMap::new(FrontierMapConfig::default()).expect("map"),
            frames: 0,
        }
    }

    fn look(&mut self, feet: &Point3<f64>, yaw: f64) {
        let eye = feet + Vector3::new(0.0, 0.0, self.mount);
        let frame = self.camera.render(
            &CameraPose {
                position: eye,
                yaw,
                pitch: 0.0,
            },
            0,
        );
        let mut pts = points(&self.pinhole, &frame, &eye, yaw, 1);
        // The floor under the robot (the camera never sees it; the agent
        // adds the same footprint).
        for i in -3..=3 {
            for j in -3..=3 {
                let (dx, dy) = (0.05 * f64::from(i), 0.05 * f64::from(j));
                if dx.hypot(dy) <= 0.18 {
                    pts.push(Point3::new(feet.x + dx, feet.y + dy, feet.z));
                }
            }
        }
        self.map.update(feet, &eye, &pts).expect("update");
        self.frames += 1;
    }

    fn turn_around(&mut self, feet: &Point3<f64>) {
        for k in 0..12 {
            self.look(feet, f64::from(k) * std::f64::consts::TAU / 12.0);
        }
    }

    /// Walks `path` in 0.25 m steps, looking along it.
    fn walk(&mut self, path: &[Point3<f64>]) {
        for w in path.windows(2) {
            let d = w[1] - w[0];
            let len = d.xy().norm();
            if len < 1e-6 {
                continue;
            }
            let yaw = d.y.atan2(d.x);
            let n = (len / 0.25).ceil() as usize;
            for i in 1..=n {
                let p = w[0] + d * (i as f64 / n as f64);
                self.look(&p, yaw);
            }
        }
    }
}

fn walk_up(scene: &Scene, max_step: f64) -> Walker {
    walk(scene, max_step, false)
}

fn walk(scene: &Scene, max_step: f64, down: bool) -> Walker {
    let nav = NavMesh::build(
        scene,
        &NavMeshConfig {
            max_step,
            ..NavMeshConfig::default()
        },
    )
    .expect("navmesh");
    let levels = scene.levels();
    assert!(levels.len() >= 2, "a two-floor scene");
    let (z0, z1) = (levels[0].elevation, levels[1].elevation);
    // A floor point of each level: the walkable span nearest to the
    // level's centre of spans.
    let pick = |z: f64| {
        nav.spans()
            .iter()
            .enumerate()
            .map(|(i, _)| nav.span_center(i as u32))
            .filter(|c| (c.z - z).abs() < 0.05)
            .min_by(|a, b| (a.x + a.y).total_cmp(&(b.x + b.y)))
            .expect("a span on the level")
    };
    let (start, top) = if down {
        (pick(z1), pick(z0))
    } else {
        (pick(z0), pick(z1))
    };
    let path = nav
        .path(&start, &top)
        .expect("path query")
        .expect("floors connected");
    let mut walker = Walker::new(scene);
    walker.turn_around(&start);
    walker.walk(&path);
    walker.turn_around(&top);
    walker
}

fn check_two_levels(walker: &mut Walker, scene: &Scene, down: bool) {
    let _ = walker
        .map
        .frontier_graph(&Point3::new(0.0, 0.0, 0.0))
        .expect("graph");
    let levels: Vec<_> = walker.map.levels().collect();
    let (mut z0, mut z1) = (scene.levels()[0].elevation, scene.levels()[1].elevation);
    if down {
        std::mem::swap(&mut z0, &mut z1);
    }
    assert!(levels.len() >= 2, "levels {levels:?}");
    assert!((levels[0].floor_z - z0).abs() < 0.1, "{levels:?}");
    assert!(
        levels.iter().any(|l| (l.floor_z - z1).abs() < 0.15),
        "no level at {z1}: {levels:?}"
    );
    let robot = Point3::new(0.0, 0.0, z0);
    let _ = walker.map.frontier_graph(&robot).expect("graph");
    let stairs = walker.map.stairs();
    let upper = levels
        .iter()
        .find(|l| (l.floor_z - z1).abs() < 0.15)
        .map(|l| l.id)
        .unwrap_or(LevelId(1));
    let (lo, hi) = if down {
        (upper, LevelId(0))
    } else {
        (LevelId(0), upper)
    };
    let joining = stairs
        .iter()
        .find(|s| s.lower.level == Some(lo) && s.upper.level == Some(hi));
    if joining.is_none() {
        for s in stairs {
            for e in [&s.lower, &s.upper] {
                let p = e.position;
                for dy in -4..=4 {
                    let row: Vec<String> = (-4..=4)
                        .map(|dx| {
                            let v = walker
                                .map
                                .surfaces_at(p.x + 0.1 * f64::from(dx), p.y + 0.1 * f64::from(dy));
                            format!(
                                "{:?}",
                                v.iter()
                                    .map(|z| (z * 100.0).round() as i32)
                                    .collect::<Vec<_>>()
                            )
                        })
                        .collect();
                    eprintln!("{}", row.join(" "));
                }
                eprintln!("---");
            }
        }
    }
    assert!(
        joining.is_some(),
        "no stair joins level 0 and {upper:?}: {:?}",
        stairs
            .iter()
            .map(|s| (s.lower.clone(), s.upper.clone(), s.length))
            .collect::<Vec<_>>()
    );
    let s = joining.unwrap();
    // The stair climbs the storey in steps the robot can take.
    assert!(
        s.path
            .windows(2)
            .all(|w| (w[1].z - w[0].z).abs() <= 0.2 + 1e-6)
    );
    assert!(s.length >= (z1 - z0).abs() - 1e-6);
}

#[test]
fn procedural_two_floor_house() {
    let mut tried = 0;
    for seed in 0..40u64 {
        let scene = Scene::procedural(
            seed,
            &ProceduralConfig {
                floors: Some(2),
                ..ProceduralConfig::default()
            },
        )
        .expect("house");
        if scene.levels().len() < 2 {
            continue;
        }
        let mut walker = walk_up(&scene, 0.2);
        check_two_levels(&mut walker, &scene, false);
        let mut walker = walk(&scene, 0.2, true);
        check_two_levels(&mut walker, &scene, true);
        tried += 1;
        if tried == 3 {
            break;
        }
    }
    assert_eq!(tried, 3);
}
