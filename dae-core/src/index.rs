//! Structural index analysis: the hidden constraints of a semi-explicit
//! model and how often each constraint is differentiated.
//!
//! For a model `c_j u_j' = f_j(t, u, λ)`, `0 = g_i(t, u, λ)` each constraint
//! is differentiated along the dynamics (every `u_j'` replaced by `f_j / c_j`,
//! the paper's construction of (3a) and (3b)) until it involves an algebraic
//! unknown; that level `d_i` is where the constraint determines the
//! multipliers. The constraints' top levels must then determine *all*
//! algebraic unknowns: a perfect matching between top-level constraints and
//! algebraic unknowns in the bipartite incidence graph (the structural test
//! of Pantelides' algorithm, which for semi-explicit systems differentiates
//! exactly these equations). No matching means the model is structurally
//! singular.

use crate::dsl::Errors;
use crate::expr::{self, Expr, Sym};
use crate::model::Model;

/// Most differentiations tried before a constraint is declared singular.
pub const MAX_LEVEL: usize = 4;

/// One constraint and its hidden derivatives.
#[derive(Clone, Debug)]
pub struct Chain {
    /// 0-based index of the original constraint.
    pub source: usize,
    /// `levels[k]` is the `k`-th total time derivative; the last one involves
    /// algebraic unknowns.
    pub levels: Vec<Expr>,
}

impl Chain {
    /// `d_i`: the level that determines the multipliers.
    pub fn top(&self) -> usize {
        self.levels.len() - 1
    }

    /// First level at which symbol `s` appears, if any (directly or,
    /// through a mass matrix, behind a der(); see [`Model::involves`]).
    pub fn first_level(&self, model: &Model, s: Sym) -> Option<usize> {
        self.levels.iter().position(|e| model.involves(e, s))
    }
}

/// Result of the analysis.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// One chain per constraint, in model order.
    pub chains: Vec<Chain>,
    /// `matching[i]`: the algebraic unknown (index into the model's
    /// unknowns) constraint `i` determines.
    pub matching: Vec<usize>,
}

impl Analysis {
    /// Largest `d_i` (the model's maximal constraint level).
    pub fn max_level(&self) -> usize {
        self.chains.iter().map(Chain::top).max().unwrap_or(0)
    }

    /// `true` when every constraint is a position-level constraint of a
    /// mechanical system (`d_i = 2`).
    pub fn is_mechanical(&self) -> bool {
        !self.chains.is_empty() && self.chains.iter().all(|c| c.top() == 2)
    }

    /// The whole chain in order (source-major, then level), as reported by
    /// `dae derive` and evaluated by `DaeSystem::constraints`.
    pub fn flat(&self) -> Vec<(usize, usize, &Expr)> {
        let mut out = Vec::new();
        for c in &self.chains {
            for (k, e) in c.levels.iter().enumerate() {
                out.push((c.source, k, e));
            }
        }
        out
    }
}

/// Differentiate every constraint until it determines multipliers, then
/// check the matching.
pub fn analyse(model: &Model) -> Result<Analysis, syn::Error> {
    let mut errors = Errors::default();
    // A level determines multipliers when it contains one, directly or
    // through the der() of a mass-matrix unknown (`M v' = f − Gᵀλ`: the
    // acceleration-level constraint `G v' + … = 0` fixes λ).
    let n_diff = model.n_diff;
    let alg =
        |e: &Expr| model.involves_any(e, &|s| matches!(s, Sym::Var(i) if i as usize >= n_diff));
    let mut chains = Vec::new();
    for (i, c) in model.constraints.iter().enumerate() {
        let mut levels = vec![c.expr.clone()];
        let mut ok = true;
        while !levels.last().is_some_and(alg) {
            if levels.len() > MAX_LEVEL {
                errors.push(
                    c.span,
                    format!(
                        "structurally singular: this constraint involves no algebraic unknown even after {MAX_LEVEL} differentiations"
                    ),
                );
                ok = false;
                break;
            }
            let last = levels.last().cloned().unwrap_or_else(Expr::zero);
            match expr::time_derivative(&last, &|s| model.rate(s)) {
                Ok(d) => {
                    if d.is_zero() {
                        errors.push(
                            c.span,
                            "structurally singular: this constraint's time derivative vanishes identically (it fixes no unknown)",
                        );
                        ok = false;
                        break;
                    }
                    levels.push(d);
                }
                Err(s) => {
                    errors.push(
                        c.span,
                        format!("cannot differentiate through `{}`", model.sym_name(s, &[])),
                    );
                    ok = false;
                    break;
                }
            }
        }
        if ok {
            chains.push(Chain { source: i, levels });
        }
    }
    if !errors.is_empty() {
        return errors.finish(Analysis {
            chains,
            matching: Vec::new(),
        });
    }
    // Bipartite matching: top-level constraints ↔ algebraic unknowns.
    let n_alg = model.n_alg();
    let adj: Vec<Vec<usize>> = chains
        .iter()
        .map(|c| {
            let top = &c.levels[c.top()];
            (0..n_alg)
                .filter(|&a| model.involves(top, Sym::Var((model.n_diff + a) as u32)))
                .collect()
        })
        .collect();
    let assign = max_matching(&adj, n_alg);
    let mut matching = vec![usize::MAX; chains.len()];
    for (a, owner) in assign.iter().enumerate() {
        if let Some(i) = owner {
            matching[*i] = model.n_diff + a;
        }
    }
    for (i, m) in matching.iter().enumerate() {
        if *m == usize::MAX {
            errors.push(
                model.constraints[chains[i].source].span,
                "structurally singular: the multipliers this constraint could determine are already fixed by other constraints",
            );
        }
    }
    for (a, owner) in assign.iter().enumerate() {
        if owner.is_none() {
            let v = &model.vars[model.n_diff + a];
            errors.push(
                v.span,
                format!("structurally singular: no constraint determines `{}` (it appears in no constraint's derivatives)", v.name),
            );
        }
    }
    errors.finish(Analysis { chains, matching })
}

/// Maximum bipartite matching (augmenting paths). `adj[i]` lists the right
/// vertices of left vertex `i`; returns for each right vertex its left mate.
pub fn max_matching(adj: &[Vec<usize>], n_right: usize) -> Vec<Option<usize>> {
    fn augment(
        i: usize,
        adj: &[Vec<usize>],
        seen: &mut [bool],
        mate: &mut [Option<usize>],
    ) -> bool {
        for &r in &adj[i] {
            if seen[r] {
                continue;
            }
            seen[r] = true;
            if mate[r].is_none_or(|j| augment(j, adj, seen, mate)) {
                mate[r] = Some(i);
                return true;
            }
        }
        false
    }
    let mut mate = vec![None; n_right];
    for i in 0..adj.len() {
        let mut seen = vec![false; n_right];
        augment(i, adj, &mut seen, &mut mate);
    }
    mate
}
