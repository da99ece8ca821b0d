//! Dense, validated cost matrices.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::error::TspError;

/// A dense `n x n` matrix of finite arc costs, `cost(i, j)` = cost of going
/// from node `i` to node `j`. Costs may be asymmetric; the diagonal is never
/// read by the solvers.
///
/// Construction validates that every entry is finite and at most
/// [`MAX_ABS_COST`] in magnitude, so the solvers never see a NaN and no
/// route cost, DP entry or move delta can overflow to infinity. Forbidden
/// arcs are expressed with a large finite cost (far below the bound, for
/// example `1e9`).
///
/// # Examples
/// ```
/// use sornav_tsp::CostMatrix;
/// let m = CostMatrix::from_fn(3, |i, j| (i as f64 - j as f64).abs())?;
/// assert_eq!(m.len(), 3);
/// assert_eq!(m.cost(0, 2), 2.0);
/// # Ok::<(), sornav_tsp::TspError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawMatrix", into = "RawMatrix")]
pub struct CostMatrix {
    n: usize,
    data: Vec<f64>,
}

/// Serialised form of [`CostMatrix`] (validated on deserialisation).
#[derive(Serialize, Deserialize)]
struct RawMatrix {
    n: usize,
    /// Row-major entries.
    data: Vec<f64>,
}

impl TryFrom<RawMatrix> for CostMatrix {
    type Error = TspError;
    fn try_from(raw: RawMatrix) -> Result<Self, TspError> {
        CostMatrix::new(raw.n, raw.data)
    }
}

impl From<CostMatrix> for RawMatrix {
    fn from(m: CostMatrix) -> Self {
        RawMatrix {
            n: m.n,
            data: m.data,
        }
    }
}

/// Largest accepted magnitude of a cost entry: sums of up to `10^8`
/// entries (any route through a matrix that fits in memory) stay finite.
pub const MAX_ABS_COST: f64 = 1.0e300;

impl CostMatrix {
    /// A matrix from `n * n` row-major entries.
    ///
    /// # Errors
    /// [`TspError::Empty`] for `n == 0`, [`TspError::NotSquare`] when the
    /// length is not `n * n`, [`TspError::NonFinite`] for NaN or infinite
    /// entries, [`TspError::CostOutOfRange`] for a finite entry of magnitude
    /// above [`MAX_ABS_COST`].
    pub fn new(n: usize, data: Vec<f64>) -> Result<Self, TspError> {
        if n == 0 {
            return Err(TspError::Empty);
        }
        if n.checked_mul(n) != Some(data.len()) {
            return Err(TspError::NotSquare { n, len: data.len() });
        }
        if let Some(k) = data.iter().position(|v| !v.is_finite()) {
            return Err(TspError::NonFinite {
                row: k / n,
                col: k % n,
                value: data[k],
            });
        }
        if let Some(k) = data.iter().position(|v| v.abs() > MAX_ABS_COST) {
            return Err(TspError::CostOutOfRange {
                row: k / n,
                col: k % n,
                value: data[k],
            });
        }
        Ok(Self { n, data })
    }

    /// A matrix whose entry `(i, j)` is `f(i, j)`.
    ///
    /// # Errors
    /// As [`CostMatrix::new`].
    pub fn from_fn(n: usize, mut f: impl FnMut(usize, usize) -> f64) -> Result<Self, TspError> {
        let mut data = Vec::with_capacity(n.saturating_mul(n));
        for i in 0..n {
            for j in 0..n {
                data.push(f(i, j));
            }
        }
        Self::new(n, data)
    }

    /// A matrix from rows.
    ///
    /// # Errors
    /// [`TspError::RaggedRow`] when a row's length differs from the number
    /// of rows, otherwise as [`CostMatrix::new`].
    pub fn from_rows(rows: &[Vec<f64>]) -> Result<Self, TspError> {
        let n = rows.len();
        if let Some((row, r)) = rows.iter().enumerate().find(|(_, r)| r.len() != n) {
            return Err(TspError::RaggedRow {
                row,
                len: r.len(),
                n,
            });
        }
        Self::new(n, rows.concat())
    }

    /// A matrix from a square nalgebra matrix (`m[(i, j)]` = cost `i -> j`).
    ///
    /// # Errors
    /// [`TspError::NotSquare`] for a non-square input, otherwise as
    /// [`CostMatrix::new`].
    pub fn from_dmatrix(m: &DMatrix<f64>) -> Result<Self, TspError> {
        if m.nrows() != m.ncols() {
            return Err(TspError::NotSquare {
                n: m.nrows(),
                len: m.len(),
            });
        }
        Self::from_fn(m.nrows(), |i, j| m[(i, j)])
    }

    /// The same costs as a nalgebra matrix.
    pub fn to_dmatrix(&self) -> DMatrix<f64> {
        DMatrix::from_row_slice(self.n, self.n, &self.data)
    }

    /// Number of nodes.
    #[allow(clippy::len_without_is_empty)] // never empty by construction
    pub fn len(&self) -> usize {
        self.n
    }

    /// Cost of the arc `i -> j`.
    ///
    /// # Panics
    /// When `i` or `j` is `>= len()`.
    #[inline]
    pub fn cost(&self, i: usize, j: usize) -> f64 {
        assert!(i < self.n && j < self.n, "node out of range");
        self.data[i * self.n + j]
    }

    /// Row-major entries.
    pub fn as_slice(&self) -> &[f64] {
        &self.data
    }

    /// Whether `cost(i, j) == cost(j, i)` for all `i != j`.
    pub fn is_symmetric(&self) -> bool {
        (0..self.n).all(|i| (0..i).all(|j| self.data[i * self.n + j] == self.data[j * self.n + i]))
    }

    /// Cost of visiting `order` in sequence (an open path: no return arc).
    ///
    /// # Errors
    /// [`TspError::NodeOutOfRange`] for an index `>= len()`.
    pub fn path_cost(&self, order: &[usize]) -> Result<f64, TspError> {
        self.check_nodes(order)?;
        Ok(order
            .windows(2)
            .map(|w| self.data[w[0] * self.n + w[1]])
            .sum())
    }

    /// Cost of the closed tour `order` (including the arc back to `order[0]`).
    ///
    /// # Errors
    /// [`TspError::NodeOutOfRange`] for an index `>= len()`.
    pub fn tour_cost(&self, order: &[usize]) -> Result<f64, TspError> {
        let path = self.path_cost(order)?;
        Ok(match (order.first(), order.last()) {
            (Some(&f), Some(&l)) if order.len() > 1 => path + self.data[l * self.n + f],
            _ => path,
        })
    }

    fn check_nodes(&self, order: &[usize]) -> Result<(), TspError> {
        match order.iter().find(|&&v| v >= self.n) {
            Some(&node) => Err(TspError::NodeOutOfRange { node, n: self.n }),
            None => Ok(()),
        }
    }
}
