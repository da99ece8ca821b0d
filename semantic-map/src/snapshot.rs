//! Saving and reloading the whole map state with serde.

use std::collections::BTreeSet;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::cluster::{ClusterEntry, ClusterStore, ObjectCluster, Summary};
use crate::config::MapConfig;
use crate::error::MapError;
use crate::evidence::VoxelEvidence;
use crate::integrate::Inserter;
use crate::key::VoxelKey;
use crate::label::LabelSet;
use crate::map::SemanticMap;

/// One cluster and its member voxels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClusterRecord {
    /// The cluster.
    pub cluster: ObjectCluster,
    /// Its member voxels, in the map's (unspecified) order.
    pub voxels: Vec<VoxelKey>,
}

/// The complete state of a [`SemanticMap`], in a layout-independent form:
/// reloading it with [`SemanticMap::from_snapshot`] gives a map that
/// behaves identically (same voxels, clusters, ids, clock and pending
/// changes).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapSnapshot {
    /// Configuration.
    pub config: MapConfig,
    /// Label vocabulary.
    pub labels: LabelSet,
    /// Integrations performed.
    pub integrations: u64,
    /// The next fresh cluster id.
    pub next_cluster_id: u64,
    /// Every observed voxel, sorted by key.
    pub voxels: Vec<(VoxelKey, VoxelEvidence)>,
    /// Every cluster, id order.
    pub clusters: Vec<ClusterRecord>,
    /// Voxels whose object label changed since the last cluster update (sorted).
    pub pending_changes: Vec<VoxelKey>,
    /// Voxels hit since the last cluster update (sorted).
    pub pending_hits: Vec<VoxelKey>,
}

impl SemanticMap {
    /// The complete state as a [`MapSnapshot`].
    ///
    /// # Complexity
    /// O(V log V) for V observed voxels.
    pub fn snapshot(&self) -> MapSnapshot {
        let mut voxels: Vec<_> = self.grid.observed().map(|(k, c)| (k, *c)).collect();
        voxels.sort_unstable_by_key(|(k, _)| *k);
        let mut pending_changes = self.dirty.clone();
        pending_changes.sort_unstable();
        pending_changes.dedup();
        let mut pending_hits: Vec<VoxelKey> = self
            .touched
            .iter()
            .flat_map(|&b| {
                let bk = self.grid.keys[b as usize];
                crate::grid::mask_indices(&self.grid.blocks[b as usize].hit)
                    .map(move |i| bk.voxel(i))
            })
            .collect();
        pending_hits.sort_unstable();
        MapSnapshot {
            config: self.config,
            labels: self.labels.clone(),
            integrations: self.integrations,
            next_cluster_id: self.clusters.next_id,
            voxels,
            clusters: self
                .clusters
                .entries
                .values()
                .map(|e| ClusterRecord {
                    cluster: e.cluster.clone(),
                    voxels: e.voxels.clone(),
                })
                .collect(),
            pending_changes,
            pending_hits,
        }
    }

