//! Which scenes an evaluation runs on: `--scenes SPEC` values and their
//! loading into simulators.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sornav_platform_sim::procedural::ProceduralConfig;
use sornav_platform_sim::{NavMeshConfig, Scene, SceneError, SimConfig, SimError, Simulator};

/// Why a scene specification could not be used.
#[derive(Debug, thiserror::Error)]
pub enum SceneSpecError {
    /// The text is not a scene specification.
    #[error(
        "bad scene specification '{spec}': {why} (expected procedural:N, procedural-shuffled:N, a .xml/.sh3d/.glb/.gltf file or a directory of them)"
    )]
    Malformed {
        /// The specification.
        spec: String,
        /// Why.
        why: String,
    },
    /// A directory with no scene file.
    #[error("no .xml, .sh3d, .glb or .gltf scene in directory {0}")]
    EmptyDirectory(PathBuf),
    /// Reading a directory failed.
    #[error("cannot read {path}: {message}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The system's message.
        message: String,
    },
    /// A Sweet Home 3D `Home.xml` needs the model directory.
    #[error(
        "{0} is a Sweet Home 3D Home.xml: its furniture models need --models DIR (no default directory was found)"
    )]
    NoModels(PathBuf),
    /// Loading a scene failed.
    #[error("loading scene {name}: {source}")]
    Load {
        /// The scene.
        name: String,
        /// Why.
        #[source]
        source: SceneError,
    },
    /// Building the simulator failed.
    #[error("building the simulator for {name}: {source}")]
    Simulator {
        /// The scene.
        name: String,
        /// Why.
        #[source]
        source: SimError,
    },
}

/// One scene to load.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SceneSource {
    /// A procedural house with this seed.
    Procedural {
        /// Generator seed.
        seed: u64,
        /// Objects placed ignoring room types.
        shuffled: bool,
    },
    /// A Sweet Home 3D `Home.xml`.
    HomeXml {
        /// The file.
        path: PathBuf,
    },
    /// A Sweet Home 3D `.sh3d` archive.
    Sh3d {
        /// The file.
        path: PathBuf,
    },
    /// A glTF / GLB mesh with labelled nodes.
    Gltf {
        /// The file.
        path: PathBuf,
    },
}

impl SceneSource {
    /// A short, unique, file-name-safe name of the scene.
    pub fn name(&self) -> String {
        match self {
            SceneSource::Procedural { seed, shuffled } => {
                format!(
                    "procedural-{}{seed}",
                    if *shuffled { "shuffled-" } else { "" }
                )
            }
            SceneSource::HomeXml { path }
            | SceneSource::Sh3d { path }
            | SceneSource::Gltf { path } => path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| path.display().to_string()),
        }
    }

    /// Loads the scene.
    ///
    /// # Errors
    /// [`SceneSpecError::NoModels`] for a `Home.xml` without a model
    /// directory, [`SceneSpecError::Load`] for the loaders' errors.
    pub fn load(&self, models: Option<&Path>) -> Result<Scene, SceneSpecError> {
        let load = |r: Result<Scene, SceneError>| {
            r.map_err(|source| SceneSpecError::Load {
                name: self.name(),
                source,
            })
        };
        match self {
            SceneSource::Procedural { seed, shuffled } => load(Scene::procedural(
                *seed,
                &ProceduralConfig {
                    shuffled_semantics: *shuffled,
                    ..ProceduralConfig::default()
                },
            )),
            SceneSource::HomeXml { path } => {
                let models = models.ok_or_else(|| SceneSpecError::NoModels(path.clone()))?;
                load(Scene::from_home_xml(path, models))
            }
            SceneSource::Sh3d { path } => load(Scene::from_sh3d(path)),
            SceneSource::Gltf { path } => load(Scene::from_gltf(path)),
        }
    }

    /// Loads the scene and builds its simulator with `camera` settings.
    ///
    /// # Errors
    /// As [`load`](Self::load), and [`SceneSpecError::Simulator`].
    pub fn simulator(
        &self,
        models: Option<&Path>,
        camera: &sornav_platform_sim::CameraConfig,
    ) -> Result<Simulator, SceneSpecError> {
        let scene = self.load(models)?;
        Simulator::new(scene, sim_config(camera)).map_err(|source| SceneSpecError::Simulator {
            name: self.name(),
            source,
        })
    }
}

