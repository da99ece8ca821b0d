//! Fusing labelled world-frame points into the voxel evidence.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::error::MapError;
use crate::grid::{NO_BLOCK, VoxelGrid};
use crate::key::{BlockKey, VoxelKey};
use crate::label::{IgnoredBitmap, LabelId};
use crate::map::SemanticMap;

/// A world-frame point with its semantic label (LiDAR return, fused
/// labelled cloud, back-projected pixel).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LabeledPoint {
    /// World-frame position (metres, z up).
    pub position: Point3<f32>,
    /// Semantic label.
    pub label: LabelId,
}

impl LabeledPoint {
    /// A point from coordinates and a label.
    pub fn new(x: f32, y: f32, z: f32, label: LabelId) -> Self {
        Self {
            position: Point3::new(x, y, z),
            label,
        }
    }
}

/// What one integration did: every input point is either accepted or counted
/// in exactly one rejection counter.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct IntegrationStats {
    /// Points (or pixels visited) offered.
    pub points: u64,
    /// Points fused into the map.
    pub accepted: u64,
    /// Rejected: NaN or infinite coordinate or depth.
    pub rejected_non_finite: u64,
    /// Rejected: outside the range limits (distance from the origin for
    /// points, z-depth window for depth images; includes zero depth).
    pub rejected_range: u64,
    /// Rejected: a coordinate beyond [`MapConfig::max_abs_coordinate`](crate::MapConfig::max_abs_coordinate).
    pub rejected_bounds: u64,
    /// Voxels hit for the first time.
    pub new_voxels: u64,
    /// Blocks allocated.
    pub new_blocks: u64,
    /// Object-label (dominant non-ignored label) changes recorded for the
    /// next cluster update. A voxel may count more than once; consecutive
    /// identical points are applied as one update, so a transient label
    /// inside such a run is not counted.
    pub object_label_changes: u64,
}

impl IntegrationStats {
    /// Total rejected points.
    pub fn rejected(&self) -> u64 {
        self.rejected_non_finite + self.rejected_range + self.rejected_bounds
    }

    /// Adds another integration's counters to these.
    pub fn accumulate(&mut self, o: &IntegrationStats) {
        self.points += o.points;
        self.accepted += o.accepted;
        self.rejected_non_finite += o.rejected_non_finite;
        self.rejected_range += o.rejected_range;
        self.rejected_bounds += o.rejected_bounds;
        self.new_voxels += o.new_voxels;
        self.new_blocks += o.new_blocks;
        self.object_label_changes += o.object_label_changes;
    }
}

/// `1.5 * 2^52`: for `|t| < 2^51`, `t + ROUND_SHIFT` lies in `[2^52, 2^53)`,
/// where doubles are the integers, so the sum is `t` rounded to the nearest
/// integer, held in the low mantissa bits as two's complement (the `2^51`
/// of the shift is a multiple of `2^32`).
const ROUND_SHIFT: f64 = 6_755_399_441_055_744.0;

/// `floor(t)` as `i32` for `|t|` well inside the `i32` range (guaranteed by
/// the coordinate bound, see [`MapConfig::validate`](crate::MapConfig::validate)).
///
/// Exact: `t + ROUND_SHIFT` rounds `t` to the nearest integer `n` (both
/// as a double and in its low 32 bits); `floor(t)` is `n - 1` when `n > t`
/// (the rounding went up), else `n`. Four arithmetic instructions and a
/// move, without the saturation checks of an `as` conversion or the
/// `floor` library call of baseline x86-64.
#[inline]
pub(crate) fn fast_floor(t: f64) -> i32 {
    let shifted = t + ROUND_SHIFT;
    let nearest = shifted - ROUND_SHIFT;
    // Truncation keeps the low 32 bits: the rounded integer.
    let n = shifted.to_bits() as i32;
    n - i32::from(nearest > t)
}

/// The write path shared by point and depth integration: caches the last
/// block and eight recent ones (see [`BlockKey::parity_slot`]), records hit
/// bits, touched blocks and object-label changes.
pub(crate) struct Inserter<'a> {
    grid: &'a mut VoxelGrid,
    dirty: &'a mut Vec<VoxelKey>,
    touched: &'a mut Vec<u32>,
    ignored: &'a IgnoredBitmap,
    inv_res: f64,
    bound: f64,
    last_key: BlockKey,
    last: u32,
    /// Recently resolved blocks by [`BlockKey::parity_slot`] (index
    /// `NO_BLOCK`: empty); each is allocated and listed as touched.
    recent: [(BlockKey, u32); 8],
    pending: [Pending; BATCH],
    len: usize,
    run: Pending,
    sink: u32,
    pub(crate) stats: IntegrationStats,
}

