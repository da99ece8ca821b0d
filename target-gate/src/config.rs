//! Gate parameters.

use serde::{Deserialize, Serialize};

use crate::GateError;

/// Parameters of the target gate.
///
/// Defaults are the paper's (`N_min = 10`, `N_obs = 3`, `N_miss = 5`, negative
/// evidence off) plus two protocol parameters of this implementation
/// ([`verify_window`](Self::verify_window) and
/// [`reject_cooldown`](Self::reject_cooldown)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct GateConfig {
    /// `N_min`: minimum voxel count for a cluster of the requested category to
    /// be a valid candidate.
    pub n_min: u32,
    /// `N_obs`: supporting observations needed (`s_t >= N_obs`). At least 1.
    pub n_obs: u32,
    /// `N_miss`: consecutive misses tolerated (`m_t <= N_miss`); a candidate
    /// with `m_t > N_miss` expires.
    pub n_miss: u32,
    /// Negative evidence: when on, an update in which a tracked candidate's
    /// location was inside the sensor's view (according to the caller's
    /// [`Visibility`](crate::Visibility) callback) but the candidate was not
    /// detected counts as a miss. Off by default.
    pub negative_evidence: bool,
    /// Number of gate updates after arrival within which a fresh detection of
    /// the candidate must arrive (`b_nav`); otherwise the candidate is
    /// rejected. At least 1.
    pub verify_window: u32,
    /// Number of gate updates during which a rejected candidate may not be
    /// selected again.
    pub reject_cooldown: u32,
    /// Navigation verification (`b_nav`): on arrival a fresh detection
    /// within [`verify_window`](Self::verify_window) updates must confirm
    /// the candidate. Off, arrival confirms it at once. On by default (the
    /// paper's gate); [`GateConfig::first_sight`] turns it off.
    pub verify_on_arrival: bool,
}

impl Default for GateConfig {
    fn default() -> Self {
        Self {
            n_min: 10,
            n_obs: 3,
            n_miss: 5,
            negative_evidence: false,
            verify_window: 3,
            reject_cooldown: 30,
            verify_on_arrival: true,
        }
    }
}

impl GateConfig {
    /// No gate: the first detection of a candidate (with at least `N_min`
    /// voxels) selects it, misses never expire it (`N_miss = u32::MAX`), and
    /// arrival confirms it without a fresh detection
    /// ([`verify_on_arrival`](Self::verify_on_arrival) off). `n_min` and the
    /// cool-down of a failed approach are kept from `self`. The ablation of
    /// the gate against a sensor that lies.
    ///
    /// # Example
    /// ```
    /// use sornav_target_gate::GateConfig;
    /// let c = GateConfig::default().first_sight();
    /// assert_eq!((c.n_obs, c.n_miss, c.verify_on_arrival), (1, u32::MAX, false));
    /// ```
    #[must_use]
    pub fn first_sight(self) -> Self {
        Self {
            n_obs: 1,
            n_miss: u32::MAX,
            verify_on_arrival: false,
            ..self
        }
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`GateError::InvalidConfig`] when `n_obs` or `verify_window` is zero.
    pub fn validate(&self) -> Result<(), GateError> {
        if self.n_obs == 0 {
            return Err(GateError::InvalidConfig("n_obs must be at least 1"));
        }
        if self.verify_window == 0 {
            return Err(GateError::InvalidConfig("verify_window must be at least 1"));
        }
        Ok(())
    }
}
