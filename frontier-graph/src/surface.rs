//! Walkable surfaces per column: the multi-layer height field of a
//! [`crate::MultiLevelMap`], built online from the robot's own returns.
//!
//! Each column (a `surface_resolution` square) keeps up to
//! [`MAX_INTERVALS`] vertical *intervals* of returns, sorted by height: a
//! return extends the interval it falls in (or within [`MERGE_GAP`] of) or
//! opens a new one. The top of an interval is a *walkable surface* when
//! * it was seen from above (a return whose ray came down onto it: a floor,
//!   a tread, a table top), or the interval is at least [`TALL`] high (a
//!   riser or a wall face whose top edge was seen: from below a stair shows
//!   risers, not treads), and
//! * the next interval above starts at least the robot's height higher
//!   (head clearance; a ceiling seen from below is a thin interval seen
//!   from below and never a surface itself).
//!
//! Whether a surface is walkable for the robot (connected by steps, wide
//! enough) is decided by the stair extraction ([`crate::stairs`]), not here.
//!
//! ```text
//!   z ^         .  ceiling (thin, seen from below: not a surface)
//!     |   ____|        upper floor (surface, level 1)
//!     |  |  __|  <- risers: tall intervals, tops = treads
//!     |  |_|
//!     |__|          floor (surface, level 0)
//!     +---------------> column
//! ```
//!
//! # Complexity
//! O(1) per return (hash lookup + at most [`MAX_INTERVALS`] intervals),
//! memory O(observed columns).

use nalgebra::Point3;
use rustc_hash::FxHashMap;

use crate::cell::cell_coord;
use serde::{Deserialize, Serialize};

/// Most intervals kept per column; when a column would get more, the two
/// closest intervals are merged.
pub(crate) const MAX_INTERVALS: usize = 6;
/// Returns closer than this (m) to an interval extend it.
pub(crate) const MERGE_GAP: f32 = 0.06;
/// An interval at least this high (m) exposes its top even if the top was
/// never seen from above.
pub(crate) const TALL: f32 = 0.08;
/// A return counts as seen from above when the sensor is at least this
/// much (m) higher.
const ABOVE: f64 = 0.05;

/// A vertical run of returns in one column.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct Interval {
    pub lo: f32,
    pub hi: f32,
    /// The top was hit by a ray coming from above.
    pub top_from_above: bool,
}

/// The intervals of one column, sorted by height.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub(crate) struct Column {
    pub intervals: Vec<Interval>,
    /// Listed in [`SurfaceMap::touched`] since the last
    /// [`SurfaceMap::take_touched`] (bookkeeping, not compared).
    #[serde(skip)]
    touched: bool,
}

impl PartialEq for Column {
    fn eq(&self, other: &Self) -> bool {
        self.intervals == other.intervals
    }
}

impl Column {
    fn insert(&mut self, z: f32, from_above: bool) {
        let iv = &mut self.intervals;
        let k = iv.partition_point(|i| i.hi + MERGE_GAP < z);
        if k < iv.len() && iv[k].lo - MERGE_GAP <= z {
            let i = &mut iv[k];
            if z > i.hi {
                i.hi = z;
                i.top_from_above = from_above;
            } else if from_above && i.hi - z <= MERGE_GAP / 2.0 {
                i.top_from_above = true;
            }
            i.lo = i.lo.min(z);
            // The grown interval may now touch its upper neighbour.
            if k + 1 < iv.len() && iv[k + 1].lo - MERGE_GAP <= iv[k].hi {
                let up = iv.remove(k + 1);
                let i = &mut iv[k];
                i.hi = up.hi;
                i.top_from_above = up.top_from_above;
            }
            return;
        }
        iv.insert(
            k,
            Interval {
                lo: z,
                hi: z,
                top_from_above: from_above,
            },
        );
        if iv.len() > MAX_INTERVALS {
            // Merge the two closest neighbours (bounded memory).
            let j = (0..iv.len() - 1)
                .min_by(|&a, &b| (iv[a + 1].lo - iv[a].hi).total_cmp(&(iv[b + 1].lo - iv[b].hi)))
                .unwrap_or(0);
            let up = iv.remove(j + 1);
            iv[j].hi = up.hi;
            iv[j].top_from_above = up.top_from_above;
        }
    }

    /// Heights of the walkable surfaces of this column, ascending.
    pub(crate) fn surfaces(&self, clearance: f32) -> impl Iterator<Item = f32> + '_ {
        let iv = &self.intervals;
        (0..iv.len()).filter_map(move |k| {
            let i = iv[k];
            let exposed = i.top_from_above || i.hi - i.lo >= TALL;
            let clear = iv.get(k + 1).is_none_or(|up| up.lo - i.hi >= clearance);
            (exposed && clear).then_some(i.hi)
        })
    }
}

/// Column coordinates at the surface resolution.
pub(crate) type ColumnKey = (i32, i32);

