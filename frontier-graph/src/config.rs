//! Configuration structs (all serde-serialisable, all with paper defaults).

use serde::{Deserialize, Serialize};

use crate::FrontierError;

/// Occupancy / traversability grid parameters.
///
/// Heights are absolute world z values measured from the floor level
/// `floor_z`; distances are metres.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct GridConfig {
    /// Cell edge length (m). Paper default 0.05 m.
    pub resolution: f64,
    /// World z of the floor of this level (m).
    pub floor_z: f64,
    /// Highest step the robot can climb (m): returns below `floor_z + step_height`
    /// are floor returns and mark their cell free.
    pub step_height: f64,
    /// Robot height (m): returns in `[floor_z + step_height, floor_z + robot_height]`
    /// are obstacles. Returns above it only carve free space up to the point
    /// where their ray leaves the robot's height band.
    pub robot_height: f64,
    /// Returns more than this far below the floor (m) are drop-offs (stairs
    /// down, holes) and mark their cell occupied.
    pub drop_off_depth: f64,
    /// Robot radius (m): occupied cells are inflated by it.
    pub robot_radius: f64,
    /// Sensor range (m, 3D). Longer rays are truncated there and only carve.
    pub max_range: f64,
    /// Log-odds increment of a hit.
    pub log_odds_hit: f64,
    /// Log-odds increment of a miss (negative).
    pub log_odds_miss: f64,
    /// Lower clamp of the log-odds.
    pub log_odds_min: f64,
    /// Upper clamp of the log-odds.
    pub log_odds_max: f64,
    /// A cell is occupied when its log-odds is at least this.
    pub occupied_threshold: f64,
    /// A cell is free when its log-odds is at most this.
    pub free_threshold: f64,
    /// Upper bound on the number of grid cells (growth beyond it, or beyond
    /// 65 535 cells on either side, is an error).
    pub max_cells: u64,
}

impl Default for GridConfig {
    fn default() -> Self {
        Self {
            resolution: 0.05,
            floor_z: 0.0,
            step_height: 0.2,
            robot_height: 0.88,
            drop_off_depth: 0.3,
            robot_radius: 0.18,
            max_range: 5.0,
            log_odds_hit: 0.85,
            log_odds_miss: -0.4,
            log_odds_min: -2.0,
            log_odds_max: 3.5,
            occupied_threshold: 0.5,
            free_threshold: -0.2,
            max_cells: 1 << 26,
        }
    }
}

impl GridConfig {
    /// Checks every value for consistency.
    ///
    /// # Errors
    /// [`FrontierError::InvalidConfig`] naming the first offending field.
    pub fn validate(&self) -> Result<(), FrontierError> {
        let bad = |m: &str| Err(FrontierError::InvalidConfig(m.to_owned()));
        let all = [
            self.resolution,
            self.floor_z,
            self.step_height,
            self.robot_height,
            self.drop_off_depth,
            self.robot_radius,
            self.max_range,
            self.log_odds_hit,
            self.log_odds_miss,
            self.log_odds_min,
            self.log_odds_max,
            self.occupied_threshold,
            self.free_threshold,
        ];
        if all.iter().any(|v| !v.is_finite()) {
            return bad("all grid parameters must be finite");
        }
        if self.resolution <= 1e-4 {
            return bad("resolution must be > 0.0001 m");
        }
        if self.step_height < 0.0 || self.robot_height <= self.step_height {
            return bad("need 0 <= step_height < robot_height");
        }
        if self.drop_off_depth < 0.0 {
            return bad("drop_off_depth must be >= 0");
        }
        if self.robot_radius < 0.0 || self.robot_radius / self.resolution > 200.0 {
            return bad("robot_radius must be >= 0 and at most 200 cells");
        }
        if self.max_range <= 0.0 {
            return bad("max_range must be > 0");
        }
        if self.log_odds_hit <= 0.0 || self.log_odds_miss >= 0.0 {
            return bad("need log_odds_hit > 0 > log_odds_miss");
        }
        if !(self.log_odds_min < self.free_threshold
            && self.free_threshold < self.occupied_threshold
            && self.occupied_threshold <= self.log_odds_max)
        {
            return bad("need log_odds_min < free_threshold < occupied_threshold <= log_odds_max");
        }
        if self.free_threshold >= 0.0 || self.occupied_threshold <= 0.0 {
            return bad("an unobserved cell (log-odds 0) must be unknown");
        }
        if self.max_cells < 1 {
            return bad("max_cells must be >= 1");
        }
        Ok(())
    }
}

/// Frontier segmentation parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FrontierConfig {
    /// Segments whose extent along their principal axis exceeds this (m) are
    /// split in two at their centroid, recursively. Default 2 m.
    pub max_extent: f64,
    /// Segments (after splitting) with fewer cells are dropped. Default 8.
    pub min_cells: usize,
}

impl Default for FrontierConfig {
    fn default() -> Self {
        Self {
            max_extent: 2.0,
            min_cells: 8,
        }
    }
}

impl FrontierConfig {
    /// Checks every value for consistency.
    ///
    /// # Errors
    /// [`FrontierError::InvalidConfig`] naming the offending field.
    pub fn validate(&self) -> Result<(), FrontierError> {
        if !self.max_extent.is_finite() || self.max_extent <= 0.0 {
            return Err(FrontierError::InvalidConfig(
                "max_extent must be finite and > 0".into(),
            ));
        }
        if self.min_cells == 0 {
            return Err(FrontierError::InvalidConfig(
                "min_cells must be >= 1".into(),
            ));
        }
        Ok(())
    }
}

/// Decision-graph parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct GraphConfig {
    /// Weight of the same-floor endpoint displacement term added to an edge's
    /// path length: `w * (d_a + d_b)` where `d` is the distance between a node's
    /// nominal position (robot pose, frontier centroid, home pose) and the grid
    /// cell its paths start from. Default 0 (cost = path length).
    pub displacement_weight: f64,
    /// Keep a home node at the first robot pose. Default true.
    pub home: bool,
    /// A robot or home pose on a non-traversable cell (inflated zone, unknown)
    /// is snapped to the nearest traversable cell within this radius (m).
    pub snap_radius: f64,
}

impl Default for GraphConfig {
    fn default() -> Self {
        Self {
            displacement_weight: 0.0,
            home: true,
            snap_radius: 0.5,
        }
    }
}

impl GraphConfig {
    /// Checks every value for consistency.
    ///
    /// # Errors
    /// [`FrontierError::InvalidConfig`] naming the offending field.
    pub fn validate(&self) -> Result<(), FrontierError> {
        if !self.displacement_weight.is_finite() || self.displacement_weight < 0.0 {
            return Err(FrontierError::InvalidConfig(
                "displacement_weight must be finite and >= 0".into(),
            ));
        }
        if !self.snap_radius.is_finite() || !(0.0..=10.0).contains(&self.snap_radius) {
            return Err(FrontierError::InvalidConfig(
                "snap_radius must be in [0, 10] m".into(),
            ));
        }
        Ok(())
    }
}

/// All parameters of a [`crate::FrontierMap`].
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct FrontierMapConfig {
    /// Occupancy / traversability grid.
    pub grid: GridConfig,
    /// Frontier segmentation.
    pub frontier: FrontierConfig,
    /// Decision graph.
    pub graph: GraphConfig,
}

impl FrontierMapConfig {
    /// Validates all three parts.
    ///
    /// # Errors
    /// The first [`FrontierError::InvalidConfig`] found.
    pub fn validate(&self) -> Result<(), FrontierError> {
        self.grid.validate()?;
        self.frontier.validate()?;
        self.graph.validate()
    }
}
