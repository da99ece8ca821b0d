//! Floors (levels) of a walkable height field, and the floor relation of an
//! episode (start level, goal level, floors between them).
//!
//! # Definition
//!
//! A **level** is a floor of the building: a large walkable surface at one
//! height. Levels are found from the [`NavMesh`] alone (so generated and
//! imported episodes, procedural, Sweet Home 3D and glTF scenes all use the
//! same definition):
//!
//! 1. The floor spans ([`NavMesh::is_floor_span`]; all spans when there is
//!    none) are binned by surface height in [`LEVEL_BIN`] (5 cm) bins, each
//!    span weighing its area.
//! 2. Bins are visited by decreasing area (the lower bin on ties). A visited
//!    bin not yet used by a level opens a window of ±[`LEVEL_HALF_HEIGHT`]
//!    (0.5 m) around it; when the unused bins of the window hold at least
//!    [`LEVEL_MIN_AREA`] (4 m^2) the window becomes a level, its elevation the
//!    area-weighted mean height of its spans, and its bins are used. Stair
//!    steps, landings and ramps hold far less area per height bin and never
//!    form a level; a sunken living room a few steps down stays on its floor.
//!    When no window reaches the minimum area, the largest one is the only
//!    level (tiny scenes still have a level 0).
//! 3. Levels are numbered by increasing elevation: level 0 is the lowest.
//! 4. **Span level**: a span whose height bin belongs to a level is on that
//!    level; any other span connected to one (a stair step, a landing) takes
//!    the level of the nearest such span in steps over the span graph
//!    (breadth-first; the lower level on ties), so the lower half of a
//!    staircase belongs to the floor below and the upper half to the floor
//!    above. Spans of islands without any level span (furniture tops) take
//!    the highest level at or below their height plus [`LEVEL_HALF_HEIGHT`].
//!
//! The **floor relation** of an episode ([`floor_relation`]): the start
//! level is the level of the span under the start position, the goal level
//! the level of the span under the goal view point nearest to the start
//! (geodesically; by straight line when none is reachable). **Floors
//! between** start and goal is `|goal_level - start_level|`, the number of
//! floor-to-floor transitions in elevation order (0 on the same level, 1 for
//! adjacent floors, 2 when one floor lies in between). An episode is
//! **cross-floor** when it is at least 1.
//!
//! # Complexity
//! Levels are computed once per height field, on first use:
//! O(S + B log B) for S spans and B height bins.

use std::collections::{BTreeMap, VecDeque};

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::geodesic::SNAP_RADIUS;
use crate::navmesh::{NavMesh, SpanId};

/// Height bin of the level histogram (m).
pub const LEVEL_BIN: f64 = 0.05;
/// Half height of a level's window (m): surfaces within it of the level's
/// densest height are on the level.
pub const LEVEL_HALF_HEIGHT: f64 = 0.5;
/// Least walkable area (m^2) of a level.
pub const LEVEL_MIN_AREA: f64 = 4.0;

const NONE: u32 = u32::MAX;

/// A floor of the height field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NavLevel {
    /// Area-weighted mean height of the level's surfaces (m).
    pub elevation: f64,
    /// Walkable floor area within the level's height window (m^2).
    pub area: f64,
    /// Lowest surface height on the level (m).
    pub min_z: f64,
    /// Highest surface height on the level (m).
    pub max_z: f64,
}

/// Levels of a height field and the level of every span.
#[derive(Debug, Clone, Default)]
pub(crate) struct Levels {
    levels: Vec<NavLevel>,
    span_level: Vec<u32>,
}

/// Per height bin: area, sum of area x height, min and max height.
#[derive(Debug, Clone, Copy)]
struct Bin {
    area: f64,
    weighted_z: f64,
    min_z: f64,
    max_z: f64,
    level: u32,
}

fn bin_of(z: f64) -> i64 {
    (z / LEVEL_BIN).floor() as i64
}

