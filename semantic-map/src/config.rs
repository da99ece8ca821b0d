//! Map configuration.

use serde::{Deserialize, Serialize};

use crate::error::MapError;

/// Configuration of a [`SemanticMap`](crate::SemanticMap). Serde-serialisable;
/// validated by [`MapConfig::validate`] (and by every constructor).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MapConfig {
    /// Voxel edge length in metres (paper default 0.05 m).
    pub resolution: f64,
    /// Points closer than this to the sensor origin are rejected (metres).
    pub min_range: f64,
    /// Points farther than this from the sensor origin are rejected (metres).
    pub max_range: f64,
    /// Points with any world coordinate of larger magnitude are rejected as
    /// absurd (metres). Must keep voxel indices well inside `i32`.
    pub max_abs_coordinate: f64,
}

impl Default for MapConfig {
    fn default() -> Self {
        Self {
            resolution: 0.05,
            min_range: 0.0,
            max_range: 50.0,
            max_abs_coordinate: 100_000.0,
        }
    }
}

impl MapConfig {
    /// The default configuration with another resolution.
    pub fn with_resolution(resolution: f64) -> Self {
        Self {
            resolution,
            ..Self::default()
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`MapError::InvalidConfig`] naming the first bad field.
    pub fn validate(&self) -> Result<(), MapError> {
        let bad = |m: &str| Err(MapError::InvalidConfig(m.to_owned()));
        if !(self.resolution.is_finite() && self.resolution > 1e-6) {
            return bad("resolution must be finite and > 1e-6 m");
        }
        if !(self.min_range.is_finite() && self.min_range >= 0.0) {
            return bad("min_range must be finite and >= 0");
        }
        if self.max_range.is_nan() || self.max_range <= self.min_range {
            return bad("max_range must be > min_range");
        }
        if !(self.max_abs_coordinate.is_finite() && self.max_abs_coordinate > 0.0) {
            return bad("max_abs_coordinate must be finite and > 0");
        }
        // Keep every key (and its neighbours) far from the i32 limits.
        if self.max_abs_coordinate / self.resolution > f64::from(i32::MAX / 4) {
            return bad("max_abs_coordinate / resolution exceeds the voxel index range");
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation() {
        assert!(MapConfig::default().validate().is_ok());
        for c in [
            MapConfig::with_resolution(0.0),
            MapConfig::with_resolution(f64::NAN),
            MapConfig {
                max_range: f64::NAN,
                ..MapConfig::default()
            },
            MapConfig {
                min_range: 5.0,
                max_range: 1.0,
                ..MapConfig::default()
            },
            MapConfig {
                max_abs_coordinate: 1e12,
                ..MapConfig::default()
            },
        ] {
            assert!(c.validate().is_err(), "{c:?}");
        }
        let json = serde_json::to_string(&MapConfig::default()).unwrap();
        let back: MapConfig = serde_json::from_str(&json).unwrap();
        assert_eq!(back, MapConfig::default());
        let partial: MapConfig = serde_json::from_str(r#"{"resolution":0.1}"#).unwrap();
        assert_eq!(partial.resolution, 0.1);
    }
}
