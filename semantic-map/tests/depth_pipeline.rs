//! End to end: depth + label images through back-projection, fusion and
//! clustering.

use nalgebra::Point3;
use sornav_semantic_map::{
    DepthFrame, DepthOptions, LabelId, LabelSet, MapConfig, PinholeCamera, SemanticMap,
    optical_pose,
};

const CHAIR: LabelId = LabelId(10);
const TABLE: LabelId = LabelId(11);
const WALL: LabelId = LabelId(1);

/// A camera at (0, 0, 1) facing a wall at x = 2 (z-depth = 2 for every
/// pixel of a level camera looking along +x); columns [40, 80) show a
/// chair, [200, 260) a table, the rest wall.
fn wall_view() -> (PinholeCamera, Vec<f32>, Vec<LabelId>) {
    let cam = PinholeCamera::from_hfov(320, 240, 79f64.to_radians());
    let n = 320 * 240;
    let depth = vec![2.0f32; n];
    let labels = (0..n)
        .map(|i| match i % 320 {
            40..80 => CHAIR,
            200..260 => TABLE,
            _ => WALL,
        })
        .collect();
    (cam, depth, labels)
}

#[test]
fn two_objects_from_two_identical_views() {
    let (cam, depth, labels) = wall_view();
    let pose = optical_pose(&Point3::new(0.0, 0.0, 1.0), 0.0, 0.0);
    let frame = DepthFrame {
        camera: &cam,
        pose: &pose,
        depth: &depth,
        labels: &labels,
    };
    let mut map = SemanticMap::new(MapConfig::default(), LabelSet::household()).unwrap();
    let s1 = map
        .integrate_depth(&frame, &DepthOptions::default())
        .unwrap();
    assert_eq!(s1.accepted, 320 * 240);
    let up = map.update_clusters();
    assert_eq!(up.created.len(), 2);
    let before: Vec<_> = map.clusters().cloned().collect();
    let s2 = map
        .integrate_depth(&frame, &DepthOptions::default())
        .unwrap();
    assert_eq!(s2.new_voxels, 0);
    let up = map.update_clusters();
    assert!(up.created.is_empty() && up.changed.is_empty() && up.retired.is_empty());
    assert_eq!(up.observed, 2);
    for (a, b) in before.iter().zip(map.clusters()) {
        assert_eq!((a.id, a.label, a.support), (b.id, b.label, b.support));
        assert_eq!(b.observations, 2);
        assert_eq!(b.last_changed, 1);
        assert_eq!(b.last_seen, 2);
        // All on the wall plane x = 2 (voxel [2.0, 2.05)).
        assert!(
            b.bounds.min.x >= 1.95 && b.bounds.max.x <= 2.05 + 1e-9,
            "{:?}",
            b.bounds
        );
    }
    // The chair is left of the optical axis (+y), the table right (-y).
    let chair = map.clusters_with_label(CHAIR).next().unwrap();
    let table = map.clusters_with_label(TABLE).next().unwrap();
    assert!(chair.centre.y > 0.5 && table.centre.y < 0.0);
    // Half-resolution view of the same scene: no new voxels of its own.
    let mut half = SemanticMap::new(MapConfig::default(), LabelSet::household()).unwrap();
    let opts = DepthOptions {
        stride: 2,
        ..DepthOptions::default()
    };
    let s = half.integrate_depth(&frame, &opts).unwrap();
    assert_eq!(s.points, 160 * 120);
    half.update_clusters();
    assert_eq!(half.cluster_count(), 2);
}
