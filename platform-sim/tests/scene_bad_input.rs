//! Bad input: typed errors naming the element, never a panic.

use std::path::{Path, PathBuf};

use sornav_platform_sim::sh3d::{Sh3dOptions, home_from_xml_str, load_sh3d};
use sornav_platform_sim::{NavError, NavMesh, NavMeshConfig, Scene, SceneError};
use sornav_test_support::shared_data;

mod common;

fn models() -> PathBuf {
    shared_data("sh3d-homes/models").unwrap_or_else(|| PathBuf::from("/nonexistent"))
}

fn load(xml: &str) -> Result<Scene, SceneError> {
    home_from_xml_str(xml, "test", &models(), &Sh3dOptions::default())
}

const WALLS: &str = "<home version='5500' wallHeight='250.0'>\
  <wall id='wall0' xStart='0' yStart='0' xEnd='400' yEnd='0' height='250' thickness='10'/>\
  <wall id='wall1' xStart='400' yStart='0' xEnd='400' yEnd='300' height='250' thickness='10'/>\
  <room name='Kitchen'><point x='0' y='0'/><point x='400' y='0'/><point x='400' y='300'/><point x='0' y='300'/></room>\
</home>";

#[test]
fn minimal_home_loads() {
    let s = load(WALLS).unwrap();
    assert_eq!(s.rooms().len(), 1);
    assert_eq!(
        s.rooms()[0].room_type,
        sornav_platform_sim::RoomType::Kitchen
    );
}

#[test]
fn truncated_xml_names_the_open_element() {
    let cut = &WALLS[..WALLS.len() - 30];
    match load(cut) {
        Err(SceneError::Xml { element, .. }) => assert!(element.is_some(), "element named"),
        other => panic!("expected Xml error, got {other:?}"),
    }
    if let Some(p) = shared_data("sh3d-homes/homes/Studio.xml") {
        let text = std::fs::read_to_string(p).unwrap();
        assert!(matches!(
            load(&text[..text.len() / 2]),
            Err(SceneError::Xml { .. })
        ));
    }
}

#[test]
fn garbled_xml_is_an_error() {
    assert!(matches!(
        load("<home><wall id='w' xStart='0' <<<>>> </home>"),
        Err(SceneError::Xml { .. })
    ));
    assert!(matches!(
        load("not xml at all"),
        Err(SceneError::Xml { .. })
    ));
}

