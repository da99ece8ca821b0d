//! The stop-in-view check: whether the robot, standing at a pose, sees an
//! object and stands within reach of it — judged on the agent's own maps.
//!
//! ObjectNav counts a stop as a success only at a *view point* of the goal:
//! a navigable pose within 1 m of the object from which the object is
//! visible to the camera held level (Habitat's rule, and the simulator's).
//! A robot that stops within 1 m of the object as the crow flies — behind
//! the wall a television hangs on, or so close to a low plant that it lies
//! below the camera's view — has not found it. The agent has no ground
//! truth, so it judges a pose on what it observed:
//! - **on the floor**: the robot stands on its level's floor (within
//!   [`FLOOR_TOLERANCE_M`]), not on a raised surface next to the object;
//! - **reach**: the distance from the robot's body (the vertical segment
//!   from its feet to the camera) to the bounds of the object's observed
//!   voxels;
//! - **middle in view**: the middle of those bounds lies inside the
//!   vertical field of view of the level camera (less a margin);
//! - **visible share**: the share of the object's observed voxels that lie
//!   inside the vertical field of view of the level camera (less a margin)
//!   and that a straight 3-D line from the camera reaches through the
//!   semantic map without meeting an observed voxel on the way — the
//!   object's own included, so that a surface seen edge-on (a television
//!   from the side) hides itself, as it does from the camera;
//! - **box samples**: at least one of 27 points spread over the object's
//!   bounds (at 1/6, 1/2 and 5/6 of each extent, the points Habitat's
//!   dataset procedure and the simulator test) is in the vertical field of
//!   view and the line from the camera to it meets the object's own voxels
//!   first. Seeing some of an object's surface is not enough: a chair seen
//!   past the edge of a table, or a television seen over its base plate,
//!   shows voxels while every line to the middle of its bounds ends on
//!   something else or in open air.
//!
//! A pose that passes with only a few box samples is a **glimpse**
//! ([`Sight::Glimpse`]); with at least the rule's `min_box_samples` it is a
//! **clear view** ([`Sight::Clear`]). The map decides a line to a box
//! sample less sharply than the camera: a voxel is up to half its size
//! larger than the surface it holds, so a line that passes a chair's seat
//! or a table's edge by a centimetre meets the object on the map and open
//! air in the world, and a box sample in the open middle of a chair's
//! bounds counts as seen. Poses that see few samples are where the two
//! disagree; a clear view sees enough of them that a few grazing lines
//! more or less do not decide it.
//!
//! Occlusion is judged in 3-D on the semantic map's observed voxels, not on
//! the 2-D occupancy grid: the cabinet under a television or a low table in
//! front of a sofa is an obstacle on the grid, yet the camera looks over
//! it. A surface the robot never observed does not occlude: the check can
//! only be as right as the map.

use std::collections::HashSet;

use nalgebra::{Point2, Point3, Vector3};
use sornav_semantic_map::{SemanticMap, VoxelKey};

/// Most object points the visible share looks at: an even subsample
/// (every k-th voxel) keeps the cost of a check bounded for large objects.
pub(crate) const MAX_VIEW_POINTS: usize = 48;

/// A view point stands on its level's floor: at most this far (m) above
/// it (a carpet), not on a hearth, a platform or a step, which ObjectNav
/// does not count as standing at the object.
pub(crate) const FLOOR_TOLERANCE_M: f64 = 0.05;

/// Voxel sizes before an object point that a line of sight does not test.
pub(crate) const TAIL_VOXELS: f64 = 2.0;

/// Box samples a view point must see. The map's voxels make surfaces up
/// to a voxel thicker than they are, so a line that grazes an edge meets
/// the object on the map but not in the world; a second sample is the
/// margin against such poses (Habitat's rule asks for one, exactly).
pub(crate) const MIN_BOX_SAMPLES: usize = 2;

/// Fractions of each extent of the object's bounds at which the box
/// samples lie (27 points).
const BOX_SAMPLE_FRACTIONS: [f64; 3] = [1.0 / 6.0, 0.5, 5.0 / 6.0];

