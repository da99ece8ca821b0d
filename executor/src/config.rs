//! Executor parameters.

use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::{ExecError, MissionKind};

/// When a mission counts as reached, computed from the robot pose (the CMU
/// autonomy stack gives no "reached" signal).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ArrivalRule {
    /// Maximum horizontal distance from the robot to the waypoint, metres.
    pub radius_m: f64,
    /// Maximum vertical offset between robot and waypoint, metres (keeps a
    /// waypoint on another floor from counting as reached).
    pub vertical_tolerance_m: f64,
    /// When set, and the mission has a [`look_at`](crate::Mission::look_at)
    /// point, the robot's heading must point at it within this many radians.
    pub heading_tolerance_rad: Option<f64>,
}

impl ArrivalRule {
    fn validate(&self) -> Result<(), ExecError> {
        if !(self.radius_m.is_finite() && self.radius_m > 0.0) {
            return Err(ExecError::InvalidConfig(
                "arrival radius must be finite and > 0",
            ));
        }
        if !(self.vertical_tolerance_m.is_finite() && self.vertical_tolerance_m >= 0.0) {
            return Err(ExecError::InvalidConfig(
                "vertical tolerance must be finite and >= 0",
            ));
        }
        if let Some(h) = self.heading_tolerance_rad
            && !(h.is_finite() && h > 0.0 && h <= std::f64::consts::PI)
        {
            return Err(ExecError::InvalidConfig(
                "heading tolerance must be in (0, pi]",
            ));
        }
        Ok(())
    }
}

/// Parameters of one mission kind.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct KindConfig {
    /// Arrival test.
    pub arrival: ArrivalRule,
    /// Mission timeout in seconds of the executor's clock (`None`: no
    /// timeout).
    pub timeout_s: Option<f64>,
}

/// Parameters of the [`Executor`](crate::Executor).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ExecutorConfig {
    /// Parameters of `Explore` missions.
    pub explore: KindConfig,
    /// Parameters of `Relocate` missions.
    pub relocate: KindConfig,
    /// Parameters of `NavToObject` missions.
    pub nav_to_object: KindConfig,
    /// Stuck detection: the mission fails when the remaining distance along
    /// the path decreased by no more than this many metres ...
    pub stuck_progress_m: f64,
    /// ... within this many seconds.
    pub stuck_window_s: f64,
}

impl Default for ExecutorConfig {
    fn default() -> Self {
        Self {
            explore: KindConfig {
                arrival: ArrivalRule {
                    radius_m: 1.0,
                    vertical_tolerance_m: 1.0,
                    heading_tolerance_rad: None,
                },
                timeout_s: Some(120.0),
            },
            relocate: KindConfig {
                arrival: ArrivalRule {
                    radius_m: 1.5,
                    vertical_tolerance_m: 1.0,
                    heading_tolerance_rad: None,
                },
                timeout_s: Some(180.0),
            },
            nav_to_object: KindConfig {
                arrival: ArrivalRule {
                    radius_m: 0.5,
                    vertical_tolerance_m: 1.0,
                    // 20 degrees: reachable with the simulator's 30-degree turns.
                    heading_tolerance_rad: Some(20f64.to_radians()),
                },
                timeout_s: Some(90.0),
            },
            stuck_progress_m: 0.5,
            stuck_window_s: 15.0,
        }
    }
}

impl ExecutorConfig {
    /// The parameters of `kind`.
    pub fn for_kind(&self, kind: &MissionKind) -> &KindConfig {
        match kind {
            MissionKind::Explore { .. } => &self.explore,
            MissionKind::Relocate { .. } => &self.relocate,
            MissionKind::NavToObject { .. } => &self.nav_to_object,
        }
    }

    /// Checks every parameter.
    ///
    /// # Errors
    /// [`ExecError::InvalidConfig`] naming the first bad parameter.
    pub fn validate(&self) -> Result<(), ExecError> {
        for kind in [&self.explore, &self.relocate, &self.nav_to_object] {
            kind.arrival.validate()?;
            if let Some(t) = kind.timeout_s
                && !(t.is_finite() && t > 0.0 && Duration::try_from_secs_f64(t).is_ok())
            {
                return Err(ExecError::InvalidConfig(
                    "timeout must be finite, > 0 and representable as a Duration",
                ));
            }
        }
        if !(self.stuck_progress_m.is_finite() && self.stuck_progress_m >= 0.0) {
            return Err(ExecError::InvalidConfig(
                "stuck progress must be finite and >= 0",
            ));
        }
        if !(self.stuck_window_s.is_finite()
            && self.stuck_window_s > 0.0
            && Duration::try_from_secs_f64(self.stuck_window_s).is_ok())
        {
            return Err(ExecError::InvalidConfig(
                "stuck window must be finite, > 0 and representable as a Duration",
            ));
        }
        Ok(())
    }
}
