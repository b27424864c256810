//! The smallest offsets by Pryce's fixed-point iteration, in worklist form.
//!
//! Pryce (BIT 41 (2001), §3) starts from `c = 0` and repeats
//! `d_j = max_i (σ_ij + c_i)`, `c_i = d_{T(i)} − σ_{i,T(i)}` until nothing
//! changes; the `c_i` never decrease and the limit is the smallest offsets.
//! Sweeping every row each time costs O(nnz) per level of the longest chain
//! of differentiations, O(n · nnz) on a linear chain of index n. The same
//! monotone iteration is run here on a queue instead: only an equation
//! whose `c_i` just rose has its row re-read, raising `d_j` and through it
//! the offset of the equation `T` assigns to `j`. Any fair order of these
//! updates reaches the same least fixed point.
//!
//! The updates are a label-correcting longest-path search in the graph with
//! an edge `k → T⁻¹(j)` of weight `σ_kj − σ_{T⁻¹(j),j}` for each entry
//! `(k, j)`, which has no positive cycle when `T` is a highest-value
//! transversal; first-in first-out, each equation is then taken from the
//! queue at most `n` times. More than `n² + n` steps would be a bug,
//! reported as [`Singular::OffsetsDidNotConverge`] rather than looping.

use std::collections::VecDeque;

use super::pattern::Pattern;
use super::Singular;

/// `(c, d)` for the transversal `t` (`t[i]` the unknown of equation `i`).
pub(crate) fn smallest(p: &Pattern, t: &[usize]) -> Result<(Vec<i64>, Vec<i64>), Singular> {
    let n = p.n;
    let mut owner = vec![0usize; n];
    for (i, &j) in t.iter().enumerate() {
        owner[j] = i;
    }
    let on_t: Vec<i64> = (0..n)
        .map(|i| p.sigma(i, t[i]).map_or(0, i64::from))
        .collect();
    // c = 0, then the first half-step d_j = max_i σ_ij.
    let mut c = vec![0i64; n];
    let mut d = vec![i64::MIN; n];
    for e in 0..p.unknown.len() {
        let j = p.unknown[e];
        d[j] = d[j].max(i64::from(p.order[e]));
    }
    let mut queue = VecDeque::new();
    let mut queued = vec![false; n];
    for i in 0..n {
        let ci = d[t[i]] - on_t[i];
        if ci > c[i] {
            c[i] = ci;
            queued[i] = true;
            queue.push_back(i);
        }
    }
    let limit = n.saturating_mul(n).saturating_add(n);
    let mut steps = 0usize;
    while let Some(k) = queue.pop_front() {
        steps += 1;
        if steps > limit {
            return Err(Singular::OffsetsDidNotConverge { steps: limit });
        }
        queued[k] = false;
        for e in p.range(k) {
            let j = p.unknown[e];
            let reach = i64::from(p.order[e]) + c[k];
            if reach > d[j] {
                d[j] = reach;
                let i = owner[j];
                let ci = reach - on_t[i];
                if ci > c[i] {
                    c[i] = ci;
                    if !queued[i] {
                        queued[i] = true;
                        queue.push_back(i);
                    }
                }
            }
        }
    }
    Ok((c, d))
}
