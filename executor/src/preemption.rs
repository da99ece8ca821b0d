//! SOR-Nav's pre-emption rules.

use serde::{Deserialize, Serialize};

use crate::MissionKind;

/// What to do with a new mission given the active one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Admission {
    /// No mission is active: start the new one.
    Start,
    /// Same kind and same target: keep the mission (and its id and timeout),
    /// take the new waypoint and path.
    Update,
    /// The new mission replaces the active one, which ends `Preempted`.
    Preempt,
    /// The active mission keeps running; the new one is refused.
    Refuse(RefusalReason),
}

/// Why a mission was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum RefusalReason {
    /// An active relocation is not interrupted by exploration decisions.
    RelocationActive,
    /// Target pursuit (`NavToObject`) is not interrupted by exploration or
    /// relocation; end it explicitly with
    /// [`Executor::cancel`](crate::Executor::cancel) first.
    TargetPursuitActive,
}

/// The pre-emption rules, as a truth table over (active, new):
///
/// | active \ new | Explore | Relocate | NavToObject |
/// |---|---|---|---|
/// | none | start | start | start |
/// | Explore | update (same frontier) / pre-empt | pre-empt | pre-empt |
/// | Relocate | refuse | update (same cluster) / pre-empt | pre-empt |
/// | NavToObject | refuse | refuse | update (same object) / pre-empt |
///
/// `NavToObject` pre-empts everything (target evidence first); an active
/// `Relocate` is not interrupted by exploration decisions; a new decision of
/// the same kind for a different target replaces the active one (receding
/// horizon re-planning, a new relocation decision, a new candidate).
///
/// # Complexity
/// `O(1)`.
pub fn admit(active: Option<&MissionKind>, new: &MissionKind) -> Admission {
    use MissionKind::{Explore, NavToObject, Relocate};
    let Some(active) = active else {
        return Admission::Start;
    };
    if active == new {
        return Admission::Update;
    }
    match (active, new) {
        (Relocate { .. }, Explore { .. }) => Admission::Refuse(RefusalReason::RelocationActive),
        (NavToObject { .. }, Explore { .. } | Relocate { .. }) => {
            Admission::Refuse(RefusalReason::TargetPursuitActive)
        }
        _ => Admission::Preempt,
    }
}
