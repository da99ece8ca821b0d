//! Iterated local search (ILS) for closed ATSP tours on a dense matrix.
//!
//! The tour lives in an array with a position index and prefix sums of the
//! forward and backward arc costs along it, so that the cost of traversing
//! any stretch of the tour *reversed* is available in `O(1)`: segment
//! reversal (2-opt) is evaluated exactly on asymmetric costs.
//!
//! Neighbourhoods (all restricted to `k` nearest-successor and
//! nearest-predecessor candidate lists, first improvement, driven by a
//! work queue of "dirty" nodes, i.e. don't-look bits):
//! * **2-opt**: remove `(a, b)`, `(d, e)`, add `(a, d)`, `(b, e)` and
//!   reverse `b..d` (Croes 1958);
//! * **Or-opt**: move a segment of 1-3 nodes elsewhere, optionally reversed
//!   (Or 1976); on symmetric costs one scan per segment end covers both
//!   orientations (a neighbour `w` of the end is tried on both of its
//!   sides);
//! * **or-3opt**: the orientation-preserving pure 3-opt move ("segment
//!   exchange", `a -> b'..c -> a'..b -> c'`), which needs no reversal and is
//!   the workhorse on strongly asymmetric instances.
//!
//! Perturbation: a random double bridge (Martin, Otto & Felten 1991): three
//! adjacent stretches of at most 30 nodes are reordered `P Q R -> R Q P`,
//! which replaces four arcs and keeps orientation, followed by local search
//! from the eight touched nodes only. (An exchange of two stretches, three
//! arcs, is itself an or-3opt move, and the local search undid it about
//! 40 % of the time; with the double bridge, about 40 % fewer kicks reach
//! the same quality on the FUEL instances, each costing about 1.4 times
//! more.) A kicked tour replaces the current one when it is no worse
//! (plateau moves are allowed), otherwise the move log is rolled back. After
//! `m / 2` kicks without improving the current tour, five kicks are applied
//! in a row and kept whatever they cost, to leave the basin (a restart close
//! to the incumbent); the best tour ever seen is returned. Without this
//! escape the search stalled for good on some asymmetric instances
//! (kro124p, measured with the earlier two-stretch kick: 1.9 % above the
//! optimum with any kick budget).
//!
//! Moves are applied in place on the array (the shorter side is rewritten)
//! and logged, so rejecting a kick costs only what it changed.

use std::collections::VecDeque;
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Parameters of one ILS run.
#[derive(Debug, Clone, Copy)]
pub(crate) struct IlsParams {
    pub candidates: usize,
    pub kicks: usize,
    pub deadline: Option<Instant>,
    pub seed: u64,
    /// Magnitude of the meaningful costs, when the matrix holds larger
    /// artificial ones (the penalty of the symmetric form): moves must gain
    /// more than `1e-9` of it. `None`: the largest entry.
    pub cost_scale: Option<f64>,
}

/// Longest stretch moved by a kick.
const KICK_MAX_SEGMENT: usize = 30;

/// Kicks applied in a row (and kept) to leave a basin after stagnation.
const ESCAPE_KICKS: usize = 5;

/// At most this many nodes may cover all asymmetric pairs for the cheap
/// reversal pricing; beyond it, prefix sums are maintained.
const MAX_COVER: usize = 4;

/// How the cost change of reversing a stretch is priced.
#[derive(Clone)]
enum Asymmetry {
    /// Symmetric costs: reversal is free (and the shorter side is reversed).
    None,
    /// Every pair with `c(x, y) != c(y, x)` touches one of these nodes (the
    /// open-path reduction gives just the start).
    Cover(Vec<u32>),
    /// Dense asymmetry: prefix sums of `c(y, x) - c(x, y)` along the tour,
    /// rebuilt after every move.
    Prefix(Vec<f64>),
}

/// The Or-opt segments tried around a node, in order: `(length, whether
/// it starts at the node)` (a one-node segment both starts and ends there).
const OR_SEGMENTS: [(usize, bool); 5] = [(1, true), (2, true), (2, false), (3, true), (3, false)];

/// A segment of the tour taken out by an Or-opt move.
#[derive(Clone, Copy)]
struct OrSegment {
    /// Position of its first node.
    ps: usize,
    /// Number of nodes (1 to 3).
    len: usize,
    /// Its first node.
    s1: u32,
    /// Its last node.
    sl: u32,
    /// The node before it.
    p: u32,
    /// The node after it.
    nx: u32,
    /// `c(p, s1) + c(sl, nx) - c(p, nx)`: what taking it out saves.
    gain: f64,
}

