//! A nested-dissection ordering of a block matrix's vertex graph, for the sparse Cholesky
//! factor ([`super::cholesky`]).
//!
//! A cloth is a two-dimensional mesh. Eliminating it in nested-dissection order (each half
//! before the band of vertices that separates it from the other, the bands last) bounds the
//! fill of its Cholesky factor far below minimum degree's on the bending springs' wide stencil.
//! The separators are levels of a breadth-first search from a peripheral vertex, which needs
//! only the graph: no positions, any mesh.

use super::BlockCsr;

/// Parts this small are not split further (their order within is the graph's).
const LEAF: usize = 48;

/// Vertex elimination order (`order[k]` is the vertex eliminated `k`-th).
pub(super) fn nested_dissection(a: &BlockCsr) -> Vec<usize> {
    let n = a.rows();
    let mut order = Vec::with_capacity(n);
    // Which part each vertex is in (parts are numbered as they are made).
    let mut part = vec![0u32; n];
    let mut next_part = 1u32;
    let mut level = vec![u32::MAX; n];
    let mut queue = Vec::new();
    // Work list: (part id, its vertices); a separator to append once both halves are ordered
    // is pushed as a part marked done.
    let mut stack: Vec<(bool, Vec<usize>)> = vec![(false, (0..n).collect())];
    while let Some((done, verts)) = stack.pop() {
        if done || verts.len() <= LEAF {
            order.extend_from_slice(&verts);
            continue;
        }
        let id = part[verts[0]];
        // A pseudo-peripheral start: the last vertex reached from the last vertex reached.
        let mut start = verts[0];
        for _ in 0..2 {
            bfs(a, &part, id, start, &mut level, &mut queue);
            start = *queue.last().unwrap_or(&start);
            queue.iter().for_each(|&v| level[v] = u32::MAX);
        }
        bfs(a, &part, id, start, &mut level, &mut queue);
        let reached = queue.len();
        let (mut halves, mut sep) = (Vec::new(), Vec::new());
        if reached < verts.len() {
            // Disconnected: the component reached and the rest are split without a separator.
            let (mut first, mut rest) = (Vec::new(), Vec::new());
            for &v in &verts {
                if level[v] == u32::MAX {
                    rest.push(v);
                } else {
                    first.push(v);
                }
            }
            halves.push(first);
            halves.push(rest);
        } else {
            // The level in which the count reaches half: its vertices separate the levels
            // before it from those after (edges join levels at most one apart).
            let middle = level[queue[reached / 2]];
            let (mut lo, mut hi) = (Vec::new(), Vec::new());
            for &v in &verts {
                match level[v].cmp(&middle) {
                    std::cmp::Ordering::Less => lo.push(v),
                    std::cmp::Ordering::Equal => sep.push(v),
                    std::cmp::Ordering::Greater => hi.push(v),
                }
            }
            if lo.is_empty() || hi.is_empty() {
                // A graph too dense to separate by levels: keep its order.
                queue.iter().for_each(|&v| level[v] = u32::MAX);
                order.extend_from_slice(&verts);
                continue;
            }
            halves.push(lo);
            halves.push(hi);
        }
        queue.iter().for_each(|&v| level[v] = u32::MAX);
        stack.push((true, sep));
        for h in halves {
            for &v in &h {
                part[v] = next_part;
            }
            next_part += 1;
            stack.push((false, h));
        }
    }
    order
}

/// Breadth-first levels from `start` within part `id`: `queue` ends as the vertices reached in
/// order, `level` holds their levels.
fn bfs(
    a: &BlockCsr,
    part: &[u32],
    id: u32,
    start: usize,
    level: &mut [u32],
    queue: &mut Vec<usize>,
) {
    queue.clear();
    queue.push(start);
    level[start] = 0;
    let mut head = 0;
    while head < queue.len() {
        let v = queue[head];
        head += 1;
        let (cols, _) = a.row(v);
        for &j in cols {
            let j = j as usize;
            if part[j] == id && level[j] == u32::MAX {
                level[j] = level[v] + 1;
                queue.push(j);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::PatternBuilder;

    /// A grid with distance-two couplings: the order is a permutation, and the last vertices
    /// are a separator (removing them leaves the first half unconnected to the second).
    #[test]
    fn order_is_a_permutation_ending_in_a_separator() {
        let res = 20u32;
        let mut p = PatternBuilder::new();
        for y in 0..res {
            for x in 0..res {
                let i = y * res + x;
                for (dx, dy) in [(1, 0), (0, 1), (2, 0), (0, 2), (1, 1)] {
                    if x + dx < res && y + dy < res {
                        p.couple(i, (y + dy) * res + x + dx);
                    }
                }
            }
        }
        let a = p.build((res * res) as usize);
        let order = nested_dissection(&a);
        let mut seen = order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..a.rows()).collect::<Vec<_>>());
        assert_ne!(order, seen, "a grid this size is dissected");
    }
}