/// How the agent's sensor sees, learned from the frames it gets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Viewer {
    /// Height of the sensor above the robot's feet (m).
    pub eye_height: f64,
    /// Half the vertical field of view (rad) of the camera held level;
    /// `None` for a sensor without a vertical limit (a labelled LiDAR
    /// cloud).
    pub half_vfov: Option<f64>,
}

impl Viewer {
    /// The sensor's position for a robot with its feet at `feet`.
    fn eye(&self, feet: &Point3<f64>) -> Point3<f64> {
        Point3::new(feet.x, feet.y, feet.z + self.eye_height)
    }

    /// Whether `p` lies inside the vertical field of view of the level
    /// camera at `eye`, less `margin_rad` (always, without a vertical
    /// limit).
    fn in_vertical_view(&self, eye: &Point3<f64>, p: &Point3<f64>, margin_rad: f64) -> bool {
        let d = p - eye;
        self.half_vfov
            .is_none_or(|h| d.z.atan2(d.xy().norm()).abs() <= (h - margin_rad).max(0.0))
    }

    /// How many of `points` lie in the vertical view from `eye` (less
    /// `margin_rad`) and pass the line test `line`.
    fn count_in_view(
        &self,
        eye: &Point3<f64>,
        margin_rad: f64,
        points: impl Iterator<Item = Point3<f64>>,
        line: impl Fn(&Point3<f64>) -> bool,
    ) -> usize {
        points
            .filter(|p| self.in_vertical_view(eye, p, margin_rad) && line(p))
            .count()
    }
}

/// What makes a pose a view point of an object.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ViewRule {
    /// Largest reach (m): body-to-bounds distance.
    pub max_reach_m: f64,
    /// Smallest visible share in `[0, 1]`.
    pub min_visible_share: f64,
    /// Margin (rad) inside the vertical field of view.
    pub vfov_margin_rad: f64,
    /// Box samples a clear view sees (see [`Sight`]).
    pub min_box_samples: usize,
}

/// How a pose views an object (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Sight {
    /// Not a view point.
    Hidden,
    /// A view point seeing fewer than the rule's `min_box_samples` box
    /// samples (but at least [`MIN_BOX_SAMPLES`], or the rule's number
    /// when that is smaller).
    Glimpse,
    /// A view point seeing at least the rule's `min_box_samples`.
    Clear,
}

/// An observed object as the check sees it.
#[derive(Debug, Clone)]
pub(crate) struct ObjectView {
    /// Subsample of the voxel centres (at most [`MAX_VIEW_POINTS`]).
    points: Vec<Point3<f64>>,
    /// All of the object's voxels.
    keys: HashSet<VoxelKey>,
    /// Bounds of all voxel centres.
    lo: Point3<f64>,
    hi: Point3<f64>,
    /// Voxel size (m).
    res: f64,
}

/// Horizontal distance from `p` to the rectangle `[lo, hi]` (0 inside).
pub(crate) fn distance_to_box(p: &Point2<f64>, lo: &Point2<f64>, hi: &Point2<f64>) -> f64 {
    let dx = (lo.x - p.x).max(0.0).max(p.x - hi.x);
    let dy = (lo.y - p.y).max(0.0).max(p.y - hi.y);
    dx.hypot(dy)
}

impl ObjectView {
    /// The view of an object from its voxels (`res`: the voxel size);
    /// `None` when there is none.
    ///
    /// # Complexity
    /// O(V) for V voxels.
    pub(crate) fn new(keys: &[VoxelKey], res: f64) -> Option<Self> {
        let first = keys.first()?.centre(res);
        let (mut lo, mut hi) = (first, first);
        for k in keys {
            let p = k.centre(res);
            lo = lo.inf(&p);
            hi = hi.sup(&p);
        }
        let stride = keys.len().div_ceil(MAX_VIEW_POINTS);
        let points = keys.iter().step_by(stride).map(|k| k.centre(res)).collect();
        Some(Self {
            points,
            keys: keys.iter().copied().collect(),
            lo,
            hi,
            res,
        })
    }

    /// Horizontal bounds `(lo, hi)` of the object.
    pub(crate) fn footprint(&self) -> (Point2<f64>, Point2<f64>) {
        (self.lo.xy(), self.hi.xy())
    }

