//! ObjectNav episodes for any scene, following Habitat's dataset procedure.
//!
//! For each target category present in the scene:
//! 1. **Goals** are all instances of the category.
//! 2. **View points** of a goal are navigable poses on a floor island
//!    ([`crate::NavMesh::is_floor_region`]: never on top of furniture) within 1.0 m of the
//!    object's bounds (distance from the agent's body, a vertical segment from
//!    the feet to camera height, to the box), sampled on a 0.1 m grid, from
//!    which the object is visible at camera height: at least one of 27 sample
//!    points spread over the object's bounds is reached by an unobstructed ray
//!    that first hits the object, within the camera's vertical field of view
//!    of a level camera facing it. The view point faces the object's centre;
//!    its `iou` is the fraction of sample rays that see the object. An
//!    object whose box samples all lie in open air seen from every pose (a
//!    shower stall whose glass sides face the walls: the rays to its inside
//!    end before they reach anything) is tested instead with points on its
//!    own surface, the centroids of up to [`SURFACE_SAMPLES`] of its largest
//!    triangles. Goals without view points are dropped, as in Habitat.
//! 3. **Starts** are navigable poses drawn uniformly over the walkable area
//!    of the floor islands (every span has the same area; islands on
//!    furniture are excluded) connected to a view point over areas at
//!    least three cells wide ([`crate::NavMesh::wide_spans`]: the agent's
//!    0.25 m moves at 30-degree headings cannot follow narrower strips),
//!    whose geodesic distance to the nearest
//!    view point lies in [1, 30] m. Episodes whose geodesic/euclidean ratio is
//!    below 1.1 are kept only with probability 20 (r - 0.98)^2, habitat-lab's
//!    filter against trivial straight-line episodes. The start heading is
//!    uniform.
//! 4. Each episode records the geodesic and euclidean distance to the closest
//!    goal, its object id, and whether the goal view point nearest to the
//!    start lies on another level of the height field (`cross_floor`, the
//!    definition of [`crate::levels`] that [`crate::run_episode`] also uses).
//!
//! Generation is deterministic for a seed.

use nalgebra::{Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::{Episode, ObjectGoal, ViewPoint};
use crate::run::Simulator;
use crate::{NavError, ObjectInstance};

/// Parameters of the generator (Habitat's ObjectNav values by default).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct GeneratorConfig {
    /// Target categories (HM3D's six by default); absent ones are skipped.
    pub categories: Vec<String>,
    /// Episodes per category.
    pub episodes_per_category: usize,
    /// Shortest allowed geodesic distance to the nearest view point (1 m).
    pub min_geodesic: f64,
    /// Longest allowed geodesic distance (30 m).
    pub max_geodesic: f64,
    /// Geodesic/euclidean ratio under which episodes are thinned out (1.1).
    pub geodesic_to_euclid_ratio: f64,
    /// Largest distance from a view point to the object's bounds (1 m).
    pub view_point_radius: f64,
    /// Grid spacing of view point candidates (0.1 m).
    pub view_point_spacing: f64,
    /// Start samples tried per episode before giving up on a category.
    pub max_attempts: usize,
    /// Seed.
    pub seed: u64,
}

impl Default for GeneratorConfig {
    fn default() -> Self {
        GeneratorConfig {
            categories: crate::category::HM3D_GOALS
                .iter()
                .map(|c| (*c).to_string())
                .collect(),
            episodes_per_category: 5,
            min_geodesic: 1.0,
            max_geodesic: 30.0,
            geodesic_to_euclid_ratio: 1.1,
            view_point_radius: 1.0,
            view_point_spacing: 0.1,
            max_attempts: 5000,
            seed: 0,
        }
    }
}

