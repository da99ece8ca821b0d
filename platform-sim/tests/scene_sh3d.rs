//! The six shared Sweet Home 3D homes and the two `.sh3d` archives.
//!
//! Expected figures are written from the `Home.xml` files (read by hand and
//! with an independent script, never from this crate's output): `<level>`
//! elements (1 when there are none), `<room>` elements with at least three
//! points, and pieces counted by name on visible levels, with names mapped to
//! categories by hand. For 2BedroomApartment, for example: beds = "Bed" +
//! "Corner bunk bed", chairs = 6 "Chair" + 1 "Armchair", plants = "Plant" + 2
//! "Flowers", sinks = 2 "Washbasin with cabinet" + "Sink", TVs = "TV unit" (a
//! flat TV on its stand), tables = "Coffee table" + "Round table" + 3
//! "Table", cabinets = "Kitchen cabinet" + 5 "Kitchen upper cabinet" + 4
//! "Wardrobe" + 2 "Bedside table" (a nightstand to the agent's normaliser,
//! folded into cabinet by the simulator's catalogue), chests of drawers = 2 "Chest", seating = 2
//! "Bank", shelving = 4 "Bookcase"; objects = every visible
//! `<pieceOfFurniture>` and `<light>` (groups flattened) except staircases,
//! and stairs = pieces with a `staircaseCutOutShape`.

use std::path::PathBuf;
use std::sync::OnceLock;

use nalgebra::Point3;
use sornav_platform_sim::sh3d::{Sh3dOptions, home_from_xml_str};
use sornav_platform_sim::{InstanceKind, NavMesh, NavMeshConfig, Scene};
use sornav_test_support::shared_data;

/// What a home's XML states.
struct Expected {
    home: &'static str,
    levels: usize,
    rooms: usize,
    /// Counts in the order of [`CATS`].
    counts: [usize; 15],
    /// All furniture instances (kind `Object`).
    objects: usize,
    /// Staircases (kind `Stairs`).
    stairs: usize,
}

const CATS: [&str; 15] = [
    "bed",
    "toilet",
    "sofa",
    "tv_monitor",
    "chair",
    "plant",
    "bathtub",
    "sink",
    "shower",
    "table",
    "cabinet",
    "stool",
    "chest_of_drawers",
    "seating",
    "shelving",
];

const EXPECTED: [Expected; 6] = [
    Expected {
        home: "Studio",
        levels: 1,
        rooms: 5,
        counts: [1, 1, 0, 2, 3, 3, 0, 2, 1, 2, 6, 1, 0, 0, 2],
        objects: 43,
        stairs: 0,
    },
    Expected {
        home: "2BedroomApartment",
        levels: 1,
        rooms: 7,
        counts: [2, 1, 1, 1, 7, 3, 1, 3, 0, 5, 12, 3, 2, 2, 4],
        objects: 72,
        stairs: 0,
    },
    Expected {
        home: "3BedroomApartment",
        levels: 1,
        rooms: 9,
        counts: [3, 1, 1, 1, 12, 6, 1, 3, 0, 7, 13, 2, 3, 0, 5],
        objects: 99,
        stairs: 0,
    },
    Expected {
        home: "4BedroomHouse",
        levels: 2,
        rooms: 11,
        counts: [4, 2, 1, 1, 13, 1, 1, 4, 1, 6, 20, 3, 5, 0, 5],
        objects: 99,
        stairs: 0,
    },
    Expected {
        home: "2BedroomHouseWithBasement",
        levels: 3,
        rooms: 13,
        counts: [2, 1, 1, 2, 8, 2, 1, 2, 0, 4, 13, 1, 1, 0, 12],
        objects: 127,
        stairs: 1,
    },
    Expected {
        home: "3BedroomHouseWithAttic",
        levels: 4,
        rooms: 11,
        counts: [3, 2, 0, 1, 10, 14, 1, 3, 1, 4, 15, 2, 1, 2, 3],
        objects: 93,
        stairs: 2,
    },
];

