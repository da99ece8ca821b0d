//! The [`SemanticMap`]: voxel evidence, pending changes and object clusters.

use crate::cluster::ClusterStore;
use crate::config::MapConfig;
use crate::error::MapError;
use crate::evidence::VoxelEvidence;
use crate::grid::{VoxelGrid, mask_indices};
use crate::key::VoxelKey;
use crate::label::{IgnoredBitmap, LabelId, LabelSet};

/// A sparse semantic voxel map with persistent object clusters.
///
/// * [`integrate_points`](Self::integrate_points) /
///   [`integrate_depth`](Self::integrate_depth) fuse labelled points into
///   per-voxel [`VoxelEvidence`];
/// * [`update_clusters`](Self::update_clusters) incrementally maintains the
///   [`ObjectCluster`](crate::ObjectCluster)s (26-connected voxels sharing a
///   dominant, non-ignored label) with persistent ids;
/// * the query methods read the clusters as of the last update;
/// * [`snapshot`](Self::snapshot) / serde save and reload the whole state.
///
/// See the [crate documentation](crate) for an example.
#[derive(Debug, Clone)]
pub struct SemanticMap {
    pub(crate) config: MapConfig,
    pub(crate) labels: LabelSet,
    pub(crate) ignored: IgnoredBitmap,
    pub(crate) grid: VoxelGrid,
    /// Voxels whose object label may have changed since the last cluster
    /// update (may hold duplicates).
    pub(crate) dirty: Vec<VoxelKey>,
    /// Blocks with hit bits set since the last cluster update.
    pub(crate) touched: Vec<u32>,
    /// Number of integrations so far (the map's clock).
    pub(crate) integrations: u64,
    pub(crate) clusters: ClusterStore,
}

impl SemanticMap {
    /// An empty map.
    ///
    /// # Errors
    /// [`MapError::InvalidConfig`] when `config` fails [`MapConfig::validate`].
    pub fn new(config: MapConfig, labels: LabelSet) -> Result<Self, MapError> {
        config.validate()?;
        Ok(Self {
            config,
            ignored: labels.ignored_bitmap(),
            labels,
            grid: VoxelGrid::default(),
            dirty: Vec::new(),
            touched: Vec::new(),
            integrations: 0,
            clusters: ClusterStore::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &MapConfig {
        &self.config
    }

    /// Voxel edge length (metres).
    pub fn resolution(&self) -> f64 {
        self.config.resolution
    }

    /// The label vocabulary.
    pub fn labels(&self) -> &LabelSet {
        &self.labels
    }

    /// Replaces the label vocabulary. When the ignored set changes, every
    /// observed voxel is re-examined at the next
    /// [`update_clusters`](Self::update_clusters).
    ///
    /// # Complexity
    /// O(allocated blocks x 512) when the ignored set changes, O(1) otherwise.
    pub fn set_labels(&mut self, labels: LabelSet) {
        let changed = labels.ignored().ne(self.labels.ignored());
        self.labels = labels;
        if !changed {
            return;
        }
        self.ignored = self.labels.ignored_bitmap();
        for (bk, block) in self.grid.keys.iter().zip(self.grid.blocks.iter_mut()) {
            for i in 0..block.cells.len() {
                let cell = &block.cells[i];
                if !cell.is_observed() {
                    continue;
                }
                let object = self.ignored.object(cell.dominant()).is_some();
                if object != block.is_object(i) {
                    block.set_object(i, object);
                    self.dirty.push(bk.voxel(i));
                }
            }
        }
    }

    /// Number of integrations performed (the map's clock; cluster stamps
    /// such as [`ObjectCluster::last_seen`](crate::ObjectCluster::last_seen)
    /// use it).
    pub fn integrations(&self) -> u64 {
        self.integrations
    }

    /// Evidence of voxel `key`, if it was ever hit.
    pub fn voxel(&self, key: &VoxelKey) -> Option<&VoxelEvidence> {
        self.grid.get(key).filter(|c| c.is_observed())
    }

    /// The object label of voxel `key`: its dominant label unless ignored.
    pub fn object_label(&self, key: &VoxelKey) -> Option<LabelId> {
        self.voxel(key)
            .and_then(|c| self.ignored.object(c.dominant()))
    }

    /// All observed voxels with their evidence (block order, unspecified).
    pub fn voxels(&self) -> impl Iterator<Item = (VoxelKey, &VoxelEvidence)> + '_ {
        self.grid.observed()
    }

    /// Number of observed voxels.
    ///
    /// # Complexity
    /// O(allocated blocks x 512).
    pub fn voxel_count(&self) -> usize {
        self.grid
            .blocks
            .iter()
            .map(|b| b.cells.iter().filter(|c| c.is_observed()).count())
            .sum()
    }

    /// Number of voxels whose dominant label is an object label (the voxels
    /// that clusters partition after an update).
    ///
    /// # Complexity
    /// O(allocated blocks).
    pub fn object_voxel_count(&self) -> usize {
        self.grid
            .blocks
            .iter()
            .map(|b| {
                b.object
                    .iter()
                    .map(|w| w.count_ones() as usize)
                    .sum::<usize>()
            })
            .sum()
    }

    /// Object voxels, block by block.
    pub(crate) fn object_voxels(&self) -> impl Iterator<Item = VoxelKey> + '_ {
        self.grid
            .keys
            .iter()
            .zip(&self.grid.blocks)
            .flat_map(|(bk, b)| mask_indices(&b.object).map(move |i| bk.voxel(i)))
    }

    /// Number of allocated `8 x 8 x 8` blocks.
    pub fn block_count(&self) -> usize {
        self.grid.block_count()
    }

    /// Whether integrations happened since the last
    /// [`update_clusters`](Self::update_clusters).
    pub fn has_pending_changes(&self) -> bool {
        !self.dirty.is_empty() || !self.touched.is_empty()
    }

    /// Heap bytes held by the map (capacity-based accounting of every
    /// container: blocks, block index, pending lists, clusters).
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        self.grid.heap_bytes()
            + self.dirty.capacity() * size_of::<VoxelKey>()
            + self.touched.capacity() * size_of::<u32>()
            + self.clusters.heap_bytes()
            + 8 * 1024 // ignored-label bitmap
    }
}
