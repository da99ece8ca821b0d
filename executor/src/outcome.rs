//! Mission outcomes and executor events.

use std::time::Duration;

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::{ClusterId, MissionId, MissionKind};

/// Why a mission failed. Each detector has its own reason.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum FailureReason {
    /// The remaining distance along the path decreased by no more than the
    /// configured distance within the configured window.
    Stuck {
        /// Progress made during the last window, metres.
        progress_m: f64,
    },
    /// The mission ran longer than its kind's timeout.
    Timeout {
        /// Time since the mission started.
        elapsed: Duration,
    },
    /// The map reported the path as no longer executable.
    PathInvalidated,
    /// The motion stack refused the mission.
    DispatchFailed(String),
}

/// How a mission ended. A mission is `Active` until exactly one of these is
/// emitted for it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum MissionStatus {
    /// The arrival rule held.
    Reached,
    /// A failure detector fired.
    Failed(FailureReason),
    /// Replaced by another mission (`by`), or cancelled by the caller
    /// (`by = None`).
    Preempted {
        /// The mission that replaced it.
        by: Option<MissionId>,
    },
}

/// The end of one mission.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissionOutcome {
    /// The mission.
    pub id: MissionId,
    /// Its kind.
    pub kind: MissionKind,
    /// How it ended.
    pub status: MissionStatus,
    /// Clock reading when it ended.
    pub at: Duration,
}

impl MissionOutcome {
    /// Whether this outcome means the robot reached a target candidate (a
    /// `NavToObject` mission reached, heading included): the signal for
    /// target verification. Reaching a relocation or exploration waypoint is
    /// never a target arrival.
    pub fn is_target_arrival(&self) -> bool {
        matches!(self.kind, MissionKind::NavToObject { .. })
            && self.status == MissionStatus::Reached
    }
}

/// What the executor reports to its caller (drained with
/// [`Executor::drain_events`](crate::Executor::drain_events)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ExecutorEvent {
    /// A mission ended (emitted exactly once per admitted mission).
    Finished(MissionOutcome),
    /// A relocation was completed: plan global exploration from the new
    /// region now. Always immediately follows the relocation's `Reached`
    /// outcome.
    ExploreFromRegion {
        /// The completed relocation.
        after: MissionId,
        /// The region reached.
        cluster: ClusterId,
        /// Robot position on arrival.
        position: Point3<f64>,
    },
}
