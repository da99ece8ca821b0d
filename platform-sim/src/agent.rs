//! Habitat's ObjectNav agent: a cylinder (radius 0.18 m, camera at 0.88 m)
//! that lives on the walkable height field and moves by discrete actions.
//!
//! * `MOVE_FORWARD` moves 0.25 m along the heading. There is no sliding: when
//!   the straight segment leaves the walkable surface (a wall, furniture, a
//!   drop or a step higher than the height field allows) the agent stays where
//!   it was and the step counts as a collision. Walkable spans are already
//!   eroded by the agent radius, so "on the surface" means "the cylinder fits".
//! * The agent follows the surface height: it climbs stairs by moving forward
//!   on them (each grid step of the segment must be a connected neighbour span).
//! * `TURN_LEFT` / `TURN_RIGHT` rotate by 30 deg, `LOOK_UP` / `LOOK_DOWN` tilt
//!   the camera by 30 deg (clamped), `STOP` ends the episode.
//! * Ground-truth pose (Habitat's GPS + compass) is available to the method.

use nalgebra::{Point3, Vector2};
use serde::{Deserialize, Serialize};

use crate::NavError;
use crate::navmesh::{DIRS, NavMesh, SpanId};

/// A discrete ObjectNav action (Habitat's ids: STOP 0, MOVE_FORWARD 1,
/// TURN_LEFT 2, TURN_RIGHT 3, LOOK_UP 4, LOOK_DOWN 5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "SCREAMING_SNAKE_CASE")]
pub enum Action {
    /// End the episode (declare the target found).
    Stop,
    /// Move forward by the step length.
    MoveForward,
    /// Turn counter-clockwise (seen from above).
    TurnLeft,
    /// Turn clockwise.
    TurnRight,
    /// Tilt the camera up.
    LookUp,
    /// Tilt the camera down.
    LookDown,
}

impl Action {
    /// Habitat's integer id of the action.
    pub fn habitat_id(self) -> u8 {
        match self {
            Action::Stop => 0,
            Action::MoveForward => 1,
            Action::TurnLeft => 2,
            Action::TurnRight => 3,
            Action::LookUp => 4,
            Action::LookDown => 5,
        }
    }
}

/// Motion parameters (Habitat ObjectNav defaults).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct AgentConfig {
    /// Forward step in metres (0.25).
    pub forward_step: f64,
    /// Turn angle in degrees (30).
    pub turn_deg: f64,
    /// Camera tilt step in degrees (30).
    pub tilt_deg: f64,
    /// Largest camera tilt up or down in degrees (60).
    pub max_tilt_deg: f64,
}

impl Default for AgentConfig {
    fn default() -> Self {
        AgentConfig {
            forward_step: 0.25,
            turn_deg: 30.0,
            tilt_deg: 30.0,
            max_tilt_deg: 60.0,
        }
    }
}

impl AgentConfig {
    /// Checks ranges.
    ///
    /// # Errors
    /// [`AgentError::Config`] naming the first invalid field.
    pub fn validate(&self) -> Result<(), AgentError> {
        let ok = |v: f64, lo: f64, hi: f64| v.is_finite() && v > lo && v <= hi;
        if !ok(self.forward_step, 0.0, 10.0) {
            return Err(AgentError::Config("forward_step must be in (0, 10] m"));
        }
        if !ok(self.turn_deg, 0.0, 180.0) {
            return Err(AgentError::Config("turn_deg must be in (0, 180]"));
        }
        if !ok(self.tilt_deg, 0.0, 90.0) || !(0.0..=90.0).contains(&self.max_tilt_deg) {
            return Err(AgentError::Config(
                "tilt_deg must be in (0, 90] and max_tilt_deg in [0, 90]",
            ));
        }
        Ok(())
    }
}

