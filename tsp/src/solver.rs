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
    /// Kicks of the iterated local search per node, at least: on `r` nodes
    /// the search makes `max(kicks_per_node * r, ceil(kicks_per_pair * r^2))`
    /// kicks. At most [`MAX_KICKS_PER_NODE`] unless `time_budget` is set.
    /// Default 6.
    pub kicks_per_node: usize,
    /// Kicks per pair of nodes (see `kicks_per_node`): larger instances get
    /// more kicks per node, as they need them to reach the same quality.
    /// Finite and at least 0, and at most [`MAX_KICKS_PER_PAIR`] unless
    /// `time_budget` is set. Default 0.05 (from `r = 120` on, the budget is
    /// quadratic: 2000 kicks at `r = 200`).
    pub kicks_per_pair: f64,
    /// Optional wall-time budget of the iterated local search (the initial
    /// descent always completes). When it binds, results depend on the
    /// machine's speed. At most [`MAX_TIME_BUDGET`]. Default `None`.
    pub time_budget: Option<Duration>,
    /// Seed of the kicks: equal inputs and seeds give equal tours. Default 0.
    pub seed: u64,
}

/// Largest [`SolverConfig::kicks_per_node`] accepted without a time budget
/// (a kick costs 5-8 microseconds: 1000 kicks per node on 300 nodes take
/// about 2 s).
pub const MAX_KICKS_PER_NODE: usize = 1000;

/// Largest [`SolverConfig::kicks_per_pair`] accepted without a time budget
/// (20 times the default: 90,000 kicks, under 1 s, on 300 nodes).
pub const MAX_KICKS_PER_PAIR: f64 = 1.0;

/// Largest accepted [`SolverConfig::time_budget`]: one hour.
pub const MAX_TIME_BUDGET: Duration = Duration::from_secs(3600);

impl Default for SolverConfig {
    fn default() -> Self {
        Self {
            exact_max_nodes: 13,
            candidates: 10,
            kicks_per_node: 6,
            kicks_per_pair: 0.05,
            time_budget: None,
            seed: 0,
        }
    }
}

