//! ObjectNav episodes: Habitat's dataset schema ([`habitat`]), its conversion
//! to this crate's z-up frame ([`Episode`]), and a generator that follows
//! Habitat's dataset procedure on any [`crate::Scene`] ([`generator`]).
//!
//! # Frames
//! Habitat is y-up with the agent looking along -z; this crate is z-up,
//! right-handed. A Habitat point `(x, y, z)` is `(x, -z, y)` here (a proper
//! rotation, so handedness is kept), and a Habitat rotation becomes a yaw
//! (heading counter-clockwise from +x): the yaw of the rotated forward axis.

pub mod generator;
pub mod habitat;

use std::path::PathBuf;

use nalgebra::{Point3, Quaternion, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use serde_json::Value;

pub use generator::{GenerateError, GeneratorConfig, generate_episodes, goal_view_points};
pub use habitat::{
    HabitatDataset, HabitatEpisode, HabitatGoal, MAX_EPISODE_FILE_BYTES, goals_key, scene_file,
    scene_stem,
};

/// Errors of episode files and conversions.
#[derive(Debug, thiserror::Error)]
pub enum EpisodeError {
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The file, or its decompressed text, exceeds the size limit.
    #[error("{path}: more than {limit} bytes of JSON (MAX_EPISODE_FILE_BYTES)")]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// The limit in bytes.
        limit: usize,
    },
    /// The file is not valid JSON of Habitat's ObjectNav schema.
    #[error("{path}: {message}")]
    Json {
        /// The file.
        path: PathBuf,
        /// serde's message (with line and column).
        message: String,
    },
    /// An episode's goals are neither inline nor in `goals_by_category`.
    #[error("episode {episode_id}: no goals (looked for key `{key}`)")]
    MissingGoals {
        /// The episode.
        episode_id: String,
        /// The `goals_by_category` key.
        key: String,
    },
    /// An episode has no object category (neither its own nor its goals').
    #[error("episode {0}: no object category")]
    NoCategory(String),
    /// A position or rotation is non-finite or degenerate.
    #[error("episode {episode_id}: invalid {field}")]
    Invalid {
        /// The episode (or goal key).
        episode_id: String,
        /// The field.
        field: &'static str,
    },
}

/// A goal view point in the z-up frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ViewPoint {
    /// Agent (feet) position.
    pub position: Point3<f64>,
    /// Heading (radians, counter-clockwise from +x) facing the object.
    pub yaw: f64,
    /// Fraction of the view the object covers, when known.
    pub iou: Option<f64>,
}

/// A goal object in the z-up frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectGoal {
    /// Object id (for generated episodes: the scene's instance id).
    pub object_id: u64,
    /// Object name, when known.
    pub object_name: Option<String>,
    /// Category.
    pub category: String,
    /// Object centre.
    pub position: Point3<f64>,
    /// Navigable poses within 1 m of the object from which it is visible.
    pub view_points: Vec<ViewPoint>,
}

/// An ObjectNav episode in the z-up frame, with its goals resolved.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Episode {
    /// Episode id.
    pub episode_id: String,
    /// Scene path as in the dataset.
    pub scene_id: String,
    /// Start (feet) position.
    pub start_position: Point3<f64>,
    /// Start heading (radians, counter-clockwise from +x).
    pub start_yaw: f64,
    /// Target category.
    pub object_category: String,
    /// All instances of the category, with view points.
    pub goals: Vec<ObjectGoal>,
    /// Geodesic distance from the start to the nearest view point.
    pub geodesic_distance: Option<f64>,
    /// Straight-line distance from the start to the closest goal.
    pub euclidean_distance: Option<f64>,
    /// Object id of the closest goal.
    pub closest_goal_object_id: Option<u64>,
    /// Whether the goal view point nearest to the start lies on another
    /// level of the height field (generated episodes, [`crate::levels`];
    /// stored as `info.cross_floor`). Informational: [`crate::run_episode`]
    /// recomputes the floors from the height field for every episode.
    pub cross_floor: Option<bool>,
}