#[test]
fn nan_coordinates_name_the_element() {
    let bad = WALLS.replace("xEnd='400' yEnd='0'", "xEnd='NaN' yEnd='0'");
    match load(&bad) {
        Err(SceneError::NonFinite { element, attribute }) => {
            assert_eq!(element, "wall 'wall0'");
            assert_eq!(attribute, "xEnd");
        }
        other => panic!("{other:?}"),
    }
    let bad = WALLS.replace("xStart='400' yStart='0'", "xStart='abc' yStart='0'");
    match load(&bad) {
        Err(SceneError::Attribute {
            element, attribute, ..
        }) => assert_eq!(
            (element.as_str(), attribute.as_str()),
            ("wall 'wall1'", "xStart")
        ),
        other => panic!("{other:?}"),
    }
    // A room corner and a piece of furniture.
    let bad = WALLS.replace("<point x='400' y='300'/>", "<point x='400' y='inf'/>");
    match load(&bad) {
        Err(SceneError::NonFinite { element, attribute }) => {
            assert_eq!(element, "point of room 'Kitchen'");
            assert_eq!(attribute, "y");
        }
        other => panic!("{other:?}"),
    }
    let bad = WALLS.replace(
        "</home>",
        "<pieceOfFurniture id='p7' name='Chair' model='chair.obj' x='NaN' y='100' width='50' depth='50' height='90'/></home>",
    );
    match load(&bad) {
        Err(SceneError::NonFinite { element, attribute }) => {
            assert_eq!(element, "pieceOfFurniture 'p7'");
            assert_eq!(attribute, "x");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn unknown_level_names_the_element() {
    let bad = WALLS.replace("<wall id='wall1'", "<wall id='wall1' level='nowhere'");
    match load(&bad) {
        Err(SceneError::Attribute {
            element,
            attribute,
            message,
        }) => {
            assert_eq!(element, "wall 'wall1'");
            assert_eq!(attribute, "level");
            assert!(message.contains("nowhere"), "{message}");
        }
        other => panic!("{other:?}"),
    }
    let bad = WALLS.replace("<room name='Kitchen'", "<room name='Kitchen' level='x'");
    assert!(matches!(
        load(&bad),
        Err(SceneError::Attribute { element, .. }) if element == "room 'Kitchen'"
    ));
}

#[test]
fn missing_model_names_the_piece() {
    let xml = WALLS.replace(
        "</home>",
        "<pieceOfFurniture id='p1' name='Mystery' model='com/eteks/sweethome3d/io/resources/nope.obj' x='100' y='100' width='50' depth='50' height='50'/></home>",
    );
    match load(&xml) {
        Err(SceneError::MissingModel { element, model }) => {
            assert!(
                element.contains("p1") || element.contains("Mystery"),
                "{element}"
            );
            assert!(model.ends_with("nope.obj"));
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn empty_home_is_an_error() {
    assert!(matches!(
        load("<home version='5500'/>"),
        Err(SceneError::Empty(_))
    ));
    assert!(matches!(load("<home></home>"), Err(SceneError::Empty(_))));
}

#[test]
fn broken_archives_are_zip_errors() {
    let dir = std::env::temp_dir().join(format!("sornav-bad-input-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let garbage = dir.join("garbage.sh3d");
    std::fs::write(&garbage, b"PK\x03\x04 this is not a zip file").unwrap();
    assert!(matches!(
        load_sh3d(&garbage, &Sh3dOptions::default()),
        Err(SceneError::Zip(_))
    ));
    if let Some(p) = shared_data("sh3d-homes/sh3d/Studio.sh3d") {
        let bytes = std::fs::read(p).unwrap();
        let cut = dir.join("truncated.sh3d");
        std::fs::write(&cut, &bytes[..bytes.len() / 3]).unwrap();
        assert!(matches!(
            load_sh3d(&cut, &Sh3dOptions::default()),
            Err(SceneError::Zip(_))
        ));
    }
    // Archives built here: no `Home.xml`, a garbled one, a missing model entry.
    let archive = |name: &str, entries: &[(&str, &str)]| {
        use std::io::Write;
        let path = dir.join(name);
        let mut z = zip::ZipWriter::new(std::fs::File::create(&path).unwrap());
        for (entry, text) in entries {
            z.start_file(*entry, zip::write::SimpleFileOptions::default())
                .unwrap();
            z.write_all(text.as_bytes()).unwrap();
        }
        z.finish().unwrap();
        path
    };
    let no_home = archive("no_home.sh3d", &[("Home", "binary"), ("0", "v 0 0 0\n")]);
    match load_sh3d(&no_home, &Sh3dOptions::default()) {
        Err(SceneError::Zip(m)) => assert!(m.contains("Home.xml"), "{m}"),
        other => panic!("{other:?}"),
    }
    let garbled = archive("garbled.sh3d", &[("Home.xml", "<home><wall id='w' <<>>")]);
    assert!(matches!(
        load_sh3d(&garbled, &Sh3dOptions::default()),
        Err(SceneError::Xml { .. })
    ));
    let home = WALLS.replace(
        "</home>",
        "<pieceOfFurniture id='p9' name='Lamp' model='3' x='100' y='100' width='50' depth='50' height='50'/></home>",
    );
    let missing_model = archive(
        "missing_model.sh3d",
        &[("Home.xml", &home), ("0", "v 0 0 0\n")],
    );
    match load_sh3d(&missing_model, &Sh3dOptions::default()) {
        Err(SceneError::MissingModel { element, model }) => {
            assert_eq!(element, "pieceOfFurniture 'p9'");
            assert_eq!(model, "3");
        }
        other => panic!("{other:?}"),
    }
    // The same archive with the model entry loads, and the model is used.
    let ok = archive(
        "ok.sh3d",
        &[
            ("Home.xml", &home),
            (
                "3",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n",
            ),
        ],
    );
    let s = load_sh3d(&ok, &Sh3dOptions::default()).unwrap();
    let lamp = s.objects().find(|o| o.name == "Lamp").unwrap();
    assert!(
        (lamp.bounds.extents().x - 0.5).abs() < 1e-6,
        "{:?}",
        lamp.bounds
    );
    let missing = load_sh3d(Path::new("/nonexistent/home.sh3d"), &Sh3dOptions::default());
    assert!(matches!(missing, Err(SceneError::Io { .. })));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn nav_queries_reject_nan_and_off_mesh_points() {
    let scene = common::house(1, 1);
    let nav = NavMesh::build(&scene, &NavMeshConfig::default()).unwrap();
    let nan = nalgebra::Point3::new(f64::NAN, 0.0, 0.0);
    assert!(!nav.is_navigable(&nan));
    assert_eq!(nav.snap(&nan, 1.0), Err(NavError::NonFinite));
    let far = nalgebra::Point3::new(1e4, 1e4, 0.0);
    assert!(matches!(
        nav.distance(&far, &far),
        Err(NavError::NotNavigable { .. })
    ));
    assert_eq!(nav.geodesic_field(&[far]).unwrap_err(), NavError::NoGoals);
    let bad = NavMeshConfig {
        cell_size: -1.0,
        ..Default::default()
    };
    assert!(matches!(
        NavMesh::build(&scene, &bad),
        Err(SceneError::Config {
            field: "cell_size",
            ..
        })
    ));
}

#[test]
fn curved_and_sloping_walls_are_extruded() {
    let xml = "<home version='5500' wallHeight='250.0'>\
      <wall id='arc' xStart='0' yStart='0' xEnd='400' yEnd='0' height='250' thickness='10' arcExtent='1.5707964'/>\
      <wall id='slope' xStart='0' yStart='300' xEnd='400' yEnd='300' height='250' heightAtEnd='100' thickness='10'/>\
    </home>";
    let s = load(xml).unwrap();
    let arc = s.instances().iter().find(|i| i.name == "wall arc").unwrap();
    // a quarter-circle arc over a 4 m chord bulges by r (1 - cos 45 deg) = 0.83 m
    let bulge = arc.bounds.extents().y;
    assert!((bulge - (0.828 + 0.1)).abs() < 0.06, "arc bulge {bulge}");
    let slope = s
        .instances()
        .iter()
        .find(|i| i.name == "wall slope")
        .unwrap();
    assert!((slope.bounds.max.z - 2.5).abs() < 1e-6);
    // the top at the far end is 1 m high
    let top_at_end = s
        .triangles()
        .iter()
        .zip(s.triangle_instances())
        .filter(|(_, i)| **i == slope.id)
        .flat_map(|(t, _)| t.iter().map(|&v| s.vertices()[v as usize]))
        .filter(|v| v[0] > 3.99)
        .map(|v| v[2])
        .fold(f32::MIN, f32::max);
    assert!((top_at_end - 1.0).abs() < 1e-3, "{top_at_end}");
}

mod fuzz {
    use proptest::prelude::*;
    use sornav_platform_sim::obj::parse_obj;

    use super::{WALLS, load};

    proptest! {
        #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

        /// Random text never panics the OBJ reader; every face it returns is in range.
        #[test]
        fn obj_reader_never_panics(text in "(v( -?[0-9]{1,3}(\\.[0-9])?){2,3}\n|f( -?[0-9]{1,2}(/[0-9]?){0,2}){1,4}\n|usemtl x\n|#.*\n|garbage\n){0,30}") {
            if let Ok(m) = parse_obj(&text, "fuzz.obj") {
                prop_assert!(m.triangles.iter().flatten().all(|&i| (i as usize) < m.vertices.len()));
            }
        }

        /// Truncating or corrupting a home anywhere gives a scene or a typed error, never a panic.
        #[test]
        fn home_loader_never_panics(cut in 0usize..WALLS.len(), pos in 0usize..WALLS.len(), byte in any::<u8>()) {
            let mut bytes = WALLS.as_bytes()[..cut.max(1)].to_vec();
            if pos < bytes.len() {
                bytes[pos] = byte;
            }
            let text = String::from_utf8_lossy(&bytes);
            let _ = load(&text);
        }
    }
}

#[test]
fn huge_scenes_are_rejected_not_allocated() {
    let xml = WALLS.replace("xEnd='400' yEnd='0'", "xEnd='4e9' yEnd='0'");
    let s = load(&xml).unwrap();
    assert!(matches!(
        NavMesh::build(&s, &NavMeshConfig::default()),
        Err(SceneError::Invalid(_))
    ));
}

/// Issue 21: a wall's `arcExtent` was never bounded: `1e12` aborted
/// allocating 91 TB of arc points, `1e300` panicked ("capacity overflow"),
/// `1e5` took 108 s and 4 GB (tests/data/sh3d_wall_arc_extent.xml).
#[test]
fn unbounded_wall_arc_extent_is_an_attribute_error() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/sh3d_wall_arc_extent.xml");
    let xml = std::fs::read_to_string(path).unwrap();
    assert!(xml.contains("arcExtent='1e12'"));
    let began = std::time::Instant::now();
    for extent in ["1e12", "1e300", "1e5", "-7", "6.2832"] {
        let doc = xml.replace("'1e12'", &format!("'{extent}'"));
        match load(&doc) {
            Err(SceneError::Attribute {
                element,
                attribute,
                message,
            }) => {
                assert_eq!(
                    (element.as_str(), attribute.as_str()),
                    ("wall 'wall0'", "arcExtent")
                );
                assert!(message.contains("2 pi"), "{message}");
            }
            Err(other) => panic!("{extent}: expected an attribute error, got {other}"),
            Ok(_) => panic!("{extent}: expected an attribute error, got a scene"),
        }
    }
    // just under a full turn still builds (36 pieces at most)
    let nearly_full = load(&xml.replace("'1e12'", "'6.28'")).unwrap();
    assert!(
        nearly_full
            .instances()
            .iter()
            .any(|i| i.name == "wall wall0")
    );
    assert!(began.elapsed() < std::time::Duration::from_secs(10));
}

#[test]
fn sh3d_entries_that_inflate_past_the_limit_are_zip_errors() {
    use sornav_platform_sim::sh3d::{MAX_SH3D_ENTRY_BYTES, sh3d_from_slice};
    use std::io::Write;
    // A `Home.xml` padded with spaces to one byte past the limit deflates to
    // about 65 KB: without the bound such an archive inflates without limit.
    let mut xml = WALLS.as_bytes().to_vec();
    xml.resize(MAX_SH3D_ENTRY_BYTES as usize + 1, b' ');
    let mut z = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .large_file(false);
    z.start_file("Home.xml", options).unwrap();
    z.write_all(&xml).unwrap();
    let bytes = z.finish().unwrap().into_inner();
    assert!(bytes.len() < 1 << 20, "{}", bytes.len());
    match sh3d_from_slice(&bytes, "bomb", &Sh3dOptions::default()) {
        Err(SceneError::Zip(m)) => assert!(m.contains("MAX_SH3D_ENTRY_BYTES"), "{m}"),
        other => panic!("{other:?}"),
    }
    // The same home within the limit loads.
    let mut z = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    z.start_file("Home.xml", options).unwrap();
    z.write_all(WALLS.as_bytes()).unwrap();
    let bytes = z.finish().unwrap().into_inner();
    assert!(sh3d_from_slice(&bytes, "home", &Sh3dOptions::default()).is_ok());
}
