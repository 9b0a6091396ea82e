//! The cloth mesh's 1-ring as compressed rows: for each vertex, its neighbours along mesh edges.
//! Self-contact excludes adjacent pairs with it; the start-inside plan walks patches with it.

/// `(start, neighbours)`: vertex `v`'s neighbours are `neighbours[start[v]..start[v + 1]]`, in
/// the order of `edges` (each `[low, high]` once). Edges with an end at or past `n` are left out.
pub(crate) fn one_ring(edges: &[[u32; 2]], n: usize) -> (Vec<u32>, Vec<u32>) {
    let within = |e: &&[u32; 2]| (e[0] as usize) < n && (e[1] as usize) < n;
    let mut start = vec![0u32; n + 1];
    for e in edges.iter().filter(within) {
        start[e[0] as usize + 1] += 1;
        start[e[1] as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut neighbours = vec![0u32; start[n] as usize];
    for e in edges.iter().filter(within) {
        for (a, b) in [(e[0], e[1]), (e[1], e[0])] {
            neighbours[fill[a as usize] as usize] = b;
            fill[a as usize] += 1;
        }
    }
    (start, neighbours)
}
