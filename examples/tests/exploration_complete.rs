//! Exploration complete before "exhausted" (issue 20, item 3): on every
//! shared Sweet Home 3D home, the real agent exploring with no findable
//! target leaves no reachable unknown area larger than 1 m² on its start
//! floor.
//!
//! # Set-up
//! * **Homes**: the six homes of `../shared/data/sh3d-homes/homes`
//!   (skipped with a message when the shared data is missing, a failure
//!   when `CI=true`: `sornav_test_support::shared_data`).
//! * **Starts** (deterministic): on every level of the simulator's height
//!   field ([`NavMesh::levels`]), for every connected piece of the
//!   level's floor of at least [`MIN_PIECE_M2`] (4 m²), the floor span
//!   nearest to the piece's centroid and [`RANDOM_STARTS`] (2) spans
//!   drawn with a seeded generator ([`SEED`]), all within
//!   [`START_HEIGHT_TOLERANCE`] of the level's elevation (on the floor,
//!   not on a stair step), heading +x: 30 starts over the six homes.
//! * **Agent**: [`SornavPolicy`] with [`sim_agent_config`] (stairs
//!   allowed, as in `sornav-sim`), 160 x 120 camera, in [`Simulator`]
//!   under [`run_episode`] (no wall-clock limit, so that the outcome does
//!   not depend on the machine's load). The target is a category added to
//!   the agent's vocabulary that no pixel carries ([`ABSENT`]): nothing
//!   can be found, so the agent explores until it declares the search
//!   exhausted (`exhausted` end: after the adapter's last full turn) or
//!   runs out of the [`BUDGET`] of 1500 actions.
//!
//! # Criterion
//! Ground truth: the simulator's walkable spans of the start's level
//! reachable from the start over the height field without leaving the
//! level's height window (`|z - elevation| <= LEVEL_HALF_HEIGHT`, so
//! stair flights beyond the floor's window are left out). A reachable span
//! whose column centre lies in a cell that the agent's own grid of its
//! start floor (`agent.frontier_map().level_map(LevelId(0))`) calls
//! [`CellState::Unknown`] is *unknown*; unknown spans are grouped into
//! 8-connected components over the height field's 0.05 m columns. A run
//! passes when the agent ended `exhausted` (not by the budget) and no
//! component exceeds [`MAX_UNKNOWN_M2`] (1 m²). Every run prints the
//! actions used, how the agent ended, the reachable area, the known share
//! and the largest unknown components (area and centroid), so that a
//! failure can be located.
//!
//! Runs use all cores (threads over the starts); about a minute on two
//! loaded cores in the dev profile. The starts where today's agent fails
//! are listed in [`KNOWN_FAILURES`] and run by the ignored
//! [`known_incomplete_explorations`], whose doc comment gives the
//! figures and causes.

mod absent_target;
#[allow(dead_code)] // this binary uses only the simulator helper
mod common;

use std::path::Path;
use std::sync::Mutex;
use std::time::Instant;