impl<'a> Inserter<'a> {
    pub(crate) fn new(map: &'a mut SemanticMap) -> Self {
        Self {
            inv_res: 1.0 / map.config.resolution,
            bound: map.config.max_abs_coordinate,
            grid: &mut map.grid,
            dirty: &mut map.dirty,
            touched: &mut map.touched,
            ignored: &map.ignored,
            last_key: BlockKey { x: 0, y: 0, z: 0 },
            last: NO_BLOCK,
            recent: [(BlockKey { x: 0, y: 0, z: 0 }, NO_BLOCK); 8],
            pending: [Pending::default(); BATCH],
            len: 0,
            run: Pending::default(),
            sink: 0,
            stats: IntegrationStats::default(),
        }
    }

    /// Queues one finite, range-checked world point; rejects it (counted)
    /// when a coordinate exceeds the absolute bound.
    #[inline(always)]
    pub(crate) fn insert(&mut self, x: f64, y: f64, z: f64, label: LabelId) {
        if x.abs() > self.bound || y.abs() > self.bound || z.abs() > self.bound {
            self.stats.rejected_bounds += 1;
            return;
        }
        self.insert_within_bound(x, y, z, label);
    }

    /// The coordinate bound ([`MapConfig::max_abs_coordinate`](crate::MapConfig::max_abs_coordinate)).
    pub(crate) fn bound(&self) -> f64 {
        self.bound
    }

    /// Queues one finite, range-checked world point whose coordinates the
    /// caller proved within the absolute bound (see [`insert`](Self::insert)).
    ///
    /// Points are applied in input order, in two stages: runs of consecutive
    /// points with the same voxel and label are merged (one evidence update
    /// per run), and runs are queued in batches of [`BATCH`] whose first pass
    /// resolves blocks and already loads each target cell, so the cache
    /// misses of scattered scans (LiDAR) overlap instead of serialising; the
    /// second pass updates the (now cached) cells.
    #[inline(always)]
    pub(crate) fn insert_within_bound(&mut self, x: f64, y: f64, z: f64, label: LabelId) {
        self.stats.accepted += 1;
        let key = VoxelKey::new(
            fast_floor(x * self.inv_res),
            fast_floor(y * self.inv_res),
            fast_floor(z * self.inv_res),
        );
        // Consecutive points in the same voxel with the same label (dense
        // depth images hit each voxel several times in a row) form a run
        // applied at once; the evidence is the same as point by point.
        if self.run.count > 0
            && self.run.count < u16::MAX
            && key == self.run.key
            && label == self.run.label
        {
            self.run.count += 1;
            return;
        }
        self.end_run();
        self.run = Pending {
            key,
            block: NO_BLOCK,
            label,
            count: 1,
        };
    }

    /// Resolves the block of the current run and queues it.
    #[inline(always)]
    fn end_run(&mut self) {
        if self.run.count == 0 {
            return;
        }
        let Pending {
            key, label, count, ..
        } = self.run;
        self.run.count = 0;
        let bk = key.block();
        if self.last == NO_BLOCK || bk != self.last_key {
            self.last = self.resolve(bk);
            self.last_key = bk;
        }
        let i = key.index_in_block();
        // Early load of the target cell (the value only feeds `sink`).
        self.sink = self
            .sink
            .wrapping_add(self.grid.blocks[self.last as usize].cells[i].hits());
        self.pending[self.len] = Pending {
            key,
            block: self.last,
            label,
            count,
        };
        self.len += 1;
        if self.len == BATCH {
            self.flush();
        }
    }

