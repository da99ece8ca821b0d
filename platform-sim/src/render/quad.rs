//! Four-wide nodes for the tile kernel: the binary tree of [`super::Bvh`]
//! collapsed so that one node holds up to four children's boxes in
//! structure-of-arrays form, tested against a packet's frustum in one SIMD
//! step ([`QuadNode::frustum_test`]).
//!
//! # Collapse
//! Starting from a binary node's two children, the inner child with the
//! largest surface area is replaced by its own two children until there are
//! four or only leaves remain (Wald et al. 2008, "Getting rid of packets").
//! The leaves keep their triangle ranges of [`super::Bvh::triangles`], so the
//! 4-wide tree references exactly the binary tree's leaves.
//!
//! # Complexity
//! O(N) time and memory for a binary tree of N nodes; about N / 3 quad nodes.

use serde::{Deserialize, Serialize};
use wide::f32x4;

use super::bvh::{MAX_DEPTH, Node, ROBUST_FAR};

/// A child reference with this bit set is a leaf; bits 28-30 hold its
/// triangle count, bits 0-27 its first triangle slot.
pub(super) const LEAF: u32 = 1 << 31;
/// Largest triangle slot a leaf reference can hold.
const MAX_SLOT: usize = (1 << 28) - 1;

/// A 4-wide node (128 bytes): the boxes of up to four children, axis by
/// axis, and one reference per child (a quad node index, or a leaf). Unused
/// children have an empty box (`+inf .. -inf`), which no frustum enters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[repr(C, align(64))]
pub(super) struct QuadNode {
    /// `lo[axis][child]`.
    pub(super) lo: [[f32; 4]; 3],
    /// `hi[axis][child]`.
    pub(super) hi: [[f32; 4]; 3],
    /// Child references (see [`LEAF`]).
    pub(super) child: [u32; 4],
    _pad: [u32; 4],
}

impl QuadNode {
    const EMPTY: QuadNode = QuadNode {
        lo: [[f32::INFINITY; 4]; 3],
        hi: [[f32::NEG_INFINITY; 4]; 3],
        child: [LEAF; 4],
        _pad: [0; 4],
    };

    /// The box of child `i` as (lo, hi).
    #[inline(always)]
    pub(super) fn child_box(&self, i: usize) -> ([f32; 3], [f32; 3]) {
        (
            [self.lo[0][i], self.lo[1][i], self.lo[2][i]],
            [self.hi[0][i], self.hi[1][i], self.hi[2][i]],
        )
    }
}

/// Decodes a leaf reference into (first slot, count).
#[inline(always)]
pub(super) fn leaf_range(r: u32) -> (usize, usize) {
    ((r & 0x0fff_ffff) as usize, ((r >> 28) & 7) as usize)
}

/// The frustum of a packet of rays that share their origin and the sign of
/// each direction component: the origin, the per-axis range of the rays'
/// reciprocal directions and which box side each axis enters through.
#[derive(Debug, Clone, Copy)]
pub(super) struct QuadFrustum {
    /// The shared origin.
    pub(super) o: [f32; 3],
    /// Smallest reciprocal direction per axis.
    pub(super) imin: [f32; 3],
    /// Largest reciprocal direction per axis.
    pub(super) imax: [f32; 3],
    /// Per axis: the rays travel towards -axis (they enter boxes through
    /// `hi`).
    pub(super) neg: [bool; 3],
}

