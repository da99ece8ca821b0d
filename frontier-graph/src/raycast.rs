//! 2D ray traversal (Amanatides & Woo, "A Fast Voxel Traversal Algorithm for
//! Ray Tracing", Eurographics 1987).

use nalgebra::Point2;

use crate::Cell;
use crate::cell::floor_i32;

/// The cells a segment passes through, as a start cell and the sequence of
/// 4-connected moves from it to the end cell (Amanatides & Woo).
/// [`Ray::walk`] follows the moves on any position type (a dense grid
/// index moves by `±1` or `±width` per move, so the cells need not be
/// mapped one by one); [`traverse`] is the cell-by-cell form.
///
/// The cells are monotone along both axes: every move brings the cell
/// closer to the end cell, so each cell is visited once and the end cell
/// only by the last move (or at the start for a segment within one cell).
///
/// # Complexity
/// O(1) to build, O(1) per move.
#[derive(Debug, Clone)]
pub(crate) struct Ray {
    start: Cell,
    step_x: i32,
    step_y: i32,
    t_max_x: f64,
    t_max_y: f64,
    t_delta_x: f64,
    t_delta_y: f64,
    /// Moves left along x and along y.
    left_x: u32,
    left_y: u32,
}

/// The start of rays that share it (a scan's sensor origin): its
/// coordinates in cell units and its cell, computed once for all of them.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RayOrigin {
    sx: f64,
    sy: f64,
    cx: i32,
    cy: i32,
}

impl RayOrigin {
    /// The origin `a` (world metres) over cells of size `res`; `a` was
    /// validated (finite, |coord| < 2^24 cells).
    #[inline]
    pub(crate) fn new(a: &Point2<f64>, res: f64) -> Self {
        let (sx, sy) = (a.x / res, a.y / res);
        Self {
            sx,
            sy,
            cx: floor_i32(sx),
            cy: floor_i32(sy),
        }
    }

    /// The ray from this origin to the end `(ex, ey)` in cell units (the
    /// end in world metres divided by the resolution), whose cell `end`
    /// (the floors of `ex` and `ey`) the caller computed while validating
    /// it ([`crate::cell::scaled_cell_of`]): the ray [`Ray::new`] builds,
    /// without dividing and flooring again.
    #[inline]
    pub(crate) fn ray_to(&self, (ex, ey): (f64, f64), end: Cell) -> Ray {
        let Self { sx, sy, cx, cy } = *self;
        let (tx, ty) = (end.x, end.y);
        let (dx, dy) = (ex - sx, ey - sy);
        let step_x = if dx > 0.0 { 1 } else { -1 };
        let step_y = if dy > 0.0 { 1 } else { -1 };
        let t_delta_x = if dx == 0.0 {
            f64::INFINITY
        } else {
            1.0 / dx.abs()
        };
        let t_delta_y = if dy == 0.0 {
            f64::INFINITY
        } else {
            1.0 / dy.abs()
        };
        let t_max_x = if dx > 0.0 {
            (f64::from(cx) + 1.0 - sx) / dx
        } else if dx < 0.0 {
            (sx - f64::from(cx)) / -dx
        } else {
            f64::INFINITY
        };
        let t_max_y = if dy > 0.0 {
            (f64::from(cy) + 1.0 - sy) / dy
        } else if dy < 0.0 {
            (sy - f64::from(cy)) / -dy
        } else {
            f64::INFINITY
        };
        // Exactly |tx - cx| + |ty - cy| moves reach the end cell (the step
        // signs point at it); counting them also guards against
        // floating-point drift.
        Ray {
            start: Cell::new(cx, cy),
            step_x,
            step_y,
            t_max_x,
            t_max_y,
            t_delta_x,
            t_delta_y,
            left_x: (tx - cx).unsigned_abs(),
            left_y: (ty - cy).unsigned_abs(),
        }
    }
}

impl Ray {
    /// The ray of the segment `a -> b` (world metres) over cells of size
    /// `res`. Callers validated both points (finite, |coord| < 2^24 cells).
    #[inline]
    pub(crate) fn new(a: &Point2<f64>, b: &Point2<f64>, res: f64) -> Self {
        let (ex, ey) = (b.x / res, b.y / res);
        RayOrigin::new(a, res).ray_to((ex, ey), Cell::new(floor_i32(ex), floor_i32(ey)))
    }