    /// Distance (m) from the robot's body — the vertical segment from
    /// `feet` up `eye_height` — to the object's bounds.
    pub(crate) fn reach(&self, feet: &Point3<f64>, eye_height: f64) -> f64 {
        let horizontal = distance_to_box(&feet.xy(), &self.lo.xy(), &self.hi.xy());
        let (bottom, top) = (feet.z, feet.z + eye_height.max(0.0));
        let vertical = (self.lo.z - top).max(0.0).max(bottom - self.hi.z);
        horizontal.hypot(vertical)
    }

    /// Share of the object's points seen from the sensor at `feet` (see the
    /// module docs), with `map`'s observed voxels as occluders.
    ///
    /// # Complexity
    /// O(P L) for P <= [`MAX_VIEW_POINTS`] points and L voxels per line.
    pub(crate) fn visible_share(
        &self,
        map: &SemanticMap,
        feet: &Point3<f64>,
        viewer: &Viewer,
        vfov_margin_rad: f64,
    ) -> f64 {
        let eye = viewer.eye(feet);
        let seen = viewer.count_in_view(&eye, vfov_margin_rad, self.points.iter().copied(), |p| {
            self.line_clear(map, &eye, p)
        });
        seen as f64 / self.points.len() as f64
    }

    /// Whether the segment from `eye` to `p` meets no observed voxel,
    /// sampled every third of a voxel; the last [`TAIL_VOXELS`] voxel
    /// sizes before `p` are not tested (the point's own surface layer, one
    /// or two voxels thick, or a neighbour touching the object such as the
    /// cabinet under a television, does not hide it).
    pub(crate) fn line_clear(&self, map: &SemanticMap, eye: &Point3<f64>, p: &Point3<f64>) -> bool {
        let length = (p - eye).norm();
        let end = length - TAIL_VOXELS * self.res;
        if end.is_nan() || end <= 0.0 {
            return true;
        }
        let n = (end / (self.res / 3.0)).ceil() as usize;
        let dir = (p - eye) / length;
        (0..=n).all(|i| {
            let q = eye + dir * (end * i as f64 / n.max(1) as f64);
            let key = VoxelKey::from_point(&q, self.res);
            map.voxel(&key).is_none()
        })
    }

    /// Whether the middle of the object's bounds lies inside the vertical
    /// field of view (less `vfov_margin_rad`) of the level camera at
    /// `feet`: the top leaves of a low plant can be in view from right next
    /// to it while the plant itself is below the image.
    pub(crate) fn middle_in_view(
        &self,
        feet: &Point3<f64>,
        viewer: &Viewer,
        vfov_margin_rad: f64,
    ) -> bool {
        let middle = Point3::from((self.lo.coords + self.hi.coords) / 2.0);
        viewer.in_vertical_view(&viewer.eye(feet), &middle, vfov_margin_rad)
    }

