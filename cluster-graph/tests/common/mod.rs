//! References shared by the integration tests.

use std::collections::{BTreeSet, VecDeque};

/// Connected components of `ids` under the symmetric relation `joined`
/// (an edge of cost `<= rho_c`), by breadth-first search over all pairs:
/// the reference for the union-find grouping.
pub fn bfs_components<Id: Copy + Ord>(
    ids: &[Id],
    joined: impl Fn(Id, Id) -> bool,
) -> BTreeSet<Vec<Id>> {
    let mut seen = vec![false; ids.len()];
    let mut out = BTreeSet::new();
    for s in 0..ids.len() {
        if std::mem::replace(&mut seen[s], true) {
            continue;
        }
        let (mut comp, mut queue) = (vec![ids[s]], VecDeque::from([s]));
        while let Some(u) = queue.pop_front() {
            for v in 0..ids.len() {
                if !seen[v] && joined(ids[u], ids[v]) {
                    seen[v] = true;
                    comp.push(ids[v]);
                    queue.push_back(v);
                }
            }
        }
        comp.sort_unstable();
        out.insert(comp);
    }
    out
}
