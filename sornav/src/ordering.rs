//! Choosing the frontier to explore: SOR-Nav's receding-horizon TSP route,
//! the nearest frontier, or a greedy semantic ranking.

use std::collections::BTreeSet;

use nalgebra::{Point2, Point3};
use serde::{Deserialize, Serialize};
use sornav_cluster_graph::ObjectSummary;
use sornav_frontier_graph::{FrontierGraph, FrontierId, NodeId};
use sornav_supervisor::CooccurrencePrior;
use sornav_tsp::{CostMatrix, HorizonFrontier, HorizonPlan, HorizonProblem, RecedingHorizon};

use crate::config::{FrontierOrdering, SemanticRankingConfig};
use crate::error::AgentError;

/// Which ordering produced a [`Route`] (the kind of
/// [`FrontierOrdering`], without its parameters). Serialises as the
/// snake-case name and compares equal to it (`kind == "tsp"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OrderingKind {
    /// [`FrontierOrdering::Tsp`].
    Tsp,
    /// [`FrontierOrdering::Nearest`].
    Nearest,
    /// [`FrontierOrdering::SemanticRanking`].
    SemanticRanking,
}

snake_case_names!(OrderingKind {
    Tsp => "tsp",
    Nearest => "nearest",
    SemanticRanking => "semantic_ranking",
});

impl FrontierOrdering {
    /// The kind of this ordering.
    pub fn kind(&self) -> OrderingKind {
        match self {
            FrontierOrdering::Tsp => OrderingKind::Tsp,
            FrontierOrdering::Nearest => OrderingKind::Nearest,
            FrontierOrdering::SemanticRanking(_) => OrderingKind::SemanticRanking,
        }
    }
}

/// The exploration route of one step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Route {
    /// Which ordering produced it.
    pub ordering: OrderingKind,
    /// Frontiers in visiting order (TSP), or by decreasing preference.
    pub order: Vec<FrontierId>,
    /// The frontier to explore now: the ordering's first, or the frontier
    /// being explored when the commitment kept it (`committed`).
    pub first: FrontierId,
    /// Its executable viewpoint (on the floor it stands on).
    pub first_viewpoint: Point3<f64>,
    /// Whether the replacement rule swapped a nearby frontier in (TSP only).
    pub replaced: bool,
    /// Route cost from the robot (TSP), or the first leg's cost.
    pub cost: f64,
    /// Whether `first` is the frontier being explored (or its successor),
    /// kept instead of the ordering's first by the commitment's hysteresis
    /// ([`crate::CommitmentConfig`]).
    #[serde(default)]
    pub committed: bool,
}

/// A reachable, admissible frontier: id, viewpoint, centroid, robot cost
/// and its worth for the latency objective ([`frontier_weights`]).
struct Reachable {
    id: FrontierId,
    viewpoint: Point3<f64>,
    centroid: Point2<f64>,
    cost: f64,
    weight: f64,
}

fn reachable(graph: &FrontierGraph, excluded: &BTreeSet<FrontierId>) -> Vec<Reachable> {
    graph
        .nodes()
        .filter(|f| !excluded.contains(&f.id))
        .filter_map(|f| {
            let cost = graph.cost(NodeId::Robot, NodeId::Frontier(f.id))?;
            cost.is_finite().then_some(Reachable {
                id: f.id,
                viewpoint: f.viewpoint3(),
                centroid: f.centroid,
                cost,
                weight: f.cells.len() as f64,
            })
        })
        .collect()
}

/// The latency objective's weights: a frontier is worth the unknown area
/// it opens, taken proportional to its length (its cell count); the open
/// end of a stair opens a floor nobody has seen, taken as worth as much as
/// all the other reachable frontiers together (at least 1). Read only by
/// [`sornav_tsp::RouteObjective::Latency`]. `O(n)`.
fn frontier_weights(cands: &mut [Reachable]) {
    let is_stair = |c: &Reachable| c.id.0 >= sornav_frontier_graph::STAIR_FRONTIER_BASE;
    let floor: f64 = cands
        .iter()
        .filter(|c| !is_stair(c))
        .map(|c| c.weight)
        .sum();
    for c in cands.iter_mut().filter(|c| is_stair(c)) {
        c.weight = floor.max(1.0);
    }
}

/// G_F's cost between nodes `a` and `b` whose costs from the robot are
/// `ra` and `rb`: their edge, or (both reachable from the robot) through
/// the robot, an executable upper bound.
pub(crate) fn pair_cost(graph: &FrontierGraph, a: NodeId, b: NodeId, ra: f64, rb: f64) -> f64 {
    graph
        .cost(a, b)
        .filter(|c| c.is_finite())
        .unwrap_or(ra + rb)
}

