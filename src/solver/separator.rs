//! One level of nested dissection for the two-core Cholesky (`split_cholesky.rs`): a vertex
//! separator Σ of the matrix graph that splits the other equations into two halves with no
//! coupling between them (George & Liu, "Computer Solution of Large Sparse Positive Definite
//! Systems", 1981, §8: level-structure separators from a pseudo-peripheral vertex).
//!
//! The graph is taken on the quotient of indistinguishable equations (consecutive equations
//! with the same closed adjacency, i.e. a node's DOFs), so a node's DOFs stay together.
//! Disconnected components are distributed between the halves whole; a component too large
//! to be placed whole is cut at the BFS level where the cumulative weight crosses the
//! half, and separator vertices that touch one side only are moved to it.

use std::collections::VecDeque;

/// Which part of the dissection an equation belongs to.
pub(super) const HALF1: u8 = 0;
/// Second half.
pub(super) const HALF2: u8 = 1;
/// The separator Σ.
pub(super) const SEP: u8 = 2;

/// Quotient graph: supervertices (runs of indistinguishable equations) with their weights
/// (equation counts) and adjacency in CSR form.
struct Quotient {
    /// First equation of each supervertex, and n at the end.
    first: Vec<usize>,
    adj_ptr: Vec<usize>,
    adj: Vec<usize>,
}

impl Quotient {
    fn len(&self) -> usize {
        self.first.len() - 1
    }
    fn weight(&self, v: usize) -> usize {
        self.first[v + 1] - self.first[v]
    }
    fn neighbours(&self, v: usize) -> &[usize] {
        &self.adj[self.adj_ptr[v]..self.adj_ptr[v + 1]]
    }
}

/// Full symmetric adjacency (without the diagonal) of the upper-triangular CSC pattern.
fn symmetric_adjacency(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let mut count = vec![0usize; n + 1];
    for c in 0..n {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            if r != c {
                count[r] += 1;
                count[c] += 1;
            }
        }
    }
    let mut ptr = vec![0usize; n + 1];
    for i in 0..n {
        ptr[i + 1] = ptr[i] + count[i];
    }
    let mut fill = ptr[..n].to_vec();
    let mut adj = vec![0usize; ptr[n]];
    for c in 0..n {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            if r != c {
                adj[fill[r]] = c;
                fill[r] += 1;
                adj[fill[c]] = r;
                fill[c] += 1;
            }
        }
    }
    for i in 0..n {
        adj[ptr[i]..ptr[i + 1]].sort_unstable();
    }
    (ptr, adj)
}

/// Closed neighbourhoods of equations i and j = i + 1 are equal (both sorted lists).
fn indistinguishable(ptr: &[usize], adj: &[usize], i: usize) -> bool {
    let (a, b) = (&adj[ptr[i]..ptr[i + 1]], &adj[ptr[i + 1]..ptr[i + 2]]);
    // N[i] = a ∪ {i}, N[i+1] = b ∪ {i+1}: equal iff a contains i+1, b contains i and
    // a \ {i+1} = b \ {i}.
    if a.len() != b.len() {
        return false;
    }
    let mut ia = a.iter().filter(|&&x| x != i + 1);
    let mut ib = b.iter().filter(|&&x| x != i);
    if a.binary_search(&(i + 1)).is_err() || b.binary_search(&i).is_err() {
        return false;
    }
    loop {
        match (ia.next(), ib.next()) {
            (None, None) => return true,
            (Some(x), Some(y)) if x == y => {}
            _ => return false,
        }
    }
}

