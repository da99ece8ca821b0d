//! Differential test of the integration fast paths (run merging, batched
//! block resolution): integrating a cloud at once must give exactly the
//! evidence of integrating it point by point.

use nalgebra::Point3;
use proptest::prelude::*;
use sornav_semantic_map::{LabelId, LabelSet, LabeledPoint, MapConfig, SemanticMap};

fn new_map() -> SemanticMap {
    SemanticMap::new(MapConfig::with_resolution(0.1), LabelSet::household()).unwrap()
}

/// Points in a small region (many repeats per voxel), with runs of
/// identical points and scattered jumps between blocks.
fn cloud() -> impl Strategy<Value = Vec<LabeledPoint>> {
    let point = (-30i32..30, -30i32..30, 0i32..10, 0usize..4, 1usize..6).prop_map(
        |(x, y, z, l, repeat)| {
            let label = [LabelId(1), LabelId(10), LabelId(11), LabelId(12)][l];
            let p = LabeledPoint::new(x as f32 * 0.07, y as f32 * 0.07, z as f32 * 0.05, label);
            vec![p; repeat]
        },
    );
    prop::collection::vec(point, 0..300).prop_map(|v| v.into_iter().flatten().collect())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn at_once_equals_point_by_point(points in cloud()) {
        let origin = Point3::new(0.0, 0.0, 0.5);
        let mut bulk = new_map();
        let s = bulk.integrate_points(&origin, &points).unwrap();
        prop_assert_eq!(s.accepted, points.len() as u64);
        let mut single = new_map();
        let mut total = sornav_semantic_map::IntegrationStats::default();
        for p in &points {
            total.accumulate(&single.integrate_points(&origin, std::slice::from_ref(p)).unwrap());
        }
        // Every counter but `object_label_changes` (a voxel passing through
        // an intermediate label inside a run records one change, not two).
        prop_assert_eq!(
            (s.points, s.accepted, s.rejected(), s.new_voxels, s.new_blocks),
            (total.points, total.accepted, total.rejected(), total.new_voxels, total.new_blocks)
        );
        prop_assert!(s.object_label_changes <= total.object_label_changes);
        let (a, b) = (bulk.snapshot(), single.snapshot());
        prop_assert_eq!(&a.voxels, &b.voxels);
        prop_assert_eq!(&a.pending_changes, &b.pending_changes);
        prop_assert_eq!(&a.pending_hits, &b.pending_hits);
        let hits: u64 = a.voxels.iter().map(|(_, c)| u64::from(c.hits())).sum();
        prop_assert_eq!(hits, points.len() as u64);
    }
}
