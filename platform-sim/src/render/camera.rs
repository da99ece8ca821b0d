//! The pinhole depth + semantic camera (Habitat's ObjectNav sensor), rendered
//! by casting one primary ray per pixel through a [`Bvh`].

use nalgebra::{Point3, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::bvh::{Bvh, BvhHit};
use super::tile::{ROWS, TileHits, TileRays, TileScratch, trace_tile, trace_tile_packet};
use super::{RenderError, RenderKernel};
use crate::Scene;
use crate::noise::{NoiseConfig, NoiseModel};

/// Side of the square pixel tiles traced as one ray packet.
const TILE: usize = 8;

/// Instance value of pixels without a semantic return.
pub const NO_INSTANCE: u32 = u32::MAX;

/// Camera intrinsics and ranges. Defaults are Habitat's ObjectNav challenge
/// sensor: 640x480, HFOV 79 deg, mounted 0.88 m above the feet, depth
/// 0.5-5.0 m, no RGB, no noise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CameraConfig {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Horizontal field of view in degrees (square pixels: fy = fx).
    pub hfov_deg: f64,
    /// Sensor height above the agent's feet in metres.
    pub mount_height: f64,
    /// Closest valid depth (closer returns read 0).
    pub min_depth: f64,
    /// Farthest valid depth (farther returns read 0).
    pub max_depth: f64,
    /// Farthest distance (z-depth) at which the semantic channel still reports
    /// an instance; `None` = unlimited, as Habitat's semantic sensor.
    pub semantic_max_depth: Option<f64>,
    /// Also render a shaded RGB image (colour by category, shade by normal).
    pub rgb: bool,
    /// Sensor noise (everything off by default).
    pub noise: NoiseConfig,
}

impl Default for CameraConfig {
    fn default() -> Self {
        CameraConfig {
            width: 640,
            height: 480,
            hfov_deg: 79.0,
            mount_height: 0.88,
            min_depth: 0.5,
            max_depth: 5.0,
            semantic_max_depth: None,
            rgb: false,
            noise: NoiseConfig::default(),
        }
    }
}

impl CameraConfig {
    /// Checks every field.
    ///
    /// # Errors
    /// [`RenderError::Config`] naming the first invalid field.
    pub fn validate(&self) -> Result<(), RenderError> {
        let bad = |field: &'static str, message: &str| {
            Err(RenderError::Config {
                field,
                message: message.into(),
            })
        };
        if self.width == 0 || self.height == 0 || self.width > 16_384 || self.height > 16_384 {
            return bad("width/height", "must be in 1..=16384");
        }
        if !(self.hfov_deg > 0.0 && self.hfov_deg < 180.0) {
            return bad("hfov_deg", "must be in (0, 180)");
        }
        if !self.mount_height.is_finite() {
            return bad("mount_height", "must be finite");
        }
        if !(self.min_depth >= 0.0 && self.max_depth > self.min_depth && self.max_depth.is_finite())
        {
            return bad(
                "min_depth/max_depth",
                "need 0 <= min_depth < max_depth < inf",
            );
        }
        if self
            .semantic_max_depth
            .is_some_and(|d| d.is_nan() || d <= 0.0)
        {
            return bad("semantic_max_depth", "must be positive");
        }
        self.noise.validate()
    }

    /// Focal length in pixels (fx = fy).
    pub fn focal(&self) -> f64 {
        (f64::from(self.width) / 2.0) / (self.hfov_deg.to_radians() / 2.0).tan()
    }

    /// Vertical field of view in degrees.
    pub fn vfov_deg(&self) -> f64 {
        2.0 * ((f64::from(self.height) / 2.0) / self.focal())
            .atan()
            .to_degrees()
    }
}

/// Where the sensor is and where it looks.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CameraPose {
    /// Optical centre (world, z up, metres).
    pub position: Point3<f64>,
    /// Heading in radians, counter-clockwise from +x.
    pub yaw: f64,
    /// Elevation in radians (positive looks up).
    pub pitch: f64,
}

impl CameraPose {
    /// Unit axes of the camera frame: (forward, right, up).
    pub fn axes(&self) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        let fwd = Vector3::new(cp * cy, cp * sy, sp);
        let right = Vector3::new(sy, -cy, 0.0);
        let up = Vector3::new(-sp * cy, -sp * sy, cp);
        (fwd, right, up)
    }
}

