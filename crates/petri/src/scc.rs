//! Strongly connected components by Tarjan's algorithm, iterative (no
//! recursion, so chains of millions of states do not overflow the stack).
//!
//! `O(V + E)` time, `O(V)` extra memory. Components are reported in reverse
//! topological order: when a component is reported, every component reachable
//! from it has been reported before.

/// A directed graph whose successor lists are slices.
pub trait Successors {
    /// Number of nodes, `0..n`.
    fn num_nodes(&self) -> usize;
    /// Successors of `v` (may contain `v` itself and duplicates).
    fn successors(&self, v: u32) -> &[u32];
}

const UNVISITED: u32 = u32::MAX;

/// Runs Tarjan's algorithm on the subgraph induced by the nodes for which
/// `include` is true, calling `on_scc` with each component. `on_scc` may stop
/// the search by returning an error.
pub fn tarjan<G: Successors, E>(
    g: &G,
    include: impl Fn(u32) -> bool,
    mut on_scc: impl FnMut(&[u32]) -> Result<(), E>,
) -> Result<(), E> {
    let n = g.num_nodes();
    let mut index = vec![UNVISITED; n];
    let mut low = vec![0u32; n];
    let mut on_stack = vec![false; n];
    let mut stack: Vec<u32> = Vec::new();
    let mut call: Vec<(u32, u32)> = Vec::new();
    let mut counter = 0u32;
    for root in 0..n as u32 {
        if index[root as usize] != UNVISITED || !include(root) {
            continue;
        }
        index[root as usize] = counter;
        low[root as usize] = counter;
        counter += 1;
        stack.push(root);
        on_stack[root as usize] = true;
        call.push((root, 0));
        while let Some(&mut (v, ref mut pos)) = call.last_mut() {
            let succ = g.successors(v);
            if (*pos as usize) < succ.len() {
                let w = succ[*pos as usize];
                *pos += 1;
                if !include(w) {
                    continue;
                }
                let wi = w as usize;
                if index[wi] == UNVISITED {
                    index[wi] = counter;
                    low[wi] = counter;
                    counter += 1;
                    stack.push(w);
                    on_stack[wi] = true;
                    call.push((w, 0));
                } else if on_stack[wi] {
                    let vi = v as usize;
                    low[vi] = low[vi].min(index[wi]);
                }
            } else {
                call.pop();
                let vi = v as usize;
                if let Some(&(parent, _)) = call.last() {
                    let pi = parent as usize;
                    low[pi] = low[pi].min(low[vi]);
                }
                if low[vi] == index[vi] {
                    let at = stack.iter().rposition(|&x| x == v).unwrap_or(0);
                    for &x in &stack[at..] {
                        on_stack[x as usize] = false;
                    }
                    on_scc(&stack[at..])?;
                    stack.truncate(at);
                }
            }
        }
    }
    Ok(())
}

/// Component structure of a whole graph: component id per node (ids in
/// reverse topological order) and which components are bottom (no edge
/// leaves them).
#[derive(Debug, Clone)]
pub(crate) struct Components {
    /// Component id of every node.
    pub comp: Vec<u32>,
    /// Number of nodes per component.
    pub size: Vec<u32>,
    /// Whether each component is bottom (closed).
    pub bottom: Vec<bool>,
}

impl Components {
    pub(crate) fn of<G: Successors>(g: &G) -> Components {
        let n = g.num_nodes();
        let mut comp = vec![0u32; n];
        let mut size = Vec::new();
        let _ = tarjan::<_, ()>(
            g,
            |_| true,
            |scc| {
                let id = size.len() as u32;
                for &v in scc {
                    comp[v as usize] = id;
                }
                size.push(scc.len() as u32);
                Ok(())
            },
        );
        let mut bottom = vec![true; size.len()];
        for v in 0..n as u32 {
            let c = comp[v as usize];
            if bottom[c as usize] && g.successors(v).iter().any(|&w| comp[w as usize] != c) {
                bottom[c as usize] = false;
            }
        }
        Components { comp, size, bottom }
    }

    /// Number of components.
    pub(crate) fn len(&self) -> usize {
        self.size.len()
    }

    /// Ids of the bottom components.
    pub(crate) fn bottoms(&self) -> Vec<u32> {
        (0..self.len() as u32)
            .filter(|&c| self.bottom[c as usize])
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A graph stored as compressed rows.
    #[derive(Debug, Clone, Default)]
    struct CsrGraph {
        offsets: Vec<u64>,
        targets: Vec<u32>,
    }

    impl Successors for CsrGraph {
        fn num_nodes(&self) -> usize {
            self.offsets.len().saturating_sub(1)
        }

        fn successors(&self, v: u32) -> &[u32] {
            let v = v as usize;
            &self.targets[self.offsets[v] as usize..self.offsets[v + 1] as usize]
        }
    }

    fn graph(n: usize, edges: &[(u32, u32)]) -> CsrGraph {
        let mut adj = vec![Vec::new(); n];
        for &(a, b) in edges {
            adj[a as usize].push(b);
        }
        let mut g = CsrGraph::default();
        g.offsets.push(0);
        for l in adj {
            g.targets.extend(l);
            g.offsets.push(g.targets.len() as u64);
        }
        g
    }

    #[test]
    fn components_and_bottoms() {
        // 0 -> 1 <-> 2 -> 3 (absorbing); 0 -> 4 <-> 5 (closed pair)
        let g = graph(6, &[(0, 1), (1, 2), (2, 1), (2, 3), (0, 4), (4, 5), (5, 4)]);
        let c = Components::of(&g);
        assert_eq!(c.len(), 4);
        assert_eq!(c.comp[1], c.comp[2]);
        assert_eq!(c.comp[4], c.comp[5]);
        let mut bottom_sets: Vec<Vec<u32>> = c
            .bottoms()
            .iter()
            .map(|&b| (0..6).filter(|&v| c.comp[v as usize] == b).collect())
            .collect();
        bottom_sets.sort();
        assert_eq!(bottom_sets, vec![vec![3], vec![4, 5]]);
        // Reverse topological order: 3 before {1,2} before 0.
        assert!(c.comp[3] < c.comp[1] && c.comp[1] < c.comp[0]);
    }

    #[test]
    fn long_chain_does_not_overflow_the_stack() {
        let n = 1_000_000u32;
        let edges: Vec<(u32, u32)> = (0..n - 1).map(|i| (i, i + 1)).chain([(n - 1, 0)]).collect();
        let g = graph(n as usize, &edges);
        let c = Components::of(&g);
        assert_eq!(c.len(), 1);
        assert!(c.bottom[0]);
    }

    #[test]
    fn filtered_subgraph() {
        let g = graph(4, &[(0, 1), (1, 0), (1, 2), (2, 3), (3, 2)]);
        let mut sccs = Vec::new();
        tarjan::<_, ()>(
            &g,
            |v| v != 2,
            |s| {
                let mut s = s.to_vec();
                s.sort();
                sccs.push(s);
                Ok(())
            },
        )
        .unwrap();
        sccs.sort();
        assert_eq!(sccs, vec![vec![0, 1], vec![3]]);
    }
}
