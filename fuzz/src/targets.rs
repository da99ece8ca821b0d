//! One fuzz target per parser or decoder, with its seeds and dictionary.
//!
//! A target feeds bytes to a public parsing entry point of a sornav crate.
//! `Ok` and `Err` are both fine outcomes; the runner ([`crate::run`]) treats
//! a panic, an abort or exceeding the time or memory bound as a crash. The
//! error text is returned so that the runner can keep inputs that reach a
//! new kind of error (a cheap stand-in for coverage feedback).
//!
//! Seeds are tiny built-in inputs (so every target works without shared
//! data) plus, when present, the real files in `../shared/data` (located
//! with [`sornav_test_support::shared_data`]).

use std::io::Write;
use std::path::{Path, PathBuf};

use sornav_platform_scout::cdr::{self, Endianness};
use sornav_platform_scout::msg::{
    Header, Joy, MarkerArray, Odometry, Path as RosPath, PointCloud2, PointField, PoseStamped,
    RosString,
};
use sornav_platform_scout::pointcloud::CloudView;
use sornav_platform_sim::episodes::habitat::HabitatDataset;
use sornav_platform_sim::sh3d::{Sh3dOptions, home_from_xml_str, sh3d_from_slice};

/// What a target returns: `Err` carries the parser's message.
pub type Outcome = Result<(), String>;

/// One fuzz target.
#[derive(Clone, Copy)]
pub struct Target {
    /// Name used on the command line.
    pub name: &'static str,
    /// The entry point it exercises.
    pub about: &'static str,
    /// Feeds one input to the parser.
    pub run: fn(&[u8]) -> Outcome,
    /// The seed inputs (built-in plus shared data when present).
    pub seeds: fn() -> Vec<Vec<u8>>,
    /// Tokens of the format that mutations insert.
    pub dictionary: &'static [&'static [u8]],
    /// Longest input generated.
    pub max_len: usize,
}

impl std::fmt::Debug for Target {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Target").field("name", &self.name).finish()
    }
}

/// Every target, in a fixed order.
pub fn all() -> Vec<Target> {
    vec![
        Target {
            name: "gltf",
            about: "sornav_platform_sim::gltf::gltf_from_slice (glTF JSON and GLB)",
            run: run_gltf,
            seeds: seeds_gltf,
            dictionary: JSON_DICT,
            max_len: 1 << 16,
        },
        Target {
            name: "sh3d-xml",
            about: "sornav_platform_sim::sh3d::home_from_xml_str (Sweet Home 3D Home.xml)",
            run: run_sh3d_xml,
            seeds: seeds_sh3d_xml,
            dictionary: XML_DICT,
            max_len: 1 << 17,
        },
        Target {
            name: "sh3d-zip",
            about: "sornav_platform_sim::sh3d::sh3d_from_slice (.sh3d ZIP archives)",
            run: run_sh3d_zip,
            seeds: seeds_sh3d_zip,
            dictionary: &[b"PK\x03\x04", b"PK\x01\x02", b"PK\x05\x06", b"Home.xml"],
            max_len: 1 << 17,
        },
        Target {
            name: "obj",
            about: "sornav_platform_sim::obj::parse_obj (Wavefront OBJ)",
            run: run_obj,
            seeds: seeds_obj,
            dictionary: &[
                b"\nv ", b"\nf ", b"\nvt ", b"\nvn ", b"/", b"\ng ", b"\no ", b"-",
            ],
            max_len: 1 << 16,
        },
        Target {
            name: "habitat-json",
            about: "sornav_platform_sim::episodes::habitat::HabitatDataset::from_json",
            run: run_habitat_json,
            seeds: seeds_habitat_json,
            dictionary: JSON_DICT,
            max_len: 1 << 18,
        },
        Target {
            name: "habitat-json-gz",
            about: "sornav_platform_sim::episodes::habitat::HabitatDataset::from_bytes (.json.gz)",
            run: run_habitat_bytes,
            seeds: seeds_habitat_gz,
            dictionary: &[b"\x1f\x8b\x08\x00"],
            max_len: 1 << 18,
        },
        Target {
            name: "tsplib",
            about: "sornav_tsp::tsplib::parse (TSPLIB instances)",
            run: run_tsplib,
            seeds: seeds_tsplib,
            dictionary: TSPLIB_DICT,
            max_len: 1 << 16,
        },
        Target {
            name: "tsplib-tour",
            about: "sornav_tsp::tsplib::parse_tour (TSPLIB tours)",
            run: run_tsplib_tour,
            seeds: seeds_tour,
            dictionary: TSPLIB_DICT,
            max_len: 1 << 14,
        },
        Target {
            name: "cdr",
            about: "sornav_platform_scout::cdr::decode (Odometry, PointCloud2, String, Joy, PoseStamped, Path, MarkerArray)",
            run: run_cdr,
            seeds: seeds_cdr,
            dictionary: &[
                b"\x00\x01\x00\x00",
                b"\x00\x00\x00\x00",
                b"\xff\xff\xff\xff",
            ],
            max_len: 1 << 14,
        },
        Target {
            name: "pointcloud2",
            about: "sornav_platform_scout::pointcloud::CloudView (layout checks, xyz, labelled and scalar points)",
            run: run_pointcloud,
            seeds: seeds_pointcloud,
            dictionary: &[b"x\x00", b"label\x00", b"intensity\x00", b"\x07", b"\x08"],
            max_len: 1 << 14,
        },
        Target {
            name: "llm-answer",
            about: "sornav_supervisor::llm::wire::parse_answer (chat-completion bodies)",
            run: run_llm,
            seeds: seeds_llm,
            dictionary: JSON_DICT,
            max_len: 1 << 14,
        },
        Target {
            name: "agent-config",
            about: "sornav::AgentConfig::from_toml",
            run: run_agent_config,
            seeds: seeds_agent_config,
            dictionary: TOML_DICT,
            max_len: 1 << 15,
        },
        Target {
            name: "scout-config",
            about: "sornav_platform_scout::config::ScoutConfig::from_toml",
            run: run_scout_config,
            seeds: seeds_scout_config,
            dictionary: TOML_DICT,
            max_len: 1 << 15,
        },
    ]
}

