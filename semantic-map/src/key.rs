//! Integer voxel coordinates and their blocks.

use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

/// Edge length of a block in voxels (blocks hold `8 x 8 x 8` voxels).
pub const BLOCK_EDGE: i32 = 8;
/// `log2(BLOCK_EDGE)`.
pub(crate) const BLOCK_SHIFT: u32 = 3;
/// Voxels per block.
pub const BLOCK_VOXELS: usize = 512;

/// Integer coordinates of a voxel: voxel `(x, y, z)` covers
/// `[x * res, (x + 1) * res) x [y * res, ...) x [z * res, ...)` in the world
/// frame, so the map extent is unbounded (up to `i32` range).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize,
)]
pub struct VoxelKey {
    /// Index along world x.
    pub x: i32,
    /// Index along world y.
    pub y: i32,
    /// Index along world z.
    pub z: i32,
}

impl VoxelKey {
    /// A key from its three indices.
    pub const fn new(x: i32, y: i32, z: i32) -> Self {
        Self { x, y, z }
    }

    /// The key of the voxel containing world point `p` at resolution `res`
    /// (floor semantics; saturates at the `i32` range for absurd inputs,
    /// which the map rejects before calling this).
    pub fn from_point(p: &Point3<f64>, res: f64) -> Self {
        let inv = 1.0 / res;
        Self::new(
            (p.x * inv).floor() as i32,
            (p.y * inv).floor() as i32,
            (p.z * inv).floor() as i32,
        )
    }

    /// World coordinates of the voxel centre.
    pub fn centre(&self, res: f64) -> Point3<f64> {
        Point3::new(
            (f64::from(self.x) + 0.5) * res,
            (f64::from(self.y) + 0.5) * res,
            (f64::from(self.z) + 0.5) * res,
        )
    }

    /// The key shifted by whole voxels (wrapping is impossible within the
    /// map's coordinate bound; saturating here keeps it panic-free).
    pub fn offset(&self, dx: i32, dy: i32, dz: i32) -> Self {
        Self::new(
            self.x.saturating_add(dx),
            self.y.saturating_add(dy),
            self.z.saturating_add(dz),
        )
    }

    /// The 26 neighbours sharing a face, an edge or a corner with this voxel.
    pub fn neighbours26(&self) -> impl Iterator<Item = VoxelKey> + '_ {
        NEIGHBOUR_OFFSETS
            .iter()
            .map(move |d| self.offset(d[0], d[1], d[2]))
    }

    /// Whether `other` is one of the 26 neighbours of this voxel.
    pub fn is_neighbour26(&self, other: &VoxelKey) -> bool {
        let d = Vector3::new(
            i64::from(self.x) - i64::from(other.x),
            i64::from(self.y) - i64::from(other.y),
            i64::from(self.z) - i64::from(other.z),
        );
        d != Vector3::zeros() && d.iter().all(|c| c.abs() <= 1)
    }

    /// The block holding this voxel.
    #[inline]
    pub(crate) fn block(&self) -> BlockKey {
        BlockKey {
            x: self.x >> BLOCK_SHIFT,
            y: self.y >> BLOCK_SHIFT,
            z: self.z >> BLOCK_SHIFT,
        }
    }

    /// Linear index of this voxel inside its block.
    #[inline]
    pub(crate) fn index_in_block(&self) -> usize {
        let m = BLOCK_EDGE - 1;
        ((self.x & m) | ((self.y & m) << BLOCK_SHIFT) | ((self.z & m) << (2 * BLOCK_SHIFT)))
            as usize
    }
}

/// The 26-neighbourhood offsets.
pub(crate) const NEIGHBOUR_OFFSETS: [[i32; 3]; 26] = {
    let mut out = [[0i32; 3]; 26];
    let mut n = 0;
    let mut dz = -1;
    while dz <= 1 {
        let mut dy = -1;
        while dy <= 1 {
            let mut dx = -1;
            while dx <= 1 {
                if !(dx == 0 && dy == 0 && dz == 0) {
                    out[n] = [dx, dy, dz];
                    n += 1;
                }
                dx += 1;
            }
            dy += 1;
        }
        dz += 1;
    }
    out
};

/// Integer coordinates of an `8 x 8 x 8` block.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct BlockKey {
    pub(crate) x: i32,
    pub(crate) y: i32,
    pub(crate) z: i32,
}

impl BlockKey {
    /// Slot `0..8` of the block in an eight-entry cache indexed by the
    /// parities of its coordinates: the (up to) eight blocks around any
    /// voxel's 26-neighbourhood, or on either side of a block border, land
    /// in distinct slots.
    #[inline]
    pub(crate) fn parity_slot(&self) -> usize {
        ((self.x & 1) | ((self.y & 1) << 1) | ((self.z & 1) << 2)) as usize
    }

    /// The key of voxel `index` (see [`VoxelKey::index_in_block`]) of this block.
    #[inline]
    pub(crate) fn voxel(&self, index: usize) -> VoxelKey {
        let i = index as i32;
        let m = BLOCK_EDGE - 1;
        VoxelKey::new(
            (self.x << BLOCK_SHIFT) | (i & m),
            (self.y << BLOCK_SHIFT) | ((i >> BLOCK_SHIFT) & m),
            (self.z << BLOCK_SHIFT) | ((i >> (2 * BLOCK_SHIFT)) & m),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn block_round_trip(x in -1_000_000i32..1_000_000, y in -1_000_000i32..1_000_000, z in -1_000_000i32..1_000_000) {
            let k = VoxelKey::new(x, y, z);
            let b = k.block();
            prop_assert_eq!(b.voxel(k.index_in_block()), k);
            prop_assert!(k.index_in_block() < BLOCK_VOXELS);
        }
    }

    #[test]
    fn neighbours_are_26_distinct() {
        let k = VoxelKey::new(-1, 0, 7);
        let mut n: Vec<_> = k.neighbours26().collect();
        n.sort();
        n.dedup();
        assert_eq!(n.len(), 26);
        assert!(n.iter().all(|m| k.is_neighbour26(m)));
        assert!(!k.is_neighbour26(&k));
        assert!(!k.is_neighbour26(&k.offset(2, 0, 0)));
    }

    #[test]
    fn floor_semantics_for_negative_coordinates() {
        let k = VoxelKey::from_point(&Point3::new(-0.01, 0.0, 0.049), 0.05);
        assert_eq!(k, VoxelKey::new(-1, 0, 0));
        assert_eq!(k.block(), BlockKey { x: -1, y: 0, z: 0 });
    }
}