#[derive(Clone)]
struct State<'a> {
    c: &'a [f64],
    m: usize,
    k: usize,
    out_c: Vec<u32>,
    in_c: Vec<u32>,
    /// `c(i, out_c[i k + t])`, cached next to the lists.
    out_cost: Vec<f64>,
    /// `c(in_c[i k + t], i)`.
    in_cost: Vec<f64>,
    tour: Vec<u32>,
    pos: Vec<u32>,
    asym: Asymmetry,
    in_cover: Vec<bool>,
    cost: f64,
    /// `(position, previous node)` writes since the last checkpoint.
    undo: Vec<(u32, u32)>,
    queue: VecDeque<u32>,
    queued: Vec<bool>,
    scratch: Vec<u32>,
    eps: f64,
    /// Largest `|c(i, j)|` off the diagonal (at least 1): the scale of the
    /// rounding in tracked costs (each move's delta is a sum of arc costs,
    /// so a delta near a large arc's magnitude loses the small arcs' digits).
    max_abs: f64,
}

impl<'a> State<'a> {
    fn new(
        c: &'a [f64],
        m: usize,
        candidates: usize,
        initial: &[usize],
        cost_scale: Option<f64>,
    ) -> Self {
        let k = candidates.clamp(1, m - 1);
        let (asym, in_cover) = asymmetry_cover(c, m);
        // On symmetric costs the predecessor lists equal the successor lists.
        let directions: &[bool] = if matches!(asym, Asymmetry::None) {
            &[true]
        } else {
            &[true, false]
        };
        let mut out_c = Vec::with_capacity(m * k);
        let mut in_c = Vec::with_capacity(m * k);
        let mut idx: Vec<(f64, u32)> = Vec::with_capacity(m);
        let mut max_abs = 1.0_f64;
        let cmp = |x: &(f64, u32), y: &(f64, u32)| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1));
        for i in 0..m {
            // The k cheapest successors, then the k cheapest predecessors
            // (ties by index), each by selection then a sort of k entries.
            for &out in directions {
                let list = if out { &mut out_c } else { &mut in_c };
                idx.clear();
                idx.extend((0..m).filter(|&j| j != i).map(|j| {
                    let v = if out { c[i * m + j] } else { c[j * m + i] };
                    (v, j as u32)
                }));
                if k < idx.len() {
                    idx.select_nth_unstable_by(k - 1, cmp);
                }
                idx[..k].sort_unstable_by(cmp);
                list.extend(idx[..k].iter().map(|e| e.1));
            }
            for j in 0..m {
                if j != i {
                    max_abs = max_abs.max(c[i * m + j].abs());
                }
            }
        }
        if directions.len() == 1 {
            in_c.clone_from(&out_c);
        }
        let out_cost = (0..m * k)
            .map(|t| c[(t / k) * m + out_c[t] as usize])
            .collect();
        let in_cost = (0..m * k)
            .map(|t| c[in_c[t] as usize * m + t / k])
            .collect();
        let mut st = Self {
            c,
            m,
            k,
            out_c,
            in_c,
            out_cost,
            in_cost,
            tour: initial.iter().map(|&v| v as u32).collect(),
            pos: vec![0; m],
            asym,
            in_cover,
            cost: 0.0,
            undo: Vec::new(),
            queue: VecDeque::with_capacity(m),
            queued: vec![false; m],
            scratch: Vec::with_capacity(m),
            eps: 1e-9 * cost_scale.map_or(max_abs, |s| s.max(1.0)),
            max_abs,
        };
        for (p, &v) in st.tour.iter().enumerate() {
            st.pos[v as usize] = p as u32;
        }
        st.cost = (0..m)
            .map(|t| st.cost(st.tour[t], st.tour[(t + 1) % m]))
            .sum();
        st.rebuild_prefix();
        st
    }

    /// Tour cost summed from scratch.
    fn recomputed_cost(&self) -> f64 {
        tour_cost(self.c, self.m, &self.tour)
    }

    #[inline]
    fn cost(&self, i: u32, j: u32) -> f64 {
        self.c[i as usize * self.m + j as usize]
    }

    /// Node at position `p` (`p < 2m`).
    #[inline]
    fn at(&self, p: usize) -> u32 {
        self.tour[self.wrap(p)]
    }

    /// `p mod m` for `p < 2m`.
    #[inline]
    fn wrap(&self, p: usize) -> usize {
        if p >= self.m { p - self.m } else { p }
    }

    #[inline]
    fn p(&self, x: u32) -> usize {
        self.pos[x as usize] as usize
    }

    #[inline]
    fn succ(&self, x: u32) -> u32 {
        self.at(self.p(x) + 1)
    }

    #[inline]
    fn pred(&self, x: u32) -> u32 {
        self.at(self.p(x) + self.m - 1)
    }

    /// Offset of `x` after `a` along the tour (`0` for `a` itself).
    #[inline]
    fn rel(&self, a: u32, x: u32) -> usize {
        self.wrap(self.p(x) + self.m - self.p(a))
    }

    /// Number of positions in the cyclic stretch `p..=q`.
    #[inline]
    fn span(&self, p: usize, q: usize) -> usize {
        self.wrap(q + self.m - p) + 1
    }

    /// Change of cost when the stretch of positions `p..=q` is traversed
    /// backwards: `sum c(y, x) - c(x, y)` over its internal arcs `(x, y)`.
    fn reversal_delta(&self, p: usize, q: usize) -> f64 {
        match &self.asym {
            Asymmetry::None => 0.0,
            Asymmetry::Prefix(d) => {
                if p <= q {
                    d[q] - d[p]
                } else {
                    d[self.m] - d[p] + d[q]
                }
            }
            Asymmetry::Cover(cover) => {
                let len = self.span(p, q);
                let mut sum = 0.0;
                for &v in cover {
                    let r = self.wrap(self.p(v) + self.m - p);
                    if r >= len {
                        continue;
                    }
                    if r + 1 < len {
                        let s = self.succ(v);
                        sum += self.cost(s, v) - self.cost(v, s);
                    }
                    let pr = self.pred(v);
                    if r > 0 && !self.in_cover[pr as usize] {
                        sum += self.cost(v, pr) - self.cost(pr, v);
                    }
                }
                sum
            }
        }
    }

    fn rebuild_prefix(&mut self) {
        let m = self.m;
        if let Asymmetry::Prefix(d) = &mut self.asym {
            for t in 0..m {
                let (x, y) = (self.tour[t] as usize, self.tour[(t + 1) % m] as usize);
                d[t + 1] = d[t] + self.c[y * m + x] - self.c[x * m + y];
            }
        }
    }

    fn push(&mut self, x: u32) {
        if !self.queued[x as usize] {
            self.queued[x as usize] = true;
            self.queue.push_back(x);
        }
    }

    #[inline]
    fn set(&mut self, p: usize, v: u32) {
        self.undo.push((p as u32, self.tour[p]));
        self.tour[p] = v;
        self.pos[v as usize] = p as u32;
    }

    /// Reverses the cyclic stretch `p..=q` in place.
    fn reverse(&mut self, p: usize, q: usize) {
        let m = self.m;
        let len = self.span(p, q);
        for t in 0..len / 2 {
            let (i, j) = (self.wrap(p + t), self.wrap(q + m - t));
            let (vi, vj) = (self.tour[i], self.tour[j]);
            self.set(i, vj);
            self.set(j, vi);
        }
    }

    /// Turns the cyclic sequence `X Y Z` (`X` = `lx` positions from `p`,
    /// `Y` the next `ly`, `Z` the rest) into `Y X Z`, by swapping whichever
    /// two cyclically adjacent pieces are shortest (all three swaps give the
    /// same cyclic order).
    fn exchange(&mut self, p: usize, lx: usize, ly: usize) {
        let m = self.m;
        let lz = m - lx - ly;
        let (start, la, lb) = if lz >= lx && lz >= ly {
            (p, lx, ly)
        } else if lx >= ly {
            (p + lx, ly, lz)
        } else {
            (p + lx + ly, lz, lx)
        };
        let start = start % m;
        self.scratch.clear();
        for t in 0..la + lb {
            self.scratch.push(self.at(start + t));
        }
        for t in 0..lb {
            let v = self.scratch[la + t];
            self.set(self.wrap(start + t), v);
        }
        for t in 0..la {
            let v = self.scratch[t];
            self.set(self.wrap(start + lb + t), v);
        }
    }

    fn finish_move(&mut self, delta: f64, touched: &[u32]) {
        self.cost += delta;
        self.rebuild_prefix();
        // The tracked cost carries the rounding of every applied delta, of
        // the order of an ulp of the largest arc per move (costs above ~1e16
        // next to small ones lose the small ones' digits): the tolerance is
        // relative to the tour cost and to the matrix's scale.
        debug_assert!(
            (self.cost - self.recomputed_cost()).abs()
                <= 1e-6 * self.cost.abs().max(1.0) + 1e-9 * self.max_abs,
            "tracked {} vs actual {} {:?}",
            self.cost,
            self.recomputed_cost(),
            self.tour
        );
        for &x in touched {
            self.push(x);
        }
    }

    /// The Or-opt segment of `len` nodes that starts (`starts_at_px`) or
    /// ends at position `px`, when taking it out of the tour gains more than
    /// `eps` (`len + 3 <= m`).
    #[inline(always)]
    fn or_segment(&self, px: usize, len: usize, starts_at_px: bool) -> Option<OrSegment> {
        let m = self.m;
        let ps = if starts_at_px {
            px
        } else {
            self.wrap(px + m - (len - 1))
        };
        let pe = self.wrap(ps + len - 1);
        let (s1, sl) = (self.tour[ps], self.tour[pe]);
        let (p, nx) = (self.at(ps + m - 1), self.at(pe + 1));
        let gain = self.cost(p, s1) + self.cost(sl, nx) - self.cost(p, nx);
        if gain <= self.eps {
            return None;
        }
        Some(OrSegment {
            ps,
            len,
            s1,
            sl,
            p,
            nx,
            gain,
        })
    }

    /// Whether node `y` lies in the segment.
    #[inline]
    fn in_segment(&self, seg: &OrSegment, y: u32) -> bool {
        self.wrap(self.p(y) + self.m - seg.ps) < seg.len
    }

    /// Applies an Or-opt move: the segment goes between `u -> v`
    /// (`reversed`: last node first), changing the cost by `delta`.
    fn apply_or_move(&mut self, seg: &OrSegment, u: u32, v: u32, reversed: bool, delta: f64) {
        // S M1 M2 with M1 = nx..u: becomes M1 S M2.
        let l1 = self.span(self.p(seg.nx), self.p(u));
        self.exchange(seg.ps, seg.len, l1);
        if reversed {
            let q = self.p(seg.s1);
            self.reverse(q, self.wrap(q + seg.len - 1));
        }
        self.finish_move(delta, &[seg.p, seg.nx, u, v, seg.s1, seg.sl]);
    }

    /// 2-opt moves with `x` as the tail `a` of the first removed arc, then as
    /// the head `b` of it.
    fn try_two_opt(&mut self, x: u32) -> bool {
        let (k, eps) = (self.k, self.eps);
        for as_tail in [true, false] {
            let (a, b) = if as_tail {
                (x, self.succ(x))
            } else {
                (self.pred(x), x)
            };
            let cab = self.cost(a, b);
            let pb = self.p(b);
            let anchor = if as_tail { a } else { b };
            let base = anchor as usize * k;
            let mut found = None;
            let lists = self.out_cost[base..base + k]
                .iter()
                .zip(&self.out_c[base..base + k]);
            for (&cy, &y) in lists {
                let gain1 = cab - cy;
                if gain1 <= eps {
                    break;
                }
                // New arcs (a, d) and (b, e) with e = succ(d); the anchor's
                // one costs `cy`.
                let (d, e) = if as_tail {
                    (y, self.succ(y))
                } else {
                    (self.pred(y), y)
                };
                if d == b || d == a {
                    continue;
                }
                let pd = self.p(d);
                let (cad, cbe) = if as_tail {
                    (cy, self.cost(b, e))
                } else {
                    (self.cost(a, d), cy)
                };
                let delta = cad + cbe - cab - self.cost(d, e) + self.reversal_delta(pb, pd);
                if delta < -eps {
                    found = Some((delta, d, e, pd));
                    break;
                }
            }
            if let Some((delta, d, e, pd)) = found {
                let inner = self.span(pb, pd);
                if matches!(self.asym, Asymmetry::None) && 2 * inner > self.m {
                    self.reverse(self.p(e), self.p(a));
                } else {
                    self.reverse(pb, pd);
                }
                self.finish_move(delta, &[a, b, d, e]);
                return true;
            }
        }
        false
    }

    /// Calls `reinsert` on the Or-opt segments of 1..=3 nodes starting or
    /// ending at `x` whose removal gains, in [`OR_SEGMENTS`] order, until
    /// one call applies a move.
    #[inline]
    fn try_or_segments(
        &mut self,
        x: u32,
        mut reinsert: impl FnMut(&mut Self, OrSegment) -> bool,
    ) -> bool {
        let px = self.p(x);
        for (len, starts_at_x) in OR_SEGMENTS {
            if len + 3 > self.m {
                break;
            }
            if let Some(seg) = self.or_segment(px, len, starts_at_x)
                && reinsert(self, seg)
            {
                return true;
            }
        }
        false
    }

    /// Or-opt: segments of 1..=3 nodes starting or ending at `x`, moved
    /// between two adjacent nodes `u -> v`, forward or reversed.
    fn try_or_opt(&mut self, x: u32) -> bool {
        self.try_or_segments(x, Self::reinsert)
    }

    /// Moves `seg` between two adjacent nodes `u -> v`, forward or
    /// reversed, when that improves the tour (first improvement).
    ///
    /// Always inlined (as are [`State::or_segment`] and
    /// [`State::reinsert_sym`]): most segments are rejected by the first
    /// test, and a call per segment cost about 12 % of the solver's time on
    /// the FUEL instances.
    #[inline(always)]
    fn reinsert(&mut self, seg: OrSegment) -> bool {
        let (k, eps) = (self.k, self.eps);
        let (len, s1, sl, gain) = (seg.len, seg.s1, seg.sl, seg.gain);
        // Cheapest first arcs of the four scans below (lists are
        // sorted): when none is below the gain, no scan can succeed.
        let (s1u, slu) = (s1 as usize * k, sl as usize * k);
        let mut first_min = self.in_cost[s1u].min(self.out_cost[slu]);
        if len > 1 {
            first_min = first_min.min(self.in_cost[slu]).min(self.out_cost[s1u]);
        }
        if first_min >= gain {
            return false;
        }
        let mut internal = 0.0;
        for t in 0..len - 1 {
            let (y, z) = (self.at(seg.ps + t), self.at(seg.ps + t + 1));
            internal += self.cost(z, y) - self.cost(y, z);
        }
        for reversed in [false, true] {
            if reversed && len == 1 {
                continue;
            }
            // Inserted as u -> head ... tail -> v.
            let (head, tail) = if reversed { (sl, s1) } else { (s1, sl) };
            let extra = if reversed { internal } else { 0.0 };
            for via_head in [true, false] {
                let base = if via_head { head } else { tail } as usize * k;
                for idx in base..base + k {
                    let first = if via_head {
                        self.in_cost[idx]
                    } else {
                        self.out_cost[idx]
                    };
                    if first >= gain {
                        break;
                    }
                    let (u, v) = if via_head {
                        let u = self.in_c[idx];
                        (u, self.succ(u))
                    } else {
                        let v = self.out_c[idx];
                        (self.pred(v), v)
                    };
                    if u == seg.p || self.in_segment(&seg, u) || self.in_segment(&seg, v) {
                        continue;
                    }
                    let delta =
                        self.cost(u, head) + self.cost(tail, v) - self.cost(u, v) + extra - gain;
                    if delta < -eps {
                        self.apply_or_move(&seg, u, v, reversed, delta);
                        return true;
                    }
                }
            }
        }
        false
    }

    /// Or-opt on symmetric costs: as [`State::try_or_opt`], but each
    /// neighbour `w` of a segment end `e` is tried on both sides (`e` next to
    /// `w`, the segment between `w` and its successor or its predecessor),
    /// which covers both orientations in one scan.
    fn try_or_opt_sym(&mut self, x: u32) -> bool {
        self.try_or_segments(x, Self::reinsert_sym)
    }

    /// [`State::reinsert`] on symmetric costs, in one scan per segment end.
    #[inline(always)]
    fn reinsert_sym(&mut self, seg: OrSegment) -> bool {
        let (k, eps) = (self.k, self.eps);
        let (len, s1, sl, gain) = (seg.len, seg.s1, seg.sl, seg.gain);
        let mut found = None;
        'ends: for (e, other) in [(s1, sl), (sl, s1)] {
            let base = e as usize * k;
            let lists = self.out_cost[base..base + k]
                .iter()
                .zip(&self.out_c[base..base + k]);
            for (&cew, &w) in lists {
                if cew >= gain {
                    break;
                }
                if self.in_segment(&seg, w) {
                    continue;
                }
                // Between w and its successor, then its predecessor.
                for after in [true, false] {
                    let z = if after { self.succ(w) } else { self.pred(w) };
                    if self.in_segment(&seg, z) {
                        continue;
                    }
                    let delta = cew + self.cost(other, z) - self.cost(w, z) - gain;
                    if delta < -eps {
                        // (u, v) = the arc the segment goes into;
                        // inserted as u -> head .. tail -> v.
                        found = Some(if after {
                            (delta, w, z, e)
                        } else {
                            (delta, z, w, other)
                        });
                        break 'ends;
                    }
                }
            }
            if len == 1 {
                break;
            }
        }
        if let Some((delta, u, v, head)) = found {
            self.apply_or_move(&seg, u, v, head != s1, delta);
            return true;
        }
        false
    }

    /// or-3opt (segment exchange) with `x` as the tail `a` of the first
    /// removed arc: `a -> b'..c -> a'..b -> c'`.
    fn try_or3(&mut self, x: u32) -> bool {
        let (k, eps) = (self.k, self.eps);
        let a = x;
        let a1 = self.succ(a);
        let caa1 = self.cost(a, a1);
        let (ba, ba1) = (a as usize * k, a1 as usize * k);
        let outs = self.out_cost[ba..ba + k]
            .iter()
            .zip(&self.out_c[ba..ba + k]);
        let mut found = None;
        'outer: for (&cab1, &b1) in outs {
            if cab1 >= caa1 - eps {
                break;
            }
            if b1 == a1 {
                continue;
            }
            let rb1 = self.rel(a, b1);
            let b = self.pred(b1);
            let g1 = caa1 - cab1 + self.cost(b, b1);
            let ins = self.in_cost[ba1..ba1 + k]
                .iter()
                .zip(&self.in_c[ba1..ba1 + k]);
            for (&cca1, &c) in ins {
                if cca1 >= g1 - eps {
                    break;
                }
                if self.rel(a, c) < rb1 {
                    continue;
                }
                let c1 = self.succ(c);
                let delta = self.cost(b, c1) - self.cost(c, c1) - (g1 - cca1);
                if delta < -eps {
                    found = Some((b, c, delta));
                    break 'outer;
                }
            }
        }
        if let Some((b, c, delta)) = found {
            self.segment_exchange(a, b, c, delta);
            return true;
        }
        false
    }

    /// Exchanges the stretches `succ(a)..b` and `succ(b)..c` (`a`, `b`, `c`
    /// in tour order, both stretches non-empty); `delta` is its cost change.
    fn segment_exchange(&mut self, a: u32, b: u32, c: u32, delta: f64) {
        let (a1, b1, c1) = (self.succ(a), self.succ(b), self.succ(c));
        let lx = self.rel(a, b);
        let ly = self.rel(b, c);
        self.exchange(self.p(a1), lx, ly);
        self.finish_move(delta, &[a, a1, b, b1, c, c1]);
    }

    fn local_search(&mut self) {
        while let Some(x) = self.queue.pop_front() {
            self.queued[x as usize] = false;
            let symmetric = matches!(self.asym, Asymmetry::None);
            let or_opt = |st: &mut Self| {
                if symmetric {
                    st.try_or_opt_sym(x)
                } else {
                    st.try_or_opt(x)
                }
            };
            if self.try_two_opt(x) || or_opt(self) || self.try_or3(x) {
                self.push(x);
            }
        }
    }

    /// Random double-bridge kick (Martin, Otto & Felten 1991): after a
    /// random node `a`, three adjacent stretches `P Q R` of
    /// `1..=KICK_MAX_SEGMENT` nodes each are put in the order `R Q P`, so
    /// that the four arcs `a -> P`, `P -> Q`, `Q -> R` and `R -> rest` are
    /// replaced. Orientation is kept (which matters on asymmetric costs),
    /// and no single move of the local search undoes it (a three-arc
    /// segment exchange would be undone by one or-3opt move).
    fn kick(&mut self, rng: &mut ChaCha8Rng) {
        let m = self.m;
        let lmax = ((m - 1) / 3).clamp(1, KICK_MAX_SEGMENT);
        let p0 = rng.random_range(0..m);
        let l1 = rng.random_range(1..=lmax);
        let l2 = rng.random_range(1..=lmax);
        let l3 = rng.random_range(1..=lmax);
        // l1 + l2 + l3 < m: every stretch and the rest (from d1 to a) are
        // non-empty.
        let (a, b) = (self.at(p0), self.at(p0 + l1));
        let (c, d) = (self.at(p0 + l1 + l2), self.at(p0 + l1 + l2 + l3));
        self.double_bridge(a, b, c, d);
    }

    /// Double bridge on the stretches `P = a1..b`, `Q = b1..c`, `R = c1..d`
    /// (`a`, `b`, `c`, `d` distinct and in tour order): the tour becomes
    /// `a -> R -> Q -> P -> d1`.
    fn double_bridge(&mut self, a: u32, b: u32, c: u32, d: u32) {
        let (a1, b1, c1, d1) = (self.succ(a), self.succ(b), self.succ(c), self.succ(d));
        let delta = self.cost(a, c1) + self.cost(d, b1) + self.cost(c, a1) + self.cost(b, d1)
            - self.cost(a, a1)
            - self.cost(b, b1)
            - self.cost(c, c1)
            - self.cost(d, d1);
        let (l1, l2, l3) = (self.rel(a, b), self.rel(b, c), self.rel(c, d));
        // P (Q R) -> (Q R) P, then Q R -> R Q.
        self.exchange(self.p(a1), l1, l2 + l3);
        self.exchange(self.p(b1), l2, l3);
        self.finish_move(delta, &[a, a1, b, b1, c, c1, d, d1]);
    }

    /// Restores the tour as it was at the last `undo.clear()`.
    fn rollback(&mut self) {
        while let Some((p, v)) = self.undo.pop() {
            self.tour[p as usize] = v;
            self.pos[v as usize] = p;
        }
        self.rebuild_prefix();
    }
}

