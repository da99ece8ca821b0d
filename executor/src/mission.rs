//! Missions and robot poses.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::{ClusterId, ExecError, FrontierId, ObjectId};

/// What a mission is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum MissionKind {
    /// Explore a frontier of the current region.
    Explore {
        /// The frontier.
        frontier: FrontierId,
    },
    /// Relocate to another region (frontier cluster).
    Relocate {
        /// The destination cluster.
        cluster: ClusterId,
    },
    /// Navigate to a target candidate.
    NavToObject {
        /// The object cluster.
        object: ObjectId,
    },
}

impl MissionKind {
    /// Short name (`"explore"`, `"relocate"`, `"nav_to_object"`).
    pub fn name(&self) -> &'static str {
        match self {
            MissionKind::Explore { .. } => "explore",
            MissionKind::Relocate { .. } => "relocate",
            MissionKind::NavToObject { .. } => "nav_to_object",
        }
    }

    /// Whether both kinds are the same variant.
    pub fn same_variant(&self, other: &MissionKind) -> bool {
        std::mem::discriminant(self) == std::mem::discriminant(other)
    }
}

/// A mission: a kind, a waypoint, an executable path when one is known, and
/// for object approaches the point to face on arrival.
///
/// Coordinates are world-frame metres, z up.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Mission {
    /// What the mission is for.
    pub kind: MissionKind,
    /// Where to go.
    pub waypoint: Point3<f64>,
    /// Executable path from (near) the robot to the waypoint, when known.
    /// Progress is measured along it.
    pub path: Option<Vec<Point3<f64>>>,
    /// Point the robot must face on arrival when the kind's
    /// [`ArrivalRule::heading_tolerance_rad`](crate::ArrivalRule::heading_tolerance_rad)
    /// is set (typically the object centre of a `NavToObject`).
    pub look_at: Option<Point3<f64>>,
    /// A tighter arrival radius (m) than the kind's
    /// [`ArrivalRule::radius_m`](crate::ArrivalRule::radius_m), for a
    /// mission whose end point matters (a view point of a confirmed
    /// target); the smaller of the two applies.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub arrival_radius_m: Option<f64>,
}

impl Mission {
    /// A mission without path and without facing requirement.
    pub fn new(kind: MissionKind, waypoint: Point3<f64>) -> Self {
        Self {
            kind,
            waypoint,
            path: None,
            look_at: None,
            arrival_radius_m: None,
        }
    }

    /// Sets the executable path.
    pub fn with_path(mut self, path: Vec<Point3<f64>>) -> Self {
        self.path = Some(path);
        self
    }

    /// Sets the point to face on arrival.
    pub fn with_look_at(mut self, look_at: Point3<f64>) -> Self {
        self.look_at = Some(look_at);
        self
    }

    /// Sets a tighter arrival radius (see the field).
    pub fn with_arrival_radius(mut self, radius_m: f64) -> Self {
        self.arrival_radius_m = Some(radius_m);
        self
    }

    /// Checks that every coordinate is finite, a given path is not empty
    /// and a given arrival radius is finite and positive.
    ///
    /// # Errors
    /// [`ExecError::InvalidMission`].
    pub fn validate(&self) -> Result<(), ExecError> {
        if !finite(&self.waypoint) {
            return Err(ExecError::InvalidMission("non-finite waypoint"));
        }
        if self.look_at.as_ref().is_some_and(|p| !finite(p)) {
            return Err(ExecError::InvalidMission("non-finite look_at point"));
        }
        if self
            .arrival_radius_m
            .is_some_and(|r| !(r.is_finite() && r > 0.0))
        {
            return Err(ExecError::InvalidMission(
                "arrival radius must be finite and > 0",
            ));
        }
        match &self.path {
            Some(path) if path.is_empty() => Err(ExecError::InvalidMission("empty path")),
            Some(path) if !path.iter().all(finite) => {
                Err(ExecError::InvalidMission("non-finite path point"))
            }
            _ => Ok(()),
        }
    }
}

/// The robot's pose as the executor needs it: position and heading.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RobotPose {
    /// Position (world frame, metres, z up).
    pub position: Point3<f64>,
    /// Heading: angle of the robot's forward axis about world z, from world x,
    /// in radians.
    pub yaw: f64,
}

impl RobotPose {
    /// A pose from position and yaw.
    pub fn new(position: Point3<f64>, yaw: f64) -> Self {
        Self { position, yaw }
    }

    /// Whether every component is finite.
    pub fn is_finite(&self) -> bool {
        finite(&self.position) && self.yaw.is_finite()
    }
}

pub(crate) fn finite(p: &Point3<f64>) -> bool {
    p.x.is_finite() && p.y.is_finite() && p.z.is_finite()
}
