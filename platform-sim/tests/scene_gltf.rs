//! glTF import: labelled nodes, y-up to z-up, typed errors.

use sornav_platform_sim::gltf::{gltf_from_slice, parse_label};
use sornav_platform_sim::{InstanceKind, Scene, SceneError};

/// A floor quad (node "floor") and a unit cube translated to x = 2 in glTF's
/// y-up frame (node "chair_1", 0.5 m up along glTF y), in one GLB.
fn glb() -> Vec<u8> {
    let mut bin: Vec<u8> = Vec::new();
    let quad: [[f32; 3]; 4] = [
        [-3.0, 0.0, 3.0],
        [3.0, 0.0, 3.0],
        [3.0, 0.0, -3.0],
        [-3.0, 0.0, -3.0],
    ];
    let cube: Vec<[f32; 3]> = (0..8)
        .map(|i| {
            [
                if i & 1 == 0 { -0.25 } else { 0.25 },
                if i & 2 == 0 { 0.0 } else { 0.9 },
                if i & 4 == 0 { -0.25 } else { 0.25 },
            ]
        })
        .collect();
    for p in quad.iter().chain(cube.iter()) {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let quad_idx: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let cube_idx: [u16; 36] = [
        0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6,
        1, 3, 5, 3, 7, 5,
    ];
    for i in quad_idx.iter().chain(cube_idx.iter()) {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
        "nodes":[{{"name":"floor","mesh":0}},{{"name":"chair_1","mesh":1,"translation":[2.0,0.0,-1.0]}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":2}}]}},{{"primitives":[{{"attributes":{{"POSITION":1}},"indices":3}}]}}],
        "buffers":[{{"byteLength":{len}}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":144}},{{"buffer":0,"byteOffset":144,"byteLength":84}}],
        "accessors":[
          {{"bufferView":0,"byteOffset":0,"componentType":5126,"count":4,"type":"VEC3","min":[-3,0,-3],"max":[3,0,3]}},
          {{"bufferView":0,"byteOffset":48,"componentType":5126,"count":8,"type":"VEC3","min":[-0.25,0,-0.25],"max":[0.25,0.9,0.25]}},
          {{"bufferView":1,"byteOffset":0,"componentType":5123,"count":6,"type":"SCALAR"}},
          {{"bufferView":1,"byteOffset":12,"componentType":5123,"count":36,"type":"SCALAR"}}]}}"#,
        len = bin.len()
    );
    glb_container(json.into_bytes(), &bin)
}

#[test]
fn labelled_nodes_become_instances_z_up() {
    let s: Scene = gltf_from_slice(&glb(), "test", None).unwrap();
    let floor = s
        .instances()
        .iter()
        .find(|i| i.kind == InstanceKind::Floor)
        .unwrap();
    assert_eq!(floor.category, "floor");
    let chair = s.objects_of("chair").next().expect("chair");
    assert_eq!(chair.name, "chair_1");
    // glTF (2, 0..0.9, -1) -> scene x = 2, y = +1, z from 0 to 0.9
    let c = chair.bounds.center();
    assert!((c.x - 2.0).abs() < 1e-6 && (c.y - 1.0).abs() < 1e-6, "{c}");
    assert!(chair.bounds.min.z.abs() < 1e-6 && (chair.bounds.max.z - 0.9).abs() < 1e-6);
    assert_eq!(s.triangles().len(), 2 + 12);
}

#[test]
fn labels_parse() {
    assert_eq!(parse_label("chair_3"), ("chair".to_string(), Some(3)));
    assert_eq!(parse_label("tv_monitor"), ("tv_monitor".to_string(), None));
}

#[test]
fn malformed_gltf_is_a_typed_error() {
    let mut g = glb();
    g.truncate(g.len() / 2);
    assert!(matches!(
        gltf_from_slice(&g, "cut", None),
        Err(SceneError::Gltf { .. })
    ));
    assert!(matches!(
        gltf_from_slice(b"{not json", "bad", None),
        Err(SceneError::Gltf { .. })
    ));
}

// ---------------------------------------------------------------------------
// GLB files written by hand: meshes go into one binary buffer, the test gives
// the node list as JSON.

/// A GLB under construction: meshes (positions + u16 indices) in one buffer.
#[derive(Default)]
struct Glb {
    bin: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
    meshes: Vec<String>,
}

impl Glb {
    fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(format!(
            r#"{{"buffer":0,"byteOffset":{},"byteLength":{}}}"#,
            self.bin.len(),
            bytes.len()
        ));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// Adds a mesh; `indices` may be out of range or of any length (bad
    /// input tests), `None` for non-indexed geometry.
    fn mesh(&mut self, positions: &[[f32; 3]], indices: Option<&[u16]>) -> usize {
        let bytes: Vec<u8> = positions
            .iter()
            .flat_map(|p| p.iter().flat_map(|c| c.to_le_bytes()))
            .collect();
        let v = self.view(&bytes);
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for p in positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        // min/max must be finite JSON numbers even for NaN test data
        let num = |x: f32| if x.is_finite() { x } else { 0.0 };
        self.accessors.push(format!(
            r#"{{"bufferView":{v},"componentType":5126,"count":{},"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}}"#,
            positions.len(),
            num(lo[0]),
            num(lo[1]),
            num(lo[2]),
            num(hi[0]),
            num(hi[1]),
            num(hi[2])
        ));
        let pos = self.accessors.len() - 1;
        let prim = match indices {
            Some(idx) => {
                let bytes: Vec<u8> = idx.iter().flat_map(|i| i.to_le_bytes()).collect();
                let v = self.view(&bytes);
                self.accessors.push(format!(
                    r#"{{"bufferView":{v},"componentType":5123,"count":{},"type":"SCALAR"}}"#,
                    idx.len()
                ));
                format!(
                    r#"{{"attributes":{{"POSITION":{pos}}},"indices":{}}}"#,
                    self.accessors.len() - 1
                )
            }
            None => format!(r#"{{"attributes":{{"POSITION":{pos}}}}}"#),
        };
        self.meshes.push(format!(r#"{{"primitives":[{prim}]}}"#));
        self.meshes.len() - 1
    }

    /// The GLB bytes with this node list and scene roots.
    fn build(mut self, nodes: &str, roots: &[usize]) -> Vec<u8> {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let roots: Vec<String> = roots.iter().map(usize::to_string).collect();
        let json = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":{nodes},"meshes":[{}],"buffers":[{{"byteLength":{}}}],"bufferViews":[{}],"accessors":[{}]}}"#,
            roots.join(","),
            self.meshes.join(","),
            self.bin.len(),
            self.views.join(","),
            self.accessors.join(",")
        );
        glb_container(json.into_bytes(), &self.bin)
    }
}

/// Wraps a JSON chunk and a binary chunk (possibly empty: no BIN chunk) in
/// the GLB container.
fn glb_container(mut json: Vec<u8>, bin: &[u8]) -> Vec<u8> {
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total = 12 + 8 + json.len() + bin_chunk;
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(bin);
    }
    out
}

/// One triangle in glTF's frame.
const TRI: [[f32; 3]; 3] = [[0.5, 0.0, 0.0], [0.0, 0.25, 0.0], [0.0, 0.0, 0.75]];

/// Scene vertices of all triangles of instance `name`.
fn vertices_of(s: &Scene, name: &str) -> Vec<[f64; 3]> {
    let id = s
        .instances()
        .iter()
        .find(|i| i.name == name)
        .unwrap_or_else(|| panic!("no instance {name}"))
        .id;
    s.triangles()
        .iter()
        .zip(s.triangle_instances())
        .filter(|(_, i)| **i == id)
        .flat_map(|(t, _)| t.iter().map(|&v| s.vertices()[v as usize].map(f64::from)))
        .collect()
}

/// glTF y-up (x, y, z) to the scene's z-up (x, -z, y).
fn z_up(p: [f64; 3]) -> [f64; 3] {
    [p[0], -p[2], p[1]]
}

fn assert_same_points(got: &[[f64; 3]], want: &[[f64; 3]]) {
    assert_eq!(got.len(), want.len());
    for w in want {
        assert!(
            got.iter()
                .any(|g| (0..3).all(|k| (g[k] - w[k]).abs() < 1e-5)),
            "{w:?} not in {got:?}"
        );
    }
}

/// Nested transforms: parent translation, rotation (90 deg about glTF +y)
/// and uniform scale, child translation; a second child given by a matrix;
/// every vertex worked out by hand.
#[test]
fn nested_rotation_scale_and_matrix_transforms() {
    let mut g = Glb::default();
    let m = g.mesh(&TRI, Some(&[0, 1, 2]));
    let s = std::f32::consts::FRAC_1_SQRT_2;
    // node 0: parent (T = (1, 0, 0), R = 90 deg about +y, S = 2)
    // node 1: child "chair_1" (T = (0, 0, 1))
    // node 2: child "table_2", matrix = translation (0, 3, 0) * scale (1, 1, -1)
    let nodes = format!(
        r#"[{{"name":"group","translation":[1,0,0],"rotation":[0,{s},0,{s}],"scale":[2,2,2],"children":[1,2]}},
            {{"name":"chair_1","mesh":{m},"translation":[0,0,1]}},
            {{"name":"table_2","mesh":{m},"matrix":[1,0,0,0, 0,1,0,0, 0,0,-1,0, 0,3,0,1]}}]"#
    );
    let scene = gltf_from_slice(&g.build(&nodes, &[0]), "nested", None).unwrap();
    // parent maps p -> T + R (2 p) with R(x, y, z) = (z, y, -x)
    let parent = |p: [f64; 3]| [1.0 + 2.0 * p[2], 2.0 * p[1], -2.0 * p[0]];
    let tri: Vec<[f64; 3]> = TRI.iter().map(|p| p.map(f64::from)).collect();
    let chair: Vec<[f64; 3]> = tri
        .iter()
        .map(|p| z_up(parent([p[0], p[1], p[2] + 1.0])))
        .collect();
    assert_same_points(&vertices_of(&scene, "chair_1"), &chair);
    // by hand: (0.5, 0, 0) -> child (0.5, 0, 1) -> parent (3, 0, -1) -> z-up (3, 1, 0)
    assert!(
        chair
            .iter()
            .any(|p| (p[0] - 3.0).abs() < 1e-9 && (p[1] - 1.0).abs() < 1e-9 && p[2].abs() < 1e-9)
    );
    let table: Vec<[f64; 3]> = tri
        .iter()
        .map(|p| z_up(parent([p[0], p[1] + 3.0, -p[2]])))
        .collect();
    assert_same_points(&vertices_of(&scene, "table_2"), &table);
    assert_eq!(scene.objects_of("chair").count(), 1);
    assert_eq!(scene.objects_of("table").count(), 1);
}

/// A mirroring transform (negative scale) keeps up-facing floors up-facing:
/// the importer flips the winding.
#[test]
fn mirrored_floor_still_faces_up() {
    for scale in ["[1,1,1]", "[-1,1,1]", "[1,1,-1]", "[-2,0.5,-1]"] {
        let mut g = Glb::default();
        // a counter-clockwise quad seen from +y (glTF up)
        let m = g.mesh(
            &[
                [-1.0, 0.0, 1.0],
                [1.0, 0.0, 1.0],
                [1.0, 0.0, -1.0],
                [-1.0, 0.0, -1.0],
            ],
            Some(&[0, 1, 2, 0, 2, 3]),
        );
        let nodes = format!(r#"[{{"name":"floor","mesh":{m},"scale":{scale}}}]"#);
        let scene = gltf_from_slice(&g.build(&nodes, &[0]), "mirror", None).unwrap();
        for t in scene.triangles() {
            let [a, b, c] = t.map(|v| scene.vertices()[v as usize].map(f64::from));
            let (u, v) = (
                [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
            );
            let nz = u[0] * v[1] - u[1] * v[0];
            assert!(nz > 0.0, "scale {scale}: normal z {nz}");
        }
    }
}

/// `category_instance` names: one instance per distinct name (a repeated
/// name adds to the same instance), categories mapped to the ObjectNav
/// vocabulary, unnamed nodes inheriting their closest named ancestor's
/// label, unnamed roots becoming "object".
#[test]
fn instance_naming_and_unlabelled_nodes() {
    let mut g = Glb::default();
    let m = g.mesh(&TRI, Some(&[0, 1, 2]));
    let nodes = format!(
        r#"[{{"name":"chair_1","mesh":{m}}},
            {{"name":"chair_2","mesh":{m},"translation":[2,0,0]}},
            {{"name":"chair_1","mesh":{m},"translation":[4,0,0]}},
            {{"name":"tv_monitor","mesh":{m}}},
            {{"name":"Sofa_3","mesh":{m}}},
            {{"name":"table_7","children":[6]}},
            {{"mesh":{m},"translation":[0,0,5]}},
            {{"mesh":{m}}},
            {{"name":"   ","mesh":{m}}},
            {{"name":"wall_4","mesh":{m}}},
            {{"name":"stairs","mesh":{m}}}]"#
    );
    let roots = [0, 1, 2, 3, 4, 5, 7, 8, 9, 10];
    let s = gltf_from_slice(&g.build(&nodes, &roots), "names", None).unwrap();
    let by_name = |n: &str| {
        s.instances()
            .iter()
            .filter(|i| i.name == n)
            .collect::<Vec<_>>()
    };
    // chair_1 twice: one instance with both triangles
    assert_eq!(by_name("chair_1").len(), 1);
    assert_eq!(vertices_of(&s, "chair_1").len(), 6);
    assert_eq!(by_name("chair_2").len(), 1);
    assert_eq!(s.objects_of("chair").count(), 2);
    assert_eq!(by_name("tv_monitor")[0].category, "tv_monitor");
    assert_eq!(by_name("Sofa_3")[0].category, "sofa");
    // the unnamed child of "table_7" belongs to it
    let table = by_name("table_7");
    assert_eq!(table.len(), 1);
    assert_eq!(table[0].category, "table");
    assert_eq!(vertices_of(&s, "table_7").len(), 3);
    // unnamed and blank-named roots share the "object" instance
    let object = by_name("object");
    assert_eq!(object.len(), 1);
    assert_eq!(object[0].category, "object");
    assert_eq!(vertices_of(&s, "object").len(), 6);
    // structure labels, with or without an instance number
    assert_eq!(by_name("wall_4")[0].kind, InstanceKind::Wall);
    assert_eq!(by_name("stairs")[0].kind, InstanceKind::Stairs);
    assert_eq!(s.triangles().len(), 10);
}

fn gltf_error(bytes: &[u8]) -> (Option<String>, String) {
    match gltf_from_slice(bytes, "bad", None) {
        Err(SceneError::Gltf { node, message }) => (node, message),
        other => panic!("expected a glTF error, got {other:?}"),
    }
}

/// NaN and infinite coordinates, bad indices and broken containers give
/// typed errors naming the node where one is concerned.
#[test]
fn bad_geometry_gives_typed_errors() {
    // NaN vertex
    let mut g = Glb::default();
    let m = g.mesh(
        &[[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 0.0, 1.0]],
        Some(&[0, 1, 2]),
    );
    let (node, msg) = gltf_error(&g.build(&format!(r#"[{{"name":"chair_1","mesh":{m}}}]"#), &[0]));
    assert_eq!(node.as_deref(), Some("chair_1"));
    assert!(msg.contains("non-finite"), "{msg}");
    // a finite vertex sent beyond f32 range (the scene's vertex type) by the
    // node's transform: 3e38 + 0.5 * 1e38 > 3.4e38
    let mut g = Glb::default();
    let m = g.mesh(&TRI, Some(&[0, 1, 2]));
    let (node, msg) = gltf_error(&g.build(
        &format!(r#"[{{"name":"bed_2","mesh":{m},"translation":[3e38,0,0],"scale":[1e38,1,1]}}]"#),
        &[0],
    ));
    assert_eq!(node.as_deref(), Some("bed_2"));
    assert!(msg.contains("non-finite"), "{msg}");
    // index out of range
    let mut g = Glb::default();
    let m = g.mesh(&TRI, Some(&[0, 1, 9]));
    let (node, msg) = gltf_error(&g.build(&format!(r#"[{{"name":"sofa","mesh":{m}}}]"#), &[0]));
    assert_eq!(node.as_deref(), Some("sofa"));
    assert!(msg.contains("out of range"), "{msg}");
    // index count not a multiple of 3 (indexed and non-indexed)
    for indices in [Some(&[0u16, 1, 2, 0][..]), None] {
        let mut g = Glb::default();
        let positions: Vec<[f32; 3]> = TRI.iter().chain(TRI.iter().take(1)).copied().collect();
        let m = g.mesh(&positions, indices);
        let (node, msg) =
            gltf_error(&g.build(&format!(r#"[{{"name":"plant","mesh":{m}}}]"#), &[0]));
        assert_eq!(node.as_deref(), Some("plant"));
        assert!(msg.contains("multiple of 3"), "{msg}");
    }
}

#[test]
fn broken_files_give_typed_errors() {
    // an accessor reaching past its buffer view (validation error)
    let mut g = Glb::default();
    let m = g.mesh(&TRI, Some(&[0, 1, 2]));
    let good = g.build(&format!(r#"[{{"name":"chair","mesh":{m}}}]"#), &[0]);
    let json_len = u32::from_le_bytes(good[12..16].try_into().unwrap()) as usize;
    let json = String::from_utf8(good[20..20 + json_len].to_vec()).unwrap();
    let bin = good[20 + json_len + 8..].to_vec();
    let cut = json.replacen(
        r#""count":3,"type":"VEC3""#,
        r#""count":300,"type":"VEC3""#,
        1,
    );
    assert_ne!(cut, json);
    let (_, msg) = gltf_error(&glb_container(cut.into_bytes(), &bin));
    assert!(!msg.is_empty());
    // a GLB whose buffer has no BIN chunk
    let (_, msg) = gltf_error(&glb_container(json.clone().into_bytes(), &[]));
    assert!(msg.contains("binary chunk"), "{msg}");
    // data URIs and external buffers without a base path
    let with_uri = |uri: &str| {
        json.replacen(
            &format!(r#""buffers":[{{"byteLength":{}}}]"#, bin.len()),
            &format!(
                r#""buffers":[{{"byteLength":{},"uri":"{uri}"}}]"#,
                bin.len()
            ),
            1,
        )
    };
    let (_, msg) = gltf_error(with_uri("data:application/octet-stream;base64,AAAA").as_bytes());
    assert!(msg.contains("data URI"), "{msg}");
    let (_, msg) = gltf_error(with_uri("mesh.bin").as_bytes());
    assert!(msg.contains("without a base path"), "{msg}");
    // a GLB whose declared chunk length exceeds the file
    let mut lying = good.clone();
    lying[12..16].copy_from_slice(&(json_len as u32 + 4096).to_le_bytes());
    gltf_error(&lying);
    // not glTF at all
    gltf_error(b"glTF\x02\x00\x00\x00");
    gltf_error(&[0u8; 64]);
    // a cyclic node hierarchy
    gltf_error(
        br#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"name":"a","children":[1]},{"name":"b","children":[0]}]}"#,
    );
    // no scene, and a scene without triangles
    let (_, msg) = gltf_error(br#"{"asset":{"version":"2.0"}}"#);
    assert!(msg.contains("no scene"), "{msg}");
    assert!(matches!(
        gltf_from_slice(
            br#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"name":"empty"}]}"#,
            "empty",
            None
        ),
        Err(SceneError::Empty(_))
    ));
}

// ---------------------------------------------------------------------------
// Issue 21: minimal reproducers (tests/data) that panicked, hit
// `unreachable!` or aborted; each is now a typed error naming the problem.

fn data(file: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(file)
}

fn load_error(result: Result<Scene, SceneError>) -> String {
    match result {
        Err(e @ SceneError::Gltf { .. }) => e.to_string(),
        Err(other) => panic!("expected a glTF error, got {other}"),
        Ok(_) => panic!("expected a glTF error, got a scene"),
    }
}

#[test]
fn reproducer_control_loads() {
    let s = Scene::from_gltf(&data("gltf_triangle.gltf")).unwrap();
    assert_eq!(s.triangles().len(), 1);
}

#[test]
fn position_attribute_to_a_missing_accessor_is_an_error() {
    // panicked (index out of bounds) inside the gltf crate's validation
    let msg = load_error(Scene::from_gltf(&data(
        "gltf_missing_position_accessor.gltf",
    )));
    assert!(msg.contains("accessor 5 of 1"), "{msg}");
}

#[test]
fn float_typed_indices_are_an_error() {
    // hit `unreachable!()` in the gltf crate's `read_indices`
    let msg = load_error(Scene::from_gltf(&data("gltf_float_indices.gltf")));
    assert!(
        msg.contains("indices accessor 1") && msg.contains("unsigned"),
        "{msg}"
    );
}

#[test]
fn glb_header_declaring_under_12_bytes_is_an_error() {
    // found by sornav-fuzz: "attempt to subtract with overflow" in the gltf
    // crate's GLB header check (debug builds)
    let msg = load_error(Scene::from_gltf(&data("glb_header_length_under_12.glb")));
    assert!(msg.contains("total length of 0 bytes"), "{msg}");
}

#[test]
fn an_external_buffer_that_is_not_a_regular_file_is_an_error() {
    // found by sornav-fuzz: a buffer URI naming /dev/zero was read without
    // end (1 GiB and growing); only the declared bytes of a regular file
    // are read now
    let began = std::time::Instant::now();
    let msg = load_error(Scene::from_gltf(&data("gltf_buffer_dev_zero.gltf")));
    assert!(msg.contains("not a regular file"), "{msg}");
    assert!(began.elapsed() < std::time::Duration::from_secs(5));
    let big = std::fs::read_to_string(data("gltf_triangle.gltf"))
        .unwrap()
        .replace("\"byteLength\":48", "\"byteLength\":4294967296");
    let msg = load_error(gltf_from_slice(
        big.as_bytes(),
        "big",
        Some(&data("gltf_triangle.gltf").with_file_name("")),
    ));
    assert!(msg.contains("MAX_GLTF_BUFFER_BYTES"), "{msg}");
}

#[test]
fn a_node_listing_itself_as_a_child_is_an_error() {
    // appended its mesh on every visit until 10^6 visits (4.5 GB, abort)
    let began = std::time::Instant::now();
    let msg = load_error(Scene::from_gltf(&data("gltf_node_cycle.gltf")));
    assert!(
        msg.contains("node `chair_1`") && msg.contains("strict trees"),
        "{msg}"
    );
    assert!(began.elapsed() < std::time::Duration::from_secs(5));
}

#[test]
fn shared_children_are_an_error_not_an_exponential_walk() {
    // 40 levels of a node listing the next one twice: 2^40 visits before.
    let mut g = Glb::default();
    let tri = g.mesh(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]], None);
    let nodes: Vec<String> = (0..40)
        .map(|k| {
            if k == 39 {
                format!(r#"{{"name":"leaf","mesh":{tri}}}"#)
            } else {
                format!(r#"{{"children":[{0},{0}]}}"#, k + 1)
            }
        })
        .collect();
    let bytes = g.build(&format!("[{}]", nodes.join(",")), &[0]);
    let msg = load_error(gltf_from_slice(&bytes, "dag", None));
    assert!(msg.contains("reached twice"), "{msg}");
}

#[test]
fn accessors_outside_their_views_or_of_the_wrong_type_are_errors() {
    let text = std::fs::read_to_string(data("gltf_triangle.gltf")).unwrap();
    let dir = data("");
    let load = |doc: String| gltf_from_slice(doc.as_bytes(), "bad", Some(&dir));
    for (from, to, expect) in [
        (r#""count":3"#, r#""count":4"#, "overrun buffer view"),
        (
            r#""count":3"#,
            r#""count":18446744073709551615"#,
            "overrun buffer view",
        ),
        (r#""count":3"#, r#""count":0"#, "count 0"),
        (
            r#""componentType":5126"#,
            r#""componentType":5121"#,
            "FLOAT VEC3",
        ),
        (r#""type":"VEC3""#, r#""type":"VEC2""#, "FLOAT VEC3"),
        (
            r#""byteOffset":0,"byteLength":36"#,
            r#""byteOffset":40,"byteLength":36"#,
            "outside its buffer",
        ),
        (
            r#""byteOffset":0,"byteLength":36"#,
            r#""byteOffset":18446744073709551615,"byteLength":36"#,
            "outside its buffer",
        ),
    ] {
        assert!(text.contains(from));
        let msg = load_error(load(text.replacen(from, to, 1)));
        assert!(msg.contains(expect), "{to}: {msg}");
    }
}

mod fuzz {
    use proptest::prelude::*;
    use sornav_platform_sim::gltf::gltf_from_slice;

    use super::{Glb, data};

    proptest! {
        #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

        /// Corrupting or truncating a glTF document (JSON with an external
        /// buffer) or a GLB anywhere gives a scene or a typed error, never
        /// a panic (issue 21: missing accessors, float indices and node
        /// cycles panicked or aborted).
        #[test]
        fn gltf_loader_never_panics(cut in 1usize..2000, pos in 0usize..2000, byte in any::<u8>(), glb: bool) {
            let mut bytes = if glb {
                let mut g = Glb::default();
                let m = g.mesh(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]], Some(&[0, 1, 2]));
                g.build(&format!(r#"[{{"name":"chair_1","mesh":{m},"children":[1]}},{{"name":"wall","mesh":{m}}}]"#), &[0])
            } else {
                std::fs::read(data("gltf_triangle.gltf")).unwrap()
            };
            bytes.truncate(cut.max(1));
            let at = pos % bytes.len();
            bytes[at] = byte;
            let dir = data("");
            let _ = gltf_from_slice(&bytes, "fuzz", Some(&dir));
        }
    }
}
