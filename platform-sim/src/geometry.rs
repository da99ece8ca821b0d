//! Geometry helpers shared by the importers and the procedural generator:
//! a labelled mesh builder, polygon triangulation (ear clipping) and convex
//! clipping.

use nalgebra::{Isometry3, Point2, Point3, Vector3};

use crate::scene::{Aabb, InstanceId, InstanceKind, Level, ObjectInstance, Room, SceneDescription};

/// Signed area of a polygon (positive when counter-clockwise).
///
/// # Complexity
/// O(n).
pub fn polygon_area(poly: &[Point2<f64>]) -> f64 {
    let n = poly.len();
    let mut a = 0.0;
    for i in 0..n {
        let (p, q) = (poly[i], poly[(i + 1) % n]);
        a += p.x * q.y - q.x * p.y;
    }
    a * 0.5
}

/// Even-odd point-in-polygon test.
///
/// # Complexity
/// O(n).
pub fn point_in_polygon(p: &Point2<f64>, poly: &[Point2<f64>]) -> bool {
    let n = poly.len();
    let mut inside = false;
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (a, b) = (poly[i], poly[j]);
        if (a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x {
            inside = !inside;
        }
        j = i;
    }
    inside
}

fn cross(o: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
}

/// Triangulates a simple polygon by ear clipping. Returns index triples into
/// `poly`, counter-clockwise. Duplicate consecutive points are skipped; when no
/// ear can be found (self-intersecting input) the remainder is fanned so that
/// no area is lost silently.
///
/// # Complexity
/// O(n^2) for n vertices (room polygons have tens of vertices).
pub fn triangulate(poly: &[Point2<f64>]) -> Vec<[usize; 3]> {
    let mut idx: Vec<usize> = Vec::with_capacity(poly.len());
    for (i, p) in poly.iter().enumerate() {
        if idx.last().is_none_or(|&l| (poly[l] - p).norm() > 1e-9) {
            idx.push(i);
        }
    }
    while idx.len() > 1 && (poly[idx[0]] - poly[*idx.last().unwrap_or(&0)]).norm() <= 1e-9 {
        idx.pop();
    }
    if idx.len() < 3 {
        return Vec::new();
    }
    let sub: Vec<Point2<f64>> = idx.iter().map(|&i| poly[i]).collect();
    if polygon_area(&sub) < 0.0 {
        idx.reverse();
    }
    let mut out = Vec::with_capacity(idx.len() - 2);
    while idx.len() > 3 {
        let n = idx.len();
        let mut clipped = false;
        for i in 0..n {
            let (ia, ib, ic) = (idx[(i + n - 1) % n], idx[i], idx[(i + 1) % n]);
            let (a, b, c) = (poly[ia], poly[ib], poly[ic]);
            let cr = cross(&a, &b, &c);
            if cr <= 1e-12 {
                if cr.abs() <= 1e-12 {
                    // collinear vertex: drop it without emitting a triangle
                    idx.remove(i);
                    clipped = true;
                    break;
                }
                continue;
            }
            let contains = idx.iter().any(|&j| {
                if j == ia || j == ib || j == ic {
                    return false;
                }
                let p = poly[j];
                // strictly inside: vertices on the ear's border (collinear
                // runs, touching notches) do not block it
                cross(&a, &b, &p) > 1e-12 && cross(&b, &c, &p) > 1e-12 && cross(&c, &a, &p) > 1e-12
            });
            if !contains {
                out.push([ia, ib, ic]);
                idx.remove(i);
                clipped = true;
                break;
            }
        }
        if !clipped {
            // degenerate input: fan the rest
            for k in 1..idx.len() - 1 {
                out.push([idx[0], idx[k], idx[k + 1]]);
            }
            idx.clear();
            break;
        }
    }
    if idx.len() == 3 && cross(&poly[idx[0]], &poly[idx[1]], &poly[idx[2]]).abs() > 1e-12 {
        out.push([idx[0], idx[1], idx[2]]);
    }
    out
}

/// Clips a convex polygon against the half-plane `n . p <= c`.
///
/// # Complexity
/// O(n).
pub fn clip_halfplane(poly: &[Point2<f64>], n: nalgebra::Vector2<f64>, c: f64) -> Vec<Point2<f64>> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    let m = poly.len();
    for i in 0..m {
        let (p, q) = (poly[i], poly[(i + 1) % m]);
        let (dp, dq) = (n.dot(&p.coords) - c, n.dot(&q.coords) - c);
        if dp <= 0.0 {
            out.push(p);
        }
        if (dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0) {
            let t = dp / (dp - dq);
            out.push(p + (q - p) * t);
        }
    }
    out
}