fn compute(nav: &NavMesh) -> Levels {
    let n = nav.span_count();
    let cs = nav.config().cell_size;
    let cell_area = cs * cs;
    let any_floor = (0..n as SpanId).any(|s| nav.is_floor_span(s));
    let candidate = |s: SpanId| !any_floor || nav.is_floor_span(s);
    let mut bins: BTreeMap<i64, Bin> = BTreeMap::new();
    for (s, sp) in nav.spans().iter().enumerate() {
        if !candidate(s as SpanId) {
            continue;
        }
        let z = f64::from(sp.floor);
        if !z.is_finite() {
            continue;
        }
        let b = bins.entry(bin_of(z)).or_insert(Bin {
            area: 0.0,
            weighted_z: 0.0,
            min_z: f64::INFINITY,
            max_z: f64::NEG_INFINITY,
            level: NONE,
        });
        b.area += cell_area;
        b.weighted_z += cell_area * z;
        b.min_z = b.min_z.min(z);
        b.max_z = b.max_z.max(z);
    }
    // Peaks by decreasing area, lower bin first on ties.
    let mut order: Vec<(i64, f64)> = bins.iter().map(|(&k, b)| (k, b.area)).collect();
    order.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let reach = (LEVEL_HALF_HEIGHT / LEVEL_BIN).round() as i64;
    let window = |bins: &BTreeMap<i64, Bin>, k: i64| -> f64 {
        bins.range(k - reach..=k + reach)
            .filter(|(_, b)| b.level == NONE)
            .map(|(_, b)| b.area)
            .sum()
    };
    let mut found: Vec<(i64, NavLevel)> = Vec::new();
    let claim = |bins: &mut BTreeMap<i64, Bin>, k: i64, id: u32| -> NavLevel {
        let mut l = NavLevel {
            elevation: 0.0,
            area: 0.0,
            min_z: f64::INFINITY,
            max_z: f64::NEG_INFINITY,
        };
        let mut wz = 0.0;
        for (_, b) in bins.range_mut(k - reach..=k + reach) {
            if b.level == NONE {
                b.level = id;
                l.area += b.area;
                wz += b.weighted_z;
                l.min_z = l.min_z.min(b.min_z);
                l.max_z = l.max_z.max(b.max_z);
            }
        }
        l.elevation = if l.area > 0.0 { wz / l.area } else { 0.0 };
        l
    };
    for &(k, _) in &order {
        if bins.get(&k).is_none_or(|b| b.level != NONE) {
            continue;
        }
        if window(&bins, k) >= LEVEL_MIN_AREA {
            let id = found.len() as u32;
            let l = claim(&mut bins, k, id);
            found.push((k, l));
        }
    }
    if found.is_empty() {
        // Small scene: the largest window is the only level.
        if let Some(&(k, _)) = order.iter().max_by(|a, b| {
            window(&bins, a.0)
                .total_cmp(&window(&bins, b.0))
                .then(b.0.cmp(&a.0))
        }) {
            let l = claim(&mut bins, k, 0);
            found.push((k, l));
        }
    }
    // Renumber by elevation.
    let mut by_elevation: Vec<usize> = (0..found.len()).collect();
    by_elevation.sort_by(|&a, &b| found[a].1.elevation.total_cmp(&found[b].1.elevation));
    let mut rank = vec![0u32; found.len()];
    for (r, &i) in by_elevation.iter().enumerate() {
        rank[i] = r as u32;
    }
    let levels: Vec<NavLevel> = by_elevation.iter().map(|&i| found[i].1).collect();

    // Seeds: spans whose height bin belongs to a level.
    let mut span_level = vec![NONE; n];
    let mut dist = vec![u32::MAX; n];
    let mut queue = VecDeque::new();
    for (s, sp) in nav.spans().iter().enumerate() {
        let z = f64::from(sp.floor);
        if let Some(b) = bins.get(&bin_of(z))
            && b.level != NONE
        {
            span_level[s] = rank[b.level as usize];
            dist[s] = 0;
            queue.push_back(s);
        }
    }
    // Breadth-first over the span graph; the lower level on ties.
    while let Some(s) = queue.pop_front() {
        let (d, l) = (dist[s], span_level[s]);
        for nb in nav.spans()[s].neighbours {
            if nb == NONE {
                continue;
            }
            let m = nb as usize;
            if dist[m] == u32::MAX {
                dist[m] = d + 1;
                span_level[m] = l;
                queue.push_back(m);
            } else if dist[m] == d + 1 && l < span_level[m] {
                span_level[m] = l;
            }
        }
    }
    // Islands without a level span: by height.
    for (s, sp) in nav.spans().iter().enumerate() {
        if span_level[s] == NONE && !levels.is_empty() {
            let z = f64::from(sp.floor);
            span_level[s] = levels
                .iter()
                .rposition(|l| l.elevation <= z + LEVEL_HALF_HEIGHT)
                .unwrap_or(0) as u32;
        }
    }
    Levels { levels, span_level }
}

impl NavMesh {
    fn level_data(&self) -> &Levels {
        self.levels.get_or_init(|| compute(self))
    }

    /// The floors of the height field, by increasing elevation (see the
    /// [`crate::levels`] module for the definition). Empty only when the
    /// height field has no span.
    ///
    /// # Complexity
    /// O(S + B log B) on the first call (S spans, B height bins), O(1) after.
    pub fn levels(&self) -> &[NavLevel] {
        &self.level_data().levels
    }

    /// The level of span `s` (index into [`NavMesh::levels`]); `None` for an
    /// unknown span.
    ///
    /// # Complexity
    /// O(1) once the levels are computed.
    pub fn span_level(&self, s: SpanId) -> Option<usize> {
        self.level_data()
            .span_level
            .get(s as usize)
            .filter(|&&l| l != NONE)
            .map(|&l| l as usize)
    }

