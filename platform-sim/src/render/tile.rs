//! The tile kernel: a camera tile of up to 8 x 8 primary rays, prepared and
//! traced through the 4-wide tree ([`super::quad`]) as one packet, 8 rays
//! (one tile row) per vector.
//!
//! # Algorithm
//! * **Rays** are made inside the kernel, a row at a time, straight into
//!   vectors: direction `base + a right`, reciprocal (clamped as
//!   [`PreparedRay::new`]), dominant axis and shear (Woop et al. 2013), with
//!   the same IEEE operations as [`PreparedRay::new`]. Rays that
//!   [`PreparedRay::new`] would refuse (zero or non-finite direction) and
//!   columns beyond the image are masked out.
//! * **Passes**: a frustum needs rays that share the sign of each direction
//!   component, and the triangle test is specialised for one dominant axis.
//!   The tile's rays are split into classes (dominant axis, three signs);
//!   nearly every tile is one class and is traced in one pass, the few along
//!   the image lines where a component changes sign or two components are
//!   equal in size take one pass per class, with the other lanes masked.
//! * **Traversal**: the tile's frustum (shared origin, per-axis range of the
//!   reciprocal directions) is tested against a quad node's four children at
//!   once by interval arithmetic (Boulos et al. 2006); children entered are
//!   visited nearest first (by the frustum's entry distance), the others
//!   pushed with that distance and skipped when popped if every ray of the
//!   tile already has a closer hit (Reshetov, Soupikov and Hurley 2005).
//!   Nodes are not tested ray by ray: the frustum decides, the leaves'
//!   per-ray box tests catch the rest.
//! * **Leaves**: each row's rays are tested against the leaf's box (an
//!   active-ray mask; rows with no active ray skip the leaf), then against
//!   each triangle with the watertight test, specialised at compile time for
//!   the tile's dominant axis. Triangle vertices relative to the shared
//!   origin are computed once per leaf, not per row. The costly part of the
//!   test (determinant, division) runs only when some active ray falls
//!   inside the triangle's edges.
//! * **Readings**: depth (z-depth in the window) and instance (within the
//!   semantic range) are made in the kernel too, 8 pixels per instruction.
//!
//! # Why AVX2 through `pulp`
//! `wide::f32x8` compiled for baseline x86-64 runs each operation as two SSE
//! instructions. `pulp`'s x86-64-v3 token is detected once at run time and
//! compiles the kernel, inlined whole, for AVX2 inside `V3::vectorize`:
//! 256-bit registers with no `unsafe` in this crate and no build flags for
//! users. Every helper the kernel calls must inline (`#[inline(always)]`,
//! no `array::map` or `from_fn` closures over vectors): an out-of-line
//! helper is compiled without AVX and each intrinsic becomes a call (that
//! mistake made the first version slower than the SSE path).
//!
//! # Results
//! Every ray's `t` is the closest hit's `t` computed by the same IEEE
//! operations as [`PreparedRay`]'s scalar test, so depth is bit-identical to
//! [`Bvh::intersect_packet`] and [`Bvh::intersect_prepared`]; where two
//! triangles are hit at exactly the same `t` (coplanar faces, a ray through
//! a shared edge), the one met first in this traversal is reported, which
//! may differ from the binary-tree traversals. The three [`super::Lanes`]
//! back ends give the same bits (the traversal's decisions are made by the
//! same code on the same values).
//!
//! # Complexity
//! O(R log T) expected for R rays and T triangles; node work is shared by
//! the tile's 64 rays and leaf work runs 8 rays per instruction.

use super::NO_INSTANCE;
use super::bvh::PreparedRay;
use super::bvh::{Bvh, BvhTriangle, MAX_DEPTH, ROBUST_FAR, fmax};
#[cfg(target_arch = "x86_64")]
use super::lanes::Avx2;
use super::lanes::{Lanes, Portable, Reference, RenderKernel, W, avx2_token};
use super::quad::{LEAF, QuadFrustum, QuadNode, leaf_range};

/// Rows of a tile (one vector of 8 rays per row).
pub(super) const ROWS: usize = 8;

/// Traversal stack: each quad level pushes at most three children.
const STACK: usize = 3 * MAX_DEPTH + 4;