    /// Rebuilds a map from a snapshot, validating it.
    ///
    /// # Errors
    /// [`MapError::InvalidConfig`], [`MapError::DuplicateVoxel`],
    /// [`MapError::DuplicateCluster`], or [`MapError::Snapshot`] when a
    /// voxel is unobserved or out of bounds, a cluster member is not an
    /// observed voxel with the cluster's object label, a voxel is in two
    /// clusters, a cluster's summary disagrees with its voxels, an id is
    /// not below `next_cluster_id`, or an object voxel is neither in a
    /// cluster nor pending.
    pub fn from_snapshot(s: MapSnapshot) -> Result<Self, MapError> {
        let mut map = SemanticMap::new(s.config, s.labels)?;
        let bad = |m: String| Err(MapError::Snapshot(m));
        let limit = (s.config.max_abs_coordinate / s.config.resolution).ceil() + 2.0;
        let mut seen = BTreeSet::new();
        {
            let mut ins = Inserter::new(&mut map);
            for (k, cell) in &s.voxels {
                if !seen.insert(*k) {
                    return Err(MapError::DuplicateVoxel(*k));
                }
                if !cell.is_observed() {
                    return bad(format!("voxel {k:?} has no hits"));
                }
                if [k.x, k.y, k.z].iter().any(|c| f64::from(*c).abs() > limit) {
                    return bad(format!("voxel {k:?} is beyond max_abs_coordinate"));
                }
                ins.restore(*k, *cell);
            }
        }
        // Restoring records no pending state; install the snapshot's own.
        map.dirty.clear();
        for k in &s.pending_changes {
            if !seen.contains(k) {
                return bad(format!("pending change {k:?} is not an observed voxel"));
            }
            map.dirty.push(*k);
        }
        for k in &s.pending_hits {
            if !map.mark_hit(k) {
                return bad(format!("pending hit {k:?} is not an observed voxel"));
            }
        }
        let pending: BTreeSet<_> = s.pending_changes.iter().copied().collect();
        let res = s.config.resolution;
        let mut store = ClusterStore {
            next_id: s.next_cluster_id,
            ..ClusterStore::default()
        };
        for rec in s.clusters {
            let c = &rec.cluster;
            if store.entries.contains_key(&c.id) {
                return Err(MapError::DuplicateCluster(c.id));
            }
            if c.id.0 >= s.next_cluster_id {
                return bad(format!("cluster {} is not below next_cluster_id", c.id));
            }
            if rec.voxels.is_empty() {
                return bad(format!("cluster {} has no voxels", c.id));
            }
            for v in &rec.voxels {
                // A pending change may have relabelled a member since the
                // last update; every other member carries the label.
                let label_ok = map.object_label(v) == Some(c.label)
                    || (pending.contains(v) && map.voxel(v).is_some());
                if !label_ok {
                    return bad(format!("member {v:?} of {} lacks label {}", c.id, c.label));
                }
                if store.assignment.insert(*v, c.id).is_some() {
                    return bad(format!("voxel {v:?} is in two clusters"));
                }
            }
            // Text formats may round floats by an ulp: compare with a
            // tolerance, then keep the exact recomputed values.
            let summary = Summary::of(&rec.voxels);
            let mut exact = c.clone();
            summary.apply(&mut exact, res);
            let close = |a: &nalgebra::Point3<f64>, b: &nalgebra::Point3<f64>| {
                (a - b).amax() <= 1e-9 * (1.0 + a.coords.amax())
            };
            if exact.support != c.support
                || !close(&exact.centre, &c.centre)
                || !close(&exact.bounds.min, &c.bounds.min)
                || !close(&exact.bounds.max, &c.bounds.max)
            {
                return bad(format!(
                    "summary of cluster {} disagrees with its voxels",
                    c.id
                ));
            }
            store.entries.insert(
                exact.id,
                ClusterEntry {
                    cluster: exact,
                    voxels: rec.voxels,
                    summary,
                },
            );
        }
        if let Some(k) = map
            .object_voxels()
            .find(|k| !store.assignment.contains_key(k) && !pending.contains(k))
        {
            return bad(format!(
                "object voxel {k:?} is neither clustered nor pending"
            ));
        }
        map.integrations = s.integrations;
        map.clusters = store;
        Ok(map)
    }

    /// Sets the hit bit of an observed voxel (snapshot restore).
    fn mark_hit(&mut self, k: &VoxelKey) -> bool {
        let Some(b) = self.grid.find(k.block()) else {
            return false;
        };
        let block = &mut self.grid.blocks[b as usize];
        let i = k.index_in_block();
        if !block.cells[i].is_observed() {
            return false;
        }
        block.hit[i >> 6] |= 1 << (i & 63);
        if !block.touched {
            block.touched = true;
            self.touched.push(b);
        }
        true
    }
}

impl Serialize for SemanticMap {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.snapshot().serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for SemanticMap {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let snapshot = MapSnapshot::deserialize(deserializer)?;
        SemanticMap::from_snapshot(snapshot).map_err(serde::de::Error::custom)
    }
}
