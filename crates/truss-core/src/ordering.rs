//! Numbering the nodes so the stiffness matrix has a narrow band of 3×3 node blocks.
//!
//! Nodes with at least one free direction ("active" nodes) are ordered by reverse
//! Cuthill–McKee (breadth-first from a pseudo-peripheral node, neighbours by increasing
//! degree, then reversed); active node number `b` owns the scalar rows `3b, 3b+1, 3b+2`.
//! For the paper's prism this numbers the nodes level by level and gives a block
//! half-bandwidth of 5, whatever the number of stages. Ties are broken by node index, so
//! the numbering (and with it every rounding in the solver) is deterministic.

use std::collections::VecDeque;

/// The numbering: each node's block (None for a fully fixed node), the number of blocks,
/// and the block half-bandwidth that results for the given members.
pub(crate) struct NodeNumbering {
    pub block: Vec<Option<usize>>,
    pub blocks: usize,
    pub bandwidth: usize,
}

/// Numbers the active nodes among `fixed.len()` nodes joined by `edges` (node pairs).
pub(crate) fn number_nodes(fixed: &[[bool; 3]], edges: &[[usize; 2]]) -> NodeNumbering {
    let n = fixed.len();
    let active: Vec<bool> = fixed.iter().map(|f| f.iter().any(|&x| !x)).collect();
    let mut adjacency = vec![Vec::new(); n];
    for &[a, b] in edges {
        if a != b && active[a] && active[b] {
            adjacency[a].push(b);
            adjacency[b].push(a);
        }
    }
    for list in &mut adjacency {
        list.sort_unstable();
        list.dedup();
    }
    let order = reverse_cuthill_mckee(&adjacency, &active);
    let mut block = vec![None; n];
    for (b, &node) in order.iter().enumerate() {
        block[node] = Some(b);
    }
    let bandwidth = edges
        .iter()
        .filter_map(|&[a, b]| Some(block[a]?.abs_diff(block[b]?)))
        .max()
        .unwrap_or(0);
    NodeNumbering {
        block,
        blocks: order.len(),
        bandwidth,
    }
}

/// Reverse Cuthill–McKee order of the active nodes, component by component.
fn reverse_cuthill_mckee(adjacency: &[Vec<usize>], active: &[bool]) -> Vec<usize> {
    let n = adjacency.len();
    let degree = |v: usize| adjacency[v].len();
    let mut visited = vec![false; n];
    let mut order = Vec::with_capacity(n);
    // The unvisited active node of least degree starts the next component.
    while let Some(seed) = (0..n)
        .filter(|&v| active[v] && !visited[v])
        .min_by_key(|&v| (degree(v), v))
    {
        let start = pseudo_peripheral(adjacency, seed);
        let first = order.len();
        visited[start] = true;
        order.push(start);
        let mut head = first;
        while head < order.len() {
            let v = order[head];
            head += 1;
            let mut next: Vec<usize> = adjacency[v]
                .iter()
                .copied()
                .filter(|&w| !visited[w])
                .collect();
            next.sort_unstable_by_key(|&w| (degree(w), w));
            for w in next {
                visited[w] = true;
                order.push(w);
            }
        }
        order[first..].reverse();
    }
    order
}

/// A node far from the others in its component (George & Liu's heuristic): repeat a
/// breadth-first search from the least-degree node of the last level while the depth grows.
fn pseudo_peripheral(adjacency: &[Vec<usize>], seed: usize) -> usize {
    let mut start = seed;
    let (mut depth, mut last) = bfs_levels(adjacency, start);
    for _ in 0..8 {
        let candidate = *last
            .iter()
            .min_by_key(|&&v| (adjacency[v].len(), v))
            .expect("a level is never empty");
        let (d, l) = bfs_levels(adjacency, candidate);
        if d <= depth {
            break;
        }
        (start, depth, last) = (candidate, d, l);
    }
    start
}

/// Depth of the breadth-first search from `start`, and the nodes of its last level.
fn bfs_levels(adjacency: &[Vec<usize>], start: usize) -> (usize, Vec<usize>) {
    let mut level = vec![usize::MAX; adjacency.len()];
    level[start] = 0;
    let mut queue = VecDeque::from([start]);
    let mut depth = 0;
    while let Some(v) = queue.pop_front() {
        depth = depth.max(level[v]);
        for &w in &adjacency[v] {
            if level[w] == usize::MAX {
                level[w] = level[v] + 1;
                queue.push_back(w);
            }
        }
    }
    let last = (0..adjacency.len())
        .filter(|&v| level[v] == depth)
        .collect();
    (depth, last)
}
