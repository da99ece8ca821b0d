//! Geometric pre-ranking of clusters, `U_geo`.

use std::cmp::Ordering;

/// SOR-Nav's geometric utility of a cluster,
/// `U_geo(C_k) = n_k (1 + eta r_k) / (1 + d_k)`.
///
/// # Parameters
/// * `members`: `n_k`, the number of member frontiers.
/// * `spread`: `r_k`, the cluster's spread (m): the RMS distance of the
///   member positions to the cluster centre, see
///   [`crate::Cluster::spread`].
/// * `distance`: `d_k`, the robot-to-cluster graph distance `w_rk`.
/// * `eta`: the spread weight (paper: 0.1).
///
/// Large clusters, spread-out clusters and near clusters score high. With
/// finite, non-negative inputs the result is finite and non-negative.
///
/// # Complexity
/// O(1).
///
/// # Example
/// ```
/// use sornav_cluster_graph::geometric_utility;
///
/// // 4 frontiers spread 2 m, 9 m of path away, eta = 0.1:
/// let u = geometric_utility(4, 2.0, 9.0, 0.1);
/// assert!((u - 4.0 * 1.2 / 10.0).abs() < 1e-12);
/// ```
pub fn geometric_utility(members: usize, spread: f64, distance: f64, eta: f64) -> f64 {
    // Member counts are far below 2^52: the conversion is exact.
    #[allow(clippy::cast_precision_loss)]
    let n = members as f64;
    n * (1.0 + eta * spread) / (1.0 + distance)
}

/// The ranking order: higher utility first, then the nearer cluster (smaller
/// `d_k`), then the smaller cluster index, so that the order is total and
/// deterministic.
pub(crate) fn ranking_order(a: (f64, f64, usize), b: (f64, f64, usize)) -> Ordering {
    b.0.total_cmp(&a.0)
        .then(a.1.total_cmp(&b.1))
        .then(a.2.cmp(&b.2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utility_matches_the_formula() {
        assert_eq!(geometric_utility(1, 0.0, 0.0, 0.1), 1.0);
        assert_eq!(geometric_utility(10, 5.0, 1.0, 0.1), 7.5);
        assert_eq!(geometric_utility(3, 100.0, 3.0, 0.0), 0.75);
    }

    #[test]
    fn order_breaks_ties_by_distance_then_index() {
        let mut v = [(1.0, 5.0, 2), (2.0, 9.0, 1), (1.0, 3.0, 3), (1.0, 3.0, 0)];
        v.sort_by(|&a, &b| ranking_order(a, b));
        let idx: Vec<usize> = v.iter().map(|e| e.2).collect();
        assert_eq!(idx, vec![1, 0, 3, 2]);
    }
}
