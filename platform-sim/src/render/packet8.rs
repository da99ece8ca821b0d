//! 8-lane SIMD kernels of the packet traversal ([`Bvh::intersect_packet`]).
//!
//! A packet of up to [`MAX_PACKET`] rays is stored as groups of 8 rays in
//! structure-of-arrays form (`wide::f32x8`, safe code; one AVX register, or
//! two SSE registers on baseline x86-64). The traversal itself is the scalar
//! one of [`Bvh::intersect_packet_scalar`], node for node: the same frustum
//! cull, the same first-active-ray index, the same child order (by the first
//! active ray). Only the per-ray work is done 8 rays at a time:
//!
//! * the search for the first active ray tests a whole group's boxes at once
//!   and takes the lowest lane that enters (a bit scan of the lane mask);
//! * in a leaf, each group is culled against the leaf's box (an active-ray
//!   mask; groups with no active lane are skipped) and the surviving lanes
//!   run the watertight triangle test of Woop, Benthin and Wald against each
//!   triangle of the leaf in turn.
//!
//! # Bit-identical to the scalar path
//! Every lane performs the scalar kernels' IEEE operations in the same order
//! (separate multiplies and adds, no fused multiply-add, one division), so
//! each ray's `t` is the same float; triangles are offered to each ray in
//! the same order with the same strict `t < t_max` test, so ties resolve
//! alike and the leaf slot is the same. Box tests feed only decisions (cull
//! or not, which child first) and reproduce the scalar decisions exactly
//! (`min`/`max` as `a < b ? a : b` / `a > b ? a : b`, operands never NaN).
//! `tests/render_bvh.rs` checks this against the scalar path on random soups
//! and camera packets. Results depend on neither thread count nor CPU
//! features.
//!
//! # Complexity
//! As the scalar traversal: O(P log T) expected for P rays and T triangles;
//! the leaf work (box cull and triangle tests) costs about an eighth of the
//! scalar instructions per ray.

use wide::f32x8;

use super::bvh::{Bvh, Frustum, MAX_DEPTH, MAX_PACKET, Node, PreparedRay, ROBUST_FAR, fmax};

/// Lanes per group.
const W: usize = 8;
/// Groups in a full packet.
const GROUPS: usize = MAX_PACKET / W;

/// Eight rays in structure-of-arrays form.
#[derive(Clone, Copy)]
struct Group {
    o: [f32x8; 3],
    inv: [f32x8; 3],
    /// All-ones lanes where the direction component is negative.
    neg: [f32x8; 3],
    shear: [f32x8; 3],
}

impl Group {
    const ZERO: Group = Group {
        o: [f32x8::ZERO; 3],
        inv: [f32x8::ONE; 3],
        neg: [f32x8::ZERO; 3],
        shear: [f32x8::ONE; 3],
    };

    /// Loads rays `8 g ..` of `rays` (missing lanes repeat the last ray; the
    /// caller gives them `t_max = -inf`, so they never enter a box or hit).
    fn load(rays: &[PreparedRay], g: usize) -> Group {
        let lanes: [&PreparedRay; W] =
            std::array::from_fn(|k| &rays[(g * W + k).min(rays.len() - 1)]);
        let all = f32::from_bits(u32::MAX);
        let mut group = Group::ZERO;
        for a in 0..3 {
            group.o[a] = f32x8::new(lanes.map(|r| r.origin[a]));
            group.inv[a] = f32x8::new(lanes.map(|r| r.inv[a]));
            group.neg[a] = f32x8::new(lanes.map(|r| if r.neg[a] == 1 { all } else { 0.0 }));
            group.shear[a] = f32x8::new(lanes.map(|r| r.shear[a]));
        }
        group
    }

    /// Lane mask (all-ones lanes) of the rays entering `n` before `t_max`;
    /// lane for lane the decision of the scalar `PreparedRay::enter`.
    #[inline(always)]
    fn enter(&self, n: &Node, t_max: f32x8) -> f32x8 {
        let mut near = [f32x8::ZERO; 3];
        let mut far = [f32x8::ZERO; 3];
        for a in 0..3 {
            let (lo, hi) = (f32x8::splat(n.min[a]), f32x8::splat(n.max[a]));
            near[a] = (self.neg[a].select(hi, lo) - self.o[a]) * self.inv[a];
            far[a] = (self.neg[a].select(lo, hi) - self.o[a]) * self.inv[a];
        }
        let rf = f32x8::splat(ROBUST_FAR);
        let t0 = near[0]
            .fast_max(near[1])
            .fast_max(near[2].fast_max(f32x8::ZERO));
        let t1 = (far[0].fast_min(far[1]) * rf).fast_min((far[2] * rf).fast_min(t_max));
        // The scalar test returns t0 (a miss when infinite) when t0 <= t1.
        t0.simd_le(t1) & t0.simd_lt(f32x8::INFINITY)
    }

