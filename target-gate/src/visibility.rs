//! Caller-provided visibility test for negative evidence.

use nalgebra::Point3;

use crate::ObjectId;

/// Answers whether a candidate's location was inside the sensor's view at the
/// current update (in the field of view, within range, not occluded).
///
/// Used only when [`GateConfig::negative_evidence`](crate::GateConfig::negative_evidence)
/// is on: a tracked candidate that was in view but not detected then counts as
/// a miss. Closures `Fn(ObjectId, &Point3<f64>) -> bool` implement it.
pub trait Visibility {
    /// Whether `object`, centred at `centre`, was in view at this update.
    fn in_view(&self, object: ObjectId, centre: &Point3<f64>) -> bool;
}

impl<F> Visibility for F
where
    F: Fn(ObjectId, &Point3<f64>) -> bool,
{
    fn in_view(&self, object: ObjectId, centre: &Point3<f64>) -> bool {
        self(object, centre)
    }
}

/// A [`Visibility`] that never reports anything in view (no negative
/// evidence).
#[derive(Debug, Clone, Copy, Default)]
pub struct NeverVisible;

impl Visibility for NeverVisible {
    fn in_view(&self, _object: ObjectId, _centre: &Point3<f64>) -> bool {
        false
    }
}