/// The target called `name`, among [`all`] and the runner's self-tests.
pub fn find(name: &str) -> Option<Target> {
    all()
        .into_iter()
        .chain(self_tests())
        .find(|t| t.name == name)
}

/// Targets that crash on purpose when an input starts with `!`: a panic
/// (`selftest-panic`), a hang (`selftest-hang`), an 8 GiB allocation
/// (`selftest-oom`: run it only in a bounded worker), 256 MiB resident
/// (`selftest-rss`) and an abort (`selftest-abort`). They check
/// the runner, are not in [`all`], and are only found by name.
pub fn self_tests() -> Vec<Target> {
    fn target(name: &'static str, run: fn(&[u8]) -> Outcome) -> Target {
        Target {
            name,
            about: "runner self-test: crashes on inputs starting with `!`",
            run,
            seeds: || vec![b"ok".to_vec(), b"!".to_vec()],
            dictionary: &[],
            max_len: 8,
        }
    }
    fn armed(bytes: &[u8]) -> bool {
        bytes.first() == Some(&b'!')
    }
    vec![
        target("selftest-panic", |b| {
            assert!(!armed(b), "self-test panic");
            Err("fine".into())
        }),
        target("selftest-hang", |b| {
            if armed(b) {
                std::thread::sleep(std::time::Duration::from_secs(3600));
            }
            Err("fine".into())
        }),
        target("selftest-oom", |b| {
            if armed(b) {
                // 8 GiB, written: beyond the worker's address-space bound
                // (the allocation fails and the worker aborts).
                return allocate_and_touch(1 << 33);
            }
            Err("fine".into())
        }),
        target("selftest-rss", |b| {
            if armed(b) {
                // 256 MiB, written: over a 128 MiB resident bound, under
                // the 512 MiB address-space cap that goes with it.
                return allocate_and_touch(256 << 20);
            }
            Err("fine".into())
        }),
        target("selftest-abort", |b| {
            if armed(b) {
                std::process::abort();
            }
            Err("fine".into())
        }),
    ]
}

