//! The six shared Sweet Home 3D homes and the two `.sh3d` archives.
//!
//! Expected figures are written from the `Home.xml` files: `<level>` elements
//! (1 when there are none), `<room>` elements with at least three points, and
//! furniture counted by name on visible levels, e.g. for 2BedroomApartment:
//! beds = "Bed" + "Corner bunk bed", chairs = 6 "Chair" + 1 "Armchair",
//! plants = "Plant" + 2 "Flowers", sinks = 2 "Washbasin with cabinet" + "Sink",
//! TVs = "TV unit" (a flat TV on its stand) + "Flat TV".

use std::path::PathBuf;
use std::sync::OnceLock;

use nalgebra::Point3;
use sornav_platform_sim::{InstanceKind, NavMesh, NavMeshConfig, Scene};
use sornav_test_support::shared_data;

/// (home, levels, rooms, [bed, toilet, sofa, tv_monitor, chair, plant, bathtub, sink, shower])
const EXPECTED: [(&str, usize, usize, [usize; 9]); 6] = [
    ("Studio", 1, 5, [1, 1, 0, 2, 3, 3, 0, 2, 1]),
    ("2BedroomApartment", 1, 7, [2, 1, 1, 1, 7, 3, 1, 3, 0]),
    ("3BedroomApartment", 1, 9, [3, 1, 1, 1, 12, 6, 1, 3, 0]),
    ("4BedroomHouse", 2, 11, [4, 2, 1, 1, 13, 1, 1, 4, 1]),
    (
        "2BedroomHouseWithBasement",
        3,
        13,
        [2, 1, 1, 2, 8, 2, 1, 2, 0],
    ),
    (
        "3BedroomHouseWithAttic",
        4,
        11,
        [3, 2, 0, 1, 10, 14, 1, 3, 1],
    ),
];
const CATS: [&str; 9] = [
    "bed",
    "toilet",
    "sofa",
    "tv_monitor",
    "chair",
    "plant",
    "bathtub",
    "sink",
    "shower",
];

fn dir() -> Option<PathBuf> {
    shared_data("sh3d-homes")
}

fn load(name: &str) -> Option<(&'static Scene, &'static NavMesh)> {
    static CACHE: OnceLock<Vec<(String, Scene, NavMesh)>> = OnceLock::new();
    let d = dir()?;
    let all = CACHE.get_or_init(|| {
        EXPECTED
            .iter()
            .map(|(n, ..)| {
                let s = Scene::from_home_xml(&d.join(format!("homes/{n}.xml")), &d.join("models"))
                    .unwrap_or_else(|e| panic!("{n}: {e}"));
                let nav = NavMesh::build(&s, &NavMeshConfig::default()).unwrap();
                (n.to_string(), s, nav)
            })
            .collect()
    });
    all.iter().find(|e| e.0 == name).map(|e| (&e.1, &e.2))
}

#[test]
fn homes_match_their_xml() {
    for (name, levels, rooms, counts) in EXPECTED {
        let Some((scene, nav)) = load(name) else {
            return;
        };
        assert_eq!(scene.levels().len(), levels, "{name}: levels");
        assert_eq!(scene.rooms().len(), rooms, "{name}: rooms");
        for (c, want) in CATS.iter().zip(counts) {
            assert_eq!(scene.objects_of(c).count(), want, "{name}: {c}");
        }
        assert!(
            nav.walkable_area() > 5.0,
            "{name}: walkable area {}",
            nav.walkable_area()
        );
        let out = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join(format!("../target/walkable_{name}.png"));
        nav.save_topdown_png(&out).unwrap();
    }
}