impl QuadFrustum {
    /// Which of the four children some ray of the frustum enters within
    /// `[t_min, t_max]` (bit `i` for child `i`), and the children's entry
    /// distances (a lower bound of every ray's entry; `+inf` or larger than
    /// the exit when missed).
    ///
    /// Interval arithmetic over the reciprocal range (Boulos et al. 2006),
    /// one SIMD lane per child: for a slab side at `c` (relative to the
    /// origin) the rays reach it between `min(c imin, c imax)` and
    /// `max(c imin, c imax)` (multiplication is monotonic in each operand
    /// under rounding, so this bounds the per-ray `c inv` exactly as the
    /// per-ray box test computes it). The far side is enlarged by
    /// `ROBUST_FAR` as in the per-ray test, so the cull is conservative.
    #[inline(always)]
    pub(super) fn test(&self, n: &QuadNode, t_min: f32, t_max: f32) -> (u32, [f32; 4]) {
        let mut tn = f32x4::splat(t_min);
        let mut tf = f32x4::splat(t_max);
        let rf = f32x4::splat(ROBUST_FAR);
        for a in 0..3 {
            let (near, far) = if self.neg[a] {
                (n.hi[a], n.lo[a])
            } else {
                (n.lo[a], n.hi[a])
            };
            let o = f32x4::splat(self.o[a]);
            let (imin, imax) = (f32x4::splat(self.imin[a]), f32x4::splat(self.imax[a]));
            let cn = f32x4::new(near) - o;
            let cf = f32x4::new(far) - o;
            tn = tn.fast_max((cn * imin).fast_min(cn * imax));
            tf = tf.fast_min((cf * imin).fast_max(cf * imax) * rf);
        }
        (tn.simd_le(tf).to_bitmask(), tn.to_array())
    }
}

/// Collapses the binary tree `nodes` (depth-first, left child next, as built
/// by `Bvh::build`) into quad nodes; root at index 0. Empty when a leaf's
/// first slot does not fit a leaf reference (more than 2^28 triangle
/// references), in which case the tile kernel is not used.
pub(super) fn collapse(nodes: &[Node]) -> Vec<QuadNode> {
    let mut out = Vec::with_capacity(nodes.len() / 3 + 1);
    if nodes.is_empty() {
        return out;
    }
    let ok = if nodes[0].count > 0 {
        // A single leaf: one quad node holding it.
        out.push(QuadNode::EMPTY);
        set_child(&mut out, 0, 0, nodes, 0, 1)
    } else {
        build(nodes, 0, &mut out, 1).map(|_| ())
    };
    if ok.is_none() {
        out.clear();
    }
    out
}

/// Surface area (half) of a binary node's box.
fn half_area(n: &Node) -> f32 {
    let e = [0, 1, 2].map(|a| n.max[a] - n.min[a]);
    e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
}

/// Writes the quad node of inner binary node `n` (and its subtree) into
/// `out`; returns its index, or `None` when a slot does not fit.
fn build(nodes: &[Node], n: usize, out: &mut Vec<QuadNode>, level: usize) -> Option<u32> {
    let mut kids: Vec<usize> = vec![n + 1, nodes[n].index as usize];
    while kids.len() < 4 {
        let widest = kids
            .iter()
            .enumerate()
            .filter(|(_, k)| nodes[**k].count == 0)
            .max_by(|a, b| half_area(&nodes[*a.1]).total_cmp(&half_area(&nodes[*b.1])))
            .map(|(i, _)| i);
        let Some(i) = widest else { break };
        let k = kids[i];
        kids[i] = k + 1;
        kids.push(nodes[k].index as usize);
    }
    let me = out.len();
    out.push(QuadNode::EMPTY);
    for (i, &k) in kids.iter().enumerate() {
        set_child(out, me, i, nodes, k, level)?;
    }
    Some(me as u32)
}

/// Sets child `i` of quad node `me` to binary node `k`.
fn set_child(
    out: &mut Vec<QuadNode>,
    me: usize,
    i: usize,
    nodes: &[Node],
    k: usize,
    level: usize,
) -> Option<()> {
    let nd = &nodes[k];
    let r = if nd.count > 0 {
        let slot = nd.index as usize;
        (slot <= MAX_SLOT && nd.count <= 7).then_some(LEAF | (nd.count << 28) | slot as u32)?
    } else if level >= MAX_DEPTH {
        // Unreachable for trees built by `Bvh::build` (depth <= MAX_DEPTH,
        // and a quad level spans at least one binary level).
        return None;
    } else {
        build(nodes, k, out, level + 1)?
    };
    let q = &mut out[me];
    for a in 0..3 {
        q.lo[a][i] = nd.min[a];
        q.hi[a][i] = nd.max[a];
    }
    q.child[i] = r;
    Some(())
}