/// Allocates `bytes` bytes, all written (resident), for the memory
/// self-tests; reads one back so the allocation is not optimised away.
fn allocate_and_touch(bytes: usize) -> Outcome {
    let v = vec![1u8; bytes];
    if v[v.len() / 2] == 1 {
        Ok(())
    } else {
        Err("?".into())
    }
}

const JSON_DICT: &[&[u8]] = &[
    b"\"uri\":\"gltf_triangle.bin\"",
    b"/dev/zero",
    b"../",
    b"{",
    b"}",
    b"[",
    b"]",
    b"\"",
    b":",
    b",",
    b"null",
    b"true",
    b"-1",
    b"1e999",
    b"\"\\u0000\"",
    b"{\"a\":[]}",
    b"[[[[[[[[",
    b"\"nodes\":[0]",
    b"\"children\":[0]",
    b"\"mesh\":0",
];

const XML_DICT: &[&[u8]] = &[
    b"<",
    b">",
    b"/>",
    b"='",
    b"'",
    b"<wall ",
    b"<room ",
    b"<level ",
    b"<point x='1' y='1'/>",
    b"<pieceOfFurniture ",
    b"<doorOrWindow ",
    b"<furnitureGroup>",
    b"</furnitureGroup>",
    b" arcExtent='",
    b" level='",
    b" height='",
    b"&amp;",
    b"&#0;",
    b"<![CDATA[",
];

const TSPLIB_DICT: &[&[u8]] = &[
    b"\nDIMENSION: ",
    b"\nEDGE_WEIGHT_TYPE: ",
    b"EXPLICIT",
    b"EUC_2D",
    b"GEO",
    b"ATT",
    b"CEIL_2D",
    b"\nEDGE_WEIGHT_FORMAT: ",
    b"FULL_MATRIX",
    b"UPPER_ROW",
    b"LOWER_DIAG_ROW",
    b"UPPER_DIAG_ROW",
    b"\nNODE_COORD_SECTION\n",
    b"\nEDGE_WEIGHT_SECTION\n",
    b"\nTOUR_SECTION\n",
    b"\n-1\n",
    b"\nEOF\n",
    b"\nTYPE: ",
    b"ATSP",
    b"TOUR",
];

const TOML_DICT: &[&[u8]] = &[
    b"\n[",
    b"]\n",
    b"[[",
    b"]]",
    b" = ",
    b"\"",
    b"true",
    b"inf",
    b"nan",
    b"-1",
    b"1e300",
    b"9223372036854775807",
    b"{ }",
    b"[]",
    b"\nsecs = ",
    b"\nnanos = ",
];

/// Text of `bytes`, lossily (a parser taking `&str` sees every mutation).
fn text(bytes: &[u8]) -> std::borrow::Cow<'_, str> {
    String::from_utf8_lossy(bytes)
}

fn shared(rel: &str) -> Option<PathBuf> {
    sornav_test_support::shared_data(rel)
}

/// Files directly in `dir` whose name ends with `suffix`, at most `max_bytes`
/// each, sorted by name.
fn files(dir: Option<PathBuf>, suffix: &str, max_bytes: u64) -> Vec<Vec<u8>> {
    let Some(dir) = dir else { return Vec::new() };
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|rd| rd.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    paths.sort();
    paths
        .into_iter()
        .filter(|p| p.to_string_lossy().ends_with(suffix))
        .filter(|p| {
            p.metadata()
                .is_ok_and(|m| m.is_file() && m.len() <= max_bytes)
        })
        .filter_map(|p| std::fs::read(p).ok())
        .collect()
}

// ---------------------------------------------------------------- glTF

fn run_gltf(bytes: &[u8]) -> Outcome {
    // External buffers resolve against platform-sim's test data (the
    // triangle seed's `.bin` is there).
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("../platform-sim/tests/data");
    sornav_platform_sim::gltf::gltf_from_slice(bytes, "fuzz", Some(&base))
        .map(drop)
        .map_err(|e| e.to_string())
}

