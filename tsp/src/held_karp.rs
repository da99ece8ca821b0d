//! Exact dynamic programming (Held-Karp) for small closed ATSP tours.

/// Largest instance the exact Held-Karp solver accepts (after the open-path
/// reduction, see [`crate::Solver`]): its `2^(n-1) (n-1)` table
/// entries are about 90 MB at `n = 20`.
pub const HELD_KARP_MAX_NODES: usize = 20;

/// Optimal closed tour through all `m` nodes of the row-major matrix `c`,
/// starting (and ending) at node 0. Returns the order (node 0 first) and its
/// cost.
///
/// # Algorithm
/// Held & Karp (1962): `D[S][j]` is the cheapest path that leaves node 0,
/// visits exactly the set `S` of other nodes and ends at `j in S`;
/// `D[S][j] = min_{i in S \ {j}} D[S \ {j}][i] + c(i, j)`. The tour closes
/// with the cheapest `D[all][j] + c(j, 0)`. Ties keep the lowest index, so
/// the result is deterministic.
///
/// # Complexity
/// `O(2^m m^2)` time and `O(2^m m)` memory. Callers keep
/// `m <= HELD_KARP_MAX_NODES`.
pub(crate) fn solve_closed(c: &[f64], m: usize) -> (Vec<usize>, f64) {
    debug_assert!((1..=HELD_KARP_MAX_NODES).contains(&m) && c.len() == m * m);
    match m {
        1 => return (vec![0], 0.0),
        2 => return (vec![0, 1], c[1] + c[m]),
        _ => {}
    }
    let k = m - 1; // nodes 1..m are bits 0..k
    let full = (1usize << k) - 1;
    let mut dp = vec![f64::INFINITY; (full + 1) * k];
    let mut parent = vec![u8::MAX; (full + 1) * k];
    for j in 0..k {
        dp[(1 << j) * k + j] = c[j + 1];
    }
    for mask in 1..=full {
        for j in 0..k {
            if mask & (1 << j) == 0 {
                continue;
            }
            let prev = mask & !(1 << j);
            if prev == 0 {
                continue;
            }
            let row = prev * k;
            let mut best = f64::INFINITY;
            let mut arg = u8::MAX;
            let mut rest = prev;
            while rest != 0 {
                let i = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                let v = dp[row + i] + c[(i + 1) * m + j + 1];
                if v < best {
                    best = v;
                    arg = i as u8;
                }
            }
            dp[mask * k + j] = best;
            parent[mask * k + j] = arg;
        }
    }
    let (mut last, mut best) = (0, f64::INFINITY);
    for j in 0..k {
        let v = dp[full * k + j] + c[(j + 1) * m];
        if v < best {
            best = v;
            last = j;
        }
    }
    (backtrack(&parent, k, last), best)
}

/// The order of a subset DP over nodes `1..=k` (bit `j` = node `j + 1`)
/// from node 0: `parent[mask * k + j]` is the node visited before `j` in
/// the best path over `mask` ending at `j` (`u8::MAX` for the first), and
/// `last` ends the best path over all of them. Node 0 first.
pub(crate) fn backtrack(parent: &[u8], k: usize, last: usize) -> Vec<usize> {
    let mut order = Vec::with_capacity(k + 1);
    let mut mask = (1usize << k) - 1;
    let mut j = last;
    loop {
        order.push(j + 1);
        let p = parent[mask * k + j];
        mask &= !(1 << j);
        if p == u8::MAX {
            break;
        }
        j = usize::from(p);
    }
    order.push(0);
    order.reverse();
    order
}
