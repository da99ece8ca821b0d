//! The camera against analytic references in a box room.

use nalgebra::Point3;
use proptest::prelude::*;
use sornav_platform_sim::render::{Bvh, Camera, CameraConfig, CameraPose, NO_INSTANCE};

mod common;

const ROOM: ([f64; 3], [f64; 3]) = ([0.0, 0.0, 0.0], [6.0, 4.0, 2.6]);
const OBJECT: ([f64; 3], [f64; 3]) = ([3.5, 1.5, 0.0], [4.5, 2.5, 0.8]);
const FLOOR: u32 = 1;
const CEILING: u32 = 2;
const WALL: u32 = 3;
const OBJ: u32 = 10;

/// The six faces of a box, each split into n x n quads (2 triangles each):
/// finely tessellated, axis-aligned faces are where cracks between triangles
/// would show.
fn box_mesh(
    lo: [f64; 3],
    hi: [f64; 3],
    n: usize,
    label: impl Fn(usize, bool) -> u32,
    v: &mut Vec<[f32; 3]>,
    t: &mut Vec<[u32; 3]>,
    p: &mut Vec<u32>,
) {
    for axis in 0..3 {
        for side in [false, true] {
            let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
            let c = if side { hi[axis] } else { lo[axis] };
            let base = v.len() as u32;
            for i in 0..=n {
                for j in 0..=n {
                    let mut q = [0.0f64; 3];
                    q[axis] = c;
                    q[a1] = lo[a1] + (hi[a1] - lo[a1]) * i as f64 / n as f64;
                    q[a2] = lo[a2] + (hi[a2] - lo[a2]) * j as f64 / n as f64;
                    v.push(q.map(|x| x as f32));
                }
            }
            let id = |i: usize, j: usize| base + (i * (n + 1) + j) as u32;
            for i in 0..n {
                for j in 0..n {
                    t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                    t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                    p.push(label(axis, side));
                    p.push(label(axis, side));
                }
            }
        }
    }
}

fn room(n: usize) -> Bvh {
    let (mut v, mut t, mut p) = (Vec::new(), Vec::new(), Vec::new());
    box_mesh(
        ROOM.0,
        ROOM.1,
        n,
        |axis, side| {
            if axis == 2 {
                if side { CEILING } else { FLOOR }
            } else {
                WALL
            }
        },
        &mut v,
        &mut t,
        &mut p,
    );
    box_mesh(OBJECT.0, OBJECT.1, n, |_, _| OBJ, &mut v, &mut t, &mut p);
    Bvh::build(&v, &t, &p).unwrap()
}

/// Analytic hits of a ray from inside the room: (t, label) for the room's
/// inner faces (exit distance) and the object's box (entry distance), sorted.
fn reference(o: [f64; 3], d: [f64; 3]) -> Vec<(f64, u32)> {
    let mut hits = Vec::new();
    // Room: leave through the nearest face.
    let mut best = (f64::INFINITY, WALL);
    for a in 0..3 {
        if d[a] != 0.0 {
            let (plane, lab) = if d[a] > 0.0 {
                (ROOM.1[a], if a == 2 { CEILING } else { WALL })
            } else {
                (ROOM.0[a], if a == 2 { FLOOR } else { WALL })
            };
            let t = (plane - o[a]) / d[a];
            if t < best.0 {
                best = (t, lab);
            }
        }
    }
    hits.push(best);
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a] < OBJECT.0[a] || o[a] > OBJECT.1[a] {
                t0 = f64::INFINITY;
            }
            continue;
        }
        let (mut p, mut q) = ((OBJECT.0[a] - o[a]) / d[a], (OBJECT.1[a] - o[a]) / d[a]);
        if p > q {
            std::mem::swap(&mut p, &mut q);
        }
        t0 = t0.max(p);
        t1 = t1.min(q);
    }
    if t0 <= t1 && t0 > 0.0 {
        hits.push((t0, OBJ));
    }
    hits.sort_by(|a, b| a.0.total_cmp(&b.0));
    hits
}

