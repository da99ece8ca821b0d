//! Receding-horizon frontier ordering with the nearby-frontier replacement
//! rule.
//!
//! SOR-Nav re-solves the global visiting order whenever observations update
//! the frontier graph and executes only the first frontier. To avoid
//! walking past a frontier right next to the robot, a nearby frontier
//! replaces the planned first choice when it lies within `radius` (5 m) of
//! the robot and the first planned leg is more than `leg_ratio` (2x) as
//! long as the leg to that nearby frontier. "Within" is measured by path
//! cost (the cost matrix), so a frontier one floor up, right above the
//! robot, is not nearby.

use std::collections::HashMap;
use std::hash::Hash;

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::construct::cheapest_insertion;
use crate::error::TspError;
use crate::latency::min_weighted_latency_path;
use crate::matrix::CostMatrix;
use crate::solver::{Method, Solver, SolverConfig, Tour};

/// The replacement rule's two parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ReplacementRule {
    /// A frontier is *nearby* when its path cost from the robot (the cost
    /// matrix's robot row, never a straight line) is at most this (metres
    /// of path when costs are path lengths). Default 5.0.
    pub radius: f64,
    /// The nearby frontier replaces the planned first one when the planned
    /// first leg costs more than `leg_ratio` times its own leg. Default 2.0.
    pub leg_ratio: f64,
}

impl Default for ReplacementRule {
    fn default() -> Self {
        Self {
            radius: 5.0,
            leg_ratio: 2.0,
        }
    }
}

impl ReplacementRule {
    /// Whether a frontier at `distance` from the robot, reached with cost
    /// `nearby_leg`, replaces a planned first frontier reached with cost
    /// `first_leg`: `distance <= radius && first_leg > leg_ratio *
    /// nearby_leg`. [`RecedingHorizon::plan`] measures `distance` as the
    /// path cost from the robot (`nearby_leg` itself), never as a straight
    /// line: a frontier 2 m away through a floor or a wall is not nearby.
    ///
    /// # Examples
    /// ```
    /// use sornav_tsp::ReplacementRule;
    /// let rule = ReplacementRule::default();
    /// assert!(rule.replaces(12.0, 4.0, 5.0));   // 12 > 2 x 5
    /// assert!(!rule.replaces(10.0, 4.0, 5.0));  // not more than twice
    /// assert!(!rule.replaces(12.0, 6.0, 5.0));  // not within 5 m
    /// ```
    pub fn replaces(&self, first_leg: f64, distance: f64, nearby_leg: f64) -> bool {
        distance <= self.radius && first_leg > self.leg_ratio * nearby_leg
    }

    /// Checks that both parameters are finite and non-negative.
    ///
    /// # Errors
    /// [`TspError::InvalidConfig`].
    pub fn validate(&self) -> Result<(), TspError> {
        for (name, v) in [("radius", self.radius), ("leg_ratio", self.leg_ratio)] {
            if !v.is_finite() || v < 0.0 {
                return Err(TspError::InvalidConfig(format!(
                    "{name} = {v} must be finite and >= 0"
                )));
            }
        }
        Ok(())
    }
}

/// A frontier as the planner sees it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HorizonFrontier<Id> {
    /// Stable identifier (for example frontier-graph's frontier id).
    pub id: Id,
    /// Position (metres). Informational (reports, drawings): the planner
    /// reads only the cost matrix, the replacement rule included.
    pub position: Point3<f64>,
    /// How much the frontier is worth reaching early: read only by
    /// [`RouteObjective::Latency`], where each arrival cost counts this
    /// many times (for example the unknown area the frontier opens, or 1
    /// for every frontier alike). Finite and `>= 0`; default 1.
    #[serde(default = "unit_weight")]
    pub weight: f64,
}

fn unit_weight() -> f64 {
    1.0
}

/// One planning request: robot, frontiers and the costs between them.
///
/// `costs` is square with node 0 = the robot, node `i + 1` = `frontiers[i]`,
/// and, when `home` is true, a last node = the home the route must end at
/// (a closed route). Costs are typically executable path lengths.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HorizonProblem<Id> {
    /// Robot position.
    pub robot: Point3<f64>,
    /// Frontiers to visit.
    pub frontiers: Vec<HorizonFrontier<Id>>,
    /// Cost matrix (see the type docs for the node layout).
    pub costs: CostMatrix,
    /// Whether the route returns home (the last matrix node).
    pub home: bool,
}

