//! Sparse block storage: hashed `8 x 8 x 8` blocks of [`VoxelEvidence`]
//! (the Bonxai / VDB leaf layout without the inner levels).

use rustc_hash::FxHashMap;

use crate::evidence::VoxelEvidence;
use crate::key::{BLOCK_VOXELS, BlockKey, VoxelKey};

/// Marker for "no cached block".
pub(crate) const NO_BLOCK: u32 = u32::MAX;

/// One `8 x 8 x 8` block: 8 KiB of evidence plus two 512-bit masks.
#[derive(Debug, Clone)]
pub(crate) struct Block {
    /// Voxel evidence, indexed by [`VoxelKey::index_in_block`].
    pub(crate) cells: Box<[VoxelEvidence; BLOCK_VOXELS]>,
    /// Voxels whose dominant label is an object (non-ignored) label.
    pub(crate) object: [u64; 8],
    /// Voxels hit since the last cluster update (observation accounting).
    pub(crate) hit: [u64; 8],
    /// Whether this block is listed in the map's touched list.
    pub(crate) touched: bool,
}

impl Block {
    fn new() -> Self {
        Self {
            cells: Box::new([VoxelEvidence::EMPTY; BLOCK_VOXELS]),
            object: [0; 8],
            hit: [0; 8],
            touched: false,
        }
    }

    #[inline]
    pub(crate) fn set_object(&mut self, i: usize, on: bool) {
        let bit = 1u64 << (i & 63);
        if on {
            self.object[i >> 6] |= bit;
        } else {
            self.object[i >> 6] &= !bit;
        }
    }

    #[inline]
    pub(crate) fn is_object(&self, i: usize) -> bool {
        self.object[i >> 6] & (1u64 << (i & 63)) != 0
    }
}

/// Iterates the set bits of a 512-bit mask as voxel indices.
pub(crate) fn mask_indices(mask: &[u64; 8]) -> impl Iterator<Item = usize> + '_ {
    mask.iter().enumerate().flat_map(|(w, &bits)| {
        let mut b = bits;
        std::iter::from_fn(move || {
            if b == 0 {
                return None;
            }
            let t = b.trailing_zeros() as usize;
            b &= b - 1;
            Some(w * 64 + t)
        })
    })
}

/// The hashed block map.
#[derive(Debug, Clone, Default)]
pub(crate) struct VoxelGrid {
    index: FxHashMap<BlockKey, u32>,
    pub(crate) blocks: Vec<Block>,
    pub(crate) keys: Vec<BlockKey>,
}

impl VoxelGrid {
    /// Index of block `bk`, if allocated.
    #[inline]
    pub(crate) fn find(&self, bk: BlockKey) -> Option<u32> {
        self.index.get(&bk).copied()
    }

    /// Index of block `bk`, allocating it when missing (`created` is set).
    #[inline]
    pub(crate) fn find_or_insert(&mut self, bk: BlockKey, created: &mut bool) -> u32 {
        if let Some(&i) = self.index.get(&bk) {
            return i;
        }
        let i = u32::try_from(self.blocks.len()).unwrap_or(NO_BLOCK - 1);
        self.blocks.push(Block::new());
        self.keys.push(bk);
        self.index.insert(bk, i);
        *created = true;
        i
    }

    /// Evidence of voxel `key` (`None` when its block is unallocated).
    #[inline]
    pub(crate) fn get(&self, key: &VoxelKey) -> Option<&VoxelEvidence> {
        self.find(key.block())
            .map(|b| &self.blocks[b as usize].cells[key.index_in_block()])
    }

    /// Number of allocated blocks.
    pub(crate) fn block_count(&self) -> usize {
        self.blocks.len()
    }

    /// All observed voxels (hits > 0), block by block.
    pub(crate) fn observed(&self) -> impl Iterator<Item = (VoxelKey, &VoxelEvidence)> + '_ {
        self.keys.iter().zip(&self.blocks).flat_map(|(bk, b)| {
            b.cells
                .iter()
                .enumerate()
                .filter(|(_, c)| c.is_observed())
                .map(move |(i, c)| (bk.voxel(i), c))
        })
    }

    /// Heap bytes held (capacity-based accounting).
    pub(crate) fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        let per_block = size_of::<[VoxelEvidence; BLOCK_VOXELS]>();
        self.blocks.capacity() * size_of::<Block>()
            + self.blocks.len() * per_block
            + self.keys.capacity() * size_of::<BlockKey>()
            // hashbrown: one control byte per bucket plus the entry.
            + self.index.capacity() * (size_of::<(BlockKey, u32)>() + 1)
    }
}

/// A read cursor with a direct-mapped cache of eight blocks, indexed by the
/// parities of the block coordinates: the (up to) eight blocks around any
/// voxel's 26-neighbourhood land in distinct slots, so neighbour scans hash
/// each block once.
pub(crate) struct GridCursor<'a> {
    grid: &'a VoxelGrid,
    slots: [(BlockKey, Option<u32>, bool); 8],
}

impl<'a> GridCursor<'a> {
    pub(crate) fn new(grid: &'a VoxelGrid) -> Self {
        Self {
            grid,
            slots: [(BlockKey { x: 0, y: 0, z: 0 }, None, false); 8],
        }
    }

    /// The block holding `key` and the voxel's index inside it.
    #[inline(always)]
    pub(crate) fn locate(&mut self, key: &VoxelKey) -> Option<(&'a Block, usize)> {
        let bk = key.block();
        let entry = &mut self.slots[bk.parity_slot()];
        if !entry.2 || entry.0 != bk {
            *entry = (bk, self.grid.find(bk), true);
        }
        entry
            .1
            .map(|b| (&self.grid.blocks[b as usize], key.index_in_block()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mask_iteration() {
        let mut m = [0u64; 8];
        m[0] = 0b1001;
        m[7] = 1 << 63;
        assert_eq!(mask_indices(&m).collect::<Vec<_>>(), vec![0, 3, 511]);
    }

    #[test]
    fn insert_and_find() {
        let mut g = VoxelGrid::default();
        let mut created = false;
        let k = VoxelKey::new(-9, 3, 100);
        let b = g.find_or_insert(k.block(), &mut created);
        assert!(created);
        created = false;
        assert_eq!(g.find_or_insert(k.block(), &mut created), b);
        assert!(!created);
        assert!(g.get(&k).is_some_and(|c| !c.is_observed()));
        assert!(g.get(&VoxelKey::new(1000, 0, 0)).is_none());
        assert!(g.heap_bytes() >= 8192);
    }
}
