//! The simulated robot: a platform-sim scene, its walkable height field, a
//! panoramic depth + semantic camera standing in for the LiDAR and the
//! segmentation, and a differential-drive body that follows NavMesh paths
//! toward the latest way point, like the CMU local planner would.

use nalgebra::Point3;
use sornav::LabelEntry;
use sornav::supervisor::normalize_label;
use sornav_platform_sim::agent::wrap_angle;
use sornav_platform_sim::render::{Camera, CameraConfig, CameraPose, NO_INSTANCE};
use sornav_platform_sim::{InstanceKind, NavMesh, NavMeshConfig, Scene};

/// Labels of the robot's default vocabulary for structure.
const WALL: u16 = 1;
const FLOOR: u16 = 2;
const CEILING: u16 = 3;
/// Label of returns the segmentation does not name.
pub const UNLABELLED: u16 = 0;

/// One labelled return in the map frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Return {
    /// Position (m).
    pub p: [f64; 3],
    /// Semantic label.
    pub label: u16,
}

/// The segmentation's label of every instance of `scene`: structure maps to
/// wall / floor / ceiling, objects to the robot vocabulary entry with the
/// same normalised category, anything else to [`UNLABELLED`].
fn instance_labels(scene: &Scene, vocabulary: &[LabelEntry]) -> Vec<u16> {
    let named: Vec<(String, u16)> = vocabulary
        .iter()
        .filter(|e| !e.ignored)
        .filter_map(|e| normalize_label(&e.name).map(|n| (n, e.id)))
        .collect();
    scene
        .instances()
        .iter()
        .map(|i| match i.kind {
            InstanceKind::Wall
            | InstanceKind::Door
            | InstanceKind::Window
            | InstanceKind::Stairs => WALL,
            InstanceKind::Floor => FLOOR,
            InstanceKind::Ceiling => CEILING,
            InstanceKind::Object => normalize_label(&i.category)
                .and_then(|c| named.iter().find(|(n, _)| *n == c).map(|(_, id)| *id))
                .unwrap_or(UNLABELLED),
        })
        .collect()
}

/// The robot in the scene.
pub struct World {
    scene: Scene,
    nav: NavMesh,
    camera: Camera,
    labels: Vec<u16>,
    /// Feet position.
    pub position: Point3<f64>,
    /// Heading (rad, counter-clockwise from +x).
    pub yaw: f64,
    path: Vec<Point3<f64>>,
    /// Forward speed (m/s).
    pub speed: f64,
    /// Yaw rate (rad/s).
    pub yaw_rate: f64,
    /// Distance travelled (m).
    pub odometer: f64,
}

