//! Property and differential tests of object clustering: brute-force BFS
//! reference, incremental vs from-scratch, support accounting, id rules,
//! translation invariance, persistence and snapshots.

use std::collections::{BTreeMap, BTreeSet, VecDeque};

use approx::assert_relative_eq;
use nalgebra::{Point3, Vector3};
use proptest::prelude::*;
use sornav_semantic_map::{
    ClusterId, ClusterQuery, LabelId, LabelSet, LabeledPoint, MapConfig, MapSnapshot, SemanticMap,
    VoxelKey,
};

/// Power-of-two resolution: voxel centres are exact in f32 and f64.
const RES: f64 = 0.25;
const WALL: LabelId = LabelId(1);
const CHAIR: LabelId = LabelId(10);
const TABLE: LabelId = LabelId(11);
const BED: LabelId = LabelId(12);

fn new_map() -> SemanticMap {
    SemanticMap::new(MapConfig::with_resolution(RES), LabelSet::household()).unwrap()
}

fn point_in(k: VoxelKey, label: LabelId) -> LabeledPoint {
    let c = k.centre(RES);
    LabeledPoint::new(c.x as f32, c.y as f32, c.z as f32, label)
}

fn integrate(map: &mut SemanticMap, voxels: &[(VoxelKey, LabelId)]) {
    integrate_at(map, voxels, Point3::origin());
}

fn integrate_at(map: &mut SemanticMap, voxels: &[(VoxelKey, LabelId)], origin: Point3<f64>) {
    let pts: Vec<_> = voxels.iter().map(|&(k, l)| point_in(k, l)).collect();
    let s = map.integrate_points(&origin, &pts).unwrap();
    assert_eq!(s.accepted, pts.len() as u64);
}

type Partition = BTreeSet<(LabelId, Vec<VoxelKey>)>;

/// Reference: plain BFS labelling of a voxel -> label field, 26-connectivity
/// written out independently of the crate.
fn bfs_partition(field: &BTreeMap<VoxelKey, LabelId>) -> Partition {
    let mut seen = BTreeSet::new();
    let mut out = Partition::new();
    for (&start, &label) in field {
        if !seen.insert(start) {
            continue;
        }
        let mut comp = vec![start];
        let mut queue = VecDeque::from([start]);
        while let Some(v) = queue.pop_front() {
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let n = VoxelKey::new(v.x + dx, v.y + dy, v.z + dz);
                        if field.get(&n) == Some(&label) && seen.insert(n) {
                            comp.push(n);
                            queue.push_back(n);
                        }
                    }
                }
            }
        }
        comp.sort();
        out.insert((label, comp));
    }
    out
}

/// Member voxels of a cluster, sorted.
fn members(map: &SemanticMap, id: ClusterId) -> Vec<VoxelKey> {
    let mut v = map.cluster_voxels(id).unwrap().to_vec();
    v.sort();
    v
}

fn map_partition(map: &SemanticMap) -> Partition {
    map.clusters()
        .map(|c| (c.label, members(map, c.id)))
        .collect()
}

/// The map's object-label field (dominant, non-ignored labels).
fn object_field(map: &SemanticMap) -> BTreeMap<VoxelKey, LabelId> {
    map.voxels()
        .filter_map(|(k, _)| map.object_label(&k).map(|l| (k, l)))
        .collect()
}

/// Checks every cluster's summary against its voxels.
fn check_summaries(map: &SemanticMap) {
    for c in map.clusters() {
        let v = map.cluster_voxels(c.id).unwrap();
        assert_eq!(c.support, v.len());
        let n = v.len() as f64;
        let mean = v
            .iter()
            .fold(Vector3::zeros(), |a, k| a + k.centre(RES).coords)
            / n;
        assert_relative_eq!(c.centre.coords, mean, epsilon = 1e-9);
        for k in v {
            assert!(c.bounds.contains(&k.centre(RES)));
            assert_eq!(map.cluster_at(k), Some(c.id));
            assert_eq!(map.object_label(k), Some(c.label));
        }
        let lo = v.iter().map(|k| k.x).min().unwrap();
        assert_relative_eq!(c.bounds.min.x, f64::from(lo) * RES);
    }
}

fn key_strategy(extent: i32) -> impl Strategy<Value = VoxelKey> {
    (0..extent, 0..extent, 0..extent / 2 + 1).prop_map(|(x, y, z)| VoxelKey::new(x - 3, y - 3, z))
}

fn label_strategy() -> impl Strategy<Value = LabelId> {
    prop_oneof![3 => Just(CHAIR), 2 => Just(TABLE), 1 => Just(BED), 2 => Just(WALL)]
}