use absent_target::{AbsentTargetFactory, absent_target_episode};
use common::simulator_160x120;
use nalgebra::{Point2, Point3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sornav::Agent;
use sornav::frontier_graph::{CellState, LevelId, NodeId, OccupancyGrid};
use sornav_examples::adapter::{
    AdapterConfig, ConfigFactory, EpisodeTrace, SornavPolicy, sim_agent_config,
};
use sornav_platform_sim::levels::LEVEL_HALF_HEIGHT;
use sornav_platform_sim::{NavMesh, RunConfig, Scene, Simulator, SpanId, run_episode};

/// Action budget per home (scan turns included).
const BUDGET: usize = 1500;
/// Largest reachable unknown component allowed (m²).
const MAX_UNKNOWN_M2: f64 = 1.0;
/// Connected pieces of a floor smaller than this (m²) get no start.
const MIN_PIECE_M2: f64 = 4.0;
/// Seeded random starts per piece, besides the one nearest its centroid.
const RANDOM_STARTS: usize = 2;
/// Starts lie within this height (m) of their level's elevation.
const START_HEIGHT_TOLERANCE: f64 = 0.1;
/// Seed of the random starts.
const SEED: u64 = 20;

/// One unknown component.
#[derive(Debug, Clone)]
struct Component {
    area_m2: f64,
    centroid: Point2<f64>,
}

/// What one home's run measured.
#[derive(Debug, Clone)]
struct HomeResult {
    home: String,
    label: String,
    start: Point3<f64>,
    actions: usize,
    end: String,
    reachable_m2: f64,
    known_share: f64,
    /// Unknown components, largest first.
    unknown: Vec<Component>,
    wall_s: f64,
}

impl HomeResult {
    fn largest_m2(&self) -> f64 {
        self.unknown.first().map_or(0.0, |c| c.area_m2)
    }

    fn passes(&self) -> bool {
        self.end == "exhausted" && self.largest_m2() <= MAX_UNKNOWN_M2
    }

    fn report(&self) -> String {
        let comps: Vec<String> = self
            .unknown
            .iter()
            .take(4)
            .map(|c| {
                format!(
                    "{:.2} m² at ({:.2}, {:.2})",
                    c.area_m2, c.centroid.x, c.centroid.y
                )
            })
            .collect();
        format!(
            "{} ({}): start ({:.2}, {:.2}, {:.2}), {} actions, end {:?}, reachable {:.1} m², known {:.1} %, \
             largest unknown components [{}] ({:.0} s)",
            self.home,
            self.label,
            self.start.x,
            self.start.y,
            self.start.z,
            self.actions,
            self.end,
            self.reachable_m2,
            100.0 * self.known_share,
            comps.join(", "),
            self.wall_s
        )
    }
}

/// A start pose of a run: the level it is on (index into
/// [`NavMesh::levels`]), that level's elevation, the feet position.
#[derive(Debug, Clone)]
struct Start {
    level: usize,
    elevation: f64,
    position: Point3<f64>,
    label: String,
}

/// The floor spans of `level` within its height window.
fn level_floor(nav: &NavMesh, level: usize, elevation: f64, s: SpanId) -> bool {
    nav.span_level(s) == Some(level)
        && nav.is_floor_span(s)
        && (f64::from(nav.spans()[s as usize].floor) - elevation).abs() <= LEVEL_HALF_HEIGHT
}

/// The starts of a home (see the module docs): per level, per connected
/// piece of its floor of at least [`MIN_PIECE_M2`], the span nearest to
/// the piece's centroid and [`RANDOM_STARTS`] seeded random spans.
fn starts_of(nav: &NavMesh, seed: u64) -> Vec<Start> {
    let cs = nav.config().cell_size;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::new();
    for (level, l) in nav.levels().iter().enumerate() {
        let keep = |s: SpanId| level_floor(nav, level, l.elevation, s);
        let mut seen = vec![false; nav.span_count()];
        for s in 0..nav.span_count() as SpanId {
            if seen[s as usize] || !keep(s) {
                continue;
            }
            let piece = flood(nav, s, &keep, &mut seen);
            if (piece.len() as f64) * cs * cs < MIN_PIECE_M2 {
                continue;
            }
            let n = piece.len() as f64;
            let c = piece.iter().fold(Point2::origin(), |a: Point2<f64>, &s| {
                a + nav.span_center(s).xy().coords / n
            });
            // Starts on the floor itself, not on a stair step or landing
            // inside the level's window.
            let piece: Vec<SpanId> = piece
                .into_iter()
                .filter(|&s| {
                    (f64::from(nav.spans()[s as usize].floor) - l.elevation).abs()
                        <= START_HEIGHT_TOLERANCE
                })
                .collect();
            let pieces =
                out.iter().filter(|s: &&Start| s.level == level).count() / (1 + RANDOM_STARTS);
            let Some(centre) = piece
                .iter()
                .map(|&s| nav.span_center(s))
                .min_by(|a, b| (a.xy() - c).norm().total_cmp(&(b.xy() - c).norm()))
            else {
                continue;
            };
            out.push(Start {
                level,
                elevation: l.elevation,
                position: centre,
                label: format!("level {level} piece {pieces} centre"),
            });
            for k in 0..RANDOM_STARTS {
                let s = piece[rng.random_range(0..piece.len())];
                out.push(Start {
                    level,
                    elevation: l.elevation,
                    position: nav.span_center(s),
                    label: format!("level {level} piece {pieces} random {k}"),
                });
            }
        }
    }
    out
}

/// Spans connected to `from` over the height field's links among those
/// `keep` accepts (marking them in `seen`).
fn flood(
    nav: &NavMesh,
    from: SpanId,
    keep: &dyn Fn(SpanId) -> bool,
    seen: &mut [bool],
) -> Vec<SpanId> {
    let mut out = vec![from];
    seen[from as usize] = true;
    let mut i = 0;
    while i < out.len() {
        let s = out[i];
        i += 1;
        for &m in &nav.spans()[s as usize].neighbours {
            if m != u32::MAX && !seen[m as usize] && keep(m) {
                seen[m as usize] = true;
                out.push(m);
            }
        }
    }
    out
}

/// Loads a home into the simulator (160 x 120 camera).
fn simulator(home: &Path, models: &Path) -> Simulator {
    simulator_160x120(
        Scene::from_home_xml(home, models).unwrap_or_else(|e| panic!("{}: {e}", home.display())),
    )
}

/// Whether the agent may take stairs: yes, as in `sim_agent_config`,
/// unless `SORNAV_EC_NO_STAIRS` is set (a robot kept on its floor).
fn allow_stairs() -> bool {
    std::env::var_os("SORNAV_EC_NO_STAIRS").is_none()
}

/// Runs the agent in `sim` from `start` and measures its start floor's map.
fn explore(sim: &Simulator, name: &str, start: &Start) -> HomeResult {
    let t0 = Instant::now();
    let nav = sim.nav();
    let p = start.position;
    let episode = absent_target_episode(format!("{name}-{}", start.label), name, p, 0.0);
    let mut config = sim_agent_config();
    config.frontier.levels.allow_stairs = allow_stairs();
    let factory = AbsentTargetFactory(ConfigFactory {
        config,
        policy: None,
    });
    let mut policy = SornavPolicy::new(factory, AdapterConfig::default());
    let run = RunConfig {
        max_actions: BUDGET,
        wall_clock_s: f64::INFINITY,
        ..RunConfig::default()
    };
    let r = run_episode(sim, &episode, &mut policy, &run).unwrap();
    let trace = policy.take_trace();
    assert!(
        trace.errors.is_empty(),
        "{name}: agent errors {:?}",
        trace.errors
    );
    let agent = policy.agent().expect("the agent was built");
    let grid = agent
        .frontier_map()
        .level_map(LevelId(0))
        .expect("the start floor's map")
        .grid();
    // Ground truth: the start level's spans reachable from the start
    // within the level's height window.
    let start_span = nav.span_at(&p).expect("the start is navigable");
    let on_floor = |s: SpanId| {
        nav.span_level(s) == Some(start.level)
            && (f64::from(nav.spans()[s as usize].floor) - start.elevation).abs()
                <= LEVEL_HALF_HEIGHT
    };
    let mut seen = vec![false; nav.span_count()];
    let reachable = flood(nav, start_span, &on_floor, &mut seen);
    let cs = nav.config().cell_size;
    // The agent's z is measured from the start floor: only x, y are compared.
    let unknown = |s: SpanId| {
        let c = nav.span_center(s);
        grid.cell_of(&Point2::new(c.x, c.y))
            .map_or(true, |cell| grid.state(cell) == CellState::Unknown)
    };
    let (w, h) = nav.grid_size();
    let mut mask = vec![false; w * h];
    let mut n_unknown = 0usize;
    for &s in &reachable {
        if unknown(s) {
            let (x, y) = nav.span_cell(s);
            mask[y * w + x] = true;
            n_unknown += 1;
        }
    }
    let origin = nav.origin();
    let mut components = Vec::new();
    for first in 0..mask.len() {
        if !mask[first] {
            continue;
        }
        mask[first] = false;
        let mut stack = vec![first];
        let (mut n, mut sx, mut sy) = (0usize, 0.0, 0.0);
        while let Some(i) = stack.pop() {
            let (x, y) = (i % w, i / w);
            n += 1;
            sx += origin.x + (x as f64 + 0.5) * cs;
            sy += origin.y + (y as f64 + 0.5) * cs;
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                    if nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                        continue;
                    }
                    let j = ny as usize * w + nx as usize;
                    if mask[j] {
                        mask[j] = false;
                        stack.push(j);
                    }
                }
            }
        }
        components.push(Component {
            area_m2: n as f64 * cs * cs,
            centroid: Point2::new(sx / n as f64, sy / n as f64),
        });
    }
    components.sort_by(|a, b| b.area_m2.total_cmp(&a.area_m2));
    if std::env::var_os("SORNAV_EC_DUMP").is_some()
        && (std::env::var_os("SORNAV_EC_TRACE").is_some()
            || trace.agent_end != "exhausted"
            || components
                .first()
                .is_some_and(|c| c.area_m2 > MAX_UNKNOWN_M2))
    {
        dump(name, start, agent, &trace, nav, &reachable, &components);
    }
    HomeResult {
        home: name.to_owned(),
        label: start.label.clone(),
        start: p,
        actions: r.actions,
        end: trace.agent_end,
        reachable_m2: reachable.len() as f64 * cs * cs,
        known_share: 1.0 - n_unknown as f64 / reachable.len().max(1) as f64,
        unknown: components,
        wall_s: t0.elapsed().as_secs_f64(),
    }
}