/// The `.sh3d` archives hold other versions of two homes (format 6500); their
/// embedded `Home.xml` differs from `homes/*.xml` (Studio.sh3d: 2 "Square
/// table" and a "Box" and 3 "Cylinder" instead of 2 "Table", the "Mirror" and
/// 3 "Pipe"; 4-BedroomHouse.sh3d: "Single bed" and "Loft double bed", 5
/// "Bedside table", 3 "Square table", 5 "Kitchen cabinet", 6 visible "Box").
const EXPECTED_SH3D: [Expected; 2] = [
    Expected {
        home: "Studio",
        levels: 1,
        rooms: 5,
        counts: [1, 1, 0, 2, 3, 3, 0, 2, 1, 2, 6, 1, 0, 0, 2],
        objects: 43,
        stairs: 0,
    },
    Expected {
        home: "4-BedroomHouse",
        levels: 2,
        rooms: 11,
        counts: [4, 2, 1, 1, 13, 1, 1, 4, 1, 4, 19, 3, 5, 0, 4],
        objects: 99,
        stairs: 0,
    },
];

fn check(scene: &Scene, e: &Expected) {
    let name = e.home;
    assert_eq!(scene.levels().len(), e.levels, "{name}: levels");
    assert_eq!(scene.rooms().len(), e.rooms, "{name}: rooms");
    for (c, want) in CATS.iter().zip(e.counts) {
        assert_eq!(scene.objects_of(c).count(), want, "{name}: {c}");
    }
    assert_eq!(scene.objects().count(), e.objects, "{name}: objects");
    let stairs = scene
        .instances()
        .iter()
        .filter(|i| i.kind == InstanceKind::Stairs)
        .count();
    assert_eq!(stairs, e.stairs, "{name}: stairs");
}

fn dir() -> Option<PathBuf> {
    shared_data("sh3d-homes")
}

