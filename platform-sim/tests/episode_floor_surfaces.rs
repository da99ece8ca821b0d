//! Agents are never placed on furniture: walkable furniture tops (a bed of
//! 1.2 m x 2 m keeps more than 1 m^2 after erosion) survive island removal,
//! but the height field marks them as non-floor islands and the episode
//! generator draws starts and view points on floor islands only.

use nalgebra::Point3;
use sornav_platform_sim::category::MP3D_GOALS;
use sornav_platform_sim::episodes::{GeneratorConfig, generate_episodes};
use sornav_platform_sim::geometry::MeshBuilder;
use sornav_platform_sim::{
    CameraConfig, Episode, InstanceKind, NavMesh, NavMeshConfig, ProceduralConfig, Scene,
    SimConfig, Simulator,
};

mod common;

/// A 6 m x 5 m floor slab of `floor_kind` with a 1.6 m x 2.1 m "bed" box,
/// 0.5 m high, in its middle.
fn room_with_bed(floor_kind: InstanceKind) -> Scene {
    let mut b = MeshBuilder::new();
    let f = b.add_instance(floor_kind, "floor", "floor", 0);
    b.aabb_box(Point3::new(0.0, 0.0, -0.1), Point3::new(6.0, 5.0, 0.0), f);
    let bed = b.add_instance(InstanceKind::Object, "bed", "bed", 0);
    b.aabb_box(Point3::new(2.0, 1.5, 0.0), Point3::new(3.6, 3.6, 0.5), bed);
    common::one_level_scene(b, "bed")
}

#[test]
fn furniture_tops_are_not_floor_islands() {
    let scene = room_with_bed(InstanceKind::Floor);
    let nav = NavMesh::build(&scene, &NavMeshConfig::default()).unwrap();
    // two islands: the floor around the bed and the bed top (1.24 x 1.74 m
    // after erosion, above the 1 m^2 threshold)
    assert_eq!(nav.region_areas().len(), 2, "{:?}", nav.region_areas());
    let top = nav
        .span_at(&Point3::new(2.8, 2.5, 0.5))
        .expect("the bed top is walkable");
    let floor = nav
        .span_at(&Point3::new(0.8, 0.8, 0.0))
        .expect("the floor is walkable");
    assert!(!nav.is_floor_span(top));
    assert!(nav.is_floor_span(floor));
    let top_region = nav.spans()[top as usize].region;
    let top_area = nav.region_areas()[top_region as usize];
    assert!(top_area > 1.5 && top_area < 2.5, "bed top {top_area} m^2");
    assert!((nav.walkable_area() - nav.floor_area() - top_area).abs() < 1e-9);
    // a scene without floor instances: every island counts as floor
    let unlabelled = room_with_bed(InstanceKind::Object);
    let nav = NavMesh::build(&unlabelled, &NavMeshConfig::default()).unwrap();
    assert_eq!(nav.region_areas().len(), 2);
    assert!((0..2).all(|r| nav.is_floor_region(r)));
    assert!((nav.walkable_area() - nav.floor_area()).abs() < 1e-9);
}

/// A carpet (an object a few millimetres thick lying on the floor) is
/// floor: inside its outline its top and bottom faces are separate
/// surfaces in the height field, and the top must keep the floor's ground
/// height (Habitat counts a rug as floor; a television seen from the rug
/// in front of it is seen from a view point). A low platform 0.1 m high is
/// not.
#[test]
fn carpets_are_floor_and_platforms_are_not() {
    for (thickness, floor) in [(0.002, true), (0.005, true), (0.03, true), (0.1, false)] {
        let mut b = MeshBuilder::new();
        let f = b.add_instance(InstanceKind::Floor, "floor", "floor", 0);
        b.aabb_box(Point3::new(0.0, 0.0, -0.1), Point3::new(6.0, 5.0, 0.0), f);
        let rug = b.add_instance(InstanceKind::Object, "rug", "carpet", 0);
        b.aabb_box(
            Point3::new(1.5, 1.0, 0.0),
            Point3::new(4.5, 4.0, thickness),
            rug,
        );
        let bed = b.add_instance(InstanceKind::Object, "bed", "bed", 0);
        b.aabb_box(Point3::new(5.0, 4.0, 0.0), Point3::new(5.8, 4.8, 0.5), bed);
        let scene = common::one_level_scene(b, "bed");
        let nav = NavMesh::build(&scene, &NavMeshConfig::default()).unwrap();
        let on_rug = nav
            .span_at(&Point3::new(3.0, 2.5, thickness))
            .expect("the carpet is walkable");
        assert!(
            (f64::from(nav.spans()[on_rug as usize].floor) - thickness).abs() < 1e-3,
            "the span is the carpet's top"
        );
        assert_eq!(
            nav.is_floor_span(on_rug),
            floor,
            "a {thickness} m cover is floor: {floor}"
        );
    }
}

