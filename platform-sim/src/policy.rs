//! The [`Policy`] trait (observation in, action out) and baseline policies
//! for sanity checks and tests: [`RandomWalk`], [`StopAtOnce`] and the
//! ground-truth [`Oracle`].

use std::collections::{HashSet, VecDeque};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::agent::{Action, Agent};
use crate::episodes::Episode;
use crate::geodesic::GeodesicField;
use crate::run::{Observation, Simulator};

/// An ObjectNav method: receives an observation per step and answers with
/// an action.
///
/// `reset` receives the simulator so that ground-truth baselines (the oracle)
/// can plan; a real method must use only the observations.
pub trait Policy {
    /// Called once before the first observation of an episode.
    fn reset(&mut self, sim: &Simulator, episode: &Episode) {
        let _ = (sim, episode);
    }
    /// Whether the policy reads camera frames (false skips rendering).
    fn needs_frames(&self) -> bool {
        true
    }
    /// The next action.
    fn act(&mut self, obs: &Observation<'_>) -> Action;
    /// Wall time (s) this episode's [`act`](Self::act) calls spent waiting
    /// for a service whose latency the policy accounts in simulated time
    /// instead (an LLM answer due at a simulated time): left out of the
    /// wall-clock budget, so that a slow machine or server does not cut
    /// the episode. Default 0.
    fn simulated_wait_s(&self) -> f64 {
        0.0
    }
}

/// Calls STOP at once (every episode must then fail: none starts at a view point).
#[derive(Debug, Clone, Copy, Default)]
pub struct StopAtOnce;

impl Policy for StopAtOnce {
    fn needs_frames(&self) -> bool {
        false
    }
    fn act(&mut self, _obs: &Observation<'_>) -> Action {
        Action::Stop
    }
}

/// A seeded random walk: moves forward with probability `p_forward`, turns
/// left or right otherwise (turning away after a collision), never stops.
#[derive(Debug, Clone)]
pub struct RandomWalk {
    rng: ChaCha8Rng,
    seed: u64,
    /// Probability of MOVE_FORWARD at each step.
    pub p_forward: f64,
    last: Option<(nalgebra::Point3<f64>, Action)>,
}

impl RandomWalk {
    /// A random walk with this seed (`p_forward` = 0.7).
    pub fn new(seed: u64) -> RandomWalk {
        RandomWalk {
            rng: ChaCha8Rng::seed_from_u64(seed),
            seed,
            p_forward: 0.7,
            last: None,
        }
    }
}

impl Policy for RandomWalk {
    fn reset(&mut self, _sim: &Simulator, episode: &Episode) {
        let h = episode
            .episode_id
            .bytes()
            .fold(self.seed, |h, b| h.rotate_left(5) ^ u64::from(b));
        self.rng = ChaCha8Rng::seed_from_u64(h);
        self.last = None;
    }
    fn needs_frames(&self) -> bool {
        false
    }
    fn act(&mut self, obs: &Observation<'_>) -> Action {
        let blocked = self
            .last
            .is_some_and(|(p, a)| a == Action::MoveForward && p == obs.position);
        let forward = !blocked && self.rng.random_bool(self.p_forward.clamp(0.0, 1.0));
        let a = if forward {
            Action::MoveForward
        } else if self.rng.random_bool(0.5) {
            Action::TurnLeft
        } else {
            Action::TurnRight
        };
        self.last = Some((obs.position, a));
        a
    }
}

/// Ground-truth oracle: follows the geodesic to the nearest goal view point
/// and stops within the success radius.
///
/// # Algorithm
/// The field descended is the geodesic distance over the walkable areas at
/// least three cells wide ([`crate::NavMesh::wide_spans`]; off them, 1 km
/// plus the plain geodesic distance): the height field connects rooms
/// through strips one or two cells wide (a 0.40 m gap between two pieces of
/// furniture) that 0.25 m moves at headings 30 deg apart cannot follow, and
/// an oracle descending the plain field walked into them and stopped. STOP
/// is decided on the plain field. Greedy descent of that field with one-step look-ahead over the 12
/// headings reachable by turning: turn (the shorter way) towards the heading
/// whose forward move lowers the distance most, move forward when it is the
/// current one ([`crate::follow::choose_heading`], the heading choice of the
/// [`crate::WaypointFollower`], with a 0.001 penalty per turn). When no forward move makes progress (a doorway or corner the
/// 30 deg headings do not fit), a breadth-first search over the exact motion
/// model (forward, left, right; up to `search_depth` actions) finds the
/// shortest action sequence to a pose closer to the goal, and its first action
/// is taken. STOP as soon as the geodesic distance is within `stop_distance`.
///
/// # Complexity
/// O(12 step / cell) per greedy step; a search costs O(3^depth) in the worst case.
#[derive(Debug, Clone)]
pub struct Oracle {
    /// Geodesic distance at which to STOP (0.1 m minus a margin: 0.09).
    pub stop_distance: f64,
    /// Depth of the fallback search (16 actions).
    pub search_depth: usize,
    field: Option<GeodesicField>,
    wide: Option<GeodesicField>,
    nav: Option<std::sync::Arc<crate::NavMesh>>,
    plan: VecDeque<Action>,
}

impl Default for Oracle {
    fn default() -> Self {
        Oracle {
            stop_distance: 0.09,
            search_depth: 16,
            field: None,
            wide: None,
            nav: None,
            plan: VecDeque::new(),
        }
    }
}

impl Oracle {
    /// An oracle with the default settings.
    pub fn new() -> Oracle {
        Oracle::default()
    }