/// A GLB: a floor quad (indexed, u16) and a triangle as a child node.
fn glb_seed() -> Vec<u8> {
    let mut bin: Vec<u8> = Vec::new();
    let pts: [[f32; 3]; 7] = [
        [-3.0, 0.0, 3.0],
        [3.0, 0.0, 3.0],
        [3.0, 0.0, -3.0],
        [-3.0, 0.0, -3.0],
        [0.5, 0.0, 0.0],
        [0.0, 0.25, 0.0],
        [0.0, 0.0, 0.75],
    ];
    for c in pts.iter().flatten() {
        bin.extend_from_slice(&c.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"name":"floor","mesh":0,"children":[1]}},{{"name":"chair_1","mesh":1,"translation":[1,0,0],"scale":[2,2,2]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":2}}]}},{{"primitives":[{{"attributes":{{"POSITION":1}}}}]}}],
"buffers":[{{"byteLength":{len}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":84}},{{"buffer":0,"byteOffset":84,"byteLength":12}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-3,0,-3],"max":[3,0,3]}},
{{"bufferView":0,"byteOffset":48,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[0.5,0.25,0.75]}},
{{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}}]}}"#,
        len = bin.len()
    );
    let mut json = json.into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

fn seeds_gltf() -> Vec<Vec<u8>> {
    let mut seeds = vec![glb_seed()];
    // The issue-21 reproducers committed with platform-sim's tests.
    for text in [
        include_str!("../../platform-sim/tests/data/gltf_missing_position_accessor.gltf"),
        include_str!("../../platform-sim/tests/data/gltf_node_cycle.gltf"),
        include_str!("../../platform-sim/tests/data/gltf_float_indices.gltf"),
        include_str!("../../platform-sim/tests/data/gltf_triangle.gltf"),
        include_str!("../../platform-sim/tests/data/gltf_buffer_dev_zero.gltf"),
    ] {
        seeds.push(text.as_bytes().to_vec());
    }
    seeds.push(
        include_bytes!("../../platform-sim/tests/data/glb_header_length_under_12.glb").to_vec(),
    );
    seeds
}

// ---------------------------------------------------------------- Sweet Home 3D

const HOME_XML: &str = "<?xml version='1.0'?>\n<home version='5500' wallHeight='250.0'>\n\
<level id='l0' name='Ground' elevation='0' floorThickness='12' height='250' elevationIndex='0'/>\n\
<level id='l1' name='Up' elevation='250' floorThickness='12' height='250' elevationIndex='1'/>\n\
<wall id='w0' level='l0' xStart='0' yStart='0' xEnd='400' yEnd='0' height='250' thickness='10'/>\n\
<wall id='w1' level='l0' xStart='400' yStart='0' xEnd='400' yEnd='300' height='250' thickness='10' arcExtent='1.5707964'/>\n\
<wall id='w2' level='l1' xStart='0' yStart='300' xEnd='400' yEnd='300' height='250' heightAtEnd='100' thickness='10'/>\n\
<room name='Kitchen' level='l0'><point x='0' y='0'/><point x='400' y='0'/><point x='400' y='300'/><point x='0' y='300'/></room>\n\
<room name='Bedroom' level='l1' areaVisible='true'><point x='0' y='0'/><point x='400' y='0'/><point x='400' y='300'/></room>\n\
<pieceOfFurniture level='l0' id='p1' name='Chair' model='0' x='100' y='100' width='50' depth='50' height='90' angle='0.5'/>\n\
<doorOrWindow level='l0' id='d1' name='Door' model='0' x='200' y='0' width='90' depth='10' height='210'/>\n\
<pieceOfFurniture level='l0' id='s1' name='Staircase' model='0' x='300' y='200' width='100' depth='200' height='250' staircaseCutOutShape='M0,0 L1,0 L1,1 L0,1 z'/>\n\
</home>\n";

const CUBE_OBJ: &str = "# unit cube\no cube\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nvn 0 0 1\nvt 0 0\ng sides\n\
f 1/1/1 2/1/1 3/1/1 4/1/1\nf 5//1 8//1 7//1 6//1\nf 1 5 6 2\nf 2 6 7 3\nf -1 -2 -3\nf 4 8 5 1\n";

/// The models directory of the shared homes, when present.
fn models_dir() -> PathBuf {
    shared("sh3d-homes/models").unwrap_or_else(|| PathBuf::from("/nonexistent-sornav-models"))
}

fn run_sh3d_xml(bytes: &[u8]) -> Outcome {
    thread_local! {
        static MODELS: PathBuf = models_dir();
    }
    MODELS.with(|m| {
        home_from_xml_str(&text(bytes), "fuzz", m, &Sh3dOptions::default())
            .map(drop)
            .map_err(|e| e.to_string())
    })
}

fn seeds_sh3d_xml() -> Vec<Vec<u8>> {
    let mut seeds = vec![HOME_XML.as_bytes().to_vec()];
    seeds.extend(files(shared("sh3d-homes/homes"), ".xml", 1 << 17));
    seeds
}

/// A stored (uncompressed) or deflated archive of `entries`.
fn zip_of(entries: &[(&str, &[u8])], deflate: bool) -> Vec<u8> {
    let mut z = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let method = if deflate {
        zip::CompressionMethod::Deflated
    } else {
        zip::CompressionMethod::Stored
    };
    let options = zip::write::SimpleFileOptions::default().compression_method(method);
    for (name, data) in entries {
        z.start_file(*name, options).expect("zip entry");
        z.write_all(data).expect("zip write");
    }
    z.finish().expect("zip finish").into_inner()
}

fn run_sh3d_zip(bytes: &[u8]) -> Outcome {
    sh3d_from_slice(bytes, "fuzz", &Sh3dOptions::default())
        .map(drop)
        .map_err(|e| e.to_string())
}

fn seeds_sh3d_zip() -> Vec<Vec<u8>> {
    let home = HOME_XML.as_bytes();
    let cube = CUBE_OBJ.as_bytes();
    let mut seeds = vec![
        zip_of(&[("Home.xml", home), ("0", cube)], false),
        zip_of(&[("Home.xml", home), ("0/cube.obj", cube)], true),
    ];
    // The smallest shared home with the models it names (as `.sh3d` files
    // store them: one entry per model).
    if let (Some(xml), Some(models)) = (
        shared("sh3d-homes/homes/Studio.xml"),
        shared("sh3d-homes/models"),
    ) && let Ok(xml) = std::fs::read_to_string(xml)
    {
        let prefix = "com/eteks/sweethome3d/io/resources/";
        let mut entries: Vec<(String, Vec<u8>)> = Vec::new();
        for chunk in xml.split("model='").skip(1) {
            let Some(model) = chunk.split('\'').next() else {
                continue;
            };
            let rel = model.strip_prefix(prefix).unwrap_or(model);
            if entries.iter().any(|(n, _)| n == model) {
                continue;
            }
            if let Ok(obj) = std::fs::read(models.join(rel)) {
                entries.push((model.to_string(), obj));
            }
        }
        let mut all: Vec<(&str, &[u8])> = vec![("Home.xml", xml.as_bytes())];
        all.extend(entries.iter().map(|(n, d)| (n.as_str(), d.as_slice())));
        seeds.push(zip_of(&all, true));
    }
    seeds
}

// ---------------------------------------------------------------- OBJ

fn run_obj(bytes: &[u8]) -> Outcome {
    sornav_platform_sim::obj::parse_obj(&text(bytes), "fuzz")
        .map(drop)
        .map_err(|e| e.to_string())
}

fn seeds_obj() -> Vec<Vec<u8>> {
    let mut seeds = vec![CUBE_OBJ.as_bytes().to_vec()];
    seeds.extend(files(shared("sh3d-homes/models"), ".obj", 16 << 10));
    seeds
}

// ---------------------------------------------------------------- Habitat episodes

const EPISODES_JSON: &str = r#"{"episodes":[{"episode_id":"0","scene_id":"hm3d/val/00800-TEEsavR23oF/TEEsavR23oF.basis.glb","scene_dataset_config":"hm3d.json","start_position":[-1.5,0.1,2.25],"start_rotation":[0,0.7071,0,0.7071],"info":{"geodesic_distance":4.5,"euclidean_distance":3.2,"closest_goal_object_id":12},"goals":[],"object_category":"chair","start_room":null,"shortest_paths":null}],
"category_to_task_category_id":{"chair":0,"bed":1},"category_to_scene_annotation_category_id":{"chair":0},
"goals_by_category":{"TEEsavR23oF.basis.glb_chair":[{"object_id":12,"object_name":"chair_12","object_category":"chair","position":[1.0,0.5,2.0],"view_points":[{"agent_state":{"position":[1.0,0.1,1.5],"rotation":[0,0,0,1]},"iou":0.5}]}]}}"#;

fn gz(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(bytes).expect("gzip");
    e.finish().expect("gzip")
}

fn gunzip(bytes: &[u8]) -> Option<Vec<u8>> {
    let mut out = Vec::new();
    std::io::Read::read_to_end(&mut flate2::read::GzDecoder::new(bytes), &mut out).ok()?;
    Some(out)
}

fn run_habitat_json(bytes: &[u8]) -> Outcome {
    HabitatDataset::from_json(&text(bytes), Path::new("fuzz"))
        .map(drop)
        .map_err(|e| e.to_string())
}

fn run_habitat_bytes(bytes: &[u8]) -> Outcome {
    HabitatDataset::from_bytes(bytes, Path::new("fuzz"))
        .map(drop)
        .map_err(|e| e.to_string())
}

/// The shared episode files (gzipped), smallest first, at most 4.
fn shared_episode_files() -> Vec<Vec<u8>> {
    let mut v = files(shared("objectnav-val-mini"), ".json.gz", 1 << 17);
    v.sort_by_key(Vec::len);
    v.truncate(4);
    v
}

fn seeds_habitat_json() -> Vec<Vec<u8>> {
    let mut seeds = vec![
        EPISODES_JSON.as_bytes().to_vec(),
        b"{\"episodes\":[]}".to_vec(),
    ];
    seeds.extend(
        shared_episode_files()
            .iter()
            .filter_map(|g| gunzip(g))
            .map(|mut j| {
                j.truncate(1 << 18);
                j
            }),
    );
    seeds
}

fn seeds_habitat_gz() -> Vec<Vec<u8>> {
    let mut seeds = vec![
        gz(EPISODES_JSON.as_bytes()),
        EPISODES_JSON.as_bytes().to_vec(),
    ];
    seeds.extend(shared_episode_files());
    seeds
}

// ---------------------------------------------------------------- TSPLIB

const TSP_SEEDS: [&str; 4] = [
    "NAME: tri\nTYPE: TSP\nDIMENSION: 3\nEDGE_WEIGHT_TYPE: EUC_2D\nNODE_COORD_SECTION\n1 0 0\n2 3 0\n3 3 4\nEOF\n",
    "NAME: geo\nTYPE: TSP\nDIMENSION: 3\nEDGE_WEIGHT_TYPE: GEO\nNODE_COORD_SECTION\n1 38.24 20.42\n2 39.57 26.15\n3 40.56 25.32\nEOF\n",
    "NAME: a4\nTYPE: ATSP\nDIMENSION: 4\nEDGE_WEIGHT_TYPE: EXPLICIT\nEDGE_WEIGHT_FORMAT: FULL_MATRIX\nEDGE_WEIGHT_SECTION\n9999 3 5 48\n3 9999 3 48\n5 3 9999 3\n48 3 5 9999\nEOF\n",
    "NAME: u4\nTYPE: TSP\nDIMENSION: 4\nEDGE_WEIGHT_TYPE: EXPLICIT\nEDGE_WEIGHT_FORMAT: UPPER_ROW\nEDGE_WEIGHT_SECTION\n1 2 3\n4 5\n6\nEOF\n",
];

fn run_tsplib(bytes: &[u8]) -> Outcome {
    sornav_tsp::tsplib::parse(&text(bytes))
        .map(drop)
        .map_err(|e| e.to_string())
}

fn seeds_tsplib() -> Vec<Vec<u8>> {
    let mut seeds: Vec<Vec<u8>> = TSP_SEEDS.iter().map(|s| s.as_bytes().to_vec()).collect();
    seeds.extend(files(shared("tsplib/tsp"), ".tsp", 8 << 10));
    seeds.extend(files(shared("tsplib/atsp"), ".atsp", 8 << 10));
    seeds.extend(files(shared("tsp-fuel"), "_s0.atsp", 8 << 10));
    seeds
}

fn run_tsplib_tour(bytes: &[u8]) -> Outcome {
    sornav_tsp::tsplib::parse_tour(&text(bytes))
        .map(drop)
        .map_err(|e| e.to_string())
}

fn seeds_tour() -> Vec<Vec<u8>> {
    let mut seeds = vec![
        b"NAME: t.opt.tour\nTYPE: TOUR\nDIMENSION: 4\nTOUR_SECTION\n1\n3\n2\n4\n-1\nEOF\n".to_vec(),
    ];
    seeds.extend(files(shared("tsplib/tsp"), ".opt.tour", 4 << 10));
    seeds
}

// ---------------------------------------------------------------- CDR and PointCloud2

fn decode_all(bytes: &[u8]) -> Outcome {
    fn one<T: serde::de::DeserializeOwned>(bytes: &[u8]) -> Result<(), cdr::CdrError> {
        cdr::decode::<T>(bytes).map(drop)
    }
    // Every type must return; the first error names the outcome.
    let results = [
        one::<Odometry>(bytes),
        one::<PointCloud2>(bytes),
        one::<RosString>(bytes),
        one::<Joy>(bytes),
        one::<PoseStamped>(bytes),
        one::<RosPath>(bytes),
        one::<MarkerArray>(bytes),
    ];
    match results.into_iter().find_map(Result::err) {
        Some(e) => Err(e.to_string()),
        None => Ok(()),
    }
}

fn run_cdr(bytes: &[u8]) -> Outcome {
    decode_all(bytes)
}

fn field(name: &str, offset: u32, datatype: u8) -> PointField {
    PointField {
        name: name.into(),
        offset,
        datatype,
        count: 1,
    }
}

/// Clouds: float32 xyz + intensity + u16 label, and float64 xyz + f32 label.
fn sample_clouds() -> Vec<PointCloud2> {
    let header = Header {
        frame_id: "map".into(),
        ..Header::default()
    };
    let mut a = PointCloud2 {
        header: header.clone(),
        height: 1,
        width: 3,
        fields: vec![
            field("x", 0, 7),
            field("y", 4, 7),
            field("z", 8, 7),
            field("intensity", 12, 7),
            field("label", 16, 4),
        ],
        point_step: 20,
        row_step: 60,
        is_dense: true,
        ..PointCloud2::default()
    };
    for (i, p) in [[1.0f32, 2.0, 0.5], [f32::NAN, 0.0, 0.0], [-3.0, 4.0, 1.25]]
        .iter()
        .enumerate()
    {
        for c in p {
            a.data.extend_from_slice(&c.to_le_bytes());
        }
        a.data.extend_from_slice(&(i as f32 * 0.5).to_le_bytes());
        a.data.extend_from_slice(&(i as u16 + 7).to_le_bytes());
        a.data.extend_from_slice(&[0, 0]);
    }
    let mut b = PointCloud2 {
        header,
        height: 2,
        width: 1,
        fields: vec![
            field("x", 0, 8),
            field("y", 8, 8),
            field("z", 16, 8),
            field("label", 24, 7),
        ],
        is_bigendian: true,
        point_step: 28,
        row_step: 28,
        ..PointCloud2::default()
    };
    for p in [[0.5f64, -0.5, 2.0], [10.0, 20.0, 30.0]] {
        for c in p {
            b.data.extend_from_slice(&c.to_be_bytes());
        }
        b.data.extend_from_slice(&3.0f32.to_be_bytes());
    }
    vec![a, b]
}

fn seeds_cdr() -> Vec<Vec<u8>> {
    let mut seeds = Vec::new();
    for e in [Endianness::Little, Endianness::Big] {
        for c in sample_clouds() {
            seeds.push(cdr::encode(&c, e).expect("encode"));
        }
        let odom = Odometry {
            child_frame_id: "vehicle".into(),
            ..Odometry::default()
        };
        seeds.push(cdr::encode(&odom, e).expect("encode"));
        let s = RosString {
            data: "toilet".into(),
        };
        seeds.push(cdr::encode(&s, e).expect("encode"));
        seeds.push(cdr::encode(&RosPath::default(), e).expect("encode"));
    }
    seeds
}

fn run_pointcloud(bytes: &[u8]) -> Outcome {
    let cloud: PointCloud2 = cdr::decode(bytes).map_err(|e| e.to_string())?;
    let view = CloudView::new(&cloud).map_err(|e| e.to_string())?;
    // Every decoder runs; the first error names the outcome.
    let xyz = view.xyz().map(drop);
    let labelled = view.labelled_points("label").map(drop);
    let scalar = view.points_with("intensity").map(drop);
    let by_label = view.points_with("label").map(drop);
    xyz.and(labelled)
        .and(by_label)
        .map_err(|e| e.to_string())
        .and(scalar.or_else(|e| match e {
            // the float64 seed has no intensity channel
            sornav_platform_scout::pointcloud::CloudError::MissingField(_) => Ok(()),
            e => Err(e.to_string()),
        }))
}

fn seeds_pointcloud() -> Vec<Vec<u8>> {
    let mut seeds = Vec::new();
    for e in [Endianness::Little, Endianness::Big] {
        for c in sample_clouds() {
            seeds.push(cdr::encode(&c, e).expect("encode"));
        }
    }
    seeds
}

// ---------------------------------------------------------------- LLM answers

fn run_llm(bytes: &[u8]) -> Outcome {
    sornav_supervisor::llm::wire::parse_answer(&text(bytes))
        .map(drop)
        .map_err(|e| e.to_string())
}

fn seeds_llm() -> Vec<Vec<u8>> {
    let body = |content: &str| {
        serde_json::json!({
            "id": "c1",
            "object": "chat.completion",
            "choices": [{"index": 0, "message": {"role": "assistant", "content": content}, "finish_reason": "stop"}],
            "usage": {"prompt_tokens": 10, "completion_tokens": 5}
        })
        .to_string()
        .into_bytes()
    };
    vec![
        body(
            r#"{"action":"relocate_cluster","cluster_id":3,"reason":"a bathroom is next to the hall"}"#,
        ),
        body(
            r#"{"action":"continue_explore","cluster_id":null,"reason":"kitchen objects around"}"#,
        ),
        body(r#"{"action":"continue_explore"}"#),
    ]
}

// ---------------------------------------------------------------- TOML configs

fn run_agent_config(bytes: &[u8]) -> Outcome {
    sornav::AgentConfig::from_toml(&text(bytes))
        .map(drop)
        .map_err(|e| e.to_string())
}

fn seeds_agent_config() -> Vec<Vec<u8>> {
    vec![
        include_str!("../../sornav/config/agent.example.toml")
            .as_bytes()
            .to_vec(),
        b"[horizon.solver.time_budget]\nsecs = 1\nnanos = 0\n".to_vec(),
        b"[policy]\nkind = \"never_relocate\"\n[ordering]\nkind = \"nearest\"\n".to_vec(),
        Vec::new(),
    ]
}

fn run_scout_config(bytes: &[u8]) -> Outcome {
    sornav_platform_scout::config::ScoutConfig::from_toml(&text(bytes))
        .map(drop)
        .map_err(|e| e.to_string())
}

fn seeds_scout_config() -> Vec<Vec<u8>> {
    vec![
        sornav_platform_scout::config::ScoutConfig::EXAMPLE
            .as_bytes()
            .to_vec(),
        Vec::new(),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_seeds_exist() {
        let all = all();
        for (i, t) in all.iter().enumerate() {
            assert!(all[..i].iter().all(|u| u.name != t.name), "{}", t.name);
            assert!(!(t.seeds)().is_empty(), "{}", t.name);
        }
    }

    #[test]
    fn built_in_seeds_parse() {
        assert_eq!(run_gltf(&glb_seed()), Ok(()));
        assert_eq!(run_obj(CUBE_OBJ.as_bytes()), Ok(()));
        assert_eq!(run_tsplib(TSP_SEEDS[0].as_bytes()), Ok(()));
        assert_eq!(run_habitat_bytes(&gz(b"{\"episodes\":[]}")), Ok(()));
        for s in seeds_pointcloud() {
            assert_eq!(run_pointcloud(&s), Ok(()));
        }
        for s in seeds_llm() {
            assert_eq!(run_llm(&s), Ok(()));
        }
        assert_eq!(run_scout_config(&seeds_scout_config()[0]), Ok(()));
        assert_eq!(run_agent_config(&seeds_agent_config()[0]), Ok(()));
    }
}