/// One rendered image: row-major, row 0 at the top.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The pose it was rendered from.
    pub pose: CameraPose,
    /// z-depth in metres along the optical axis; 0 for no return in
    /// [min_depth, max_depth] (or a return dropped by the noise model).
    pub depth: Vec<f32>,
    /// Instance id per pixel ([`NO_INSTANCE`] for none).
    pub instance: Vec<u32>,
    /// Shaded RGB, when [`CameraConfig::rgb`] is set.
    pub rgb: Option<Vec<[u8; 3]>>,
}

impl Frame {
    /// Pixel index of (u, v) (column, row).
    pub fn index(&self, u: u32, v: u32) -> usize {
        v as usize * self.width as usize + u as usize
    }

    /// Number of pixels with a depth return.
    pub fn valid_depth_count(&self) -> usize {
        self.depth.iter().filter(|d| **d > 0.0).count()
    }

    /// World point of pixel (u, v) from its depth, or `None` without a return.
    pub fn unproject(&self, config: &CameraConfig, u: u32, v: u32) -> Option<Point3<f64>> {
        let z = f64::from(*self.depth.get(self.index(u, v))?);
        if z <= 0.0 {
            return None;
        }
        let (a, b) = pixel_offsets(config, u, v);
        let (f, r, up) = self.pose.axes();
        Some(self.pose.position + (f + r * a + up * b) * z)
    }

    /// Writes the depth image as a grey PNG, for debugging: near is
    /// light, `far` metres and beyond are dark, no return is black.
    ///
    /// # Errors
    /// [`RenderError::Io`] when the file cannot be written.
    pub fn save_depth_png(&self, path: &std::path::Path, far: f32) -> Result<(), RenderError> {
        let far = if far.is_finite() && far > 0.0 {
            far
        } else {
            1.0
        };
        let data: Vec<u8> = self
            .depth
            .iter()
            .flat_map(|&z| {
                let g = if z.is_finite() && z > 0.0 {
                    // 255 at the camera down to 32 at `far`; the cast
                    // saturates.
                    (255.0 - 223.0 * (z / far).min(1.0)) as u8
                } else {
                    0
                };
                [g; 3]
            })
            .collect();
        crate::write_rgb_png(path, self.width, self.height, &data).map_err(|e| RenderError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        })
    }

    /// Writes the RGB image (or, without one, the instance image in false
    /// colours) as a PNG; for figures and debugging.
    ///
    /// # Errors
    /// [`RenderError::Io`] when the file cannot be written.
    pub fn save_png(&self, path: &std::path::Path) -> Result<(), RenderError> {
        let data: Vec<u8> = match &self.rgb {
            Some(rgb) => rgb.iter().flatten().copied().collect(),
            None => self
                .instance
                .iter()
                .flat_map(|&i| if i == NO_INSTANCE { [0; 3] } else { palette(i) })
                .collect(),
        };
        crate::write_rgb_png(path, self.width, self.height, &data).map_err(|e| RenderError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        })
    }
}

/// Normalised image-plane offsets (a right, b up) of the centre of pixel (u, v).
fn pixel_offsets(config: &CameraConfig, u: u32, v: u32) -> (f64, f64) {
    let f = config.focal();
    let cx = f64::from(config.width) / 2.0;
    let cy = f64::from(config.height) / 2.0;
    (
        (f64::from(u) + 0.5 - cx) / f,
        -(f64::from(v) + 0.5 - cy) / f,
    )
}

/// A distinct, saturated colour for a key (golden-ratio hue walk).
pub fn palette(key: u32) -> [u8; 3] {
    let h = (f64::from(key) * 0.618_033_988_749_895).fract() * 6.0;
    let x = 1.0 - ((h % 2.0) - 1.0).abs();
    let (r, g, b) = match h as u32 {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        4 => (x, 0.0, 1.0),
        _ => (1.0, 0.0, x),
    };
    [r, g, b].map(|c: f64| (40.0 + 200.0 * c) as u8)
}

