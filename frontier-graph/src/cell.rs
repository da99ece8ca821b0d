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
    if !p.x.is_finite() || !p.y.is_finite() {
        return Err(FrontierError::NonFinite { what, index });
    }
    let fx = (p.x / resolution).floor();
    let fy = (p.y / resolution).floor();
    let lim = f64::from(MAX_CELL_COORD);
    if fx.abs() >= lim || fy.abs() >= lim {
        return Err(FrontierError::OutOfRange {
            what,
            x: p.x,
            y: p.y,
        });
    }
    // In range by the check above.
    #[allow(clippy::cast_possible_truncation)]
    Ok(Cell::new(fx as i32, fy as i32))
}
