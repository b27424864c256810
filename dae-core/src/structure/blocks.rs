//! Block-triangular form: the strongly connected components of the graph
//! with an edge from equation `i` to the equation solved for each unknown
//! of `i`, by Tarjan's algorithm on an explicit stack.
//!
//! Tarjan (SIAM J. Comput. 1 (1972)) completes a component only after every
//! component reachable from it, so the components come out with each one's
//! dependencies before it: the order in which they can be solved.

use super::matching::NONE;
use super::pattern::Pattern;

/// The blocks in solve order, each ascending. `owner[j]` is the equation
/// the transversal assigns to unknown `j`.
pub(crate) fn blocks(p: &Pattern, owner: &[usize]) -> Vec<Vec<usize>> {
    let n = p.n;
    let mut number = vec![NONE; n];
    let mut low = vec![0usize; n];
    let mut on_stack = vec![false; n];
    let mut stack: Vec<usize> = Vec::new();
    // (equation, next entry of its row to follow)
    let mut calls: Vec<(usize, usize)> = Vec::new();
    let mut counter = 0usize;
    let mut out = Vec::new();
    for root in 0..n {
        if number[root] != NONE {
            continue;
        }
        number[root] = counter;
        low[root] = counter;
        counter += 1;
        stack.push(root);
        on_stack[root] = true;
        calls.push((root, 0));
        while let Some(top) = calls.last_mut() {
            let (i, next) = *top;
            let row = p.row(i);
            if next < row.len() {
                top.1 += 1;
                let k = owner[row[next]];
                if number[k] == NONE {
                    number[k] = counter;
                    low[k] = counter;
                    counter += 1;
                    stack.push(k);
                    on_stack[k] = true;
                    calls.push((k, 0));
                } else if on_stack[k] {
                    low[i] = low[i].min(number[k]);
                }
                continue;
            }
            calls.pop();
            if let Some(&(parent, _)) = calls.last() {
                low[parent] = low[parent].min(low[i]);
            }
            if low[i] == number[i] {
                let mut block = Vec::new();
                while let Some(k) = stack.pop() {
                    on_stack[k] = false;
                    block.push(k);
                    if k == i {
                        break;
                    }
                }
                block.sort_unstable();
                out.push(block);
            }
        }
    }
    out
}