    /// Geodesic distance from `p` to the goals (decides STOP).
    fn goal_distance(&self, p: &nalgebra::Point3<f64>) -> f64 {
        match (&self.field, &self.nav) {
            (Some(f), Some(n)) => f.distance(n, p).unwrap_or(f64::INFINITY),
            _ => f64::INFINITY,
        }
    }

    /// What the oracle descends: the geodesic distance over the areas at
    /// least three cells wide ([`crate::NavMesh::wide_spans`]) where that
    /// field reaches `p`, else 1 km plus the plain geodesic distance (so
    /// that a pose off the wide areas heads back to them, or, when no goal
    /// lies on them, the plain field is descended).
    fn cost(&self, p: &nalgebra::Point3<f64>) -> f64 {
        if let (Some(w), Some(n)) = (&self.wide, &self.nav)
            && let Ok(d) = w.distance(n, p)
            && d.is_finite()
        {
            return d;
        }
        1e3 + self.goal_distance(p)
    }

    fn dist(&self, agent: &Agent) -> f64 {
        self.cost(&agent.position())
    }

    /// Shortest action sequence (BFS) to a pose strictly closer than `d0 - 0.05`
    /// or within the stop distance.
    fn search(&self, start: &Agent, d0: f64) -> Option<Vec<Action>> {
        let nav = self.nav.as_ref()?;
        let key = |a: &Agent| {
            let p = a.position();
            (
                (p.x * 200.0).round() as i64,
                (p.y * 200.0).round() as i64,
                (p.z * 20.0).round() as i64,
                (a.yaw() * 1000.0).round() as i64,
            )
        };
        let mut seen = HashSet::new();
        let mut queue = VecDeque::new();
        seen.insert(key(start));
        queue.push_back((start.clone(), Vec::new()));
        while let Some((agent, path)) = queue.pop_front() {
            if path.len() >= self.search_depth {
                continue;
            }
            for a in [Action::MoveForward, Action::TurnLeft, Action::TurnRight] {
                let mut next = agent.clone();
                if next.step(nav, a).collided {
                    continue;
                }
                if !seen.insert(key(&next)) {
                    continue;
                }
                let mut p = path.clone();
                p.push(a);
                let d = self.dist(&next);
                if self.goal_distance(&next.position()) <= self.stop_distance || d < d0 - 0.05 {
                    return Some(p);
                }
                queue.push_back((next, p));
            }
        }
        None
    }
}

impl Policy for Oracle {
    fn reset(&mut self, sim: &Simulator, episode: &Episode) {
        self.field = sim.goal_field(episode).ok();
        let nav = sim.nav_shared();
        self.wide = nav
            .geodesic_field_within(&episode.view_point_positions(), &nav.wide_spans())
            .ok();
        self.nav = Some(nav);
        self.plan.clear();
    }

    fn needs_frames(&self) -> bool {
        false
    }

    fn act(&mut self, obs: &Observation<'_>) -> Action {
        let agent = obs.agent;
        if self.goal_distance(&agent.position()) <= self.stop_distance {
            return Action::Stop;
        }
        let d0 = self.dist(agent);
        if let Some(a) = self.plan.pop_front() {
            return a;
        }
        let Some(nav) = self.nav.as_ref() else {
            return Action::Stop;
        };
        // Greedy: best heading among the 12 reachable ones (the heading
        // choice shared with the waypoint follower).
        let turns = (std::f64::consts::TAU / agent.config().turn_deg.to_radians())
            .round()
            .max(1.0) as usize;
        // Distance after a forward move for each signed turn count k of
        // `choose_heading` (k > 0: k left turns, k < 0: |k| right turns).
        // Each heading is probed by the very turns the agent will take to
        // reach it: k left turns and 12 - k right turns end at headings
        // that differ in the last bits, and a forward move that grazes a
        // cell corner can be free for one and blocked for the other (the
        // agent then turned back and forth between two headings forever).
        let after = |k: i32| -> Option<f64> {
            let turn = if k > 0 {
                Action::TurnLeft
            } else {
                Action::TurnRight
            };
            let mut probe = agent.clone();
            for _ in 0..k.unsigned_abs() {
                probe.step(nav, turn);
            }
            probe.try_forward(nav).map(|(p, _)| self.cost(&p))
        };
        let best =
            crate::follow::choose_heading(turns, 1e-3, |k| after(k).filter(|&d| d < d0 - 1e-6));
        match best {
            Some(k) => crate::follow::heading_action(k),
            None => match self.search(agent, d0) {
                Some(p) => {
                    self.plan = p.into();
                    self.plan.pop_front().unwrap_or(Action::Stop)
                }
                // Nowhere closer is reachable: stopping is the best an oracle can do.
                None => Action::Stop,
            },
        }
    }
}
