//! A compact bounding volume hierarchy over plain triangle data, for the
//! camera's primary rays.
//!
//! # Why not parry's BVH
//! parry3d's `TriMesh::cast_local_ray` measured 3.8-5.7 M rays/s on one core for
//! 640x480 primary rays on `house_tess40.obj` (518k triangles); the target
//! is Embree 3's single-ray figure on the same mesh, 9.7 M rays/s. This BVH is
//! built for that workload:
//!
//! * **split references** for large triangles (early split clipping, Ernst and
//!   Greiner 2007): a triangle much larger than the scene's detail (walls and
//!   floor slabs of a house span several rooms) is referenced from several
//!   leaves, each with the bounds of the triangle clipped to one cell of a
//!   grid over its box. The geometry is not changed (no new vertices, so no
//!   T-junction cracks); only the boxes get tight, which keeps rays from
//!   visiting every wall of the house;
//! * **binned SAH build** (16 bins per axis on centroid bounds, Wald 2007), leaves
//!   of at most [`MAX_LEAF`] triangles;
//! * **flattened nodes** of 32 bytes (two per cache line) in depth-first order, the
//!   left child stored right after its parent;
//! * triangles **reordered into leaf order** and stored as their three vertices
//!   plus a payload (48 bytes), so a leaf is one contiguous read;
//! * **ray packets** ([`Bvh::intersect_packet`], what the camera uses for 8x8
//!   pixel tiles): ranged traversal with a first-active-ray index, an
//!   interval-arithmetic frustum cull, and a per-ray box cull in the leaves.
//!   With ordered single rays ([`Bvh::intersect`]) this mesh took 24 node
//!   visits and 2 triangle tests per ray, but two box tests per visited node
//!   held it near 3 M rays/s on one core. A packet shares node fetches and box
//!   tests across 64 coherent rays, which lifts it to 13-15 M rays/s;
//! * **8-lane SIMD kernels** for the packets (`packet8`, safe code on
//!   `wide::f32x8`): the first-active-ray search, the leaf box cull (an
//!   active-ray mask per group of 8 rays; groups without an active ray skip
//!   the leaf) and the triangle test run over 8 rays at once. The traversal
//!   order is the scalar one node for node and every lane repeats the
//!   scalar IEEE operations, so the results equal
//!   [`Bvh::intersect_packet_scalar`] bit for bit (tested on random soups
//!   and camera tiles);
//! * **a 4-wide copy of the tree** for the camera's **tile kernel** (module
//!   `tile`; what [`super::Camera`] uses): quad nodes tested against a
//!   tile's frustum in one SIMD step, rays made and tested 8 per AVX2
//!   instruction (run-time detected). About 3x the throughput of the packet
//!   path; see the crate README;
//! * **ordered single-ray traversal** for incoherent queries (nearest child
//!   first, far child skipped once a closer hit is known), with a per-ray
//!   precomputed reciprocal direction and a stack on the call frame;
//! * the **watertight ray/triangle test** of Woop, Benthin and Wald (JCGT 2013),
//!   specialised at compile time for the ray's dominant axis, so rays through a
//!   shared edge or vertex never fall between two triangles (no holes on
//!   axis-aligned, finely tessellated meshes), and robust box tests (the far
//!   slab distance is enlarged by `1 + 2 gamma(3)`, Ize 2013) so flat boxes of
//!   axis-aligned faces are never missed.
//!
//! Measured figures are in the crate README (`examples/bench_render.rs`).

use serde::{Deserialize, Serialize};

use super::RenderError;

/// Largest number of triangles in a leaf.
pub const MAX_LEAF: usize = 4;
/// Number of SAH bins per axis.
const BINS: usize = 16;
/// Relative enlargement of the far slab distance that makes box tests
/// conservative under f32 rounding (`1 + 2 gamma(3)`, Ize 2013).
pub(super) const ROBUST_FAR: f32 =
    1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// `max` as one instruction (operands are never NaN here: reciprocals are
