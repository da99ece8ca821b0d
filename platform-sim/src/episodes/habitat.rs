//! Habitat's ObjectNav dataset schema (`*.json` / `*.json.gz`), as written by
//! habitat-lab: a split file and per-scene content files, y-up coordinates.
//!
//! The structs type the fields the simulator uses and keep every other field
//! verbatim (`extra`), so reading and writing a file loses nothing. Both the
//! HM3D layout (goals in `goals_by_category`, keyed `"<scene file>_<category>"`)
//! and the MP3D 2020 layout (goals inline in each episode, category only in
//! the goals) are read.

use std::collections::{BTreeMap, BTreeSet};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use super::EpisodeError;

/// Most bytes of JSON text an episode file may hold (after decompression):
/// 128 MiB (per-scene content files of the HM3D and MP3D ObjectNav
/// datasets are a few MiB to a few tens of MiB). A 1.5 MB `.json.gz` could
/// otherwise inflate to gigabytes.
pub const MAX_EPISODE_FILE_BYTES: usize = 128 << 20;

/// A whole dataset file (split or content file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HabitatDataset {
    /// Episodes (empty in a split file whose episodes live in content files).
    pub episodes: Vec<HabitatEpisode>,
    /// Goals per `"<scene file name>_<category>"` (HM3D / MP3D 2021 layout).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub goals_by_category: Option<BTreeMap<String, Vec<HabitatGoal>>>,
    /// Category name -> task category id.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub category_to_task_category_id: Option<BTreeMap<String, u64>>,
    /// Every other top-level field (`category_to_scene_annotation_category_id`,
    /// `category_to_mp3d_category_id`, ...), kept verbatim.
    #[serde(flatten)]
    pub extra: Map<String, Value>,
}

/// One episode in Habitat's frame (y up, -z forward).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HabitatEpisode {
    /// Episode id.
    pub episode_id: String,
    /// Scene path, e.g. `hm3d/val/00800-TEEsavR23oF/TEEsavR23oF.basis.glb`.
    pub scene_id: String,
    /// Start position (x, y up, z).
    pub start_position: [f64; 3],
    /// Start rotation quaternion (x, y, z, w).
    pub start_rotation: [f64; 4],
    /// Target category (absent in the MP3D 2020 files: see the goals).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub object_category: Option<String>,
    /// Episode info.
    #[serde(default)]
    pub info: HabitatInfo,
    /// Inline goals (MP3D 2020 layout; empty when `goals_by_category` is used).
    #[serde(default)]
    pub goals: Vec<HabitatGoal>,
    /// Every other field (`shortest_paths`, `start_room`, ...), verbatim.
    #[serde(flatten)]
    pub extra: Map<String, Value>,
}

/// The `info` object of an episode.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct HabitatInfo {
    /// Geodesic distance from the start to the nearest view point.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub geodesic_distance: Option<f64>,
    /// Straight-line distance from the start to the closest goal.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub euclidean_distance: Option<f64>,
    /// Object id of the closest goal.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub closest_goal_object_id: Option<u64>,
    /// Every other field (`navigation_bounds`, `best_viewpoint_position`, and
    /// this crate's `cross_floor`), verbatim.
    #[serde(flatten)]
    pub extra: Map<String, Value>,
}

/// One goal object.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HabitatGoal {
    /// Object centre (Habitat frame).
    pub position: [f64; 3],
    /// Object id in the scene's semantic annotation.
    pub object_id: u64,
    /// Object name, e.g. `bed_16`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub object_name: Option<String>,
    /// Category.
    pub object_category: String,
    /// Navigable poses from which the object is visible.
    #[serde(default)]
    pub view_points: Vec<HabitatViewPoint>,
    /// Every other field (`radius`, `room_id`, `room_name`, ...), verbatim.
    #[serde(flatten)]
    pub extra: Map<String, Value>,
}

/// A goal view point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HabitatViewPoint {
    /// The agent's pose at the view point.
    pub agent_state: HabitatAgentState,
    /// Fraction of the view the object covers (Habitat's `iou`), if given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub iou: Option<f64>,
    /// Every other field, verbatim.
    #[serde(flatten)]
    pub extra: Map<String, Value>,
}

/// An agent pose in Habitat's frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HabitatAgentState {
    /// Position (x, y up, z).
    pub position: [f64; 3],
    /// Rotation quaternion (x, y, z, w).
    pub rotation: [f64; 4],
    /// Every other field, verbatim.
    #[serde(flatten)]
    pub extra: Map<String, Value>,
}

