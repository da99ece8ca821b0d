//! Time sources: simulated steps or wall time.

use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

/// A monotone time source. The executor only compares and subtracts its
/// readings, so the origin is arbitrary.
///
/// Closures `Fn() -> Duration` implement it.
pub trait Clock {
    /// Time elapsed since the clock's origin.
    fn now(&self) -> Duration;
}

impl<F: Fn() -> Duration> Clock for F {
    fn now(&self) -> Duration {
        self()
    }
}

/// Simulated time: a step counter times a fixed step duration (for example
/// one discrete simulator action).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SimClock {
    steps: u64,
    step: Duration,
}

impl SimClock {
    /// A clock at step 0 whose steps last `step`.
    pub fn new(step: Duration) -> Self {
        Self { steps: 0, step }
    }

    /// Advances by `n` steps.
    pub fn advance(&mut self, n: u64) {
        self.steps = self.steps.saturating_add(n);
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }
}

impl Clock for SimClock {
    fn now(&self) -> Duration {
        let steps = u32::try_from(self.steps).unwrap_or(u32::MAX);
        self.step.saturating_mul(steps)
    }
}

/// Wall time since the clock was created.
#[derive(Debug, Clone, Copy)]
pub struct WallClock {
    origin: Instant,
}

impl WallClock {
    /// A clock whose origin is now.
    pub fn new() -> Self {
        Self {
            origin: Instant::now(),
        }
    }
}

impl Default for WallClock {
    fn default() -> Self {
        Self::new()
    }
}

impl Clock for WallClock {
    fn now(&self) -> Duration {
        self.origin.elapsed()
    }
}