/// The trace of a run (`SORNAV_EC_TRACE`): the start floor's grid at its
/// resolution 4 m around `centre` (`R`/`F` traversable / frontier cells
/// connected to the robot's cell by straight moves, `t`/`f` the same not
/// connected, `.` free, `#` occupied, blank unknown), then the trajectory
/// every 10 actions and every decision.
fn trace_dump(agent: &Agent, trace: &EpisodeTrace, grid: &OccupancyGrid, centre: &Point2<f64>) {
    let last = trace.trajectory.last().copied().unwrap_or_default();
    let robot = Point2::new(f64::from(last[0]), f64::from(last[1]));
    let mut connected = std::collections::HashSet::new();
    if let Ok(start) = grid.cell_of(&robot) {
        let mut queue = vec![start];
        connected.insert(start);
        while let Some(c) = queue.pop() {
            for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                let n = c.offset(dx, dy);
                if grid.is_traversable(n) && connected.insert(n) {
                    queue.push(n);
                }
            }
        }
    }
    let frontier: std::collections::HashSet<_> = agent
        .frontier_map()
        .level_map(LevelId(0))
        .map(|m| m.frontier_cells().collect())
        .unwrap_or_default();
    let r = grid.resolution();
    let n = (4.0 / r).round() as i32;
    eprintln!(
        "  start floor's grid, {r} m per character, 4 m around ({:.2}, {:.2}), y down the page; robot at ({:.2}, {:.2})",
        centre.x, centre.y, robot.x, robot.y
    );
    for dy in (-n..=n).rev() {
        let row: String = (-n..=n)
            .map(|dx| {
                let q = Point2::new(centre.x + r * f64::from(dx), centre.y + r * f64::from(dy));
                let Ok(c) = grid.cell_of(&q) else {
                    return '?';
                };
                match (frontier.contains(&c), connected.contains(&c)) {
                    (true, true) => 'F',
                    (true, false) => 'f',
                    (false, true) => 'R',
                    (false, false) if grid.is_traversable(c) => 't',
                    _ => match grid.state(c) {
                        CellState::Occupied => '#',
                        CellState::Free => '.',
                        CellState::Unknown => ' ',
                    },
                }
            })
            .collect();
        eprintln!("  |{row}|");
    }
    for (i, t) in trace.trajectory.iter().enumerate().step_by(10) {
        eprintln!("  action {i}: ({:.2}, {:.2}, {:.2})", t[0], t[1], t[2]);
    }
    for d in trace.decisions.runs() {
        eprintln!("  {d:?}");
    }
}

