//! Exact shortest paths on the traversable grid: Dijkstra with a bucket
//! queue (Dial's algorithm), 8-connected, octile costs, no corner cutting.

use nalgebra::Point2;
use std::f64::consts::SQRT_2;

use crate::{Cell, OccupancyGrid};

/// The 8 moves: 4 straight then 4 diagonal.
pub(crate) const DIRS: [(i32, i32); 8] = [
    (1, 0),
    (-1, 0),
    (0, 1),
    (0, -1),
    (1, 1),
    (1, -1),
    (-1, 1),
    (-1, -1),
];
const NO_PARENT: u8 = u8::MAX;
/// Bucket width is the smallest move cost (1 cell): every label in the lowest
/// non-empty bucket is final, and the largest move (√2) spans at most 3
/// buckets, so 4 circular buckets suffice.
const NB: usize = 4;

/// An exact path length `a + b√2` (a straight and b diagonal moves), packed
/// into an unsigned integer: the straight count in the low half, the
/// diagonal count in the high half.
///
/// Comparisons go through [`Label::value`], which evaluates `a + b√2` in
/// `f64` from the integer counts. Distinct `(a, b)` have distinct lengths
/// (√2 is irrational) that differ by at least about `1 / (2√2 · max(a, b))`,
/// far above the `f64` evaluation error for counts below 2^32, so the order
/// is exact and equal lengths are bit-identical (no accumulated rounding).
trait Label: Copy {
    /// Length 0.
    const ZERO: Self;
    /// The label one move further (`diag`: a diagonal move), `None` when a
    /// count would overflow.
    fn step(self, diag: bool) -> Option<Self>;
    /// `a + b√2` in cells.
    fn value(self) -> f64;
    /// A key ordered exactly as [`value`](Self::value) (equal keys for
    /// equal lengths), cheaper to compare.
    type Key: PartialOrd + Copy;
    /// The key of this length.
    fn key(self) -> Self::Key;
    /// `floor(value)`: the bucket (before the modulo) of this length.
    fn bucket(self) -> usize;
}

/// Fixed-point scale of the [`u32`] label keys: `2^35`.
const KEY_SHIFT: u32 = 35;
/// `round(√2 · 2^35)`.
const KEY_SQRT2: u64 = 48_592_008_000;

/// Counts below 2^16 each: the compact label (4 bytes per cell keeps the
/// distance array of a large map in cache).
impl Label for u32 {
    const ZERO: Self = 0;
    #[inline]
    fn step(self, diag: bool) -> Option<Self> {
        let (mask, inc) = if diag {
            (0xFFFF_0000, 0x1_0000)
        } else {
            (0xFFFF, 1)
        };
        (self & mask != mask).then(|| self + inc)
    }
    #[inline]
    fn value(self) -> f64 {
        f64::from(self & 0xFFFF) + f64::from(self >> 16) * SQRT_2
    }
    /// `a · 2^35 + b · round(√2 · 2^35)` in integers (below 2^53). Exact
    /// order: the rounding error is at most `b / 2 < 2^15` per key, while
    /// two distinct lengths `a + b√2` with counts below 2^16 differ by at
    /// least `1 / |p − q√2| > 5.3e-6` (as `|p² − 2q²| ≥ 1`), i.e. by more
    /// than 1.8e5 key units.
    type Key = u64;
    #[inline]
    fn key(self) -> u64 {
        (u64::from(self & 0xFFFF) << KEY_SHIFT) + u64::from(self >> 16) * KEY_SQRT2
    }
    /// `key >> 35`: the key's error (below 1e-6 cells) is smaller than the
    /// distance of any `b√2` (`0 < b < 2^16`) to an integer (above 5.3e-6),
    /// so this is exactly `floor(a + b√2)`.
    #[inline]
    fn bucket(self) -> usize {
        // Below 2^18.
        #[allow(clippy::cast_possible_truncation)]
        let b = (self.key() >> KEY_SHIFT) as usize;
        b
    }
}

