//! 2D ray traversal (Amanatides & Woo, "A Fast Voxel Traversal Algorithm for
//! Ray Tracing", Eurographics 1987).

use nalgebra::Point2;

use crate::Cell;

/// Visits, in order, every cell the segment `a -> b` passes through (both end
/// cells included). Coordinates are world metres, `res` the cell size.
///
/// # Complexity
/// O(L) for a segment crossing L cells.
pub(crate) fn traverse(a: &Point2<f64>, b: &Point2<f64>, res: f64, mut visit: impl FnMut(Cell)) {
    let (sx, sy) = (a.x / res, a.y / res);
    let (ex, ey) = (b.x / res, b.y / res);
    // Callers validated both points (finite, |coord| < 2^24 cells).
    #[allow(clippy::cast_possible_truncation)]
    let (mut cx, mut cy) = (sx.floor() as i32, sy.floor() as i32);
    #[allow(clippy::cast_possible_truncation)]
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
    // Exactly |tx - cx| + |ty - cy| steps reach the end cell; the bound also
    // guards against floating-point drift.
    let steps = (tx - cx).unsigned_abs() + (ty - cy).unsigned_abs();
    visit(Cell::new(cx, cy));
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
        visit(Cell::new(cx, cy));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

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
    }
}
