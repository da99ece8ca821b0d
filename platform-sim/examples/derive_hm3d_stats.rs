//! Regenerates `data/hm3d_val_stats.json`, the statistics the procedural house
//! generator samples from, out of the HM3D-Semantics v0.2 statistics in
//! `../shared/data/hm3d-sem-stats/` (HM3D-Semantics, Yadav et al. 2023).
//!
//! Only validation scenes (ids 00800-00899) are used, as the issue asks: the
//! procedural houses stand in for the evaluation distribution, while agent
//! priors are derived from train scenes elsewhere.
//!
//! Run: `cargo run -p sornav-platform-sim --example derive_hm3d_stats [data dir] [out file]`.

use std::collections::BTreeMap;
use std::error::Error;
use std::path::PathBuf;

use sornav_platform_sim::RoomType;
use sornav_platform_sim::category::{objectnav_category, room_type_from_name};
use sornav_platform_sim::procedural::{CategoryStats, HouseSize, HouseStats, RoomTypeStats};

/// Per room type: number of regions, and per category (regions holding it, instances).
type TypeCounts = BTreeMap<RoomType, (usize, BTreeMap<String, (usize, usize)>)>;

fn is_val(scene: &str) -> bool {
    scene
        .get(..5)
        .and_then(|s| s.parse::<u32>().ok())
        .is_some_and(|n| (800..900).contains(&n))
}

fn room_type(proposal: &str) -> Option<RoomType> {
    let p = proposal.trim();
    match p {
        "Hall/stairwell" => Some(RoomType::Hallway),
        "Unknown room" | "" => None,
        _ => Some(room_type_from_name(p)),
    }
}

fn main() -> Result<(), Box<dyn Error>> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(
        args.next()
            .unwrap_or_else(|| "../shared/data/hm3d-sem-stats".into()),
    );
    let out = PathBuf::from(
        args.next()
            .unwrap_or_else(|| "platform-sim/data/hm3d_val_stats.json".into()),
    );

    // house sizes of all val scenes
    let mut houses = Vec::new();
    let mut rdr = csv::Reader::from_path(dir.join("hm3d_scene_metadata.csv"))?;
    let hdr = rdr.headers()?.clone();
    let col = |n: &str| {
        hdr.iter()
            .position(|h| h == n)
            .ok_or_else(|| format!("column {n} missing"))
    };
    let (c_scene, c_split, c_floors, c_rooms, c_area) = (
        col("scene")?,
        col("split")?,
        col("num_floors")?,
        col("num_rooms")?,
        col("navigable_area")?,
    );
    for r in rdr.records() {
        let r = r?;
        if &r[c_split] != "val" {
            continue;
        }
        houses.push(HouseSize {
            scene: r[c_scene].to_string(),
            floors: r[c_floors].parse()?,
            rooms: r[c_rooms].parse()?,
            navigable_area: r[c_area].parse()?,
        });
    }

    // region -> room type (weighted votes)
    let mut region_type: BTreeMap<(String, u32), RoomType> = BTreeMap::new();
    let mut rdr = csv::ReaderBuilder::new()
        .flexible(true)
        .from_path(dir.join("Per_Scene_Region_Weighted_Votes.csv"))?;
    for r in rdr.records() {
        let r = r?;
        if !is_val(&r[0]) {
            continue;
        }
        if let Some(t) = room_type(&r[r.len() - 1]) {
            region_type.insert((r[0].to_string(), r[1].parse()?), t);
        }
    }

    // region -> objects
    let mut per_type: TypeCounts = BTreeMap::new();
    let mut scenes = std::collections::BTreeSet::new();
    let mut type_scene_count: BTreeMap<RoomType, BTreeMap<String, usize>> = BTreeMap::new();
    let mut rdr = csv::ReaderBuilder::new()
        .flexible(true)
        .from_path(dir.join("Per_Scene_Region_Neighborhoods.csv"))?;
    for r in rdr.records() {
        let r = r?;
        let Some(&t) = region_type.get(&(r[0].to_string(), r[1].parse()?)) else {
            continue;
        };
        scenes.insert(r[0].to_string());
        *type_scene_count
            .entry(t)
            .or_default()
            .entry(r[0].to_string())
            .or_default() += 1;
        let mut counts: BTreeMap<String, usize> = BTreeMap::new();
        for inst in r[4].split(':') {
            let name = inst.rsplit_once('_').map_or(inst, |(n, _)| n);
            if let Some(c) = objectnav_category(name) {
                *counts.entry(c.to_string()).or_default() += 1;
            }
        }
        let e = per_type.entry(t).or_default();
        e.0 += 1;
        for (c, n) in counts {
            let s = e.1.entry(c).or_default();
            s.0 += 1;
            s.1 += n;
        }
    }
    let n_scenes = scenes.len().max(1) as f64;
    let room_types = per_type
        .into_iter()
        .map(|(t, (regions, cats))| RoomTypeStats {
            room_type: t,
            regions,
            mean_per_scene: type_scene_count
                .get(&t)
                .map_or(0, |m| m.values().sum::<usize>()) as f64
                / n_scenes,
            scene_presence: type_scene_count.get(&t).map_or(0, |m| m.len()) as f64 / n_scenes,
            objects: cats
                .into_iter()
                .map(|(category, (present, total))| CategoryStats {
                    category,
                    presence: present as f64 / regions as f64,
                    mean_count: total as f64 / present as f64,
                })
                .collect(),
        })
        .collect();
    let stats = HouseStats {
        attribution: "Derived from HM3D-Semantics v0.2 statistics (Yadav et al. 2023, \
                      matterport/habitat-matterport-3dresearch), validation scenes 00800-00899 only; \
                      used under the Matterport academic terms. Regenerate with \
                      `cargo run -p sornav-platform-sim --example derive_hm3d_stats`."
            .to_string(),
        semantic_scenes: scenes.len(),
        houses,
        room_types,
    };
    std::fs::write(&out, serde_json::to_string_pretty(&stats)? + "\n")?;
    println!(
        "wrote {} ({} semantic val scenes)",
        out.display(),
        scenes.len()
    );
    Ok(())
}