/// clamped to finite values).
#[inline(always)]
pub(super) fn fmax(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// `min` as one instruction (see [`fmax`]).
#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// Largest number of rays traversed together by [`Bvh::intersect_packet`].
pub const MAX_PACKET: usize = 64;

/// Axis-aligned box in f32.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
struct Bounds {
    min: [f32; 3],
    max: [f32; 3],
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        min: [f32::INFINITY; 3],
        max: [f32::NEG_INFINITY; 3],
    };

    fn grow_point(&mut self, p: [f32; 3]) {
        for ((lo, hi), c) in self.min.iter_mut().zip(self.max.iter_mut()).zip(p) {
            *lo = lo.min(c);
            *hi = hi.max(c);
        }
    }

    fn grow(&mut self, b: &Bounds) {
        for a in 0..3 {
            self.min[a] = self.min[a].min(b.min[a]);
            self.max[a] = self.max[a].max(b.max[a]);
        }
    }

    /// Extent along each axis.
    fn extent(&self) -> [f32; 3] {
        [0, 1, 2].map(|a| self.max[a] - self.min[a])
    }

    /// Centre of the box.
    fn centre(&self) -> [f32; 3] {
        [0, 1, 2].map(|a| 0.5 * (self.min[a] + self.max[a]))
    }

    /// Half the surface area (enough for SAH ratios); 0 for empty boxes.
    fn half_area(&self) -> f32 {
        let e = self.extent();
        if e.iter().any(|x| x.is_nan() || *x < 0.0) {
            return 0.0;
        }
        e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
    }
}

/// A flattened BVH node (32 bytes). Inner nodes: the left child is the next
/// node, `index` is the right child, `count == 0`. Leaves: triangles
/// `index..index + count` of [`Bvh::triangles`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(super) struct Node {
    pub(super) min: [f32; 3],
    pub(super) index: u32,
    pub(super) max: [f32; 3],
    pub(super) count: u32,
}

/// A triangle in leaf order: its vertices and two payloads (48 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BvhTriangle {
    /// First vertex.
    pub a: [f32; 3],
    /// Second vertex.
    pub b: [f32; 3],
    /// Third vertex.
    pub c: [f32; 3],
    /// Index of the triangle in the input.
    pub index: u32,
    /// Caller payload (the instance id for scenes, the label for OBJ groups).
    pub payload: u32,
    _pad: u32,
}

/// The closest intersection of a ray with the triangles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BvhHit {
    /// Ray parameter: the hit point is `origin + t * dir` (`dir` as given, not
    /// normalised).
    pub t: f32,
    /// Index of the triangle in the input order.
    pub triangle: u32,
    /// Payload of that triangle.
    pub payload: u32,
    /// Position of the triangle in [`Bvh::triangles`] (leaf order).
    pub slot: u32,
}

/// A ray prepared for traversal.
#[derive(Debug, Clone, Copy)]
pub struct PreparedRay {
    pub(super) origin: [f32; 3],
    pub(super) dir: [f32; 3],
    pub(super) inv: [f32; 3],
    /// Sign of each direction component (1 when negative).
    pub(super) neg: [usize; 3],
    /// Dominant axis of the direction (Woop's kz).
    pub(super) kz: usize,
    /// Shear constants (Woop's Sx, Sy, Sz).
    pub(super) shear: [f32; 3],
}

impl PreparedRay {
    /// A placeholder ray (origin 0, direction +x) for initialising arrays.
    pub const DUMMY: PreparedRay = PreparedRay {
        origin: [0.0; 3],
        dir: [1.0, 0.0, 0.0],
        inv: [1.0, 1.0e30, 1.0e30],
        neg: [0; 3],
        kz: 0,
        shear: [0.0, 0.0, 1.0],
    };

    /// The ray's origin.
    pub fn origin(&self) -> [f32; 3] {
        self.origin
    }

    /// The ray's direction (as given, not normalised).
    pub fn direction(&self) -> [f32; 3] {
        self.dir
    }

    /// Prepares a ray for [`Bvh::intersect_prepared`]; `None` for a zero or
    /// non-finite direction or a non-finite origin.
    #[inline]
    pub fn new(origin: [f32; 3], dir: [f32; 3]) -> Option<PreparedRay> {
        if !origin.iter().chain(dir.iter()).all(|c| c.is_finite()) || dir.iter().all(|c| *c == 0.0)
        {
            return None;
        }
        let kz = largest_axis(dir.map(f32::abs));
        let kx = (kz + 1) % 3;
        let ky = (kz + 2) % 3;
        let sz = 1.0 / dir[kz];
        let shear = [dir[kx] * sz, dir[ky] * sz, sz];
        // A zero component gives an infinite reciprocal; replace it by a huge
        // finite one so that `0 * inv` never produces NaN in the slab test.
        let inv = dir.map(|d| {
            if d == 0.0 {
                1.0e30
            } else {
                let r = 1.0 / d;
                r.clamp(-1.0e30, 1.0e30)
            }
        });
        let neg = dir.map(|d| usize::from(d < 0.0));
        Some(PreparedRay {
            origin,
            dir,
            inv,
            neg,
            kz,
            shear,
        })
    }