/// Prints a failing run (`SORNAV_EC_DUMP`): the end pose, the agent's
/// levels, stairs, frontiers and last decisions, and an 8 m map of the
/// agent's grid against the ground truth around the largest unknown
/// component (or the end pose).
fn dump(
    name: &str,
    start: &Start,
    agent: &Agent,
    trace: &EpisodeTrace,
    nav: &NavMesh,
    reachable: &[SpanId],
    components: &[Component],
) {
    let grid = agent
        .frontier_map()
        .level_map(LevelId(0))
        .expect("the start floor's map")
        .grid();
    let (cs, origin, p) = (nav.config().cell_size, nav.origin(), start.position);
    let map = agent.frontier_map();
    let last = trace.trajectory.last().copied().unwrap_or_default();
    eprintln!(
        "{name} ({}): end at ({:.2}, {:.2}, {:.2}); agent levels {:?}; stairs {:?}",
        start.label,
        last[0],
        last[1],
        last[2],
        map.levels()
            .map(|l| (l.id.0, l.floor_z))
            .collect::<Vec<_>>(),
        map.stairs()
            .iter()
            .map(|s| format!(
                "{:?}->{:?} complete {}",
                s.lower.level,
                s.upper.level,
                s.is_complete()
            ))
            .collect::<Vec<_>>()
    );
    for l in map.levels() {
        let lm = map.level_map(l.id).expect("level");
        eprintln!(
            "  level {} frontiers {} frontier cells {}",
            l.id.0,
            lm.graph().len(),
            lm.frontier_cells().count()
        );
        if std::env::var_os("SORNAV_EC_TRACE").is_some() {
            for f in lm.graph().nodes() {
                let cost = lm.graph().cost(NodeId::Robot, NodeId::Frontier(f.id));
                eprintln!(
                    "    frontier {:?}: centroid ({:.2}, {:.2}), viewpoint ({:.2}, {:.2}), {} cells, cost from the robot {cost:?}",
                    f.id,
                    f.centroid.x,
                    f.centroid.y,
                    f.viewpoint.x,
                    f.viewpoint.y,
                    f.cells.len(),
                );
            }
        }
    }
    let runs = trace.decisions.runs();
    for d in runs
        .iter()
        .filter(|d| {
            d.action != sornav::DecisionAction::Exhausted
                && !format!("{:?}", d.action).contains("Continue")
        })
        .rev()
        .take(14)
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
    {
        eprintln!("  {d:?}");
    }
    let centre = components
        .first()
        .map_or(Point2::new(f64::from(last[0]), f64::from(last[1])), |c| {
            c.centroid
        });
    if std::env::var_os("SORNAV_EC_TRACE").is_some() {
        trace_dump(agent, trace, grid, &centre);
    }
    let reach: std::collections::HashSet<(usize, usize)> =
        reachable.iter().map(|&s| nav.span_cell(s)).collect();
    eprintln!(
        "{name} ({}): 8 m around ({:.2}, {:.2}), y down the page, 0.1 m per character: \
         U reachable + unknown, o reachable + known + traversable for the agent, x reachable + known, not traversable; off the reachable floor: # occupied, . free, blank unknown; \
         then the height (dm, relative to the start) of the walking surface nearest the start floor",
        start.label, centre.x, centre.y
    );
    for dy in (-40..=40).rev() {
        let mut row = String::new();
        let mut hrow = String::new();
        for dx in -40..=40 {
            let q = Point2::new(
                centre.x + 0.1 * f64::from(dx),
                centre.y + 0.1 * f64::from(dy),
            );
            let col = (
                ((q.x - origin.x) / cs).floor() as usize,
                ((q.y - origin.y) / cs).floor() as usize,
            );
            let state = grid
                .cell_of(&q)
                .map_or(CellState::Unknown, |cell| grid.state(cell));
            let trav = grid.cell_of(&q).is_ok_and(|cell| grid.is_traversable(cell));
            row.push(if reach.contains(&col) {
                if state == CellState::Unknown {
                    'U'
                } else if trav {
                    'o'
                } else {
                    'x'
                }
            } else {
                match state {
                    CellState::Occupied => '#',
                    CellState::Free => '.',
                    CellState::Unknown => ' ',
                }
            });
            let hz = nav
                .height_at(q.x, q.y, p.z)
                .map(|z| ((z - p.z) * 10.0).round() as i64);
            hrow.push_str(&match hz {
                Some(z) => format!("{:>3}", z.clamp(-99, 99)),
                None => "  .".to_owned(),
            });
        }
        eprintln!("  {row}   {hrow}");
    }
}