impl SolverConfig {
    /// Checks the documented ranges.
    ///
    /// # Errors
    /// [`TspError::InvalidConfig`] naming the offending field and its limit.
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
        if !(self.kicks_per_pair.is_finite() && self.kicks_per_pair >= 0.0) {
            return Err(TspError::InvalidConfig(format!(
                "kicks_per_pair = {} must be finite and at least 0",
                self.kicks_per_pair
            )));
        }
        if let Some(b) = self.time_budget
            && b > MAX_TIME_BUDGET
        {
            return Err(TspError::InvalidConfig(format!(
                "time_budget = {} s exceeds the limit of {} s",
                b.as_secs_f64(),
                MAX_TIME_BUDGET.as_secs()
            )));
        }
        // Without a time budget nothing but the kick count ends the search,
        // so it must stay within what a solve can finish.
        if self.time_budget.is_none() {
            if self.kicks_per_node > MAX_KICKS_PER_NODE {
                return Err(TspError::InvalidConfig(format!(
                    "kicks_per_node = {} exceeds the limit of {MAX_KICKS_PER_NODE} (set time_budget to allow more)",
                    self.kicks_per_node
                )));
            }
            if self.kicks_per_pair > MAX_KICKS_PER_PAIR {
                return Err(TspError::InvalidConfig(format!(
                    "kicks_per_pair = {} exceeds the limit of {MAX_KICKS_PER_PAIR} (set time_budget to allow more)",
                    self.kicks_per_pair
                )));
            }
        }
        Ok(())
    }

    /// Kick budget of the iterated local search on `r` nodes:
    /// `max(kicks_per_node * r, ceil(kicks_per_pair * r^2))` (saturating).
    ///
    /// # Examples
    /// ```
    /// use sornav_tsp::SolverConfig;
    /// let config = SolverConfig::default();
    /// assert_eq!(config.kicks(50), 300); // 6 per node
    /// assert_eq!(config.kicks(200), 2000); // 200^2 / 20
    /// ```
    pub fn kicks(&self, r: usize) -> usize {
        let pairs = (self.kicks_per_pair * r as f64 * r as f64).ceil() as usize;
        self.kicks_per_node.saturating_mul(r).max(pairs)
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

    /// The symmetric form of an open route whose costs are symmetric away
    /// from the start (`c(i, j) == c(j, i)` for all other nodes), else
    /// `None`. See [`SymmetricForm`].
    fn symmetric_form(&self) -> Option<SymmetricForm> {
        if !matches!(self.route, Route::Open { .. }) {
            return None;
        }
        let (r, c) = (self.r, &self.c);
        if !(2..r).all(|i| (1..i).all(|j| c[i * r + j] == c[j * r + i])) {
            return None;
        }
        let q = r + 1;
        // Off-diagonal entries only (the diagonal is never read).
        let max_abs = (0..r * r)
            .filter(|t| t / r != t % r)
            .fold(0.0_f64, |acc, t| acc.max(c[t].abs()));
        let penalty = 2.0 * q as f64 * max_abs + 1.0;
        let mut sc = vec![0.0; q * q];
        for i in 0..q {
            for j in 0..i {
                // `j < i`; node r is the end node E.
                let v = match (j, i) {
                    (0, i) if i == r => 0.0,
                    (0, i) => c[i] + penalty,
                    (j, i) if i == r => c[j * r],
                    (j, i) => c[i * r + j],
                };
                sc[i * q + j] = v;
                sc[j * q + i] = v;
            }
        }
        Some(SymmetricForm { q, c: sc, max_abs })
    }

    fn cost_of(&self, order: &[usize]) -> f64 {
        let r = self.r;
        (0..order.len())
            .map(|t| self.c[order[t] * r + order[(t + 1) % order.len()]])
            .sum()
    }
}

/// An open route as a symmetric closed tour problem on `q = r + 1` nodes:
/// the reduced nodes `0..r` (0 the start) plus an end node `E = r` standing
/// for "the path ends here" (free end) or for the fixed end itself.
/// Edge costs: `{0, E} = 0`; `{j, E} = c(j, end)` (0 for a free end);
/// `{0, j} = c(start, j) + penalty`; `{i, j} = c(i, j)` otherwise.
///
/// A tour in which `0` and `E` are adjacent, read from `0` away from `E`,
/// is a path `start .. E` and costs exactly the path plus `penalty`. With
/// `penalty > (2q - 1) max |c|`, any tour in which they are not adjacent
/// (two penalised edges at 0) costs more than every tour in which they are,
/// so the iterated local search, which never accepts a worse best tour than
/// its valid start, always returns one where they are. On this form
/// reversing a stretch is free and the local search takes the cheaper
/// symmetric code paths.
struct SymmetricForm {
    q: usize,
    c: Vec<f64>,
    /// Largest magnitude of the route's own costs (the penalty excluded).
    max_abs: f64,
}

impl SymmetricForm {
    /// A reduced tour (start first) as a tour of the form.
    fn tour(&self, reduced: &[usize]) -> Vec<usize> {
        let mut t = reduced.to_vec();
        t.push(self.q - 1);
        t
    }