/// Subtracts a convex polygon (counter-clockwise) from a convex polygon,
/// returning convex pieces that tile `poly \ hole`.
///
/// # Complexity
/// O(n m) for n and m vertices.
pub fn subtract_convex(poly: &[Point2<f64>], hole: &[Point2<f64>]) -> Vec<Vec<Point2<f64>>> {
    let mut pieces = Vec::new();
    let mut rest = poly.to_vec();
    let m = hole.len();
    for i in 0..m {
        if rest.len() < 3 {
            break;
        }
        let (a, b) = (hole[i], hole[(i + 1) % m]);
        let e = b - a;
        // outward normal of a counter-clockwise edge
        let n = nalgebra::Vector2::new(e.y, -e.x);
        let c = n.dot(&a.coords);
        let outside = clip_halfplane(&rest, -n, -c);
        if outside.len() >= 3 && polygon_area(&outside).abs() > 1e-10 {
            pieces.push(outside);
        }
        rest = clip_halfplane(&rest, n, c);
    }
    pieces
}

/// Accumulates a labelled triangle mesh and its instances, then produces a
/// [`SceneDescription`].
#[derive(Debug, Default, Clone)]
pub struct MeshBuilder {
    vertices: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    triangle_instances: Vec<InstanceId>,
    instances: Vec<ObjectInstance>,
}