    /// The index of block `bk`, allocated (counted) and listed as touched
    /// when first met; blocks met again soon are not hashed again.
    #[inline]
    fn resolve(&mut self, bk: BlockKey) -> u32 {
        let slot = bk.parity_slot();
        let (key, index) = self.recent[slot];
        if index != NO_BLOCK && key == bk {
            return index;
        }
        let mut created = false;
        let index = self.grid.find_or_insert(bk, &mut created);
        if created {
            self.stats.new_blocks += 1;
        }
        let block = &mut self.grid.blocks[index as usize];
        if !block.touched {
            block.touched = true;
            self.touched.push(index);
        }
        self.recent[slot] = (bk, index);
        index
    }

    /// Applies the queued points in order.
    fn flush(&mut self) {
        for p in &self.pending[..self.len] {
            let block = &mut self.grid.blocks[p.block as usize];
            let i = p.key.index_in_block();
            block.hit[i >> 6] |= 1u64 << (i & 63);
            let cell = &mut block.cells[i];
            if !cell.is_observed() {
                self.stats.new_voxels += 1;
            }
            let (before, after) = cell.add_n(p.label, p.count);
            if before != after {
                let after_obj = self.ignored.object(after);
                if self.ignored.object(before) != after_obj {
                    block.set_object(i, after_obj.is_some());
                    self.dirty.push(p.key);
                    self.stats.object_label_changes += 1;
                }
            }
        }
        self.len = 0;
    }

    /// Applies what is still queued and returns the counters.
    pub(crate) fn finish(mut self) -> IntegrationStats {
        self.end_run();
        self.flush();
        std::hint::black_box(self.sink);
        self.stats
    }
}

/// Points per insertion batch.
const BATCH: usize = 32;

/// A point waiting in the insertion batch.
#[derive(Debug, Clone, Copy, Default)]
struct Pending {
    key: VoxelKey,
    block: u32,
    label: LabelId,
    /// Points in the run (0: no run).
    count: u16,
}

impl Inserter<'_> {
    /// Stores `cell` as the evidence of `key` (snapshot restore).
    pub(crate) fn restore(&mut self, key: VoxelKey, cell: crate::VoxelEvidence) {
        let mut created = false;
        let b = self.grid.find_or_insert(key.block(), &mut created);
        let block = &mut self.grid.blocks[b as usize];
        let i = key.index_in_block();
        block.cells[i] = cell;
        block.set_object(i, self.ignored.object(cell.dominant()).is_some());
    }
}