    /// The reduced tour (start first) read off a tour of the form.
    fn path(&self, tour: &[usize]) -> Vec<usize> {
        let (q, e) = (self.q, self.q - 1);
        let z = tour.iter().position(|&v| v == 0).unwrap_or(0);
        let forward = tour[(z + q - 1) % q] == e;
        debug_assert!(forward || tour[(z + 1) % q] == e, "start and end apart");
        (0..q)
            .map(|t| {
                if forward {
                    tour[(z + t) % q]
                } else {
                    tour[(z + q - t) % q]
                }
            })
            .filter(|&v| v != e)
            .collect()
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
/// see the crate docs). An open path whose costs are symmetric apart from
/// the start's row (FUEL's frontier matrices: only the robot's costs carry a
/// heading term) is searched as a symmetric tour on `r + 1` nodes, with an
/// end node tied to the start by a cost penalty, where reversing a stretch
/// is free (measured 12-19 % less time at n = 50-200 than pricing
/// reversals around the start). The heuristic is deterministic for a given
/// [`SolverConfig::seed`] unless [`SolverConfig::time_budget`] binds, and it
/// never returns a tour worse than nearest neighbour.
///
/// # Complexity
/// Reduction `O(n^2)`; exact: `O(2^r r^2)`; heuristic: `O(n^2)` set-up
/// plus [`SolverConfig::kicks`]`(r)` kicks (`6 r` up to `r = 120`, then
/// `r^2 / 20`), each a local search around eight nodes (`O(k^2)`
/// evaluations per node, `O(n)` per applied move).
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
            kicks: self.config.kicks(r),
            // validated at most MAX_TIME_BUDGET; an unrepresentable instant
            // would only mean no deadline
            deadline: self.config.time_budget.and_then(|b| began.checked_add(b)),
            seed: self.config.seed,
            cost_scale: None,
        };
        let order = match red.symmetric_form() {
            Some(sym) => {
                let params = IlsParams {
                    cost_scale: Some(sym.max_abs),
                    ..params
                };
                let tour = iterated_local_search(&sym.c, sym.q, &sym.tour(&start_tour), params);
                sym.path(&tour)
            }
            None => iterated_local_search(&red.c, r, &start_tour, params),
        };
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::lcg;

    #[test]
    fn kick_budget_and_its_validation() {
        let config = SolverConfig::default();
        assert_eq!(config.kicks(0), 0);
        assert_eq!(config.kicks(100), 600);
        assert_eq!(config.kicks(121), 733); // ceil(0.05 * 121^2) = 733 > 726
        let huge = SolverConfig {
            kicks_per_node: usize::MAX,
            kicks_per_pair: 1e300,
            ..SolverConfig::default()
        };
        assert_eq!(huge.kicks(1000), usize::MAX);
        for bad in [f64::NAN, -0.5, f64::INFINITY] {
            let config = SolverConfig {
                kicks_per_pair: bad,
                ..SolverConfig::default()
            };
            assert!(matches!(
                Solver::new(config),
                Err(TspError::InvalidConfig(_))
            ));
        }
    }

    /// The penalty of the symmetric form must not coarsen the improvement
    /// threshold: with a forbidden arc of 1e9, gains of 10 still count.
    #[test]
    fn forbidden_arcs_do_not_blunt_the_symmetric_search() {
        let solver = Solver::new(SolverConfig {
            exact_max_nodes: 0,
            ..SolverConfig::default()
        })
        .unwrap();
        for seed in 0..8u64 {
            let mut r = lcg(seed);
            let n = 12;
            let pts: Vec<(f64, f64)> = (0..n).map(|_| (r() * 30.0, r() * 30.0)).collect();
            let m = CostMatrix::from_fn(n, |i, j| {
                if (i, j) == (3, 7) || (i, j) == (7, 3) {
                    return 1e9;
                }
                let d = ((pts[i].0 - pts[j].0).powi(2) + (pts[i].1 - pts[j].1).powi(2)).sqrt();
                10.0 * d.round()
            })
            .unwrap();
            let red = Reduced::new(
                &m,
                Route::Open {
                    start: 0,
                    end: None,
                },
            )
            .unwrap();
            assert!(red.symmetric_form().is_some());
            let exact = held_karp(&m, 0, None, false).unwrap().cost;
            let t = solver.open_path(&m, 0, None).unwrap();
            assert_eq!(t.method, Method::Heuristic);
            assert_eq!(t.cost, exact, "seed {seed}");
        }
    }