/// Counts below 2^32 each: never overflows, since a shortest path visits
/// distinct cells and a grid holds fewer than 2^32 of them.
impl Label for u64 {
    const ZERO: Self = 0;
    #[inline]
    fn step(self, diag: bool) -> Option<Self> {
        let (mask, inc) = if diag {
            (0xFFFF_FFFF_0000_0000, 1 << 32)
        } else {
            (0xFFFF_FFFF, 1)
        };
        (self & mask != mask).then(|| self + inc)
    }
    #[inline]
    #[allow(clippy::cast_possible_truncation)] // Halves of a u64 fit in u32.
    fn value(self) -> f64 {
        f64::from(self as u32) + f64::from((self >> 32) as u32) * SQRT_2
    }
    /// The `f64` value (exact order, see [`Label`]).
    type Key = f64;
    #[inline]
    fn key(self) -> f64 {
        self.value()
    }
    #[inline]
    fn bucket(self) -> usize {
        // Finite, non-negative, far below usize::MAX.
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let b = self.value() as usize;
        b
    }
}

/// Reusable search buffers (grid-sized; generation stamps avoid clearing).
///
/// The per-cell state is a separate byte array: the most frequent test of a
/// search ("is this neighbour settled already?") then reads a compact array
/// that stays in cache, and the distances are touched only for cells on the
/// wavefront. A byte holds `2g` (reached) or `2g + 1` (settled) for the
/// search generation `g` in 1..=127; the array is cleared once every 127
/// searches. Distances are exact [`Label`]s: 4-byte labels first, and in the
/// rare case a count exceeds 2^16 the search is rerun with 8-byte labels.
#[derive(Debug, Clone, Default)]
pub(crate) struct Scratch {
    dist: Vec<u32>,
    /// Allocated on the first overflow of `dist`.
    wide_dist: Vec<u64>,
    /// Whether the last search used `wide_dist`.
    wide: bool,
    state: Vec<u8>,
    /// Index into [`DIRS`] of the move that reached the cell.
    parent: Vec<u8>,
    generation: u8,
    buckets: [Vec<u32>; NB],
}

impl Scratch {
    fn prepare(&mut self, n: usize) {
        if self.state.len() != n {
            self.dist = vec![0; n];
            self.wide_dist = Vec::new();
            self.state = vec![0; n];
            self.parent = vec![NO_PARENT; n];
            self.generation = 0;
        }
        if self.generation >= 127 {
            self.state.fill(0);
            self.generation = 0;
        }
        self.generation += 1;
        for b in &mut self.buckets {
            b.clear();
        }
    }

    /// Final distance (cells) of dense index `i` after [`dijkstra`], if settled.
    pub(crate) fn settled(&self, i: usize) -> Option<f64> {
        (self.state.get(i) == Some(&(2 * self.generation + 1))).then(|| {
            if self.wide {
                self.wide_dist[i].value()
            } else {
                self.dist[i].value()
            }
        })
    }

    /// Whether the last search left one of `targets` (traversable or not)
    /// unsettled.
    pub(crate) fn missed(&self, targets: &[usize]) -> bool {
        targets.iter().any(|&t| self.settled(t).is_none())
    }

    fn parent(&self, i: usize) -> u8 {
        self.parent[i]
    }
}

/// A label count overflowed; the search must be rerun with wider labels.
struct Overflow;

