//! The verification protocol: phases, commands and events.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::ObjectId;

/// Where the verification protocol stands.
///
/// ```text
///  Search --select--> Approach --arrived--> Verify --fresh detection--> Confirmed (STOP)
///    ^                   |                    |
///    +----- rejected / abandoned -------------+
/// ```
///
/// The paper's steps map as follows: *candidate* is selection
/// ([`GateEvent::Selected`]); *approach* is [`Phase::Approach`]
/// ([`GateCommand::NavToObject`]); *arrived* is the caller's
/// [`TargetGate::on_arrived`](crate::TargetGate::on_arrived)
/// ([`GateEvent::Arrived`]), normally on a `NavToObject` mission reached with
/// its heading requirement, i.e. in the neighbourhood and facing the cluster;
/// *verify* is [`Phase::Verify`] ([`GateCommand::Verify`]: a fresh
/// observation is requested); *confirmed* is [`Phase::Confirmed`]
/// ([`GateCommand::Stop`]); *rejected* returns to [`Phase::Search`] with the
/// candidate marked ([`GateEvent::Rejected`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Phase {
    /// No candidate qualifies (or none was selected yet): keep searching.
    Search,
    /// A qualifying candidate was selected; the platform should navigate to
    /// it (a `NAV_TO_OBJECT` mission).
    Approach {
        /// The candidate.
        object: ObjectId,
    },
    /// The platform arrived in the candidate's neighbourhood and faces it; a
    /// fresh detection is awaited.
    Verify {
        /// The candidate.
        object: ObjectId,
        /// Update index at which arrival was reported; only later updates are
        /// fresh.
        arrived_at: u64,
        /// Last update index at which a fresh detection is accepted.
        deadline: u64,
    },
    /// Success condition met: the episode may stop.
    Confirmed {
        /// The confirmed object.
        object: ObjectId,
        /// Its centre when it was confirmed.
        centre: Point3<f64>,
    },
}

impl Phase {
    /// Short name of the phase.
    pub fn name(&self) -> &'static str {
        match self {
            Phase::Search => "search",
            Phase::Approach { .. } => "approach",
            Phase::Verify { .. } => "verify",
            Phase::Confirmed { .. } => "confirmed",
        }
    }

    /// The candidate the phase is about, if any.
    pub fn object(&self) -> Option<ObjectId> {
        match *self {
            Phase::Search => None,
            Phase::Approach { object }
            | Phase::Verify { object, .. }
            | Phase::Confirmed { object, .. } => Some(object),
        }
    }
}

/// What the gate asks of the rest of the system.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum GateCommand {
    /// No target to pursue: exploration / relocation decide.
    Search,
    /// Navigate to the candidate (pre-empts exploration).
    NavToObject {
        /// The candidate.
        object: ObjectId,
        /// Its current centre.
        centre: Point3<f64>,
    },
    /// Stay in the neighbourhood, face the candidate and provide a fresh
    /// observation.
    Verify {
        /// The candidate.
        object: ObjectId,
        /// Its current centre (look at it).
        centre: Point3<f64>,
    },
    /// Target confirmed: stop.
    Stop {
        /// The confirmed object.
        object: ObjectId,
        /// Its centre.
        centre: Point3<f64>,
    },
}

/// Why a candidate was rejected (and marked so that it is not re-selected
/// immediately).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RejectReason {
    /// No fresh detection within the verification window after arrival.
    NotSeenOnVerification,
    /// The caller reported that navigation to the candidate failed.
    ApproachFailed,
}

/// Why the protocol dropped a candidate without marking it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum AbandonReason {
    /// Its misses exceeded `N_miss`; the candidate no longer exists.
    Expired,
    /// The map split its cluster; the parts are re-evaluated.
    Split,
}

/// Something that happened in the gate, for the caller and for logs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum GateEvent {
    /// A candidate started being tracked.
    Tracked(ObjectId),
    /// A candidate expired (`m_t > N_miss`).
    Expired(ObjectId),
    /// A candidate was selected for approach.
    Selected(ObjectId),
    /// Arrival at the candidate was reported; verification started.
    Arrived(ObjectId),
    /// The success condition held: stop.
    Confirmed(ObjectId),
    /// The candidate under approach or verification was rejected.
    Rejected {
        /// The candidate.
        object: ObjectId,
        /// Why.
        reason: RejectReason,
    },
    /// The candidate under approach or verification was dropped.
    Abandoned {
        /// The candidate.
        object: ObjectId,
        /// Why.
        reason: AbandonReason,
    },
    /// The candidate under approach or verification changed id in a remap.
    Followed {
        /// Old id.
        from: ObjectId,
        /// New id.
        to: ObjectId,
    },
}