/// The walkable-surface map.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub(crate) struct SurfaceMap {
    pub resolution: f64,
    #[serde(with = "column_list")]
    pub columns: FxHashMap<ColumnKey, Column>,
    /// Columns changed since the last [`SurfaceMap::take_dirty`].
    #[serde(skip)]
    dirty: bool,
    /// Columns that received returns since the last
    /// [`take_touched`](Self::take_touched), each once.
    #[serde(skip)]
    touched: Vec<ColumnKey>,
}

impl SurfaceMap {
    pub(crate) fn new(resolution: f64) -> Self {
        Self {
            resolution,
            columns: FxHashMap::default(),
            dirty: false,
            touched: Vec::new(),
        }
    }

    /// The column of a horizontal position; `None` outside the numeric range.
    pub(crate) fn key(&self, x: f64, y: f64) -> Option<ColumnKey> {
        Some((
            cell_coord(x / self.resolution)?,
            cell_coord(y / self.resolution)?,
        ))
    }

    /// World x/y of a column centre.
    pub(crate) fn center(&self, k: ColumnKey) -> (f64, f64) {
        (
            (f64::from(k.0) + 0.5) * self.resolution,
            (f64::from(k.1) + 0.5) * self.resolution,
        )
    }

    /// Adds the returns of one scan from `origin`; returns farther than
    /// `max_range` are ignored (they are truncated rays, not surfaces).
    /// Points must be finite (checked by the caller).
    pub(crate) fn integrate(
        &mut self,
        origin: &Point3<f64>,
        points: &[Point3<f64>],
        max_range: f64,
    ) {
        for p in points {
            if (p - origin).norm() > max_range {
                continue;
            }
            let Some(k) = self.key(p.x, p.y) else {
                continue;
            };
            // Heights are within the grid's numeric range; f32 keeps 1 mm.
            #[allow(clippy::cast_possible_truncation)]
            let z = p.z as f32;
            let above = origin.z > p.z + ABOVE;
            let c = self.columns.entry(k).or_default();
            c.insert(z, above);
            if !c.touched {
                c.touched = true;
                self.touched.push(k);
            }
            self.dirty = true;
        }
    }

    /// Forces the next [`take_dirty`](Self::take_dirty) to report a change.
    pub(crate) fn mark_dirty(&mut self) {
        self.dirty = true;
    }

    /// Whether anything changed since the last call.
    pub(crate) fn take_dirty(&mut self) -> bool {
        std::mem::take(&mut self.dirty)
    }

    /// The columns that received returns since the last call, each once.
    pub(crate) fn take_touched(&mut self) -> Vec<ColumnKey> {
        let touched = std::mem::take(&mut self.touched);
        for k in &touched {
            if let Some(c) = self.columns.get_mut(k) {
                c.touched = false;
            }
        }
        touched
    }

    /// Walkable surface heights of column `k`.
    pub(crate) fn surfaces(&self, k: ColumnKey, clearance: f32) -> impl Iterator<Item = f32> + '_ {
        self.columns
            .get(&k)
            .into_iter()
            .flat_map(move |c| c.surfaces(clearance))
    }
}

/// Serialises the column map as a sorted list.
mod column_list {
    use super::{Column, ColumnKey};
    use rustc_hash::FxHashMap;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub(super) fn serialize<S: Serializer>(
        m: &FxHashMap<ColumnKey, Column>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        let mut v: Vec<(&ColumnKey, &Column)> = m.iter().collect();
        v.sort_by_key(|(k, _)| **k);
        v.serialize(s)
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<FxHashMap<ColumnKey, Column>, D::Error> {
        Ok(Vec::<(ColumnKey, Column)>::deserialize(d)?
            .into_iter()
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_is_a_surface_ceiling_is_not() {
        let mut c = Column::default();
        for _ in 0..3 {
            c.insert(0.0, true);
            c.insert(2.5, false);
        }
        let s: Vec<f32> = c.surfaces(0.88).collect();
        assert_eq!(s, vec![0.0]);
    }

    #[test]
    fn riser_top_is_a_surface_from_below() {
        let mut c = Column::default();
        for k in 0..5 {
            c.insert(1.0 + 0.04 * k as f32, false);
        }
        assert_eq!(c.surfaces(0.88).collect::<Vec<_>>(), vec![1.16]);
    }

    #[test]
    fn clearance_hides_floor_under_table() {
        let mut c = Column::default();
        c.insert(0.0, true);
        c.insert(0.75, true);
        assert_eq!(c.surfaces(0.88).collect::<Vec<_>>(), vec![0.75]);
        assert_eq!(c.surfaces(0.5).collect::<Vec<_>>(), vec![0.0, 0.75]);
    }

    #[test]
    fn intervals_stay_bounded_and_sorted() {
        let mut c = Column::default();
        for k in 0..40 {
            c.insert((k * 37 % 40) as f32 * 0.3, k % 2 == 0);
        }
        assert!(c.intervals.len() <= MAX_INTERVALS);
        assert!(c.intervals.windows(2).all(|w| w[0].hi < w[1].lo));
        assert!(c.intervals.iter().all(|i| i.lo <= i.hi));
    }
}