/// Errors of agent placement and configuration.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AgentError {
    /// The start pose is not on the walkable surface.
    #[error("start pose is not navigable: {0}")]
    NotNavigable(#[from] NavError),
    /// The start yaw is not finite.
    #[error("start yaw is not finite")]
    NonFiniteYaw,
    /// A configuration value is out of range.
    #[error("invalid agent configuration: {0}")]
    Config(&'static str),
}

/// What an action did.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StepOutcome {
    /// A forward move was blocked (the agent did not move).
    pub collided: bool,
    /// Distance travelled in metres (3-D).
    pub moved: f64,
}

/// The agent's state on a [`NavMesh`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Agent {
    config: AgentConfig,
    position: Point3<f64>,
    span: SpanId,
    yaw: f64,
    pitch: f64,
    start_position: Point3<f64>,
    start_yaw: f64,
}

impl Agent {
    /// Places the agent at `position` (feet) with heading `yaw` (radians,
    /// counter-clockwise from +x). The position is snapped onto the walkable
    /// surface (its height, or the nearest span within 0.5 m when it lies just
    /// off the eroded surface, as Habitat snaps episode starts).
    ///
    /// # Errors
    /// [`AgentError`] when the position is not near the walkable surface, the
    /// yaw is not finite or the configuration is invalid.
    pub fn spawn(
        nav: &NavMesh,
        position: &Point3<f64>,
        yaw: f64,
        config: AgentConfig,
    ) -> Result<Agent, AgentError> {
        config.validate()?;
        if !yaw.is_finite() {
            return Err(AgentError::NonFiniteYaw);
        }
        let p = nav.snap(position, crate::geodesic::SNAP_RADIUS)?;
        let span = nav.span_at(&p).ok_or(NavError::NotNavigable {
            x: p.x,
            y: p.y,
            z: p.z,
        })?;
        let yaw = wrap_angle(yaw);
        Ok(Agent {
            config,
            position: p,
            span,
            yaw,
            pitch: 0.0,
            start_position: p,
            start_yaw: yaw,
        })
    }

    /// The motion parameters.
    pub fn config(&self) -> &AgentConfig {
        &self.config
    }
    /// Feet position (on the walking surface).
    pub fn position(&self) -> Point3<f64> {
        self.position
    }
    /// The span the agent stands on.
    pub fn span(&self) -> SpanId {
        self.span
    }
    /// Heading in radians in (-pi, pi], counter-clockwise from +x.
    pub fn yaw(&self) -> f64 {
        self.yaw
    }
    /// Camera tilt in radians (positive up).
    pub fn pitch(&self) -> f64 {
        self.pitch
    }
    /// Habitat's GPS sensor: position relative to the episode start, in the
    /// start's frame (x forward, y left), metres.
    pub fn gps(&self) -> Vector2<f64> {
        let d = self.position - self.start_position;
        let (s, c) = self.start_yaw.sin_cos();
        Vector2::new(c * d.x + s * d.y, -s * d.x + c * d.y)
    }
    /// Habitat's compass sensor: heading relative to the start heading, in (-pi, pi].
    pub fn compass(&self) -> f64 {
        wrap_angle(self.yaw - self.start_yaw)
    }

    /// Applies one action. `Stop` changes nothing (the episode loop ends the
    /// episode).
    ///
    /// # Complexity
    /// O(step / cell size) for a forward move, O(1) otherwise.
    pub fn step(&mut self, nav: &NavMesh, action: Action) -> StepOutcome {
        let still = StepOutcome {
            collided: false,
            moved: 0.0,
        };
        match action {
            Action::Stop => still,
            Action::TurnLeft => {
                self.yaw = wrap_angle(self.yaw + self.config.turn_deg.to_radians());
                still
            }
            Action::TurnRight => {
                self.yaw = wrap_angle(self.yaw - self.config.turn_deg.to_radians());
                still
            }
            Action::LookUp | Action::LookDown => {
                let sign = if action == Action::LookUp { 1.0 } else { -1.0 };
                let max = self.config.max_tilt_deg.to_radians();
                self.pitch =
                    (self.pitch + sign * self.config.tilt_deg.to_radians()).clamp(-max, max);
                still
            }
            Action::MoveForward => match self.try_forward(nav) {
                Some((p, span)) => {
                    let moved = (p - self.position).norm();
                    self.position = p;
                    self.span = span;
                    StepOutcome {
                        collided: false,
                        moved,
                    }
                }
                None => StepOutcome {
                    collided: true,
                    moved: 0.0,
                },
            },
        }
    }