/// The rays of one tile: row `g`, column `i` has direction
/// `base[g] + a[i] * right` (component-wise, multiply then add) and the
/// shared `origin`.
#[derive(Debug, Clone, Copy)]
pub(super) struct TileRays<'a> {
    /// Shared origin.
    pub(super) origin: [f32; 3],
    /// Per row: the direction of the row's column offset 0.
    pub(super) base: [[f32; 3]; ROWS],
    /// Direction step per unit of column offset.
    pub(super) right: [f32; 3],
    /// Column offsets.
    pub(super) a: &'a [f32; W],
    /// Rows used (1..=8).
    pub(super) rows: usize,
    /// Columns used (1..=8): lanes beyond are not traced.
    pub(super) cols: usize,
    /// The depth window: hits at `t` in `[depth.0, depth.1]` give a depth
    /// reading ([`TileHits::depth`]).
    pub(super) depth: (f32, f32),
    /// Hits at `t <= semantic` give an instance reading.
    pub(super) semantic: f32,
}

/// Closest hits of a tile: `t`, leaf slot and payload per ray (slot
/// `u32::MAX` where the ray hits nothing in range).
#[derive(Debug, Clone, Copy)]
pub(super) struct TileHits {
    /// Ray parameter of the closest hit (`t_max` without a hit).
    pub(super) t: [[f32; W]; ROWS],
    /// Leaf slot of the closest hit.
    pub(super) slot: [[u32; W]; ROWS],
    /// Payload of the closest hit's triangle.
    pub(super) payload: [[u32; W]; ROWS],
    /// Depth reading: `t` of a hit in the depth window, else 0.
    pub(super) depth: [[f32; W]; ROWS],
    /// Instance reading: the payload of a hit within the semantic range,
    /// else `NO_INSTANCE`.
    pub(super) instance: [[u32; W]; ROWS],
}

impl TileHits {
    /// No hits.
    pub(super) const EMPTY: TileHits = TileHits {
        t: [[0.0; W]; ROWS],
        slot: [[u32::MAX; W]; ROWS],
        payload: [[0; W]; ROWS],
        depth: [[0.0; W]; ROWS],
        instance: [[NO_INSTANCE; W]; ROWS],
    };
}

/// Traces a tile with `kernel` (`Auto` picks the best available). `false`,
/// with `out` unspecified, when the kernel is not available on this CPU,
/// the tree has no 4-wide form (see [`super::quad::collapse`]), the origin
/// is not finite, `t_min < t_max` does not hold or `tile.rows` is not in
/// `1..=ROWS`; the caller then uses [`trace_tile_packet`].
pub(super) fn trace_tile(
    kernel: RenderKernel,
    bvh: &Bvh,
    tile: &TileRays<'_>,
    t_min: f32,
    t_max: f32,
    out: &mut TileHits,
    scratch: &mut TileScratch,
) -> bool {
    let ordered = t_min < t_max;
    if bvh.quads().is_empty() || !ordered || !(1..=ROWS).contains(&tile.rows) {
        return false;
    }
    match kernel.resolve() {
        RenderKernel::Avx2 => avx2(bvh, tile, t_min, t_max, out, scratch),
        RenderKernel::Reference => trace(Reference, bvh, tile, t_min, t_max, out, scratch),
        _ => trace(Portable, bvh, tile, t_min, t_max, out, scratch),
    }
}

/// Traces a tile ray by ray through [`Bvh::intersect_packet`] (the binary
/// tree): the same depth as [`trace_tile`], for trees the tile kernel cannot
/// take and as the reference of the tests.
pub(super) fn trace_tile_packet(
    bvh: &Bvh,
    tile: &TileRays<'_>,
    t_min: f32,
    t_max: f32,
    out: &mut TileHits,
) {
    let mut rays = [PreparedRay::DUMMY; ROWS * W];
    let mut index = [(0usize, 0usize); ROWS * W];
    let mut n = 0;
    *out = TileHits::EMPTY;
    for g in 0..tile.rows.min(ROWS) {
        for i in 0..tile.cols.min(W) {
            let dir = [0, 1, 2].map(|c| tile.base[g][c] + tile.a[i] * tile.right[c]);
            if let Some(ray) = PreparedRay::new(tile.origin, dir) {
                rays[n] = ray;
                index[n] = (g, i);
                n += 1;
            }
        }
    }
    let mut hits = [None; ROWS * W];
    bvh.intersect_packet(&rays[..n], t_min, t_max, &mut hits[..n]);
    for (hit, &(g, i)) in hits[..n].iter().zip(&index[..n]) {
        if let Some(h) = hit {
            out.t[g][i] = h.t;
            out.slot[g][i] = h.slot;
            out.payload[g][i] = h.payload;
            if h.t >= tile.depth.0 && h.t <= tile.depth.1 {
                out.depth[g][i] = h.t;
            }
            if h.t <= tile.semantic {
                out.instance[g][i] = h.payload;
            }
        }
    }
}