/// Errors of the generator.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GenerateError {
    /// A configuration value is out of range.
    #[error("invalid generator configuration: {0}")]
    Config(&'static str),
    /// A geodesic query failed.
    #[error(transparent)]
    Nav(#[from] NavError),
}

impl GeneratorConfig {
    /// Checks ranges.
    ///
    /// # Errors
    /// [`GenerateError::Config`].
    pub fn validate(&self) -> Result<(), GenerateError> {
        if !(self.min_geodesic >= 0.0
            && self.max_geodesic > self.min_geodesic
            && self.max_geodesic.is_finite())
        {
            return Err(GenerateError::Config(
                "need 0 <= min_geodesic < max_geodesic < inf",
            ));
        }
        if !(self.view_point_radius > 0.0 && self.view_point_radius.is_finite()) {
            return Err(GenerateError::Config("view_point_radius must be positive"));
        }
        if !(self.view_point_spacing > 0.0 && self.view_point_spacing.is_finite()) {
            return Err(GenerateError::Config("view_point_spacing must be positive"));
        }
        if !self.geodesic_to_euclid_ratio.is_finite() {
            return Err(GenerateError::Config(
                "geodesic_to_euclid_ratio must be finite",
            ));
        }
        Ok(())
    }
}

/// Distance from an agent body (vertical segment `[feet.z, feet.z + height]`)
/// to an object's bounds.
pub fn body_distance(object: &ObjectInstance, feet: &Point3<f64>, height: f64) -> f64 {
    object.bounds.body_distance(feet, height)
}

/// View points of one object (see the module docs).
///
/// # Complexity
/// O(C (h + 27 log T)) for C grid candidates around the object, h walking
/// surfaces per column and T triangles; when no box sample is seen, another
/// O(T + C (h + 64 log T)) for the surface samples.
pub fn goal_view_points(
    sim: &Simulator,
    object: &ObjectInstance,
    config: &GeneratorConfig,
) -> Vec<ViewPoint> {
    let b = &object.bounds;
    if b.is_empty() {
        return Vec::new();
    }
    // Sample points over the object's bounds.
    let fr = [1.0 / 6.0, 0.5, 5.0 / 6.0];
    let mut targets = Vec::with_capacity(27);
    for fx in fr {
        for fy in fr {
            for fz in fr {
                let e = b.extents();
                targets.push(b.min + Vector3::new(e.x * fx, e.y * fy, e.z * fz));
            }
        }
    }
    let out = view_points_seeing(sim, object, config, &targets);
    if out.is_empty() {
        view_points_seeing(sim, object, config, &surface_samples(sim, object))
    } else {
        out
    }
}

/// Largest number of surface points [`goal_view_points`] tests for an object
/// that no box sample shows.
pub const SURFACE_SAMPLES: usize = 64;

/// Centroids of the object's [`SURFACE_SAMPLES`] largest triangles (ties by
/// triangle index, so deterministic).
///
/// # Complexity
/// O(T + k log k) for T scene triangles and k of the object's.
fn surface_samples(sim: &Simulator, object: &ObjectInstance) -> Vec<Point3<f64>> {
    let scene = sim.scene();
    let v = scene.vertices();
    let point = |i: u32| {
        let p = v[i as usize];
        Point3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]))
    };
    let mut tris: Vec<(f64, Point3<f64>)> = scene
        .triangles()
        .iter()
        .zip(scene.triangle_instances())
        .filter(|(_, id)| **id == object.id)
        .map(|(t, _)| {
            let (a, b, c) = (point(t[0]), point(t[1]), point(t[2]));
            let area = (b - a).cross(&(c - a)).norm();
            (area, Point3::from((a.coords + b.coords + c.coords) / 3.0))
        })
        .filter(|(area, _)| area.is_finite())
        .collect();
    // stable: equal areas keep triangle order
    tris.sort_by(|x, y| y.0.total_cmp(&x.0));
    tris.truncate(SURFACE_SAMPLES);
    tris.into_iter().map(|(_, c)| c).collect()
}

/// Poses on the 0.1 m grid around the object (see the module docs) from
/// which at least one of `targets` is visible; `iou` is the visible share.
fn view_points_seeing(
    sim: &Simulator,
    object: &ObjectInstance,
    config: &GeneratorConfig,
    targets: &[Point3<f64>],
) -> Vec<ViewPoint> {
    let nav = sim.nav();
    let cam = sim.camera().config();
    let cam_h = cam.mount_height;
    let half_vfov = cam.vfov_deg().to_radians() / 2.0;
    let b = &object.bounds;
    let r = config.view_point_radius;
    let step = config.view_point_spacing;
    if targets.is_empty() {
        return Vec::new();
    }
    let centre = b.center();
    let nx = ((b.max.x - b.min.x + 2.0 * r) / step).floor() as usize + 1;
    let ny = ((b.max.y - b.min.y + 2.0 * r) / step).floor() as usize + 1;
    let mut out = Vec::new();
    for i in 0..nx {
        for j in 0..ny {
            let (x, y) = (b.min.x - r + i as f64 * step, b.min.y - r + j as f64 * step);
            for h in nav.heights_at(x, y) {
                let feet = Point3::new(x, y, h);
                if body_distance(object, &feet, cam_h) > r
                    || !nav.span_at(&feet).is_some_and(|s| nav.is_floor_span(s))
                {
                    continue;
                }
                let eye = Point3::new(x, y, h + cam_h);
                let seen = targets
                    .iter()
                    .filter(|t| visible(sim, object.id, &eye, t, half_vfov))
                    .count();
                if seen > 0 {
                    out.push(ViewPoint {
                        position: feet,
                        yaw: (centre.y - y).atan2(centre.x - x),
                        iou: Some(seen as f64 / targets.len() as f64),
                    });
                }
            }
        }
    }
    out
}