fn quotient(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Quotient {
    let (ptr, adj) = symmetric_adjacency(n, col_ptr, row_idx);
    let mut first = vec![0usize];
    let mut vertex_of = vec![0usize; n];
    for i in 0..n {
        if i > 0 && !indistinguishable(&ptr, &adj, i - 1) {
            first.push(i);
        }
        vertex_of[i] = first.len() - 1;
    }
    first.push(n);
    let nv = first.len() - 1;
    let mut adj_ptr = vec![0usize];
    let mut qadj = Vec::new();
    for v in 0..nv {
        let i = first[v];
        let mut row: Vec<usize> = adj[ptr[i]..ptr[i + 1]].iter().map(|&j| vertex_of[j]).filter(|&w| w != v).collect();
        row.dedup(); // sorted by equation, so by supervertex: duplicates are consecutive
        qadj.extend_from_slice(&row);
        adj_ptr.push(qadj.len());
    }
    Quotient { first, adj_ptr, adj: qadj }
}

/// Breadth-first level of every vertex reachable from `root` (usize::MAX elsewhere);
/// returns the vertices in visiting order.
fn bfs(g: &Quotient, root: usize, level: &mut [usize]) -> Vec<usize> {
    let mut order = vec![root];
    level[root] = 0;
    let mut queue = VecDeque::from([root]);
    while let Some(v) = queue.pop_front() {
        for &w in g.neighbours(v) {
            if level[w] == usize::MAX {
                level[w] = level[v] + 1;
                order.push(w);
                queue.push_back(w);
            }
        }
    }
    order
}

/// Pseudo-peripheral vertex of the component of `start` (George & Liu 1979): repeated BFS
/// from a minimum-degree vertex of the last level while the eccentricity grows.
fn pseudo_peripheral(g: &Quotient, start: usize, level: &mut [usize]) -> usize {
    let mut root = start;
    let mut ecc = None;
    for _ in 0..8 {
        let order = bfs(g, root, level);
        let last = order.last().map_or(0, |&v| level[v]);
        let next = order
            .iter()
            .filter(|&&v| level[v] == last)
            .min_by_key(|&&v| g.neighbours(v).len())
            .copied()
            .unwrap_or(root);
        for &v in &order {
            level[v] = usize::MAX;
        }
        if ecc.is_some_and(|e| last <= e) {
            break;
        }
        ecc = Some(last);
        root = next;
    }
    root
}

/// Candidate roots of the level structure of each kind (side middles, boundary vertices).
const ROOT_CANDIDATES: usize = 12;

/// Splits the component `vertices` at the BFS level from `root` where the cumulative weight
/// reaches `target`: lower levels HALF1, the level SEP, higher levels HALF2; a separator
/// vertex with no neighbour in one half joins the other. Returns the separator's weight.
fn level_cut(g: &Quotient, vertices: &[usize], root: usize, target: usize, level: &mut [usize], part_v: &mut [u8]) -> usize {
    let order = bfs(g, root, level);
    let mut acc = 0;
    let mut cut = usize::MAX;
    for &u in &order {
        acc += g.weight(u);
        if acc >= target {
            cut = level[u];
            break;
        }
    }
    for &u in vertices {
        part_v[u] = match level[u].cmp(&cut) {
            std::cmp::Ordering::Less => HALF1,
            std::cmp::Ordering::Equal => SEP,
            std::cmp::Ordering::Greater => HALF2,
        };
        level[u] = usize::MAX;
    }
    let mut weight = 0;
    for &u in vertices {
        if part_v[u] != SEP {
            continue;
        }
        let touches = |h: u8| g.neighbours(u).iter().any(|&w| part_v[w] == h);
        if !touches(HALF2) {
            part_v[u] = HALF1;
        } else if !touches(HALF1) {
            part_v[u] = HALF2;
        } else {
            weight += g.weight(u);
        }
    }
    weight
}

/// Assignment of each equation to HALF1, HALF2 or SEP. Every coupling of the pattern is
/// within a half, within Σ, or between a half and Σ.
pub(super) fn dissect(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Vec<u8> {
    let g = quotient(n, col_ptr, row_idx);
    let nv = g.len();
    // Connected components, largest first.
    let mut comp = vec![usize::MAX; nv];
    let mut level = vec![usize::MAX; nv];
    let mut comps: Vec<(usize, usize, Vec<usize>)> = Vec::new(); // (weight, root, vertices)
    for v in 0..nv {
        if comp[v] != usize::MAX {
            continue;
        }
        let order = bfs(&g, v, &mut level);
        let w: usize = order.iter().map(|&u| g.weight(u)).sum();
        for &u in &order {
            comp[u] = comps.len();
            level[u] = usize::MAX;
        }
        comps.push((w, v, order));
    }
    comps.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut part_v = vec![HALF1; nv];
    let mut load = [0usize; 2];
    let mut rest = comps.as_slice();
    if let Some((w, root, vertices)) = comps.first() {
        if 2 * w > n {
            // Cut the largest component at a middle BFS level; of the candidate roots (a
            // pseudo-peripheral vertex and low-degree, i.e. boundary, vertices spread over
            // the component) keep the smallest trimmed separator.
            // Boundary vertices at half the eccentricity from the pseudo-peripheral vertex
            // are the middles of its sides: BFS from there cuts a rectangle straight across.
            let r0 = pseudo_peripheral(&g, *root, &mut level);
            let mut candidates = vec![r0];
            let min_degree = vertices.iter().map(|&u| g.neighbours(u).len()).min().unwrap_or(0);
            let boundary: Vec<usize> = vertices.iter().copied().filter(|&u| g.neighbours(u).len() <= min_degree + 2).collect();
            let order = bfs(&g, r0, &mut level);
            let half_ecc = order.last().map_or(0, |&v| level[v]) / 2;
            let middles: Vec<usize> = boundary.iter().copied().filter(|&u| level[u].abs_diff(half_ecc) <= 1).collect();
            for &u in &order {
                level[u] = usize::MAX;
            }
            candidates.extend(middles.iter().step_by(middles.len().div_ceil(ROOT_CANDIDATES).max(1)));
            candidates.extend(boundary.iter().step_by(boundary.len().div_ceil(ROOT_CANDIDATES).max(1)));
            let mut best: Option<(usize, Vec<(usize, u8)>)> = None;
            for &r in &candidates {
                let sep = level_cut(&g, vertices, r, n / 2, &mut level, &mut part_v);
                if best.as_ref().is_none_or(|b| sep < b.0) {
                    best = Some((sep, vertices.iter().map(|&u| (u, part_v[u])).collect()));
                }
            }
            if let Some((_, parts)) = best {
                for (u, p) in parts {
                    part_v[u] = p;
                }
            }
            for &u in vertices {
                if part_v[u] != SEP {
                    load[part_v[u] as usize] += g.weight(u);
                }
            }
            rest = &comps[1..];
        }
    }
    // Whole components to the lighter half (largest first).
    for (w, _, vertices) in rest {
        let h = if load[0] <= load[1] { HALF1 } else { HALF2 };
        for &u in vertices {
            part_v[u] = h;
        }
        load[h as usize] += w;
    }
    let mut part = vec![HALF1; n];
    for v in 0..nv {
        part[g.first[v]..g.first[v + 1]].fill(part_v[v]);
    }
    part
}