/// The simulator configuration of a scene: Habitat's defaults (0.2 m step)
/// for every source; Sweet Home 3D staircases are re-stepped on import to
/// risers of at most 0.19 m (`sornav_platform_sim::sh3d`).
pub fn sim_config(camera: &sornav_platform_sim::CameraConfig) -> SimConfig {
    SimConfig {
        camera: camera.clone(),
        nav: NavMeshConfig::default(),
        ..SimConfig::default()
    }
}

fn malformed(spec: &str, why: impl Into<String>) -> SceneSpecError {
    SceneSpecError::Malformed {
        spec: spec.to_owned(),
        why: why.into(),
    }
}

fn by_extension(path: &Path) -> Option<SceneSource> {
    let ext = path.extension()?.to_string_lossy().to_ascii_lowercase();
    let path = path.to_path_buf();
    match ext.as_str() {
        "xml" => Some(SceneSource::HomeXml { path }),
        "sh3d" => Some(SceneSource::Sh3d { path }),
        "glb" | "gltf" => Some(SceneSource::Gltf { path }),
        _ => None,
    }
}

/// Expands one `--scenes` value.
///
/// * `procedural:N` — N procedural houses, seeds `base_seed * 1000 + i`;
/// * `procedural-shuffled:N` — the same houses with objects placed
///   ignoring room types;
/// * a `.xml` (Sweet Home 3D `Home.xml`), `.sh3d`, `.glb` or `.gltf` file;
/// * a directory: every such file in it, sorted by name.
///
/// # Errors
/// [`SceneSpecError`] for malformed values, missing files and empty
/// directories.
pub fn parse_scene_spec(spec: &str, base_seed: u64) -> Result<Vec<SceneSource>, SceneSpecError> {
    for (prefix, shuffled) in [("procedural:", false), ("procedural-shuffled:", true)] {
        if let Some(n) = spec.strip_prefix(prefix) {
            let n: u64 = n
                .trim()
                .parse()
                .map_err(|_| malformed(spec, "N is not a whole number"))?;
            if n == 0 || n > 100_000 {
                return Err(malformed(spec, "N must be in 1..=100000"));
            }
            return Ok((0..n)
                .map(|i| SceneSource::Procedural {
                    seed: base_seed.wrapping_mul(1000).wrapping_add(i),
                    shuffled,
                })
                .collect());
        }
    }
    let path = Path::new(spec);
    if path.is_dir() {
        let io = |e: std::io::Error| SceneSpecError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let mut files: Vec<PathBuf> = std::fs::read_dir(path)
            .map_err(io)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && by_extension(p).is_some())
            .collect();
        files.sort();
        if files.is_empty() {
            return Err(SceneSpecError::EmptyDirectory(path.to_path_buf()));
        }
        return Ok(files.iter().filter_map(|p| by_extension(p)).collect());
    }
    if !path.is_file() {
        return Err(malformed(spec, "no such file or directory"));
    }
    by_extension(path)
        .map(|s| vec![s])
        .ok_or_else(|| malformed(spec, "unknown file extension"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn procedural_specs() {
        let s = parse_scene_spec("procedural:3", 7).unwrap();
        assert_eq!(s.len(), 3);
        assert_eq!(
            s[2],
            SceneSource::Procedural {
                seed: 7002,
                shuffled: false
            }
        );
        assert_eq!(s[0].name(), "procedural-7000");
        let s = parse_scene_spec("procedural-shuffled:1", 0).unwrap();
        assert_eq!(s[0].name(), "procedural-shuffled-0");
        for bad in [
            "procedural:",
            "procedural:x",
            "procedural:0",
            "procedural:-1",
            "nowhere.xml",
            "Cargo.toml",
        ] {
            assert!(parse_scene_spec(bad, 0).is_err(), "{bad}");
        }
    }

    #[test]
    fn directories_list_scene_files_sorted() {
        let dir = std::env::temp_dir().join(format!("sornav-scenes-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        assert!(matches!(
            parse_scene_spec(dir.to_str().unwrap(), 0),
            Err(SceneSpecError::EmptyDirectory(_))
        ));
        for f in ["b.xml", "a.sh3d", "c.glb", "notes.txt"] {
            std::fs::write(dir.join(f), b"").unwrap();
        }
        let s = parse_scene_spec(dir.to_str().unwrap(), 0).unwrap();
        let names: Vec<String> = s.iter().map(SceneSource::name).collect();
        assert_eq!(names, ["a", "b", "c"]);
        assert!(matches!(s[1], SceneSource::HomeXml { .. }));
        assert!(matches!(s[1].load(None), Err(SceneSpecError::NoModels(_))));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