/// Runs the starts of `homes` (file stems) that `select` accepts (home,
/// start label) on parallel threads; results in home, then start order.
fn run_homes(homes: &[&str], select: &dyn Fn(&str, &str) -> bool) -> Option<Vec<HomeResult>> {
    let dir = sornav_test_support::shared_data("sh3d-homes")?;
    let models = dir.join("models");
    let sims: Vec<(String, Simulator)> = homes
        .iter()
        .map(|h| {
            (
                (*h).to_owned(),
                simulator(&dir.join("homes").join(format!("{h}.xml")), &models),
            )
        })
        .collect();
    let jobs: Vec<(usize, Start)> = sims
        .iter()
        .enumerate()
        .flat_map(|(i, (_, sim))| starts_of(sim.nav(), SEED).into_iter().map(move |s| (i, s)))
        .filter(|(i, s)| {
            select(&sims[*i].0, &s.label)
                && std::env::var("SORNAV_EC_START").map_or(true, |f| s.label == f)
        })
        .collect();
    let threads = std::thread::available_parallelism()
        .map_or(2, std::num::NonZeroUsize::get)
        .min(jobs.len())
        .max(1);
    let next = Mutex::new(0usize);
    let results: Mutex<Vec<Option<HomeResult>>> = Mutex::new(vec![None; jobs.len()]);
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| {
                loop {
                    let i = {
                        let mut n = next.lock().unwrap();
                        let i = *n;
                        *n += 1;
                        i
                    };
                    let Some((home, start)) = jobs.get(i) else {
                        break;
                    };
                    let (name, sim) = &sims[*home];
                    let r = explore(sim, name, start);
                    eprintln!("{}", r.report());
                    results.lock().unwrap()[i] = Some(r);
                }
            });
        }
    });
    Some(
        results
            .into_inner()
            .unwrap()
            .into_iter()
            .map(|r| r.expect("every start ran"))
            .collect(),
    )
}

