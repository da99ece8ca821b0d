//! Synthetic two-floor scenes of axis-aligned boxes and an analytic ray
//! caster that produces returns as a robot's depth sensor would (the eye at
//! feet + 0.88 m, the returns on the first surface each ray hits).
//!
//! Layout in the scene's local frame (u along the stair, v across), then
//! turned by a multiple of 90 degrees and shifted:
//!
//! ```text
//!  v ^ outer walls                           roof at H + 2.6
//!    | +----------------------------------------------+
//!    | | table   platform |side wall|   floor 1 (z=H)  |
//!    | |  (0.75)  (drop)  |=========|   mezzanine over |
//!    | |    floor 0       | stair ->|   floor 0        |
//!    | |  (z = 0)         |=========|                  |
//!    | +----------------------------------------------+--> u
//!              u = us (foot)     u = top
//! ```

use nalgebra::{Point2, Point3, Vector3};

/// Axis-aligned solid box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
}

impl Aabb {
    /// Whether the horizontal position lies in the box's footprint grown by `m`.
    pub fn covers_xy(&self, p: Point2<f64>, m: f64) -> bool {
        p.x >= self.lo[0] - m
            && p.x <= self.hi[0] + m
            && p.y >= self.lo[1] - m
            && p.y <= self.hi[1] + m
    }

    /// Entry parameter of the ray `o + t d` (t > 1e-9), if it hits.
    fn hit(&self, o: &Point3<f64>, d: &Vector3<f64>) -> Option<f64> {
        let (mut t0, mut t1) = (1e-9f64, f64::INFINITY);
        for a in 0..3 {
            if d[a].abs() < 1e-15 {
                if o[a] < self.lo[a] || o[a] > self.hi[a] {
                    return None;
                }
                continue;
            }
            let (mut ta, mut tb) = ((self.lo[a] - o[a]) / d[a], (self.hi[a] - o[a]) / d[a]);
            if ta > tb {
                std::mem::swap(&mut ta, &mut tb);
            }
            t0 = t0.max(ta);
            t1 = t1.min(tb);
            if t0 > t1 {
                return None;
            }
        }
        Some(t0)
    }
}

/// Parameters of a scene.
#[derive(Debug, Clone, Copy)]
pub struct SceneParams {
    pub rise: f64,
    pub tread: f64,
    pub width: f64,
    /// Quarter turns of the layout.
    pub turn: u8,
    pub offset: (f64, f64),
    /// A flat landing (1 m deep) half-way up.
    pub landing: bool,
    /// Walls beside the stair (left, right); an open side drops to floor 0.
    pub walls: (bool, bool),
    /// A platform of this height (a sheer drop, higher than a step).
    pub platform: Option<f64>,
    /// A table (top at 0.75 m).
    pub table: bool,
    /// Where the stair starts across the building (0..1).
    pub across: f64,
}

/// A generated scene with its ground truth.
#[derive(Debug, Clone)]
pub struct Scene {
    pub boxes: Vec<Aabb>,
    /// Height of floor 1.
    pub h: f64,
    pub steps: usize,
    /// Horizontal run of the stair from the first riser to the top (m).
    pub run: f64,
    pub platform: Option<Aabb>,
    pub table: Option<Aabb>,
    /// Feet positions of the scans: floor 0, on the stair, floor 1.
    pub feet: Vec<Point3<f64>>,
    pub params: SceneParams,
}

const LV: f64 = 7.0;
const US: f64 = 5.5;

