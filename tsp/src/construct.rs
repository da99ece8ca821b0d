//! Tour construction: nearest neighbour and cheapest insertion.

/// Nearest-neighbour closed tour over the row-major `m x m` matrix `c`,
/// starting at node 0; ties go to the lowest index.
///
/// # Complexity
/// `O(m^2)`.
pub(crate) fn nearest_neighbour(c: &[f64], m: usize) -> Vec<usize> {
    let mut visited = vec![false; m];
    let mut order = Vec::with_capacity(m);
    let mut cur = 0;
    visited[0] = true;
    order.push(0);
    for _ in 1..m {
        let row = &c[cur * m..(cur + 1) * m];
        let next = (0..m)
            .filter(|&j| !visited[j])
            .min_by(|&x, &y| row[x].total_cmp(&row[y]).then(x.cmp(&y)))
            .unwrap_or(cur);
        visited[next] = true;
        order.push(next);
        cur = next;
    }
    order
}

/// Inserts each node of `missing` (in the given order) into the open path
/// `order` where it increases the path cost least. The first node stays
/// first; with `keep_last`, the last node stays last.
///
/// # Complexity
/// `O(|missing| * m)`.
pub(crate) fn cheapest_insertion(
    c: &[f64],
    m: usize,
    order: &mut Vec<usize>,
    missing: &[usize],
    keep_last: bool,
) {
    for &v in missing {
        let len = order.len();
        let (mut best, mut at) = (f64::INFINITY, len);
        if !keep_last && let Some(&last) = order.last() {
            best = c[last * m + v];
        }
        for t in 0..len.saturating_sub(1) {
            let (x, y) = (order[t], order[t + 1]);
            let delta = c[x * m + v] + c[v * m + y] - c[x * m + y];
            if delta < best {
                best = delta;
                at = t + 1;
            }
        }
        order.insert(at, v);
    }
}