/// A depth + semantic (+ RGB) camera over a triangle mesh.
///
/// # Example
/// ```
/// use nalgebra::Point3;
/// use sornav_platform_sim::render::{Bvh, Camera, CameraConfig, CameraPose};
/// // A wall at x = 3 spanning y, z in [-10, 10], labelled 7.
/// let v = [[3.0, -10.0, -10.0], [3.0, 10.0, -10.0], [3.0, 10.0, 10.0], [3.0, -10.0, 10.0]];
/// let bvh = Bvh::build(&v, &[[0, 1, 2], [0, 2, 3]], &[7, 7]).unwrap();
/// let config = CameraConfig { width: 64, height: 48, ..CameraConfig::default() };
/// let camera = Camera::new(bvh, config).unwrap();
/// let pose = CameraPose { position: Point3::new(0.0, 0.0, 0.0), yaw: 0.0, pitch: 0.0 };
/// let frame = camera.render(&pose, 0);
/// assert!(frame.depth.iter().all(|d| (d - 3.0).abs() < 1e-5)); // z-depth is constant on a facing wall
/// assert!(frame.instance.iter().all(|i| *i == 7));
/// ```
#[derive(Debug, Clone)]
pub struct Camera {
    bvh: Bvh,
    config: CameraConfig,
    /// Colour key per payload (category index for scenes); identity when empty.
    colour_keys: Vec<u32>,
    noise: Option<NoiseModel>,
    kernel: RenderKernel,
}

impl Camera {
    /// A camera over a prebuilt BVH whose payloads are instance ids.
    ///
    /// # Errors
    /// [`RenderError::Config`] for an invalid configuration.
    pub fn new(bvh: Bvh, config: CameraConfig) -> Result<Camera, RenderError> {
        config.validate()?;
        let noise = config
            .noise
            .is_active()
            .then(|| NoiseModel::new(config.noise.clone(), Vec::new()));
        Ok(Camera {
            bvh,
            config,
            colour_keys: Vec::new(),
            noise,
            kernel: RenderKernel::Auto,
        })
    }