    /// Entry distance of the ray into a node's box, or `f32::INFINITY` on a miss.
    #[inline(always)]
    pub(super) fn enter(&self, n: &Node, t_max: f32) -> f32 {
        let lo = |a: usize| if self.neg[a] == 0 { n.min[a] } else { n.max[a] };
        let hi = |a: usize| if self.neg[a] == 0 { n.max[a] } else { n.min[a] };
        let tx0 = (lo(0) - self.origin[0]) * self.inv[0];
        let tx1 = (hi(0) - self.origin[0]) * self.inv[0];
        let ty0 = (lo(1) - self.origin[1]) * self.inv[1];
        let ty1 = (hi(1) - self.origin[1]) * self.inv[1];
        let tz0 = (lo(2) - self.origin[2]) * self.inv[2];
        let tz1 = (hi(2) - self.origin[2]) * self.inv[2];
        let t0 = fmax(fmax(tx0, ty0), fmax(tz0, 0.0));
        let t1 = fmin(fmin(tx1, ty1) * ROBUST_FAR, fmin(tz1 * ROBUST_FAR, t_max));
        if t0 <= t1 { t0 } else { f32::INFINITY }
    }

    /// Watertight ray/triangle test (Woop et al. 2013) for dominant axis `KZ`;
    /// returns the ray parameter if the triangle is hit in `(t_min, t_max)`.
    #[inline(always)]
    fn triangle<const KZ: usize>(&self, tri: &BvhTriangle, t_min: f32, t_max: f32) -> Option<f32> {
        let kx = (KZ + 1) % 3;
        let ky = (KZ + 2) % 3;
        let o = self.origin;
        let [sx, sy, sz] = self.shear;
        let a = [tri.a[0] - o[0], tri.a[1] - o[1], tri.a[2] - o[2]];
        let b = [tri.b[0] - o[0], tri.b[1] - o[1], tri.b[2] - o[2]];
        let c = [tri.c[0] - o[0], tri.c[1] - o[1], tri.c[2] - o[2]];
        let ax = a[kx] - sx * a[KZ];
        let ay = a[ky] - sy * a[KZ];
        let bx = b[kx] - sx * b[KZ];
        let by = b[ky] - sy * b[KZ];
        let cx = c[kx] - sx * c[KZ];
        let cy = c[ky] - sy * c[KZ];
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t_scaled = u * (sz * a[KZ]) + v * (sz * b[KZ]) + w * (sz * c[KZ]);
        let t = t_scaled / det;
        (t > t_min && t < t_max).then_some(t)
    }
}

/// Bounding volume hierarchy over a triangle soup (see the module docs).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// The same tree with 4-wide nodes, for the camera's tile kernel (empty
    /// when it cannot be built; the kernel then declines every tile).
    quads: Vec<super::quad::QuadNode>,
    triangles: Vec<BvhTriangle>,
    depth: usize,
    input_triangles: usize,
}

/// Build-time record of one triangle.
#[derive(Clone, Copy)]
struct Prim {
    bounds: Bounds,
    centroid: [f32; 3],
    index: u32,
}

impl Bvh {
    /// Builds the hierarchy over `triangles` (indices into `vertices`), with one
    /// payload per triangle (for scenes: the instance id).
    ///
    /// Degenerate triangles (zero area) are kept: the intersection test never
    /// reports them.
    ///
    /// # Errors
    /// [`RenderError::EmptyMesh`] without triangles, [`RenderError::Mesh`] when
    /// `payloads` has the wrong length, an index is out of range or a used
    /// vertex is not finite.
    ///
    /// # Complexity
    /// O(T log T) time and O(T) memory for T triangles (binned SAH with a
    /// constant number of bins per level).
    pub fn build(
        vertices: &[[f32; 3]],
        triangles: &[[u32; 3]],
        payloads: &[u32],
    ) -> Result<Bvh, RenderError> {
        if triangles.is_empty() {
            return Err(RenderError::EmptyMesh);
        }
        if payloads.len() != triangles.len() {
            return Err(RenderError::Mesh(format!(
                "{} triangles but {} payloads",
                triangles.len(),
                payloads.len()
            )));
        }
        if u32::try_from(triangles.len()).is_err() {
            return Err(RenderError::Mesh("more than u32::MAX triangles".into()));
        }
        let mut refs = Vec::with_capacity(triangles.len());
        for (i, t) in triangles.iter().enumerate() {
            let mut bounds = Bounds::EMPTY;
            for &vi in t {
                let v = vertices.get(vi as usize).ok_or_else(|| {
                    RenderError::Mesh(format!("triangle {i} indexes missing vertex {vi}"))
                })?;
                if !v.iter().all(|c| c.is_finite()) {
                    return Err(RenderError::Mesh(format!("vertex {vi} is not finite")));
                }
                bounds.grow_point(*v);
            }
            refs.push(Prim {
                bounds,
                centroid: bounds.centre(),
                index: i as u32,
            });
        }
        let mut prims = split_references(refs, vertices, triangles);
        let mut nodes = Vec::with_capacity(2 * prims.len() / MAX_LEAF + 1);
        let mut depth = 0;
        build_range(&mut prims, 0, &mut nodes, 1, &mut depth);
        let tris = prims
            .iter()
            .map(|p| {
                let t = triangles[p.index as usize];
                BvhTriangle {
                    a: vertices[t[0] as usize],
                    b: vertices[t[1] as usize],
                    c: vertices[t[2] as usize],
                    index: p.index,
                    payload: payloads[p.index as usize],
                    _pad: 0,
                }
            })
            .collect();
        Ok(Bvh {
            quads: super::quad::collapse(&nodes),
            nodes,
            triangles: tris,
            depth,
            input_triangles: triangles.len(),
        })
    }

