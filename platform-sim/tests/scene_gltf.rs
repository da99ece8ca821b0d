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
