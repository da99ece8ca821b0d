//! Grouping frontiers into clusters by low-cost connectivity.

use petgraph::unionfind::UnionFind;

/// Groups `n` nodes into the connected components of the thresholded edge
/// set `{(a, b) : w_ab <= rho_c}`.
///
/// This is SOR-Nav's frontier grouping: `v_i ~ v_j` iff a chain of edges,
/// each of cost `<= rho_c`, joins them. Frontiers that are close in space but
/// joined only by a long detour (an expensive edge) stay apart.
///
/// # Parameters
/// * `n`: number of nodes, indexed `0..n`.
/// * `edges`: `(a, b, w_ab)` with `a, b < n`; edges naming an index `>= n`
///   or with a cost that is not `<= rho_c` (including NaN) are skipped.
/// * `rho_c`: the cost threshold.
///
/// # Returns
/// The groups, each sorted ascending, ordered by their smallest member. Every
/// node is in exactly one group (isolated nodes are singletons).
///
/// # Algorithm
/// Disjoint-set union (petgraph's [`UnionFind`], union by rank with path
/// compression) over the kept edges, then one labelling pass.
///
/// # Complexity
/// O(n + E α(n)) time, O(n) extra space.
///
/// # Example
/// ```
/// use sornav_cluster_graph::connected_groups;
///
/// // 0 - 1 cheap, 1 - 2 expensive (a wall between them), 3 alone.
/// let groups = connected_groups(4, [(0, 1, 3.0), (1, 2, 40.0)], 25.0);
/// assert_eq!(groups, vec![vec![0, 1], vec![2], vec![3]]);
/// ```
pub fn connected_groups(
    n: usize,
    edges: impl IntoIterator<Item = (usize, usize, f64)>,
    rho_c: f64,
) -> Vec<Vec<usize>> {
    let mut sets = UnionFind::<usize>::new(n);
    for (a, b, w) in edges {
        if a < n && b < n && w <= rho_c {
            sets.union(a, b);
        }
    }
    // Nodes are visited in increasing order, so the first time a root is seen
    // is at its group's smallest member: groups come out ordered and sorted.
    let mut group_of_root = vec![usize::MAX; n];
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (node, root) in sets.into_labeling().into_iter().enumerate() {
        if group_of_root[root] == usize::MAX {
            group_of_root[root] = groups.len();
            groups.push(Vec::new());
        }
        groups[group_of_root[root]].push(node);
    }
    groups
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_and_isolated() {
        assert!(connected_groups(0, [], 1.0).is_empty());
        assert_eq!(connected_groups(2, [], 1.0), vec![vec![0], vec![1]]);
    }

    #[test]
    fn threshold_is_inclusive_and_nan_never_joins() {
        let g = connected_groups(3, [(0, 1, 25.0), (1, 2, f64::NAN)], 25.0);
        assert_eq!(g, vec![vec![0, 1], vec![2]]);
    }

    #[test]
    fn chains_join_transitively() {
        let g = connected_groups(5, [(4, 2, 1.0), (0, 4, 1.0), (1, 3, 30.0)], 25.0);
        assert_eq!(g, vec![vec![0, 2, 4], vec![1], vec![3]]);
    }

    #[test]
    fn out_of_range_indices_are_skipped() {
        assert_eq!(connected_groups(1, [(0, 5, 0.0)], 1.0), vec![vec![0]]);
    }
}
