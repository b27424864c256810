//! Maximum matching of equations to unknowns (Hopcroft–Karp, iterative) and
//! the Dulmage–Mendelsohn coarse decomposition when it is not perfect.
//!
//! Hopcroft and Karp, "An n^{5/2} algorithm for maximum matchings in
//! bipartite graphs", SIAM J. Comput. 2 (1973): phases of a breadth-first
//! layering from the free equations followed by vertex-disjoint shortest
//! augmenting paths, O(√n · nnz). The depth-first part runs on an explicit
//! stack, so deep alternating paths (long chains) cannot overflow the call
//! stack.

use super::pattern::Pattern;
use super::Singular;

/// Marks a free equation or unknown.
pub(crate) const NONE: usize = usize::MAX;

/// A matching: `of_equation[i]` is the unknown of equation `i` (or
/// [`NONE`]), `of_unknown[j]` the equation of unknown `j`.
#[derive(Clone, Debug)]
pub(crate) struct Matching {
    pub(crate) of_equation: Vec<usize>,
    pub(crate) of_unknown: Vec<usize>,
}

impl Matching {
    /// Number of matched pairs.
    pub(crate) fn size(&self) -> usize {
        self.of_equation.iter().filter(|&&j| j != NONE).count()
    }
}

/// A maximum matching of the pattern (ignoring σ).
pub(crate) fn maximum(p: &Pattern) -> Matching {
    let n = p.n;
    let mut m = Matching {
        of_equation: vec![NONE; n],
        of_unknown: vec![NONE; n],
    };
    // Greedy start: most equations of a model find a free unknown at once.
    for i in 0..n {
        if let Some(&j) = p.row(i).iter().find(|&&j| m.of_unknown[j] == NONE) {
            m.of_equation[i] = j;
            m.of_unknown[j] = i;
        }
    }
    let unreached = usize::MAX;
    let mut layer = vec![unreached; n];
    let mut next = vec![0usize; n];
    let mut queue = Vec::with_capacity(n);
    let mut stack: Vec<usize> = Vec::new();
    loop {
        // Breadth-first layering of equations from the free ones.
        queue.clear();
        for (i, l) in layer.iter_mut().enumerate() {
            if m.of_equation[i] == NONE {
                *l = 0;
                queue.push(i);
            } else {
                *l = unreached;
            }
        }
        let mut found = false;
        let mut head = 0;
        while head < queue.len() {
            let i = queue[head];
            head += 1;
            for &j in p.row(i) {
                let k = m.of_unknown[j];
                if k == NONE {
                    found = true;
                } else if layer[k] == unreached {
                    layer[k] = layer[i] + 1;
                    queue.push(k);
                }
            }
        }
        if !found {
            return m;
        }
        // Depth-first search along the layers, one augmenting path per
        // free equation at most.
        next.iter_mut().for_each(|e| *e = 0);
        for root in 0..n {
            if m.of_equation[root] != NONE {
                continue;
            }
            stack.clear();
            stack.push(root);
            while let Some(&i) = stack.last() {
                let row = p.row(i);
                if next[i] == row.len() {
                    // Dead end: never enter this equation again this phase.
                    layer[i] = unreached;
                    stack.pop();
                    continue;
                }
                let j = row[next[i]];
                next[i] += 1;
                let k = m.of_unknown[j];
                if k == NONE {
                    // Augment: each equation on the stack takes the unknown
                    // it last tried.
                    for &e in &stack {
                        let u = p.row(e)[next[e] - 1];
                        m.of_equation[e] = u;
                        m.of_unknown[u] = e;
                    }
                    for &e in &stack {
                        layer[e] = unreached;
                    }
                    break;
                }
                if layer[k] != unreached && layer[k] == layer[i] + 1 {
                    stack.push(k);
                }
            }
        }
    }
}