/// Everything the orderings read.
pub(crate) struct OrderingInput<'a> {
    pub graph: &'a FrontierGraph,
    pub excluded: &'a BTreeSet<FrontierId>,
    pub target: &'a str,
    pub objects: &'a [ObjectSummary],
    pub n_min: usize,
    pub r_s: f64,
}

/// Chooses the next frontier with `ordering`; `Ok(None)` when no admissible
/// frontier is reachable. `previous` warm-starts the TSP and receives its
/// new plan.
///
/// # Complexity
/// TSP: that of `RecedingHorizon::plan` on `n + 1` nodes plus `O(n^2)` to
/// fill the matrix; nearest: `O(n)`; semantic ranking: `O(n M)` for `M`
/// objects plus the prior's posterior per frontier.
pub(crate) fn choose(
    ordering: &FrontierOrdering,
    horizon: &RecedingHorizon,
    input: &OrderingInput<'_>,
    previous: &mut Option<HorizonPlan<FrontierId>>,
) -> Result<Option<Route>, AgentError> {
    let mut cands = reachable(input.graph, input.excluded);
    if cands.is_empty() {
        *previous = None;
        return Ok(None);
    }
    let route = match ordering {
        FrontierOrdering::Tsp => {
            frontier_weights(&mut cands);
            tsp(horizon, input, &cands, previous)?
        }
        FrontierOrdering::Nearest => nearest(&cands),
        FrontierOrdering::SemanticRanking(weights) => semantic(weights, input, &cands),
    };
    Ok(route)
}

fn tsp(
    horizon: &RecedingHorizon,
    input: &OrderingInput<'_>,
    cands: &[Reachable],
    previous: &mut Option<HorizonPlan<FrontierId>>,
) -> Result<Option<Route>, AgentError> {
    let n = cands.len() + 1;
    let leg = |i: usize| if i == 0 { 0.0 } else { cands[i - 1].cost };
    let costs = CostMatrix::from_fn(n, |i, j| {
        if i == j {
            0.0
        } else if i == 0 || j == 0 {
            leg(i.max(j))
        } else {
            let (a, b) = (&cands[i - 1], &cands[j - 1]);
            pair_cost(
                input.graph,
                NodeId::Frontier(a.id),
                NodeId::Frontier(b.id),
                a.cost,
                b.cost,
            )
        }
    })?;
    let problem = HorizonProblem {
        robot: input.graph.robot().position3(),
        frontiers: cands
            .iter()
            .map(|c| HorizonFrontier {
                id: c.id,
                position: c.viewpoint,
                weight: c.weight,
            })
            .collect(),
        costs,
        home: false,
    };
    let plan = horizon.plan(&problem, previous.as_ref())?;
    let route = plan.as_ref().and_then(|p| {
        let first = cands.iter().find(|c| c.id == p.first)?;
        Some(Route {
            ordering: OrderingKind::Tsp,
            order: p.order.clone(),
            first: p.first,
            first_viewpoint: first.viewpoint,
            replaced: p.replaced,
            cost: p.route_cost,
            committed: false,
        })
    });
    *previous = plan;
    Ok(route)
}

/// Candidates by decreasing `scores` (aligned with `cands`), ties by id.
fn ranked(kind: OrderingKind, cands: &[Reachable], scores: &[f64]) -> Option<Route> {
    let mut idx: Vec<usize> = (0..cands.len()).collect();
    idx.sort_by(|&a, &b| {
        scores[b]
            .total_cmp(&scores[a])
            .then(cands[a].id.cmp(&cands[b].id))
    });
    let best = &cands[*idx.first()?];
    Some(Route {
        ordering: kind,
        order: idx.iter().map(|&i| cands[i].id).collect(),
        first: best.id,
        first_viewpoint: best.viewpoint,
        replaced: false,
        cost: best.cost,
        committed: false,
    })
}

fn nearest(cands: &[Reachable]) -> Option<Route> {
    let scores: Vec<f64> = cands.iter().map(|c| -c.cost).collect();
    ranked(OrderingKind::Nearest, cands, &scores)
}

/// `P(g | labels of the objects with support >= N_min within R_s of the
/// frontier centroid)`, 0 when the prior does not know the target.
fn relevance(input: &OrderingInput<'_>, centroid: &Point2<f64>) -> f64 {
    let labels = input
        .objects
        .iter()
        .filter(|o| o.support >= input.n_min)
        .filter(|o| (Point2::new(o.centre.x, o.centre.y) - centroid).norm() <= input.r_s)
        .map(|o| o.label.as_str());
    CooccurrencePrior::embedded()
        .posterior(input.target, labels)
        .map_or(0.0, |p| p.probability)
}