    /// The 27 box samples: points at [`BOX_SAMPLE_FRACTIONS`] of each
    /// extent of the bounds of the object's voxels (voxel faces, not
    /// centres).
    fn box_samples(&self) -> impl Iterator<Item = Point3<f64>> + '_ {
        let half = Vector3::repeat(self.res / 2.0);
        let (lo, hi) = (self.lo - half, self.hi + half);
        let e = hi - lo;
        BOX_SAMPLE_FRACTIONS.into_iter().flat_map(move |fx| {
            BOX_SAMPLE_FRACTIONS.into_iter().flat_map(move |fy| {
                BOX_SAMPLE_FRACTIONS
                    .into_iter()
                    .map(move |fz| lo + Vector3::new(e.x * fx, e.y * fy, e.z * fz))
            })
        })
    }

    /// Whether the line from `eye` to `p` (sampled every third of a voxel,
    /// up to half a voxel past `p`) meets one of the object's voxels before
    /// any other observed voxel: the object is what the camera sees in that
    /// direction. A line that ends in open air or on another surface first
    /// does not show the object.
    fn first_hit_is_object(&self, map: &SemanticMap, eye: &Point3<f64>, p: &Point3<f64>) -> bool {
        let length = (p - eye).norm();
        let end = length + self.res / 2.0;
        if !end.is_finite() || length <= 0.0 {
            return false;
        }
        let n = (end / (self.res / 3.0)).ceil() as usize;
        let dir = (p - eye) / length;
        for i in 0..=n {
            let q = eye + dir * (end * i as f64 / n.max(1) as f64);
            let key = VoxelKey::from_point(&q, self.res);
            if self.keys.contains(&key) {
                return true;
            }
            if map.voxel(&key).is_some() {
                return false;
            }
        }
        false
    }

    /// How many box samples (see the module docs) are seen from the sensor
    /// at `feet`: inside the vertical field of view (less
    /// `vfov_margin_rad`), with the object first on the line to them.
    ///
    /// # Complexity
    /// O(27 L) for L voxels per line.
    pub(crate) fn box_samples_seen(
        &self,
        map: &SemanticMap,
        feet: &Point3<f64>,
        viewer: &Viewer,
        vfov_margin_rad: f64,
    ) -> usize {
        let eye = viewer.eye(feet);
        viewer.count_in_view(&eye, vfov_margin_rad, self.box_samples(), |p| {
            self.first_hit_is_object(map, &eye, p)
        })
    }

    /// Whether `feet` is a view point of the object under `rule` (a
    /// glimpse or a clear view, see [`Self::sight`]).
    #[cfg(test)]
    pub(crate) fn seen_from(
        &self,
        map: &SemanticMap,
        feet: &Point3<f64>,
        viewer: &Viewer,
        rule: &ViewRule,
    ) -> bool {
        self.sight(map, feet, viewer, rule) != Sight::Hidden
    }

    /// How the sensor at `feet` views the object under `rule`; the visible
    /// share and the box samples are computed only when the cheaper tests
    /// pass.
    ///
    /// # Complexity
    /// O((P + 27) L) for P <= [`MAX_VIEW_POINTS`] object points and L
    /// voxels per line.
    pub(crate) fn sight(
        &self,
        map: &SemanticMap,
        feet: &Point3<f64>,
        viewer: &Viewer,
        rule: &ViewRule,
    ) -> Sight {
        let visible = self.reach(feet, viewer.eye_height) <= rule.max_reach_m
            && self.middle_in_view(feet, viewer, rule.vfov_margin_rad)
            && self.visible_share(map, feet, viewer, rule.vfov_margin_rad)
                >= rule.min_visible_share;
        if !visible {
            return Sight::Hidden;
        }
        let seen = self.box_samples_seen(map, feet, viewer, rule.vfov_margin_rad);
        if seen >= rule.min_box_samples {
            Sight::Clear
        } else if seen >= MIN_BOX_SAMPLES {
            Sight::Glimpse
        } else {
            Sight::Hidden
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use proptest::prelude::*;
    use sornav_frontier_graph::{FrontierMapConfig, MultiLevelMap};
    use sornav_semantic_map::{LabelId, LabelSet, LabeledPoint, MapConfig};

    /// A closed 8 m x 6 m room scanned from the origin (sensor 0.5 m up),
    /// with a box obstacle `(lo, hi)`: the traversability map.
    pub(crate) fn room_with_box(lo: Point2<f64>, hi: Point2<f64>) -> MultiLevelMap {
        let mut map = MultiLevelMap::new(FrontierMapConfig::default()).unwrap();
        let mut points = Vec::new();
        for k in 0..1440 {
            let t = f64::from(k) * std::f64::consts::PI / 720.0;
            let (c, s) = (t.cos(), t.sin());
            let tx = if c.abs() > 1e-9 {
                4.0 / c.abs()
            } else {
                f64::INFINITY
            };
            let ty = if s.abs() > 1e-9 {
                3.0 / s.abs()
            } else {
                f64::INFINITY
            };
            // First hit of the box by slab intersection.
            let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
            for (d, l, h) in [(c, lo.x, hi.x), (s, lo.y, hi.y)] {
                if d.abs() < 1e-12 {
                    if l > 0.0 || h < 0.0 {
                        t0 = f64::INFINITY;
                    }
                } else {
                    let (a, b) = (l / d, h / d);
                    t0 = t0.max(a.min(b));
                    t1 = t1.min(a.max(b));
                }
            }
            let hit_box = (t0 <= t1 && t0 > 0.0).then_some(t0 + 0.01);
            let r = hit_box.unwrap_or(f64::INFINITY).min(tx.min(ty));
            points.push(Point3::new(r * c, r * s, 0.5));
        }
        map.update(&Point3::origin(), &Point3::new(0.0, 0.0, 0.5), &points)
            .unwrap();
        map
    }

    /// A solid box for the semantic map: its corners.
    pub(crate) type Solid = (Point3<f64>, Point3<f64>);

    /// A semantic map holding the surfaces of the given boxes (points every
    /// 2.5 cm on the six faces, label 1 + index: what a sensor observes),
    /// and each box's voxels.
    pub(crate) fn voxel_map(solids: &[Solid]) -> (SemanticMap, Vec<Vec<VoxelKey>>) {
        let mut map = SemanticMap::new(MapConfig::default(), LabelSet::household()).unwrap();
        let res = map.resolution();
        let mut keys = Vec::new();
        for (i, (lo, hi)) in solids.iter().enumerate() {
            let n = |a: f64, b: f64| ((b - a) / 0.025).floor() as usize;
            let mut points = Vec::new();
            let mut own = std::collections::BTreeSet::new();
            for x in 0..=n(lo.x, hi.x) {
                for y in 0..=n(lo.y, hi.y) {
                    for z in 0..=n(lo.z, hi.z) {
                        let face = [(x, n(lo.x, hi.x)), (y, n(lo.y, hi.y)), (z, n(lo.z, hi.z))]
                            .iter()
                            .any(|&(i, m)| i == 0 || i == m);
                        if !face {
                            continue;
                        }
                        let p = Point3::new(
                            lo.x + 0.025 * x as f64,
                            lo.y + 0.025 * y as f64,
                            lo.z + 0.025 * z as f64,
                        );
                        // The map stores f32 points: key them as it does.
                        let stored = Point3::new(
                            f64::from(p.x as f32),
                            f64::from(p.y as f32),
                            f64::from(p.z as f32),
                        );
                        own.insert(VoxelKey::from_point(&stored, res));
                        points.push(LabeledPoint::new(
                            p.x as f32,
                            p.y as f32,
                            p.z as f32,
                            LabelId(1 + i as u16),
                        ));
                    }
                }
            }
            let centre =
                Point3::from((lo.coords + hi.coords) / 2.0) + nalgebra::Vector3::new(0.0, 0.0, 2.0);
            map.integrate_points(&centre, &points).unwrap();
            keys.push(own.into_iter().collect());
        }
        (map, keys)
    }

    pub(crate) fn solid(x0: f64, y0: f64, z0: f64, x1: f64, y1: f64, z1: f64) -> Solid {
        (Point3::new(x0, y0, z0), Point3::new(x1, y1, z1))
    }

    pub(crate) const LEVEL: Viewer = Viewer {
        eye_height: 0.88,
        half_vfov: Some(0.55),
    };

    const RULE: ViewRule = ViewRule {
        max_reach_m: 0.85,
        min_visible_share: 0.25,
        vfov_margin_rad: 0.05,
        min_box_samples: 8,
    };

    fn feet(x: f64, y: f64) -> Point3<f64> {
        Point3::new(x, y, 0.0)
    }

    #[test]
    fn an_occluder_hides_what_lies_behind_it() {
        let (map, keys) = voxel_map(&[
            solid(1.5, -0.5, 0.0, 1.7, 0.5, 1.5),
            solid(2.5, -0.2, 0.4, 2.9, 0.2, 0.8),
        ]);
        let object = ObjectView::new(&keys[1], map.resolution()).unwrap();
        assert_eq!(
            object.visible_share(&map, &feet(0.5, 0.0), &LEVEL, 0.0),
            0.0
        );
        let share = object.visible_share(&map, &feet(2.6, 1.2), &LEVEL, 0.0);
        assert!(share >= RULE.min_visible_share, "{share}");
        // The occluder is seen from the front.
        let occluder = ObjectView::new(&keys[0], map.resolution()).unwrap();
        assert!(occluder.visible_share(&map, &feet(0.2, 0.0), &LEVEL, 0.0) > 0.25);
    }

    #[test]
    fn an_object_on_a_wall_is_hidden_from_behind_the_wall() {
        // A television on the near face of a wall, seen from the wall's far
        // side: within reach, but not in view.
        let (map, keys) = voxel_map(&[
            solid(1.5, -1.0, 0.0, 1.6, 1.0, 2.0),
            solid(1.4, -0.4, 0.6, 1.47, 0.4, 1.0),
        ]);
        let tv = ObjectView::new(&keys[1], map.resolution()).unwrap();
        let behind = feet(2.2, 0.0);
        assert!(tv.reach(&behind, 0.88) < 0.85);
        assert!(!tv.seen_from(&map, &behind, &LEVEL, &RULE));
        assert!(tv.seen_from(&map, &feet(0.8, 0.0), &LEVEL, &RULE));
    }

    #[test]
    fn a_cabinet_under_a_television_does_not_hide_it() {
        // The cabinet is an obstacle on a 2-D grid between the robot and
        // the screen; the camera looks over it.
        let (map, keys) = voxel_map(&[
            solid(0.5, -0.6, 0.0, 1.0, 0.6, 0.5),
            solid(0.55, -0.5, 0.55, 0.62, 0.5, 1.2),
        ]);
        let tv = ObjectView::new(&keys[1], map.resolution()).unwrap();
        assert!(tv.seen_from(&map, &feet(1.4, 0.0), &LEVEL, &RULE));
    }

    #[test]
    fn a_low_object_at_the_feet_is_below_the_view() {
        let (map, keys) = voxel_map(&[solid(1.0, -0.1, 0.0, 1.2, 0.1, 0.2)]);
        let plant = ObjectView::new(&keys[0], map.resolution()).unwrap();
        // 0.2 m away, the eye 0.88 m up: about 70 degrees down.
        assert_eq!(plant.visible_share(&map, &feet(0.8, 0.0), &LEVEL, 0.0), 0.0);
        // 1.5 m away: under 30 degrees down, inside the 31.5-degree half view.
        assert!(plant.visible_share(&map, &feet(-0.5, 0.0), &LEVEL, 0.0) > 0.25);
        // A sensor without a vertical limit sees it from near by.
        let lidar = Viewer {
            eye_height: 0.88,
            half_vfov: None,
        };
        assert!(plant.visible_share(&map, &feet(0.8, 0.0), &lidar, 0.0) > 0.25);
    }

    #[test]
    fn a_low_plant_needs_its_middle_in_view() {
        // A 0.5 m pot with leaves up to 0.9 m: from 0.3 m away the top
        // leaves are in view, the pot and the middle below the image.
        let (map, keys) = voxel_map(&[
            solid(1.0, -0.15, 0.0, 1.3, 0.15, 0.5),
            solid(0.9, -0.3, 0.5, 1.4, 0.3, 0.9),
        ]);
        let mut both = keys[0].clone();
        both.extend(&keys[1]);
        let plant = ObjectView::new(&both, map.resolution()).unwrap();
        let near = feet(0.6, 0.0);
        assert!(plant.visible_share(&map, &near, &LEVEL, 0.05) > 0.0);
        assert!(!plant.middle_in_view(&near, &LEVEL, 0.05));
        assert!(!plant.seen_from(&map, &near, &LEVEL, &RULE));
        assert!(plant.middle_in_view(&feet(0.2, 0.0), &LEVEL, 0.05));
    }

    /// A chair: a seat on four legs (open below the seat) and a back
    /// along its +x side.
    fn chair(x: f64, y: f64) -> Vec<Solid> {
        let mut parts = vec![
            solid(x, y, 0.42, x + 0.45, y + 0.45, 0.47),
            solid(x + 0.4, y, 0.47, x + 0.45, y + 0.45, 0.9),
        ];
        for (dx, dy) in [(0.0, 0.0), (0.4, 0.0), (0.0, 0.4), (0.4, 0.4)] {
            parts.push(solid(
                x + dx,
                y + dy,
                0.0,
                x + dx + 0.05,
                y + dy + 0.05,
                0.42,
            ));
        }
        parts
    }

    #[test]
    fn a_chair_past_a_table_edge_is_glimpsed_and_clear_beside_it() {
        // The chair's open side faces -x, where a table top (0.72-0.76 m,
        // y from -0.6 m) stands in front of it.
        let mut solids = chair(1.0, 0.0);
        let n = solids.len();
        solids.push(solid(0.45, -0.6, 0.72, 0.95, 1.0, 0.76));
        let (map, keys) = voxel_map(&solids);
        let all: Vec<VoxelKey> = keys[..n].iter().flatten().copied().collect();
        let chair = ObjectView::new(&all, map.resolution()).unwrap();
        let margin = RULE.vfov_margin_rad;
        // Past the table's corner: the lines to most samples end on the
        // table top or in the open middle of the chair; a glimpse.
        let corner = feet(0.8, -0.7);
        let seen = chair.box_samples_seen(&map, &corner, &LEVEL, margin);
        assert!(
            (MIN_BOX_SAMPLES..RULE.min_box_samples).contains(&seen),
            "{seen}"
        );
        assert_eq!(chair.sight(&map, &corner, &LEVEL, &RULE), Sight::Glimpse);
        // 0.3 m further along the chair's side: a clear view.
        let beside = feet(1.1, -0.8);
        assert!(chair.box_samples_seen(&map, &beside, &LEVEL, margin) >= RULE.min_box_samples);
        assert_eq!(chair.sight(&map, &beside, &LEVEL, &RULE), Sight::Clear);
        // Behind the table: hidden.
        assert_eq!(
            chair.sight(&map, &feet(0.3, 0.2), &LEVEL, &RULE),
            Sight::Hidden
        );
        // A rule asking for one sample calls every view point clear.
        let lenient = ViewRule {
            min_box_samples: 1,
            ..RULE
        };
        assert_eq!(chair.sight(&map, &corner, &LEVEL, &lenient), Sight::Clear);
    }

    /// Whether the segment `a -> b` meets the cube of voxel `k` (slabs).
    fn meets(a: &Point3<f64>, b: &Point3<f64>, k: &VoxelKey, res: f64) -> bool {
        let c = k.centre(res);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for i in 0..3 {
            let (lo, hi) = (c[i] - res / 2.0, c[i] + res / 2.0);
            let d = b[i] - a[i];
            if d.abs() < 1e-12 {
                if a[i] < lo || a[i] > hi {
                    return false;
                }
            } else {
                let (u, v) = ((lo - a[i]) / d, (hi - a[i]) / d);
                t0 = t0.max(u.min(v));
                t1 = t1.min(u.max(v));
            }
        }
        t0 <= t1
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// The reach is the distance between the body segment and the
        /// object's bounds: it matches a brute-force minimum over points of
        /// the segment (each clamped into the box), and is never larger.
        #[test]
        fn reach_matches_brute_force(
            fx in -2.0f64..2.0, fy in -2.0f64..2.0, fz in -1.0f64..2.0,
            eye in 0.0f64..1.5,
            z0 in -0.5f64..1.5, dz in 0.0f64..1.0,
        ) {
            let res = 0.05;
            let (a, b) = (Point3::new(-0.3, -0.2, z0), Point3::new(0.4, 0.3, z0 + dz));
            let object = ObjectView::new(
                &[VoxelKey::from_point(&a, res), VoxelKey::from_point(&b, res)],
                res,
            )
            .unwrap();
            let (lo, hi) = (object.lo, object.hi);
            let f = Point3::new(fx, fy, fz);
            let reach = object.reach(&f, eye);
            let mut brute = f64::INFINITY;
            for i in 0..=2000 {
                let p = Point3::new(fx, fy, fz + eye * f64::from(i) / 2000.0);
                let q = Point3::new(p.x.clamp(lo.x, hi.x), p.y.clamp(lo.y, hi.y), p.z.clamp(lo.z, hi.z));
                brute = brute.min((p - q).norm());
            }
            prop_assert!(reach <= brute + 1e-12);
            prop_assert!(brute - reach <= eye / 2000.0 + 1e-9);
        }

        /// Differential against the exact test of every observed voxel: a
        /// line is never blocked unless the segment (less its last voxel)
        /// meets an observed voxel, and it is blocked whenever it passes
        /// through the middle of one (the last two voxels left out).
        #[test]
        fn a_block_is_a_voxel_on_the_line(
            bx in 0.5f64..1.5, by in -0.5f64..0.5, bz in 0.0f64..1.0,
            tx in 2.0f64..3.0, ty in -1.0f64..1.0, tz in 0.0f64..1.5,
            ex in -1.0f64..0.3, ey in -1.0f64..1.0,
        ) {
            let (map, keys) = voxel_map(&[
                solid(bx, by, bz, bx + 0.2, by + 0.3, bz + 0.4),
                solid(tx, ty, tz, tx + 0.1, ty + 0.1, tz + 0.1),
            ]);
            let res = map.resolution();
            let object = ObjectView::new(&keys[1], res).unwrap();
            let eye = Point3::new(ex, ey, 0.88);
            for p in &object.points {
                let clear = object.line_clear(&map, &eye, p);
                let dir = (p - eye).normalize();
                let end = p - dir * TAIL_VOXELS * res;
                let len = (end - eye).norm();
                if !clear {
                    prop_assert!(
                        map.voxels().any(|(k, _)| meets(&eye, &end, &k, res)),
                        "blocked without a voxel on the line"
                    );
                }
                // Through the middle: the segment passes within 0.4 voxel of
                // a voxel's centre, with 0.3 voxel of segment on each side.
                let deep = map.voxels().any(|(k, _)| {
                    let c = k.centre(res);
                    let t = (c - eye).dot(&dir).clamp(0.0, len);
                    let q = eye + dir * t;
                    (c - q).norm() < 0.4 * res && t >= 0.3 * res && len - t >= 0.3 * res
                });
                if deep {
                    prop_assert!(!clear, "a line through a voxel's middle was clear");
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// [`ObjectView::sight`] against its definition, computed test by
        /// test: hidden unless reach, middle, share and at least
        /// `min(2, min_box_samples)` box samples hold; clear from
        /// `min_box_samples` samples. A stricter rule never makes a view
        /// clearer.
        #[test]
        fn sight_matches_its_definition(
            fx in -0.5f64..2.5, fy in -1.5f64..1.5,
            k in 1usize..=27,
            tx in 0.5f64..1.5, tz in 0.0f64..0.8,
            occluder in proptest::bool::ANY,
            panel in proptest::bool::ANY,
        ) {
            // A chair, or a thin panel seen from its face or edge-on.
            let mut solids = if panel {
                vec![solid(tx, -0.4, tz + 0.3, tx + 0.05, 0.4, tz + 0.8)]
            } else {
                chair(tx, -0.2)
            };
            let n = solids.len();
            if occluder {
                solids.push(solid(tx - 0.6, -1.0, tz, tx - 0.3, 1.0, tz + 0.05));
            }
            let (map, keys) = voxel_map(&solids);
            let all: Vec<VoxelKey> = keys[..n].iter().flatten().copied().collect();
            let object = ObjectView::new(&all, map.resolution()).unwrap();
            let p = feet(fx, fy);
            let rule = ViewRule { min_box_samples: k, ..RULE };
            let seen = object.box_samples_seen(&map, &p, &LEVEL, rule.vfov_margin_rad);
            let gates = object.reach(&p, LEVEL.eye_height) <= rule.max_reach_m
                && object.middle_in_view(&p, &LEVEL, rule.vfov_margin_rad)
                && object.visible_share(&map, &p, &LEVEL, rule.vfov_margin_rad) >= rule.min_visible_share;
            let want = if !gates || seen < k.min(MIN_BOX_SAMPLES) {
                Sight::Hidden
            } else if seen >= k {
                Sight::Clear
            } else {
                Sight::Glimpse
            };
            let got = object.sight(&map, &p, &LEVEL, &rule);
            prop_assert_eq!(got, want);
            prop_assert_eq!(object.seen_from(&map, &p, &LEVEL, &rule), want != Sight::Hidden);
            if k < 27 {
                let stricter = ViewRule { min_box_samples: k + 1, ..rule };
                prop_assert!(object.sight(&map, &p, &LEVEL, &stricter) <= got);
            }
        }
    }
}
