//! The report's failure analysis: for every variant and failure class, a
//! few failed episodes with their top-down maps (robot path, stop pose and
//! heading, goal objects and their view points), so that failures can be
//! seen rather than guessed.
//!
//! A failure class is the cause (step limit, timeout, false stop, other;
//! [`OUTCOME_CLASSES`]) together with the cross-floor flag: same-floor and
//! cross-floor failures of one cause have different stories (a thrashing
//! robot in a room, a stair never recognised).
//!
//! # How the examples are chosen
//! While running, the harness saves the map of *every* failed episode of an
//! agent variant in `maps/failures/` ([`crate::topdown::FAILURES_DIR`])
//! when [`EvalConfig::failure_maps`] is positive. The examples are picked
//! here, at report time, from the records: spread over the scenes — the
//! first failure of every scene (in the configuration's scene order, then
//! by episode id), then the second of every scene, and so on — among those
//! whose map exists. The choice therefore depends on the set of records
//! only, not on the order in which parallel jobs finished them, and it is
//! the same after a resume or a `merge` (which copies `maps/failures/`).
//! Re-simulating the chosen episodes at report time was not an option: an
//! episode cut by the wall-clock budget or answered by a live LLM does not
//! replay exactly.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use sornav_platform_sim::Outcome;

use crate::harness::{EvalConfig, round_robin};
use crate::record::EpisodeRecord;
use crate::summary::OUTCOME_CLASSES;
use crate::topdown::{self, FAILURES_DIR};

/// A failure class: the cause and whether the goal is on another floor
/// than the start. Orders as the report lists them: causes in
/// [`OUTCOME_CLASSES`] order, same floor before cross-floor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct FailureClass {
    /// Index of the cause in [`OUTCOME_CLASSES`] (1 or more).
    cause: usize,
    /// The goal is on another floor than the start.
    pub cross_floor: bool,
}

impl FailureClass {
    /// The class of a record; `None` for a success.
    pub fn of(record: &EpisodeRecord) -> Option<Self> {
        let outcome = record.result.outcome;
        if outcome == Outcome::Success {
            return None;
        }
        let cause = OUTCOME_CLASSES.iter().position(|c| c.0 == outcome)?;
        Some(Self {
            cause,
            cross_floor: record.result.cross_floor,
        })
    }

    /// The cause.
    pub fn cause(self) -> Outcome {
        OUTCOME_CLASSES[self.cause].0
    }

    /// The cause's label ("step limit", "false stop", ...).
    pub fn cause_label(self) -> &'static str {
        OUTCOME_CLASSES[self.cause].1
    }

    /// "step limit, same floor", "false stop, cross-floor", ...
    pub fn label(self) -> String {
        format!(
            "{}, {}",
            self.cause_label(),
            if self.cross_floor {
                "cross-floor"
            } else {
                "same floor"
            }
        )
    }
}

/// The order of episode ids within a scene: numeric ids by value (as
/// generated and in Habitat files), then any others by text.
fn episode_order(id: &str) -> (u64, &str) {
    (id.parse().unwrap_or(u64::MAX), id)
}

/// Up to `n` of `failures` spread over the scenes: the first of every scene
/// (scenes in `scene_order`, unknown ones after them by name; episodes by
/// id), then the second of every scene, and so on. Deterministic: the
/// result does not depend on the order of `failures`.
pub fn spread_over_scenes<'a>(
    failures: &[&'a EpisodeRecord],
    scene_order: &[String],
    n: usize,
) -> Vec<&'a EpisodeRecord> {
    let mut by_scene: BTreeMap<(usize, &str), Vec<&'a EpisodeRecord>> = BTreeMap::new();
    for r in failures {
        let scene = r.result.scene_id.as_str();
        let rank = scene_order
            .iter()
            .position(|s| s == scene)
            .unwrap_or(usize::MAX);
        by_scene.entry((rank, scene)).or_default().push(r);
    }
    for list in by_scene.values_mut() {
        list.sort_by(|a, b| {
            episode_order(&a.result.episode_id).cmp(&episode_order(&b.result.episode_id))
        });
    }
    let groups: Vec<Vec<&'a EpisodeRecord>> = by_scene.into_values().collect();
    round_robin(&groups, n)
}

/// The path of a record's failure map relative to the output directory.
pub fn map_path(record: &EpisodeRecord) -> String {
    format!(
        "maps/{FAILURES_DIR}/{}",
        topdown::file_name(
            &record.variant,
            &record.result.scene_id,
            &record.result.episode_id
        )
    )
}

/// One line describing a failed episode of `class`.
fn example_line(r: &EpisodeRecord, class: FailureClass) -> String {
    let res = &r.result;
    format!(
        "`{}` #{}, target {}: {}; {} to the nearest view point; {} actions, {} collisions, {:.1} m path, {} missions, {} verifications; ended by {}",
        res.scene_id,
        res.episode_id,
        res.object_category,
        class.cause_label(),
        res.dtg_m
            .map_or("no route".to_owned(), |d| format!("{d:.2} m")),
        res.actions,
        res.collisions,
        res.path_length_m,
        r.missions,
        r.verifications,
        if r.agent_end.is_empty() {
            "the budget"
        } else {
            r.agent_end.as_str()
        },
    )
}