impl Episode {
    /// All view point positions of all goals.
    pub fn view_point_positions(&self) -> Vec<Point3<f64>> {
        self.goals
            .iter()
            .flat_map(|g| g.view_points.iter().map(|v| v.position))
            .collect()
    }
}

/// Habitat point (y up) to z-up.
pub fn point_from_habitat(p: [f64; 3]) -> Point3<f64> {
    Point3::new(p[0], -p[2], p[1])
}

/// z-up point to Habitat (y up).
pub fn point_to_habitat(p: &Point3<f64>) -> [f64; 3] {
    [p.x, p.z, -p.y]
}

/// Yaw (z-up, counter-clockwise from +x) of a Habitat rotation `[x, y, z, w]`:
/// the heading of the rotated forward axis (-z in Habitat). `None` for a
/// non-finite or zero quaternion, or one that points the agent straight up or down.
pub fn yaw_from_habitat(q: [f64; 4]) -> Option<f64> {
    if !q.iter().all(|c| c.is_finite()) {
        return None;
    }
    let q = Quaternion::new(q[3], q[0], q[1], q[2]);
    if q.norm() < 1e-9 {
        return None;
    }
    let f = UnitQuaternion::from_quaternion(q) * Vector3::new(0.0, 0.0, -1.0);
    let (x, y) = (f.x, -f.z);
    (x.hypot(y) > 1e-9).then(|| y.atan2(x))
}

/// Habitat rotation `[x, y, z, w]` (about the y axis) of a z-up yaw.
pub fn yaw_to_habitat(yaw: f64) -> [f64; 4] {
    let theta = yaw - std::f64::consts::FRAC_PI_2;
    let (s, c) = (theta / 2.0).sin_cos();
    [0.0, s, 0.0, c]
}

fn finite_point(
    p: [f64; 3],
    episode_id: &str,
    field: &'static str,
) -> Result<Point3<f64>, EpisodeError> {
    if p.iter().all(|c| c.is_finite()) {
        Ok(point_from_habitat(p))
    } else {
        Err(EpisodeError::Invalid {
            episode_id: episode_id.to_string(),
            field,
        })
    }
}

fn goal_from_habitat(g: &HabitatGoal, episode_id: &str) -> Result<ObjectGoal, EpisodeError> {
    let view_points = g
        .view_points
        .iter()
        .map(|v| {
            Ok(ViewPoint {
                position: finite_point(v.agent_state.position, episode_id, "view point position")?,
                yaw: yaw_from_habitat(v.agent_state.rotation).ok_or_else(|| {
                    EpisodeError::Invalid {
                        episode_id: episode_id.to_string(),
                        field: "view point rotation",
                    }
                })?,
                iou: v.iou,
            })
        })
        .collect::<Result<_, EpisodeError>>()?;
    Ok(ObjectGoal {
        object_id: g.object_id,
        object_name: g.object_name.clone(),
        category: g.object_category.clone(),
        position: finite_point(g.position, episode_id, "goal position")?,
        view_points,
    })
}

fn goal_to_habitat(g: &ObjectGoal) -> HabitatGoal {
    let mut extra = serde_json::Map::new();
    extra.insert("radius".into(), Value::Null);
    extra.insert("room_id".into(), Value::Null);
    extra.insert("room_name".into(), Value::Null);
    HabitatGoal {
        position: point_to_habitat(&g.position),
        object_id: g.object_id,
        object_name: g.object_name.clone(),
        object_category: g.category.clone(),
        view_points: g
            .view_points
            .iter()
            .map(|v| habitat::HabitatViewPoint {
                agent_state: habitat::HabitatAgentState {
                    position: point_to_habitat(&v.position),
                    rotation: yaw_to_habitat(v.yaw),
                    extra: serde_json::Map::new(),
                },
                iou: v.iou,
                extra: serde_json::Map::new(),
            })
            .collect(),
        extra,
    }
}

