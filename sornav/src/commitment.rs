//! Commitment to the frontier being explored: hysteresis against a route
//! whose first frontier flips from step to step.
//!
//! The route is re-planned at every step on a map that changed since the
//! last one. Two effects make its first frontier flip although nothing
//! important changed, and every flip costs a platform with 30-degree turns
//! several actions of turning back and forth:
//!
//! * **Re-identification**: a frontier the robot approaches changes with
//!   every frame (its cells are observed), so it gets a new id and the
//!   active mission's frontier "vanishes". Its *successor* is the
//!   admissible frontier whose viewpoint is nearest to the vanished
//!   frontier's viewpoint, on the same floor, within
//!   [`CommitmentConfig::successor_radius_m`].
//! * **Near ties**: two frontiers of similar cost swap places in the TSP
//!   (or in the nearest-frontier order) as costs change by centimetres.
//!
//! [`committed_frontier`] keeps the frontier being explored (or its
//! successor) unless the route's first frontier is better by more than
//! [`CommitmentConfig::switch_margin_m`]: for a TSP route, the extra cost
//! of the route that visits the committed frontier first (inserted before
//! the route's first frontier and removed from its later place); for a
//! ranking (nearest, semantic), the extra first-leg cost. Paths costs are
//! G_F's (over stairs too). A margin of 0 gives the route's choice; ties
//! keep the committed frontier.

use std::collections::BTreeSet;

use nalgebra::Point3;
use serde::{Deserialize, Serialize};
use sornav_frontier_graph::{FrontierGraph, FrontierId, NodeId};

use crate::ordering::{self, OrderingKind, Route};

/// Settings of the exploration commitment.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CommitmentConfig {
    /// The route's first frontier replaces the one being explored only
    /// when the route through the latter is longer by more than this (m).
    /// Default 1.5: six forward moves, the cost of turning about (six
    /// 30-degree turns). 0 follows the route at every step.
    pub switch_margin_m: f64,
    /// A vanished frontier's successor is the admissible frontier whose
    /// viewpoint is nearest to its viewpoint within this horizontal
    /// distance (m), on the same floor (default 1.0; 0 disables).
    pub successor_radius_m: f64,
    /// Largest height difference (m) between a frontier's viewpoint and
    /// its successor's (default 0.5: same floor, or the next steps of a
    /// stair).
    pub successor_height_m: f64,
}

impl Default for CommitmentConfig {
    fn default() -> Self {
        Self {
            switch_margin_m: 1.5,
            successor_radius_m: 1.0,
            successor_height_m: 0.5,
        }
    }
}

impl CommitmentConfig {
    /// Whether every value is finite and non-negative.
    pub fn is_valid(&self) -> bool {
        [
            self.switch_margin_m,
            self.successor_radius_m,
            self.successor_height_m,
        ]
        .iter()
        .all(|v| v.is_finite() && *v >= 0.0)
    }
}