impl HabitatDataset {
    /// An empty dataset with the ObjectNav category maps of `categories`
    /// (ids in the given order).
    pub fn new(categories: &[&str]) -> HabitatDataset {
        let ids: BTreeMap<String, u64> = categories
            .iter()
            .enumerate()
            .map(|(i, c)| ((*c).to_string(), i as u64))
            .collect();
        let mut extra = Map::new();
        extra.insert(
            "category_to_scene_annotation_category_id".into(),
            Value::Object(
                ids.iter()
                    .map(|(k, v)| (k.clone(), Value::from(*v)))
                    .collect(),
            ),
        );
        HabitatDataset {
            episodes: Vec::new(),
            goals_by_category: Some(BTreeMap::new()),
            category_to_task_category_id: Some(ids),
            extra,
        }
    }

    /// Parses a dataset from JSON text.
    ///
    /// # Errors
    /// [`EpisodeError::Json`] naming the problem (serde's message carries the
    /// line and column).
    pub fn from_json(text: &str, origin: &Path) -> Result<HabitatDataset, EpisodeError> {
        serde_json::from_str(text).map_err(|e| EpisodeError::Json {
            path: origin.to_path_buf(),
            message: e.to_string(),
        })
    }

    /// Reads a `.json` or `.json.gz` file (gzip is detected by its magic
    /// bytes). The JSON text, after decompression, may hold at most
    /// [`MAX_EPISODE_FILE_BYTES`].
    ///
    /// # Errors
    /// [`EpisodeError::Io`] when the file cannot be read or decompressed,
    /// [`EpisodeError::TooLarge`] when the file or its decompressed text
    /// exceeds [`MAX_EPISODE_FILE_BYTES`], [`EpisodeError::Json`] when it
    /// does not follow the schema.
    ///
    /// # Complexity
    /// O(file size).
    pub fn read(path: &Path) -> Result<HabitatDataset, EpisodeError> {
        let io = |e: std::io::Error| EpisodeError::Io {
            path: path.to_path_buf(),
            source: e,
        };
        let limit = MAX_EPISODE_FILE_BYTES as u64;
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|f| f.take(limit + 1).read_to_end(&mut bytes))
            .map_err(io)?;
        HabitatDataset::from_bytes(&bytes, path)
    }

    /// Parses the bytes of a `.json` or `.json.gz` file (gzip is detected by
    /// its magic bytes), as [`HabitatDataset::read`] does after reading the
    /// file; `origin` names the source in errors.
    ///
    /// # Errors
    /// [`EpisodeError::Io`] when the gzip stream cannot be decompressed,
    /// [`EpisodeError::TooLarge`] when the bytes or the decompressed text
    /// exceed [`MAX_EPISODE_FILE_BYTES`], [`EpisodeError::Json`] when the text
    /// is not UTF-8 or does not follow the schema.
    ///
    /// # Examples
    /// ```
    /// use std::path::Path;
    /// use sornav_platform_sim::episodes::habitat::HabitatDataset;
    /// let data = HabitatDataset::from_bytes(br#"{"episodes": []}"#, Path::new("inline")).unwrap();
    /// assert!(data.episodes.is_empty());
    /// assert!(HabitatDataset::from_bytes(&[0x1f, 0x8b, 0, 1], Path::new("inline")).is_err());
    /// ```
    ///
    /// # Complexity
    /// O(decompressed size).
    pub fn from_bytes(bytes: &[u8], origin: &Path) -> Result<HabitatDataset, EpisodeError> {
        let io = |e: std::io::Error| EpisodeError::Io {
            path: origin.to_path_buf(),
            source: e,
        };
        let too_large = || EpisodeError::TooLarge {
            path: origin.to_path_buf(),
            limit: MAX_EPISODE_FILE_BYTES,
        };
        let limit = MAX_EPISODE_FILE_BYTES as u64;
        if bytes.len() as u64 > limit {
            return Err(too_large());
        }
        let text = if bytes.starts_with(&[0x1f, 0x8b]) {
            // Decompress at most one byte past the limit: a small file may
            // inflate a thousandfold.
            let mut s = String::new();
            flate2::read::GzDecoder::new(bytes)
                .take(limit + 1)
                .read_to_string(&mut s)
                .map_err(io)?;
            if s.len() as u64 > limit {
                return Err(too_large());
            }
            s
        } else {
            String::from_utf8(bytes.to_vec()).map_err(|e| EpisodeError::Json {
                path: origin.to_path_buf(),
                message: format!("not UTF-8: {e}"),
            })?
        };
        HabitatDataset::from_json(&text, origin)
    }

    /// Writes the dataset as JSON, gzipped when the path ends in `.gz`.
    ///
    /// # Errors
    /// [`EpisodeError::Io`] when the file cannot be written.
    pub fn write(&self, path: &Path) -> Result<(), EpisodeError> {
        let io = |e: std::io::Error| EpisodeError::Io {
            path: path.to_path_buf(),
            source: e,
        };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(io)?;
        }
        let json = serde_json::to_vec(self).map_err(|e| EpisodeError::Json {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        let file = std::fs::File::create(path).map_err(io)?;
        if path.extension().is_some_and(|e| e == "gz") {
            let mut enc = flate2::write::GzEncoder::new(file, flate2::Compression::default());
            enc.write_all(&json).map_err(io)?;
            enc.finish().map_err(io)?;
        } else {
            let mut w = std::io::BufWriter::new(file);
            w.write_all(&json).map_err(io)?;
            w.flush().map_err(io)?;
        }
        Ok(())
    }

    /// Adds the episodes and goals of `other` (category maps: `self` wins).
    pub fn merge(&mut self, other: HabitatDataset) {
        self.episodes.extend(other.episodes);
        if let Some(g) = other.goals_by_category {
            let mine = self.goals_by_category.get_or_insert_with(BTreeMap::new);
            for (k, v) in g {
                mine.entry(k).or_insert(v);
            }
        }
        if self.category_to_task_category_id.is_none() {
            self.category_to_task_category_id = other.category_to_task_category_id;
        }
        for (k, v) in other.extra {
            self.extra.entry(k).or_insert(v);
        }
    }

    /// Reads a split as habitat-lab lays it out: the split file
    /// (`<dir>/<split>.json.gz`) and, when its episode list is empty, every
    /// content file in `<dir>/content/` (sorted by name), merged.
    ///
    /// # Errors
    /// As [`HabitatDataset::read`], for the split or any content file.
    pub fn read_split(split_file: &Path) -> Result<HabitatDataset, EpisodeError> {
        let mut data = HabitatDataset::read(split_file)?;
        if !data.episodes.is_empty() {
            return Ok(data);
        }
        let dir = split_file
            .parent()
            .unwrap_or(Path::new("."))
            .join("content");
        for file in content_files(&dir)? {
            data.merge(HabitatDataset::read(&file)?);
        }
        Ok(data)
    }

    /// Writes a split in habitat-lab's layout: `<dir>/<split>.json.gz` with the
    /// category maps and no episodes, and one `<dir>/content/<scene>.json.gz`
    /// per scene with its episodes and goals. Returns the files written.
    ///
    /// # Errors
    /// [`EpisodeError::Io`] when a file cannot be written.
    pub fn write_split(&self, dir: &Path, split: &str) -> Result<Vec<PathBuf>, EpisodeError> {
        let head = HabitatDataset {
            episodes: Vec::new(),
            goals_by_category: None,
            category_to_task_category_id: self.category_to_task_category_id.clone(),
            extra: self.extra.clone(),
        };
        let split_file = dir.join(format!("{split}.json.gz"));
        head.write(&split_file)?;
        let mut written = vec![split_file];
        let mut by_scene: BTreeMap<String, Vec<HabitatEpisode>> = BTreeMap::new();
        for e in &self.episodes {
            by_scene
                .entry(scene_stem(&e.scene_id).to_string())
                .or_default()
                .push(e.clone());
        }
        for (scene, episodes) in by_scene {
            let goals = self.goals_by_category.as_ref().map(|g| {
                let prefixes: BTreeSet<String> = episodes
                    .iter()
                    .map(|e| format!("{}_", scene_file(&e.scene_id)))
                    .collect();
                g.iter()
                    .filter(|(k, _)| prefixes.iter().any(|p| k.starts_with(p.as_str())))
                    .map(|(k, v)| (k.clone(), v.clone()))
                    .collect()
            });
            let part = HabitatDataset {
                episodes,
                goals_by_category: goals,
                ..head.clone()
            };
            let file = dir.join("content").join(format!("{scene}.json.gz"));
            part.write(&file)?;
            written.push(file);
        }
        Ok(written)
    }
}

/// `*.json` and `*.json.gz` files of a directory, sorted.
fn content_files(dir: &Path) -> Result<Vec<PathBuf>, EpisodeError> {
    let io = |e: std::io::Error| EpisodeError::Io {
        path: dir.to_path_buf(),
        source: e,
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io)? {
        let p = entry.map_err(io)?.path();
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if name.ends_with(".json") || name.ends_with(".json.gz") {
            files.push(p);
        }
    }
    files.sort();
    Ok(files)
}

/// File name of a scene path (`.../TEEsavR23oF.basis.glb` -> `TEEsavR23oF.basis.glb`),
/// the prefix of habitat-lab's `goals_by_category` keys.
pub fn scene_file(scene_id: &str) -> &str {
    scene_id.rsplit(['/', '\\']).next().unwrap_or(scene_id)
}

/// Scene name without extensions (`TEEsavR23oF`), the name of its content file.
pub fn scene_stem(scene_id: &str) -> &str {
    let f = scene_file(scene_id);
    f.split('.').next().unwrap_or(f)
}

/// habitat-lab's key into `goals_by_category`.
pub fn goals_key(scene_id: &str, category: &str) -> String {
    format!("{}_{category}", scene_file(scene_id))
}