/// The "Failure analysis" section of `report.md` (empty when
/// `config.failure_maps` is 0 or nothing failed): per variant (in
/// `config.variants` order) and failure class, the number of failures and
/// up to `config.failure_maps` examples ([`spread_over_scenes`] among the
/// failures whose map exists in `dir`), each with one line and its map.
pub fn section(config: &EvalConfig, records: &[EpisodeRecord], dir: &Path) -> String {
    let n = config.failure_maps;
    if n == 0 || records.iter().all(|r| FailureClass::of(r).is_none()) {
        return String::new();
    }
    let scene_order: Vec<String> = config
        .scenes
        .iter()
        .map(crate::scenes::SceneSource::name)
        .collect();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\n## Failure analysis\n\nPer variant and failure class (the cause; same-floor and cross-floor apart), up to {n} failed episodes with their top-down maps, spread over the scenes (the first failure of every scene in scene order, then the second, ...; episodes by id). Distances to the nearest view point are geodesic, at the end of the episode; \"ended by\" is how the agent ended (`stop` on a confirmed target, `exhausted` with nothing left to explore, or the budget). On the maps: the trajectory (red, start black), the stop pose with its heading (red dot and bar), the goal objects (green boxes) with their view points (green dots), the agent's explored occupancy (grey) and remaining frontiers (blue), verified candidates (orange crosses), relocations (purple). Every failed episode's map is in `maps/{FAILURES_DIR}/`.\n"
    );
    for variant in &config.variants {
        let mut classes: BTreeMap<FailureClass, Vec<&EpisodeRecord>> = BTreeMap::new();
        for r in records.iter().filter(|r| &r.variant == variant) {
            if let Some(c) = FailureClass::of(r) {
                classes.entry(c).or_default().push(r);
            }
        }
        if classes.is_empty() {
            continue;
        }
        let _ = writeln!(s, "### {variant}\n");
        for (class, failures) in &classes {
            let with_map: Vec<&EpisodeRecord> = failures
                .iter()
                .copied()
                .filter(|r| dir.join(map_path(r)).is_file())
                .collect();
            let chosen = spread_over_scenes(&with_map, &scene_order, n);
            let _ = writeln!(
                s,
                "#### {}: {} episode{}\n",
                class.label(),
                failures.len(),
                if failures.len() == 1 { "" } else { "s" }
            );
            if chosen.is_empty() {
                let _ = writeln!(
                    s,
                    "No map saved (not an agent variant, or recorded without failure maps).\n"
                );
            }
            for r in chosen {
                let path = map_path(r);
                let _ = writeln!(s, "- {}\n\n  ![{path}]({path})\n", example_line(r, *class));
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::test_record;

    fn failure(scene: &str, id: &str, outcome: Outcome, floors: usize) -> EpisodeRecord {
        let mut r = test_record(id, outcome, 0.0, floors);
        r.result.scene_id = scene.to_owned();
        r
    }

    #[test]
    fn classes_split_cause_and_floor_and_skip_successes() {
        let same = failure("a", "1", Outcome::FalseStop, 0);
        let cross = failure("a", "2", Outcome::FalseStop, 1);
        let step = failure("a", "3", Outcome::StepLimit, 0);
        assert_eq!(
            FailureClass::of(&failure("a", "4", Outcome::Success, 0)),
            None
        );
        let (same, cross, step) = (
            FailureClass::of(&same).unwrap(),
            FailureClass::of(&cross).unwrap(),
            FailureClass::of(&step).unwrap(),
        );
        assert_ne!(same, cross);
        assert!(step < same && same < cross);
        assert_eq!(same.cause(), Outcome::FalseStop);
        assert_eq!(cross.label(), "false stop, cross-floor");
    }

    #[test]
    fn examples_are_spread_over_scenes_in_order_whatever_the_input_order() {
        let records = [
            failure("b", "10", Outcome::Other, 0),
            failure("a", "10", Outcome::Other, 0),
            failure("b", "2", Outcome::Other, 0),
            failure("a", "9", Outcome::Other, 0),
            failure("c", "0", Outcome::Other, 0),
        ];
        let order = vec!["b".to_owned(), "a".to_owned()];
        let mut refs: Vec<&EpisodeRecord> = records.iter().collect();
        let ids = |chosen: Vec<&EpisodeRecord>| -> Vec<(String, String)> {
            chosen
                .iter()
                .map(|r| (r.result.scene_id.clone(), r.result.episode_id.clone()))
                .collect()
        };
        let want = vec![
            ("b".to_owned(), "2".to_owned()),
            ("a".to_owned(), "9".to_owned()),
            ("c".to_owned(), "0".to_owned()),
        ];
        assert_eq!(ids(spread_over_scenes(&refs, &order, 3)), want);
        refs.reverse();
        assert_eq!(ids(spread_over_scenes(&refs, &order, 3)), want);
        // A second round once every scene gave one.
        assert_eq!(
            ids(spread_over_scenes(&refs, &order, 4))[3],
            ("b".to_owned(), "10".to_owned())
        );
        assert_eq!(spread_over_scenes(&refs, &order, 9).len(), 5);
        assert!(spread_over_scenes(&refs, &order, 0).is_empty());
    }
}
