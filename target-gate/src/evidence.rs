//! The two evidence recursions `s_t` and `m_t`, and the success condition.

use serde::{Deserialize, Serialize};

use crate::GateConfig;

/// Evidence kept for one candidate: supporting observations and consecutive
/// misses.
///
/// With `z_t = 1` when the candidate is present at update `t`:
///
/// * `s_t = s_{t-1} + z_t`
/// * `m_t = 0` if `z_t = 1`, else `m_{t-1} + 1`
///
/// Both counters saturate at `u32::MAX` instead of overflowing.
///
/// # Complexity
/// `O(1)` per update.
///
/// # Example
/// ```
/// use sornav_target_gate::Evidence;
/// let mut e = Evidence::default();
/// for z in [true, false, true, true, false] {
///     e.observe(z);
/// }
/// assert_eq!((e.support, e.misses), (3, 1));
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Evidence {
    /// `s_t`: number of supporting observations so far.
    pub support: u32,
    /// `m_t`: number of consecutive misses since the last supporting
    /// observation.
    pub misses: u32,
}

impl Evidence {
    /// Applies one update with observation `z` (`true` for `z_t = 1`).
    pub fn observe(&mut self, z: bool) {
        if z {
            self.support = self.support.saturating_add(1);
            self.misses = 0;
        } else {
            self.misses = self.misses.saturating_add(1);
        }
    }

    /// Whether the evidence part of the success condition holds:
    /// `s_t >= N_obs` and `m_t <= N_miss`.
    pub fn qualifies(&self, config: &GateConfig) -> bool {
        self.support >= config.n_obs && self.misses <= config.n_miss
    }

    /// Whether the candidate has expired: `m_t > N_miss`.
    pub fn expired(&self, config: &GateConfig) -> bool {
        self.misses > config.n_miss
    }
}

/// The final success condition: `s_t >= N_obs`, `m_t <= N_miss` and
/// `b_nav = 1`.
///
/// # Example
/// ```
/// use sornav_target_gate::{success, Evidence, GateConfig};
/// let cfg = GateConfig::default();
/// let e = Evidence { support: 3, misses: 0 };
/// assert!(success(&e, true, &cfg));
/// assert!(!success(&e, false, &cfg)); // never without navigation verification
/// ```
pub fn success(evidence: &Evidence, b_nav: bool, config: &GateConfig) -> bool {
    b_nav && evidence.qualifies(config)
}