/// The planner's answer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HorizonPlan<Id> {
    /// Frontier to execute now.
    pub first: Id,
    /// Whether `first` is a nearby frontier that replaced the route's first.
    pub replaced: bool,
    /// The full visiting order found by the solver (before replacement).
    pub order: Vec<Id>,
    /// Cost of `order` from the robot (including the return home if any).
    pub route_cost: f64,
    /// How the route was solved.
    pub method: Method,
}

/// Receding-horizon planner: solve the open path from the robot through all
/// frontiers (ending at home when configured), execute the first frontier,
/// apply the [`ReplacementRule`].
///
/// The previous plan, when given, warm-starts the solver: its order
/// restricted to the frontiers that still exist, with new frontiers added
/// by cheapest insertion (the solver keeps the better of that and nearest
/// neighbour).
///
/// # Examples
/// ```
/// use nalgebra::Point3;
/// use sornav_tsp::{CostMatrix, HorizonFrontier, HorizonProblem, RecedingHorizon};
/// // Robot at the origin, frontiers on the x axis at 3, -10, -11 m.
/// let xs = [0.0, 3.0, -10.0, -11.0];
/// let problem = HorizonProblem {
///     robot: Point3::origin(),
///     frontiers: (1..4)
///         .map(|i| HorizonFrontier { id: i as u32, position: Point3::new(xs[i], 0.0, 0.0), weight: 1.0 })
///         .collect(),
///     costs: CostMatrix::from_fn(4, |i, j| (xs[i] - xs[j]).abs())?,
///     home: false,
/// };
/// let plan = RecedingHorizon::default().plan(&problem, None)?.expect("frontiers exist");
/// assert_eq!(plan.order, vec![1, 2, 3]); // 3 + 13 + 1 = 17 beats 10 + 1 + 14 = 25
/// assert_eq!(plan.first, 1);
/// assert!(!plan.replaced);
/// # Ok::<(), sornav_tsp::TspError>(())
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RecedingHorizon {
    /// The replacement rule.
    pub rule: ReplacementRule,
    /// Solver settings.
    pub solver: SolverConfig,
    /// What the route minimises (default: its length, the paper's TSP).
    pub objective: RouteObjective,
}

/// What the receding-horizon route minimises.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RouteObjective {
    /// The route's length: the open-path ATSP (SOR-Nav's and FUEL's
    /// coverage ordering).
    #[default]
    PathLength,
    /// The sum of the costs at which each frontier is reached
    /// ([`min_latency_path`](crate::min_latency_path)): the expected cost
    /// of reaching the frontier the target is behind, each frontier being
    /// equally likely. Needs a free end (`home = false`).
    Latency,
}

