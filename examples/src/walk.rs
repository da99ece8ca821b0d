//! A scripted walk through a simulator scene that feeds rendered depth to
//! a [`MultiLevelMap`]: the rendered-depth fixture of the multi-level map's
//! tests and of `bench_multilevel`. Only the rendered frames and the
//! walker's poses reach the map (plus the robot's footprint, as the agent
//! adds it).

use std::time::{Duration, Instant};

use nalgebra::{Point3, Vector3};
use sornav::frontier_graph::{FrontierError, FrontierMapConfig, MultiLevelMap};
use sornav::semantic_map::{PinholeCamera, optical_pose};
use sornav::{AgentConfig, occupancy_stride};
use sornav_platform_sim::{
    Camera, CameraConfig, CameraPose, Frame, NavMesh, NavMeshConfig, RenderError, Scene,
};

/// Depth frame -> world points (every `stride`-th pixel).
fn points(
    camera: &PinholeCamera,
    frame: &Frame,
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

/// A camera walking through a scene, mapping what it sees.
#[derive(Debug)]
pub struct Walker {
    camera: Camera,
    pinhole: PinholeCamera,
    mount: f64,
    /// Pixel stride of the points fed to the map: the agent's (at most
    /// `AgentConfig::occupancy_max_columns` columns, same stride in rows).
    stride: usize,
    /// The map being built.
    pub map: MultiLevelMap,
    /// Frames integrated so far.
    pub frames: usize,
    /// Time spent in [`MultiLevelMap::update`] per frame.
    pub update_times: Vec<Duration>,
    /// Time spent in [`MultiLevelMap::frontier_graph`] per frame.
    pub refresh_times: Vec<Duration>,
}

impl Walker {
    /// A walker with a `width` x `height` camera (Habitat's HFOV and mount
    /// height) and an empty map with `config`; frames reach the map
    /// subsampled as the agent subsamples them (every 4th pixel in each
    /// direction at 640x480, every pixel at 160x120).
    ///
    /// # Errors
    /// The camera's and the map's construction errors, as strings.
    pub fn new(
        scene: &Scene,
        width: u32,
        height: u32,
        config: FrontierMapConfig,
    ) -> Result<Self, String> {
        let camera_config = CameraConfig {
            width,
            height,
            ..CameraConfig::default()
        };
        let pinhole = PinholeCamera::from_hfov(width, height, camera_config.hfov_deg.to_radians());
        let mount = camera_config.mount_height;
        Ok(Self {
            camera: Camera::for_scene(scene, camera_config)
                .map_err(|e: RenderError| e.to_string())?,
            pinhole,
            mount,
            stride: occupancy_stride(1, width, AgentConfig::default().occupancy_max_columns),
            map: MultiLevelMap::new(config).map_err(|e| e.to_string())?,
            frames: 0,
            update_times: Vec::new(),
            refresh_times: Vec::new(),
        })
    }

    /// Renders the view from `feet` facing `yaw`, integrates it (with the
    /// robot's footprint: the floor under it is never in view) and
    /// refreshes G_F, as the agent does at every step.
    ///
    /// # Errors
    /// The map's errors.
    pub fn look(&mut self, feet: &Point3<f64>, yaw: f64) -> Result<(), FrontierError> {
        let eye = feet + Vector3::new(0.0, 0.0, self.mount);
        let frame = self.camera.render(
            &CameraPose {
                position: eye,
                yaw,
                pitch: 0.0,
            },
            0,
        );
        let mut pts = points(&self.pinhole, &frame, &eye, yaw, self.stride);
        for i in -3..=3 {
            for j in -3..=3 {
                let (dx, dy) = (0.05 * f64::from(i), 0.05 * f64::from(j));
                if dx.hypot(dy) <= 0.18 {
                    pts.push(Point3::new(feet.x + dx, feet.y + dy, feet.z));
                }
            }
        }
        let t = Instant::now();
        self.map.update(feet, &eye, &pts)?;
        self.update_times.push(t.elapsed());
        self.frames += 1;
        // As the agent does at every step.
        let t = Instant::now();
        self.map.frontier_graph(feet)?;
        self.refresh_times.push(t.elapsed());
        Ok(())
    }

    /// A full turn in place (12 views).
    ///
    /// # Errors
    /// The map's errors.
    pub fn turn_around(&mut self, feet: &Point3<f64>) -> Result<(), FrontierError> {
        for k in 0..12 {
            self.look(feet, f64::from(k) * std::f64::consts::TAU / 12.0)?;
        }
        Ok(())
    }

    /// Walks `path` in steps of `step` metres along its length (0.25 is
    /// the simulator's forward step), looking along the path, with a last
    /// look at its end.
    ///
    /// # Errors
    /// The map's errors.
    pub fn walk(&mut self, path: &[Point3<f64>], step: f64) -> Result<(), FrontierError> {
        let step = if step.is_finite() && step > 1e-3 {
            step
        } else {
            0.25
        };
        let mut since = 0.0;
        let mut last = None;
        for w in path.windows(2) {
            let d = w[1] - w[0];
            let len = d.xy().norm();
            if len < 1e-6 {
                continue;
            }
            let yaw = d.y.atan2(d.x);
            let mut s = step - since;
            while s <= len {
                self.look(&(w[0] + d * (s / len)), yaw)?;
                s += step;
            }
            since = len - (s - step);
            last = Some((w[1], yaw));
        }
        if let Some((end, yaw)) = last
            && since > 1e-6
        {
            self.look(&end, yaw)?;
        }
        Ok(())
    }
}

/// The walkable point of level `level` (by the scene's level elevations)
/// with the smallest `x + y`, and the navmesh; `None` when the scene has
/// no such level or no walkable span on it.
///
/// # Errors
/// The navmesh's construction error, as a string.
pub fn level_corner(scene: &Scene, level: usize) -> Result<Option<(NavMesh, Point3<f64>)>, String> {
    let nav = NavMesh::build(scene, &NavMeshConfig::default()).map_err(|e| e.to_string())?;
    let Some(z) = scene.levels().get(level).map(|l| l.elevation) else {
        return Ok(None);
    };
    let p = (0..nav.spans().len())
        .map(|i| nav.span_center(i as u32))
        .filter(|c| (c.z - z).abs() < 0.25)
        .min_by(|a, b| (a.x + a.y).total_cmp(&(b.x + b.y)));
    Ok(p.map(|p| (nav, p)))
}

/// Walks from the corner of level `from` to the corner of level `to` along
/// the navmesh's shortest path in 5 cm steps (dense: a stair is seen from
/// every tread), turning around at both ends.
///
/// # Errors
/// Construction, path and map errors, as strings.
pub fn walk_between(
    scene: &Scene,
    from: usize,
    to: usize,
    width: u32,
    height: u32,
) -> Result<Walker, String> {
    let (Some((nav, a)), Some((_, b))) = (level_corner(scene, from)?, level_corner(scene, to)?)
    else {
        return Err(format!("the scene has no levels {from} and {to}"));
    };
    let path = nav
        .path(&a, &b)
        .map_err(|e| e.to_string())?
        .ok_or_else(|| format!("levels {from} and {to} are not connected"))?;
    let mut walker = Walker::new(scene, width, height, FrontierMapConfig::default())?;
    let e = |e: FrontierError| e.to_string();
    walker.turn_around(&a).map_err(e)?;
    walker.walk(&path, 0.05).map_err(e)?;
    walker.turn_around(&b).map_err(e)?;
    Ok(walker)
}
