//! Geodesic distance on the walkable height field.
//!
//! Distances are shortest paths over the span graph of a [`NavMesh`]: each
//! span connects to its 4 neighbours and to diagonal neighbours reachable by
//! both orthogonal routes (octile moves); a move costs the 3-D distance between
//! span centres, so geodesic distance is never shorter than the straight line.
//! A query point off a span centre adds its straight-line offset to the
//! snapped span (and two points over the same span are at straight-line
//! distance), which keeps d(a, a) = 0, symmetry and the triangle inequality.
//! A [`GeodesicField`] also measures goals within [`NEAR_GOAL_RADIUS`] of
//! the query point exactly when the straight segment to them is walkable, so
//! that success radii of a few centimetres (Habitat's 0.1 m) are not
//! distorted by the 5 cm span discretisation.
//!
//! Algorithm: Dijkstra (1959) with a binary heap, multi-source for goal sets.

use std::collections::BinaryHeap;

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::NavError;
use crate::navmesh::{HeapItem, NavMesh, SpanId};

/// Horizontal search radius used to snap query points that are not exactly
/// over a walkable span (0.5 m).
pub const SNAP_RADIUS: f64 = 0.5;

/// Goals within this straight-line distance (m) of a query point are
/// measured exactly when the straight segment to them is walkable.
pub const NEAR_GOAL_RADIUS: f64 = 0.3;

/// Field values up to this (m) trigger the exact near-goal check (a goal
/// within [`NEAR_GOAL_RADIUS`] always gives a field value below it: the
/// octile span graph overstates short distances by at most 8 %, plus one
/// cell diagonal at each end).
const NEAR_GOAL_SCAN: f64 = 0.5;

/// Distances from a set of goal points to every span of a [`NavMesh`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct GeodesicField {
    dist: Vec<f64>,
    /// Goal points snapped to spans: (span, offset of the goal from the span centre, goal).
    goals: Vec<(SpanId, Point3<f64>)>,
}

impl GeodesicField {
    /// Geodesic distance from `p` to the nearest goal (`f64::INFINITY` when unreachable).
    ///
    /// # Errors
    /// [`NavError::NonFinite`] or [`NavError::NotNavigable`] when `p` cannot be
    /// snapped to the walkable surface.
    ///
    /// # Complexity
    /// O(1) after snapping.
    pub fn distance(&self, nav: &NavMesh, p: &Point3<f64>) -> Result<f64, NavError> {
        let s = locate(nav, p)?;
        let c = nav.span_center(s);
        let mut d = (p - c).norm() + self.dist[s as usize];
        if d <= NEAR_GOAL_SCAN {
            // Near a goal the span discretisation would overstate the
            // distance by up to a cell diagonal: a goal in straight-line
            // reach over walkable spans is at its straight-line distance.
            for (gs, g) in &self.goals {
                let e = (p - g).norm();
                if e < d
                    && (*gs == s
                        || (e <= NEAR_GOAL_RADIUS
                            && crate::agent::walk_segment(nav, s, p, g)
                                .is_some_and(|(_, end)| end == *gs)))
                {
                    d = e;
                }
            }
        }
        Ok(d)
    }

    /// Distance stored for span `s` (from its centre).
    pub fn span_distance(&self, s: SpanId) -> f64 {
        self.dist.get(s as usize).copied().unwrap_or(f64::INFINITY)
    }

    /// Per-span distances, indexed by [`SpanId`].
    pub fn span_distances(&self) -> &[f64] {
        &self.dist
    }
}

fn locate(nav: &NavMesh, p: &Point3<f64>) -> Result<SpanId, NavError> {
    if !p.coords.iter().all(|c| c.is_finite()) {
        return Err(NavError::NonFinite);
    }
    nav.nearest_span(p, SNAP_RADIUS)
        .ok_or(NavError::NotNavigable {
            x: p.x,
            y: p.y,
            z: p.z,
        })
}

fn dijkstra(
    nav: &NavMesh,
    sources: &[(SpanId, f64)],
    target: Option<SpanId>,
    within: Option<&[bool]>,
) -> (Vec<f64>, Vec<u32>) {
    let allowed = |s: usize| within.is_none_or(|w| w.get(s).copied().unwrap_or(false));
    let n = nav.span_count();
    let mut dist = vec![f64::INFINITY; n];
    let mut parent = vec![u32::MAX; n];
    let mut heap = BinaryHeap::new();
    for &(s, d0) in sources {
        if allowed(s as usize) && d0 < dist[s as usize] {
            dist[s as usize] = d0;
            heap.push(HeapItem(d0, s));
        }
    }
    while let Some(HeapItem(d, s)) = heap.pop() {
        if d > dist[s as usize] {
            continue;
        }
        if target == Some(s) {
            break;
        }
        for (m, w) in nav.moves_3d(s as usize) {
            let nd = d + w;
            if nd < dist[m] && allowed(m) {
                dist[m] = nd;
                parent[m] = s;
                heap.push(HeapItem(nd, m as u32));
            }
        }
    }
    (dist, parent)
}