impl World {
    /// A world over `scene` with the camera standing `sensor_height` above
    /// the feet, `width` x `height` pixels per 90-degree face, returns up to
    /// `range` m; the robot starts at `start` (snapped) or at the walkable
    /// span nearest the centre of the largest walkable region.
    ///
    /// # Errors
    /// A message when the scene cannot be prepared.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        scene: Scene,
        vocabulary: &[LabelEntry],
        sensor_height: f64,
        width: u32,
        height: u32,
        range: f64,
        start: Option<[f64; 2]>,
    ) -> Result<Self, String> {
        let nav = NavMesh::build(&scene, &NavMeshConfig::default()).map_err(|e| e.to_string())?;
        let config = CameraConfig {
            width,
            height,
            hfov_deg: 90.0,
            mount_height: sensor_height,
            min_depth: 0.3,
            max_depth: range,
            ..CameraConfig::default()
        };
        let camera = Camera::for_scene(&scene, config).map_err(|e| e.to_string())?;
        let position = match start {
            Some([x, y]) => {
                let z = nav.heights_at(x, y).first().copied().unwrap_or(0.0);
                nav.snap(&Point3::new(x, y, z), 1.5)
                    .map_err(|e| e.to_string())?
            }
            None => {
                let region = nav
                    .largest_region()
                    .ok_or("the scene has no walkable surface")?;
                let spans: Vec<Point3<f64>> = (0..nav.span_count() as u32)
                    .filter(|&s| nav.spans()[s as usize].region == region)
                    .map(|s| nav.span_center(s))
                    .collect();
                let n = spans.len() as f64;
                let c = spans
                    .iter()
                    .fold(Point3::origin(), |acc, p| acc + p.coords / n);
                *spans
                    .iter()
                    .min_by(|a, b| (*a - c).xy().norm().total_cmp(&(*b - c).xy().norm()))
                    .ok_or("empty region")?
            }
        };
        let labels = instance_labels(&scene, vocabulary);
        Ok(Self {
            scene,
            nav,
            camera,
            labels,
            position,
            yaw: 0.0,
            path: Vec::new(),
            speed: 1.0,
            yaw_rate: 90f64.to_radians(),
            odometer: 0.0,
        })
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The segmentation's label of every instance of the scene (see
    /// `instance_labels`), indexed by instance id.
    pub fn labels(&self) -> &[u16] {
        &self.labels
    }

    /// The camera height above the feet.
    pub fn sensor_height(&self) -> f64 {
        self.camera.config().mount_height
    }

    /// Plans a NavMesh path from the robot to `goal` (snapped to the
    /// walkable surface within 1.5 m). Returns whether a path exists; without
    /// one the robot stops.
    pub fn set_goal(&mut self, goal: [f64; 3]) -> bool {
        let g = Point3::new(goal[0], goal[1], self.position.z);
        let snapped = self
            .nav
            .snap(&g, 1.5)
            .or_else(|_| self.nav.snap(&Point3::new(goal[0], goal[1], goal[2]), 1.5));
        let path = snapped
            .ok()
            .and_then(|g| self.nav.path(&self.position, &g).ok().flatten());
        match path {
            Some(p) => {
                self.path = p.into_iter().skip(1).collect();
                true
            }
            None => {
                self.path.clear();
                false
            }
        }
    }

    /// Advances the body by `dt` seconds: turn in place toward the next path
    /// point when it is more than 30 degrees off, otherwise drive toward it
    /// (steering while driving), like a skid-steer path follower.
    pub fn advance(&mut self, dt: f64) {
        let mut budget = self.speed * dt;
        while budget > 1e-9 {
            let Some(next) = self.path.first().copied() else {
                return;
            };
            let d = next - self.position;
            let dist = d.xy().norm();
            if dist < 1e-6 {
                self.position = next;
                self.path.remove(0);
                continue;
            }
            let want = d.y.atan2(d.x);
            let err = wrap_angle(want - self.yaw);
            let max_turn = self.yaw_rate * dt;
            self.yaw = wrap_angle(self.yaw + err.clamp(-max_turn, max_turn));
            if err.abs() > 30f64.to_radians() {
                return;
            }
            let step = budget.min(dist);
            let t = step / dist;
            self.position += d * t;
            self.odometer += step;
            budget -= step;
            if step >= dist - 1e-9 {
                self.position = next;
                self.path.remove(0);
            }
        }
    }

    /// One panoramic scan: four 90-degree faces around the heading; every
    /// pixel with a depth return becomes a map-frame return with its label.
    pub fn scan(&self, seed: u64) -> Vec<Return> {
        let config = self.camera.config();
        let mut out = Vec::new();
        for k in 0u32..4 {
            let yaw = wrap_angle(self.yaw + f64::from(k) * std::f64::consts::FRAC_PI_2);
            let pose: CameraPose = self.camera.pose_at(&self.position, yaw, 0.0);
            let frame = self.camera.render(&pose, seed.wrapping_add(u64::from(k)));
            for v in 0..frame.height {
                for u in 0..frame.width {
                    let Some(p) = frame.unproject(config, u, v) else {
                        continue;
                    };
                    let instance = frame.instance[frame.index(u, v)];
                    let label = if instance == NO_INSTANCE {
                        UNLABELLED
                    } else {
                        self.labels
                            .get(instance as usize)
                            .copied()
                            .unwrap_or(UNLABELLED)
                    };
                    out.push(Return {
                        p: [p.x, p.y, p.z],
                        label,
                    });
                }
            }
        }
        out
    }
}
