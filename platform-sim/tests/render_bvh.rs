//! The BVH against a brute-force reference on random triangle soups, and the
//! 8-lane SIMD packet traversal against the scalar one (bit for bit).

use proptest::prelude::*;
use sornav_platform_sim::render::{Bvh, BvhHit, PreparedRay};

/// Brute force: closest hit over all triangles with a double-precision
/// Moller-Trumbore test (the reference the BVH must agree with).
fn brute(v: &[[f32; 3]], t: &[[u32; 3]], o: [f32; 3], d: [f32; 3]) -> Option<(f64, usize)> {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let f = |p: [f32; 3]| p.map(f64::from);
    let (o, d) = (f(o), f(d));
    let mut best: Option<(f64, usize)> = None;
    for (i, tri) in t.iter().enumerate() {
        let (a, b, c) = (
            f(v[tri[0] as usize]),
            f(v[tri[1] as usize]),
            f(v[tri[2] as usize]),
        );
        let (e1, e2) = (sub(b, a), sub(c, a));
        let p = cross(d, e2);
        let det = dot(e1, p);
        if det.abs() < 1e-12 {
            continue;
        }
        let s = sub(o, a);
        let u = dot(s, p) / det;
        let q = cross(s, e1);
        let w = dot(d, q) / det;
        let tt = dot(e2, q) / det;
        if u >= 0.0 && w >= 0.0 && u + w <= 1.0 && tt > 0.0 && best.is_none_or(|(bt, _)| tt < bt) {
            best = Some((tt, i));
        }
    }
    best
}