fn semantic(
    weights: &SemanticRankingConfig,
    input: &OrderingInput<'_>,
    cands: &[Reachable],
) -> Option<Route> {
    let scores: Vec<f64> = cands
        .iter()
        .map(|c| {
            weights.relevance_weight * relevance(input, &c.centroid)
                - weights.distance_weight * c.cost
        })
        .collect();
    ranked(OrderingKind::SemanticRanking, cands, &scores)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use proptest::prelude::*;
    use sornav_frontier_graph::{FrontierMap, FrontierMapConfig};

    /// A 360-degree scan of a `2a x 2b` room centred on the robot whose
    /// walls are open in the angular `gaps` (rays there run beyond range).
    pub(crate) fn room_graph(a: f64, b: f64, gaps: &[(f64, f64)]) -> FrontierMap {
        let mut map = FrontierMap::new(FrontierMapConfig::default()).unwrap();
        let origin = Point3::new(0.0, 0.0, 0.5);
        let mut points = Vec::new();
        for k in 0..720 {
            let t = f64::from(k) * std::f64::consts::PI / 360.0;
            let (c, s) = (t.cos(), t.sin());
            let tx = if c.abs() > 1e-9 {
                a / c.abs()
            } else {
                f64::INFINITY
            };
            let ty = if s.abs() > 1e-9 {
                b / s.abs()
            } else {
                f64::INFINITY
            };
            let open = gaps.iter().any(|&(lo, hi)| t >= lo && t <= hi);
            let r = if open { 8.0 } else { tx.min(ty) };
            points.push(Point3::new(r * c, r * s, 0.5));
        }
        map.update(&origin, &points).unwrap();
        map
    }

    pub(crate) fn gaps() -> impl Strategy<Value = Vec<(f64, f64)>> {
        proptest::collection::vec((0.0f64..6.0, 0.1f64..0.5), 1..5)
            .prop_map(|v| v.into_iter().map(|(lo, w)| (lo, lo + w)).collect())
    }

    pub(crate) fn input<'a>(
        graph: &'a FrontierGraph,
        excluded: &'a BTreeSet<FrontierId>,
        objects: &'a [ObjectSummary],
    ) -> OrderingInput<'a> {
        OrderingInput {
            graph,
            excluded,
            target: "toilet",
            objects,
            n_min: 10,
            r_s: 10.0,
        }
    }

    /// Cost of visiting `order` (frontier ids) from the robot, with the
    /// agent's matrix rule (graph edge, else through the robot).
    pub(crate) fn open_path_cost(graph: &FrontierGraph, order: &[FrontierId]) -> f64 {
        let robot = |f: FrontierId| graph.cost(NodeId::Robot, NodeId::Frontier(f)).unwrap();
        let mut cost = robot(order[0]);
        for w in order.windows(2) {
            cost += graph
                .cost(NodeId::Frontier(w[0]), NodeId::Frontier(w[1]))
                .unwrap_or(robot(w[0]) + robot(w[1]));
        }
        cost
    }

    fn permutations(items: &[FrontierId]) -> Vec<Vec<FrontierId>> {
        if items.len() <= 1 {
            return vec![items.to_vec()];
        }
        let mut out = Vec::new();
        for i in 0..items.len() {
            let mut rest = items.to_vec();
            let head = rest.remove(i);
            for mut tail in permutations(&rest) {
                tail.insert(0, head);
                out.push(tail);
            }
        }
        out
    }

    #[test]
    fn a_stair_frontier_weighs_as_much_as_the_floor() {
        let stair = FrontierId(sornav_frontier_graph::STAIR_FRONTIER_BASE + 7);
        let mk = |id: FrontierId, cells: f64| Reachable {
            id,
            viewpoint: Point3::origin(),
            centroid: Point2::origin(),
            cost: 1.0,
            weight: cells,
        };
        let mut cands = vec![
            mk(FrontierId(1), 12.0),
            mk(stair, 3.0),
            mk(FrontierId(2), 5.0),
        ];
        frontier_weights(&mut cands);
        let w: Vec<f64> = cands.iter().map(|c| c.weight).collect();
        assert_eq!(w, vec![12.0, 17.0, 5.0]);
        // Alone, a stair frontier still weighs 1.
        let mut only = vec![mk(stair, 0.0)];
        frontier_weights(&mut only);
        assert_eq!(only[0].weight, 1.0);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// Nearest: the brute-force cheapest reachable, admissible frontier.
        /// TSP: a permutation of the admissible frontiers whose cost equals
        /// the brute-force optimum over all orders (small instances).
        #[test]
        fn orderings_match_brute_force(
            a in 2.0f64..4.0,
            b in 1.5f64..3.0,
            gaps in gaps(),
            exclude_first in any::<bool>(),
        ) {
            let mut map = room_graph(a, b, &gaps);
            let graph = map.frontier_graph(&Point2::origin()).unwrap();
            let mut excluded = BTreeSet::new();
            if exclude_first && let Some(f) = graph.nodes().next() {
                excluded.insert(f.id);
            }
            let admissible: Vec<FrontierId> = graph
                .nodes()
                .map(|f| f.id)
                .filter(|id| !excluded.contains(id))
                .filter(|&id| graph.cost(NodeId::Robot, NodeId::Frontier(id)).is_some())
                .collect();
            let objects = [];
            let input = input(graph, &excluded, &objects);
            let mut previous = None;
            let nearest = choose(&FrontierOrdering::Nearest, &RecedingHorizon::default(), &input, &mut previous).unwrap();
            let brute = admissible.iter().copied().min_by(|&x, &y| {
                let c = |f| graph.cost(NodeId::Robot, NodeId::Frontier(f)).unwrap();
                c(x).total_cmp(&c(y)).then(x.cmp(&y))
            });
            prop_assert_eq!(nearest.as_ref().map(|r| r.first), brute);

            let tsp = choose(&FrontierOrdering::Tsp, &RecedingHorizon::default(), &input, &mut previous).unwrap();
            prop_assert_eq!(tsp.is_some(), !admissible.is_empty());
            if let Some(route) = tsp {
                let mut sorted = route.order.clone();
                sorted.sort();
                prop_assert_eq!(&sorted, &admissible);
                prop_assert!(!excluded.contains(&route.first));
                let cost = open_path_cost(graph, &route.order);
                prop_assert!((cost - route.cost).abs() < 1e-6, "{} vs {}", cost, route.cost);
                if admissible.len() <= 6 {
                    let best = permutations(&admissible)
                        .iter()
                        .map(|p| open_path_cost(graph, p))
                        .fold(f64::INFINITY, f64::min);
                    prop_assert!((route.cost - best).abs() < 1e-6, "{} vs optimum {}", route.cost, best);
                }
            }
        }

        /// Semantic ranking: the brute-force argmax of
        /// `w_r P(g | S_f) - w_d cost`; with `w_r = 0` it is the nearest.
        #[test]
        fn semantic_ranking_matches_brute_force(
            gaps in gaps(),
            sx in -3.0f64..3.0,
            sy in -3.0f64..3.0,
            w in 0.0f64..50.0,
        ) {
            let mut map = room_graph(3.0, 2.0, &gaps);
            let graph = map.frontier_graph(&Point2::origin()).unwrap();
            let excluded = BTreeSet::new();
            let objects = [
                ObjectSummary { level: None, label: "sink".into(), support: 50, centre: Point3::new(sx, sy, 0.8) },
                ObjectSummary { level: None, label: "bathtub".into(), support: 200, centre: Point3::new(sx + 0.5, sy, 0.3) },
                ObjectSummary { level: None, label: "bed".into(), support: 5, centre: Point3::new(-sx, -sy, 0.3) },
            ];
            let input = input(graph, &excluded, &objects);
            let weights = SemanticRankingConfig { relevance_weight: w, distance_weight: 1.0 };
            let mut previous = None;
            let route = choose(&FrontierOrdering::SemanticRanking(weights), &RecedingHorizon::default(), &input, &mut previous).unwrap();
            let prior = CooccurrencePrior::embedded();
            let mut best: Option<(f64, FrontierId)> = None;
            for f in graph.nodes() {
                let Some(cost) = graph.cost(NodeId::Robot, NodeId::Frontier(f.id)) else { continue };
                let near: Vec<&str> = objects
                    .iter()
                    .filter(|o| o.support >= 10 && (o.centre.xy() - f.centroid).norm() <= 10.0)
                    .map(|o| o.label.as_str())
                    .collect();
                let p = prior.posterior("toilet", near).map_or(0.0, |p| p.probability);
                let score = w * p - cost;
                if best.is_none_or(|(s, id)| score > s || (score == s && f.id < id)) {
                    best = Some((score, f.id));
                }
            }
            prop_assert_eq!(route.as_ref().map(|r| r.first), best.map(|b| b.1));
            let zero = SemanticRankingConfig { relevance_weight: 0.0, distance_weight: 1.0 };
            let greedy = choose(&FrontierOrdering::SemanticRanking(zero), &RecedingHorizon::default(), &input, &mut previous).unwrap();
            let nearest = choose(&FrontierOrdering::Nearest, &RecedingHorizon::default(), &input, &mut previous).unwrap();
            prop_assert_eq!(greedy.map(|r| r.first), nearest.map(|r| r.first));
        }
    }
}