/// The AVX2 back end, compiled for x86-64-v3 inside `pulp`'s `vectorize`.
#[cfg(target_arch = "x86_64")]
fn avx2(
    bvh: &Bvh,
    tile: &TileRays<'_>,
    t_min: f32,
    t_max: f32,
    out: &mut TileHits,
    scratch: &mut TileScratch,
) -> bool {
    struct Run<'a> {
        v3: pulp::x86::V3,
        bvh: &'a Bvh,
        tile: &'a TileRays<'a>,
        t_min: f32,
        t_max: f32,
        out: &'a mut TileHits,
        scratch: &'a mut TileScratch,
    }
    impl pulp::NullaryFnOnce for Run<'_> {
        type Output = bool;
        #[inline(always)]
        fn call(self) -> bool {
            trace(
                Avx2(self.v3),
                self.bvh,
                self.tile,
                self.t_min,
                self.t_max,
                self.out,
                self.scratch,
            )
        }
    }
    let Some(v3) = avx2_token() else {
        return false;
    };
    v3.vectorize(Run {
        v3,
        bvh,
        tile,
        t_min,
        t_max,
        out,
        scratch,
    })
}

/// No AVX2 off x86-64.
#[cfg(not(target_arch = "x86_64"))]
fn avx2(_: &Bvh, _: &TileRays<'_>, _: f32, _: f32, _: &mut TileHits, _: &mut TileScratch) -> bool {
    let _ = avx2_token();
    false
}

/// Memory the tile kernel reuses from tile to tile (one per thread):
/// the prepared rays and the traversal stack.
#[derive(Debug, Clone)]
pub(super) struct TileScratch {
    rays: Rays,
    stack: Vec<(u32, u32, f32)>,
}

impl TileScratch {
    /// Scratch for any tile.
    pub(super) fn new() -> TileScratch {
        TileScratch {
            rays: Rays {
                inv: [[[0.0; W]; 3]; ROWS],
                shear: [[[0.0; W]; 3]; ROWS],
                rows: 0,
                origin: [0.0; 3],
            },
            stack: Vec::with_capacity(STACK),
        }
    }
}

/// A tile's prepared rays, lanes per row.
#[derive(Debug, Clone)]
struct Rays {
    /// Reciprocal directions per row and axis (clamped to +-1e30).
    inv: [[[f32; W]; 3]; ROWS],
    /// Woop's shear constants (Sx, Sy, Sz) per row, for each lane's own
    /// dominant axis.
    shear: [[[f32; W]; 3]; ROWS],
    rows: usize,
    origin: [f32; 3],
}

/// Per-row lane bit masks of a tile's rays.
struct RayClasses {
    /// Lanes with a valid ray (finite, non-zero direction, column in use).
    valid: [u8; ROWS],
    /// Lanes whose dominant axis is 0, 1, 2.
    kz: [[u8; ROWS]; 3],
    /// Lanes whose direction is negative along axis 0, 1, 2.
    neg: [[u8; ROWS]; 3],
}

/// The rays of one traversal pass: lanes sharing their dominant axis and
/// direction signs (usually the whole tile).
struct Pass<V> {
    /// Lane mask per row.
    lanes: [V; ROWS],
    /// Rows with a lane in the pass (bit per row).
    used: u8,
    /// Per axis: the pass's rays travel towards -axis.
    neg: [bool; 3],
}

