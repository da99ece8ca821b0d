//! The multi-level frontier map on depth rendered by platform-sim: after a
//! scripted walk up (and down) the stairs of two-floor houses, both levels
//! and the stair joining them are in the map, built only from the rendered
//! frames and the walker's poses.

use nalgebra::Point3;
use sornav::frontier_graph::{FrontierMapConfig, LevelId};
use sornav_examples::walk::{Walker, walk_between};
use sornav_platform_sim::{ProceduralConfig, Scene};

fn check_two_levels(walker: &mut Walker, scene: &Scene, down: bool) {
    let _ = walker
        .map
        .frontier_graph(&Point3::new(0.0, 0.0, 0.0))
        .expect("graph");
    let levels: Vec<_> = walker.map.levels().collect();
    let (mut z0, mut z1) = (scene.levels()[0].elevation, scene.levels()[1].elevation);
    if down {
        std::mem::swap(&mut z0, &mut z1);
    }
    assert!(levels.len() >= 2, "levels {levels:?}");
    assert!((levels[0].floor_z - z0).abs() < 0.1, "{levels:?}");
    let upper = levels
        .iter()
        .find(|l| (l.floor_z - z1).abs() < 0.15)
        .map(|l| l.id)
        .unwrap_or_else(|| panic!("no level at {z1}: {levels:?}"));
    let (lo, hi) = if down {
        (upper, LevelId(0))
    } else {
        (LevelId(0), upper)
    };
    let stairs = walker.map.stairs();
    let s = stairs
        .iter()
        .find(|s| s.lower.level == Some(lo) && s.upper.level == Some(hi))
        .unwrap_or_else(|| {
            panic!(
                "no stair joins {lo:?} and {hi:?}: {:?}",
                stairs
                    .iter()
                    .map(|s| (s.lower.clone(), s.upper.clone(), s.length))
                    .collect::<Vec<_>>()
            )
        });
    // The stair climbs the storey in rises the map accepts between
    // neighbouring columns: a step, or inside a flight several risers of
    // treads shallower than a column (`max_stair_column_rise`).
    let config = FrontierMapConfig::default();
    let rise = config
        .grid
        .step_height
        .max(config.levels.max_stair_column_rise);
    assert!(
        s.path
            .windows(2)
            .all(|w| (w[1].z - w[0].z).abs() <= rise + 1e-6),
        "{:?}",
        s.path
    );
    assert!(s.length >= (z1 - z0).abs() - 1e-6);
    // And the map plans across it: a path from one floor to the other.
    let (a, b) = (s.lower.position, s.upper.position);
    let path = walker.map.path(&a, &b).expect("path query");
    assert!(path.is_some(), "no path over the stair from {a} to {b}");
}

#[test]
fn procedural_two_floor_houses_up_and_down() {
    let mut tried = 0;
    for seed in 0..40u64 {
        let scene = Scene::procedural(
            seed,
            &ProceduralConfig {
                floors: Some(2),
                ..ProceduralConfig::default()
            },
        )
        .expect("house");
        if scene.levels().len() < 2 {
            continue;
        }
        let mut up = walk_between(&scene, 0, 1, 160, 120).expect("walk up");
        check_two_levels(&mut up, &scene, false);
        let mut down = walk_between(&scene, 1, 0, 160, 120).expect("walk down");
        check_two_levels(&mut down, &scene, true);
        tried += 1;
        if tried == 2 {
            break;
        }
    }
    assert_eq!(tried, 2);
}

/// A two-floor Sweet Home 3D home of the shared data (4BedroomHouse.xml has
/// a second level without a walkable floor reached by stairs; the attic
/// house has a staircase between two walkable floors).
#[test]
fn sweet_home_two_floor_home() {
    let Some(dir) = sornav_test_support::shared_data("sh3d-homes") else {
        return;
    };
    let home = dir.join("homes/3BedroomHouseWithAttic.xml");
    let models = dir.join("models");
    let scene = match Scene::from_home_xml(&home, &models) {
        Ok(s) => s,
        Err(e) => panic!("{}: {e}", home.display()),
    };
    assert!(
        scene.levels().len() >= 2,
        "{} has two levels",
        home.display()
    );
    eprintln!(
        "levels {:?}",
        scene
            .levels()
            .iter()
            .map(|l| l.elevation)
            .collect::<Vec<_>>()
    );
    let mut up = walk_between(&scene, 0, 1, 160, 120).expect("walk up");
    check_two_levels(&mut up, &scene, false);
}