/// Batches of labelled voxels (with repeats, so dominant labels change).
fn batches_strategy() -> impl Strategy<Value = Vec<Vec<(VoxelKey, LabelId)>>> {
    prop_oneof![
        // Dense: many votes per voxel, labels flip, clusters split and merge.
        prop::collection::vec(
            prop::collection::vec((key_strategy(7), label_strategy()), 0..60),
            1..10,
        ),
        // Sparse and wider: many separate clusters that grow and bridge.
        prop::collection::vec(
            prop::collection::vec((key_strategy(14), label_strategy()), 0..120),
            1..6,
        ),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// One point per voxel: clusters equal a brute-force BFS labelling.
    #[test]
    fn clusters_equal_bfs_reference(
        set in prop::collection::btree_map(key_strategy(12), label_strategy(), 0..250)
    ) {
        let mut map = new_map();
        let voxels: Vec<_> = set.iter().map(|(k, l)| (*k, *l)).collect();
        integrate(&mut map, &voxels);
        map.update_clusters();
        let field: BTreeMap<_, _> = set.into_iter().filter(|(_, l)| *l != WALL).collect();
        prop_assert_eq!(map_partition(&map), bfs_partition(&field));
        check_summaries(&map);
    }

    /// Incremental updates after every batch give the same partition as one
    /// clustering from scratch, and both equal the BFS reference; supports
    /// sum to the number of labelled voxels.
    #[test]
    fn incremental_equals_from_scratch(batches in batches_strategy()) {
        let mut inc = new_map();
        let mut scratch = new_map();
        for b in &batches {
            integrate(&mut inc, b);
            inc.update_clusters();
            integrate(&mut scratch, b);
            let total: usize = inc.clusters().map(|c| c.support).sum();
            prop_assert_eq!(total, inc.object_voxel_count());
            prop_assert_eq!(total, object_field(&inc).len());
        }
        scratch.update_clusters();
        let reference = bfs_partition(&object_field(&scratch));
        prop_assert_eq!(&map_partition(&inc), &reference);
        prop_assert_eq!(&map_partition(&scratch), &reference);
        check_summaries(&inc);
    }

    /// Generic id rules on random sequences: a surviving id keeps its label
    /// and shares voxels with its previous self, fresh ids exceed all
    /// earlier ids, retired ids never come back, and the largest part of a
    /// dissolved cluster carries its id or a successor.
    #[test]
    fn id_rules_on_random_sequences(batches in batches_strategy()) {
        let mut map = new_map();
        let mut ever: BTreeSet<ClusterId> = BTreeSet::new();
        let mut retired: BTreeSet<ClusterId> = BTreeSet::new();
        for b in &batches {
            let before: BTreeMap<ClusterId, (LabelId, Vec<VoxelKey>)> = map
                .clusters()
                .map(|c| (c.id, (c.label, members(&map, c.id))))
                .collect();
            integrate(&mut map, b);
            let up = map.update_clusters();
            let max_before = ever.iter().next_back().copied();
            for id in &up.created {
                prop_assert!(max_before.is_none_or(|m| *id > m));
                prop_assert!(!before.contains_key(id));
            }
            for c in map.clusters() {
                prop_assert!(!retired.contains(&c.id));
                if let Some((label, old)) = before.get(&c.id) {
                    prop_assert_eq!(*label, c.label);
                    let now = members(&map, c.id);
                    prop_assert!(old.iter().any(|v| now.binary_search(v).is_ok()));
                }
            }
            for r in &up.retired {
                prop_assert!(map.cluster(r.id).is_none());
                if let Some(s) = r.successor {
                    prop_assert!(map.cluster(s).is_some());
                }
                retired.insert(r.id);
            }
            // Every vanished id is reported as retired.
            for id in before.keys() {
                if map.cluster(*id).is_none() {
                    prop_assert!(up.retired.iter().any(|r| r.id == *id));
                }
            }
            ever.extend(map.clusters().map(|c| c.id));
        }
    }

    /// Grow then merge: the merged cluster keeps the id of the larger
    /// predecessor, the other id retires with it as successor.
    #[test]
    fn merge_keeps_largest_predecessor(a in 1i32..8, b in 1i32..8, grow in 0i32..4) {
        prop_assume!(a != b);
        let mut map = new_map();
        // Bars along x on y = 0: A covers x in [0, a), B covers [a + 1, a + 1 + b).
        let bar = |from: i32, len: i32| -> Vec<(VoxelKey, LabelId)> {
            (from..from + len).map(|x| (VoxelKey::new(x, 0, 0), CHAIR)).collect()
        };
        integrate(&mut map, &bar(0, a));
        integrate(&mut map, &bar(a + 1, b));
        map.update_clusters();
        prop_assert_eq!(map.cluster_count(), 2);
        let id_a = map.cluster_at(&VoxelKey::new(0, 0, 0)).unwrap();
        let id_b = map.cluster_at(&VoxelKey::new(a + 1, 0, 0)).unwrap();
        // Grow A sideways (y = 1) without touching B: id kept.
        integrate(&mut map, &(0..grow.min(a)).map(|x| (VoxelKey::new(x, -1, 0), CHAIR)).collect::<Vec<_>>());
        let up = map.update_clusters();
        prop_assert!(up.created.is_empty());
        prop_assert_eq!(map.cluster_at(&VoxelKey::new(0, 0, 0)), Some(id_a));
        let size_a = map.cluster(id_a).unwrap().support;
        let size_b = map.cluster(id_b).unwrap().support;
        // Bridge.
        integrate(&mut map, &[(VoxelKey::new(a, 0, 0), CHAIR)]);
        let up = map.update_clusters();
        prop_assert_eq!(map.cluster_count(), 1);
        let (keep, gone) = if size_a > size_b || (size_a == size_b && id_a < id_b) {
            (id_a, id_b)
        } else {
            (id_b, id_a)
        };
        let merged = map.cluster(keep).unwrap();
        prop_assert_eq!(merged.support, size_a + size_b + 1);
        prop_assert_eq!(up.retired.len(), 1);
        prop_assert_eq!(up.retired[0].id, gone);
        prop_assert_eq!(up.retired[0].successor, Some(keep));
        prop_assert!(up.created.is_empty());
    }

    /// Split: relabelling the bridge voxel splits a bar; the largest part
    /// keeps the id, the smaller gets a fresh one. Shrinking keeps the id.
    #[test]
    fn split_largest_part_keeps_id(left in 1i32..8, right in 1i32..8) {
        prop_assume!(left != right);
        let mut map = new_map();
        let n = left + 1 + right;
        integrate(&mut map, &(0..n).map(|x| (VoxelKey::new(x, 0, 0), CHAIR)).collect::<Vec<_>>());
        map.update_clusters();
        let id = map.cluster_at(&VoxelKey::new(0, 0, 0)).unwrap();
        // Two wall votes make the bridge wall-dominant (ignored).
        let bridge = VoxelKey::new(left, 0, 0);
        integrate(&mut map, &[(bridge, WALL), (bridge, WALL)]);
        let up = map.update_clusters();
        prop_assert_eq!(map.cluster_count(), 2);
        prop_assert_eq!(map.cluster_at(&bridge), None);
        let (big_x, small_x) = if left > right { (0, n - 1) } else { (n - 1, 0) };
        prop_assert_eq!(map.cluster_at(&VoxelKey::new(big_x, 0, 0)), Some(id));
        let other = map.cluster_at(&VoxelKey::new(small_x, 0, 0)).unwrap();
        prop_assert!(other > id);
        prop_assert_eq!(up.created, vec![other]);
        prop_assert_eq!(up.changed, vec![id]);
        // Shrink the big part by one end voxel: id kept.
        let end = VoxelKey::new(big_x, 0, 0);
        integrate(&mut map, &[(end, WALL), (end, WALL)]);
        let up = map.update_clusters();
        prop_assert!(up.created.is_empty());
        prop_assert_eq!(map.cluster(id).unwrap().support, left.max(right) as usize - 1);
        // (A part of size 1 vanishes entirely when shrunk.)
        prop_assert!(map.cluster(id).is_some() || left.max(right) == 1);
    }

    /// Translating every point by whole voxels translates the clusters
    /// (voxels, centres, bounds) and changes nothing else.
    #[test]
    fn translation_by_whole_voxels(
        batches in batches_strategy(),
        (tx, ty, tz) in (-200i32..200, -200i32..200, -50i32..50),
    ) {
        let mut a = new_map();
        let mut b = new_map();
        let t = Vector3::new(f64::from(tx), f64::from(ty), f64::from(tz)) * RES;
        for batch in &batches {
            integrate(&mut a, batch);
            a.update_clusters();
            let moved: Vec<_> = batch.iter().map(|(k, l)| (k.offset(tx, ty, tz), *l)).collect();
            integrate_at(&mut b, &moved, Point3::origin() + t);
            b.update_clusters();
        }
        prop_assert_eq!(a.cluster_count(), b.cluster_count());
        for (ca, cb) in a.clusters().zip(b.clusters()) {
            prop_assert_eq!(ca.id, cb.id);
            prop_assert_eq!(ca.label, cb.label);
            prop_assert_eq!(ca.support, cb.support);
            prop_assert_eq!((ca.first_seen, ca.last_seen, ca.last_changed, ca.observations),
                (cb.first_seen, cb.last_seen, cb.last_changed, cb.observations));
            assert_relative_eq!(ca.centre + t, cb.centre, epsilon = 1e-9);
            assert_relative_eq!(ca.bounds.min + t, cb.bounds.min, epsilon = 1e-9);
            assert_relative_eq!(ca.bounds.max + t, cb.bounds.max, epsilon = 1e-9);
            let va: Vec<_> = members(&a, ca.id).iter().map(|k| k.offset(tx, ty, tz)).collect();
            prop_assert_eq!(va, members(&b, cb.id));
        }
    }

    /// A snapshot (including pending, not yet clustered changes) reloads
    /// identically through JSON and keeps behaving identically.
    #[test]
    fn snapshot_round_trip(batches in batches_strategy(), pending in prop::collection::vec((key_strategy(9), label_strategy()), 0..30)) {
        let mut map = new_map();
        for b in &batches {
            integrate(&mut map, b);
            map.update_clusters();
        }
        integrate(&mut map, &pending);
        let json = serde_json::to_string(&map).unwrap();
        let mut back: SemanticMap = serde_json::from_str(&json).unwrap();
        prop_assert_eq!(back.snapshot(), map.snapshot());
        let ua = map.update_clusters();
        let ub = back.update_clusters();
        prop_assert_eq!(ua, ub);
        integrate(&mut map, &pending);
        integrate(&mut back, &pending);
        map.update_clusters();
        back.update_clusters();
        prop_assert_eq!(back.snapshot(), map.snapshot());
    }

    /// The combined query equals a brute-force filter.
    #[test]
    fn queries_match_brute_force(
        batches in batches_strategy(),
        px in -2.0f64..3.0, py in -2.0f64..3.0, r in 0.0f64..2.0, n in 0usize..6,
        label in label_strategy(),
        band in (-0.5f64..1.5, 0.0f64..1.5, 0u8..8),
    ) {
        let mut map = new_map();
        for b in &batches {
            integrate(&mut map, b);
        }
        map.update_clusters();
        let p = Point3::new(px, py, 7.0);
        let all: Vec<_> = map.clusters().cloned().collect();
        let brute: Vec<_> = all
            .iter()
            .filter(|c| c.label == label && c.support >= n)
            .filter(|c| ((c.centre.x - px).powi(2) + (c.centre.y - py).powi(2)).sqrt() <= r)
            .map(|c| c.id)
            .collect();
        let q = ClusterQuery::default().label(label).min_support(n).within(p, r);
        prop_assert_eq!(map.query(&q).iter().map(|c| c.id).collect::<Vec<_>>(), brute);
        // A height band [lo, hi): random, on a centre height (bounds hit
        // exactly), open-ended, or with a NaN bound (matches nothing).
        let zs: Vec<f64> = all.iter().map(|c| c.centre.z).collect();
        let (lo, hi) = match band.2 {
            0 if !zs.is_empty() => (zs[band.0.to_bits() as usize % zs.len()], band.0 + band.1),
            1 if !zs.is_empty() => (band.0, zs[band.1.to_bits() as usize % zs.len()]),
            2 => (f64::NEG_INFINITY, band.0),
            3 => (band.0, f64::INFINITY),
            4 => (f64::NAN, band.0),
            5 => (band.0, f64::NAN),
            _ => (band.0, band.0 + band.1),
        };
        let in_band: Vec<_> = all
            .iter()
            .filter(|c| c.label == label && c.support >= n)
            .filter(|c| ((c.centre.x - px).powi(2) + (c.centre.y - py).powi(2)).sqrt() <= r)
            .filter(|c| c.centre.z >= lo && c.centre.z < hi)
            .map(|c| c.id)
            .collect();
        let qb = q.clone().heights(lo, hi);
        prop_assert_eq!(map.query(&qb).iter().map(|c| c.id).collect::<Vec<_>>(), in_band);
        if lo.is_nan() || hi.is_nan() {
            prop_assert!(map.query(&qb).is_empty());
        }
        let band_only: Vec<_> = all.iter().filter(|c| c.centre.z >= lo && c.centre.z < hi).map(|c| c.id).collect();
        prop_assert_eq!(
            map.query(&ClusterQuery::default().heights(lo, hi)).iter().map(|c| c.id).collect::<Vec<_>>(),
            band_only
        );
        prop_assert_eq!(map.clusters_with_label(label).count(), all.iter().filter(|c| c.label == label).count());
        prop_assert_eq!(map.clusters_with_support(n).count(), all.iter().filter(|c| c.support >= n).count());
        prop_assert_eq!(map.clusters_within(p, r).count(),
            all.iter().filter(|c| ((c.centre.x - px).powi(2) + (c.centre.y - py).powi(2)).sqrt() <= r).count());
        for c in &all {
            prop_assert_eq!(map.cluster(c.id), Some(c));
        }
    }
}

#[test]
fn repeated_views_add_support_and_clusters_persist() {
    let mut map = new_map();
    let chair: Vec<_> = (0..4).map(|x| (VoxelKey::new(x, 0, 1), CHAIR)).collect();
    let far_chair: Vec<_> = (0..4).map(|x| (VoxelKey::new(x, 10, 1), CHAIR)).collect();
    for _ in 0..3 {
        integrate(&mut map, &chair);
        let up = map.update_clusters();
        assert_eq!(up.observed, 1);
    }
    assert_eq!(map.cluster_count(), 1);
    let c = map.clusters().next().unwrap().clone();
    assert_eq!(
        (c.support, c.observations, c.first_seen, c.last_seen),
        (4, 3, 1, 3)
    );
    assert_eq!(c.last_changed, 1);
    assert_eq!(map.voxel(&VoxelKey::new(0, 0, 1)).unwrap().hits(), 3);
    // A disconnected instance of the same label is a separate cluster; the
    // first one persists while out of view.
    integrate(&mut map, &far_chair);
    let up = map.update_clusters();
    assert_eq!(up.created.len(), 1);
    assert_eq!(map.cluster_count(), 2);
    let old = map.cluster(c.id).unwrap();
    assert_eq!((old.observations, old.last_seen), (3, 3));
    assert_eq!(map.clusters_with_label(CHAIR).count(), 2);
}

#[test]
fn ignored_set_changes_recluster() {
    let mut map = new_map();
    integrate(
        &mut map,
        &[
            (VoxelKey::new(0, 0, 0), WALL),
            (VoxelKey::new(1, 0, 0), WALL),
        ],
    );
    map.update_clusters();
    assert_eq!(map.cluster_count(), 0);
    let mut labels = LabelSet::household();
    labels.set_ignored(WALL, false);
    map.set_labels(labels);
    map.update_clusters();
    assert_eq!(map.cluster_count(), 1);
    assert_eq!(map.clusters().next().unwrap().support, 2);
    map.set_labels(LabelSet::household());
    let up = map.update_clusters();
    assert_eq!(map.cluster_count(), 0);
    assert_eq!(up.retired.len(), 1);
    assert_eq!(up.retired[0].successor, None);
}

#[test]
fn corrupted_snapshots_are_rejected() {
    let mut map = new_map();
    integrate(
        &mut map,
        &[
            (VoxelKey::new(0, 0, 0), CHAIR),
            (VoxelKey::new(1, 0, 0), CHAIR),
            (VoxelKey::new(5, 0, 0), WALL),
        ],
    );
    map.update_clusters();
    let good = map.snapshot();
    assert!(SemanticMap::from_snapshot(good.clone()).is_ok());
    type Corruption = Box<dyn Fn(&mut MapSnapshot)>;
    let corrupt: Vec<Corruption> = vec![
        Box::new(|s| s.voxels.push(s.voxels[0])),
        Box::new(|s| s.clusters[0].voxels.push(VoxelKey::new(5, 0, 0))),
        Box::new(|s| s.clusters[0].cluster.support = 7),
        Box::new(|s| s.clusters[0].voxels.pop().map(|_| ()).unwrap_or(())),
        Box::new(|s| s.next_cluster_id = 0),
        Box::new(|s| s.clusters.push(s.clusters[0].clone())),
        Box::new(|s| s.config.resolution = -1.0),
        Box::new(|s| s.pending_hits.push(VoxelKey::new(9, 9, 9))),
        Box::new(|s| s.clusters[0].cluster.centre.x += 1.0),
    ];
    for (i, f) in corrupt.iter().enumerate() {
        let mut s = good.clone();
        f(&mut s);
        assert!(
            SemanticMap::from_snapshot(s).is_err(),
            "corruption {i} accepted"
        );
    }
}
