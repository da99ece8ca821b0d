//! Frontier visiting order for SOR-Nav: an open-path / closed-tour ATSP
//! solver on dense cost matrices, the receding-horizon planner with the
//! nearby-frontier replacement rule, and a TSPLIB reader.
//!
//! # Should I use this crate?
//! Use it when you have up to a few hundred places and a full matrix of
//! (possibly asymmetric) travel costs between them, and you need a very good
//! visiting order within milliseconds, for example re-planning exploration
//! frontiers at every map update. It is not meant for thousands of cities
//! (the dense matrix is `O(n^2)` memory) and gives no optimality proof
//! beyond the exact Held-Karp range.
//!
//! # API themes
//! * [`CostMatrix`]: validated dense costs (no NaN reaches the solver).
//! * [`Solver`]: [`Solver::open_path`] (fixed start, free or fixed end) and
//!   [`Solver::closed_tour`], plus warm-started variants. Exact Held-Karp up
//!   to [`SolverConfig::exact_max_nodes`] nodes, iterated local search above
//!   (2-opt with exact asymmetric pricing, Or-opt, or-3opt; double-bridge
//!   kicks), deterministic per seed, with an optional time budget.
//!   [`held_karp`] and [`nearest_neighbour_route`] expose the exact solver
//!   and the baseline.
//! * [`RecedingHorizon`]: the SOR-Nav loop step: route from the robot
//!   through all frontiers (optionally ending home), first frontier to
//!   execute, [`ReplacementRule`] (nearby frontier within 5 m wins when the
//!   first planned leg is more than twice as long), warm start from the
//!   previous plan. It takes plain data ([`HorizonProblem`]), not a graph
//!   type.
//! * [`min_latency_path`]: the minimum-latency open path (travelling
//!   repairman: least sum of arrival costs), exact up to 13 nodes, local
//!   search above; [`RouteObjective::Latency`] plans the receding horizon
//!   with it, for a search that wants every frontier reached early rather
//!   than all of them covered cheaply.
//! * [`tsplib`]: TSPLIB95 problems and tours, to check the solver on
//!   instances with proven optima.
//!
//! # Example
//! ```
//! use sornav_tsp::{CostMatrix, Solver, SolverConfig, tsplib};
//!
//! // Five places in a plane; start at place 0, visit all, end anywhere.
//! let text = "NAME: demo\nTYPE: TSP\nDIMENSION: 5\nEDGE_WEIGHT_TYPE: EUC_2D\n\
//!             NODE_COORD_SECTION\n1 0 0\n2 10 0\n3 10 10\n4 0 10\n5 5 5\nEOF\n";
//! let inst = tsplib::parse(text)?;
//! let solver = Solver::new(SolverConfig::default())?;
//! let path = solver.open_path(&inst.matrix, 0, None)?;
//! assert_eq!(path.order[0], 0);
//! assert_eq!(path.cost, 34.0); // 0 -> centre -> a corner -> around: 7 + 7 + 10 + 10
//! let tour = solver.closed_tour(&inst.matrix, 0)?;
//! assert_eq!(tour.cost, 44.0); // 10 + 10 + 10 + 7 + 7
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Performance
//! On the FUEL/ApexNav open-tour instances (`examples/bench_tsp.rs`, see the
//! crate README for the table) the solver matches LKH run with FUEL's
//! settings in a fraction of its time.
#![forbid(unsafe_code)]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]

/// The README's example is compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod construct;
mod error;
mod held_karp;
mod horizon;
mod latency;
mod local_search;
mod matrix;
mod solver;
#[cfg(test)]
mod test_rng;
pub mod tsplib;

pub use error::TspError;
pub use held_karp::HELD_KARP_MAX_NODES;
pub use horizon::{
    HorizonFrontier, HorizonPlan, HorizonProblem, RecedingHorizon, ReplacementRule, RouteObjective,
};
pub use latency::{
    LATENCY_EXACT_MAX_NODES, LATENCY_MAX_PASSES, LatencyPath, latency, min_latency_path,
    min_weighted_latency_path, weighted_latency,
};
pub use matrix::{CostMatrix, MAX_ABS_COST};
pub use solver::{
    MAX_KICKS_PER_NODE, MAX_KICKS_PER_PAIR, MAX_TIME_BUDGET, Method, Solver, SolverConfig, Tour,
    held_karp, nearest_neighbour_route,
};