/// The successor of a vanished frontier whose viewpoint was `viewpoint`:
/// the admissible (not `excluded`, reachable from the robot) frontier of
/// `graph` with the viewpoint nearest to it horizontally, within
/// `successor_radius_m` and `successor_height_m`; ties by id.
///
/// # Complexity
/// O(n) for n frontiers.
pub(crate) fn successor(
    graph: &FrontierGraph,
    excluded: &BTreeSet<FrontierId>,
    viewpoint: &Point3<f64>,
    config: &CommitmentConfig,
) -> Option<FrontierId> {
    graph
        .nodes()
        .filter(|f| !excluded.contains(&f.id))
        .filter(|f| {
            graph
                .cost(NodeId::Robot, NodeId::Frontier(f.id))
                .is_some_and(f64::is_finite)
        })
        .filter_map(|f| {
            let v = f.viewpoint3();
            let d = (v.xy() - viewpoint.xy()).norm();
            (d <= config.successor_radius_m
                && (v.z - viewpoint.z).abs() <= config.successor_height_m)
                .then_some((d, f.id))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
        .map(|(_, id)| id)
}

/// G_F's path cost between two nodes; through the robot when no direct
/// edge exists (both reachable from it: an executable upper bound), as the
/// TSP's matrix does. `None` when one of them is unreachable.
fn cost(graph: &FrontierGraph, a: NodeId, b: NodeId) -> Option<f64> {
    if a == b {
        return Some(0.0);
    }
    let from_robot = |n: NodeId| {
        if n == NodeId::Robot {
            Some(0.0)
        } else {
            graph.cost(NodeId::Robot, n).filter(|c| c.is_finite())
        }
    };
    Some(ordering::pair_cost(
        graph,
        a,
        b,
        from_robot(a)?,
        from_robot(b)?,
    ))
}

/// The extra cost of visiting `committed` before the route's first
/// frontier: for a TSP route (`route.ordering == OrderingKind::Tsp`; its tour is
/// `route.first` then `route.order`) the insertion of `committed` at the
/// front minus the saving of removing it from its later place in the
/// tour; for a ranking the difference of the first legs.
/// `None` when `committed` is unreachable.
///
/// # Complexity
/// O(n) for a route of n frontiers (one pass to find `committed`).
pub(crate) fn detour(graph: &FrontierGraph, route: &Route, committed: FrontierId) -> Option<f64> {
    let robot = NodeId::Robot;
    let c = NodeId::Frontier(committed);
    let first = NodeId::Frontier(route.first);
    let to_c = cost(graph, robot, c)?;
    let to_first = cost(graph, robot, first)?;
    if route.ordering != OrderingKind::Tsp {
        return Some(to_c - to_first);
    }
    let insertion = to_c + cost(graph, c, first)? - to_first;
    // The route's tour: its first frontier (the replacement rule may have
    // swapped it in), then the visiting order.
    let tour: Vec<FrontierId> = std::iter::once(route.first)
        .chain(route.order.iter().copied().filter(|&f| f != route.first))
        .collect();
    let saving = match tour.iter().position(|&f| f == committed) {
        // Its later place: between `prev` and `next` (or at the end).
        Some(i) if i > 0 => {
            let prev = NodeId::Frontier(tour[i - 1]);
            let via = cost(graph, prev, c)?;
            match tour.get(i + 1) {
                Some(&next) => {
                    let next = NodeId::Frontier(next);
                    via + cost(graph, c, next)? - cost(graph, prev, next)?
                }
                None => via,
            }
        }
        _ => 0.0,
    };
    Some(insertion - saving)
}

/// The frontier to explore now: `committed` (the frontier being explored,
/// or its successor) when it is admissible and the route through it is
/// longer than `route` by at most `switch_margin_m` ([`detour`]);
/// otherwise the route's first frontier.
///
/// # Complexity
/// O(n) for a route of n frontiers.
pub(crate) fn committed_frontier(
    graph: &FrontierGraph,
    excluded: &BTreeSet<FrontierId>,
    route: &Route,
    committed: Option<FrontierId>,
    config: &CommitmentConfig,
) -> FrontierId {
    let Some(c) = committed.filter(|&c| c != route.first) else {
        return route.first;
    };
    if excluded.contains(&c) || graph.frontier(c).is_none() {
        return route.first;
    }
    match detour(graph, route, c) {
        Some(d) if d <= config.switch_margin_m => c,
        _ => route.first,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::FrontierOrdering;
    use crate::ordering::tests::{gaps, input, open_path_cost, room_graph};
    use crate::ordering::{self};
    use nalgebra::Point2;
    use proptest::prelude::*;
    use sornav_tsp::RecedingHorizon;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// The detour equals the brute-force cost difference of the two
        /// tours (TSP) or first legs (nearest); the commitment keeps the
        /// committed frontier exactly when the detour is within the margin;
        /// margin 0 never keeps a worse one.
        #[test]
        fn commitment_matches_the_tour_costs(
            a in 2.0f64..4.0,
            b in 1.5f64..3.0,
            gaps in gaps(),
            margin in 0.0f64..4.0,
            tsp in any::<bool>(),
        ) {
            let mut map = room_graph(a, b, &gaps);
            let graph = map.frontier_graph(&Point2::origin()).unwrap();
            let excluded = BTreeSet::new();
            let objects = [];
            let ordering = if tsp { FrontierOrdering::Tsp } else { FrontierOrdering::Nearest };
            let mut previous = None;
            let Some(route) = ordering::choose(&ordering, &RecedingHorizon::default(), &input(graph, &excluded, &objects), &mut previous).unwrap() else {
                return Ok(());
            };
            let config = CommitmentConfig { switch_margin_m: margin, ..CommitmentConfig::default() };
            prop_assert_eq!(committed_frontier(graph, &excluded, &route, None, &config), route.first);
            let tour: Vec<FrontierId> = std::iter::once(route.first)
                .chain(route.order.iter().copied().filter(|&f| f != route.first))
                .collect();
            for &c in &route.order {
                let d = detour(graph, &route, c).unwrap();
                let reference = if tsp {
                    let mut moved = vec![c];
                    moved.extend(tour.iter().copied().filter(|&f| f != c));
                    open_path_cost(graph, &moved) - open_path_cost(graph, &tour)
                } else {
                    open_path_cost(graph, &[c]) - open_path_cost(graph, &[route.first])
                };
                prop_assert!((d - reference).abs() < 1e-9, "{} vs {}", d, reference);
                let kept = committed_frontier(graph, &excluded, &route, Some(c), &config);
                prop_assert_eq!(kept, if d <= margin { c } else { route.first });
                let strict = CommitmentConfig { switch_margin_m: 0.0, ..config };
                let kept0 = committed_frontier(graph, &excluded, &route, Some(c), &strict);
                prop_assert!(kept0 == route.first || d <= 0.0);
                // An excluded frontier is never kept.
                let mut ex = excluded.clone();
                ex.insert(c);
                if c != route.first {
                    prop_assert_eq!(committed_frontier(graph, &ex, &route, Some(c), &config), route.first);
                }
            }
        }

        /// The successor is the brute-force nearest admissible viewpoint
        /// within the radius and height band.
        #[test]
        fn successor_is_the_nearest_admissible_viewpoint(
            gaps in gaps(),
            x in -4.0f64..4.0,
            y in -4.0f64..4.0,
            z in -0.8f64..0.8,
            radius in 0.0f64..3.0,
            exclude_first in any::<bool>(),
        ) {
            let mut map = room_graph(3.0, 2.0, &gaps);
            let graph = map.frontier_graph(&Point2::origin()).unwrap();
            let mut excluded = BTreeSet::new();
            if exclude_first && let Some(f) = graph.nodes().next() {
                excluded.insert(f.id);
            }
            let config = CommitmentConfig { successor_radius_m: radius, ..CommitmentConfig::default() };
            let at = Point3::new(x, y, z);
            let mut best: Option<(f64, FrontierId)> = None;
            for f in graph.nodes() {
                if excluded.contains(&f.id) || graph.cost(NodeId::Robot, NodeId::Frontier(f.id)).is_none() {
                    continue;
                }
                let v = f.viewpoint3();
                let d = ((v.x - x).powi(2) + (v.y - y).powi(2)).sqrt();
                if d <= radius && (v.z - z).abs() <= config.successor_height_m
                    && best.is_none_or(|(bd, bid)| d < bd || (d == bd && f.id < bid))
                {
                    best = Some((d, f.id));
                }
            }
            prop_assert_eq!(successor(graph, &excluded, &at, &config), best.map(|b| b.1));
        }
    }

    #[test]
    fn config_validation() {
        assert!(CommitmentConfig::default().is_valid());
        for bad in [f64::NAN, -1.0, f64::INFINITY] {
            assert!(
                !CommitmentConfig {
                    switch_margin_m: bad,
                    ..CommitmentConfig::default()
                }
                .is_valid()
            );
            assert!(
                !CommitmentConfig {
                    successor_radius_m: bad,
                    ..CommitmentConfig::default()
                }
                .is_valid()
            );
            assert!(
                !CommitmentConfig {
                    successor_height_m: bad,
                    ..CommitmentConfig::default()
                }
                .is_valid()
            );
        }
        let mut config = crate::AgentConfig::default();
        config.commitment.switch_margin_m = f64::NAN;
        assert!(config.validate().is_err());
    }
}