/// The object instance (not structure) that `p` stands on or in: `p` lies
/// inside the object's footprint, at least 0.1 m above its bottom (a carpet
/// does not count) and at most at its top (2 cm tolerance; a floor slab
/// resting on an object is higher).
fn object_under(scene: &Scene, p: &Point3<f64>) -> Option<u32> {
    scene
        .objects()
        .find(|o| {
            let b = &o.bounds;
            p.x > b.min.x
                && p.x < b.max.x
                && p.y > b.min.y
                && p.y < b.max.y
                && p.z >= b.min.z + 0.1
                && p.z <= b.max.z + 0.02
        })
        .map(|o| o.id)
}

fn simulator(scene: Scene, nav: NavMeshConfig) -> Simulator {
    let camera = CameraConfig {
        width: 64,
        height: 48,
        ..CameraConfig::default()
    };
    Simulator::new(
        scene,
        SimConfig {
            camera,
            nav,
            ..SimConfig::default()
        },
    )
    .unwrap()
}

/// Checks every start and view point; returns (poses checked, walkable spans
/// on furniture that a generator without the floor rule could have used).
fn check(sim: &Simulator, episodes: &[Episode]) -> (usize, usize) {
    let (scene, nav) = (sim.scene(), sim.nav());
    let mut poses = 0;
    for e in episodes {
        let mut all = vec![e.start_position];
        all.extend(e.view_point_positions());
        for p in all {
            poses += 1;
            assert!(
                object_under(scene, &p).is_none(),
                "{} episode {}: pose {p} on object {:?}",
                scene.name(),
                e.episode_id,
                object_under(scene, &p)
            );
            let s = nav.span_at(&p).expect("pose on the height field");
            assert!(nav.is_floor_span(s));
        }
    }
    let on_furniture = (0..nav.span_count() as u32)
        .filter(|&s| object_under(scene, &nav.span_center(s)).is_some())
        .count();
    // the floor rule removes exactly the spans on furniture (up to the
    // low-hanging thresholds and lamp bases below 0.1 m)
    for s in 0..nav.span_count() as u32 {
        if object_under(scene, &nav.span_center(s)).is_some() {
            assert!(
                !nav.is_floor_span(s),
                "{}: span {s} at {} on furniture belongs to a floor island",
                scene.name(),
                nav.span_center(s)
            );
        }
    }
    (poses, on_furniture)
}

fn generator(seed: u64) -> GeneratorConfig {
    GeneratorConfig {
        categories: MP3D_GOALS.iter().map(|c| (*c).to_string()).collect(),
        episodes_per_category: 2,
        seed,
        ..GeneratorConfig::default()
    }
}

#[test]
fn procedural_episodes_stay_off_furniture() {
    let (mut poses, mut hazard) = (0, 0);
    for seed in 0..8u64 {
        let scene = Scene::procedural(seed, &ProceduralConfig::default()).unwrap();
        let sim = simulator(scene, NavMeshConfig::default());
        let episodes = generate_episodes(&sim, &generator(seed)).unwrap();
        assert!(!episodes.is_empty());
        let (p, h) = check(&sim, &episodes);
        poses += p;
        hazard += h;
    }
    eprintln!("procedural: {poses} poses checked, {hazard} walkable spans on furniture");
    // the hazard is real: furniture tops are walkable in these houses
    assert!(hazard > 0);
}

#[test]
fn shared_home_episodes_stay_off_furniture() {
    let Some(dir) = sornav_test_support::shared_data("sh3d-homes") else {
        return;
    };
    let (mut poses, mut hazard) = (0, 0);
    for home in [
        "Studio",
        "2BedroomApartment",
        "3BedroomApartment",
        "4BedroomHouse",
        "2BedroomHouseWithBasement",
        "3BedroomHouseWithAttic",
    ] {
        let scene = Scene::from_home_xml(
            &dir.join("homes").join(format!("{home}.xml")),
            &dir.join("models"),
        )
        .unwrap();
        let sim = simulator(scene, NavMeshConfig::default());
        let episodes = generate_episodes(&sim, &generator(3)).unwrap();
        assert!(!episodes.is_empty(), "{home}");
        let (p, h) = check(&sim, &episodes);
        eprintln!(
            "{home}: {} episodes, {p} poses, {h} spans on furniture",
            episodes.len()
        );
        poses += p;
        hazard += h;
    }
    assert!(poses > 0);
    assert!(hazard > 0, "no walkable furniture top in the shared homes");
}

/// `object_under` itself: a point on the bed top is on the bed, a point on
/// the floor beside it is not, nor a point above the bed's top.
#[test]
fn object_under_recognises_tops() {
    let scene = room_with_bed(InstanceKind::Floor);
    let bed = scene.objects_of("bed").next().unwrap().id;
    assert_eq!(object_under(&scene, &Point3::new(2.8, 2.5, 0.5)), Some(bed));
    assert_eq!(object_under(&scene, &Point3::new(1.0, 1.0, 0.0)), None);
    assert_eq!(object_under(&scene, &Point3::new(2.8, 2.5, 0.3)), Some(bed));
    assert_eq!(object_under(&scene, &Point3::new(2.8, 2.5, 0.6)), None);
}