    /// Every cyclic order of `0..q` starting at 0.
    fn tours(q: usize) -> Vec<Vec<usize>> {
        fn rec(cur: &mut Vec<usize>, rest: &mut Vec<usize>, out: &mut Vec<Vec<usize>>) {
            if rest.is_empty() {
                out.push(cur.clone());
            }
            for i in 0..rest.len() {
                let v = rest.remove(i);
                cur.push(v);
                rec(cur, rest, out);
                cur.pop();
                rest.insert(i, v);
            }
        }
        let mut out = Vec::new();
        rec(&mut vec![0], &mut (1..q).collect(), &mut out);
        out
    }

    /// Brute force over all tours of the symmetric form: a tour with the
    /// start next to the end node prices its path plus the penalty, and
    /// every other tour costs more than all of those.
    #[test]
    fn symmetric_form_prices_paths_and_penalises_the_rest() {
        for seed in 0..12u64 {
            let mut r = lcg(seed);
            let n = 4 + (seed as usize % 4);
            let pts: Vec<(f64, f64)> = (0..n).map(|_| (r() * 50.0, r() * 50.0)).collect();
            // Symmetric among all nodes but the start's row, which is skewed;
            // negative costs are allowed.
            let skew: Vec<f64> = (0..n).map(|_| r() * 30.0 - 10.0).collect();
            let m = CostMatrix::from_fn(n, |i, j| {
                let d = ((pts[i].0 - pts[j].0).powi(2) + (pts[i].1 - pts[j].1).powi(2)).sqrt();
                if i == 0 { d + skew[j] } else { d - 5.0 }
            })
            .unwrap();
            for end in [None, Some(n - 1)] {
                let red = Reduced::new(&m, Route::Open { start: 0, end }).unwrap();
                let sym = red.symmetric_form().expect("symmetric away from the start");
                let (q, e) = (sym.q, sym.q - 1);
                assert_eq!(q, red.r + 1);
                let penalty = sym.c[1] - red.c[1];
                let cost =
                    |t: &[usize]| -> f64 { (0..q).map(|i| sym.c[t[i] * q + t[(i + 1) % q]]).sum() };
                let (mut worst_valid, mut best_invalid) = (f64::NEG_INFINITY, f64::INFINITY);
                for t in tours(q) {
                    let c = cost(&t);
                    if t[1] == e || t[q - 1] == e {
                        let path = sym.path(&t);
                        assert_eq!(path[0], 0);
                        assert_eq!(path.len(), red.r);
                        assert_eq!(sym.tour(&path).len(), q);
                        let expect = red.cost_of(&path) + penalty;
                        assert!(
                            (c - expect).abs() <= 1e-9 * c.abs().max(1.0),
                            "{c} vs {expect}"
                        );
                        worst_valid = worst_valid.max(c);
                    } else {
                        best_invalid = best_invalid.min(c);
                    }
                }
                assert!(
                    worst_valid < best_invalid,
                    "{worst_valid} >= {best_invalid}"
                );
            }
        }
        // Not applicable: closed tours and asymmetric costs among the others.
        let asym = CostMatrix::from_fn(5, |i, j| (i * 5 + j) as f64).unwrap();
        assert!(
            Reduced::new(
                &asym,
                Route::Open {
                    start: 0,
                    end: None
                }
            )
            .unwrap()
            .symmetric_form()
            .is_none()
        );
        let sym = CostMatrix::from_fn(5, |i, j| (i as f64 - j as f64).abs()).unwrap();
        assert!(
            Reduced::new(&sym, Route::Closed { start: 0 })
                .unwrap()
                .symmetric_form()
                .is_none()
        );
        assert!(
            Reduced::new(
                &sym,
                Route::Open {
                    start: 2,
                    end: Some(4)
                }
            )
            .unwrap()
            .symmetric_form()
            .is_some()
        );
    }
}