/// Single- or multi-source Dijkstra over the traversable cells of `grid`.
///
/// Sources that are not traversable are ignored. When `targets` is non-empty,
/// the search stops as soon as all traversable targets are settled. Results
/// are read with [`Scratch::settled`] and [`extract_path`]. Distances are
/// exact (see [`Label`]). Returns the number of cells settled (the
/// search's work).
///
/// Relies on the grid invariant that no traversable cell lies on the outer
/// ring of the allocated area (the grid keeps a margin around every cell an
/// update touches), so neighbour indices never wrap to another row; indices
/// are still bounds-checked.
///
/// # Complexity
/// O(N) for N traversable cells within the distance of the farthest target
/// (bucket queue: O(1) per insertion and removal).
pub(crate) fn dijkstra(
    grid: &OccupancyGrid,
    s: &mut Scratch,
    sources: &[usize],
    targets: &[usize],
) -> usize {
    let n = grid.cell_count();
    s.prepare(n);
    s.wide = false;
    let mut dist = std::mem::take(&mut s.dist);
    let done = search(grid, s, &mut dist, sources, targets);
    s.dist = dist;
    match done {
        Ok(settled) => settled,
        Err(Overflow) => {
            s.prepare(n);
            s.wide = true;
            let mut wide = std::mem::take(&mut s.wide_dist);
            wide.resize(n, 0);
            // Cannot overflow: counts stay below the number of grid cells < 2^32.
            let settled = search(grid, s, &mut wide, sources, targets).unwrap_or(0);
            s.wide_dist = wide;
            settled
        }
    }
}

/// The search of [`dijkstra`] with labels of type `L`.
fn search<L: Label>(
    grid: &OccupancyGrid,
    s: &mut Scratch,
    dist: &mut [L],
    sources: &[usize],
    targets: &[usize],
) -> Result<usize, Overflow> {
    let n = grid.cell_count();
    let g = s.generation;
    let (reached, settled) = (2 * g, 2 * g + 1);
    let trav = grid.trav_layer();
    let w = grid.dims().0 as isize;
    let off: [isize; 8] = [1, -1, w, -w, w + 1, 1 - w, w - 1, -w - 1];
    let Scratch {
        state,
        parent,
        buckets,
        ..
    } = s;
    // Targets are checked in list order at bucket boundaries (each target
    // once when settled, amortised O(1) per bucket), so settling a cell does
    // not need a per-cell target mark.
    let pending: Vec<usize> = targets
        .iter()
        .copied()
        .filter(|&t| t < n && trav[t])
        .collect();
    let stop_early = !pending.is_empty();
    let mut next_target = 0usize;
    let mut queued = 0usize;
    let mut count = 0usize;
    for &src in sources {
        if src < n && trav[src] && state[src] != reached {
            state[src] = reached;
            dist[src] = L::ZERO;
            parent[src] = NO_PARENT;
            buckets[0].push(src as u32);
            queued += 1;
        }
    }
    let wu = w as usize;
    let mut k = 0usize;
    while queued > 0 {
        let b = k % NB;
        if buckets[b].is_empty() {
            k += 1;
            continue;
        }
        let items = std::mem::take(&mut buckets[b]);
        for &iu in &items {
            queued -= 1;
            let i = iu as usize;
            if state[i] == settled {
                continue;
            }
            state[i] = settled;
            count += 1;
            let d = dist[i];
            // The 3 x 3 neighbourhood as three row slices (3 bounds checks
            // instead of 8); traversable cells never touch the grid border.
            let (Some(up), Some(mid), Some(down)) = (
                i.checked_add(wu).and_then(|a| trav.get(a - 1..=a + 1)),
                trav.get(i.wrapping_sub(1)..=i + 1),
                i.checked_sub(wu)
                    .and_then(|a| trav.get(a.wrapping_sub(1)..=a + 1)),
            ) else {
                continue;
            };
            let (e, wst, n, s8) = (mid[2], mid[0], up[1], down[1]);
            let straight = d.step(false).ok_or(Overflow)?;
            let diagonal = d.step(true).ok_or(Overflow)?;
            let (ks, kd) = (straight.key(), diagonal.key());
            let (bs, bd) = (straight.bucket(), diagonal.bucket());
            // Relaxes the move `k8` (index into DIRS) with label `nd`.
            macro_rules! relax {
                ($k8:expr, $nd:expr, $key:expr, $bucket:expr) => {{
                    let j = i.wrapping_add_signed(off[$k8]);
                    let sj = state[j];
                    if sj != settled && (sj != reached || $key < dist[j].key()) {
                        state[j] = reached;
                        dist[j] = $nd;
                        parent[j] = $k8;
                        // Dense indices fit in u32 (see OccupancyGrid::ensure).
                        #[allow(clippy::cast_possible_truncation)]
                        buckets[$bucket % NB].push(j as u32);
                        queued += 1;
                    }
                }};
            }
            if e {
                relax!(0, straight, ks, bs);
            }
            if wst {
                relax!(1, straight, ks, bs);
            }
            if n {
                relax!(2, straight, ks, bs);
            }
            if s8 {
                relax!(3, straight, ks, bs);
            }
            // Diagonals need both straight neighbours (no corner cutting).
            if e && n && up[2] {
                relax!(4, diagonal, kd, bd);
            }
            if e && s8 && down[2] {
                relax!(5, diagonal, kd, bd);
            }
            if wst && n && up[0] {
                relax!(6, diagonal, kd, bd);
            }
            if wst && s8 && down[0] {
                relax!(7, diagonal, kd, bd);
            }
        }
        buckets[b] = items;
        buckets[b].clear();
        k += 1;
        if stop_early {
            while next_target < pending.len() && state[pending[next_target]] == settled {
                next_target += 1;
            }
            if next_target == pending.len() {
                return Ok(count);
            }
        }
    }
    Ok(count)
}