/// Whether the ray from `eye` to `target` first hits instance `id` and lies
/// within the vertical field of view of a level camera.
fn visible(
    sim: &Simulator,
    id: u32,
    eye: &Point3<f64>,
    target: &Point3<f64>,
    half_vfov: f64,
) -> bool {
    let d = target - eye;
    if d.z.atan2(d.xy().norm()).abs() > half_vfov {
        return false;
    }
    let o = [eye.x as f32, eye.y as f32, eye.z as f32];
    let dir = [d.x as f32, d.y as f32, d.z as f32];
    sim.camera()
        .bvh()
        .intersect(o, dir, 0.0, 1.0 + 1e-4)
        .is_some_and(|h| h.payload == id)
}

/// Generates episodes for every configured category present in the scene
/// (see the module docs). Episode ids are `"<index>"`, the scene id is the
/// scene's name.
///
/// # Errors
/// [`GenerateError::Config`] for an invalid configuration.
///
/// # Complexity
/// Per category: view points (see [`goal_view_points`]) plus one geodesic
/// field per goal, O(G S log S), plus O(attempts) start samples and one
/// geodesic field per accepted episode (its floor relation).
pub fn generate_episodes(
    sim: &Simulator,
    config: &GeneratorConfig,
) -> Result<Vec<Episode>, GenerateError> {
    config.validate()?;
    let nav = sim.nav();
    let scene = sim.scene();
    let mut episodes = Vec::new();
    // Starts are drawn from the spans of floor islands (never on furniture).
    let floor_spans: Vec<u32> = (0..nav.span_count() as u32)
        .filter(|&s| nav.is_floor_span(s))
        .collect();
    if floor_spans.is_empty() {
        return Ok(episodes);
    }
    let wide_spans = nav.wide_spans();
    for category in &config.categories {
        let goals: Vec<ObjectGoal> = scene
            .objects_of(category)
            .map(|o| ObjectGoal {
                object_id: u64::from(o.id),
                object_name: Some(format!("{}_{}", o.category, o.id)),
                category: o.category.clone(),
                position: o.bounds.center(),
                view_points: goal_view_points(sim, o, config),
            })
            .filter(|g| !g.view_points.is_empty())
            .collect();
        if goals.is_empty() {
            continue;
        }
        // One field per goal; the distance to the nearest goal is their
        // per-span minimum (Dijkstra is exact for each source set).
        let per_goal: Vec<_> = goals
            .iter()
            .map(|g| {
                nav.geodesic_field(&g.view_points.iter().map(|v| v.position).collect::<Vec<_>>())
            })
            .collect::<Result<_, _>>()?;
        // The agent's 0.25 m moves at 30-degree headings cannot follow
        // strips narrower than three cells: a start must reach a view point
        // over wide spans (the oracle's field).
        let all_view_points: Vec<Point3<f64>> = goals
            .iter()
            .flat_map(|g| g.view_points.iter().map(|v| v.position))
            .collect();
        let wide = nav.geodesic_field_within(&all_view_points, &wide_spans)?;
        let seed = category
            .bytes()
            .fold(config.seed, |h, b| h.rotate_left(7) ^ u64::from(b))
            .wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut made = 0;
        let mut attempts = 0;
        while made < config.episodes_per_category
            && attempts < config.max_attempts * config.episodes_per_category
        {
            attempts += 1;
            let s = floor_spans[rng.random_range(0..floor_spans.len())];
            let start = nav.span_center(s);
            // Closest goal by geodesic distance (the first on ties).
            let (gi, d) = per_goal
                .iter()
                .enumerate()
                .map(|(i, f)| (i, f.span_distance(s)))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap_or((0, f64::INFINITY));
            let in_range = d >= config.min_geodesic && d <= config.max_geodesic;
            if !(in_range && wide.span_distance(s).is_finite()) {
                continue;
            }
            let closest = &goals[gi];
            let euclid = (closest.position - start).norm();
            let ratio = d / euclid.max(1e-9);
            if ratio < config.geodesic_to_euclid_ratio {
                let keep = 20.0 * (ratio - 0.98).powi(2);
                if !rng.random_bool(keep.clamp(0.0, 1.0)) {
                    continue;
                }
            }
            let view_points: Vec<Point3<f64>> = goals
                .iter()
                .flat_map(|g| g.view_points.iter().map(|v| v.position))
                .collect();
            let cross_floor =
                crate::levels::floor_relation(nav, &start, &view_points).map(|f| f.cross_floor());
            let yaw = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
            episodes.push(Episode {
                episode_id: episodes.len().to_string(),
                scene_id: scene.name().to_string(),
                start_position: start,
                start_yaw: yaw,
                object_category: category.clone(),
                goals: goals.clone(),
                geodesic_distance: Some(d),
                euclidean_distance: Some(euclid),
                closest_goal_object_id: Some(closest.object_id),
                cross_floor,
            });
            made += 1;
        }
    }
    Ok(episodes)
}