    /// A camera over a scene's mesh: payloads are instance ids, RGB colours
    /// follow the instance's category, and false-positive noise blobs borrow
    /// the ids of the scene's objects.
    ///
    /// # Errors
    /// [`RenderError`] for an invalid configuration or mesh.
    ///
    /// # Complexity
    /// O(T log T) (BVH build).
    pub fn for_scene(scene: &Scene, config: CameraConfig) -> Result<Camera, RenderError> {
        config.validate()?;
        let bvh = Bvh::build(
            scene.vertices(),
            scene.triangles(),
            scene.triangle_instances(),
        )?;
        let mut cats: Vec<&str> = scene
            .instances()
            .iter()
            .map(|i| i.category.as_str())
            .collect();
        cats.sort_unstable();
        cats.dedup();
        let colour_keys = scene
            .instances()
            .iter()
            .map(|i| {
                cats.binary_search(&i.category.as_str())
                    .map_or(0, |k| k as u32)
            })
            .collect();
        let objects: Vec<u32> = scene.objects().map(|o| o.id).collect();
        let noise = config
            .noise
            .is_active()
            .then(|| NoiseModel::new(config.noise.clone(), objects));
        Ok(Camera {
            bvh,
            config,
            colour_keys,
            noise,
            kernel: RenderKernel::Auto,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &CameraConfig {
        &self.config
    }

    /// This camera tracing with `kernel` (default [`RenderKernel::Auto`]).
    /// Frames are the same bits with every kernel; only the speed differs.
    ///
    /// # Errors
    /// [`RenderError::Config`] when the kernel cannot run on this CPU.
    pub fn with_kernel(mut self, kernel: RenderKernel) -> Result<Camera, RenderError> {
        if !kernel.is_available() {
            return Err(RenderError::Config {
                field: "kernel",
                message: format!("{kernel:?} is not available on this CPU"),
            });
        }
        self.kernel = kernel;
        Ok(self)
    }

    /// The kernel that traces this camera's tiles.
    pub fn kernel(&self) -> RenderKernel {
        self.kernel
    }

    /// The acceleration structure.
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// The camera pose of an agent standing at `feet` with heading `yaw` and
    /// camera tilt `pitch`.
    pub fn pose_at(&self, feet: &Point3<f64>, yaw: f64, pitch: f64) -> CameraPose {
        CameraPose {
            position: feet + Vector3::new(0.0, 0.0, self.config.mount_height),
            yaw,
            pitch,
        }
    }

    /// Renders one frame: 8x8 pixel tiles are traced by the tile kernel
    /// (one frustum per tile through a 4-wide BVH, 8 rays per AVX2
    /// instruction where the CPU has it; [`Camera::with_kernel`]), bands of
    /// tiles in parallel. Depth equals, bit for bit, what
    /// [`Bvh::intersect_packet`] gives for the same rays; `frame_seed` seeds
    /// the noise model (unused without noise), so a given (pose, seed)
    /// always yields the same image.
    ///
    /// Pixels are rendered in parallel rows (rayon); set `RAYON_NUM_THREADS=1`
    /// for single-core figures.
    ///
    /// # Complexity
    /// O(W H log T) expected for a W x H image and T triangles.
    pub fn render(&self, pose: &CameraPose, frame_seed: u64) -> Frame {
        let mut frame = Frame {
            width: 0,
            height: 0,
            pose: *pose,
            depth: Vec::new(),
            instance: Vec::new(),
            rgb: None,
        };
        self.render_into(pose, frame_seed, &mut frame);
        frame
    }

    /// [`Camera::render`] into `frame`, reusing its buffers: no allocation
    /// and no clearing once they are large enough (every pixel is written).
    /// The frame's previous contents are replaced entirely; the result is
    /// the frame [`Camera::render`] returns.
    ///
    /// # Complexity
    /// As [`Camera::render`].
    pub fn render_into(&self, pose: &CameraPose, frame_seed: u64, frame: &mut Frame) {
        let c = &self.config;
        let (w, h) = (c.width as usize, c.height as usize);
        frame.width = c.width;
        frame.height = c.height;
        frame.pose = *pose;
        let mut depth = std::mem::take(&mut frame.depth);
        let mut instance = std::mem::take(&mut frame.instance);
        depth.resize(w * h, 0.0);
        instance.resize(w * h, NO_INSTANCE);
        let mut rgb = c.rgb.then(|| {
            let mut rgb = frame.rgb.take().unwrap_or_default();
            rgb.resize(w * h, [0; 3]);
            rgb
        });
        let (f, r, up) = pose.axes();
        let to32 = |v: Vector3<f64>| [v.x as f32, v.y as f32, v.z as f32];
        let (f, r, up) = (to32(f), to32(r), to32(up));
        let origin = [
            pose.position.x as f32,
            pose.position.y as f32,
            pose.position.z as f32,
        ];
        let focal = c.focal() as f32;
        let (cx, cy) = (c.width as f32 / 2.0, c.height as f32 / 2.0);
        // Image-plane offset of every column, padded to whole tiles.
        let columns: Vec<f32> = (0..w.next_multiple_of(TILE))
            .map(|u| (u as f32 + 0.5 - cx) / focal)
            .collect();
        let (dmin, dmax) = (c.min_depth as f32, c.max_depth as f32);
        let t_far = c
            .semantic_max_depth
            .map_or(f32::INFINITY, |d| d as f32)
            .max(dmax);
        let sem_max = c.semantic_max_depth.map_or(f32::INFINITY, |d| d as f32);
        let valid_pose = origin.iter().chain(f.iter()).all(|x| x.is_finite());
        if !valid_pose {
            // No rays: an empty frame.
            depth.fill(0.0);
            instance.fill(NO_INSTANCE);
            if let Some(rgb) = rgb.as_mut() {
                rgb.fill([0; 3]);
            }
        }
        let render_band = |band: usize,
                           drows: &mut [f32],
                           irows: &mut [u32],
                           mut crows: Option<&mut [[u8; 3]]>| {
            if !valid_pose {
                return;
            }
            let v0 = band * TILE;
            let rows = drows.len() / w;
            let mut tile = TileRays {
                origin,
                base: [[0.0; 3]; ROWS],
                right: r,
                a: &[0.0; TILE],
                rows,
                cols: TILE,
                depth: (dmin, dmax),
                semantic: sem_max,
            };
            for (dv, base) in tile.base[..rows].iter_mut().enumerate() {
                let b = -(((v0 + dv) as f32 + 0.5 - cy) / focal);
                *base = [f[0] + b * up[0], f[1] + b * up[1], f[2] + b * up[2]];
            }
            let mut hits = TileHits::EMPTY;
            let mut scratch = TileScratch::new();
            for u0 in (0..w).step_by(TILE) {
                tile.cols = (w - u0).min(TILE);
                // Borrowed, not copied: the kernel loads it as one vector.
                tile.a = columns[u0..u0 + TILE].try_into().unwrap_or(&[0.0; TILE]);
                if !trace_tile(
                    self.kernel,
                    &self.bvh,
                    &tile,
                    0.0,
                    t_far,
                    &mut hits,
                    &mut scratch,
                ) {
                    // A tree the tile kernel cannot take (see `Bvh::build`).
                    trace_tile_packet(&self.bvh, &tile, 0.0, t_far, &mut hits);
                }
                for dv in 0..rows {
                    let row = dv * w + u0..dv * w + u0 + tile.cols;
                    let (t, slot) = (&hits.t[dv], &hits.slot[dv]);
                    let (depth, id) = (&hits.depth[dv], &hits.instance[dv]);
                    if let (Ok(d), Ok(k)) = (
                        <&mut [f32; TILE]>::try_from(&mut drows[row.clone()]),
                        <&mut [u32; TILE]>::try_from(&mut irows[row.clone()]),
                    ) {
                        // A full tile row: two fixed-size copies.
                        *d = *depth;
                        *k = *id;
                    } else {
                        drows[row.clone()].copy_from_slice(&depth[..tile.cols]);
                        irows[row.clone()].copy_from_slice(&id[..tile.cols]);
                    }
                    let Some(crows) = crows.as_deref_mut() else {
                        continue;
                    };
                    for (i, c) in crows[row].iter_mut().enumerate() {
                        let Some(tri) = self.bvh.triangles().get(slot[i] as usize) else {
                            *c = [0; 3];
                            continue;
                        };
                        let hit = BvhHit {
                            t: t[i],
                            triangle: tri.index,
                            payload: tri.payload,
                            slot: slot[i],
                        };
                        let dir = [0, 1, 2].map(|k| tile.base[dv][k] + tile.a[i] * r[k]);
                        *c = self.shade(&hit, dir);
                    }
                }
            }
        };
        match rgb.as_mut() {
            Some(rgb) => depth
                .par_chunks_mut(w * TILE)
                .zip(instance.par_chunks_mut(w * TILE))
                .zip(rgb.par_chunks_mut(w * TILE))
                .enumerate()
                .for_each(|(band, ((d, i), c))| render_band(band, d, i, Some(c))),
            None => depth
                .par_chunks_mut(w * TILE)
                .zip(instance.par_chunks_mut(w * TILE))
                .enumerate()
                .for_each(|(band, (d, i))| render_band(band, d, i, None)),
        }
        frame.depth = depth;
        frame.instance = instance;
        frame.rgb = rgb;
        if let Some(noise) = &self.noise {
            noise.apply(frame, frame_seed);
        }
    }

    /// Colour by category, shaded by the angle between surface and ray.
    fn shade(&self, hit: &super::BvhHit, dir: [f32; 3]) -> [u8; 3] {
        let tri = &self.bvh.triangles()[hit.slot as usize];
        let e1 = Vector3::new(
            tri.b[0] - tri.a[0],
            tri.b[1] - tri.a[1],
            tri.b[2] - tri.a[2],
        );
        let e2 = Vector3::new(
            tri.c[0] - tri.a[0],
            tri.c[1] - tri.a[1],
            tri.c[2] - tri.a[2],
        );
        let n = e1.cross(&e2);
        let d = Vector3::new(dir[0], dir[1], dir[2]);
        let cos = (n.dot(&d) / (n.norm() * d.norm())).abs();
        let shade = if cos.is_finite() {
            0.35 + 0.65 * cos
        } else {
            0.35
        };
        let key = self
            .colour_keys
            .get(hit.payload as usize)
            .copied()
            .unwrap_or(hit.payload);
        palette(key).map(|ch| (f32::from(ch) * shade) as u8)
    }
}
