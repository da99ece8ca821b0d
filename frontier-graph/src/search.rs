//! Exact shortest paths on the traversable grid: 8-connected, octile costs,
//! no corner cutting; Dijkstra over jump points in the canonical order of
//! grid paths, straight runs labelled by scans.

use nalgebra::Point2;
use std::cmp::Reverse;
use std::collections::BinaryHeap;
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

/// An exact path length `a + b√2` (a straight and b diagonal moves), packed
/// into an unsigned integer: the straight count in the low half, the
/// diagonal count in the high half.
///
/// Comparisons go through [`Label::key_bits`], an integer ordered exactly as
/// the length (equal lengths have equal keys: no accumulated rounding).
trait Label: Copy {
    /// Length 0.
    const ZERO: Self;
    /// The label one move further (`diag`: a diagonal move), `None` when a
    /// count would overflow.
    fn step(self, diag: bool) -> Option<Self>;
    /// `a + b√2` in cells.
    fn value(self) -> f64;
    /// A key ordered exactly as [`value`](Self::value), equal for equal
    /// lengths.
    fn key_bits(self) -> u64;
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
    #[inline]
    fn key_bits(self) -> u64 {
        (u64::from(self & 0xFFFF) << KEY_SHIFT) + u64::from(self >> 16) * KEY_SQRT2
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
    /// The bits of the `f64` value: non-negative floats order as their
    /// bits. Distinct lengths differ by at least `1 / (2√2 · max(a, b))`,
    /// above the evaluation error while the counts stay below about 2^24
    /// (paths of 16 M cells, far beyond any map this crate builds).
    #[inline]
    fn key_bits(self) -> u64 {
        self.value().to_bits()
    }
}

/// One cell of a search: label, generation stamp and parent move, side by
/// side (a scan touches one cache line per cell, also along columns).
#[derive(Debug, Clone, Copy, Default)]
#[repr(C)]
struct Rec<L> {
    /// The label, valid when `generation` is the search's.
    d: L,
    /// The search generation that wrote this cell (0: none).
    generation: u8,
    /// Index into [`DIRS`] of the move that reached the cell.
    parent: u8,
}

/// Reusable search buffers (grid-sized; generation stamps avoid clearing).
///
/// Each cell holds the search generation `g` (1..=255) when it has a label
/// in the current search; the stamps are cleared once every 255 searches.
/// Distances are exact [`Label`]s: 4-byte labels first, and in the rare
/// case a count exceeds 2^16 the search is rerun with 8-byte labels.
#[derive(Debug, Clone, Default)]
pub(crate) struct Scratch {
    cells: Vec<Rec<u32>>,
    /// Allocated on the first overflow of `cells`.
    wide_cells: Vec<Rec<u64>>,
    /// Whether the last search used `wide_cells`.
    wide: bool,
    generation: u8,
    /// Jump points: `(key bits of the label, dense index, directions)`.
    heap: BinaryHeap<Reverse<(u64, u32, u8)>>,
    /// Labels with key bits up to this are final (see [`search`]).
    final_bits: u64,
}

impl Scratch {
    fn prepare(&mut self, n: usize, wide: bool) {
        if self.cells.len() != n {
            self.cells = vec![Rec::default(); n];
            self.wide_cells = Vec::new();
            self.generation = 0;
        }
        if wide && self.wide_cells.len() != n {
            self.wide_cells = vec![Rec::default(); n];
        }
        if self.generation == u8::MAX {
            self.cells.iter_mut().for_each(|r| r.generation = 0);
            self.wide_cells.iter_mut().for_each(|r| r.generation = 0);
            self.generation = 0;
        }
        self.generation += 1;
        self.wide = wide;
        self.heap.clear();
        self.final_bits = 0;
    }