#[test]
fn loading_twice_gives_identical_scenes() {
    let Some(d) = dir() else { return };
    let p = d.join("homes/Studio.xml");
    let a = Scene::from_home_xml(&p, &d.join("models")).unwrap();
    let b = Scene::from_home_xml(&p, &d.join("models")).unwrap();
    assert_eq!(a, b);
    // serde round trip (JSON floats may move by one ulp, so compare the mesh
    // and the labels exactly and the bounds within tolerance)
    let json = serde_json::to_string(&a).unwrap();
    let c: Scene = serde_json::from_str(&json).unwrap();
    assert_eq!(a.vertices(), c.vertices());
    assert_eq!(a.triangles(), c.triangles());
    assert_eq!(a.triangle_instances(), c.triangle_instances());
    for (x, y) in a.instances().iter().zip(c.instances()) {
        assert_eq!(
            (x.kind, &x.category, &x.name, x.level, x.room),
            (y.kind, &y.category, &y.name, y.level, y.room)
        );
        assert!(
            (x.bounds.min - y.bounds.min).norm() < 1e-9
                && (x.bounds.max - y.bounds.max).norm() < 1e-9
        );
    }
}

#[test]
fn sh3d_archives_load_like_their_xml() {
    let Some(d) = dir() else { return };
    let s = Scene::from_sh3d(&d.join("sh3d/Studio.sh3d")).unwrap();
    let (x, _) = load("Studio").unwrap();
    assert_eq!(s.rooms().len(), x.rooms().len());
    for c in CATS {
        assert_eq!(s.objects_of(c).count(), x.objects_of(c).count(), "{c}");
    }
}

/// Handedness: plan x right / y down must become scene x right / y up. In the
/// Studio plan (Home.xml) the toilet (x=188.9, y=408.2 cm) lies right of and
/// below (larger plan y) the fridge (x=43.8, y=44.0 cm).
#[test]
fn handedness_matches_the_plan() {
    let Some((scene, _)) = load("Studio") else {
        return;
    };
    let centre = |cat: &str| {
        scene
            .objects_of(cat)
            .next()
            .map(|o| o.bounds.center())
            .unwrap()
    };
    let toilet = centre("toilet");
    let fridge = centre("refrigerator");
    assert!(
        (toilet.x - 1.889).abs() < 0.3 && (toilet.y + 4.082).abs() < 0.3,
        "{toilet}"
    );
    assert!(
        (fridge.x - 0.438).abs() < 0.3 && (fridge.y + 0.440).abs() < 0.3,
        "{fridge}"
    );
    assert!(toilet.x > fridge.x && toilet.y < fridge.y);
    // furniture stands on the floor, z up
    let bed = scene.objects_of("bed").next().unwrap();
    assert!(bed.bounds.min.z.abs() < 0.05 && bed.bounds.max.z > 0.3);
}

/// The example homes' staircases have 21.8 cm risers (2.62 m level height in
/// 12 steps), above Habitat's 0.2 m climb, so this test builds the height
/// field with a 0.22 m step.
#[test]
fn multi_level_homes_connect_floors() {
    let Some(d) = dir() else { return };
    let cfg = NavMeshConfig {
        max_step: 0.22,
        ..NavMeshConfig::default()
    };
    for name in ["2BedroomHouseWithBasement", "3BedroomHouseWithAttic"] {
        let Some((scene, _)) = load(name) else { return };
        let nav = NavMesh::build(scene, &cfg).unwrap();
        let nav = &nav;
        let _ = &d;
        assert!(
            scene
                .instances()
                .iter()
                .any(|i| i.kind == InstanceKind::Stairs),
            "{name}: stairs"
        );
        let main = nav.largest_region().unwrap();
        let on = |z: f64| {
            (0..nav.span_count() as u32)
                .find(|&s| {
                    nav.spans()[s as usize].region == main
                        && (nav.span_center(s).z - z).abs() < 0.02
                })
                .map(|s| nav.span_center(s))
        };
        let (z0, z1) = (scene.levels()[0].elevation, scene.levels()[1].elevation);
        let a = on(z0).unwrap_or_else(|| panic!("{name}: no walkable floor at {z0}"));
        let b = on(z1).unwrap_or_else(|| panic!("{name}: floor at {z1} not connected to {z0}"));
        let d = nav.distance(&a, &b).unwrap();
        let e = (b - a).norm();
        assert!(
            d.is_finite() && d > e,
            "{name}: geodesic {d} vs euclidean {e}"
        );
        let path = nav.path(&a, &b).unwrap().unwrap();
        assert!(
            path.iter()
                .any(|p: &Point3<f64>| p.z > z0 + 0.5 && p.z < z1 - 0.5),
            "{name}: path climbs stairs"
        );
    }
}
