//! The generic clock of the supervisor's state machine.
//!
//! The robot runs on [`std::time::Instant`]; the simulator on its own
//! simulated time ([`std::time::Duration`] since the episode start, or `f64`
//! seconds). Algorithm 1 only needs elapsed seconds between two readings.

use std::time::{Duration, Instant};

/// A point in time of some clock.
pub trait Timestamp: Copy {
    /// Seconds from `earlier` to `self`. Implementations saturate at zero
    /// when the clock went backwards; the result may be NaN only for `f64`
    /// readings that are themselves NaN (the supervisor rejects those).
    fn seconds_since(&self, earlier: &Self) -> f64;
}

impl Timestamp for Instant {
    fn seconds_since(&self, earlier: &Self) -> f64 {
        self.saturating_duration_since(*earlier).as_secs_f64()
    }
}

impl Timestamp for Duration {
    fn seconds_since(&self, earlier: &Self) -> f64 {
        self.saturating_sub(*earlier).as_secs_f64()
    }
}

impl Timestamp for f64 {
    fn seconds_since(&self, earlier: &Self) -> f64 {
        let d = self - earlier;
        if d < 0.0 { 0.0 } else { d }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clocks_saturate_backwards() {
        assert_eq!(
            Duration::from_secs(1).seconds_since(&Duration::from_secs(3)),
            0.0
        );
        assert_eq!(1.0_f64.seconds_since(&3.0), 0.0);
        assert_eq!(3.5_f64.seconds_since(&1.0), 2.5);
        let t = Instant::now();
        assert_eq!(t.seconds_since(&t), 0.0);
        assert!(f64::NAN.seconds_since(&0.0).is_nan());
    }
}