    /// Where a forward move would end (position and span), or `None` when it
    /// is blocked. Does not change the agent.
    ///
    /// # Complexity
    /// O(step / cell size).
    pub fn try_forward(&self, nav: &NavMesh) -> Option<(Point3<f64>, SpanId)> {
        let (s, c) = self.yaw.sin_cos();
        let step = self.config.forward_step;
        let end = Point3::new(
            self.position.x + step * c,
            self.position.y + step * s,
            self.position.z,
        );
        walk_segment(nav, self.span, &self.position, &end)
    }
}

/// Follows the straight horizontal segment `from -> to` over connected spans
/// starting at `start`; returns the end point (at the surface height of its
/// span) and span, or `None` when the segment leaves the walkable surface.
///
/// The segment is sampled at a quarter of the cell size; every change of
/// column must reach a connected neighbour span (a diagonal change through
/// either orthogonal neighbour).
///
/// # Complexity
/// O(length / cell size).
pub fn walk_segment(
    nav: &NavMesh,
    start: SpanId,
    from: &Point3<f64>,
    to: &Point3<f64>,
) -> Option<(Point3<f64>, SpanId)> {
    let cs = nav.config().cell_size;
    let origin = nav.origin();
    let col = |x: f64, y: f64| {
        (
            ((x - origin.x) / cs).floor() as i64,
            ((y - origin.y) / cs).floor() as i64,
        )
    };
    let len = (to.xy() - from.xy()).norm();
    if !len.is_finite() {
        return None;
    }
    let n = ((len / (cs * 0.25)).ceil() as usize).max(1);
    let mut span = start;
    let (sx, sy) = nav.span_cell(start);
    let mut cur = (sx as i64, sy as i64);
    for k in 1..=n {
        let t = k as f64 / n as f64;
        let (x, y) = (from.x + (to.x - from.x) * t, from.y + (to.y - from.y) * t);
        let next = col(x, y);
        if next == cur {
            continue;
        }
        let (dx, dy) = (next.0 - cur.0, next.1 - cur.1);
        span = if dx.abs() + dy.abs() == 1 {
            neighbour_towards(nav, span, dx, dy)?
        } else if dx.abs() == 1 && dy.abs() == 1 {
            neighbour_towards(nav, span, dx, 0)
                .and_then(|m| neighbour_towards(nav, m, 0, dy))
                .or_else(|| {
                    neighbour_towards(nav, span, 0, dy)
                        .and_then(|m| neighbour_towards(nav, m, dx, 0))
                })?
        } else {
            // Sampling at a quarter cell never skips a column.
            return None;
        };
        cur = next;
    }
    let floor = f64::from(nav.spans()[span as usize].floor);
    Some((Point3::new(to.x, to.y, floor), span))
}

/// The connected neighbour of `s` in grid direction (dx, dy) (one of the four).
fn neighbour_towards(nav: &NavMesh, s: SpanId, dx: i64, dy: i64) -> Option<SpanId> {
    let d = DIRS
        .iter()
        .position(|&(ex, ey)| i64::from(ex) == dx && i64::from(ey) == dy)?;
    let n = nav.spans()[s as usize].neighbours[d];
    (n != u32::MAX).then_some(n)
}

/// Wraps an angle to (-pi, pi].
pub fn wrap_angle(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let mut w = a.rem_euclid(t);
    if w > std::f64::consts::PI {
        w -= t;
    }
    w
}