    /// Number of input triangles.
    pub fn triangle_count(&self) -> usize {
        self.input_triangles
    }

    /// Number of triangle references in the leaves (at least
    /// [`Bvh::triangle_count`]; more when large triangles were split).
    pub fn reference_count(&self) -> usize {
        self.triangles.len()
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Depth of the tree (1 for a single leaf).
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// Triangle references in leaf order.
    pub fn triangles(&self) -> &[BvhTriangle] {
        &self.triangles
    }

    /// Closest hit of the ray `origin + t dir`, `t` in `(t_min, t_max)`.
    /// Returns `None` for a miss or an invalid ray (zero or non-finite).
    ///
    /// # Complexity
    /// O(log T) expected for T triangles; O(T) worst case.
    pub fn intersect(
        &self,
        origin: [f32; 3],
        dir: [f32; 3],
        t_min: f32,
        t_max: f32,
    ) -> Option<BvhHit> {
        let ray = PreparedRay::new(origin, dir)?;
        self.intersect_prepared(&ray, t_min, t_max)
    }

    /// [`Bvh::intersect`] for a ray prepared once.
    ///
    /// # Complexity
    /// O(log T) expected; O(T) worst case.
    pub fn intersect_prepared(&self, ray: &PreparedRay, t_min: f32, t_max: f32) -> Option<BvhHit> {
        if t_max.is_nan() || t_min.is_nan() || t_max <= t_min {
            return None;
        }
        match ray.kz {
            0 => self.traverse::<0>(ray, t_min, t_max),
            1 => self.traverse::<1>(ray, t_min, t_max),
            _ => self.traverse::<2>(ray, t_min, t_max),
        }
    }

    fn hit_at(&self, slot: usize, t: f32) -> BvhHit {
        let tri = &self.triangles[slot];
        BvhHit {
            t,
            triangle: tri.index,
            payload: tri.payload,
            slot: slot as u32,
        }
    }

    /// Closest hits of a packet of coherent rays (for example an 8x8 pixel
    /// tile of primary rays), traversed together: `out[i]` receives the hit of
    /// `rays[i]` in `(t_min, t_max)`. Packets longer than [`MAX_PACKET`] are
    /// processed in chunks. Results equal those of [`Bvh::intersect_prepared`]
    /// ray by ray (up to ties: two triangles at exactly the same distance, or
    /// one large triangle referenced from several leaves, may be reported
    /// through a different triangle or leaf slot), and those of
    /// [`Bvh::intersect_packet_scalar`] bit for bit (same `t`, same slot).
    ///
    /// # Algorithm
    /// Ranged packet traversal (Wald et al. 2001; Overbeck, Ramamoorthi and
    /// Mark 2008): the packet descends the tree with the index of its first
    /// active ray; a node is culled at once by an interval-arithmetic frustum
    /// test (Boulos et al. 2006) when all rays share their origin and direction
    /// signs, otherwise rays are tested in order until one enters the node, and
    /// rays before it are inactive below it. Children are ordered by the first
    /// active ray. Node fetches and box tests are shared by the whole packet.
    /// When all rays share their dominant axis (camera tiles, but for the few
    /// where it changes), the per-ray work runs on 8 rays at a time (see the
    /// module docs); otherwise rays are tested one by one.
    ///
    /// # Panics
    /// Never; `out` shorter than `rays` only receives the first `out.len()` results.
    ///
    /// # Complexity
    /// O(P log T) expected for P rays and T triangles, with the node work
    /// shared across coherent rays.
    pub fn intersect_packet(
        &self,
        rays: &[PreparedRay],
        t_min: f32,
        t_max: f32,
        out: &mut [Option<BvhHit>],
    ) {
        self.packet_chunks(rays, t_min, t_max, out, true);
    }

    /// [`Bvh::intersect_packet`] with the scalar kernels only: the same ranged
    /// traversal, rays tested one by one in the leaves. This is the reference
    /// the 8-lane SIMD path is checked against bit for bit (same `t`, same
    /// leaf slot for every ray); it is also what packets whose rays do not
    /// share their dominant axis use.
    ///
    /// # Complexity
    /// As [`Bvh::intersect_packet`].
    pub fn intersect_packet_scalar(
        &self,
        rays: &[PreparedRay],
        t_min: f32,
        t_max: f32,
        out: &mut [Option<BvhHit>],
    ) {
        self.packet_chunks(rays, t_min, t_max, out, false);
    }

    fn packet_chunks(
        &self,
        rays: &[PreparedRay],
        t_min: f32,
        t_max: f32,
        out: &mut [Option<BvhHit>],
        simd: bool,
    ) {
        for (rays, out) in rays.chunks(MAX_PACKET).zip(out.chunks_mut(MAX_PACKET)) {
            let n = rays.len().min(out.len());
            let mut tmax = [t_max; MAX_PACKET];
            let mut slot = [u32::MAX; MAX_PACKET];
            if t_max > t_min {
                self.packet(&rays[..n], t_min, &mut tmax[..n], &mut slot[..n], simd);
            }
            for i in 0..n {
                out[i] = (slot[i] != u32::MAX).then(|| self.hit_at(slot[i] as usize, tmax[i]));
            }
        }
    }

    /// The 4-wide nodes (for the tile kernel).
    pub(super) fn quads(&self) -> &[super::quad::QuadNode] {
        &self.quads
    }

    /// The flattened nodes (for the SIMD kernels).
    pub(super) fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    fn packet(
        &self,
        rays: &[PreparedRay],
        t_min: f32,
        tmax: &mut [f32],
        slot: &mut [u32],
        simd: bool,
    ) {
        let Some(r0) = rays.first() else { return };
        // Specialise the triangle test once when all rays share their dominant
        // axis (nearly always for camera tiles); 3 = per-ray dispatch.
        match (rays.iter().all(|r| r.kz == r0.kz).then_some(r0.kz), simd) {
            (Some(0), true) => super::packet8::packet::<0>(self, rays, t_min, tmax, slot),
            (Some(1), true) => super::packet8::packet::<1>(self, rays, t_min, tmax, slot),
            (Some(_), true) => super::packet8::packet::<2>(self, rays, t_min, tmax, slot),
            (Some(0), false) => self.packet_kz::<0>(rays, t_min, tmax, slot),
            (Some(1), false) => self.packet_kz::<1>(rays, t_min, tmax, slot),
            (Some(_), false) => self.packet_kz::<2>(rays, t_min, tmax, slot),
            (None, _) => self.packet_kz::<3>(rays, t_min, tmax, slot),
        }
    }

    fn packet_kz<const KZ: usize>(
        &self,
        rays: &[PreparedRay],
        t_min: f32,
        tmax: &mut [f32],
        slot: &mut [u32],
    ) {
        let n = rays.len();
        let frustum = Frustum::of(rays);
        let packet_max = |tmax: &[f32]| tmax.iter().fold(0.0f32, |m, &t| fmax(m, t));
        let mut pmax = packet_max(tmax);
        let mut stack = [(0u32, 0u32); MAX_DEPTH + 4];
        let mut sp = 0usize;
        let mut node = 0usize;
        let mut first = 0usize;
        loop {
            let nd = &self.nodes[node];
            let mut visit = frustum.is_none_or(|f| f.enters(nd, pmax));
            if visit {
                while first < n && rays[first].enter(nd, tmax[first]) == f32::INFINITY {
                    first += 1;
                }
                visit = first < n;
            }
            if visit {
                if nd.count > 0 {
                    let s0 = nd.index as usize;
                    let tris = &self.triangles[s0..s0 + nd.count as usize];
                    for j in first..n {
                        let r = &rays[j];
                        // Per-ray cull: rays that miss the leaf's box, or hit
                        // something closer already, skip its triangles.
                        if j > first && r.enter(nd, tmax[j]) == f32::INFINITY {
                            continue;
                        }
                        for (k, tri) in tris.iter().enumerate() {
                            let h = match if KZ < 3 { KZ } else { r.kz } {
                                0 => r.triangle::<0>(tri, t_min, tmax[j]),
                                1 => r.triangle::<1>(tri, t_min, tmax[j]),
                                _ => r.triangle::<2>(tri, t_min, tmax[j]),
                            };
                            if let Some(t) = h {
                                tmax[j] = t;
                                slot[j] = (s0 + k) as u32;
                            }
                        }
                    }
                    pmax = packet_max(tmax);
                } else {
                    let (near, far) = self.ordered_children(node, &rays[first]);
                    stack[sp] = (far as u32, first as u32);
                    sp += 1;
                    node = near;
                    continue;
                }
            }
            if sp == 0 {
                return;
            }
            sp -= 1;
            node = stack[sp].0 as usize;
            first = stack[sp].1 as usize;
        }
    }

    /// The children of inner node `node` as (near, far): ordered by the
    /// entry distance of `ray` into their boxes (left first on ties).
    #[inline(always)]
    pub(super) fn ordered_children(&self, node: usize, ray: &PreparedRay) -> (usize, usize) {
        let left = node + 1;
        let right = self.nodes[node].index as usize;
        let tl = ray.enter(&self.nodes[left], f32::INFINITY);
        let tr = ray.enter(&self.nodes[right], f32::INFINITY);
        if tl <= tr {
            (left, right)
        } else {
            (right, left)
        }
    }

    fn traverse<const KZ: usize>(
        &self,
        ray: &PreparedRay,
        t_min: f32,
        t_max: f32,
    ) -> Option<BvhHit> {
        let nodes = &self.nodes[..];
        let mut best_t = t_max;
        let mut best: Option<usize> = None;
        let mut stack = [0u32; MAX_DEPTH + 4];
        let mut sp = 0usize;
        let mut node = 0usize;
        if ray.enter(&nodes[0], best_t) == f32::INFINITY {
            return None;
        }
        loop {
            let n = &nodes[node];
            if n.count > 0 {
                let first = n.index as usize;
                for (k, tri) in self.triangles[first..first + n.count as usize]
                    .iter()
                    .enumerate()
                {
                    if let Some(t) = ray.triangle::<KZ>(tri, t_min, best_t) {
                        best_t = t;
                        best = Some(first + k);
                    }
                }
            } else {
                let left = node + 1;
                let right = n.index as usize;
                let tl = ray.enter(&nodes[left], best_t);
                let tr = ray.enter(&nodes[right], best_t);
                match (tl < f32::INFINITY, tr < f32::INFINITY) {
                    (true, true) => {
                        let (near, far) = if tl <= tr {
                            (left, right)
                        } else {
                            (right, left)
                        };
                        // The depth-limited build keeps the stack within bounds.
                        stack[sp] = far as u32;
                        sp += 1;
                        node = near;
                        continue;
                    }
                    (true, false) => {
                        node = left;
                        continue;
                    }
                    (false, true) => {
                        node = right;
                        continue;
                    }
                    (false, false) => {}
                }
            }
            // Pop the next node that the current best hit does not prune.
            loop {
                if sp == 0 {
                    return best.map(|i| self.hit_at(i, best_t));
                }
                sp -= 1;
                let cand = stack[sp] as usize;
                if ray.enter(&nodes[cand], best_t) < f32::INFINITY {
                    node = cand;
                    break;
                }
            }
        }
    }
}

/// The frustum of a packet whose rays share their origin and the signs of
/// their direction components: the origin and per-axis bounds of the
/// reciprocal directions.
#[derive(Debug, Clone, Copy)]
pub(super) struct Frustum {
    o: [f32; 3],
    imin: [f32; 3],
    imax: [f32; 3],
}

impl Frustum {
    /// The packet's frustum, or `None` when the rays do not share their
    /// origin and direction signs (no frustum cull then).
    pub(super) fn of(rays: &[PreparedRay]) -> Option<Frustum> {
        let o = rays.first()?.origin;
        let mut imin = [f32::INFINITY; 3];
        let mut imax = [f32::NEG_INFINITY; 3];
        for r in rays {
            for a in 0..3 {
                imin[a] = fmin(r.inv[a], imin[a]);
                imax[a] = fmax(r.inv[a], imax[a]);
            }
        }
        (rays.iter().all(|r| r.origin == o) && (0..3).all(|a| (imin[a] > 0.0) == (imax[a] > 0.0)))
            .then_some(Frustum { o, imin, imax })
    }