/// Prepares the tile's rays and their classes; `None` for a non-finite
/// origin.
#[inline(always)]
fn prepare<L: Lanes>(l: L, tile: &TileRays<'_>, rays: &mut Rays) -> Option<RayClasses> {
    if !tile.origin.iter().all(|c| c.is_finite()) {
        return None;
    }
    let zero = l.splat(0.0);
    let one = l.splat(1.0);
    let big = l.splat(1.0e30);
    let nbig = l.splat(-1.0e30);
    let a = l.load(*tile.a);
    let right = [
        l.splat(tile.right[0]),
        l.splat(tile.right[1]),
        l.splat(tile.right[2]),
    ];
    let cols = if tile.cols >= W {
        0xff
    } else {
        (1u8 << tile.cols) - 1
    };
    rays.rows = tile.rows;
    rays.origin = tile.origin;
    let mut classes = RayClasses {
        valid: [0; ROWS],
        kz: [[0; ROWS]; 3],
        neg: [[0; ROWS]; 3],
    };
    for g in 0..tile.rows {
        let mut d = [zero; 3];
        for c in 0..3 {
            d[c] = l.add(l.splat(tile.base[g][c]), l.mul(a, right[c]));
        }
        let finite = l.and(
            l.and(l.is_finite(d[0]), l.is_finite(d[1])),
            l.is_finite(d[2]),
        );
        let null = l.and(l.and(l.eq(d[0], zero), l.eq(d[1], zero)), l.eq(d[2], zero));
        classes.valid[g] = (l.bitmask(l.and_not(finite, null)) as u8) & cols;
        // Dominant axis as `largest_axis` (the first one on ties).
        let e = [l.abs(d[0]), l.abs(d[1]), l.abs(d[2])];
        let k0 = l.and(l.ge(e[0], e[1]), l.ge(e[0], e[2]));
        let k1 = l.and_not(l.ge(e[1], e[2]), k0);
        let (b0, b1) = (l.bitmask(k0) as u8, l.bitmask(k1) as u8);
        classes.kz[0][g] = b0;
        classes.kz[1][g] = b1;
        classes.kz[2][g] = !(b0 | b1);
        for (neg, dc) in classes.neg.iter_mut().zip(d) {
            neg[g] = l.bitmask(l.lt(dc, zero)) as u8;
        }
        // Each lane's (kz, kx, ky) components.
        let dx = l.select(k0, d[1], l.select(k1, d[2], d[0]));
        let dy = l.select(k0, d[2], l.select(k1, d[0], d[1]));
        // 1 / d per axis; Sz = 1 / d[kz] is the same quotient.
        let q = [l.div(one, d[0]), l.div(one, d[1]), l.div(one, d[2])];
        let sz = l.select(k0, q[0], l.select(k1, q[1], q[2]));
        rays.shear[g] = [l.store(l.mul(dx, sz)), l.store(l.mul(dy, sz)), l.store(sz)];
        for c in 0..3 {
            let r = l.max(l.min(q[c], big), nbig);
            rays.inv[g][c] = l.store(l.select(l.eq(d[c], zero), big, r));
        }
    }
    Some(classes)
}

/// A lane mask vector from a bit mask.
#[inline(always)]
fn lane_mask<L: Lanes>(l: L, bits: u8) -> L::V {
    let t = f32::from_bits(u32::MAX);
    l.load(std::array::from_fn(|i| {
        if bits & (1 << i) != 0 { t } else { 0.0 }
    }))
}