impl MeshBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Registers a new instance (bounds are filled from its triangles).
    pub fn add_instance(
        &mut self,
        kind: InstanceKind,
        category: &str,
        name: &str,
        level: usize,
    ) -> InstanceId {
        let id = self.instances.len() as InstanceId;
        self.instances.push(ObjectInstance {
            id,
            kind,
            category: category.to_string(),
            name: name.to_string(),
            level,
            room: None,
            bounds: Aabb::empty(),
        });
        id
    }

    /// Number of triangles so far.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Instances so far.
    pub fn instances(&self) -> &[ObjectInstance] {
        &self.instances
    }

    /// Adds one triangle of instance `inst`. Non-finite triangles are skipped
    /// and reported as `false`.
    pub fn triangle(
        &mut self,
        a: Point3<f64>,
        b: Point3<f64>,
        c: Point3<f64>,
        inst: InstanceId,
    ) -> bool {
        if ![a, b, c]
            .iter()
            .all(|p| p.coords.iter().all(|v| v.is_finite()))
        {
            return false;
        }
        let base = self.vertices.len() as u32;
        for p in [a, b, c] {
            self.vertices.push([p.x as f32, p.y as f32, p.z as f32]);
            self.include_in_bounds(inst, p);
        }
        self.triangles.push([base, base + 1, base + 2]);
        self.triangle_instances.push(inst);
        true
    }

    /// Adds a planar quad (a, b, c, d in order) as two triangles.
    pub fn quad(
        &mut self,
        a: Point3<f64>,
        b: Point3<f64>,
        c: Point3<f64>,
        d: Point3<f64>,
        inst: InstanceId,
    ) {
        self.triangle(a, b, c, inst);
        self.triangle(a, c, d, inst);
    }

    /// Adds a box of half extents `half` placed by `pose` (all 12 triangles).
    pub fn oriented_box(&mut self, pose: &Isometry3<f64>, half: Vector3<f64>, inst: InstanceId) {
        let c =
            |sx: f64, sy: f64, sz: f64| pose * Point3::new(sx * half.x, sy * half.y, sz * half.z);
        let p = [
            c(-1., -1., -1.),
            c(1., -1., -1.),
            c(1., 1., -1.),
            c(-1., 1., -1.),
            c(-1., -1., 1.),
            c(1., -1., 1.),
            c(1., 1., 1.),
            c(-1., 1., 1.),
        ];
        self.hexahedron(&p, inst);
    }

    /// Adds a hexahedron given its bottom corners `p[0..4]` (counter-clockwise
    /// seen from above) and the top corners `p[4..8]` above them, with outward
    /// faces.
    pub fn hexahedron(&mut self, p: &[Point3<f64>; 8], inst: InstanceId) {
        for f in [
            [0, 3, 2, 1],
            [4, 5, 6, 7],
            [0, 1, 5, 4],
            [1, 2, 6, 5],
            [2, 3, 7, 6],
            [3, 0, 4, 7],
        ] {
            self.quad(p[f[0]], p[f[1]], p[f[2]], p[f[3]], inst);
        }
    }

    /// Adds an axis-aligned box.
    pub fn aabb_box(&mut self, min: Point3<f64>, max: Point3<f64>, inst: InstanceId) {
        let centre = nalgebra::center(&min, &max);
        self.oriented_box(
            &Isometry3::translation(centre.x, centre.y, centre.z),
            (max - min) * 0.5,
            inst,
        );
    }

    /// Adds a horizontal polygon at height `z` (triangulated; facing up when `up`).
    pub fn horizontal_polygon(&mut self, poly: &[Point2<f64>], z: f64, up: bool, inst: InstanceId) {
        for t in triangulate(poly) {
            let p = t.map(|i| Point3::new(poly[i].x, poly[i].y, z));
            if up {
                self.triangle(p[0], p[1], p[2], inst);
            } else {
                self.triangle(p[0], p[2], p[1], inst);
            }
        }
    }

    /// Extrudes a polygon from `z0` to `z1` (side faces and both caps).
    pub fn prism(&mut self, poly: &[Point2<f64>], z0: f64, z1: f64, inst: InstanceId) {
        let n = poly.len();
        if n < 3 {
            return;
        }
        let ccw = polygon_area(poly) >= 0.0;
        for i in 0..n {
            let (a, b) = if ccw {
                (poly[i], poly[(i + 1) % n])
            } else {
                (poly[(i + 1) % n], poly[i])
            };
            self.quad(
                Point3::new(a.x, a.y, z0),
                Point3::new(b.x, b.y, z0),
                Point3::new(b.x, b.y, z1),
                Point3::new(a.x, a.y, z1),
                inst,
            );
        }
        self.horizontal_polygon(poly, z1, true, inst);
        self.horizontal_polygon(poly, z0, false, inst);
    }

    /// Grows the bounds of `inst` to include `p` (for instances, such as door
    /// openings, whose extent is not given by triangles).
    pub fn include_in_bounds(&mut self, inst: InstanceId, p: Point3<f64>) {
        if let Some(i) = self.instances.get_mut(inst as usize) {
            i.bounds.include(&p);
        }
    }

    /// Finishes the mesh: assigns each object instance to the room containing
    /// its centre and returns the description.
    pub fn finish(mut self, name: &str, levels: Vec<Level>, rooms: Vec<Room>) -> SceneDescription {
        for inst in &mut self.instances {
            if inst.bounds.is_empty() {
                inst.bounds = Aabb {
                    min: Point3::origin(),
                    max: Point3::origin(),
                };
                continue;
            }
            let c = inst.bounds.center();
            inst.room = rooms.iter().position(|r| {
                r.level == inst.level && point_in_polygon(&Point2::new(c.x, c.y), &r.polygon)
            });
        }
        SceneDescription {
            name: name.to_string(),
            levels,
            rooms,
            instances: self.instances,
            vertices: self.vertices,
            triangles: self.triangles,
            triangle_instances: self.triangle_instances,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area_of(poly: &[Point2<f64>], tris: &[[usize; 3]]) -> f64 {
        tris.iter()
            .map(|t| polygon_area(&[poly[t[0]], poly[t[1]], poly[t[2]]]))
            .sum()
    }

    #[test]
    fn triangulation_preserves_area_and_orientation() {
        // L-shape with a collinear run and a small notch (as in Sweet Home 3D rooms)
        let poly: Vec<Point2<f64>> = [
            (2.2575, -2.3625),
            (2.2575, -2.4949),
            (2.2197, -2.4949),
            (2.2197, -3.4322),
            (2.2575, -3.4322),
            (2.2575, -4.4921),
            (2.3725, -4.4921),
            (2.3725, -4.518),
            (3.3875, -4.5227),
            (3.3875, -4.4921),
            (3.5042, -4.4921),
            (3.5042, -2.8614),
            (3.5042, -2.3625),
        ]
        .iter()
        .map(|&(x, y)| Point2::new(x, y))
        .collect();
        let tris = triangulate(&poly);
        let a = polygon_area(&poly).abs();
        assert!(
            (area_of(&poly, &tris) - a).abs() < 1e-9,
            "{} vs {a}",
            area_of(&poly, &tris)
        );
        for t in &tris {
            assert!(polygon_area(&[poly[t[0]], poly[t[1]], poly[t[2]]]) > 0.0);
        }
    }

    /// Polygon with vertices at sorted angles and the given radii around
    /// `c`; convex when all radii are equal.
    fn star(c: (f64, f64), angles: &[f64], radii: &[f64]) -> Vec<Point2<f64>> {
        let mut a: Vec<f64> = angles.to_vec();
        a.sort_by(f64::total_cmp);
        a.dedup_by(|x, y| (*x - *y).abs() < 1e-3);
        a.iter()
            .zip(radii.iter().cycle())
            .map(|(t, r)| Point2::new(c.0 + r * t.cos(), c.1 + r * t.sin()))
            .collect()
    }

    /// Angles (k + jitter_k) 2 pi / n: consecutive gaps stay below pi for
    /// n >= 4, so the polygon is star-shaped around its centre, hence simple.
    fn sector_angles(jitter: &[f64]) -> Vec<f64> {
        let n = jitter.len() as f64;
        jitter
            .iter()
            .enumerate()
            .map(|(k, j)| (k as f64 + j) * std::f64::consts::TAU / n)
            .collect()
    }

    /// Grid points of [-3, 3]^2 (step 0.07, offset so they avoid round numbers).
    fn grid() -> impl Iterator<Item = Point2<f64>> {
        (0..86).flat_map(|i| {
            (0..86).map(move |j| {
                Point2::new(
                    -3.0 + 0.0123 + 0.07 * i as f64,
                    -3.0 + 0.0371 + 0.07 * j as f64,
                )
            })
        })
    }

    proptest::proptest! {
        /// Ear clipping of random simple (star-shaped) polygons of either
        /// orientation: counter-clockwise triangles whose areas sum to the
        /// polygon's, and (differential test against the even-odd rule) a point
        /// is in the polygon iff it is in one of the triangles.
        #[test]
        fn triangulation_tiles_random_simple_polygons(
            jitter in proptest::collection::vec(0.0f64..1.0, 4..24),
            radii in proptest::collection::vec(0.3f64..2.5, 1..24),
            reverse in proptest::bool::ANY,
        ) {
            let mut poly = star((0.1, -0.2), &sector_angles(&jitter), &radii);
            proptest::prop_assume!(poly.len() >= 3 && polygon_area(&poly) > 1e-3);
            if reverse {
                poly.reverse();
            }
            let tris = triangulate(&poly);
            proptest::prop_assert!(tris.len() <= poly.len() - 2);
            for t in &tris {
                proptest::prop_assert!(polygon_area(&[poly[t[0]], poly[t[1]], poly[t[2]]]) > 0.0);
            }
            let a = polygon_area(&poly).abs();
            proptest::prop_assert!((area_of(&poly, &tris) - a).abs() < 1e-9 * a.max(1.0));
            for p in grid() {
                let inside = point_in_polygon(&p, &poly);
                let covered = tris.iter().any(|t| point_in_polygon(&p, &[poly[t[0]], poly[t[1]], poly[t[2]]]));
                proptest::prop_assert_eq!(inside, covered, "point {}", p);
            }
        }

        /// Subtracting a random convex hole from a random convex polygon:
        /// pieces are disjoint and cover exactly the points of the polygon
        /// outside the hole (differential test against point membership).
        #[test]
        fn subtract_convex_matches_point_membership(
            a1 in proptest::collection::vec(0.0f64..std::f64::consts::TAU, 3..10),
            a2 in proptest::collection::vec(0.0f64..std::f64::consts::TAU, 3..10),
            r1 in 1.0f64..2.8, r2 in 0.2f64..2.0,
            cx in -1.5f64..1.5, cy in -1.5f64..1.5,
        ) {
            let poly = star((0.0, 0.0), &a1, &[r1]);
            let hole = star((cx, cy), &a2, &[r2]);
            proptest::prop_assume!(poly.len() >= 3 && hole.len() >= 3);
            proptest::prop_assume!(polygon_area(&poly) > 1e-3 && polygon_area(&hole) > 1e-3);
            let pieces = subtract_convex(&poly, &hole);
            for p in grid() {
                let want = point_in_polygon(&p, &poly) && !point_in_polygon(&p, &hole);
                let n = pieces.iter().filter(|q| point_in_polygon(&p, q)).count();
                proptest::prop_assert!(n <= 1, "pieces overlap at {}", p);
                proptest::prop_assert_eq!(want, n == 1, "point {}", p);
            }
        }
    }

    #[test]
    fn subtract_convex_tiles_the_difference() {
        let sq = |x0: f64, y0: f64, x1: f64, y1: f64| {
            vec![
                Point2::new(x0, y0),
                Point2::new(x1, y0),
                Point2::new(x1, y1),
                Point2::new(x0, y1),
            ]
        };
        let pieces = subtract_convex(&sq(0.0, 0.0, 4.0, 4.0), &sq(1.0, 1.0, 2.0, 3.0));
        let a: f64 = pieces.iter().map(|p| polygon_area(p).abs()).sum();
        assert!((a - 14.0).abs() < 1e-9);
        assert!(
            pieces
                .iter()
                .all(|p| !point_in_polygon(&Point2::new(1.5, 2.0), p))
        );
    }
}