impl SemanticMap {
    /// Fuses world-frame labelled points seen from sensor `origin`.
    ///
    /// Each point adds one vote for its label to the voxel containing it
    /// (see [`VoxelEvidence`](crate::VoxelEvidence) for the slot rule).
    /// Points with a non-finite coordinate, a distance from `origin` outside
    /// `[min_range, max_range]`, or a coordinate beyond
    /// `max_abs_coordinate` are rejected and counted, never fused.
    /// Clusters are not touched: call
    /// [`update_clusters`](Self::update_clusters) afterwards (after each
    /// integration, or after a batch).
    ///
    /// # Errors
    /// [`MapError::NonFinitePose`] when `origin` is not finite (nothing is
    /// integrated).
    ///
    /// # Complexity
    /// O(n) expected for n points: one hash lookup per change of block
    /// between consecutive points (spatially coherent scans mostly stay in
    /// the cached block) and O(1) work per point.
    pub fn integrate_points(
        &mut self,
        origin: &Point3<f64>,
        points: &[LabeledPoint],
    ) -> Result<IntegrationStats, MapError> {
        if !origin.iter().all(|c| c.is_finite()) {
            return Err(MapError::NonFinitePose);
        }
        let (min2, max2) = (
            self.config.min_range * self.config.min_range,
            self.config.max_range * self.config.max_range,
        );
        let mut ins = Inserter::new(self);
        ins.stats.points = points.len() as u64;
        for p in points {
            let (x, y, z) = (
                f64::from(p.position.x),
                f64::from(p.position.y),
                f64::from(p.position.z),
            );
            if !(x.is_finite() && y.is_finite() && z.is_finite()) {
                ins.stats.rejected_non_finite += 1;
                continue;
            }
            let d2 = (x - origin.x).powi(2) + (y - origin.y).powi(2) + (z - origin.z).powi(2);
            if !(min2..=max2).contains(&d2) {
                ins.stats.rejected_range += 1;
                continue;
            }
            ins.insert(x, y, z, p.label);
        }
        let stats = ins.finish();
        self.integrations += 1;
        Ok(stats)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{LabelSet, MapConfig};

    #[test]
    fn rejected_point_accounting() {
        let mut map = SemanticMap::new(MapConfig::default(), LabelSet::household()).unwrap();
        let l = LabelId(10);
        let pts = [
            LabeledPoint::new(1.0, 0.0, 0.0, l),           // ok
            LabeledPoint::new(f32::NAN, 0.0, 0.0, l),      // non-finite
            LabeledPoint::new(0.0, f32::INFINITY, 0.0, l), // non-finite
            LabeledPoint::new(60.0, 0.0, 0.0, l),          // beyond max_range 50
            LabeledPoint::new(1.02, 0.0, 0.0, l),          // ok, same voxel
            LabeledPoint::new(1.0, 1.0, 0.0, LabelId(1)),  // ok (wall)
            LabeledPoint::new(3.0e38, 0.0, 0.0, l),        // out of range
        ];
        let s = map.integrate_points(&Point3::origin(), &pts).unwrap();
        assert_eq!(s.points, 7);
        assert_eq!(s.accepted, 3);
        assert_eq!(s.rejected_non_finite, 2);
        assert_eq!(s.rejected_range, 2);
        assert_eq!(s.rejected_bounds, 0);
        assert_eq!(s.accepted + s.rejected(), s.points);
        assert_eq!(s.new_voxels, 2);
        assert_eq!(s.object_label_changes, 1); // the chair voxel; wall is ignored
        assert_eq!(map.voxel_count(), 2);
        assert_eq!(map.integrations(), 1);

        // Absurd coordinates within range of an absurd-but-finite origin.
        let far = Point3::new(2.0e5, 0.0, 0.0);
        let s = map
            .integrate_points(&far, &[LabeledPoint::new(2.0e5, 0.0, 0.5, l)])
            .unwrap();
        assert_eq!((s.accepted, s.rejected_bounds), (0, 1));

        // A non-finite origin is an error and integrates nothing.
        let err = map.integrate_points(&Point3::new(f64::NAN, 0.0, 0.0), &pts);
        assert_eq!(err, Err(MapError::NonFinitePose));
        assert_eq!(map.integrations(), 2);
        assert_eq!(map.voxel_count(), 2);
    }

    #[test]
    fn fast_floor_matches_floor() {
        let limit = f64::from(i32::MAX / 4);
        for t in [
            -2.5,
            -2.0,
            -1e-12,
            -0.0,
            0.0,
            1e-12,
            0.999_999,
            1.0,
            3.7,
            -3.7,
            1e8,
            -1e8,
            0.5,
            -0.5,
            1.5,
            -1.5,
            1.0 - f64::EPSILON / 2.0,
            -1.0 + f64::EPSILON / 2.0,
            -f64::MIN_POSITIVE,
            limit,
            -limit,
            limit - 0.5,
            -limit + 0.5,
        ] {
            assert_eq!(fast_floor(t), t.floor() as i32, "{t}");
        }
    }

    proptest::proptest! {
        /// The shifted rounding equals `floor` on the whole index range,
        /// halves and near-integers included.
        #[test]
        fn fast_floor_is_floor(
            t in -f64::from(i32::MAX / 4)..f64::from(i32::MAX / 4),
            n in -(i32::MAX / 4)..(i32::MAX / 4),
            ulps in 0usize..4,
        ) {
            proptest::prop_assert_eq!(fast_floor(t), t.floor() as i32);
            // Integers, halves and their floating-point neighbours.
            for base in [f64::from(n), f64::from(n) + 0.5] {
                let (mut up, mut down) = (base, base);
                for _ in 0..ulps {
                    (up, down) = (up.next_up(), down.next_down());
                }
                for u in [base, up, down] {
                    proptest::prop_assert_eq!(fast_floor(u), u.floor() as i32, "{}", u);
                }
            }
        }
    }

    #[test]
    fn min_range_rejects_close_points() {
        let cfg = MapConfig {
            min_range: 0.5,
            ..MapConfig::default()
        };
        let mut map = SemanticMap::new(cfg, LabelSet::new()).unwrap();
        let s = map
            .integrate_points(
                &Point3::origin(),
                &[LabeledPoint::new(0.1, 0.0, 0.0, LabelId(3))],
            )
            .unwrap();
        assert_eq!(s.rejected_range, 1);
    }
}