/// Prepares and traces a tile with back end `l`: one traversal pass per
/// class of rays (dominant axis and direction signs) present in the tile.
#[inline(always)]
fn trace<L: Lanes>(
    l: L,
    bvh: &Bvh,
    tile: &TileRays<'_>,
    t_min: f32,
    t_max: f32,
    out: &mut TileHits,
    scratch: &mut TileScratch,
) -> bool {
    let TileScratch { rays, stack } = scratch;
    let Some(classes) = prepare(l, tile, rays) else {
        return false;
    };
    let mut hits = Hits {
        t: [l.splat(t_max); ROWS],
        slot: [l.splat(f32::from_bits(u32::MAX)); ROWS],
        payload: [l.splat(0.0); ROWS],
        hit: [l.splat(0.0); ROWS],
        pmax: t_max,
    };
    let rows = &classes.valid[..rays.rows];
    let uniform = |m: &[u8; ROWS]| {
        let m = &m[..rays.rows];
        m.iter().all(|b| *b == 0xff) || m.iter().all(|b| *b == 0)
    };
    if rows.iter().all(|v| *v == 0xff)
        && classes.kz.iter().all(uniform)
        && classes.neg.iter().all(uniform)
    {
        // One class of rays, every lane valid (nearly every camera tile).
        let pass = Pass {
            lanes: [lane_mask(l, 0xff); ROWS],
            used: ((1u16 << rays.rows) - 1) as u8,
            neg: [0, 1, 2].map(|a| classes.neg[a][0] == 0xff),
        };
        match (classes.kz[0][0], classes.kz[1][0]) {
            (0xff, _) => traverse::<L, 0>(l, bvh, rays, &pass, t_min, &mut hits, stack),
            (_, 0xff) => traverse::<L, 1>(l, bvh, rays, &pass, t_min, &mut hits, stack),
            _ => traverse::<L, 2>(l, bvh, rays, &pass, t_min, &mut hits, stack),
        }
        store_hits(l, &hits, tile, out);
        return true;
    }
    let mut remaining = classes.valid;
    while let Some(g0) = remaining.iter().position(|m| *m != 0) {
        // The class of the first remaining lane.
        let i0 = remaining[g0].trailing_zeros();
        let kz = (0..3)
            .find(|k| classes.kz[*k][g0] >> i0 & 1 == 1)
            .unwrap_or(2);
        let neg = [0, 1, 2].map(|a| classes.neg[a][g0] >> i0 & 1 == 1);
        let mut pass = Pass {
            lanes: [l.splat(0.0); ROWS],
            used: 0,
            neg,
        };
        for (g, left) in remaining[..rays.rows].iter_mut().enumerate() {
            let mut bits = *left & classes.kz[kz][g];
            for (a, n) in neg.iter().enumerate() {
                bits &= if *n {
                    classes.neg[a][g]
                } else {
                    !classes.neg[a][g]
                };
            }
            *left &= !bits;
            if bits != 0 {
                pass.used |= 1 << g;
                pass.lanes[g] = lane_mask(l, bits);
            }
        }
        match kz {
            0 => traverse::<L, 0>(l, bvh, rays, &pass, t_min, &mut hits, stack),
            1 => traverse::<L, 1>(l, bvh, rays, &pass, t_min, &mut hits, stack),
            _ => traverse::<L, 2>(l, bvh, rays, &pass, t_min, &mut hits, stack),
        }
    }
    store_hits(l, &hits, tile, out);
    true
}

/// Writes the tile's rows of `hits` and the readings they give into `out`.
#[inline(always)]
fn store_hits<L: Lanes>(l: L, hits: &Hits<L::V>, tile: &TileRays<'_>, out: &mut TileHits) {
    let (dmin, dmax) = (l.splat(tile.depth.0), l.splat(tile.depth.1));
    let sem = l.splat(tile.semantic);
    let zero = l.splat(0.0);
    let none = l.splat(f32::from_bits(NO_INSTANCE));
    for g in 0..tile.rows {
        let (t, hit) = (hits.t[g], hits.hit[g]);
        let in_depth = l.and(hit, l.and(l.ge(t, dmin), l.le(t, dmax)));
        let in_sem = l.and(hit, l.le(t, sem));
        out.t[g] = l.store(t);
        out.slot[g] = l.store(hits.slot[g]).map(f32::to_bits);
        out.payload[g] = l.store(hits.payload[g]).map(f32::to_bits);
        out.depth[g] = l.store(l.select(in_depth, t, zero));
        out.instance[g] = l
            .store(l.select(in_sem, hits.payload[g], none))
            .map(f32::to_bits);
    }
}

/// The frustum of a pass's rays.
#[inline(always)]
fn frustum<L: Lanes>(l: L, rays: &Rays, pass: &Pass<L::V>) -> QuadFrustum {
    let inf = l.splat(f32::INFINITY);
    let ninf = l.splat(f32::NEG_INFINITY);
    let mut lo = [inf; 3];
    let mut hi = [ninf; 3];
    for g in 0..rays.rows {
        if pass.used & (1 << g) == 0 {
            continue;
        }
        for a in 0..3 {
            let inv = l.load(rays.inv[g][a]);
            lo[a] = l.min(lo[a], l.select(pass.lanes[g], inv, inf));
            hi[a] = l.max(hi[a], l.select(pass.lanes[g], inv, ninf));
        }
    }
    let (mut imin, mut imax) = ([0.0; 3], [0.0; 3]);
    for a in 0..3 {
        let (l0, h0) = (l.store(lo[a]), l.store(hi[a]));
        imin[a] = l0
            .into_iter()
            .fold(f32::INFINITY, |m, x| if x < m { x } else { m });
        imax[a] = h0.into_iter().fold(f32::NEG_INFINITY, fmax);
    }
    QuadFrustum {
        o: rays.origin,
        imin,
        imax,
        neg: pass.neg,
    }
}