    /// The cell of the segment's start.
    pub(crate) fn start(&self) -> Cell {
        self.start
    }

    /// The cell offsets of a move along x and of a move along y: `(±1,
    /// ±1)`.
    pub(crate) fn direction(&self) -> (i32, i32) {
        (self.step_x, self.step_y)
    }

    /// Visits `start` and then, in order, the position after each move
    /// (`along_x` and `along_y` give the position one move further);
    /// returns the last position (the end cell's).
    ///
    /// While both axes have moves left, the axis whose next cell border is
    /// nearer along the segment moves (y on a tie); then the remaining
    /// moves of the other axis follow.
    #[inline]
    pub(crate) fn walk<P: Copy>(
        mut self,
        start: P,
        along_x: impl Fn(P) -> P,
        along_y: impl Fn(P) -> P,
        mut visit: impl FnMut(P),
    ) -> P {
        let mut p = start;
        visit(p);
        while self.left_x > 0 && self.left_y > 0 {
            if self.t_max_x < self.t_max_y {
                p = along_x(p);
                self.left_x -= 1;
                self.t_max_x += self.t_delta_x;
            } else {
                p = along_y(p);
                self.left_y -= 1;
                self.t_max_y += self.t_delta_y;
            }
            visit(p);
        }
        for _ in 0..self.left_x {
            p = along_x(p);
            visit(p);
        }
        for _ in 0..self.left_y {
            p = along_y(p);
            visit(p);
        }
        p
    }

    /// The number of moves from the start cell to the end cell.
    #[cfg(test)]
    fn moves(&self) -> usize {
        self.left_x as usize + self.left_y as usize
    }
}