fn check_frame(camera: &Camera, pose: &CameraPose) {
    let c = camera.config();
    let frame = camera.render(pose, 0);
    let (f, r, up) = pose.axes();
    let focal = c.focal();
    let mut label_ties = 0;
    for v in 0..c.height {
        for u in 0..c.width {
            let a = (f64::from(u) + 0.5 - f64::from(c.width) / 2.0) / focal;
            let b = -(f64::from(v) + 0.5 - f64::from(c.height) / 2.0) / focal;
            let d = f + r * a + up * b;
            let hits = reference(pose.position.coords.into(), d.into());
            let (t, label) = hits[0];
            let i = frame.index(u, v);
            let depth = f64::from(frame.depth[i]);
            if t >= c.min_depth + 1e-4 && t <= c.max_depth - 1e-4 {
                assert!(
                    (depth - t).abs() < 2e-4 * t.max(1.0),
                    "pixel ({u},{v}): depth {depth} vs {t}"
                );
            } else if t < c.min_depth - 1e-4 || t > c.max_depth + 1e-4 {
                assert_eq!(
                    depth, 0.0,
                    "pixel ({u},{v}) outside the depth range must read 0 (t = {t})"
                );
            }
            let got = frame.instance[i];
            if got != label {
                // Only a tie between two surfaces (an edge of the object) may differ.
                let tie = hits
                    .iter()
                    .any(|&(t2, l2)| l2 == got && (t2 - t).abs() < 1e-4 * t.max(1.0));
                let corner = got == WALL || got == FLOOR || got == CEILING;
                assert!(tie || corner, "pixel ({u},{v}): label {got} vs {label}");
                label_ties += 1;
            }
        }
    }
    assert!(
        label_ties * 1000 < frame.instance.len(),
        "{label_ties} label mismatches"
    );
}

#[test]
fn depth_and_labels_match_the_analytic_box_room() {
    let camera = Camera::new(
        room(8),
        CameraConfig {
            width: 160,
            height: 120,
            ..CameraConfig::default()
        },
    )
    .unwrap();
    for (x, y, yaw, pitch) in [
        (1.0, 2.0, 0.0, 0.0),
        (1.0, 2.0, 0.3, -0.5),
        (2.5, 0.7, 1.1, 0.2),
        (5.5, 3.5, -2.6, -0.2),
        (1.2, 3.0, -0.6, 0.0),
    ] {
        check_frame(
            &camera,
            &CameraPose {
                position: Point3::new(x, y, 0.88),
                yaw,
                pitch,
            },
        );
    }
}

#[test]
fn habitat_defaults_and_a_hand_computed_pixel() {
    let c = CameraConfig::default();
    assert_eq!((c.width, c.height), (640, 480));
    assert!((c.focal() - 388.2).abs() < 0.1, "fx = {}", c.focal());
    assert_eq!((c.min_depth, c.max_depth, c.mount_height), (0.5, 5.0, 0.88));
    // Looking along +x from x = 2 at the wall x = 6: every pixel that sees the
    // wall reads z-depth 4.
    let camera = Camera::new(room(4), c.clone()).unwrap();
    let frame = camera.render(
        &CameraPose {
            position: Point3::new(2.0, 2.0, 1.3),
            yaw: 0.0,
            pitch: 0.0,
        },
        0,
    );
    // Centre-right pixel (u = 400, v = 240) sees the far wall (the object is lower).
    let i = frame.index(400, 240);
    assert_eq!(frame.instance[i], WALL);
    assert!((frame.depth[i] - 4.0).abs() < 1e-4);
    // A floor pixel at the bottom row: z-depth = h / tan(angle below the axis).
    let v = 479;
    let b = (f64::from(v) + 0.5 - 240.0) / c.focal();
    let i = frame.index(100, v);
    assert_eq!(frame.instance[i], FLOOR);
    assert!((f64::from(frame.depth[i]) - 1.3 / b).abs() < 1e-4);
}

