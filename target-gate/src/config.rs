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
        }
    }
}

impl GateConfig {
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