fn load(name: &str) -> Option<(&'static Scene, &'static NavMesh)> {
    static CACHE: OnceLock<Vec<(String, Scene, NavMesh)>> = OnceLock::new();
    let d = dir()?;
    let all = CACHE.get_or_init(|| {
        EXPECTED
            .iter()
            .map(|Expected { home: n, .. }| {
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
    for e in &EXPECTED {
        let name = e.home;
        let Some((scene, nav)) = load(name) else {
            return;
        };
        check(scene, e);
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
fn sh3d_archives_match_their_embedded_xml() {
    let Some(d) = dir() else { return };
    for e in &EXPECTED_SH3D {
        let s = Scene::from_sh3d(&d.join(format!("sh3d/{}.sh3d", e.home)))
            .unwrap_or_else(|err| panic!("{}: {err}", e.home));
        check(&s, e);
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

/// The example homes' staircase models have 21.8 cm risers (2.62 m level
/// height in 12 steps), above Habitat's 0.2 m climb; the importer re-steps
/// them (`restep_staircase`). With the default height field (0.2 m step) a
/// path climbs from each floor to the next, every step on it at most
/// 0.19 m, and every walkable height of the staircase lies at most 0.19 m
/// above the next lower one (or the floor).
#[test]
fn multi_level_homes_connect_floors() {
    for name in ["2BedroomHouseWithBasement", "3BedroomHouseWithAttic"] {
        let Some((scene, nav)) = load(name) else {
            return;
        };
        assert_eq!(nav.config().max_step, 0.2);
        let (z0, z1) = (scene.levels()[0].elevation, scene.levels()[1].elevation);
        assert!((z1 - z0 - 2.62).abs() < 1e-9, "{name}: level height");
        let at = |s: u32, z: f64| (nav.span_center(s).z - z).abs() < 0.02;
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
                .find(|&s| nav.spans()[s as usize].region == main && at(s, z))
                .map(|s| nav.span_center(s))
        };
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
        let riser = path
            .windows(2)
            .map(|w| (w[1].z - w[0].z).abs())
            .fold(0.0, f64::max);
        assert!(riser <= 0.19 + 1e-3, "{name}: largest step {riser}");
        // the staircases' walkable heights: no riser above 0.19 m
        for (k, inst) in scene.instances().iter().enumerate() {
            if inst.kind != InstanceKind::Stairs {
                continue;
            }
            let foot = inst.bounds.min.z;
            let mut hs: Vec<f64> = vec![foot];
            let verts = scene.vertices();
            for (t, &i) in scene.triangles().iter().zip(scene.triangle_instances()) {
                if i as usize != k {
                    continue;
                }
                let p = t.map(|v| verts[v as usize].map(f64::from));
                let (a, b, c) = (Point3::from(p[0]), Point3::from(p[1]), Point3::from(p[2]));
                let n = (b - a).cross(&(c - a));
                if n.norm() > 1e-9 && n.z / n.norm() > 0.9 && a.z <= z1 + 0.02 {
                    hs.push(a.z);
                }
            }
            hs.sort_by(f64::total_cmp);
            let gap = hs.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
            assert!(gap <= 0.19 + 1e-3, "{name}/{}: riser {gap}", inst.name);
        }
    }
}

/// OBJ text of two boxes (model units, y up): a base x in [0, 2], y in
/// [0, 1], z in [0, 1] and a tower x in [1.5, 2], y in [1, 3], z in [0.5, 1]
/// (right end, front half). `map` transforms each vertex.
fn wedge_obj(map: impl Fn([f64; 3]) -> [f64; 3]) -> String {
    let mut out = String::from("mtllib missing.mtl\nusemtl no_such_material\n");
    let boxes = [
        ([0.0, 0.0, 0.0], [2.0, 1.0, 1.0]),
        ([1.5, 1.0, 0.5], [2.0, 3.0, 1.0]),
    ];
    for (k, (lo, hi)) in boxes.iter().enumerate() {
        for i in 0..8 {
            let v = [
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            ];
            let v = map(v);
            out += &format!("v {} {} {}\n", v[0], v[1], v[2]);
        }
        let b = k * 8 + 1;
        for f in [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ] {
            out += &format!("f {} {} {} {}\n", b + f[0], b + f[1], b + f[2], b + f[3]);
        }
    }
    out
}

fn temp_models(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sornav-sh3d-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("wedge.obj"), wedge_obj(|v| v)).unwrap();
    // The same model authored z up; `modelRotation` (rows 1 0 0 / 0 0 1 /
    // 0 -1 0) maps (x, y, z) to (x, z, -y), which restores the y-up wedge.
    std::fs::write(
        dir.join("wedge_zup.obj"),
        wedge_obj(|v| [v[0], -v[2], v[1]]),
    )
    .unwrap();
    dir
}

/// (min, max) of the scene x and y of an instance's vertices above `z`.
fn footprint_above(scene: &Scene, name: &str, z: f32) -> ([f32; 2], [f32; 2]) {
    let id = scene
        .instances()
        .iter()
        .find(|i| i.name == name)
        .unwrap_or_else(|| panic!("{name}"))
        .id;
    let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
    for (t, _) in scene
        .triangles()
        .iter()
        .zip(scene.triangle_instances())
        .filter(|(_, i)| **i == id)
    {
        for &v in t {
            let p = scene.vertices()[v as usize];
            if p[2] > z {
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
    }
    (lo, hi)
}

fn assert_box(got: ([f32; 2], [f32; 2]), want: ([f32; 2], [f32; 2]), what: &str) {
    for k in 0..2 {
        assert!(
            (got.0[k] - want.0[k]).abs() < 1e-3 && (got.1[k] - want.1[k]).abs() < 1e-3,
            "{what}: got {got:?}, want {want:?}"
        );
    }
}

/// Sweet Home 3D's placement rule with an asymmetric model, expectations
/// worked out by hand from the rule and the plan's axes (x right, y down,
/// angles clockwise on the plan, a model's front (+z) facing down the plan):
/// centre the bounds, scale to width x height x depth, mirror, rotate by
/// `angle`, translate to (x, y, level elevation + elevation); `modelRotation`
/// first. Scene y = -plan y.
#[test]
fn furniture_follows_the_sweet_home_3d_placement_rule() {
    let models = temp_models("placement");
    let piece = |name: &str, model: &str, x: f64, angle: f64, extra: &str| {
        format!(
            "<pieceOfFurniture level='up' name='{name}' model='com/eteks/sweethome3d/io/resources/{model}' \
             x='{x}' y='200' elevation='20' angle='{angle}' width='200' depth='100' height='150' {extra}/>"
        )
    };
    let xml = format!(
        "<home version='5500' wallHeight='250.0'>\
         <level id='ground' name='Ground' elevation='0' floorThickness='12' height='250'/>\
         <level id='up' name='Up' elevation='100' floorThickness='12' height='250'/>\
         {}{}{}{}</home>",
        piece("plain", "wedge.obj", 300.0, 1.5707964, ""),
        piece(
            "mirrored",
            "wedge.obj",
            700.0,
            1.5707964,
            "modelMirrored='true'"
        ),
        piece(
            "rotated",
            "wedge_zup.obj",
            1100.0,
            1.5707964,
            "modelRotation='1 0 0 0 0 1 0 -1 0'"
        ),
        piece("front", "wedge.obj", 1500.0, 0.0, ""),
    );
    let scene = home_from_xml_str(&xml, "placement", &models, &Sh3dOptions::default()).unwrap();
    assert_eq!(scene.objects().count(), 4);
    for o in scene.objects() {
        assert_eq!(o.level, 1, "{}", o.name);
        // level 1 m + elevation 0.2 m; height 1.5 m
        assert!(
            (o.bounds.min.z - 1.2).abs() < 1e-4,
            "{}: {:?}",
            o.name,
            o.bounds
        );
        assert!(
            (o.bounds.max.z - 2.7).abs() < 1e-4,
            "{}: {:?}",
            o.name,
            o.bounds
        );
    }
    // Rotated by 90 deg clockwise on the plan: the model's right end (+x)
    // points down the plan (scene -y), its front (+z) to the plan's left
    // (scene -x). Footprint 1 m (depth) along x, 2 m (width) along y.
    let all = |n: &str| footprint_above(&scene, n, 0.0);
    let tower = |n: &str| footprint_above(&scene, n, 2.0);
    assert_box(all("plain"), ([2.5, -3.0], [3.5, -1.0]), "plain");
    assert_box(tower("plain"), ([2.5, -3.0], [3.0, -2.5]), "plain tower");
    // Mirroring flips the model's x before the rotation.
    assert_box(all("mirrored"), ([6.5, -3.0], [7.5, -1.0]), "mirrored");
    assert_box(
        tower("mirrored"),
        ([6.5, -1.5], [7.0, -1.0]),
        "mirrored tower",
    );
    // modelRotation turns the z-up model into the same y-up piece.
    assert_box(all("rotated"), ([10.5, -3.0], [11.5, -1.0]), "rotated");
    assert_box(
        tower("rotated"),
        ([10.5, -3.0], [11.0, -2.5]),
        "rotated tower",
    );
    // Angle 0: right end to the right, front down the plan (scene -y).
    assert_box(all("front"), ([14.0, -2.5], [16.0, -1.5]), "front");
    assert_box(tower("front"), ([15.5, -2.5], [16.0, -2.0]), "front tower");
    std::fs::remove_dir_all(&models).ok();
}

/// A wall between two halves of a room: a door (an opening from the floor,
/// at least 1.8 m high) is cut through it and left open, so the halves
/// connect; a window (opening above the floor) keeps them apart.
#[test]
fn doors_are_open_and_windows_are_not() {
    let models = temp_models("doors");
    let home = |opening: &str| {
        format!(
            "<home version='5500' wallHeight='250.0'>\
             <room name='Hall'><point x='0' y='0'/><point x='600' y='0'/><point x='600' y='300'/><point x='0' y='300'/></room>\
             <wall id='middle' xStart='300' yStart='0' xEnd='300' yEnd='300' height='250' thickness='10'/>\
             {opening}</home>"
        )
    };
    let door = "<doorOrWindow name='Door' model='com/eteks/sweethome3d/io/resources/wedge.obj' \
                x='300' y='150' angle='1.5707964' width='90' depth='10' height='210'/>";
    let window = "<doorOrWindow name='Window' model='com/eteks/sweethome3d/io/resources/wedge.obj' \
                  x='300' y='150' elevation='100' angle='1.5707964' width='90' depth='10' height='100'/>";
    let (left, right) = (Point3::new(1.5, -1.5, 0.0), Point3::new(4.5, -1.5, 0.0));
    let cfg = NavMeshConfig::default();

    let with_door =
        home_from_xml_str(&home(door), "door", &models, &Sh3dOptions::default()).unwrap();
    assert!(
        with_door
            .instances()
            .iter()
            .any(|i| i.kind == InstanceKind::Door)
    );
    let nav = NavMesh::build(&with_door, &cfg).unwrap();
    assert!(
        nav.connected(&left, &right).unwrap(),
        "the door is passable"
    );
    let d = nav.distance(&left, &right).unwrap();
    assert!(d.is_finite() && d >= 3.0 - 1e-9, "through the door: {d}");
    // The opening spans the door's width: the wall is cut from y = -1.05 to -1.95.
    assert!(nav.is_navigable(&Point3::new(3.0, -1.5, 0.0)));

    let with_window =
        home_from_xml_str(&home(window), "window", &models, &Sh3dOptions::default()).unwrap();
    assert!(
        with_window
            .instances()
            .iter()
            .any(|i| i.kind == InstanceKind::Window)
    );
    let nav = NavMesh::build(&with_window, &cfg).unwrap();
    assert!(nav.is_navigable(&left) && nav.is_navigable(&right));
    assert!(
        !nav.connected(&left, &right).unwrap(),
        "a window is not a door"
    );
    assert!(!nav.is_navigable(&Point3::new(3.0, -1.5, 0.0)));
    std::fs::remove_dir_all(&models).ok();
}
