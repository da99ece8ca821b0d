//! Room and object statistics the generator samples from.
//!
//! The embedded figures (`data/hm3d_val_stats.json`) are derived from the
//! HM3D-Semantics v0.2 statistics (Yadav et al. 2023), validation scenes only,
//! by the `derive_hm3d_stats` example; no raw file is shipped.

use std::sync::OnceLock;

use serde::{Deserialize, Serialize};

use crate::SceneError;
use crate::scene::RoomType;

/// Size of one HM3D scene (from `hm3d_scene_metadata.csv`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HouseSize {
    /// HM3D scene id.
    pub scene: String,
    /// Number of floors.
    pub floors: u32,
    /// Number of rooms.
    pub rooms: u32,
    /// Navigable area in m^2.
    pub navigable_area: f64,
}

/// How often a category occurs in rooms of one type.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CategoryStats {
    /// ObjectNav category.
    pub category: String,
    /// Fraction of rooms of this type holding at least one instance.
    pub presence: f64,
    /// Mean number of instances in the rooms that hold any.
    pub mean_count: f64,
}

/// Statistics of one room type.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RoomTypeStats {
    /// The room type.
    pub room_type: RoomType,
    /// Number of HM3D regions of this type.
    pub regions: usize,
    /// Mean number of rooms of this type per scene.
    pub mean_per_scene: f64,
    /// Fraction of scenes with at least one room of this type (0 when the
    /// figure is missing from an older statistics file).
    #[serde(default)]
    pub scene_presence: f64,
    /// Object statistics.
    pub objects: Vec<CategoryStats>,
}

/// All statistics the generator uses.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HouseStats {
    /// Source and licence of the figures.
    pub attribution: String,
    /// Number of scenes with semantic annotations the room statistics come from.
    pub semantic_scenes: usize,
    /// House sizes.
    pub houses: Vec<HouseSize>,
    /// Per room type statistics.
    pub room_types: Vec<RoomTypeStats>,
}

const EMBEDDED: &str = include_str!("../../data/hm3d_val_stats.json");

impl HouseStats {
    /// The embedded statistics (parsed once).
    ///
    /// # Errors
    /// [`SceneError::Invalid`] if the embedded file does not parse (a build defect).
    pub fn embedded() -> Result<&'static HouseStats, SceneError> {
        static CELL: OnceLock<Result<HouseStats, String>> = OnceLock::new();
        CELL.get_or_init(|| {
            let s: HouseStats = serde_json::from_str(EMBEDDED).map_err(|e| e.to_string())?;
            s.validate().map_err(|e| e.to_string())?;
            Ok(s)
        })
        .as_ref()
        .map_err(|e| SceneError::Invalid(format!("embedded HM3D statistics: {e}")))
    }

    /// Checks that the statistics can drive the generator.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] when there are no houses or room types, or when
    /// a probability or count is out of range.
    pub fn validate(&self) -> Result<(), SceneError> {
        if self.houses.is_empty() || self.room_types.is_empty() {
            return Err(SceneError::Invalid(
                "statistics without houses or room types".into(),
            ));
        }
        for h in &self.houses {
            if !(h.navigable_area.is_finite() && h.navigable_area > 0.0) {
                return Err(SceneError::Invalid(format!(
                    "house {}: bad navigable area",
                    h.scene
                )));
            }
        }
        for r in &self.room_types {
            if !(r.mean_per_scene.is_finite()
                && r.mean_per_scene >= 0.0
                && (0.0..=1.0).contains(&r.scene_presence))
            {
                return Err(SceneError::Invalid(format!(
                    "{:?}: bad mean_per_scene or scene_presence",
                    r.room_type
                )));
            }
            for o in &r.objects {
                if !((0.0..=1.0).contains(&o.presence)
                    && o.mean_count.is_finite()
                    && o.mean_count >= 1.0)
                {
                    return Err(SceneError::Invalid(format!(
                        "{:?}/{}: bad figures",
                        r.room_type, o.category
                    )));
                }
            }
        }
        Ok(())
    }

    /// Statistics of one room type.
    pub fn room_type(&self, t: RoomType) -> Option<&RoomTypeStats> {
        self.room_types.iter().find(|r| r.room_type == t)
    }
}