impl NavMesh {
    /// Multi-goal geodesic distance field. Goals farther than [`SNAP_RADIUS`]
    /// from the walkable surface are ignored; at least one must snap.
    ///
    /// # Errors
    /// [`NavError::NoGoals`] when no goal lies on (or near) the walkable surface.
    ///
    /// # Complexity
    /// O(S log S) for S spans.
    pub fn geodesic_field(&self, goals: &[Point3<f64>]) -> Result<GeodesicField, NavError> {
        self.field_within(goals, None)
    }

    /// [`NavMesh::geodesic_field`] over the spans flagged in `within` only
    /// (other spans are at infinite distance; goals on them are ignored),
    /// e.g. [`NavMesh::wide_spans`].
    ///
    /// # Errors
    /// [`NavError::NoGoals`] when no goal lies on (or near) a flagged span.
    ///
    /// # Complexity
    /// O(S log S) for S spans.
    pub fn geodesic_field_within(
        &self,
        goals: &[Point3<f64>],
        within: &[bool],
    ) -> Result<GeodesicField, NavError> {
        self.field_within(goals, Some(within))
    }

    fn field_within(
        &self,
        goals: &[Point3<f64>],
        within: Option<&[bool]>,
    ) -> Result<GeodesicField, NavError> {
        let mut snapped = Vec::new();
        let mut sources = Vec::new();
        for g in goals {
            if let Ok(s) = locate(self, g)
                && within.is_none_or(|w| w.get(s as usize).copied().unwrap_or(false))
            {
                snapped.push((s, *g));
                sources.push((s, (g - self.span_center(s)).norm()));
            }
        }
        if sources.is_empty() {
            return Err(NavError::NoGoals);
        }
        let (dist, _) = dijkstra(self, &sources, None, within);
        Ok(GeodesicField {
            dist,
            goals: snapped,
        })
    }

    /// Geodesic distance between two points (`f64::INFINITY` when they lie on
    /// different islands).
    ///
    /// # Errors
    /// [`NavError`] when either point cannot be snapped to the walkable surface.
    ///
    /// # Complexity
    /// O(S log S) worst case (Dijkstra stopped at the target).
    pub fn distance(&self, a: &Point3<f64>, b: &Point3<f64>) -> Result<f64, NavError> {
        let (sa, sb) = match self.locate_pair(a, b)? {
            Pair::Same => return Ok((a - b).norm()),
            Pair::Apart => return Ok(f64::INFINITY),
            Pair::Connected(sa, sb) => (sa, sb),
        };
        let (ca, cb) = (self.span_center(sa), self.span_center(sb));
        let (dist, _) = dijkstra(self, &[(sa, 0.0)], Some(sb), None);
        Ok((a - ca).norm() + dist[sb as usize] + (b - cb).norm())
    }

    /// Shortest path from `a` to `b` as a polyline of span centres (starting
    /// with `a`, ending with `b`), or `None` when unreachable.
    ///
    /// # Errors
    /// [`NavError`] when either point cannot be snapped to the walkable surface.
    ///
    /// # Complexity
    /// O(S log S) worst case.
    pub fn path(
        &self,
        a: &Point3<f64>,
        b: &Point3<f64>,
    ) -> Result<Option<Vec<Point3<f64>>>, NavError> {
        let (sa, sb) = match self.locate_pair(a, b)? {
            Pair::Same => return Ok(Some(vec![*a, *b])),
            Pair::Apart => return Ok(None),
            Pair::Connected(sa, sb) => (sa, sb),
        };
        let (dist, parent) = dijkstra(self, &[(sa, 0.0)], Some(sb), None);
        if !dist[sb as usize].is_finite() {
            return Ok(None);
        }
        let mut rev = vec![*b];
        let mut s = sb;
        while s != sa {
            rev.push(self.span_center(s));
            s = parent[s as usize];
        }
        rev.push(self.span_center(sa));
        rev.push(*a);
        rev.reverse();
        Ok(Some(rev))
    }

    /// True when some walkable path connects `a` and `b`.
    ///
    /// # Errors
    /// [`NavError`] when either point cannot be snapped.
    pub fn connected(&self, a: &Point3<f64>, b: &Point3<f64>) -> Result<bool, NavError> {
        Ok(!matches!(self.locate_pair(a, b)?, Pair::Apart))
    }

    /// Snaps `a` and `b` to spans and classifies the pair.
    fn locate_pair(&self, a: &Point3<f64>, b: &Point3<f64>) -> Result<Pair, NavError> {
        let (sa, sb) = (locate(self, a)?, locate(self, b)?);
        Ok(if sa == sb {
            Pair::Same
        } else if self.spans()[sa as usize].region != self.spans()[sb as usize].region {
            Pair::Apart
        } else {
            Pair::Connected(sa, sb)
        })
    }
}

/// Two query points snapped to spans.
enum Pair {
    /// Both over the same span.
    Same,
    /// On spans of different regions (islands).
    Apart,
    /// On different spans of one region.
    Connected(SpanId, SpanId),
}