impl RecedingHorizon {
    /// Plans the route and picks the frontier to execute; `Ok(None)` when
    /// there are no frontiers.
    ///
    /// The nearby candidate is the frontier with the cheapest leg from the
    /// robot among those within `rule.radius` (ties: earlier in
    /// `frontiers`); it replaces the route's first frontier when
    /// [`ReplacementRule::replaces`] holds.
    ///
    /// # Errors
    /// [`TspError::InconsistentProblem`] when the matrix size does not match
    /// the frontiers (and `home`), ids repeat or a position is not finite;
    /// [`TspError::InvalidConfig`] for bad settings.
    ///
    /// # Complexity
    /// That of [`Solver::open_path`] on `frontiers.len() + 1 (+1)` nodes.
    pub fn plan<Id: Copy + Eq + Hash>(
        &self,
        problem: &HorizonProblem<Id>,
        previous: Option<&HorizonPlan<Id>>,
    ) -> Result<Option<HorizonPlan<Id>>, TspError> {
        self.rule.validate()?;
        let solver = Solver::new(self.solver.clone())?;
        let k = problem.frontiers.len();
        let n = k + 1 + usize::from(problem.home);
        if problem.costs.len() != n {
            return Err(TspError::InconsistentProblem(format!(
                "{k} frontiers{} need a {n}x{n} matrix, got {}",
                if problem.home { " and home" } else { "" },
                problem.costs.len()
            )));
        }
        let mut index: HashMap<Id, usize> = HashMap::with_capacity(k);
        for (i, f) in problem.frontiers.iter().enumerate() {
            if index.insert(f.id, i + 1).is_some() {
                return Err(TspError::InconsistentProblem(format!(
                    "frontier {i} repeats an id"
                )));
            }
            let p = f.position;
            if !(f.weight.is_finite() && f.weight >= 0.0) {
                return Err(TspError::InconsistentProblem(format!(
                    "frontier {i} has weight {}, not finite and >= 0",
                    f.weight
                )));
            }
            if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
                return Err(TspError::InconsistentProblem(format!(
                    "frontier {i} has a non-finite position"
                )));
            }
        }
        let r = problem.robot;
        if !(r.x.is_finite() && r.y.is_finite() && r.z.is_finite()) {
            return Err(TspError::InconsistentProblem(
                "the robot position is not finite".into(),
            ));
        }
        if k == 0 {
            return Ok(None);
        }
        let end = problem.home.then_some(n - 1);
        let initial = previous.map(|prev| self.warm_start(problem, prev, &index, end));
        let tour = match (self.objective, &initial) {
            (RouteObjective::Latency, _) if problem.home => {
                return Err(TspError::InvalidConfig(
                    "the latency objective needs a free end (home = false)".into(),
                ));
            }
            (RouteObjective::Latency, initial) => {
                let weights: Vec<f64> = std::iter::once(0.0)
                    .chain(problem.frontiers.iter().map(|f| f.weight))
                    .collect();
                let path = min_weighted_latency_path(
                    &problem.costs,
                    0,
                    &weights,
                    initial.as_deref(),
                    self.solver.exact_max_nodes,
                )?;
                Tour {
                    order: path.order,
                    cost: path.cost,
                    closed: false,
                    method: path.method,
                }
            }
            (RouteObjective::PathLength, Some(initial)) => {
                solver.open_path_from(&problem.costs, 0, end, initial)?
            }
            (RouteObjective::PathLength, None) => solver.open_path(&problem.costs, 0, end)?,
        };
        let order: Vec<Id> = tour
            .order
            .iter()
            .filter(|&&v| v != 0 && Some(v) != end)
            .map(|&v| problem.frontiers[v - 1].id)
            .collect();
        let planned = tour.order[1];
        let first_leg = problem.costs.cost(0, planned);
        // "Nearby" by path cost: a frontier behind a wall or on another
        // floor is not near, however close in a straight line.
        let distance = |v: usize| problem.costs.cost(0, v);
        let nearby = (1..=k)
            .filter(|&v| distance(v) <= self.rule.radius)
            .min_by(|&a, &b| {
                problem
                    .costs
                    .cost(0, a)
                    .total_cmp(&problem.costs.cost(0, b))
                    .then(a.cmp(&b))
            });
        let (first, replaced) = match nearby {
            Some(v)
                if v != planned
                    && self
                        .rule
                        .replaces(first_leg, distance(v), problem.costs.cost(0, v)) =>
            {
                (v, true)
            }
            _ => (planned, false),
        };
        Ok(Some(HorizonPlan {
            first: problem.frontiers[first - 1].id,
            replaced,
            order,
            route_cost: tour.cost,
            method: tour.method,
        }))
    }

    /// The previous order restricted to current frontiers, new ones inserted
    /// at their cheapest place; as matrix indices, robot first (home last).
    fn warm_start<Id: Copy + Eq + Hash>(
        &self,
        problem: &HorizonProblem<Id>,
        prev: &HorizonPlan<Id>,
        index: &HashMap<Id, usize>,
        end: Option<usize>,
    ) -> Vec<usize> {
        let n = problem.costs.len();
        let mut seen = vec![false; n];
        let mut order = vec![0];
        seen[0] = true;
        for id in &prev.order {
            if let Some(&v) = index.get(id)
                && !std::mem::replace(&mut seen[v], true)
            {
                order.push(v);
            }
        }
        if let Some(e) = end {
            order.push(e);
            seen[e] = true;
        }
        let missing: Vec<usize> = (0..n).filter(|&v| !seen[v]).collect();
        // Insert on the open path: never before the robot or after home.
        cheapest_insertion(
            problem.costs.as_slice(),
            n,
            &mut order,
            &missing,
            end.is_some(),
        );
        order
    }
}
