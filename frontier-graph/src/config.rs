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
    /// Threads for the shortest-path rows of one refresh: 0 (default) uses
    /// every available core, at most 8; 1 runs them on the calling thread.
    /// The graph does not depend on it (each row is searched alone).
    pub search_threads: usize,
}

impl Default for GraphConfig {
    fn default() -> Self {
        Self {
            displacement_weight: 0.0,
            home: true,
            snap_radius: 0.5,
            search_threads: 0,
        }
    }
}

impl GraphConfig {
    /// The number of row-search threads [`search_threads`](Self::search_threads)
    /// asks for on this machine.
    #[must_use]
    pub fn row_threads(&self) -> usize {
        match self.search_threads {
            0 => std::thread::available_parallelism().map_or(1, |n| n.get().min(8)),
            n => n,
        }
    }

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
        if self.search_threads > 256 {
            return Err(FrontierError::InvalidConfig(
                "search_threads must be <= 256".into(),
            ));
        }
        Ok(())
    }
}

/// Floors and stairs of a [`crate::MultiLevelMap`] (ignored by the
/// single-level [`crate::FrontierMap`]). Robot geometry (step height,
/// height, radius) comes from [`GridConfig`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LevelConfig {
    /// Whether the robot can climb stairs. `false`: one level at the first
    /// pose's height, no surface map, no stairs — exactly the single-floor
    /// [`crate::FrontierMap`] (robots that cannot climb, 2-D users).
    pub allow_stairs: bool,
    /// Keep the surface map and find stairs even when `allow_stairs` is
    /// false, so that a robot that cannot climb can say where stairs lead
    /// to another floor ([`crate::MultiLevelMap::stairs`]); they never enter
    /// G_F then. `allow_stairs = false, detect_stairs = false` is exactly a
    /// single [`crate::FrontierMap`].
    pub detect_stairs: bool,
    /// Column size (m) of the walkable-surface map (default 0.1: two grid
    /// cells; a stair tread is 2-3 columns deep).
    pub surface_resolution: f64,
    /// A surface within this height (m) of a level's floor belongs to the
    /// level (default 0.08).
    pub level_tolerance: f64,
    /// The robot is on a level when its feet are within this height (m) of
    /// the level's floor (default 0.25: on the first tread it still maps
    /// the floor it came from).
    pub robot_level_tolerance: f64,
    /// Floors of two levels differ by at least this (m, default 1.8):
    /// landings and mezzanine-like platforms lower than this are stair
    /// surfaces, not levels.
    pub min_level_separation: f64,
    /// A flat walkable area of at least this size (m², default 3) at a new
    /// height, reached over a stair, makes a new level.
    pub min_level_area: f64,
    /// A chain of steps is a stair when it climbs or descends at least this
    /// (m, default 0.4) from the level it starts on.
    pub min_stair_rise: f64,
    /// A partly seen stair may rise less than `min_stair_rise` over
    /// walkable steps when the step-connected surfaces around it (walkable
    /// or not) rise at least this (m, default 0.8, four to five risers)
    /// from its level: a flight seen from the side, whose treads above the
    /// camera or beyond the near edge are not observed, so that the walkable
    /// chain ends after its first treads. Its open end is then the highest
    /// walkable tread seen; standing there shows the flight.
    pub min_stair_sighting_rise: f64,
    /// Largest height difference (m) between neighbouring surface columns
    /// inside a flight (default 0.35; never less than the step height).
    /// Where treads are shallower than a column (steep stairs, winders near
    /// their narrow end) a column's top is the tread after its riser, so
    /// neighbouring columns differ by two or three risers though every
    /// riser is a step. Such a jump joins two columns only when the columns
    /// before and after them rise the same way by at most a step each, and
    /// a stair's first tread must be within a step of the floor, so
    /// furniture (a chair seat beside a counter) stays apart.
    pub max_stair_column_rise: f64,
    /// Cost (graph units, metres of path) added for climbing one stair
    /// (default 2).
    pub stair_cost_up: f64,
    /// Cost added for descending one stair (default 1).
    pub stair_cost_down: f64,
    /// A stair end is joined to the nearest traversable cell of its level
    /// within this radius (m, default 0.8: the cells next to the first
    /// step lie inside the inflation of the steps above them).
    pub portal_radius: f64,
}

impl Default for LevelConfig {
    fn default() -> Self {
        Self {
            allow_stairs: true,
            detect_stairs: true,
            surface_resolution: 0.1,
            level_tolerance: 0.08,
            robot_level_tolerance: 0.25,
            min_level_separation: 1.8,
            min_level_area: 3.0,
            min_stair_rise: 0.4,
            min_stair_sighting_rise: 0.8,
            max_stair_column_rise: 0.35,
            stair_cost_up: 2.0,
            stair_cost_down: 1.0,
            portal_radius: 0.8,
        }
    }
}

impl LevelConfig {
    /// Checks every value for consistency.
    ///
    /// # Errors
    /// [`FrontierError::InvalidConfig`] naming the offending field.
    pub fn validate(&self) -> Result<(), FrontierError> {
        let bad = |m: &str| Err(FrontierError::InvalidConfig(format!("levels: {m}")));
        let all = [
            self.surface_resolution,
            self.level_tolerance,
            self.robot_level_tolerance,
            self.min_level_separation,
            self.min_level_area,
            self.min_stair_rise,
            self.min_stair_sighting_rise,
            self.max_stair_column_rise,
            self.stair_cost_up,
            self.stair_cost_down,
            self.portal_radius,
        ];
        if all.iter().any(|v| !v.is_finite() || *v < 0.0) {
            return bad("all level parameters must be finite and >= 0");
        }
        if !(0.02..=1.0).contains(&self.surface_resolution) {
            return bad("surface_resolution must be in [0.02, 1] m");
        }
        if self.level_tolerance <= 0.0 || self.robot_level_tolerance < self.level_tolerance {
            return bad("need 0 < level_tolerance <= robot_level_tolerance");
        }
        if self.min_level_separation <= 2.0 * self.robot_level_tolerance {
            return bad("min_level_separation must exceed 2 robot_level_tolerance");
        }
        if self.min_stair_rise <= self.level_tolerance {
            return bad("min_stair_rise must exceed level_tolerance");
        }
        if self.min_stair_sighting_rise < self.min_stair_rise {
            return bad("min_stair_sighting_rise must be at least min_stair_rise");
        }
        if self.max_stair_column_rise > 1.0 {
            return bad("max_stair_column_rise must be at most 1 m");
        }
        if self.portal_radius > 10.0 {
            return bad("portal_radius must be at most 10 m");
        }
        Ok(())
    }
}

/// All parameters of a [`crate::FrontierMap`] (and of a
/// [`crate::MultiLevelMap`], which also reads `levels`).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct FrontierMapConfig {
    /// Occupancy / traversability grid.
    pub grid: GridConfig,
    /// Frontier segmentation.
    pub frontier: FrontierConfig,
    /// Decision graph.
    pub graph: GraphConfig,
    /// Floors and stairs (multi-level maps only).
    pub levels: LevelConfig,
}

impl FrontierMapConfig {
    /// Validates all parts.
    ///
    /// # Errors
    /// The first [`FrontierError::InvalidConfig`] found.
    pub fn validate(&self) -> Result<(), FrontierError> {
        self.grid.validate()?;
        self.frontier.validate()?;
        self.graph.validate()?;
        self.levels.validate()
    }
}