/// Finds a small set of nodes touching every asymmetric pair, if one of at
/// most [`MAX_COVER`] nodes exists (greedy), else prepares prefix sums.
fn asymmetry_cover(c: &[f64], m: usize) -> (Asymmetry, Vec<bool>) {
    let mut in_cover = vec![false; m];
    if (0..m).all(|i| (0..i).all(|j| c[i * m + j] == c[j * m + i])) {
        return (Asymmetry::None, in_cover);
    }
    let asym = |i: usize, j: usize| c[i * m + j] != c[j * m + i];
    let mut cover = Vec::new();
    loop {
        let mut best = (0usize, 0usize);
        for i in 0..m {
            if in_cover[i] {
                continue;
            }
            let cnt = (0..m)
                .filter(|&j| j != i && !in_cover[j] && asym(i, j))
                .count();
            if cnt > best.0 {
                best = (cnt, i);
            }
        }
        if best.0 == 0 {
            break;
        }
        if cover.len() == MAX_COVER {
            return (Asymmetry::Prefix(vec![0.0; m + 1]), vec![false; m]);
        }
        in_cover[best.1] = true;
        cover.push(best.1 as u32);
    }
    if cover.is_empty() {
        (Asymmetry::None, in_cover)
    } else {
        (Asymmetry::Cover(cover), in_cover)
    }
}