/// A compressed path and the bounding box (min, max) of its cells.
pub(crate) type ExtractedPath = (Vec<Point2<f64>>, (Cell, Cell));

/// Path (compressed to direction changes, in world coordinates) from the
/// search source to the settled dense index `target`, with its cell bounding
/// box. `None` if `target` was not settled.
///
/// # Complexity
/// O(L) for a path of L cells.
pub(crate) fn extract_path(
    grid: &OccupancyGrid,
    s: &Scratch,
    target: usize,
) -> Option<ExtractedPath> {
    s.settled(target)?;
    let mut cell = grid.cell_at(target);
    let (mut lo, mut hi) = (cell, cell);
    let mut rev = vec![cell];
    let mut last_dir = NO_PARENT;
    let mut i = target;
    loop {
        let p = s.parent(i);
        if p == NO_PARENT {
            if *rev.last().unwrap_or(&cell) != cell {
                rev.push(cell);
            }
            break;
        }
        if p != last_dir && last_dir != NO_PARENT {
            rev.push(cell);
        }
        last_dir = p;
        let (dx, dy) = DIRS[p as usize];
        cell = cell.offset(-dx, -dy);
        lo = Cell::new(lo.x.min(cell.x), lo.y.min(cell.y));
        hi = Cell::new(hi.x.max(cell.x), hi.y.max(cell.y));
        i = grid.index(cell)?;
    }
    rev.reverse();
    Some((
        rev.into_iter().map(|c| grid.cell_center(c)).collect(),
        (lo, hi),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{FrontierMap, FrontierMapConfig};
    use nalgebra::Point3;

    /// `sign(x + y√2)` in exact integer arithmetic.
    fn sign_exact(x: i64, y: i64) -> std::cmp::Ordering {
        use std::cmp::Ordering::{Equal, Greater, Less};
        let (x2, y2) = (
            i128::from(x) * i128::from(x),
            2 * i128::from(y) * i128::from(y),
        );
        match (x.signum(), y.signum()) {
            (0, 0) => Equal,
            (sx, sy) if sx >= 0 && sy >= 0 => Greater,
            (sx, sy) if sx <= 0 && sy <= 0 => Less,
            // Opposite signs: the larger magnitude wins.
            (sx, _) if sx > 0 => x2.cmp(&y2),
            _ => y2.cmp(&x2),
        }
    }

    /// Packs `a` straight and `b` diagonal moves.
    fn label(a: u32, b: u32) -> u32 {
        (b << 16) | a
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(4096))]
        /// The integer keys order lengths exactly as `a + b√2` (reference:
        /// exact integer sign test) and give `floor(a + b√2)` as bucket
        /// (reference: `a + isqrt(2b²)`), up to the largest counts.
        #[test]
        fn keys_order_lengths_exactly(
            a in 0u32..0x1_0000, b in 0u32..0x1_0000,
            da in -300i64..300, db in -300i64..300,
            near in proptest::bool::ANY,
        ) {
            // Near-ties come from nearby counts along a convergent of √2.
            let (c, d) = if near {
                (i64::from(a) + da * 577 - db * 816, i64::from(b) - da * 408 + db * 577)
            } else {
                (i64::from(a) + da, i64::from(b) + db)
            };
            let (c, d) = (c.clamp(0, 0xFFFF), d.clamp(0, 0xFFFF));
            #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
            let (x, y) = (label(a, b), label(c as u32, d as u32));
            let want = sign_exact(i64::from(a) - c, i64::from(b) - d);
            proptest::prop_assert_eq!(x.key().partial_cmp(&y.key()), Some(want));
            let isqrt = |v: u64| {
                let mut r = (v as f64).sqrt() as u64;
                while r * r > v { r -= 1; }
                while (r + 1) * (r + 1) <= v { r += 1; }
                r
            };
            let floor = u64::from(a) + isqrt(2 * u64::from(b) * u64::from(b));
            proptest::prop_assert_eq!(x.bucket() as u64, floor);
        }
    }

    #[test]
    fn labels_detect_overflow_and_evaluate_exactly() {
        let a = 0xFFFF_u32; // 65535 straight moves
        assert_eq!(a.step(false), None);
        assert_eq!(a.step(true).map(Label::value), Some(65535.0 + SQRT_2));
        let b = 0xFFFF_0000_u32;
        assert_eq!(b.step(true), None);
        assert_eq!(b.step(false), Some(0xFFFF_0001));
        assert_eq!(u64::from(u32::MAX).step(false), None);
        let w = (7_u64 << 32) | 3;
        assert!((w.value() - (3.0 + 7.0 * SQRT_2)).abs() < 1e-12);
        // A near tie (99 vs 70√2 = 98.9949...) is ordered correctly.
        assert!((70_u32 << 16).value() < 99_u32.value());
    }

    #[test]
    fn compact_and_wide_labels_agree() {
        let mut map = FrontierMap::new(FrontierMapConfig::default()).expect("config");
        let origin = Point3::new(0.0, 0.0, 0.5);
        let points: Vec<_> = (0..360)
            .map(|k| {
                let a = f64::from(k).to_radians();
                let r = if k % 90 < 20 { 3.0 } else { 4.0 };
                Point3::new(r * a.cos(), r * a.sin(), 0.5)
            })
            .collect();
        map.update(&origin, &points).expect("scan");
        let grid = map.grid();
        let src = grid.index(Cell::new(0, 0)).expect("origin cell");
        let n = grid.cell_count();
        let mut s = Scratch::default();
        s.prepare(n);
        let mut compact = vec![0_u32; n];
        assert!(search(grid, &mut s, &mut compact, &[src], &[]).is_ok());
        let narrow: Vec<Option<f64>> = (0..n)
            .map(|i| (s.state[i] == 2 * s.generation + 1).then(|| compact[i].value()))
            .collect();
        s.prepare(n);
        let mut wide = vec![0_u64; n];
        assert!(search(grid, &mut s, &mut wide, &[src], &[]).is_ok());
        let wide: Vec<Option<f64>> = (0..n)
            .map(|i| (s.state[i] == 2 * s.generation + 1).then(|| wide[i].value()))
            .collect();
        assert!(narrow.iter().filter(|d| d.is_some()).count() > 1000);
        assert_eq!(narrow, wide);
    }
}
