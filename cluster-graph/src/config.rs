//! Parameters of clustering, ranking and semantic contexts.

use serde::{Deserialize, Serialize};

use crate::ClusterError;

/// Largest accepted spread weight [`ClusterConfig::eta`]: keeps
/// `n (1 + eta r)` finite for every accepted position.
pub const MAX_ETA: f64 = 1.0e6;

/// Parameters of SOR-Nav's cluster graph and semantic contexts (paper
/// defaults in [`ClusterConfig::default`]).
///
/// Serialisable so that agent configurations can be stored with their runs.
///
/// # Example
/// ```
/// use sornav_cluster_graph::ClusterConfig;
///
/// let config = ClusterConfig { rho_c: 15.0, ..ClusterConfig::default() };
/// assert!(config.validate().is_ok());
/// assert_eq!(config.top_k, 10);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ClusterConfig {
    /// `rho_c`: two frontiers belong to the same cluster when a chain of
    /// frontier-graph edges, each of cost `<= rho_c`, joins them (graph-cost
    /// units; metres of path in the simulator). Default 25.0.
    pub rho_c: f64,
    /// `eta`: weight of the spread in `U_geo = n (1 + eta r) / (1 + d)`.
    /// Default 0.1; accepted range `[0, MAX_ETA]`.
    pub eta: f64,
    /// `K`: number of clusters, best `U_geo` first, passed on to the
    /// supervisor. Default 10; must be at least 1.
    pub top_k: usize,
    /// `N_min`: minimum support (voxels) of an object to enter a semantic
    /// context. Default 10.
    pub n_min: usize,
    /// `R_s`: radius (m, horizontal) of a cluster's semantic context, measured
    /// from the object centre to the nearest member frontier. Default 10.
    pub r_s: f64,
    /// `R_r`: radius (m, horizontal) of the robot's semantic context. Default 10.
    pub r_r: f64,
}

impl Default for ClusterConfig {
    fn default() -> Self {
        Self {
            rho_c: 25.0,
            eta: 0.1,
            top_k: 10,
            n_min: 10,
            r_s: 10.0,
            r_r: 10.0,
        }
    }
}

impl ClusterConfig {
    /// Checks every parameter against its documented range.
    ///
    /// # Errors
    /// [`ClusterError::InvalidConfig`] naming the first offending parameter:
    /// `rho_c`, `r_s` and `r_r` must be finite and `>= 0`, `eta` in
    /// `[0, MAX_ETA]`, `top_k >= 1`.
    pub fn validate(&self) -> Result<(), ClusterError> {
        let non_negative = |name: &str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(ClusterError::InvalidConfig(format!(
                    "{name} must be finite and >= 0, got {v}"
                )))
            }
        };
        non_negative("rho_c", self.rho_c)?;
        non_negative("r_s", self.r_s)?;
        non_negative("r_r", self.r_r)?;
        if !(0.0..=MAX_ETA).contains(&self.eta) {
            return Err(ClusterError::InvalidConfig(format!(
                "eta must be in [0, {MAX_ETA}], got {}",
                self.eta
            )));
        }
        if self.top_k == 0 {
            return Err(ClusterError::InvalidConfig("top_k must be >= 1".into()));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_papers_and_valid() {
        let c = ClusterConfig::default();
        assert_eq!((c.rho_c, c.eta, c.top_k, c.n_min), (25.0, 0.1, 10, 10));
        assert_eq!((c.r_s, c.r_r), (10.0, 10.0));
        assert!(c.validate().is_ok());
    }

    #[test]
    fn rejects_out_of_range_values() {
        let d = ClusterConfig::default();
        for bad in [
            ClusterConfig {
                rho_c: f64::NAN,
                ..d
            },
            ClusterConfig { rho_c: -1.0, ..d },
            ClusterConfig {
                rho_c: f64::INFINITY,
                ..d
            },
            ClusterConfig { eta: -0.1, ..d },
            ClusterConfig { eta: f64::NAN, ..d },
            ClusterConfig {
                eta: 2.0 * MAX_ETA,
                ..d
            },
            ClusterConfig { top_k: 0, ..d },
            ClusterConfig { r_s: f64::NAN, ..d },
            ClusterConfig { r_r: -3.0, ..d },
        ] {
            assert!(
                matches!(bad.validate(), Err(ClusterError::InvalidConfig(_))),
                "{bad:?}"
            );
        }
    }

    #[test]
    fn serde_fills_missing_fields_with_defaults() {
        let c: ClusterConfig = serde_json::from_str(r#"{"rho_c": 12.5}"#).unwrap();
        assert_eq!(c.rho_c, 12.5);
        assert_eq!(c.top_k, 10);
        assert!(serde_json::from_str::<ClusterConfig>(r#"{"rho": 1}"#).is_err());
    }
}
