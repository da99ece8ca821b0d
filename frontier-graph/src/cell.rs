//! Grid cells and the world <-> cell mapping.

use nalgebra::Point2;
use serde::{Deserialize, Serialize};

use crate::FrontierError;

/// Largest absolute cell coordinate a world point may map to (2^24).
///
/// Coordinates beyond it are rejected with [`FrontierError::OutOfRange`]; this
/// keeps all cell arithmetic far from `i32` overflow.
pub const MAX_CELL_COORD: i32 = 1 << 24;

/// A cell of the 2D grid, in global integer coordinates: cell `(x, y)` covers
/// the world square `[x r, (x + 1) r) x [y r, (y + 1) r)` for resolution `r`.
///
/// Cells are global (they do not move when the grid grows), so they can be
/// stored across updates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Cell {
    /// Column.
    pub x: i32,
    /// Row.
    pub y: i32,
}

impl Cell {
    /// Creates a cell.
    pub const fn new(x: i32, y: i32) -> Self {
        Self { x, y }
    }

    /// Cell `(x + dx, y + dy)`.
    pub const fn offset(self, dx: i32, dy: i32) -> Self {
        Self::new(self.x + dx, self.y + dy)
    }
}

/// World x/y (m) of the centre of `cell` at `resolution`.
pub fn cell_center(cell: Cell, resolution: f64) -> Point2<f64> {
    Point2::new(
        (f64::from(cell.x) + 0.5) * resolution,
        (f64::from(cell.y) + 0.5) * resolution,
    )
}

/// `t.floor() as i32` for `|t| < 2^31` (every cell coordinate passes
/// [`MAX_CELL_COORD`] first): a truncation and a correction, two
/// instructions where `f64::floor` is a library call on baseline x86-64
/// (no SSE4.1 `roundsd`); it runs for every point and ray of a scan.
#[inline]
pub(crate) fn floor_i32(t: f64) -> i32 {
    // In range by the caller's contract.
    #[allow(clippy::cast_possible_truncation)]
    let i = t as i32;
    if f64::from(i) > t { i - 1 } else { i }
}

/// The cell containing the world point `p`.
///
/// # Errors
/// [`FrontierError::NonFinite`] / [`FrontierError::OutOfRange`] for NaN,
/// infinite or too distant coordinates (`what` and `index` name the input).
pub fn cell_of(
    p: &Point2<f64>,
    resolution: f64,
    what: &'static str,
    index: usize,
) -> Result<Cell, FrontierError> {
    scaled_cell_of(p, resolution, what, index).map(|(_, cell)| cell)
}

/// [`cell_of`], also returning `p` in cell units (`p / resolution`, the
/// coordinates the cell is the floor of), for a caller that goes on to
/// walk a ray there ([`crate::raycast::RayOrigin::ray_to`]).
///
/// # Errors
/// As [`cell_of`].
#[inline]
pub(crate) fn scaled_cell_of(
    p: &Point2<f64>,
    resolution: f64,
    what: &'static str,
    index: usize,
) -> Result<((f64, f64), Cell), FrontierError> {
    if !p.x.is_finite() || !p.y.is_finite() {
        return Err(FrontierError::NonFinite { what, index });
    }
    let (sx, sy) = (p.x / resolution, p.y / resolution);
    match (cell_coord(sx), cell_coord(sy)) {
        (Some(x), Some(y)) => Ok(((sx, sy), Cell::new(x, y))),
        _ => Err(FrontierError::OutOfRange {
            what,
            x: p.x,
            y: p.y,
        }),
    }
}

/// `floor(t)` as a cell coordinate when `|floor(t)| < MAX_CELL_COORD`,
/// `None` beyond or for NaN.
#[inline]
pub(crate) fn cell_coord(t: f64) -> Option<i32> {
    // |floor(t)| < lim exactly when 1 - lim <= t < lim (lim is an integer);
    // NaN fails both comparisons.
    let lim = f64::from(MAX_CELL_COORD);
    (1.0 - lim <= t && t < lim).then(|| floor_i32(t))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn floor_i32_examples() {
        for (t, f) in [
            (0.0, 0),
            (-0.0, 0),
            (0.5, 0),
            (-0.5, -1),
            (-1.0, -1),
            (1.0, 1),
            (-1.0 - f64::EPSILON, -2),
            (2147483647.0, i32::MAX),
            (-2147483648.0, i32::MIN),
        ] {
            assert_eq!(floor_i32(t), f, "{t}");
        }
    }

    /// The range check is the one on `floor`, at the limits too.
    #[test]
    fn cell_of_limits() {
        let lim = f64::from(MAX_CELL_COORD);
        for t in [
            lim - 1.0,
            lim - 0.5,
            lim,
            1.0 - lim,
            0.5 - lim,
            -lim,
            -lim - 0.5,
        ] {
            let reference = t.floor().abs() >= lim;
            let got = cell_of(&Point2::new(t, 0.0), 1.0, "p", 0);
            assert_eq!(got.is_err(), reference, "{t}");
            let got = cell_of(&Point2::new(0.0, t), 1.0, "p", 0);
            assert_eq!(got.is_err(), reference, "{t}");
        }
    }

    #[test]
    fn cell_coord_refuses_nan_and_infinities() {
        assert_eq!(cell_coord(f64::NAN), None);
        assert_eq!(cell_coord(f64::INFINITY), None);
        assert_eq!(cell_coord(f64::NEG_INFINITY), None);
    }

    proptest! {
        /// Differential against `f64::floor` over the whole `i32` range and
        /// near integers.
        #[test]
        fn floor_i32_matches_floor(
            t in prop_oneof![
                -2.1e9f64..2.1e9,
                -100.0f64..100.0,
                (-1000i32..1000, -3i64..=3).prop_map(|(k, u)| {
                    f64::from_bits((f64::from(k).to_bits() as i64 + u) as u64)
                }),
            ]
        ) {
            prop_assert_eq!(floor_i32(t), t.floor() as i32);
        }

        /// Differential: the cell (or the error) is the one computed with
        /// `f64::floor`.
        #[test]
        fn cell_of_matches_floor(
            x in prop_oneof![-1.0e6f64..1.0e6, -20.0f64..20.0],
            y in prop_oneof![-1.0e6f64..1.0e6, -20.0f64..20.0],
            res in prop_oneof![Just(0.05), 0.01f64..1.0],
        ) {
            let (fx, fy) = ((x / res).floor(), (y / res).floor());
            let lim = f64::from(MAX_CELL_COORD);
            let got = cell_of(&Point2::new(x, y), res, "p", 0);
            if fx.abs() >= lim || fy.abs() >= lim {
                prop_assert!(got.is_err());
            } else {
                prop_assert_eq!(got.ok(), Some(Cell::new(fx as i32, fy as i32)));
            }
        }
    }
}