/// Cost of the closed tour `tour` on the `m x m` row-major matrix `c`.
fn tour_cost(c: &[f64], m: usize, tour: &[u32]) -> f64 {
    (0..m)
        .map(|t| c[tour[t] as usize * m + tour[(t + 1) % m] as usize])
        .sum()
}

/// Improves `initial` (a permutation of `0..m`, `m >= 4`) by iterated local
/// search and returns the best tour found.
///
/// # Complexity
/// `O(m^2)` for the candidate lists (selection) and the asymmetry cover, then per
/// kick `O(k^2)` evaluations per queued node and, per applied move, time
/// linear in the shorter side of the change (`O(m)` with dense asymmetry).
pub(crate) fn iterated_local_search(
    c: &[f64],
    m: usize,
    initial: &[usize],
    params: IlsParams,
) -> Vec<usize> {
    debug_assert!(m >= 4 && initial.len() == m);
    let mut st = State::new(c, m, params.candidates, initial, params.cost_scale);
    for v in 0..m as u32 {
        st.push(v);
    }
    st.local_search();
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut current = st.cost;
    let (mut best_cost, mut best_tour) = (st.cost, st.tour.clone());
    let stagnation_limit = (m / 2).max(1);
    let mut stagnation = 0;
    for _ in 0..params.kicks {
        if params.deadline.is_some_and(|d| Instant::now() >= d) {
            break;
        }
        st.undo.clear();
        if stagnation >= stagnation_limit {
            // Escape the basin: a few kicks in a row, kept whatever they cost.
            for _ in 0..ESCAPE_KICKS {
                st.kick(&mut rng);
            }
            st.local_search();
            current = st.cost;
            stagnation = 0;
        } else {
            st.kick(&mut rng);
            st.local_search();
            if st.cost < current - st.eps {
                stagnation = 0;
            } else {
                stagnation += 1;
            }
            if st.cost <= current + st.eps {
                current = st.cost;
            } else {
                st.rollback();
                st.cost = current;
            }
        }
        if current < best_cost - st.eps {
            best_cost = current;
            best_tour.copy_from_slice(&st.tour);
        }
    }
    // The final choice prices both tours from scratch: tracked costs drift by
    // the rounding of every delta, and on matrices mixing costs above ~1e16
    // with small ones that drift (and `eps`, relative to the largest cost)
    // hides differences of the small costs, so the walk's `current` may be
    // worse than the best tour seen.
    let best_exact = tour_cost(c, m, &best_tour);
    if best_exact < st.recomputed_cost() {
        st.tour.copy_from_slice(&best_tour);
    }
    st.tour.into_iter().map(|v| v as usize).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::lcg;

    /// Symmetric, single-node-asymmetric (open path) and dense asymmetric
    /// matrices exercise the three reversal pricings.
    fn instances() -> Vec<(usize, Vec<f64>)> {
        let mut out = Vec::new();
        for (seed, m) in [(1u64, 5usize), (2, 9), (3, 30), (4, 120)] {
            let mut r = lcg(seed);
            let pts: Vec<(f64, f64)> = (0..m).map(|_| (r() * 100.0, r() * 100.0)).collect();
            let d = |i: usize, j: usize| {
                ((pts[i].0 - pts[j].0).powi(2) + (pts[i].1 - pts[j].1).powi(2))
                    .sqrt()
                    .round()
            };
            let sym: Vec<f64> = (0..m * m).map(|k| d(k / m, k % m)).collect();
            let mut open = sym.clone();
            for i in 0..m {
                open[i * m] = 0.0;
            }
            let dense: Vec<f64> = (0..m * m)
                .map(|k| d(k / m, k % m) + (r() * 30.0).round())
                .collect();
            out.extend([(m, sym), (m, open), (m, dense)]);
        }
        out
    }

    /// The double bridge against a reference built by slicing the tour.
    #[test]
    fn double_bridge_matches_the_reference() {
        for (m, c) in instances() {
            let init: Vec<usize> = (0..m).rev().collect();
            let mut st = State::new(&c, m, 8, &init, None);
            let mut rng = ChaCha8Rng::seed_from_u64(m as u64);
            for _ in 0..30 {
                // Four distinct positions p0 < p1 < p2 < p3 after a rotation.
                let p0 = rng.random_range(0..m);
                let mut cuts: Vec<usize> = (1..m).collect();
                for i in 0..3 {
                    let j = rng.random_range(i..cuts.len());
                    cuts.swap(i, j);
                }
                let mut cuts = cuts[..3].to_vec();
                cuts.sort_unstable();
                let before: Vec<u32> = (0..m).map(|t| st.at(p0 + t)).collect();
                let (a, b, c3, d) = (before[0], before[cuts[0]], before[cuts[1]], before[cuts[2]]);
                // a P Q R rest -> a R Q P rest.
                let mut expected = vec![a];
                expected.extend_from_slice(&before[cuts[1] + 1..=cuts[2]]);
                expected.extend_from_slice(&before[cuts[0] + 1..=cuts[1]]);
                expected.extend_from_slice(&before[1..=cuts[0]]);
                expected.extend_from_slice(&before[cuts[2] + 1..]);
                let cost = st.cost;
                st.undo.clear();
                st.double_bridge(a, b, c3, d);
                let pa = st.p(a);
                let after: Vec<u32> = (0..m).map(|t| st.at(pa + t)).collect();
                assert_eq!(after, expected);
                assert!((st.cost - st.recomputed_cost()).abs() < 1e-6);
                st.rollback();
                st.cost = cost;
                let back: Vec<u32> = (0..m).map(|t| st.at(st.p(before[0]) + t)).collect();
                assert_eq!(back, before);
                st.queue.clear();
                st.queued.fill(false);
            }
        }
    }

    /// On symmetric costs the one-scan Or-opt has exactly the neighbourhood
    /// of the general one: from every node of random tours, both find an
    /// improving move or neither does (and the debug build checks every
    /// applied move's tracked cost).
    #[test]
    fn symmetric_or_opt_matches_the_general_scan() {
        let mut outcomes = [0usize; 2];
        for (m, c) in instances() {
            if (0..m).any(|i| (0..i).any(|j| c[i * m + j] != c[j * m + i])) {
                continue;
            }
            let mut rng = ChaCha8Rng::seed_from_u64(5);
            for k in [3, m - 1] {
                for _ in 0..5 {
                    let mut init: Vec<usize> = (0..m).collect();
                    for i in (1..m).rev() {
                        init.swap(i, rng.random_range(0..=i));
                    }
                    // A random tour, its local optimum, and that optimum kicked.
                    let random = State::new(&c, m, k, &init, None);
                    let mut optimum = random.clone();
                    for v in 0..m as u32 {
                        optimum.push(v);
                    }
                    optimum.local_search();
                    let mut kicked = optimum.clone();
                    kicked.kick(&mut rng);
                    for mut st in [random, optimum, kicked] {
                        st.queue.clear();
                        st.queued.fill(false);
                        for x in 0..m as u32 {
                            let (mut g, mut s) = (st.clone(), st.clone());
                            let found = g.try_or_opt(x);
                            assert_eq!(s.try_or_opt_sym(x), found, "m {m} k {k} node {x}");
                            outcomes[usize::from(found)] += 1;
                            if found {
                                assert!(s.cost < st.cost && g.cost < st.cost);
                                assert!((s.cost - s.recomputed_cost()).abs() < 1e-6);
                            }
                        }
                    }
                }
            }
        }
        assert!(outcomes[0] > 20 && outcomes[1] > 20, "{outcomes:?}");
    }

    #[test]
    fn tracked_cost_and_rollback_stay_exact() {
        for (m, c) in instances() {
            let init: Vec<usize> = (0..m).collect();
            let mut st = State::new(&c, m, 8, &init, None);
            for v in 0..m as u32 {
                st.push(v);
            }
            st.local_search();
            let mut rng = ChaCha8Rng::seed_from_u64(9);
            for _ in 0..50 {
                let (before, cost) = (st.tour.clone(), st.cost);
                st.undo.clear();
                st.kick(&mut rng);
                st.local_search();
                assert!((st.cost - st.recomputed_cost()).abs() < 1e-6);
                let mut seen = vec![false; m];
                for (p, &v) in st.tour.iter().enumerate() {
                    assert!(!std::mem::replace(&mut seen[v as usize], true));
                    assert_eq!(st.pos[v as usize] as usize, p);
                }
                st.rollback();
                st.cost = cost;
                assert_eq!(st.tour, before);
                assert!((st.recomputed_cost() - cost).abs() < 1e-6);
            }
        }
    }
}