#[test]
fn semantic_range_rgb_and_bad_configs() {
    let bvh = room(2);
    let mut c = CameraConfig {
        width: 40,
        height: 30,
        rgb: true,
        semantic_max_depth: Some(1.0),
        ..CameraConfig::default()
    };
    let camera = Camera::new(bvh.clone(), c.clone()).unwrap();
    let frame = camera.render(
        &CameraPose {
            position: Point3::new(1.5, 2.0, 1.0),
            yaw: 0.0,
            pitch: 0.0,
        },
        0,
    );
    // The far wall is beyond 1 m: no semantic return in the centre, but a depth.
    let i = frame.index(20, 15);
    assert_eq!(frame.instance[i], NO_INSTANCE);
    assert!((frame.depth[i] - 4.5).abs() < 1e-4);
    let png = std::env::temp_dir().join(format!("sornav-rgb-{}.png", std::process::id()));
    frame.save_png(&png).unwrap();
    let bytes = std::fs::read(&png).unwrap();
    assert!(bytes.starts_with(b"\x89PNG"));
    std::fs::remove_file(&png).ok();
    assert!(
        frame
            .save_png(std::path::Path::new("/nonexistent-dir/x.png"))
            .is_err()
    );
    let rgb = frame.rgb.as_ref().unwrap();
    assert!(
        rgb.iter().all(|p| p.iter().any(|c| *c > 0)),
        "every pixel sees a surface"
    );
    // Invalid configurations are typed errors.
    for bad in [
        CameraConfig {
            width: 0,
            ..c.clone()
        },
        CameraConfig {
            hfov_deg: 180.0,
            ..c.clone()
        },
        CameraConfig {
            min_depth: 6.0,
            ..c.clone()
        },
        CameraConfig {
            max_depth: f64::NAN,
            ..c.clone()
        },
    ] {
        assert!(Camera::new(bvh.clone(), bad).is_err());
    }
    c.noise.missing_rate = 1.5;
    assert!(Camera::new(bvh.clone(), c).is_err());
    // A non-finite pose renders nothing rather than garbage.
    let frame = camera.render(
        &CameraPose {
            position: Point3::new(f64::NAN, 2.0, 1.0),
            yaw: 0.0,
            pitch: 0.0,
        },
        0,
    );
    assert_eq!(frame.valid_depth_count(), 0);
    assert!(frame.instance.iter().all(|i| *i == NO_INSTANCE));
}

#[test]
fn noise_models_are_off_by_default_and_deterministic() {
    let bvh = room(2);
    let base = CameraConfig {
        width: 80,
        height: 60,
        ..CameraConfig::default()
    };
    let pose = CameraPose {
        position: Point3::new(1.0, 2.0, 0.88),
        yaw: 0.0,
        pitch: -0.3,
    };
    let clean = Camera::new(bvh.clone(), base.clone())
        .unwrap()
        .render(&pose, 0);
    let mut noisy_cfg = base.clone();
    noisy_cfg.noise.depth_sigma = 0.01;
    noisy_cfg.noise.missing_rate = 0.1;
    noisy_cfg.noise.boundary_flip_rate = 0.5;
    noisy_cfg.noise.false_positive_rate = 1.0;
    let noisy = Camera::new(bvh.clone(), noisy_cfg).unwrap();
    let a = noisy.render(&pose, 7);
    let b = noisy.render(&pose, 7);
    assert_eq!(a, b, "same seed, same frame");
    assert_ne!(a, noisy.render(&pose, 8));
    let missing = clean.valid_depth_count() - a.valid_depth_count();
    let frac = missing as f64 / clean.valid_depth_count() as f64;
    assert!((0.07..0.13).contains(&frac), "missing fraction {frac}");
    assert!(
        clean
            .depth
            .iter()
            .zip(&a.depth)
            .any(|(x, y)| *y > 0.0 && x != y),
        "depth noise applied"
    );
    // Missed detections remove whole objects.
    let mut miss = base.clone();
    miss.noise.missed_detection_rate = 1.0;
    let m = Camera::new(bvh, miss).unwrap().render(&pose, 1);
    assert!(clean.instance.contains(&OBJ));
    assert!(!m.instance.contains(&OBJ));
}