const ALL: [&str; 6] = [
    "2BedroomApartment",
    "2BedroomHouseWithBasement",
    "3BedroomApartment",
    "3BedroomHouseWithAttic",
    "4BedroomHouse",
    "Studio",
];

/// The starts (home, start label) where today's agent does not meet the
/// criterion: run by [`known_incomplete_explorations`] (ignored), left out
/// of [`exploration_leaves_no_reachable_unknown_area`].
/// Empty since 2026-11-29 (sixteenth session): the two basement starts
/// of `2BedroomHouseWithBasement` listed until then pass (see
/// [`known_incomplete_explorations`]).
const KNOWN_FAILURES: [(&str, &str); 0] = [];

fn known_failure(home: &str, label: &str) -> bool {
    KNOWN_FAILURES.contains(&(home, label))
}

/// The homes to run: all, or `SORNAV_EC_HOMES` (comma-separated stems).
fn homes() -> Vec<String> {
    std::env::var("SORNAV_EC_HOMES")
        .ok()
        .map(|v| v.split(',').map(|s| s.trim().to_owned()).collect())
        .unwrap_or_else(|| ALL.iter().map(|s| (*s).to_owned()).collect())
}

/// Runs the selected starts and asserts the criterion on each.
fn check(select: &dyn Fn(&str, &str) -> bool) {
    let t0 = Instant::now();
    let homes = homes();
    let homes: Vec<&str> = homes.iter().map(String::as_str).collect();
    let Some(results) = run_homes(&homes, select) else {
        return;
    };
    eprintln!(
        "{} runs, wall time {:.0} s",
        results.len(),
        t0.elapsed().as_secs_f64()
    );
    let failed: Vec<String> = results
        .iter()
        .filter(|r| !r.passes())
        .map(HomeResult::report)
        .collect();
    assert!(
        failed.is_empty(),
        "exploration incomplete or not finished:\n{}",
        failed.join("\n")
    );
}

