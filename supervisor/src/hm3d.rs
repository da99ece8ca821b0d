//! Reader for the HM3D-Semantics v0.2 region statistics
//! (`Per_Scene_Region_Neighborhoods.csv` plus the scene split column of
//! `hm3d_scene_metadata.csv`), the raw material of the commonsense prior.
//!
//! Data: HM3D-Semantics, Yadav et al. 2023 (matterport/habitat-matterport-3dresearch,
//! `statistics/HM3DSem-v0.2.zip`, `metadata.csv`).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::SupervisorError;
use crate::label::normalize_label;

/// Region file inside the statistics folder.
pub const REGIONS_FILE: &str = "Per_Scene_Region_Neighborhoods.csv";
/// Scene metadata file (split column) inside the statistics folder.
pub const METADATA_FILE: &str = "hm3d_scene_metadata.csv";

/// HM3D's dataset split of a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    /// Training scenes (ids 00000-00799): the prior is derived from these only.
    Train,
    /// Validation scenes (ids 00800-00899): held out for evaluation.
    Val,
}

/// One annotated region (room) of an HM3D scene.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Hm3dRegion {
    /// Scene name, e.g. `00006-HkseAnWCgqk`.
    pub scene: String,
    /// Region number within the scene.
    pub region: u32,
    /// The scene's split.
    pub split: Split,
    /// Normalised labels present in the region (structural labels dropped).
    pub labels: BTreeSet<String>,
}

/// The regions of the statistics folder plus what had to be skipped.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Hm3dStats {
    /// Regions in file order.
    pub regions: Vec<Hm3dRegion>,
    /// Rows whose scene has no split in the metadata, or whose split is
    /// neither train nor val (counted, not silently dropped).
    pub skipped_rows: usize,
}

fn malformed(path: &Path, message: impl Into<String>) -> SupervisorError {
    SupervisorError::MalformedStats {
        path: path.display().to_string(),
        message: message.into(),
    }
}

fn open(path: &Path) -> Result<csv::Reader<std::fs::File>, SupervisorError> {
    let file = std::fs::File::open(path).map_err(|source| SupervisorError::Io {
        path: path.display().to_string(),
        source,
    })?;
    Ok(csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .from_reader(file))
}

fn column(path: &Path, headers: &csv::StringRecord, name: &str) -> Result<usize, SupervisorError> {
    headers
        .iter()
        .position(|h| h.trim() == name)
        .ok_or_else(|| malformed(path, format!("missing column {name:?}")))
}

/// Strips the `_<instance id>` suffix of an HM3D object instance name.
fn instance_category(instance: &str) -> &str {
    match instance.rsplit_once('_') {
        Some((name, id)) if !id.is_empty() && id.bytes().all(|b| b.is_ascii_digit()) => name,
        _ => instance,
    }
}

impl Hm3dStats {
    /// Reads the statistics folder (`../shared/data/hm3d-sem-stats`).
    ///
    /// # Errors
    /// [`SupervisorError::Io`] when a file is missing,
    /// [`SupervisorError::MalformedStats`] for a missing column, a bad region
    /// number or a CSV syntax error.
    ///
    /// # Complexity
    /// O(total file size).
    pub fn read_dir(dir: &Path) -> Result<Self, SupervisorError> {
        let meta_path = dir.join(METADATA_FILE);
        let mut meta = open(&meta_path)?;
        let headers = meta
            .headers()
            .map_err(|e| malformed(&meta_path, e.to_string()))?
            .clone();
        let (scene_col, split_col) = (
            column(&meta_path, &headers, "scene")?,
            column(&meta_path, &headers, "split")?,
        );
        let mut splits = BTreeMap::new();
        for row in meta.records() {
            let row = row.map_err(|e| malformed(&meta_path, e.to_string()))?;
            let split = match row.get(split_col).map(str::trim) {
                Some("train") => Some(Split::Train),
                Some("val") => Some(Split::Val),
                _ => None,
            };
            if let (Some(scene), Some(split)) = (row.get(scene_col), split) {
                splits.insert(scene.trim().to_owned(), split);
            }
        }

        let reg_path = dir.join(REGIONS_FILE);
        let mut regions_csv = open(&reg_path)?;
        let headers = regions_csv
            .headers()
            .map_err(|e| malformed(&reg_path, e.to_string()))?
            .clone();
        let scene_col = column(&reg_path, &headers, "Scene Name")?;
        let region_col = column(&reg_path, &headers, "Region #")?;
        let objects_col = column(&reg_path, &headers, "Object Instances in Region")?;
        let mut stats = Hm3dStats::default();
        for row in regions_csv.records() {
            let row = row.map_err(|e| malformed(&reg_path, e.to_string()))?;
            let scene = row.get(scene_col).unwrap_or("").trim();
            let region: u32 = row
                .get(region_col)
                .unwrap_or("")
                .trim()
                .parse()
                .map_err(|_| malformed(&reg_path, format!("bad region number in scene {scene}")))?;
            let Some(&split) = splits.get(scene) else {
                stats.skipped_rows += 1;
                continue;
            };
            let labels = row
                .get(objects_col)
                .unwrap_or("")
                .split(':')
                .filter_map(|inst| normalize_label(instance_category(inst)))
                .collect();
            stats.regions.push(Hm3dRegion {
                scene: scene.to_owned(),
                region,
                split,
                labels,
            });
        }
        if stats.regions.is_empty() {
            return Err(malformed(&reg_path, "no region with a known split"));
        }
        Ok(stats)
    }

    /// The regions of one split.
    pub fn split(&self, split: Split) -> impl Iterator<Item = &Hm3dRegion> {
        self.regions.iter().filter(move |r| r.split == split)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instance_suffix_is_stripped() {
        assert_eq!(instance_category("door frame_21"), "door frame");
        assert_eq!(instance_category("tv_monitor_3"), "tv_monitor");
        assert_eq!(instance_category("tv_monitor"), "tv_monitor");
        assert_eq!(instance_category("lamp"), "lamp");
    }
}
