//! What platforms implement, and the map's path-validity callback.

use crate::{Mission, MotionError};

/// A platform's motion stack (a discrete-action simulator controller, a ROS
/// waypoint publisher, ...).
///
/// The executor calls [`dispatch`](Self::dispatch) when a mission starts or
/// its waypoint/path is updated, and [`cancel`](Self::cancel) when the active
/// mission ends for any reason other than being replaced by a newly
/// dispatched one.
pub trait MotionStack {
    /// Starts moving toward `mission`'s waypoint (replacing any previous
    /// mission).
    ///
    /// # Errors
    /// [`MotionError`] when the platform cannot accept it; the mission then
    /// fails with [`FailureReason::DispatchFailed`](crate::FailureReason::DispatchFailed).
    fn dispatch(&mut self, mission: &Mission) -> Result<(), MotionError>;
    /// Stops pursuing the current mission.
    fn cancel(&mut self);
}

impl<M: MotionStack + ?Sized> MotionStack for &mut M {
    fn dispatch(&mut self, mission: &Mission) -> Result<(), MotionError> {
        (**self).dispatch(mission)
    }
    fn cancel(&mut self) {
        (**self).cancel();
    }
}

/// Asks the map whether the active mission's path is still executable (for
/// example, no newly observed obstacle blocks it). Closures
/// `Fn(&Mission) -> bool` implement it.
pub trait PathValidity {
    /// Whether `mission` can still be executed as dispatched.
    fn still_valid(&self, mission: &Mission) -> bool;
}

impl<F: Fn(&Mission) -> bool> PathValidity for F {
    fn still_valid(&self, mission: &Mission) -> bool {
        self(mission)
    }
}

/// A [`PathValidity`] that never invalidates anything.
#[derive(Debug, Clone, Copy, Default)]
pub struct AlwaysValid;

impl PathValidity for AlwaysValid {
    fn still_valid(&self, _mission: &Mission) -> bool {
        true
    }
}