/// Every start of every shared home but the [`KNOWN_FAILURES`]: the agent
/// declares the search exhausted within the budget and leaves no
/// reachable unknown component larger than 1 m² on its start floor (see
/// the module docs).
#[test]
fn exploration_leaves_no_reachable_unknown_area() {
    check(&|home, label| !known_failure(home, label));
}

/// The [`KNOWN_FAILURES`] (none today). Until 2026-11-29 they were both
/// basement starts of `2BedroomHouseWithBasement` (the basement stair, a
/// curved flight from z -1.50 to the ground floor at z 1.12, lies around
/// x 4.9-5.3, y -1.6..-0.2); with the sixteenth session's agent (the
/// footprint on a stair reduced to the feet, the back-off after a mission
/// stuck where it started, the void rule, the unfinished-mission bound)
/// they end `exhausted` after 544 actions with 99.9 % known
/// (`random 1`) and after 707 actions with 100.0 % known (`random 0`),
/// and they run with the others. What they were, measured with the agent
/// before that session (`sim_agent_config`, 160 x 120, 1500 actions):
///
/// * `level 0 piece 0 random 1` (basement start (9.29, -0.99)):
///   **exhausted too early** after 194 actions, known 92.3 %, largest
///   unknown component 2.56 m² at (2.22, -0.77), the far half of the
///   basement's west room, seen only from its doorway. The agent explored
///   a stair frontier and stopped on the flight's first tread (z +0.22,
///   within the level's tolerance) where the stair then left its map; every
///   MOVE_FORWARD from there toward the remaining frontiers (heading -60
///   deg) collides in the simulator, so each of the five exploration
///   missions that followed failed `Stuck` after four collisions *without
///   the robot moving*, and each failure excluded its frontier (a failed
///   non-stair exploration excludes its frontier). With all of them
///   excluded the agent declared the search exhausted. The frontiers were
///   not unreachable: the robot was stuck (the follower's fallback when
///   no heading is traversable on the agent's map repeats the blocked
///   move). With `SORNAV_EC_NO_STAIRS=1` the same start ends `exhausted`
///   after 143 actions with 99.9 % known.
/// * `level 0 piece 0 random 0` (basement start (1.04, -2.29)):
///   **exhausted on the other floor** after 672 actions with the basement
///   90.1 % known (largest unknown component 3.06 m² at (0.95, -4.51), a
///   corner of the basement's west room). The agent went up the stair
///   before the basement was finished, explored the ground floor and
///   declared the search exhausted there (it ended at (4.93, -2.54, 1.12)):
///   the exhaustion check looks at the robot's floor only, and the
///   basement's last frontier was not revisited. This start passed with
///   the agent before the drop-edge looks (the robot left the basement
///   later); the three ground-floor starts that failed then (budget ends
///   thrashing on the basement stair) pass now.
///
/// Run with `cargo test -p sornav-examples --test exploration_complete --
/// --ignored --nocapture`. Knobs (any test of this file):
/// `SORNAV_EC_HOMES=Studio,4BedroomHouse` picks homes,
/// `SORNAV_EC_START="level 0 piece 0 random 1"` one start label,
/// `SORNAV_EC_NO_STAIRS=1` keeps the robot on its floor
/// (`frontier.levels.allow_stairs = false`), `SORNAV_EC_DUMP=1` prints,
/// for a failing run, the end pose, the agent's levels, stairs, frontiers
/// and last decisions and an 8 m map of the agent's grid against the
/// ground truth around the largest unknown component (`SORNAV_EC_TRACE=1`
/// as well: for every run, with each frontier's cost from the robot, the
/// start floor's grid at its resolution, the trajectory and every
/// decision); `SORNAV_DEBUG=1` /
/// `SORNAV_DEBUG_ACTIONS=1` log dispatches / actions.
#[test]
#[ignore = "known failures of today's agent (none since 2026-11-29); a diagnostic run"]
fn known_incomplete_explorations() {
    check(&known_failure);
}
