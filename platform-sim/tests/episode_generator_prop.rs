//! proptest over random seeds: generated episodes satisfy their constraints
//! on small random houses, checked with independent tools (a fresh geodesic
//! field, parry's ray caster), and generation is deterministic.

use nalgebra::Vector3;
use proptest::prelude::*;
use sornav_platform_sim::episodes::generator::body_distance;
use sornav_platform_sim::episodes::{GeneratorConfig, generate_episodes};
use sornav_platform_sim::{Episode, ProceduralConfig, Scene, Simulator};

mod common;

fn check(sim: &Simulator, episodes: &[Episode], cfg: &GeneratorConfig) -> Result<(), String> {
    let (scene, nav) = (sim.scene(), sim.nav());
    let parry = common::ParryMesh::new(scene);
    let cam_h = sim.camera().config().mount_height;
    for e in episodes {
        let id = &e.episode_id;
        let start = nav
            .span_at(&e.start_position)
            .ok_or(format!("episode {id}: start not navigable"))?;
        if !nav.is_floor_span(start) {
            return Err(format!("episode {id}: start off the floor"));
        }
        let vps = e.view_point_positions();
        let field = nav.geodesic_field(&vps).map_err(|x| x.to_string())?;
        let d = field
            .distance(nav, &e.start_position)
            .map_err(|x| x.to_string())?;
        if !(cfg.min_geodesic..=cfg.max_geodesic).contains(&d) {
            return Err(format!("episode {id}: geodesic {d}"));
        }
        if !e.geodesic_distance.is_some_and(|r| (r - d).abs() <= 1e-6) {
            return Err(format!(
                "episode {id}: recorded {:?}, measured {d}",
                e.geodesic_distance
            ));
        }
        for g in &e.goals {
            let object = scene
                .instance(g.object_id as u32)
                .ok_or(format!("episode {id}: goal {} missing", g.object_id))?;
            if object.category != e.object_category {
                return Err(format!(
                    "episode {id}: goal of category {}",
                    object.category
                ));
            }
            for v in &g.view_points {
                if !nav
                    .span_at(&v.position)
                    .is_some_and(|s| nav.is_floor_span(s))
                {
                    return Err(format!(
                        "episode {id}: view point {} off the floor",
                        v.position
                    ));
                }
                let reach = body_distance(object, &v.position, cam_h);
                if reach > cfg.view_point_radius + 1e-9 {
                    return Err(format!(
                        "episode {id}: view point {reach} m from the object"
                    ));
                }
                let eye = v.position + Vector3::new(0.0, 0.0, cam_h);
                if !common::sees(&parry, &eye, object) {
                    return Err(format!(
                        "episode {id}: view point {} does not see object {}",
                        v.position, object.id
                    ));
                }
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    #[test]
    fn generated_episodes_satisfy_their_constraints(
        house in any::<u64>(),
        seed in any::<u64>(),
        floors in 1u32..=2,
    ) {
        let scene = Scene::procedural(
            house,
            &ProceduralConfig {
                floors: Some(floors),
                max_rooms_per_floor: 3,
                ..ProceduralConfig::default()
            },
        )
        .unwrap();
        let sim = common::simulator(scene, 32, 24);
        let cfg = GeneratorConfig { episodes_per_category: 1, seed, ..GeneratorConfig::default() };
        let episodes = generate_episodes(&sim, &cfg).unwrap();
        prop_assert!(!episodes.is_empty(), "house {house}: no episodes");
        prop_assert_eq!(check(&sim, &episodes, &cfg), Ok(()));
        // deterministic for a seed
        prop_assert_eq!(&episodes, &generate_episodes(&sim, &cfg).unwrap());
    }
}

/// The checker itself rejects broken episodes: a start moved off the
/// height field, a geodesic distance out of range, a view point moved away
/// from its object.
#[test]
fn the_checker_rejects_broken_episodes() {
    let scene = Scene::procedural(
        5,
        &ProceduralConfig {
            floors: Some(1),
            max_rooms_per_floor: 3,
            ..ProceduralConfig::default()
        },
    )
    .unwrap();
    let sim = common::simulator(scene, 32, 24);
    let cfg = GeneratorConfig {
        episodes_per_category: 1,
        ..GeneratorConfig::default()
    };
    let episodes = generate_episodes(&sim, &cfg).unwrap();
    assert_eq!(check(&sim, &episodes, &cfg), Ok(()));
    let mut off = episodes[..1].to_vec();
    off[0].start_position.z += 5.0;
    assert!(check(&sim, &off, &cfg).is_err());
    let tight = GeneratorConfig {
        max_geodesic: episodes[0].geodesic_distance.unwrap() - 0.01,
        ..cfg.clone()
    };
    assert!(check(&sim, &episodes[..1], &tight).is_err());
    // the floor span farthest from the goal object
    let mut far = episodes[..1].to_vec();
    let object = sim
        .scene()
        .instance(far[0].goals[0].object_id as u32)
        .unwrap();
    let nav = sim.nav();
    let away = (0..nav.span_count() as u32)
        .filter(|&s| nav.is_floor_span(s))
        .max_by(|&a, &b| {
            let d = |s| object.bounds.distance_xy(&nav.span_center(s));
            d(a).total_cmp(&d(b))
        })
        .unwrap();
    far[0].goals[0].view_points[0].position = nav.span_center(away);
    assert!(check(&sim, &far, &cfg).is_err());
}