    /// The level of the span under `p` (nearest span within
    /// [`SNAP_RADIUS`] horizontally); `None` off the walkable surface.
    ///
    /// # Complexity
    /// O((SNAP_RADIUS / cell_size)^2) columns.
    pub fn level_at(&self, p: &Point3<f64>) -> Option<usize> {
        self.span_level(self.nearest_span(p, SNAP_RADIUS)?)
    }
}

/// Where an episode's start and goal lie among the floors (see the module
/// docs for the definition).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FloorRelation {
    /// Level of the start.
    pub start_level: usize,
    /// Level of the goal view point nearest to the start.
    pub goal_level: usize,
    /// `|goal_level - start_level|`.
    pub floors_between: usize,
}

impl FloorRelation {
    /// Whether start and goal are on different levels.
    pub fn cross_floor(&self) -> bool {
        self.floors_between > 0
    }
}

/// The floor relation of a start and its goal view points: the level of the
/// start and of the view point nearest to it (geodesically, by straight line
/// when none is reachable; the first on ties). `None` when the start or
/// every view point is off the walkable surface.
///
/// # Complexity
/// One geodesic field from the start, O(S log S), plus O(V) view points.
pub fn floor_relation(
    nav: &NavMesh,
    start: &Point3<f64>,
    view_points: &[Point3<f64>],
) -> Option<FloorRelation> {
    let start_level = nav.level_at(start)?;
    let on_mesh: Vec<(&Point3<f64>, usize)> = view_points
        .iter()
        .filter_map(|v| Some((v, nav.level_at(v)?)))
        .collect();
    let field = nav.geodesic_field(std::slice::from_ref(start)).ok();
    let geodesic = |v: &Point3<f64>| {
        field
            .as_ref()
            .and_then(|f| f.distance(nav, v).ok())
            .filter(|d| d.is_finite())
    };
    let nearest = on_mesh
        .iter()
        .filter_map(|&(v, l)| Some((geodesic(v)?, l)))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .or_else(|| {
            on_mesh
                .iter()
                .map(|&(v, l)| ((v - start).norm(), l))
                .min_by(|a, b| a.0.total_cmp(&b.0))
        })?;
    let goal_level = nearest.1;
    Some(FloorRelation {
        start_level,
        goal_level,
        floors_between: start_level.abs_diff(goal_level),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{NavMeshConfig, ProceduralConfig, Scene};

    #[test]
    fn procedural_floors_are_levels_and_stairs_split_between_them() {
        let house = ProceduralConfig {
            floors: Some(2),
            ..ProceduralConfig::default()
        };
        let scene = Scene::procedural(3, &house).unwrap();
        let nav = NavMesh::build(&scene, &NavMeshConfig::default()).unwrap();
        let levels = nav.levels();
        assert_eq!(levels.len(), 2, "{levels:?}");
        assert!(
            levels[1].elevation - levels[0].elevation > 2.0,
            "{levels:?}"
        );
        // every span has a level; spans at a level's height are on it
        for s in 0..nav.span_count() as SpanId {
            let l = nav.span_level(s).unwrap();
            let z = f64::from(nav.spans()[s as usize].floor);
            if (z - levels[0].elevation).abs() < 0.05 {
                assert_eq!(l, 0);
            }
            if (z - levels[1].elevation).abs() < 0.05 {
                assert_eq!(l, 1);
            }
        }
        // a start on level 0 and a view point on level 1: one floor between
        let lo = (0..nav.span_count() as SpanId)
            .find(|&s| nav.span_level(s) == Some(0) && nav.is_floor_span(s))
            .unwrap();
        let hi = (0..nav.span_count() as SpanId)
            .find(|&s| nav.span_level(s) == Some(1) && nav.is_floor_span(s))
            .unwrap();
        let (a, b) = (nav.span_center(lo), nav.span_center(hi));
        let r = floor_relation(&nav, &a, &[b]).unwrap();
        assert_eq!((r.start_level, r.goal_level, r.floors_between), (0, 1, 1));
        assert!(r.cross_floor());
        // the nearer view point decides: one on the start's level wins
        let r = floor_relation(&nav, &a, &[b, a]).unwrap();
        assert_eq!(r.floors_between, 0);
        assert!(floor_relation(&nav, &a, &[Point3::new(1e6, 0.0, 0.0)]).is_none());
    }

    #[test]
    fn single_floor_house_has_one_level() {
        let house = ProceduralConfig {
            floors: Some(1),
            ..ProceduralConfig::default()
        };
        let scene = Scene::procedural(5, &house).unwrap();
        let nav = NavMesh::build(&scene, &NavMeshConfig::default()).unwrap();
        assert_eq!(nav.levels().len(), 1);
        assert!((0..nav.span_count() as SpanId).all(|s| nav.span_level(s) == Some(0)));
    }
}