/// Visits, in order, every cell the segment `a -> b` passes through (both end
/// cells included). Coordinates are world metres, `res` the cell size.
///
/// # Complexity
/// O(L) for a segment crossing L cells.
pub(crate) fn traverse(a: &Point2<f64>, b: &Point2<f64>, res: f64, visit: impl FnMut(Cell)) {
    let ray = Ray::new(a, b, res);
    let (sx, sy) = ray.direction();
    let start = ray.start();
    ray.walk(start, |c| c.offset(sx, 0), |c| c.offset(0, sy), visit);
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The traversal as first written (Amanatides & Woo with `f64::floor`
    /// and cell coordinates compared against the end cell): the reference
    /// the move-based [`Ray`] must reproduce cell for cell.
    fn reference_traverse(a: &Point2<f64>, b: &Point2<f64>, res: f64) -> Vec<Cell> {
        let (sx, sy) = (a.x / res, a.y / res);
        let (ex, ey) = (b.x / res, b.y / res);
        let (mut cx, mut cy) = (sx.floor() as i32, sy.floor() as i32);
        let (tx, ty) = (ex.floor() as i32, ey.floor() as i32);
        let (dx, dy) = (ex - sx, ey - sy);
        let step_x = if dx > 0.0 { 1 } else { -1 };
        let step_y = if dy > 0.0 { 1 } else { -1 };
        let t_delta_x = if dx == 0.0 {
            f64::INFINITY
        } else {
            1.0 / dx.abs()
        };
        let t_delta_y = if dy == 0.0 {
            f64::INFINITY
        } else {
            1.0 / dy.abs()
        };
        let mut t_max_x = if dx > 0.0 {
            (f64::from(cx) + 1.0 - sx) / dx
        } else if dx < 0.0 {
            (sx - f64::from(cx)) / -dx
        } else {
            f64::INFINITY
        };
        let mut t_max_y = if dy > 0.0 {
            (f64::from(cy) + 1.0 - sy) / dy
        } else if dy < 0.0 {
            (sy - f64::from(cy)) / -dy
        } else {
            f64::INFINITY
        };
        let steps = (tx - cx).unsigned_abs() + (ty - cy).unsigned_abs();
        let mut cells = vec![Cell::new(cx, cy)];
        for _ in 0..steps {
            let go_x = if cx == tx {
                false
            } else if cy == ty {
                true
            } else {
                t_max_x < t_max_y
            };
            if go_x {
                cx += step_x;
                t_max_x += t_delta_x;
            } else {
                cy += step_y;
                t_max_y += t_delta_y;
            }
            cells.push(Cell::new(cx, cy));
        }
        cells
    }

    /// Coordinates on and near cell borders (multiples of the resolution,
    /// nudged by an ulp or so) as well as anywhere, at several magnitudes.
    fn coordinate() -> impl Strategy<Value = f64> {
        prop_oneof![
            -20.0f64..20.0,
            (-400i32..400, -2i32..=2).prop_map(|(k, ulps)| {
                let x = f64::from(k) * 0.05;
                let bits = x.to_bits() as i64 + i64::from(ulps);
                f64::from_bits(bits as u64)
            }),
            -1.0e5f64..1.0e5,
            Just(0.0),
            Just(-0.0),
        ]
    }

    proptest! {
        #[test]
        fn ray_is_4_connected_and_ends_at_target(
            ax in -20.0f64..20.0, ay in -20.0f64..20.0,
            bx in -20.0f64..20.0, by in -20.0f64..20.0,
        ) {
            let (a, b) = (Point2::new(ax, ay), Point2::new(bx, by));
            let mut cells = Vec::new();
            traverse(&a, &b, 0.5, |c| cells.push(c));
            let first = Cell::new((ax / 0.5).floor() as i32, (ay / 0.5).floor() as i32);
            let last = Cell::new((bx / 0.5).floor() as i32, (by / 0.5).floor() as i32);
            prop_assert_eq!(cells[0], first);
            prop_assert_eq!(*cells.last().unwrap(), last);
            for w in cells.windows(2) {
                prop_assert_eq!((w[0].x - w[1].x).abs() + (w[0].y - w[1].y).abs(), 1);
            }
            // Every visited cell is within one cell of the segment.
            let d = b - a;
            for c in &cells {
                let p = Point2::new((f64::from(c.x) + 0.5) * 0.5, (f64::from(c.y) + 0.5) * 0.5);
                let t = if d.norm_squared() > 0.0 { ((p - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0) } else { 0.0 };
                prop_assert!((a + d * t - p).norm() <= 0.5 * std::f64::consts::SQRT_2 + 1e-9);
            }
        }

        /// Differential: the move-based traversal visits exactly the cells
        /// of the reference, in the same order, including segments along a
        /// grid line, within one cell, or starting and ending on borders.
        #[test]
        fn traverse_matches_the_reference(
            ax in coordinate(), ay in coordinate(),
            bx in coordinate(), by in coordinate(),
            res in prop_oneof![Just(0.05), Just(0.1), 0.01f64..1.0],
        ) {
            let (a, b) = (Point2::new(ax, ay), Point2::new(bx, by));
            prop_assume!((ax - bx).abs() / res + (ay - by).abs() / res < 1.0e5);
            let mut cells = Vec::new();
            traverse(&a, &b, res, |c| cells.push(c));
            prop_assert_eq!(cells, reference_traverse(&a, &b, res));
            let ray = Ray::new(&a, &b, res);
            prop_assert_eq!(ray.moves() + 1, reference_traverse(&a, &b, res).len());
        }

        /// Differential: a ray built from a shared [`RayOrigin`] and the
        /// end's validated cell ([`crate::cell::scaled_cell_of`]), as the
        /// occupancy grid builds its scan's rays, visits the cells of the
        /// reference.
        #[test]
        fn ray_from_origin_matches_the_reference(
            ax in coordinate(), ay in coordinate(),
            bx in coordinate(), by in coordinate(),
            res in prop_oneof![Just(0.05), Just(0.1), 0.01f64..1.0],
        ) {
            let (a, b) = (Point2::new(ax, ay), Point2::new(bx, by));
            prop_assume!((ax - bx).abs() / res + (ay - by).abs() / res < 1.0e5);
            let (scaled, end) = crate::cell::scaled_cell_of(&b, res, "b", 0).unwrap();
            let ray = RayOrigin::new(&a, res).ray_to(scaled, end);
            let (sx, sy) = ray.direction();
            let start = ray.start();
            let mut cells = Vec::new();
            ray.walk(start, |c| c.offset(sx, 0), |c| c.offset(0, sy), |c| cells.push(c));
            prop_assert_eq!(cells, reference_traverse(&a, &b, res));
        }

    }
}