    /// Final distance (cells) of dense index `i` after [`dijkstra`], if the
    /// search proved it.
    pub(crate) fn settled(&self, i: usize) -> Option<f64> {
        fn get<L: Label>(cells: &[Rec<L>], i: usize, g: u8, bits: u64) -> Option<f64> {
            let r = cells.get(i)?;
            (r.generation == g && r.d.key_bits() <= bits).then(|| r.d.value())
        }
        if self.wide {
            get(&self.wide_cells, i, self.generation, self.final_bits)
        } else {
            get(&self.cells, i, self.generation, self.final_bits)
        }
    }

    /// Whether the last search left one of `targets` (traversable or not)
    /// unsettled.
    pub(crate) fn missed(&self, targets: &[usize]) -> bool {
        targets.iter().any(|&t| self.settled(t).is_none())
    }

    fn parent(&self, i: usize) -> u8 {
        if self.wide {
            self.wide_cells[i].parent
        } else {
            self.cells[i].parent
        }
    }
}

/// A label count overflowed; the search must be rerun with wider labels.
struct Overflow;

/// Single- or multi-source exact shortest paths over the traversable cells
/// of `grid`.
///
/// Sources that are not traversable are ignored. When `targets` is non-empty,
/// the search stops as soon as all traversable targets are proven final.
/// Results are read with [`Scratch::settled`] and [`extract_path`]. Distances
/// are exact (see [`Label`]). Returns the number of cell visits (the
/// search's work).
///
/// # Complexity
/// O(N + J log J) for N traversable cells within the distance of the
/// farthest target and J jump points (see [`search`]); each cell is visited
/// by a few scans at most in practice.
pub(crate) fn dijkstra(
    grid: &OccupancyGrid,
    s: &mut Scratch,
    sources: &[usize],
    targets: &[usize],
) -> usize {
    layer_dijkstra(grid.trav_layer(), grid.dims().0, s, sources, targets)
}

/// [`dijkstra`] over a row-major traversability layer of `width` columns.
/// Cells outside the layer read as blocked.
fn layer_dijkstra(
    trav: &[bool],
    width: usize,
    s: &mut Scratch,
    sources: &[usize],
    targets: &[usize],
) -> usize {
    let n = trav.len();
    s.prepare(n, false);
    let mut cells = std::mem::take(&mut s.cells);
    let done = search(trav, width, s, &mut cells, sources, targets);
    s.cells = cells;
    match done {
        Ok(visits) => visits,
        Err(Overflow) => {
            s.prepare(n, true);
            let mut wide = std::mem::take(&mut s.wide_cells);
            // Cannot overflow: counts stay below the number of grid cells < 2^32.
            let visits = search(trav, width, s, &mut wide, sources, targets).unwrap_or(0);
            s.wide_cells = wide;
            visits
        }
    }
}

/// Direction bits (`1 << k` for the move `DIRS[k]`).
const ALL_DIRS: u8 = 0xFF;
/// For each straight move (index into [`DIRS`]): its two side moves, each
/// with the diagonal between the move and that side.
const SIDES: [[(usize, usize); 2]; 4] = [
    [(2, 4), (3, 5)], // east: north / north-east, south / south-east
    [(2, 6), (3, 7)], // west: north / north-west, south / south-west
    [(0, 4), (1, 6)], // north: east / north-east, west / north-west
    [(0, 5), (1, 7)], // south: east / south-east, west / south-west
];
/// For each diagonal move (index into [`DIRS`] minus 4): its two straight
/// components.
const COMPONENTS: [(usize, usize); 4] = [(0, 2), (0, 3), (1, 2), (1, 3)];

/// The state of one [`search`].
struct Canonical<'a, L: Label> {
    trav: &'a [bool],
    cells: &'a mut [Rec<L>],
    heap: &'a mut BinaryHeap<Reverse<(u64, u32, u8)>>,
    generation: u8,
    off: [isize; 8],
    visits: usize,
}

/// Whether a scan goes on after [`Canonical::visit`].
#[derive(PartialEq, Eq)]
enum Visit {
    Go,
    Stop,
}