impl Scene {
    pub fn new(p: SceneParams) -> Self {
        let steps = (2.5 / p.rise).round() as usize;
        let h = steps as f64 * p.rise;
        let landing_at = steps / 2;
        let vs = 1.0 + p.across * (LV - 2.0 - p.width);
        let (v0, v1) = (vs, vs + p.width);
        let vc = 0.5 * (v0 + v1);
        let mut local: Vec<Aabb> = Vec::new();
        let bx = |u0: f64, v0: f64, z0: f64, u1: f64, v1: f64, z1: f64| Aabb {
            lo: [u0, v0, z0],
            hi: [u1, v1, z1],
        };
        // Steps (solid), with the landing.
        let mut u = US;
        let mut mid_feet = Vec::new();
        for i in 1..=steps {
            let z = i as f64 * p.rise;
            local.push(bx(u, v0, 0.0, u + p.tread, v1, z));
            if i == steps / 4 || i == steps / 2 || i == 3 * steps / 4 {
                mid_feet.push(Point3::new(u + 0.5 * p.tread, vc, z));
            }
            u += p.tread;
            if p.landing && i == landing_at {
                local.push(bx(u, v0, 0.0, u + 1.0, v1, z));
                u += 1.0;
            }
        }
        let top = u;
        let run = top - US;
        let lu = top + 4.0;
        let roof = h + 2.6;
        // Floors, roof, outer walls.
        local.push(bx(0.0, 0.0, -0.2, lu, LV, 0.0));
        local.push(bx(top, 0.0, h - 0.2, lu, LV, h));
        local.push(bx(-0.1, -0.1, roof, lu + 0.1, LV + 0.1, roof + 0.2));
        local.push(bx(-0.1, -0.1, -0.2, 0.0, LV + 0.1, roof));
        local.push(bx(lu, -0.1, -0.2, lu + 0.1, LV + 0.1, roof));
        local.push(bx(-0.1, -0.1, -0.2, lu + 0.1, 0.0, roof));
        local.push(bx(-0.1, LV, -0.2, lu + 0.1, LV + 0.1, roof));
        // Walls beside the stair.
        if p.walls.0 {
            local.push(bx(US, v0 - 0.1, 0.0, top, v0, h + 1.0));
        }
        if p.walls.1 {
            local.push(bx(US, v1, 0.0, top, v1 + 0.1, h + 1.0));
        }
        // Furniture on floor 0, in front of the stair.
        let table = p.table.then(|| bx(0.6, 0.6, 0.71, 1.8, 1.4, 0.75));
        if let Some(t) = table {
            local.push(t);
            for (a, b) in [(0.6, 0.6), (1.75, 0.6), (0.6, 1.35), (1.75, 1.35)] {
                local.push(bx(a, b, 0.0, a + 0.05, b + 0.05, 0.71));
            }
        }
        let platform = p
            .platform
            .map(|hp| bx(0.6, LV - 2.6, 0.0, 2.6, LV - 0.6, hp));
        local.extend(platform);
        let feet_local = {
            let mut f = vec![
                Point3::new(US - 1.2, vc, 0.0),
                Point3::new(3.2, 0.5 * LV, 0.0),
            ];
            f.extend(mid_feet);
            f.push(Point3::new(top + 1.2, vc, h));
            f.push(Point3::new(top + 2.6, 0.5 * LV, h));
            f
        };
        let tr = |q: [f64; 3]| -> [f64; 3] {
            let (x, y) = match p.turn % 4 {
                0 => (q[0], q[1]),
                1 => (-q[1], q[0]),
                2 => (-q[0], -q[1]),
                _ => (q[1], -q[0]),
            };
            [x + p.offset.0, y + p.offset.1, q[2]]
        };
        let tb = |b: Aabb| {
            let (a, c) = (tr(b.lo), tr(b.hi));
            Aabb {
                lo: [a[0].min(c[0]), a[1].min(c[1]), a[2]],
                hi: [a[0].max(c[0]), a[1].max(c[1]), c[2]],
            }
        };
        Scene {
            boxes: local.iter().map(|b| tb(*b)).collect(),
            h,
            steps,
            run,
            platform: platform.map(tb),
            table: table.map(tb),
            feet: feet_local
                .iter()
                .map(|f| {
                    let q = tr([f.x, f.y, f.z]);
                    Point3::new(q[0], q[1], q[2])
                })
                .collect(),
            params: p,
        }
    }

    /// First hit of the ray from `o` along `d`.
    pub fn cast(&self, o: &Point3<f64>, d: &Vector3<f64>) -> Option<Point3<f64>> {
        self.boxes
            .iter()
            .filter_map(|b| b.hit(o, d))
            .min_by(f64::total_cmp)
            .map(|t| o + d * t)
    }

    /// A depth-like scan from `eye`: rays aimed at horizontal lattices
    /// (about `spacing`, within `radius`) on planes 0.88, 0.4 and 0.15 m below
    /// the eye (floors, treads seen from near and far, faces) and on a
    /// coarser one 1.6 m above it (ceilings, risers above the eye). Returns farther than `range` are
    /// replaced by a point at `range + 1` along the ray (a truncated ray).
    pub fn scan(
        &self,
        eye: &Point3<f64>,
        spacing: f64,
        radius: f64,
        range: f64,
    ) -> Vec<Point3<f64>> {
        let mut out = Vec::new();
        let planes = [
            (-0.88, spacing, radius),
            (-0.4, 0.85 * spacing, radius),
            (-0.15, 0.7 * spacing, 0.75 * radius),
            (1.6, 2.0 * spacing, radius),
        ];
        for (dz, sp, radius) in planes {
            let n = (radius / sp).ceil() as i32;
            for i in -n..=n {
                for j in -n..=n {
                    let (x, y) = (f64::from(i) * sp, f64::from(j) * sp);
                    if x.hypot(y) > radius {
                        continue;
                    }
                    let d = Vector3::new(x, y, dz).normalize();
                    match self.cast(eye, &d) {
                        Some(p) if (p - eye).norm() <= range => out.push(p),
                        _ => out.push(eye + d * (range + 1.0)),
                    }
                }
            }
        }
        out
    }
}
