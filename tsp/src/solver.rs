//! The solver facade: open paths (fixed start, optional fixed end) and
//! closed tours, exact for small instances and heuristic above.

use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use crate::construct::nearest_neighbour;
use crate::error::TspError;
use crate::held_karp::{self, HELD_KARP_MAX_NODES};
use crate::local_search::{IlsParams, iterated_local_search};
use crate::matrix::CostMatrix;

/// Solver settings. Every field has a default (see [`SolverConfig::default`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SolverConfig {
    /// Closed instances (after the open-path reduction, see [`Solver`]) with
    /// at most this many nodes are solved exactly by Held-Karp. At most
    /// [`HELD_KARP_MAX_NODES`]. Default 13.
    pub exact_max_nodes: usize,
    /// Candidate-list size of the local search (nearest successors and
    /// predecessors per node). At least 1. Default 10.
    pub candidates: usize,
    /// Kicks of the iterated local search per node of the instance. Default 12.
    pub kicks_per_node: usize,
    /// Optional wall-time budget of the iterated local search (the initial
    /// descent always completes). When it binds, results depend on the
    /// machine's speed. Default `None`.
    pub time_budget: Option<Duration>,
    /// Seed of the kicks: equal inputs and seeds give equal tours. Default 0.
    pub seed: u64,
}

impl Default for SolverConfig {
    fn default() -> Self {
        Self {
            exact_max_nodes: 13,
            candidates: 10,
            kicks_per_node: 12,
            time_budget: None,
            seed: 0,
        }
    }
}

impl SolverConfig {
    /// Checks the documented ranges.
    ///
    /// # Errors
    /// [`TspError::InvalidConfig`] naming the offending field.
    pub fn validate(&self) -> Result<(), TspError> {
        if self.exact_max_nodes > HELD_KARP_MAX_NODES {
            return Err(TspError::InvalidConfig(format!(
                "exact_max_nodes = {} exceeds {HELD_KARP_MAX_NODES}",
                self.exact_max_nodes
            )));
        }
        if self.candidates == 0 {
            return Err(TspError::InvalidConfig(
                "candidates must be at least 1".into(),
            ));
        }
        Ok(())
    }
}

/// How a tour was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Method {
    /// Held-Karp: the tour is optimal.
    Exact,
    /// Nearest neighbour followed by iterated local search.
    Heuristic,
    /// Nearest-neighbour construction only (the baseline).
    NearestNeighbour,
}

/// A solution: an open path or a closed tour over the nodes of a matrix.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Tour {
    /// Every node exactly once, the fixed start first (and, for an open
    /// path with a fixed end, that end last).
    pub order: Vec<usize>,
    /// Cost on the input matrix: the sum of the arcs along `order`, plus
    /// the arc back to the start when `closed`.
    pub cost: f64,
    /// Whether the tour returns to its start.
    pub closed: bool,
    /// How it was computed.
    pub method: Method,
}

/// Which route is asked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Route {
    Closed { start: usize },
    Open { start: usize, end: Option<usize> },
}

impl Route {
    fn new(start: usize, end: Option<usize>, closed: bool) -> Result<Self, TspError> {
        match (closed, end) {
            (true, None) => Ok(Route::Closed { start }),
            (true, Some(_)) => Err(TspError::InvalidConfig(
                "a closed tour has no fixed end".into(),
            )),
            (false, end) => Ok(Route::Open { start, end }),
        }
    }
}

/// A route reduced to a closed tour on `r` nodes whose node 0 is the start.
///
/// * closed tour: the matrix restricted and relabelled;
/// * open path, free end: every arc into the start costs 0, so a tour's cost
///   is the cost of the path it contains;
/// * open path, fixed end `e`: `e` is merged into the start (arcs into the
///   merged node are the arcs into `e`), so tours correspond one-to-one with
///   paths `start .. e`.
struct Reduced {
    r: usize,
    c: Vec<f64>,
    /// Reduced index -> input node.
    nodes: Vec<usize>,
    route: Route,
}

impl Reduced {
    fn new(m: &CostMatrix, route: Route) -> Result<Self, TspError> {
        let n = m.len();
        let check = |v: usize| {
            if v < n {
                Ok(())
            } else {
                Err(TspError::NodeOutOfRange { node: v, n })
            }
        };
        let (start, end) = match route {
            Route::Closed { start } => (start, None),
            Route::Open { start, end } => (start, end),
        };
        check(start)?;
        if let Some(e) = end {
            check(e)?;
            if e == start {
                return Err(TspError::EndEqualsStart(e));
            }
        }
        let mut nodes = Vec::with_capacity(n);
        nodes.push(start);
        nodes.extend((0..n).filter(|&v| v != start && Some(v) != end));
        let r = nodes.len();
        let mut c = Vec::with_capacity(r * r);
        for &i in &nodes {
            for (jr, &j) in nodes.iter().enumerate() {
                let v = match (jr, route) {
                    (0, Route::Open { end: None, .. }) => 0.0,
                    (0, Route::Open { end: Some(e), .. }) => m.cost(i, e),
                    _ => m.cost(i, j),
                };
                c.push(v);
            }
        }
        Ok(Self { r, c, nodes, route })
    }