    /// Watertight ray/triangle test (Woop et al. 2013) for dominant axis
    /// `KZ`, lane for lane the scalar `PreparedRay::triangle`: the mask of
    /// lanes hitting in `(t_min, t_max)` and their ray parameters.
    #[inline(always)]
    fn triangle<const KZ: usize>(
        &self,
        tri: &super::BvhTriangle,
        t_min: f32x8,
        t_max: f32x8,
    ) -> (f32x8, f32x8) {
        let kx = (KZ + 1) % 3;
        let ky = (KZ + 2) % 3;
        let o = &self.o;
        let [sx, sy, sz] = self.shear;
        let rel = |p: [f32; 3]| [0, 1, 2].map(|a| f32x8::splat(p[a]) - o[a]);
        let (a, b, c) = (rel(tri.a), rel(tri.b), rel(tri.c));
        let ax = a[kx] - sx * a[KZ];
        let ay = a[ky] - sy * a[KZ];
        let bx = b[kx] - sx * b[KZ];
        let by = b[ky] - sy * b[KZ];
        let cx = c[kx] - sx * c[KZ];
        let cy = c[ky] - sy * c[KZ];
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let z = f32x8::ZERO;
        let negative = u.simd_lt(z) | v.simd_lt(z) | w.simd_lt(z);
        let positive = u.simd_gt(z) | v.simd_gt(z) | w.simd_gt(z);
        let det = u + v + w;
        let t_scaled = u * (sz * a[KZ]) + v * (sz * b[KZ]) + w * (sz * c[KZ]);
        let t = t_scaled / det;
        let reject = (negative & positive) | det.simd_eq(z);
        let inside = t.simd_gt(t_min) & t.simd_lt(t_max);
        (reject.select(z, inside), t)
    }
}

/// Mask of lanes `>= k` (all-ones lanes).
fn lanes_from(k: usize) -> f32x8 {
    let all = f32::from_bits(u32::MAX);
    f32x8::new(std::array::from_fn(|i| if i >= k { all } else { 0.0 }))
}

/// The packet traversal of `Bvh::packet_kz::<KZ>` with 8-lane kernels; every
/// ray shares the dominant axis `KZ < 3`. `tmax` and `slot` as there (one
/// entry per ray, updated in place).
pub(super) fn packet<const KZ: usize>(
    bvh: &Bvh,
    rays: &[PreparedRay],
    t_min: f32,
    tmax: &mut [f32],
    slot: &mut [u32],
) {
    let n = rays.len();
    debug_assert!(n <= MAX_PACKET && tmax.len() == n && slot.len() == n);
    if n == 0 {
        return;
    }
    let groups = n.div_ceil(W);
    let g: [Group; GROUPS] = std::array::from_fn(|k| {
        if k < groups {
            Group::load(rays, k)
        } else {
            Group::ZERO
        }
    });
    let mut gt: [f32x8; GROUPS] = std::array::from_fn(|k| {
        f32x8::new(std::array::from_fn(|l| {
            tmax.get(k * W + l).copied().unwrap_or(f32::NEG_INFINITY)
        }))
    });
    let mut gs: [f32x8; GROUPS] = std::array::from_fn(|k| {
        f32x8::new(std::array::from_fn(|l| {
            f32::from_bits(slot.get(k * W + l).copied().unwrap_or(u32::MAX))
        }))
    });
    let t_min8 = f32x8::splat(t_min);
    let lane_from: [f32x8; W] = std::array::from_fn(lanes_from);
    let frustum = Frustum::of(rays);
    // Largest t_max of the packet (padding lanes hold -inf); only compared
    // against, so the order of the reduction does not matter.
    let packet_max = |gt: &[f32x8]| {
        gt[..groups]
            .iter()
            .fold(f32x8::ZERO, |m, v| m.fast_max(*v))
            .to_array()
            .into_iter()
            .fold(0.0f32, fmax)
    };
    let mut pmax = packet_max(&gt);
    let nodes = bvh.nodes();
    let triangles = bvh.triangles();
    let mut stack = [(0u32, 0u32); MAX_DEPTH + 4];
    let mut sp = 0usize;
    let mut node = 0usize;
    let mut first = 0usize;
    loop {
        let nd = &nodes[node];
        let mut visit = frustum.is_none_or(|f| f.enters(nd, pmax));
        if visit {
            // First ray at or after `first` that enters the node: usually
            // `first` itself (one scalar test), else a group at a time.
            while first < n
                && rays[first].enter(nd, gt[first / W].as_array()[first % W]) == f32::INFINITY
            {
                first += 1;
                if first.is_multiple_of(W) {
                    continue;
                }
                let k = first / W;
                let m = (g[k].enter(nd, gt[k]) & lane_from[first % W]).to_bitmask();
                if m != 0 {
                    first = k * W + m.trailing_zeros() as usize;
                    break;
                }
                first = ((k + 1) * W).min(n);
            }
            visit = first < n;
        }
        if visit {
            if nd.count > 0 {
                let s0 = nd.index as usize;
                let tris = &triangles[s0..s0 + nd.count as usize];
                for k in first / W..groups {
                    // Active-ray mask: rays of the range that enter the leaf's
                    // box before their closest hit so far.
                    let mut active = g[k].enter(nd, gt[k]);
                    if k == first / W {
                        active &= lane_from[first % W];
                    }
                    if !active.any() {
                        continue;
                    }
                    let (mut t, mut s) = (gt[k], gs[k]);
                    for (j, tri) in tris.iter().enumerate() {
                        let (hit, th) = g[k].triangle::<KZ>(tri, t_min8, t);
                        let hit = hit & active;
                        t = hit.select(th, t);
                        s = hit.select(f32x8::splat(f32::from_bits((s0 + j) as u32)), s);
                    }
                    gt[k] = t;
                    gs[k] = s;
                }
                pmax = packet_max(&gt);
            } else {
                let (near, far) = bvh.ordered_children(node, &rays[first]);
                stack[sp] = (far as u32, first as u32);
                sp += 1;
                node = near;
                continue;
            }
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        node = stack[sp].0 as usize;
        first = stack[sp].1 as usize;
    }
    for k in 0..groups {
        let (t, s) = (gt[k].to_array(), gs[k].to_array());
        for l in 0..W {
            let i = k * W + l;
            if i < n {
                tmax[i] = t[l];
                slot[i] = s[l].to_bits();
            }
        }
    }
}