impl<L: Label> Canonical<'_, L> {
    /// The neighbour of `i` by move `k`, if traversable (out of range reads
    /// as blocked).
    #[inline(always)]
    fn free(&self, i: usize, k: usize) -> Option<usize> {
        let j = i.wrapping_add_signed(self.off[k]);
        self.trav.get(j).copied().unwrap_or(false).then_some(j)
    }

    #[inline(always)]
    fn blocked(&self, i: usize, k: usize) -> bool {
        self.free(i, k).is_none()
    }

    /// Offers label `lab` reached by move `k` to cell `j`: written when
    /// strictly better. A scan stops where its label is strictly worse (the
    /// better label's continuation dominates it) or ties with a label
    /// reached by the same move (whose scan continues the same way).
    #[inline(always)]
    fn visit(&mut self, j: usize, lab: L, k: usize) -> Visit {
        self.visits += 1;
        let r = &mut self.cells[j];
        if r.generation == self.generation {
            let (old, new) = (r.d.key_bits(), lab.key_bits());
            if new > old || (new == old && usize::from(r.parent) == k) {
                return Visit::Stop;
            }
            if new == old {
                return Visit::Go;
            }
        }
        #[allow(clippy::cast_possible_truncation)] // k < 8.
        {
            *r = Rec {
                d: lab,
                generation: self.generation,
                parent: k as u8,
            };
        }
        Visit::Go
    }

    /// Queues jump point `j` with label `lab`, to be expanded along `dirs`.
    #[inline]
    fn jump_point(&mut self, j: usize, lab: L, dirs: u8) {
        // Dense indices fit in u32 (see OccupancyGrid::ensure).
        #[allow(clippy::cast_possible_truncation)]
        self.heap.push(Reverse((lab.key_bits(), j as u32, dirs)));
    }

    /// Straight scan from `i` (label `lab`) along move `k` (< 4) until
    /// blocked or dominated; cells where an obstacle beside the scan ends
    /// become jump points (their side and diagonal moves were cut off
    /// before).
    fn scan(&mut self, mut i: usize, mut lab: L, k: usize) -> Result<(), Overflow> {
        let [(s0, d0), (s1, d1)] = SIDES[k];
        // Whether the side cells of the previous cell were blocked.
        let (mut b0, mut b1) = (self.blocked(i, s0), self.blocked(i, s1));
        while let Some(j) = self.free(i, k) {
            lab = lab.step(false).ok_or(Overflow)?;
            if self.visit(j, lab, k) == Visit::Stop {
                break;
            }
            let (f0, f1) = (self.free(j, s0).is_some(), self.free(j, s1).is_some());
            if (b0 && f0) || (b1 && f1) {
                let mut forced = 0u8;
                if b0 && f0 {
                    forced |= (1 << s0) | (1 << d0);
                }
                if b1 && f1 {
                    forced |= (1 << s1) | (1 << d1);
                }
                self.jump_point(j, lab, forced);
            }
            (b0, b1) = (!f0, !f1);
            i = j;
        }
        Ok(())
    }

    /// Diagonal walk from `i` along move `k` (>= 4), with a straight scan
    /// along both components from every cell reached (diagonal moves first,
    /// then straight ones: the canonical order of 8-connected paths).
    fn walk(&mut self, mut i: usize, mut lab: L, k: usize) -> Result<(), Overflow> {
        let (a, b) = COMPONENTS[k - 4];
        loop {
            // No corner cutting: both straight neighbours must be free.
            let (Some(_), Some(_), Some(j)) = (self.free(i, a), self.free(i, b), self.free(i, k))
            else {
                return Ok(());
            };
            lab = lab.step(true).ok_or(Overflow)?;
            if self.visit(j, lab, k) == Visit::Stop {
                return Ok(());
            }
            self.scan(j, lab, a)?;
            self.scan(j, lab, b)?;
            i = j;
        }
    }

    /// Scans and walks from jump point `i` along the moves in `dirs`.
    fn expand(&mut self, i: usize, lab: L, dirs: u8) -> Result<(), Overflow> {
        for k in 0..4 {
            if dirs & (1 << k) != 0 {
                self.scan(i, lab, k)?;
            }
        }
        for k in 4..8 {
            if dirs & (1 << k) != 0 {
                self.walk(i, lab, k)?;
            }
        }
        Ok(())
    }
}