/// Depth noise follows its model: zero-mean Gaussian with standard deviation
/// `depth_sigma * z^2`, applied to valid returns only.
#[test]
fn depth_noise_has_the_configured_spread() {
    let base = CameraConfig {
        width: 120,
        height: 90,
        ..CameraConfig::default()
    };
    let pose = CameraPose {
        position: Point3::new(1.0, 2.0, 0.88),
        yaw: 0.2,
        pitch: -0.3,
    };
    let clean = Camera::new(room(2), base.clone()).unwrap().render(&pose, 0);
    let mut cfg = base;
    cfg.noise.depth_sigma = 0.01;
    let noisy = Camera::new(room(2), cfg).unwrap().render(&pose, 3);
    let mut z = Vec::new();
    for (c, n) in clean.depth.iter().zip(&noisy.depth) {
        if *c == 0.0 {
            assert_eq!(*n, 0.0, "no noise where there is no return");
            continue;
        }
        let c = f64::from(*c);
        z.push((f64::from(*n) - c) / (0.01 * c * c));
    }
    assert!(z.len() > 5000, "{} valid pixels", z.len());
    let mean = z.iter().sum::<f64>() / z.len() as f64;
    let sd = (z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / z.len() as f64).sqrt();
    // 4-sigma bounds for the mean and the spread of ~9,000 standard normals
    assert!(mean.abs() < 0.05, "mean {mean}");
    assert!((sd - 1.0).abs() < 0.04, "sd {sd}");
    let beyond_2 = z.iter().filter(|v| v.abs() > 2.0).count() as f64 / z.len() as f64;
    assert!((beyond_2 - 0.0455).abs() < 0.012, "tail {beyond_2}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]
    /// No holes: from anywhere inside a closed, finely tessellated
    /// axis-aligned room, every pixel returns a surface.
    #[test]
    fn no_holes_in_a_closed_room(x in 0.05f64..5.95, y in 0.05f64..3.95, z in 0.05f64..2.55,
                                yaw in -3.2f64..3.2, pitch in -1.5f64..1.5, axis_aligned in any::<bool>()) {
        let bvh = room(16);
        let camera = Camera::new(bvh, CameraConfig { width: 64, height: 48, ..CameraConfig::default() }).unwrap();
        // Axis-aligned views put whole rows of rays exactly on triangle edges.
        let (yaw, pitch) = if axis_aligned { ((yaw / std::f64::consts::FRAC_PI_2).round() * std::f64::consts::FRAC_PI_2, 0.0) } else { (yaw, pitch) };
        let frame = camera.render(&CameraPose { position: Point3::new(x, y, z), yaw, pitch }, 0);
        let holes = frame.instance.iter().filter(|i| **i == NO_INSTANCE).count();
        prop_assert_eq!(holes, 0);
    }
}

/// Differential test on a real scene: every pixel of the camera agrees with
/// parry's independent ray cast (parry3d, a dev-dependency) on a procedural house.
#[test]
fn camera_matches_parry_on_a_procedural_house() {
    use sornav_platform_sim::{NavMesh, NavMeshConfig};
    let scene = common::house(5, 2);
    let nav = NavMesh::build(&scene, &NavMeshConfig::default()).unwrap();
    let config = CameraConfig {
        width: 64,
        height: 48,
        ..CameraConfig::default()
    };
    let camera = Camera::for_scene(&scene, config.clone()).unwrap();
    let parry = common::ParryMesh::new(&scene);
    let (mut pixels, mut mismatches) = (0usize, 0usize);
    for k in 0..6u32 {
        let feet = nav.span_center((k as usize * nav.span_count() / 6) as u32);
        let pose = camera.pose_at(&feet, f64::from(k) * 1.1, [0.0, -0.4, 0.3][k as usize % 3]);
        let frame = camera.render(&pose, 0);
        let (f, r, up) = pose.axes();
        for v in 0..config.height {
            for u in 0..config.width {
                let a = (f64::from(u) + 0.5 - 32.0) / config.focal();
                let b = -(f64::from(v) + 0.5 - 24.0) / config.focal();
                let d = f + r * a + up * b;
                let i = frame.index(u, v);
                pixels += 1;
                match parry.cast_ray(&pose.position, &d, 1e3) {
                    // parry's distance is along the normalised direction; z-depth = that / |d|.
                    Some(hit) => {
                        let z = hit.distance / d.norm();
                        let got = frame.instance[i];
                        let depth_ok = if (0.5 + 1e-3..=5.0 - 1e-3).contains(&z) {
                            (f64::from(frame.depth[i]) - z).abs() < 1e-3 * z.max(1.0)
                        } else {
                            true
                        };
                        if got != hit.instance || !depth_ok {
                            mismatches += 1;
                        }
                    }
                    None => mismatches += usize::from(frame.instance[i] != NO_INSTANCE),
                }
            }
        }
    }
    // Ties on edges between two instances may resolve differently; nothing else.
    assert!(
        mismatches * 500 < pixels,
        "{mismatches} of {pixels} pixels differ from parry"
    );
}

/// Label flips happen only at instance boundaries (to a neighbour's label);
/// false-positive blobs carry a scene object's id; unprojected pixels lie on
/// the surfaces they see.
#[test]
fn noise_invariants_and_unprojection() {
    use sornav_platform_sim::{NavMesh, NavMeshConfig};
    let scene = common::house(2, 1);
    let nav = NavMesh::build(&scene, &NavMeshConfig::default()).unwrap();
    let base = CameraConfig {
        width: 96,
        height: 72,
        ..CameraConfig::default()
    };
    let clean_cam = Camera::for_scene(&scene, base.clone()).unwrap();
    let parry = common::ParryMesh::new(&scene);
    let mut flip = base.clone();
    flip.noise.boundary_flip_rate = 1.0;
    let flip_cam = Camera::for_scene(&scene, flip).unwrap();
    let mut fp = base.clone();
    fp.noise.false_positive_rate = 1.0;
    fp.noise.false_positive_radius = 0.1;
    let fp_cam = Camera::for_scene(&scene, fp).unwrap();
    let objects: Vec<u32> = scene.objects().map(|o| o.id).collect();
    let (w, h) = (base.width as usize, base.height as usize);
    for k in 0..4usize {
        let feet = nav.span_center((k * nav.span_count() / 4) as u32);
        let pose = clean_cam.pose_at(&feet, k as f64 * 1.7, -0.2);
        let clean = clean_cam.render(&pose, 0);
        let flipped = flip_cam.render(&pose, k as u64);
        let mut changed = 0;
        for v in 0..h {
            for u in 0..w {
                let i = v * w + u;
                if flipped.instance[i] != clean.instance[i] {
                    changed += 1;
                    let nb = [
                        (u > 0).then(|| i - 1),
                        (u + 1 < w).then(|| i + 1),
                        (v > 0).then(|| i - w),
                        (v + 1 < h).then(|| i + w),
                    ];
                    assert!(
                        nb.into_iter()
                            .flatten()
                            .any(|j| clean.instance[j] == flipped.instance[i])
                    );
                }
            }
        }
        assert!(changed > 0, "some boundary pixels flip");
        let blob = fp_cam.render(&pose, k as u64);
        let new: Vec<u32> = blob
            .instance
            .iter()
            .zip(&clean.instance)
            .filter(|(a, b)| a != b)
            .map(|(a, _)| *a)
            .collect();
        assert!(
            new.iter().all(|id| objects.contains(id)),
            "blobs are labelled as scene objects"
        );
        assert_eq!(
            blob.depth, clean.depth,
            "false positives do not touch depth"
        );
        // Unprojection: the point of a pixel lies at its depth along the ray,
        // and parry's ray to it hits (almost) exactly there.
        for (u, v) in [(10u32, 10u32), (48, 36), (90, 70)] {
            if let Some(p) = clean.unproject(&base, u, v) {
                let d = p - pose.position;
                let hit = parry.cast_ray(&pose.position, &d, 100.0).unwrap();
                assert!((hit.distance - d.norm()).abs() < 2e-3 * d.norm().max(1.0));
            }
        }
    }
}

/// The camera's ray through pixel (u, v), built with the camera's f32
/// operations: (origin, direction with unit forward component).
fn camera_ray(camera: &Camera, pose: &CameraPose, u: usize, v: usize) -> ([f32; 3], [f32; 3]) {
    let config = camera.config();
    let (f, r, up) = pose.axes();
    let to32 = |v: nalgebra::Vector3<f64>| [v.x as f32, v.y as f32, v.z as f32];
    let (f, r, up) = (to32(f), to32(r), to32(up));
    let o = pose.position.map(|c| c as f32);
    let focal = config.focal() as f32;
    let (cx, cy) = (config.width as f32 / 2.0, config.height as f32 / 2.0);
    let b = -((v as f32 + 0.5 - cy) / focal);
    let base = [0, 1, 2].map(|c| f[c] + b * up[c]);
    let a = (u as f32 + 0.5 - cx) / focal;
    ([o.x, o.y, o.z], [0, 1, 2].map(|c| base[c] + a * r[c]))
}

/// The scalar reference frame of `pose`: every 8x8 tile traced with the
/// binary tree's scalar packet kernels (`intersect_packet_scalar`), rays
/// built as the camera builds them. Returns depth, labels and each pixel's
/// hit `t` (`NaN` without a hit).
fn scalar_frame(camera: &Camera, pose: &CameraPose) -> (Vec<f32>, Vec<u32>, Vec<f32>) {
    use sornav_platform_sim::render::PreparedRay;
    let config = camera.config();
    let (w, h) = (config.width as usize, config.height as usize);
    let (dmin, dmax) = (config.min_depth as f32, config.max_depth as f32);
    let sem = config
        .semantic_max_depth
        .map_or(f32::INFINITY, |d| d as f32);
    let mut depth = vec![0f32; w * h];
    let mut instance = vec![NO_INSTANCE; w * h];
    let mut t = vec![f32::NAN; w * h];
    for v0 in (0..h).step_by(8) {
        for u0 in (0..w).step_by(8) {
            let (mut rays, mut index) = (Vec::new(), Vec::new());
            for v in v0..(v0 + 8).min(h) {
                for u in u0..(u0 + 8).min(w) {
                    let (origin, dir) = camera_ray(camera, pose, u, v);
                    rays.push(PreparedRay::new(origin, dir).unwrap());
                    index.push(v * w + u);
                }
            }
            let mut hits = vec![None; rays.len()];
            camera
                .bvh()
                .intersect_packet_scalar(&rays, 0.0, f32::INFINITY, &mut hits);
            for (hit, &p) in hits.iter().zip(&index) {
                let Some(hit) = hit else { continue };
                t[p] = hit.t;
                if hit.t >= dmin && hit.t <= dmax {
                    depth[p] = hit.t;
                }
                if hit.t <= sem {
                    instance[p] = hit.payload;
                }
            }
        }
    }
    (depth, instance, t)
}

/// 640x480 frames of a procedural house (level, tilted, and at headings
/// near 45 deg where tiles mix dominant axes) against the scalar reference:
/// depth equal bit for bit at every pixel; labels equal except where two
/// instances are hit at exactly the same `t` (coplanar faces), which the
/// tile kernel's traversal may resolve to the other instance. Each such
/// pixel is checked to be a genuine tie: the camera's instance alone is hit
/// at that very `t`.
#[test]
fn camera_depth_equals_the_scalar_path_and_labels_differ_only_at_ties() {
    use sornav_platform_sim::{NavMesh, NavMeshConfig};
    let scene = common::house(3, 2);
    let nav = NavMesh::build(&scene, &NavMeshConfig::default()).unwrap();
    let camera = Camera::for_scene(&scene, CameraConfig::default()).unwrap();
    let w = camera.config().width as usize;
    let mut instance_bvh = std::collections::HashMap::new();
    let (mut ties, mut checked) = (0, 0);
    for k in 0..8u32 {
        let feet = nav.span_center((k as usize * nav.span_count() / 8) as u32);
        let yaw = f64::from(k) * 0.785 + 0.01;
        let pose = camera.pose_at(&feet, yaw, [0.0, -0.5, 0.4][k as usize % 3]);
        let frame = camera.render(&pose, 0);
        let (depth, instance, t) = scalar_frame(&camera, &pose);
        let bits = |d: &[f32]| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(
            bits(&frame.depth) == bits(&depth),
            "depth differs at pose {k}"
        );
        for p in 0..frame.instance.len() {
            checked += 1;
            let (got, want) = (frame.instance[p], instance[p]);
            if got == want {
                continue;
            }
            ties += 1;
            assert!(
                got != NO_INSTANCE && want != NO_INSTANCE,
                "pose {k} pixel {p}"
            );
            let bvh = instance_bvh.entry(got).or_insert_with(|| {
                let tris: Vec<[u32; 3]> = scene
                    .triangles()
                    .iter()
                    .zip(scene.triangle_instances())
                    .filter(|(_, i)| **i == got)
                    .map(|(t, _)| *t)
                    .collect();
                let n = tris.len();
                Bvh::build(scene.vertices(), &tris, &vec![got; n]).unwrap()
            });
            let (origin, dir) = camera_ray(&camera, &pose, p % w, p / w);
            let hit = bvh
                .intersect(origin, dir, 0.0, f32::INFINITY)
                .expect("the camera's instance is hit");
            assert!(
                hit.t.to_bits() == t[p].to_bits(),
                "pose {k} pixel {p}: instance {got} at t = {} but the closest hit is at {}",
                hit.t,
                t[p]
            );
        }
    }
    // Ties are rare: coplanar wall pieces seen face-on.
    assert!(ties * 50 < checked, "{ties} of {checked} labels differ");
}

/// Every tile kernel available on this CPU renders the same bits: depth,
/// labels and RGB, on a procedural house, at a size that is not a multiple
/// of the tile (partial tiles), with a semantic range shorter than the
/// depth range.
#[test]
fn every_kernel_renders_the_same_frame() {
    use sornav_platform_sim::render::RenderKernel;
    use sornav_platform_sim::{NavMesh, NavMeshConfig};
    let scene = common::house(5, 1);
    let nav = NavMesh::build(&scene, &NavMeshConfig::default()).unwrap();
    let config = CameraConfig {
        width: 203,
        height: 117,
        rgb: true,
        semantic_max_depth: Some(3.0),
        ..CameraConfig::default()
    };
    let kernels: Vec<RenderKernel> = [
        RenderKernel::Reference,
        RenderKernel::Portable,
        RenderKernel::Avx2,
        RenderKernel::Auto,
    ]
    .into_iter()
    .filter(|k| k.is_available())
    .collect();
    let cameras: Vec<Camera> = kernels
        .iter()
        .map(|k| {
            Camera::for_scene(&scene, config.clone())
                .unwrap()
                .with_kernel(*k)
                .unwrap()
        })
        .collect();
    for k in 0..12u32 {
        let feet = nav.span_center((k as usize * nav.span_count() / 12) as u32);
        let yaw = f64::from(k) * 0.53;
        let pose = cameras[0].pose_at(&feet, yaw, [0.0, -0.7, 0.3, 1.2][k as usize % 4]);
        let reference = cameras[0].render(&pose, 0);
        assert!(reference.valid_depth_count() > 0);
        for (camera, kernel) in cameras.iter().zip(&kernels).skip(1) {
            let frame = camera.render(&pose, 0);
            let bits = |d: &[f32]| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert!(
                bits(&frame.depth) == bits(&reference.depth)
                    && frame.instance == reference.instance
                    && frame.rgb == reference.rgb,
                "{kernel:?} differs from the reference at pose {k}"
            );
        }
    }
}

/// `render_into` a frame that held another image (another pose, another
/// size, RGB or not) gives exactly the frame `render` returns, noise
/// included; an invalid pose clears it.
#[test]
fn render_into_a_used_frame_equals_render() {
    use sornav_platform_sim::noise::NoiseConfig;
    use sornav_platform_sim::{NavMesh, NavMeshConfig};
    let scene = common::house(2, 1);
    let nav = NavMesh::build(&scene, &NavMeshConfig::default()).unwrap();
    let noisy = CameraConfig {
        width: 96,
        height: 72,
        rgb: true,
        noise: NoiseConfig {
            depth_sigma: 0.02,
            missing_rate: 0.05,
            missed_detection_rate: 0.1,
            ..NoiseConfig::default()
        },
        ..CameraConfig::default()
    };
    let cameras = [
        Camera::for_scene(&scene, CameraConfig::default()).unwrap(),
        Camera::for_scene(&scene, noisy).unwrap(),
        Camera::for_scene(
            &scene,
            CameraConfig {
                width: 37,
                height: 21,
                ..CameraConfig::default()
            },
        )
        .unwrap(),
    ];
    let mut frame = cameras[0].render(&cameras[0].pose_at(&nav.span_center(0), 0.0, 0.0), 0);
    for k in 0..9u32 {
        let camera = &cameras[k as usize % 3];
        let feet = nav.span_center((k as usize * nav.span_count() / 9) as u32);
        let pose = camera.pose_at(&feet, f64::from(k) * 1.3, 0.0);
        camera.render_into(&pose, u64::from(k), &mut frame);
        let fresh = camera.render(&pose, u64::from(k));
        assert!(frame == fresh, "pose {k}");
    }
    let bad = CameraPose {
        position: Point3::new(f64::NAN, 0.0, 1.0),
        yaw: 0.0,
        pitch: 0.0,
    };
    cameras[1].render_into(&bad, 0, &mut frame);
    assert!(
        frame.depth.iter().all(|d| *d == 0.0) && frame.instance.iter().all(|i| *i == NO_INSTANCE)
    );
    assert!(
        frame
            .rgb
            .as_ref()
            .is_some_and(|c| c.iter().all(|p| *p == [0; 3]))
    );
}