    /// Maps a reduced tour back to an input-node route and prices it.
    fn finish(&self, m: &CostMatrix, mut order: Vec<usize>, method: Method) -> Tour {
        if let Some(z) = order.iter().position(|&v| v == 0) {
            order.rotate_left(z);
        }
        let mut out: Vec<usize> = order.into_iter().map(|v| self.nodes[v]).collect();
        let closed = matches!(self.route, Route::Closed { .. });
        if let Route::Open { end: Some(e), .. } = self.route {
            out.push(e);
        }
        // Indices come from `nodes`, all < n: pricing cannot fail.
        let cost = if closed {
            m.tour_cost(&out)
        } else {
            m.path_cost(&out)
        }
        .unwrap_or(f64::NAN);
        Tour {
            order: out,
            cost,
            closed,
            method,
        }
    }

    /// Maps a caller's order to a reduced tour (start first), validating it.
    fn map_initial(&self, n: usize, initial: &[usize]) -> Result<Vec<usize>, TspError> {
        let bad = |msg: String| Err(TspError::InvalidInitialOrder(msg));
        if initial.len() != n {
            return bad(format!("{} nodes given, the matrix has {n}", initial.len()));
        }
        let mut reduced_of = vec![usize::MAX; n];
        for (ri, &v) in self.nodes.iter().enumerate() {
            reduced_of[v] = ri;
        }
        let mut seen = vec![false; n];
        for &v in initial {
            if v >= n || std::mem::replace(&mut seen[v], true) {
                return bad(format!("node {v} is out of range or repeated"));
            }
        }
        let start = self.nodes[0];
        let body = match self.route {
            Route::Closed { .. } => {
                let z = initial.iter().position(|&v| v == start).unwrap_or(0);
                let mut rot = initial.to_vec();
                rot.rotate_left(z);
                rot
            }
            Route::Open { end, .. } => {
                if initial[0] != start {
                    return bad(format!("an open path must start at node {start}"));
                }
                match end {
                    Some(e) if initial[n - 1] != e => {
                        return bad(format!("the path must end at node {e}"));
                    }
                    Some(_) => initial[..n - 1].to_vec(),
                    None => initial.to_vec(),
                }
            }
        };
        Ok(body.into_iter().map(|v| reduced_of[v]).collect())
    }

    fn cost_of(&self, order: &[usize]) -> f64 {
        let r = self.r;
        (0..order.len())
            .map(|t| self.c[order[t] * r + order[(t + 1) % order.len()]])
            .sum()
    }
}

/// Solves open paths and closed tours on a [`CostMatrix`].
///
/// Every request is reduced to a closed (asymmetric) tour problem on `r`
/// nodes whose node 0 is the start:
/// * **open path, free end** (the frontier-ordering case): arcs into the
///   start cost nothing, so a tour prices exactly the path it contains
///   (`r = n`);
/// * **open path, fixed end** `e`: `e` is merged into the start, arcs into
///   the merged node being the arcs into `e` (`r = n - 1`);
/// * **closed tour**: unchanged (`r = n`).
///
/// Then `r <= exact_max_nodes` (or `r <= 3`) is solved exactly by Held-Karp;
/// larger instances by nearest neighbour followed by iterated local search
/// (2-opt, Or-opt and or-3opt moves on candidate lists, double-bridge kicks;
/// see the crate docs). The heuristic is deterministic for a given
/// [`SolverConfig::seed`] unless [`SolverConfig::time_budget`] binds, and it
/// never returns a tour worse than nearest neighbour.
///
/// # Complexity
/// Reduction `O(n^2)`; exact: `O(2^r r^2)`; heuristic: `O(n^2)` set-up
/// plus `kicks_per_node * n` kicks, each a local search around six nodes
/// (`O(k^2)` evaluations per node, `O(n)` per applied move).
///
/// # Examples
/// ```
/// use sornav_tsp::{CostMatrix, Solver, SolverConfig};
/// // Points on a line; the robot (node 0) is at x = 2.
/// let xs: [f64; 5] = [2.0, 0.0, 1.0, 5.0, 3.0];
/// let m = CostMatrix::from_fn(5, |i, j| (xs[i] - xs[j]).abs())?;
/// let solver = Solver::new(SolverConfig::default())?;
/// let path = solver.open_path(&m, 0, None)?;
/// assert_eq!(path.order, vec![0, 2, 1, 4, 3]); // 1 + 1 + 3 + 2
/// assert_eq!(path.cost, 7.0);
/// # Ok::<(), sornav_tsp::TspError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Solver {
    config: SolverConfig,
}

impl Solver {
    /// A solver with validated settings.
    ///
    /// # Errors
    /// [`TspError::InvalidConfig`].
    pub fn new(config: SolverConfig) -> Result<Self, TspError> {
        config.validate()?;
        Ok(Self { config })
    }