/// The Dulmage–Mendelsohn coarse decomposition from a maximum matching
/// that is not perfect: the over-determined part (everything reachable from
/// a free equation along alternating paths: equation → any unknown of it →
/// the equation matched to that unknown) and the under-determined part
/// (reachable from a free unknown: unknown → any equation it occurs in →
/// the unknown matched to that equation). Both are independent of which
/// maximum matching was found; the free equations and unknowns are not.
pub(crate) fn no_transversal(p: &Pattern, m: &Matching) -> Singular {
    let n = p.n;
    // Over-determined part.
    let mut eq_seen = vec![false; n];
    let mut unk_seen = vec![false; n];
    let mut queue: Vec<usize> = (0..n).filter(|&i| m.of_equation[i] == NONE).collect();
    let unmatched_equations = queue.clone();
    for &i in &queue {
        eq_seen[i] = true;
    }
    let mut head = 0;
    while head < queue.len() {
        let i = queue[head];
        head += 1;
        for &j in p.row(i) {
            if !unk_seen[j] {
                unk_seen[j] = true;
                let k = m.of_unknown[j];
                if k != NONE && !eq_seen[k] {
                    eq_seen[k] = true;
                    queue.push(k);
                }
            }
        }
    }
    let equations = indices(&eq_seen);
    let unknowns = indices(&unk_seen);

    // Under-determined part.
    let (col_start, col_equation) = p.columns();
    let mut eq_seen = vec![false; n];
    let mut unk_seen = vec![false; n];
    let mut queue: Vec<usize> = (0..n).filter(|&j| m.of_unknown[j] == NONE).collect();
    let unmatched_unknowns = queue.clone();
    for &j in &queue {
        unk_seen[j] = true;
    }
    let mut head = 0;
    while head < queue.len() {
        let j = queue[head];
        head += 1;
        for &i in &col_equation[col_start[j]..col_start[j + 1]] {
            if !eq_seen[i] {
                eq_seen[i] = true;
                let u = m.of_equation[i];
                if u != NONE && !unk_seen[u] {
                    unk_seen[u] = true;
                    queue.push(u);
                }
            }
        }
    }
    Singular::NoTransversal {
        equations,
        unknowns,
        unmatched_equations,
        unmatched_unknowns,
        underdetermined_equations: indices(&eq_seen),
        underdetermined_unknowns: indices(&unk_seen),
    }
}

fn indices(flags: &[bool]) -> Vec<usize> {
    flags
        .iter()
        .enumerate()
        .filter_map(|(k, &f)| f.then_some(k))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::SigmaMatrix;

    fn pattern(rows: &[&[usize]]) -> Pattern {
        let s = SigmaMatrix::from_rows(
            rows.len(),
            rows.iter()
                .map(|r| r.iter().map(|&j| (j, 0)).collect::<Vec<_>>()),
        )
        .unwrap();
        Pattern::read(&s).unwrap()
    }

    #[test]
    fn greedy_start_is_repaired_by_augmenting_paths() {
        // Greedy gives e0-u0, e1-u1 and leaves e2 (only u0) free; a path of
        // length 5 is needed: e2-u0-e0-u1-e1-u2.
        let p = pattern(&[&[0, 1], &[1, 2], &[0]]);
        let m = maximum(&p);
        assert_eq!(m.size(), 3);
        assert_eq!(m.of_equation, vec![1, 2, 0]);
    }

    #[test]
    fn long_alternating_path_needs_no_recursion() {
        // e_k has unknowns k and k+1; the last equation only unknown 0. The
        // greedy start matches e_k to k, leaving one augmenting path through
        // the whole chain.
        let n = 200_000;
        let mut rows: Vec<Vec<usize>> = (0..n - 1).map(|k| vec![k, k + 1]).collect();
        rows.push(vec![0]);
        let s = SigmaMatrix::from_rows(
            n,
            rows.into_iter()
                .map(|r| r.into_iter().map(|j| (j, 0)).collect::<Vec<_>>()),
        )
        .unwrap();
        let m = maximum(&Pattern::read(&s).unwrap());
        assert_eq!(m.size(), n);
        assert_eq!(m.of_equation[n - 1], 0);
        assert_eq!(m.of_equation[0], 1);
    }

    #[test]
    fn decomposition_of_a_deficient_pattern() {
        // e0, e1 only involve u0; u2 occurs only in e2, which also has u1.
        let p = pattern(&[&[0], &[0], &[1, 2]]);
        let m = maximum(&p);
        assert_eq!(m.size(), 2);
        match no_transversal(&p, &m) {
            Singular::NoTransversal {
                equations,
                unknowns,
                unmatched_equations,
                unmatched_unknowns,
                underdetermined_equations,
                underdetermined_unknowns,
            } => {
                assert_eq!(equations, vec![0, 1]);
                assert_eq!(unknowns, vec![0]);
                assert_eq!(unmatched_equations, vec![1]);
                assert_eq!(unmatched_unknowns, vec![2]);
                assert_eq!(underdetermined_equations, vec![2]);
                assert_eq!(underdetermined_unknowns, vec![1, 2]);
            }
            other => panic!("expected NoTransversal, got {other:?}"),
        }
    }
}