/// One traversal pass for dominant axis `KZ`.
#[inline(always)]
fn traverse<L: Lanes, const KZ: usize>(
    l: L,
    bvh: &Bvh,
    rays: &Rays,
    pass: &Pass<L::V>,
    t_min: f32,
    hits: &mut Hits<L::V>,
    stack: &mut Vec<(u32, u32, f32)>,
) {
    let quads = bvh.quads();
    let fr = frustum(l, rays, pass);
    stack.clear();
    let mut cur = 0usize;
    'descend: loop {
        let q = &quads[cur];
        let (mask, tn) = fr.test(q, 0.0, hits.pmax);
        let mut next = None;
        if mask != 0 {
            // Children entered, nearest first (ties by position).
            let mut order = [(0f32, 0usize); 4];
            let mut k = 0;
            for (i, t) in tn.iter().enumerate() {
                if mask & (1 << i) != 0 {
                    let mut j = k;
                    while j > 0 && order[j - 1].0 > *t {
                        order[j] = order[j - 1];
                        j -= 1;
                    }
                    order[j] = (*t, i);
                    k += 1;
                }
            }
            for &(t, i) in order[1..k].iter().rev() {
                stack.push((q.child[i], (cur * 4 + i) as u32, t));
            }
            let i = order[0].1;
            if q.child[i] & LEAF != 0 {
                leaf::<L, KZ>(l, bvh.triangles(), q, i, rays, pass, t_min, hits);
            } else {
                next = Some(q.child[i] as usize);
            }
        }
        if let Some(n) = next {
            cur = n;
            continue;
        }
        while let Some((r, b, t)) = stack.pop() {
            if t > hits.pmax {
                continue;
            }
            if r & LEAF != 0 {
                let q = &quads[b as usize / 4];
                leaf::<L, KZ>(
                    l,
                    bvh.triangles(),
                    q,
                    b as usize % 4,
                    rays,
                    pass,
                    t_min,
                    hits,
                );
            } else {
                cur = r as usize;
                continue 'descend;
            }
        }
        break;
    }
}

/// The closest hits so far: `t`, slot and payload (as bits) per row, and
/// the largest `t` of the tile.
struct Hits<V> {
    t: [V; ROWS],
    slot: [V; ROWS],
    payload: [V; ROWS],
    /// Lanes with a hit.
    hit: [V; ROWS],
    pmax: f32,
}

