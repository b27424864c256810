//! The smallest offsets by Pryce's fixed-point iteration.
//!
//! From `c = 0`, repeat `d_j = max_i (σ_ij + c_i)` and
//! `c_i = d_{T(i)} − σ_{i,T(i)}` until nothing changes (Pryce, BIT 41
//! (2001), §3). The `c_i` never decrease; each sweep lengthens by one edge
//! the longest paths it has accounted for in the graph with an edge
//! `k → i` of weight `σ_{k,T(i)} − σ_{i,T(i)}`, which has no positive cycle
//! when `T` is a highest-value transversal. So at most `n` sweeps change
//! something; one more that changes something is a bug, reported as
//! [`Singular::OffsetsDidNotConverge`] rather than looping.

use super::pattern::Pattern;
use super::Singular;

/// `(c, d)` for the transversal `t` (`t[i]` the unknown of equation `i`).
pub(crate) fn smallest(p: &Pattern, t: &[usize]) -> Result<(Vec<i64>, Vec<i64>), Singular> {
    let n = p.n;
    let on_t: Vec<i64> = (0..n)
        .map(|i| p.sigma(i, t[i]).map_or(0, i64::from))
        .collect();
    let mut c = vec![0i64; n];
    let mut d = vec![i64::MIN; n];
    let bound = n + 1;
    for _ in 0..bound {
        d.iter_mut().for_each(|x| *x = i64::MIN);
        for (i, &ci) in c.iter().enumerate() {
            for e in p.range(i) {
                let j = p.unknown[e];
                d[j] = d[j].max(i64::from(p.order[e]) + ci);
            }
        }
        let mut changed = false;
        for i in 0..n {
            let ci = d[t[i]] - on_t[i];
            if ci != c[i] {
                c[i] = ci;
                changed = true;
            }
        }
        if !changed {
            return Ok((c, d));
        }
    }
    Err(Singular::OffsetsDidNotConverge { sweeps: bound })
}