/// The search of [`dijkstra`] with labels of type `L`: Dijkstra over *jump
/// points* in the canonical ordering of grid paths (diagonal moves before
/// straight ones between turns), in the manner of canonical Dijkstra
/// (Sturtevant and Rabin, 2016) for moves without corner cutting.
///
/// A jump point (a source, or a cell where an obstacle beside a straight
/// scan ends) is expanded by straight scans and diagonal walks, each
/// diagonal cell sending straight scans along the walk's two components;
/// scans label cells on the way without queueing them. Without corner
/// cutting, diagonal moves have no forced neighbours, so every cell has a
/// shortest path that turns only at jump points or from a diagonal run into
/// one of its components; the scans carrying such a path are never cut
/// (their labels are optimal), and jump points are expanded in order of
/// their labels, so every label is exact once no queued jump point is
/// below it. The search stops when every traversable target has a label no
/// larger than the smallest queued jump point.
fn search<L: Label>(
    trav: &[bool],
    width: usize,
    s: &mut Scratch,
    cells: &mut [Rec<L>],
    sources: &[usize],
    targets: &[usize],
) -> Result<usize, Overflow> {
    let n = trav.len();
    // Widths are below 2^16 (see OccupancyGrid::ensure).
    #[allow(clippy::cast_possible_wrap)]
    let w = width as isize;
    let generation = s.generation;
    let Scratch {
        heap, final_bits, ..
    } = s;
    let mut c = Canonical {
        trav,
        cells,
        heap,
        generation,
        off: [1, -1, w, -w, w + 1, 1 - w, w - 1, -w - 1],
        visits: 0,
    };
    let pending: Vec<usize> = targets
        .iter()
        .copied()
        .filter(|&t| t < n && c.trav[t])
        .collect();
    for &src in sources {
        if src < n && c.trav[src] && c.cells[src].generation != generation {
            c.cells[src] = Rec {
                d: L::ZERO,
                generation,
                parent: NO_PARENT,
            };
            c.jump_point(src, L::ZERO, ALL_DIRS);
        }
    }
    // Targets are checked in list order (each once when labelled), then by
    // an upper bound on their labels, tightened every few expansions
    // (labels only decrease, so a stale bound is still an upper bound).
    let mut next_target = 0usize;
    let mut bound: Option<u64> = None;
    let mut pops = 0usize;
    let stop_early = !pending.is_empty();
    *final_bits = u64::MAX;
    while let Some(Reverse((key, iu, dirs))) = c.heap.pop() {
        let i = iu as usize;
        if stop_early {
            while next_target < pending.len()
                && c.cells[pending[next_target]].generation == generation
            {
                next_target += 1;
            }
            if next_target == pending.len() {
                pops += 1;
                if bound.is_none() || pops.is_multiple_of(64) {
                    bound = pending.iter().map(|&t| c.cells[t].d.key_bits()).max();
                }
                if bound.is_some_and(|b| b <= key) {
                    *final_bits = key;
                    return Ok(c.visits);
                }
            }
        }
        let lab = c.cells[i].d;
        if lab.key_bits() < key {
            // Reached more cheaply since it was queued.
            continue;
        }
        c.expand(i, lab, dirs)?;
    }
    Ok(c.visits)
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
        /// exact integer sign test) and carry `floor(a + b√2)` in their integer part
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
            proptest::prop_assert_eq!(x.key_bits().partial_cmp(&y.key_bits()), Some(want));
            let isqrt = |v: u64| {
                let mut r = (v as f64).sqrt() as u64;
                while r * r > v { r -= 1; }
                while (r + 1) * (r + 1) <= v { r += 1; }
                r
            };
            let floor = u64::from(a) + isqrt(2 * u64::from(b) * u64::from(b));
            proptest::prop_assert_eq!(x.key_bits() >> KEY_SHIFT, floor);
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
        s.prepare(n, false);
        let mut compact = vec![Rec::<u32>::default(); n];
        let (trav, width) = (grid.trav_layer(), grid.dims().0);
        assert!(search(trav, width, &mut s, &mut compact, &[src], &[]).is_ok());
        let narrow: Vec<Option<f64>> = (0..n)
            .map(|i| (compact[i].generation == s.generation).then(|| compact[i].d.value()))
            .collect();
        s.prepare(n, true);
        let mut wide = vec![Rec::<u64>::default(); n];
        assert!(search(trav, width, &mut s, &mut wide, &[src], &[]).is_ok());
        let wide: Vec<Option<f64>> = (0..n)
            .map(|i| (wide[i].generation == s.generation).then(|| wide[i].d.value()))
            .collect();
        assert!(narrow.iter().filter(|d| d.is_some()).count() > 1000);
        assert_eq!(narrow, wide);
    }

    /// Textbook Dijkstra on a layer (binary heap over exact `(a, b)` move
    /// counts compared by the exact integer sign test): the reference.
    fn reference(trav: &[bool], width: usize, sources: &[usize]) -> Vec<Option<(i64, i64)>> {
        #[derive(PartialEq, Eq)]
        struct Item(i64, i64, usize);
        impl Ord for Item {
            fn cmp(&self, o: &Self) -> std::cmp::Ordering {
                // Min-heap on a + b√2.
                sign_exact(o.0 - self.0, o.1 - self.1).then(o.2.cmp(&self.2))
            }
        }
        impl PartialOrd for Item {
            fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
                Some(self.cmp(o))
            }
        }
        let free = |x: i64, y: i64| {
            x >= 0
                && y >= 0
                && (x as usize) < width
                && trav.get(y as usize * width + x as usize) == Some(&true)
        };
        let mut best: Vec<Option<(i64, i64)>> = vec![None; trav.len()];
        let mut heap = BinaryHeap::new();
        for &s in sources {
            if trav.get(s) == Some(&true) {
                best[s] = Some((0, 0));
                heap.push(Item(0, 0, s));
            }
        }
        while let Some(Item(a, b, i)) = heap.pop() {
            if best[i] != Some((a, b)) {
                continue;
            }
            let (x, y) = ((i % width) as i64, (i / width) as i64);
            for (dx, dy) in DIRS {
                let (dx, dy) = (i64::from(dx), i64::from(dy));
                let diag = dx != 0 && dy != 0;
                if !free(x + dx, y + dy) || (diag && !(free(x + dx, y) && free(x, y + dy))) {
                    continue;
                }
                let j = (y + dy) as usize * width + (x + dx) as usize;
                let (na, nb) = if diag { (a, b + 1) } else { (a + 1, b) };
                let better = best[j].is_none_or(|(oa, ob)| {
                    sign_exact(na - oa, nb - ob) == std::cmp::Ordering::Less
                });
                if better {
                    best[j] = Some((na, nb));
                    heap.push(Item(na, nb, j));
                }
            }
        }
        best
    }

    /// A random layer: free cells with probability `density`, obstacles as
    /// random rectangles and single cells, the outer ring blocked.
    fn layer_strategy() -> impl proptest::strategy::Strategy<Value = (Vec<bool>, usize)> {
        use proptest::prelude::*;
        (
            4usize..40,
            4usize..40,
            0.0f64..0.45,
            0usize..12,
            any::<u64>(),
        )
            .prop_map(|(w, h, noise, rects, seed)| {
                let mut rng = seed;
                let mut next = move || {
                    rng ^= rng << 13;
                    rng ^= rng >> 7;
                    rng ^= rng << 17;
                    rng
                };
                let mut trav = vec![true; w * h];
                for _ in 0..rects {
                    let (x0, y0) = ((next() as usize) % w, (next() as usize) % h);
                    let (rw, rh) = (1 + (next() as usize) % 8, 1 + (next() as usize) % 8);
                    for y in y0..(y0 + rh).min(h) {
                        for x in x0..(x0 + rw).min(w) {
                            trav[y * w + x] = false;
                        }
                    }
                }
                for (i, t) in trav.iter_mut().enumerate() {
                    let (x, y) = (i % w, i / w);
                    #[allow(clippy::cast_precision_loss)]
                    let u = (next() % 1_000_000) as f64 / 1e6;
                    if x == 0 || y == 0 || x + 1 == w || y + 1 == h || u < noise {
                        *t = false;
                    }
                }
                (trav, w)
            })
    }

    fn value(ab: (i64, i64)) -> f64 {
        #[allow(clippy::cast_precision_loss)]
        let v = ab.0 as f64 + ab.1 as f64 * SQRT_2;
        v
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(2000))]
        #[allow(clippy::needless_range_loop)] // Cells are indexed in several arrays.
        /// Every label of a full search, and the targets' labels of an
        /// early-terminated one, equal textbook Dijkstra's exactly; paths
        /// follow legal moves and have the label's length.
        #[test]
        fn labels_match_reference_dijkstra(
            (trav, width) in layer_strategy(),
            picks in proptest::collection::vec(proptest::prelude::any::<usize>(), 1..8),
            nsrc in 1usize..3,
        ) {
            let n = trav.len();
            let free: Vec<usize> = (0..n).filter(|&i| trav[i]).collect();
            proptest::prop_assume!(!free.is_empty());
            let pick: Vec<usize> = picks.iter().map(|p| free[p % free.len()]).collect();
            let sources = &pick[..nsrc.min(pick.len())];
            let targets = &pick[nsrc.min(pick.len())..];
            let want = reference(&trav, width, sources);
            let mut s = Scratch::default();
            layer_dijkstra(&trav, width, &mut s, sources, &[]);
            for i in 0..n {
                let got = s.settled(i);
                proptest::prop_assert_eq!(got.is_some(), want[i].is_some(), "cell {}", i);
                if let (Some(g), Some(w)) = (got, want[i]) {
                    proptest::prop_assert_eq!(g, value(w), "cell {}", i);
                    // The parent chain is a legal path of exactly this length.
                    let (mut a, mut b, mut j) = (0i64, 0i64, i);
                    while s.parent(j) != NO_PARENT {
                        let (dx, dy) = DIRS[s.parent(j) as usize];
                        let diag = dx != 0 && dy != 0;
                        if diag { b += 1 } else { a += 1 }
                        let (x, y) = ((j % width) as i64 - i64::from(dx), (j / width) as i64 - i64::from(dy));
                        let p = y as usize * width + x as usize;
                        proptest::prop_assert!(trav[p]);
                        if diag {
                            proptest::prop_assert!(trav[y as usize * width + (j % width)]);
                            proptest::prop_assert!(trav[(j / width) * width + x as usize]);
                        }
                        j = p;
                    }
                    proptest::prop_assert!(sources.contains(&j));
                    proptest::prop_assert_eq!((a, b), w, "path of cell {}", i);
                }
            }
            // Early termination: targets exact, no non-final label reported.
            layer_dijkstra(&trav, width, &mut s, sources, targets);
            for &t in targets {
                proptest::prop_assert_eq!(s.settled(t), want[t].map(value));
            }
            for i in 0..n {
                if let Some(g) = s.settled(i) {
                    proptest::prop_assert_eq!(Some(g), want[i].map(value), "cell {}", i);
                }
            }
        }
    }
}