/// Tests the rows of the tile against leaf child `i` of `q`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn leaf<L: Lanes, const KZ: usize>(
    l: L,
    triangles: &[BvhTriangle],
    q: &QuadNode,
    i: usize,
    rays: &Rays,
    pass: &Pass<L::V>,
    t_min: f32,
    hits: &mut Hits<L::V>,
) {
    let (s0, count) = leaf_range(q.child[i]);
    let Some(tris) = triangles.get(s0..s0 + count) else {
        return;
    };
    let (lo, hi) = q.child_box(i);
    let o = rays.origin;
    // Slab sides relative to the origin: entered through `near`.
    let zero = l.splat(0.0);
    let (mut near, mut far) = ([zero; 3], [zero; 3]);
    for a in 0..3 {
        let (n, f) = if pass.neg[a] {
            (hi[a], lo[a])
        } else {
            (lo[a], hi[a])
        };
        near[a] = l.splat(n - o[a]);
        far[a] = l.splat(f - o[a]);
    }
    // Vertices relative to the origin, once per leaf: (kx, ky, kz) parts.
    let (kx, ky) = ((KZ + 1) % 3, (KZ + 2) % 3);
    let mut verts = [[[0f32; 3]; 3]; 4];
    for (v, tri) in verts.iter_mut().zip(tris) {
        for (p, corner) in v.iter_mut().zip([&tri.a, &tri.b, &tri.c]) {
            *p = [corner[kx] - o[kx], corner[ky] - o[ky], corner[KZ] - o[KZ]];
        }
    }
    let inf = l.splat(f32::INFINITY);
    let rf = l.splat(ROBUST_FAR);
    let tmin = l.splat(t_min);
    let mut touched = false;
    for g in 0..rays.rows {
        if pass.used & (1 << g) == 0 {
            continue;
        }
        let inv = [
            l.load(rays.inv[g][0]),
            l.load(rays.inv[g][1]),
            l.load(rays.inv[g][2]),
        ];
        let tg = hits.t[g];
        // The per-ray box test of `PreparedRay::enter`.
        let t0 = l.max(
            l.max(l.mul(near[0], inv[0]), l.mul(near[1], inv[1])),
            l.max(l.mul(near[2], inv[2]), zero),
        );
        let t1 = l.min(
            l.mul(l.min(l.mul(far[0], inv[0]), l.mul(far[1], inv[1])), rf),
            l.min(l.mul(l.mul(far[2], inv[2]), rf), tg),
        );
        let active = l.and(l.and(l.le(t0, t1), l.lt(t0, inf)), pass.lanes[g]);
        if l.bitmask(active) == 0 {
            continue;
        }
        let [sx, sy, sz] = [
            l.load(rays.shear[g][0]),
            l.load(rays.shear[g][1]),
            l.load(rays.shear[g][2]),
        ];
        let (mut t, mut slot, mut payload) = (tg, hits.slot[g], hits.payload[g]);
        let mut any = zero;
        for (j, v) in verts[..tris.len()].iter().enumerate() {
            // Woop's watertight test, lane for lane `PreparedRay::triangle`.
            let sheared = |p: &[f32; 3]| {
                let z = l.splat(p[2]);
                (
                    l.sub(l.splat(p[0]), l.mul(sx, z)),
                    l.sub(l.splat(p[1]), l.mul(sy, z)),
                )
            };
            let (ax, ay) = sheared(&v[0]);
            let (bx, by) = sheared(&v[1]);
            let (cx, cy) = sheared(&v[2]);
            let u = l.sub(l.mul(cx, by), l.mul(cy, bx));
            let w_ = l.sub(l.mul(bx, ay), l.mul(by, ax));
            let v_ = l.sub(l.mul(ax, cy), l.mul(ay, cx));
            let negative = l.or(l.or(l.lt(u, zero), l.lt(v_, zero)), l.lt(w_, zero));
            let positive = l.or(l.or(l.gt(u, zero), l.gt(v_, zero)), l.gt(w_, zero));
            let inside = l.and_not(active, l.and(negative, positive));
            if l.bitmask(inside) == 0 {
                continue;
            }
            let det = l.add(l.add(u, v_), w_);
            let t_scaled = l.add(
                l.add(
                    l.mul(u, l.mul(sz, l.splat(v[0][2]))),
                    l.mul(v_, l.mul(sz, l.splat(v[1][2]))),
                ),
                l.mul(w_, l.mul(sz, l.splat(v[2][2]))),
            );
            let th = l.div(t_scaled, det);
            let hit = l.and(
                l.and_not(inside, l.eq(det, zero)),
                l.and(l.gt(th, tmin), l.lt(th, t)),
            );
            if l.bitmask(hit) != 0 {
                t = l.select(hit, th, t);
                slot = l.select(hit, l.splat(f32::from_bits((s0 + j) as u32)), slot);
                payload = l.select(hit, l.splat(f32::from_bits(tris[j].payload)), payload);
                any = l.or(any, hit);
                touched = true;
            }
        }
        hits.t[g] = t;
        hits.slot[g] = slot;
        hits.payload[g] = payload;
        hits.hit[g] = l.or(hits.hit[g], any);
    }
    if touched {
        let mut m = hits.t[0];
        for g in 1..rays.rows {
            m = l.max(m, hits.t[g]);
        }
        hits.pmax = l.store(m).into_iter().fold(0.0, fmax);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A random soup: free triangles plus axis-aligned quads, some of them
    /// duplicated with another payload (exact ties).
    fn soup() -> impl Strategy<Value = (Vec<[f32; 3]>, Vec<[u32; 3]>, Vec<u32>)> {
        let tri = proptest::array::uniform3(proptest::array::uniform3(-4.0f32..4.0));
        let quad = (
            0usize..3,
            -4.0f32..4.0,
            -4.0f32..4.0,
            -4.0f32..4.0,
            0.1f32..3.0,
            any::<bool>(),
        );
        (
            proptest::collection::vec(tri, 1..40),
            proptest::collection::vec(quad, 0..12),
        )
            .prop_map(|(tris, quads)| {
                let (mut v, mut t, mut p) = (Vec::new(), Vec::new(), Vec::new());
                for (k, tri) in tris.into_iter().enumerate() {
                    let b = v.len() as u32;
                    v.extend(tri);
                    t.push([b, b + 1, b + 2]);
                    p.push(k as u32);
                }
                for (k, (axis, c, x, y, s, twin)) in quads.into_iter().enumerate() {
                    let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
                    let corner = |i: f32, j: f32| {
                        let mut q = [0.0; 3];
                        q[axis] = c;
                        q[a1] = x + i * s;
                        q[a2] = y + j * s;
                        q
                    };
                    for copy in 0..if twin { 2 } else { 1 } {
                        let b = v.len() as u32;
                        v.extend([
                            corner(0.0, 0.0),
                            corner(1.0, 0.0),
                            corner(1.0, 1.0),
                            corner(0.0, 1.0),
                        ]);
                        t.push([b, b + 1, b + 2]);
                        t.push([b, b + 2, b + 3]);
                        p.extend([1000 + 2 * k as u32 + copy; 2]);
                    }
                }
                (v, t, p)
            })
    }

    /// Origin, row bases, right vector, column offsets, rows, columns.
    type Tile = ([f32; 3], [[f32; 3]; ROWS], [f32; 3], [f32; W], usize, usize);

    fn tile() -> impl Strategy<Value = Tile> {
        let v3 = || proptest::array::uniform3(-1.0f32..1.0);
        (
            proptest::array::uniform3(-5.0f32..5.0),
            proptest::array::uniform8(v3()),
            v3(),
            proptest::array::uniform8(-1.0f32..1.0),
            1usize..=ROWS,
            1usize..=W,
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Every kernel against the binary tree's packet path on random
        /// soups and tiles (incoherent rays, mixed dominant axes and
        /// signs, partial tiles): the same rays hit, at the same `t` bit
        /// for bit, with the same readings except at exact ties, where the
        /// kernel's triangle is checked to be hit at that very `t`.
        #[test]
        fn kernels_equal_the_packet_path(
            (v, t, p) in soup(),
            (origin, base, right, a, rows, cols) in tile(),
            window in (0.0f32..2.0, 2.0f32..9.0, 0.5f32..9.0),
        ) {
            let bvh = Bvh::build(&v, &t, &p).unwrap();
            let tile = TileRays {
                origin,
                base,
                right,
                a: &a,
                rows,
                cols,
                depth: (window.0, window.1),
                semantic: window.2,
            };
            let mut want = TileHits::EMPTY;
            trace_tile_packet(&bvh, &tile, 0.0, f32::INFINITY, &mut want);
            let mut scratch = TileScratch::new();
            for kernel in [RenderKernel::Reference, RenderKernel::Portable, RenderKernel::Avx2] {
                if !kernel.is_available() {
                    continue;
                }
                let mut got = TileHits::EMPTY;
                prop_assert!(trace_tile(kernel, &bvh, &tile, 0.0, f32::INFINITY, &mut got, &mut scratch));
                #[allow(clippy::needless_range_loop)]
                for g in 0..rows {
                    for i in 0..cols {
                        let (gs, ws) = (got.slot[g][i], want.slot[g][i]);
                        prop_assert_eq!(gs == u32::MAX, ws == u32::MAX, "{:?} row {} lane {}", kernel, g, i);
                        if ws == u32::MAX {
                            continue;
                        }
                        prop_assert_eq!(got.t[g][i].to_bits(), want.t[g][i].to_bits());
                        prop_assert_eq!(got.depth[g][i].to_bits(), want.depth[g][i].to_bits());
                        let tri = bvh.triangles()[gs as usize];
                        prop_assert_eq!(got.payload[g][i], tri.payload);
                        if gs != ws && got.payload[g][i] != want.payload[g][i] {
                            let one = Bvh::build(&[tri.a, tri.b, tri.c], &[[0, 1, 2]], &[0]).unwrap();
                            let dir = [0, 1, 2].map(|c| base[g][c] + a[i] * right[c]);
                            let hit = one.intersect(origin, dir, 0.0, f32::INFINITY);
                            prop_assert_eq!(hit.map(|h| h.t.to_bits()), Some(got.t[g][i].to_bits()));
                        } else {
                            prop_assert_eq!(got.instance[g][i], want.instance[g][i]);
                        }
                    }
                }
            }
        }
    }
}
