//! The embedded prior against the real HM3D-Semantics statistics: exact
//! regeneration from train scenes, and held-out val ROC AUC.

use sornav_supervisor::{
    CooccurrencePrior, Hm3dStats, OBJECTNAV_CATEGORIES, PriorBuildConfig, Split, evaluate_prior,
};

fn stats() -> Option<Hm3dStats> {
    let dir = sornav_test_support::shared_data("hm3d-sem-stats")?;
    Some(Hm3dStats::read_dir(&dir).expect("readable statistics"))
}

#[test]
fn build_prior_regenerates_the_embedded_table_exactly() {
    let Some(stats) = stats() else { return };
    assert_eq!(stats.skipped_rows, 0);
    let prior = CooccurrencePrior::build(&stats.regions, PriorBuildConfig::default()).unwrap();
    assert_eq!(prior.to_json(), CooccurrencePrior::embedded_json());
    // Train only: 145 scenes with statistics (ids below 00800).
    assert_eq!(prior.train_scenes, 145);
    assert!(
        stats
            .split(Split::Train)
            .all(|r| r.scene.as_str() < "00800")
    );
    assert!(stats.split(Split::Val).all(|r| r.scene.as_str() >= "00800"));
}

#[test]
fn val_regions_are_not_used_by_the_build() {
    let Some(stats) = stats() else { return };
    let val_only: Vec<_> = stats.split(Split::Val).cloned().collect();
    assert!(CooccurrencePrior::build(&val_only, PriorBuildConfig::default()).is_err());
    // Adding val regions changes nothing.
    let train_only: Vec<_> = stats.split(Split::Train).cloned().collect();
    assert_eq!(
        CooccurrencePrior::build(&train_only, PriorBuildConfig::default()).unwrap(),
        CooccurrencePrior::build(&stats.regions, PriorBuildConfig::default()).unwrap()
    );
}

#[test]
fn held_out_val_auc_is_informative() {
    let Some(stats) = stats() else { return };
    let table = evaluate_prior(
        CooccurrencePrior::embedded(),
        &stats.regions,
        Split::Val,
        &OBJECTNAV_CATEGORIES,
    );
    let mut mean = 0.0;
    for (g, row) in &table {
        let auc = row.auc.unwrap();
        eprintln!(
            "{g}: AUC {auc:.3} ({} positives, {} negatives)",
            row.positives, row.negatives
        );
        // README figures; far above chance (0.5) for every category.
        assert!(auc > 0.7, "{g}: {auc}");
        mean += auc / table.len() as f64;
    }
    assert!(mean > 0.85, "mean AUC {mean}");
}

#[test]
fn missing_or_malformed_statistics_are_typed_errors() {
    let dir = std::env::temp_dir().join(format!("sornav-sv-stats-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    assert!(Hm3dStats::read_dir(&dir).is_err());
    std::fs::write(
        dir.join("hm3d_scene_metadata.csv"),
        "scene,split\n00001-a,train\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("Per_Scene_Region_Neighborhoods.csv"),
        "Scene Name,Region #\n00001-a,x\n",
    )
    .unwrap();
    assert!(Hm3dStats::read_dir(&dir).is_err());
    std::fs::write(
        dir.join("Per_Scene_Region_Neighborhoods.csv"),
        "Scene Name,Region #,# Unique Categories,# Objects,Object Instances in Region\n00001-a,0,2,2,bed_1:couch_2:wall_3\n09999-z,0,1,1,bed_4\n",
    )
    .unwrap();
    let s = Hm3dStats::read_dir(&dir).unwrap();
    assert_eq!(s.skipped_rows, 1);
    assert_eq!(
        s.regions[0].labels.iter().collect::<Vec<_>>(),
        ["bed", "sofa"]
    );
    let _ = std::fs::remove_dir_all(&dir);
}