    /// Interval-arithmetic frustum test (Boulos et al. 2006): false only if
    /// no ray with this origin and reciprocal directions in `[imin, imax]`
    /// (same sign per axis) enters the node's box before `t_max`.
    #[inline(always)]
    pub(super) fn enters(&self, nd: &Node, t_max: f32) -> bool {
        let (o, imin, imax) = (&self.o, &self.imin, &self.imax);
        let mut tn = 0.0f32;
        let mut tf = t_max;
        for a in 0..3 {
            let c0 = nd.min[a] - o[a];
            let c1 = nd.max[a] - o[a];
            // Smallest and largest of c * inv over inv in [imin, imax].
            let lo = |c: f32| if c >= 0.0 { c * imin[a] } else { c * imax[a] };
            let hi = |c: f32| if c >= 0.0 { c * imax[a] } else { c * imin[a] };
            let (near, far) = if imin[a] > 0.0 {
                (lo(c0), hi(c1))
            } else {
                (lo(c1), hi(c0))
            };
            tn = fmax(tn, near);
            tf = fmin(tf, far * ROBUST_FAR);
        }
        tn <= tf
    }
}

/// Maximum tree depth; the traversal stack holds one entry per level.
pub(super) const MAX_DEPTH: usize = 60;

/// Scene diagonal / this = the largest box extent a triangle reference may keep.
const SPLIT_DIVISOR: f64 = 32.0;
/// Most cells a single triangle is split into.
const MAX_SPLIT_CELLS: usize = 4096;

/// Replaces the references of triangles larger than the split threshold by
/// one reference per grid cell their surface crosses, with the bounds of the
/// triangle clipped to the cell (computed in f64, rounded outwards, then
/// enlarged by a relative epsilon so that the pieces cover the triangle).
/// At most 4 T + 65,536 references are made in total.
fn split_references(prims: Vec<Prim>, vertices: &[[f32; 3]], triangles: &[[u32; 3]]) -> Vec<Prim> {
    let mut scene = Bounds::EMPTY;
    for p in &prims {
        scene.grow(&p.bounds);
    }
    let diag = (0..3)
        .map(|a| f64::from(scene.max[a] - scene.min[a]).powi(2))
        .sum::<f64>()
        .sqrt();
    let limit = diag / SPLIT_DIVISOR;
    if !(limit.is_finite() && limit > 0.0) {
        return prims;
    }
    let eps = (diag * 1e-6) as f32;
    let mut budget = 3 * prims.len() + 65_536;
    let mut out = Vec::with_capacity(prims.len());
    for p in prims {
        let ext = p.bounds.extent().map(f64::from);
        let k = ext.map(|e| ((e / limit).ceil() as usize).clamp(1, 64));
        let cells = k[0] * k[1] * k[2];
        if cells <= 1 || cells > MAX_SPLIT_CELLS || cells > budget {
            out.push(p);
            continue;
        }
        let t = triangles[p.index as usize];
        let tri: Vec<[f64; 3]> = t
            .iter()
            .map(|&v| vertices[v as usize].map(f64::from))
            .collect();
        let lo = p.bounds.min.map(f64::from);
        let edge = |a: usize, i: usize| {
            if i == k[a] {
                f64::from(p.bounds.max[a])
            } else {
                lo[a] + ext[a] * i as f64 / k[a] as f64
            }
        };
        let before = out.len();
        for i in 0..k[0] {
            for j in 0..k[1] {
                for l in 0..k[2] {
                    let cell_lo = [edge(0, i), edge(1, j), edge(2, l)];
                    let cell_hi = [edge(0, i + 1), edge(1, j + 1), edge(2, l + 1)];
                    let Some(b) = clip_bounds(&tri, &cell_lo, &cell_hi) else {
                        continue;
                    };
                    let bounds = Bounds {
                        min: [0, 1, 2].map(|a| ((b.0[a] as f32) - eps).max(p.bounds.min[a])),
                        max: [0, 1, 2].map(|a| ((b.1[a] as f32) + eps).min(p.bounds.max[a])),
                    };
                    out.push(Prim {
                        bounds,
                        centroid: bounds.centre(),
                        index: p.index,
                    });
                }
            }
        }
        if out.len() == before {
            // Numerical corner case: keep the whole triangle.
            out.push(p);
        }
        budget = budget.saturating_sub(out.len() - before);
    }
    out
}

/// Bounds of a convex polygon clipped to the box `[lo, hi]`, or `None` when
/// nothing remains (Sutherland-Hodgman against the six planes).
fn clip_bounds(poly: &[[f64; 3]], lo: &[f64; 3], hi: &[f64; 3]) -> Option<([f64; 3], [f64; 3])> {
    let mut cur: Vec<[f64; 3]> = poly.to_vec();
    for a in 0..3 {
        for (c, keep_above) in [(lo[a], true), (hi[a], false)] {
            let inside = |p: &[f64; 3]| if keep_above { p[a] >= c } else { p[a] <= c };
            let mut next = Vec::with_capacity(cur.len() + 2);
            for (i, p) in cur.iter().enumerate() {
                let q = &cur[(i + 1) % cur.len()];
                let (pi, qi) = (inside(p), inside(q));
                if pi {
                    next.push(*p);
                }
                if pi != qi {
                    let t = (c - p[a]) / (q[a] - p[a]);
                    let mut x = [0.0; 3];
                    for (d, xd) in x.iter_mut().enumerate() {
                        *xd = p[d] + (q[d] - p[d]) * t;
                    }
                    x[a] = c;
                    next.push(x);
                }
            }
            if next.is_empty() {
                return None;
            }
            cur = next;
        }
    }
    let mut bmin = [f64::INFINITY; 3];
    let mut bmax = [f64::NEG_INFINITY; 3];
    for p in &cur {
        for a in 0..3 {
            bmin[a] = bmin[a].min(p[a]);
            bmax[a] = bmax[a].max(p[a]);
        }
    }
    Some((bmin, bmax))
}

/// Builds the subtree over `prims` (which start at `offset` of the final
/// triangle order) into `nodes`, depth-first; returns its node index.
fn build_range(
    prims: &mut [Prim],
    offset: usize,
    nodes: &mut Vec<Node>,
    level: usize,
    depth: &mut usize,
) -> usize {
    *depth = (*depth).max(level);
    let mut bounds = Bounds::EMPTY;
    let mut cbounds = Bounds::EMPTY;
    for p in prims.iter() {
        bounds.grow(&p.bounds);
        cbounds.grow_point(p.centroid);
    }
    let me = nodes.len();
    nodes.push(Node {
        min: bounds.min,
        index: offset as u32,
        max: bounds.max,
        count: prims.len() as u32,
    });
    // At the depth limit (only reachable with pathological inputs, since every
    // split at least halves or SAH-partitions the set) the node stays a leaf,
    // which keeps the traversal stack bounded.
    if prims.len() <= 1 || level >= MAX_DEPTH {
        return me;
    }
    let mid = match sah_split(prims, &bounds, &cbounds) {
        Some(m) => m,
        None if prims.len() <= MAX_LEAF => return me,
        // All centroids coincide (or SAH found no split): median split on the
        // widest centroid axis.
        None => {
            let axis = widest(&cbounds);
            let mid = prims.len() / 2;
            prims.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
            mid
        }
    };
    let (lo, hi) = prims.split_at_mut(mid);
    build_range(lo, offset, nodes, level + 1, depth);
    let right = build_range(hi, offset + mid, nodes, level + 1, depth);
    nodes[me].index = right as u32;
    nodes[me].count = 0;
    me
}

fn widest(b: &Bounds) -> usize {
    largest_axis(b.extent())
}

/// Index of the largest of `e` (the first one on ties).
fn largest_axis(e: [f32; 3]) -> usize {
    if e[0] >= e[1] && e[0] >= e[2] {
        0
    } else if e[1] >= e[2] {
        1
    } else {
        2
    }
}

/// Binned SAH: partitions `prims` and returns the split index, or `None` when
/// a leaf is cheaper (only allowed for at most [`MAX_LEAF`] triangles) or all
/// centroids coincide.
fn sah_split(prims: &mut [Prim], bounds: &Bounds, cbounds: &Bounds) -> Option<usize> {
    let n = prims.len();
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bin)
    for axis in 0..3 {
        let lo = cbounds.min[axis];
        let extent = cbounds.max[axis] - lo;
        if extent.is_nan() || extent <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / extent;
        let mut bin_bounds = [Bounds::EMPTY; BINS];
        let mut bin_count = [0usize; BINS];
        for p in prims.iter() {
            let b = (((p.centroid[axis] - lo) * scale) as usize).min(BINS - 1);
            bin_count[b] += 1;
            bin_bounds[b].grow(&p.bounds);
        }
        // Sweep from the right to get suffix areas and counts.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0usize; BINS];
        let mut acc = Bounds::EMPTY;
        let mut cnt = 0;
        for b in (1..BINS).rev() {
            acc.grow(&bin_bounds[b]);
            cnt += bin_count[b];
            right_area[b] = acc.half_area();
            right_count[b] = cnt;
        }
        let mut acc = Bounds::EMPTY;
        let mut cnt = 0;
        for b in 0..BINS - 1 {
            acc.grow(&bin_bounds[b]);
            cnt += bin_count[b];
            if cnt == 0 || right_count[b + 1] == 0 {
                continue;
            }
            let cost = acc.half_area() * cnt as f32 + right_area[b + 1] * right_count[b + 1] as f32;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }
    let (cost, axis, bin) = best?;
    // Leaf cost vs split cost (traversal step ~ 1 triangle test).
    let leaf_cost = bounds.half_area() * n as f32;
    if n <= MAX_LEAF && cost + bounds.half_area() >= leaf_cost {
        return None;
    }
    let lo = cbounds.min[axis];
    let scale = BINS as f32 / (cbounds.max[axis] - lo);
    let mut i = 0;
    let mut j = n;
    while i < j {
        let b = (((prims[i].centroid[axis] - lo) * scale) as usize).min(BINS - 1);
        if b <= bin {
            i += 1;
        } else {
            j -= 1;
            prims.swap(i, j);
        }
    }
    (i > 0 && i < n).then_some(i)
}