impl HabitatDataset {
    /// The episodes converted to the z-up frame, with goals resolved (inline
    /// goals first, else `goals_by_category`).
    ///
    /// # Errors
    /// [`EpisodeError::MissingGoals`], [`EpisodeError::NoCategory`] or
    /// [`EpisodeError::Invalid`] for the first bad episode.
    ///
    /// # Complexity
    /// O(E + G) for E episodes and G goal view points (goal lists are
    /// converted once per key).
    pub fn to_episodes(&self) -> Result<Vec<Episode>, EpisodeError> {
        let mut cache: std::collections::HashMap<String, Vec<ObjectGoal>> =
            std::collections::HashMap::new();
        let mut out = Vec::with_capacity(self.episodes.len());
        for e in &self.episodes {
            let id = &e.episode_id;
            let category = e
                .object_category
                .clone()
                .or_else(|| e.goals.first().map(|g| g.object_category.clone()))
                .ok_or_else(|| EpisodeError::NoCategory(id.clone()))?;
            let goals = if !e.goals.is_empty() {
                e.goals
                    .iter()
                    .map(|g| goal_from_habitat(g, id))
                    .collect::<Result<Vec<_>, _>>()?
            } else {
                let key = goals_key(&e.scene_id, &category);
                if let Some(g) = cache.get(&key) {
                    g.clone()
                } else {
                    let raw = self
                        .goals_by_category
                        .as_ref()
                        .and_then(|m| m.get(&key))
                        .ok_or_else(|| EpisodeError::MissingGoals {
                            episode_id: id.clone(),
                            key: key.clone(),
                        })?;
                    let g = raw
                        .iter()
                        .map(|g| goal_from_habitat(g, &key))
                        .collect::<Result<Vec<_>, _>>()?;
                    cache.insert(key, g.clone());
                    g
                }
            };
            out.push(Episode {
                episode_id: id.clone(),
                scene_id: e.scene_id.clone(),
                start_position: finite_point(e.start_position, id, "start_position")?,
                start_yaw: yaw_from_habitat(e.start_rotation).ok_or_else(|| {
                    EpisodeError::Invalid {
                        episode_id: id.clone(),
                        field: "start_rotation",
                    }
                })?,
                object_category: category,
                goals,
                geodesic_distance: e.info.geodesic_distance,
                euclidean_distance: e.info.euclidean_distance,
                closest_goal_object_id: e.info.closest_goal_object_id,
                cross_floor: e.info.extra.get("cross_floor").and_then(Value::as_bool),
            });
        }
        Ok(out)
    }

    /// A dataset in the HM3D layout (goals in `goals_by_category`) holding
    /// `episodes`, with category ids in the order of `categories` (categories
    /// of the episodes that are not listed get the next ids).
    ///
    /// # Complexity
    /// O(E + G).
    pub fn from_episodes(episodes: &[Episode], categories: &[&str]) -> HabitatDataset {
        let mut cats: Vec<&str> = categories.to_vec();
        for e in episodes {
            if !cats.contains(&e.object_category.as_str()) {
                cats.push(&e.object_category);
            }
        }
        let mut data = HabitatDataset::new(&cats);
        let goals = data.goals_by_category.get_or_insert_with(Default::default);
        for e in episodes {
            goals
                .entry(goals_key(&e.scene_id, &e.object_category))
                .or_insert_with(|| e.goals.iter().map(goal_to_habitat).collect());
            let mut info_extra = serde_json::Map::new();
            if let Some(c) = e.cross_floor {
                info_extra.insert("cross_floor".into(), Value::Bool(c));
            }
            let mut extra = serde_json::Map::new();
            extra.insert("scene_dataset_config".into(), Value::from("default"));
            extra.insert(
                "additional_obj_config_paths".into(),
                Value::Array(Vec::new()),
            );
            extra.insert("start_room".into(), Value::Null);
            extra.insert("shortest_paths".into(), Value::Null);
            data.episodes.push(HabitatEpisode {
                episode_id: e.episode_id.clone(),
                scene_id: e.scene_id.clone(),
                start_position: point_to_habitat(&e.start_position),
                start_rotation: yaw_to_habitat(e.start_yaw),
                object_category: Some(e.object_category.clone()),
                info: habitat::HabitatInfo {
                    geodesic_distance: e.geodesic_distance,
                    euclidean_distance: e.euclidean_distance,
                    closest_goal_object_id: e.closest_goal_object_id,
                    extra: info_extra,
                },
                goals: Vec::new(),
                extra,
            });
        }
        data
    }
}