    /// The settings.
    pub fn config(&self) -> &SolverConfig {
        &self.config
    }

    /// Cheapest path found from `start` through every node, ending anywhere
    /// (`end = None`) or at `end`.
    ///
    /// # Errors
    /// [`TspError::NodeOutOfRange`], [`TspError::EndEqualsStart`].
    pub fn open_path(
        &self,
        m: &CostMatrix,
        start: usize,
        end: Option<usize>,
    ) -> Result<Tour, TspError> {
        self.solve(m, Route::Open { start, end }, None)
    }

    /// As [`Solver::open_path`], warm-started from `initial` (a permutation
    /// of all nodes starting at `start`, and ending at `end` if fixed), for
    /// example the previous plan. The search starts from the better of
    /// `initial` and nearest neighbour.
    ///
    /// # Errors
    /// As [`Solver::open_path`], and [`TspError::InvalidInitialOrder`].
    pub fn open_path_from(
        &self,
        m: &CostMatrix,
        start: usize,
        end: Option<usize>,
        initial: &[usize],
    ) -> Result<Tour, TspError> {
        self.solve(m, Route::Open { start, end }, Some(initial))
    }

    /// Cheapest closed tour found through every node, listed from `start`.
    ///
    /// # Errors
    /// [`TspError::NodeOutOfRange`].
    pub fn closed_tour(&self, m: &CostMatrix, start: usize) -> Result<Tour, TspError> {
        self.solve(m, Route::Closed { start }, None)
    }

    /// As [`Solver::closed_tour`], warm-started from the permutation `initial`.
    ///
    /// # Errors
    /// As [`Solver::closed_tour`], and [`TspError::InvalidInitialOrder`].
    pub fn closed_tour_from(
        &self,
        m: &CostMatrix,
        start: usize,
        initial: &[usize],
    ) -> Result<Tour, TspError> {
        self.solve(m, Route::Closed { start }, Some(initial))
    }

    fn solve(
        &self,
        m: &CostMatrix,
        route: Route,
        initial: Option<&[usize]>,
    ) -> Result<Tour, TspError> {
        let began = Instant::now();
        let red = Reduced::new(m, route)?;
        let hint = initial.map(|o| red.map_initial(m.len(), o)).transpose()?;
        let r = red.r;
        if r <= self.config.exact_max_nodes.max(3) {
            let (order, _) = held_karp::solve_closed(&red.c, r);
            return Ok(red.finish(m, order, Method::Exact));
        }
        let nn = nearest_neighbour(&red.c, r);
        let start_tour = match hint {
            Some(h) if red.cost_of(&h) < red.cost_of(&nn) => h,
            _ => nn,
        };
        let params = IlsParams {
            candidates: self.config.candidates,
            kicks: self.config.kicks_per_node.saturating_mul(r),
            deadline: self.config.time_budget.map(|b| began + b),
            seed: self.config.seed,
        };
        let order = iterated_local_search(&red.c, r, &start_tour, params);
        Ok(red.finish(m, order, Method::Heuristic))
    }
}

/// Exact optimum by Held-Karp regardless of [`SolverConfig::exact_max_nodes`]:
/// open path from `start` (ending at `end` if given), or the closed tour when
/// `closed` is true (then `end` must be `None`).
///
/// # Errors
/// [`TspError::TooLargeForExact`] when the reduced instance exceeds
/// [`HELD_KARP_MAX_NODES`] nodes; [`TspError::InvalidConfig`] for `closed`
/// with an `end`; otherwise as [`Solver::open_path`].
///
/// # Complexity
/// `O(2^n n^2)` time, `O(2^n n)` memory.
pub fn held_karp(
    m: &CostMatrix,
    start: usize,
    end: Option<usize>,
    closed: bool,
) -> Result<Tour, TspError> {
    let red = Reduced::new(m, Route::new(start, end, closed)?)?;
    if red.r > HELD_KARP_MAX_NODES {
        return Err(TspError::TooLargeForExact {
            n: red.r,
            max: HELD_KARP_MAX_NODES,
        });
    }
    let (order, _) = held_karp::solve_closed(&red.c, red.r);
    Ok(red.finish(m, order, Method::Exact))
}

/// The nearest-neighbour baseline: from `start`, always go to the cheapest
/// unvisited node (lowest index on ties); with a fixed `end`, that node is
/// visited last. Closed when `closed` is true (then `end` must be `None`).
///
/// # Errors
/// As [`held_karp`], without the size limit.
///
/// # Complexity
/// `O(n^2)`.
pub fn nearest_neighbour_route(
    m: &CostMatrix,
    start: usize,
    end: Option<usize>,
    closed: bool,
) -> Result<Tour, TspError> {
    let red = Reduced::new(m, Route::new(start, end, closed)?)?;
    let order = nearest_neighbour(&red.c, red.r);
    Ok(red.finish(m, order, Method::NearestNeighbour))
}