fn soup() -> impl Strategy<Value = (Vec<[f32; 3]>, Vec<[u32; 3]>)> {
    (1usize..120).prop_flat_map(|n| {
        prop::collection::vec(
            (
                prop::array::uniform3(-5.0f32..5.0),
                prop::array::uniform3(-1.0f32..1.0),
                prop::array::uniform3(-1.0f32..1.0),
            ),
            n,
        )
        .prop_map(|tris| {
            let mut v = Vec::new();
            let mut t = Vec::new();
            for (c, e1, e2) in tris {
                let k = v.len() as u32;
                v.push(c);
                v.push([c[0] + e1[0], c[1] + e1[1], c[2] + e1[2]]);
                v.push([c[0] + e2[0], c[1] + e2[1], c[2] + e2[2]]);
                t.push([k, k + 1, k + 2]);
            }
            (v, t)
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Same closest hit as brute force (up to ties within float tolerance),
    /// and packets give exactly the single-ray results.
    #[test]
    fn bvh_matches_brute_force((v, t) in soup(), origin in prop::array::uniform3(-6.0f32..6.0),
                               dirs in prop::collection::vec(prop::array::uniform3(-1.0f32..1.0), 1..80)) {
        let payload: Vec<u32> = (0..t.len() as u32).map(|i| i * 7).collect();
        let bvh = Bvh::build(&v, &t, &payload).unwrap();
        prop_assert_eq!(bvh.triangle_count(), t.len());
        let rays: Vec<PreparedRay> = dirs.iter().filter_map(|d| PreparedRay::new(origin, *d)).collect();
        let mut packet = vec![None; rays.len()];
        bvh.intersect_packet(&rays, 0.0, f32::INFINITY, &mut packet);
        for (ray, p) in rays.iter().zip(&packet) {
            let single = bvh.intersect_prepared(ray, 0.0, f32::INFINITY);
            // Same hit (the leaf slot may differ: large triangles are
            // referenced from several leaves).
            prop_assert_eq!(single.map(|h| (h.t, h.triangle, h.payload)), p.map(|h| (h.t, h.triangle, h.payload)));
            let reference = brute(&v, &t, origin, ray.direction());
            match (single, reference) {
                (Some(h), Some((rt, ri))) => {
                    let tol = 1e-3 * (1.0 + rt);
                    prop_assert!((f64::from(h.t) - rt).abs() < tol, "t {} vs {}", h.t, rt);
                    prop_assert_eq!(h.payload, h.triangle * 7);
                    // Either the same triangle or a tie at the same distance.
                    prop_assert!(h.triangle as usize == ri || (f64::from(h.t) - rt).abs() < tol);
                }
                (None, Some((rt, ri))) => {
                    // Only grazing hits on an edge may differ between the two tests.
                    let d = ray.direction();
                    let hit = [origin[0] as f64 + rt * d[0] as f64, origin[1] as f64 + rt * d[1] as f64, origin[2] as f64 + rt * d[2] as f64];
                    let tri = t[ri];
                    let near_edge = (0..3).any(|k| {
                        let a = v[tri[k] as usize].map(f64::from);
                        let b = v[tri[(k + 1) % 3] as usize].map(f64::from);
                        dist_to_segment(hit, a, b) < 1e-4
                    });
                    prop_assert!(near_edge, "BVH missed a hit at t = {}", rt);
                }
                (Some(h), None) => prop_assert!(false, "BVH hit {:?} that brute force misses", h),
                (None, None) => {}
            }
        }
    }

    /// Limiting t_max never yields a farther hit, and t_min skips closer ones.
    #[test]
    fn bvh_respects_the_ray_interval((v, t) in soup(), origin in prop::array::uniform3(-6.0f32..6.0),
                                     dir in prop::array::uniform3(-1.0f32..1.0), cut in 0.0f32..10.0) {
        let bvh = Bvh::build(&v, &t, &vec![0; t.len()]).unwrap();
        if let Some(h) = bvh.intersect(origin, dir, 0.0, cut) { prop_assert!(h.t < cut && h.t > 0.0); }
        if let Some(h) = bvh.intersect(origin, dir, cut, f32::INFINITY) { prop_assert!(h.t > cut); }
    }
}

fn dist_to_segment(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let ap = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
    let l2 = ab.iter().map(|x| x * x).sum::<f64>();
    let s = if l2 > 0.0 {
        (ap.iter().zip(&ab).map(|(x, y)| x * y).sum::<f64>() / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (0..3)
        .map(|k| (ap[k] - s * ab[k]).powi(2))
        .sum::<f64>()
        .sqrt()
}

#[test]
fn bad_meshes_are_typed_errors() {
    use sornav_platform_sim::render::RenderError;
    assert_eq!(
        Bvh::build(&[], &[], &[]).unwrap_err(),
        RenderError::EmptyMesh
    );
    let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    assert!(matches!(
        Bvh::build(&v, &[[0, 1, 3]], &[0]),
        Err(RenderError::Mesh(_))
    ));
    assert!(matches!(
        Bvh::build(&v, &[[0, 1, 2]], &[]),
        Err(RenderError::Mesh(_))
    ));
    let nan = [[0.0, f32::NAN, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    assert!(matches!(
        Bvh::build(&nan, &[[0, 1, 2]], &[0]),
        Err(RenderError::Mesh(_))
    ));
    let bvh = Bvh::build(&v, &[[0, 1, 2]], &[0]).unwrap();
    assert!(
        bvh.intersect([0.2, 0.2, 1.0], [0.0, 0.0, 0.0], 0.0, 10.0)
            .is_none()
    );
    assert!(
        bvh.intersect([f32::NAN, 0.2, 1.0], [0.0, 0.0, -1.0], 0.0, 10.0)
            .is_none()
    );
    assert!(
        bvh.intersect([0.2, 0.2, 1.0], [0.0, 0.0, -1.0], 0.0, 10.0)
            .is_some()
    );
    // Many identical triangles (all centroids equal) still build and hit.
    let tris = vec![[0u32, 1, 2]; 1000];
    let bvh = Bvh::build(&v, &tris, &vec![5; 1000]).unwrap();
    assert_eq!(
        bvh.intersect([0.2, 0.2, 1.0], [0.0, 0.0, -1.0], 0.0, 10.0)
            .unwrap()
            .payload,
        5
    );
}

/// Bit-identical comparison of two packet results (`t` by its bits, leaf
/// slot, triangle and payload).
fn same_hits(a: &[Option<BvhHit>], b: &[Option<BvhHit>]) -> Result<(), TestCaseError> {
    prop_assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        let key = |h: &Option<BvhHit>| h.map(|h| (h.t.to_bits(), h.slot, h.triangle, h.payload));
        prop_assert_eq!(key(x), key(y), "ray {}", i);
    }
    Ok(())
}

/// An 8x8 tile of camera rays (common origin, directions on a pinhole grid)
/// looking along `fwd`, with pixel pitch `step`.
fn tile(origin: [f32; 3], fwd: [f32; 3], step: f32, n: usize) -> Vec<PreparedRay> {
    let up = [0.0f32, 0.0, 1.0];
    let right = [fwd[1], -fwd[0], 0.0];
    let mut rays = Vec::new();
    for k in 0..n {
        let (a, b) = ((k % 8) as f32 * step, (k / 8) as f32 * step);
        let d = [0, 1, 2].map(|c| fwd[c] + a * right[c] + b * up[c]);
        rays.extend(PreparedRay::new(origin, d));
    }
    rays
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    /// The 8-lane SIMD packet traversal equals the scalar packet traversal
    /// bit for bit, on incoherent packets (random directions, up to 150 rays,
    /// so several chunks and ragged groups; directions with zero components,
    /// one shared or mixed dominant axes) with random ray intervals.
    #[test]
    fn simd_packets_equal_scalar_packets((v, t) in soup(),
                                         origin in prop::array::uniform3(-6.0f32..6.0),
                                         dirs in prop::collection::vec(prop::array::uniform3(
                                             prop_oneof![3 => -1.0f32..1.0, 1 => Just(0.0f32), 1 => Just(-0.0f32)]), 1..150),
                                         jitter in prop::collection::vec(prop::array::uniform3(-0.5f32..0.5), 150),
                                         shared_origin in any::<bool>(),
                                         dominant in prop::option::of(0usize..3),
                                         t_min in prop_oneof![Just(0.0f32), 0.0f32..3.0],
                                         t_max in prop_oneof![Just(f32::INFINITY), 0.5f32..12.0]) {
        let payload: Vec<u32> = (0..t.len() as u32).map(|i| i ^ 0x55).collect();
        let bvh = Bvh::build(&v, &t, &payload).unwrap();
        let rays: Vec<PreparedRay> = dirs
            .iter()
            .zip(&jitter)
            .filter_map(|(d, j)| {
                // Optionally one dominant axis for every ray (the SIMD path;
                // mixed axes take the scalar one).
                let mut d = *d;
                if let Some(a) = dominant {
                    d[a] = if d[a] < 0.0 { -1.5 } else { 1.5 };
                }
                let o = if shared_origin { origin } else { [0, 1, 2].map(|a| origin[a] + j[a]) };
                PreparedRay::new(o, d)
            })
            .collect();
        let mut simd = vec![None; rays.len()];
        let mut scalar = vec![None; rays.len()];
        bvh.intersect_packet(&rays, t_min, t_max, &mut simd);
        bvh.intersect_packet_scalar(&rays, t_min, t_max, &mut scalar);
        same_hits(&simd, &scalar)?;
    }

    /// Same on coherent camera tiles (shared origin, one dominant axis: the
    /// SIMD path with the frustum cull), 1-64 rays, on soups and on a finely
    /// tessellated closed room where rays run along shared edges.
    #[test]
    fn simd_tiles_equal_scalar_tiles((v, t) in soup(),
                                     origin in prop::array::uniform3(-6.0f32..6.0),
                                     yaw in 0.0f32..std::f32::consts::TAU,
                                     pitch in -0.8f32..0.8,
                                     step in prop_oneof![Just(0.0f32), 1e-4f32..0.05],
                                     n in 1usize..=64,
                                     room_origin in prop::array::uniform3(0.1f32..2.9)) {
        let fwd = [yaw.cos(), yaw.sin(), pitch];
        let payload: Vec<u32> = (0..t.len() as u32).collect();
        let bvh = Bvh::build(&v, &t, &payload).unwrap();
        let rays = tile(origin, fwd, step, n);
        let mut simd = vec![None; rays.len()];
        let mut scalar = vec![None; rays.len()];
        bvh.intersect_packet(&rays, 0.0, f32::INFINITY, &mut simd);
        bvh.intersect_packet_scalar(&rays, 0.0, f32::INFINITY, &mut scalar);
        same_hits(&simd, &scalar)?;
        // A closed cube room [0, 3]^3 tessellated 6 x 6 per face.
        let (rv, rt) = cube_room(3.0, 6);
        let room = Bvh::build(&rv, &rt, &vec![1; rt.len()]).unwrap();
        let rays = tile(room_origin, fwd, step, n);
        let mut simd = vec![None; rays.len()];
        let mut scalar = vec![None; rays.len()];
        room.intersect_packet(&rays, 0.0, f32::INFINITY, &mut simd);
        room.intersect_packet_scalar(&rays, 0.0, f32::INFINITY, &mut scalar);
        same_hits(&simd, &scalar)?;
        prop_assert!(simd.iter().all(Option::is_some), "a ray escaped the closed room");
    }
}

/// The six faces of the cube `[0, s]^3`, each cut into `k x k` squares of two
/// triangles.
fn cube_room(s: f32, k: usize) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let (mut v, mut t) = (Vec::new(), Vec::new());
    for axis in 0..3 {
        for side in [0.0, s] {
            for i in 0..k {
                for j in 0..k {
                    let base = v.len() as u32;
                    for (di, dj) in [(0, 0), (1, 0), (1, 1), (0, 1)] {
                        let mut p = [0.0f32; 3];
                        p[axis] = side;
                        p[(axis + 1) % 3] = s * (i + di) as f32 / k as f32;
                        p[(axis + 2) % 3] = s * (j + dj) as f32 / k as f32;
                        v.push(p);
                    }
                    t.push([base, base + 1, base + 2]);
                    t.push([base, base + 2, base + 3]);
                }
            }
        }
    }
    (v, t)
}
