//! Structural index analysis: how often each equation of a model is
//! differentiated, and the hidden constraints that result.
//!
//! The model's equations — the dynamic rows `c·u' = f` (or rows of a mass
//! matrix) and the constraints `0 = g` — are read as a signature matrix
//! `σ_ij` (the order of the highest derivative of unknown `j` in equation
//! `i`) and analysed by Pryce's Σ-method ([`crate::structure`]): the
//! smallest offsets `c_i` say that equation `i` is differentiated `c_i`
//! times, `d_j` that unknown `j` appears up to its `d_j`-th derivative. That
//! one analysis covers every model the language can write: the mechanical
//! multipliers (each position constraint `c_i = 2`), Hessenberg index-2
//! systems (`c_i = 1`), and algebraic unknowns that are fixed by their own
//! equations and whose derivatives other constraints need (the reaction rate
//! of a CSTR with a prescribed output).
//!
//! The hidden constraints are then built *along the dynamics*, as in the
//! paper's construction of (3a) and (3b): each constraint is differentiated
//! `c_i` times, every `u_j'` replaced by its rate `f_j / c_j`. An algebraic
//! unknown whose derivative is needed (`d_j ≥ 1`) gets a rate too, from the
//! constraint that determines it: `0 = e(t, x, r)` gives
//! `r' = −(∂e/∂t + Σ ∂e/∂x · x') / (∂e/∂r)` symbolically, and that
//! constraint stays at its own level (it determines `r`, index 1). The top
//! levels must then determine the other algebraic unknowns: a perfect
//! matching between top-level constraints and algebraic unknowns.

use crate::dsl::Errors;
use crate::expr::{self, Expr, Sym};
use crate::model::{Dynamic, Model};
use crate::structure::{self, Sigma, SigmaMatrix, Singular, Structure};
use std::collections::HashMap;

/// Most differentiations of one constraint.
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

    /// [`Chain::first_level`] of every symbol the chain involves, from one
    /// walk of each level: asking [`Chain::first_level`] for each of a
    /// model's unknowns would walk every level once per unknown, quadratic
    /// in the size of a large model.
    pub fn first_levels(&self, model: &Model) -> HashMap<Sym, usize> {
        let mut first = HashMap::new();
        for (l, e) in self.levels.iter().enumerate() {
            for s in model.involved(e) {
                first.entry(s).or_insert(l);
            }
        }
        first
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
    /// The Σ-method's result on the model's equations: the dynamic rows
    /// first (in unknown order), then the constraints.
    pub structure: Structure,
    /// Rates of the algebraic unknowns whose derivatives the chains need
    /// (`d_j ≥ 1`): `(unknown, r')`, in the order they were derived.
    pub rates: Vec<(usize, Expr)>,
    /// Constraints implied by a constant, singular mass matrix (see
    /// [`implied_constraints`]): members of the chain (for consistent
    /// initialisation and drift reports), never rows of a formulation, which
    /// hold them already through the dynamic rows.
    pub implied: Vec<Implied>,
}

/// `0 = Σ_i w_i f_i`: a combination of dynamic rows `Σ_j M_ij u_j' = f_i`
/// with `Σ_i w_i M_ij = 0`, so that every der() cancels.
#[derive(Clone, Debug)]
pub struct Implied {
    /// `(unknown whose dynamic row it is, weight w_i)`, ascending.
    pub rows: Vec<(usize, Expr)>,
    /// `Σ_i w_i f_i`.
    pub expr: Expr,
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
    /// `dae derive` and evaluated by `DaeSystem::constraints`; the implied
    /// constraints of a singular mass matrix follow at level 0, numbered
    /// after the model's own constraints.
    pub fn flat(&self) -> Vec<(usize, usize, &Expr)> {
        let mut out = Vec::new();
        for c in &self.chains {
            for (k, e) in c.levels.iter().enumerate() {
                out.push((c.source, k, e));
            }
        }
        for (k, i) in self.implied.iter().enumerate() {
            out.push((self.chains.len() + k, 0, &i.expr));
        }
        out
    }
}

/// The signature matrix of a model's equations: rows are the dynamic
/// equations (in unknown order) and then the constraints; `σ = 1` for a
/// der() term, `0` for an unknown the row contains otherwise.
pub fn signature(model: &Model) -> SigmaMatrix {
    let n = model.vars.len();
    let rows = model.dynamics.len() + model.constraints.len();
    let mut sig = SigmaMatrix::new(rows, n);
    let mark = |i: usize, e: &Expr, sig: &mut SigmaMatrix| {
        for s in e.symbols() {
            if let Sym::Var(j) = s {
                if (j as usize) < n && sig.sigma(i, j as usize).is_none() {
                    sig.set(i, j as usize, 0).expect("an unknown of the model");
                }
            }
        }
    };
    for (i, d) in model.dynamics.iter().enumerate() {
        for (j, c) in d.terms() {
            sig.set(i, j, 1).expect("an unknown of the model");
            mark(i, c, &mut sig);
        }
        mark(i, &d.rhs, &mut sig);
    }
    for (k, c) in model.constraints.iter().enumerate() {
        mark(model.dynamics.len() + k, &c.expr, &mut sig);
    }
    sig
}

/// Analyse a checked model: Σ-method offsets, rates of the algebraic
/// unknowns whose derivatives are needed, the constraint chains and the
/// matching of their top levels to the algebraic unknowns.
pub fn analyse(model: &Model) -> Result<Analysis, syn::Error> {
    let mut errors = Errors::default();
    let n_dyn = model.dynamics.len();
    let sig = signature(model);
    let st = match structure::analyse(&sig) {
        Ok(st) => st,
        Err(singular) => return Err(diagnose(model, &singular)),
    };
    let c_of = |i: usize| st.c[n_dyn + i] as usize;
    if let Some(i) = (0..model.constraints.len()).find(|&i| c_of(i) > MAX_LEVEL) {
        errors.push(
            model.constraints[i].span,
            format!(
                "this constraint would be differentiated {} times (at most {MAX_LEVEL} are supported)",
                c_of(i)
            ),
        );
        return Err(errors.finish(()).unwrap_err());
    }

    // Algebraic unknowns whose derivatives the differentiated constraints
    // need, each with the constraint that determines it.
    let n_diff = model.n_diff;
    let needed: Vec<usize> = (n_diff..model.vars.len())
        .filter(|&j| st.d[j] >= 1)
        .collect();
    let (rates, definers) = algebraic_rates(model, &st, &needed)?;
    let rate_of = |s: Sym| rate_with(model, &rates, s);

    let mut chains = Vec::new();
    for (i, c) in model.constraints.iter().enumerate() {
        let depth = if definers.contains(&i) { 0 } else { c_of(i) };
        let mut levels = vec![c.expr.clone()];
        let mut ok = true;
        while levels.len() <= depth {
            let last = levels.last().cloned().unwrap_or_else(Expr::zero);
            let derived = expr::time_derivative(&last, &rate_of);
            if let Err(grew) = derived.as_ref().map_or(Ok(()), expr::check_growth) {
                errors.push(
                    c.span,
                    format!(
                        "this constraint's time derivative of order {} {grew}",
                        levels.len()
                    ),
                );
                ok = false;
                break;
            }
            match derived {
                Ok(d) if d.is_zero() => {
                    errors.push(
                        c.span,
                        "structurally singular: this constraint's time derivative vanishes identically (it fixes no unknown)",
                    );
                    ok = false;
                    break;
                }
                Ok(d) => levels.push(d),
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
            structure: st,
            rates,
            implied: Vec::new(),
        });
    }
    // A member that still holds the der() of an implicit unknown is not a
    // function of (t, y): its derivative did not cancel.
    for c in &chains {
        for (k, e) in c.levels.iter().enumerate() {
            if let Some(&j) = model
                .implicit
                .iter()
                .find(|&&j| e.contains(Sym::Der(j as u32)))
            {
                errors.push(
                    model.constraints[c.source].span,
                    format!(
                        "this constraint's derivative {k} holds `der({})`, which has no equation of its own; \
                         such hidden constraints are not supported yet",
                        model.vars[j].name
                    ),
                );
            }
        }
    }
    // Bipartite matching: top-level constraints ↔ the unknowns the
    // constraints determine (algebraic, and implicit differential ones).
    let determined = model.determined();
    let adj: Vec<Vec<usize>> = chains
        .iter()
        .map(|c| {
            let top = &c.levels[c.top()];
            (0..determined.len())
                .filter(|&a| model.involves(top, Sym::Var(determined[a] as u32)))
                .collect()
        })
        .collect();
    let assign = max_matching(&adj, determined.len());
    let mut matching = vec![usize::MAX; chains.len()];
    for (a, owner) in assign.iter().enumerate() {
        if let Some(i) = owner {
            matching[*i] = determined[a];
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
            let v = &model.vars[determined[a]];
            errors.push(
                v.span,
                format!("structurally singular: no constraint determines `{}` (it appears in no constraint's derivatives)", v.name),
            );
        }
    }
    let implied = implied_constraints(model).unwrap_or_else(|(span, msg)| {
        errors.push(span, msg);
        Vec::new()
    });
    errors.finish(Analysis {
        chains,
        matching,
        structure: st,
        rates,
        implied,
    })
}

/// The rate of `s` for the total time derivative: an algebraic unknown's
/// from `rates` (see [`algebraic_rates`]), anything else the model's
/// ([`Model::rate`]).
fn rate_with(model: &Model, rates: &[(usize, Expr)], s: Sym) -> Result<Option<Expr>, Sym> {
    if let Sym::Var(j) = s {
        if let Some((_, r)) = rates.iter().find(|(k, _)| *k == j as usize) {
            return Ok(Some(r.clone()));
        }
    }
    model.rate(s)
}

/// Largest block of a mass matrix whose left null space is computed
/// symbolically (fraction-free elimination grows the entries with the
/// block's size).
pub const IMPLIED_MAX_BLOCK: usize = 12;

/// The constraints a constant, singular mass matrix implies.
///
/// The Σ-method sees only which derivatives occur, so a mass matrix that is
/// structurally regular but singular (the IVP Test Set's transistor
/// amplifier: rows `−c1·y1' + c1·y2' = f1` and `c1·y1' − c1·y2' = f2`) looks
/// like an ODE. For every block of coupled unknowns whose coefficients are
/// free of unknowns and of `t`, the left null space of the block is found by
/// fraction-free elimination with exact, symbolic pivots (generic in the
/// parameters: a pivot such as `c1` is taken as non-zero), and each null
/// vector `w` gives `0 = Σ w_i f_i` (normalised so its first weight is 1).
/// A combination whose right-hand side vanishes too is a redundant row, one
/// that is a non-zero number an inconsistent one: both are errors at the
/// row.
pub fn implied_constraints(model: &Model) -> Result<Vec<Implied>, (proc_macro2::Span, String)> {
    let mut out = Vec::new();
    if !model.has_mass_matrix() {
        return Ok(out);
    }
    let mut done = vec![false; model.n_diff];
    for j in 0..model.n_diff {
        if done[j] || !model.is_coupled(j) {
            continue;
        }
        let block = model.block(j);
        for &k in &block {
            done[k] = true;
        }
        if block.len() > IMPLIED_MAX_BLOCK {
            continue;
        }
        let constant = block.iter().all(|&r| {
            model
                .dynamic(r)
                .into_iter()
                .flat_map(Dynamic::terms)
                .all(|(_, c)| !c.any_sym(&|s| matches!(s, Sym::Var(_) | Sym::Time)))
        });
        if !constant {
            continue;
        }
        // Rows of the block: coefficients by column of the block, and the
        // combination of original rows each stands for.
        let nb = block.len();
        let col = |u: usize| block.iter().position(|&b| b == u);
        let mut m: Vec<Vec<Expr>> = block
            .iter()
            .map(|&r| {
                let mut row = vec![Expr::zero(); nb];
                for (u, c) in model.dynamic(r).into_iter().flat_map(Dynamic::terms) {
                    if let Some(k) = col(u) {
                        row[k] = c.clone();
                    }
                }
                row
            })
            .collect();
        let mut w: Vec<Vec<Expr>> = (0..nb)
            .map(|i| {
                let mut v = vec![Expr::zero(); nb];
                v[i] = Expr::one();
                v
            })
            .collect();
        let mut pivot_rows = Vec::new();
        for c in 0..nb {
            let Some(p) = (0..nb).find(|&r| !pivot_rows.contains(&r) && !m[r][c].is_zero()) else {
                continue;
            };
            pivot_rows.push(p);
            let pv = m[p][c].clone();
            for r in 0..nb {
                if r == p || m[r][c].is_zero() {
                    continue;
                }
                let f = m[r][c].clone();
                for k in 0..nb {
                    m[r][k] = expr::sub(&expr::mul(&pv, &m[r][k]), &expr::mul(&f, &m[p][k]));
                    w[r][k] = expr::sub(&expr::mul(&pv, &w[r][k]), &expr::mul(&f, &w[p][k]));
                }
            }
        }
        for r in (0..nb).filter(|r| !pivot_rows.contains(r)) {
            let Some(first) = w[r].iter().find(|e| !e.is_zero()).cloned() else {
                continue;
            };
            let rows: Vec<(usize, Expr)> = (0..nb)
                .filter(|&k| !w[r][k].is_zero())
                .map(|k| (block[k], expr::div(&w[r][k], &first)))
                .collect();
            let g = expr::add_all(
                rows.iter()
                    .filter_map(|(u, wt)| Some(expr::mul(wt, &model.dynamic(*u)?.rhs))),
            );
            let span = model
                .dynamic(rows.last().map_or(block[r], |(u, _)| *u))
                .map_or(model.name_span, |d| d.span);
            let names = rows
                .iter()
                .map(|(u, _)| format!("`der({})`", model.vars[*u].name))
                .collect::<Vec<_>>()
                .join(", ");
            if g.is_zero() {
                return Err((
                    span,
                    format!("the rows of {names} are linearly dependent, right-hand sides included: one of them is redundant (a structurally singular model)"),
                ));
            }
            if !g.any_sym(&|s| matches!(s, Sym::Var(_))) {
                return Err((
                    span,
                    format!("the rows of {names} are inconsistent: their der() terms cancel in a combination whose right-hand side `{}` is not zero", model.text(&g)),
                ));
            }
            out.push(Implied { rows, expr: g });
        }
    }
    Ok(out)
}

/// Rates `r' = …` of the algebraic unknowns `needed`, each from a
/// constraint that contains it (Σ-method: `c_i = d_r`), and those
/// constraints. The rate is the constraint's time derivative solved for the
/// one der() it holds; unknowns are taken in an order where each rate uses
/// only rates already derived.
#[allow(clippy::type_complexity)]
fn algebraic_rates(
    model: &Model,
    st: &Structure,
    needed: &[usize],
) -> Result<(Vec<(usize, Expr)>, Vec<usize>), syn::Error> {
    let mut errors = Errors::default();
    let n_dyn = model.dynamics.len();
    if needed.is_empty() {
        return Ok((Vec::new(), Vec::new()));
    }
    // Candidate constraints for each needed unknown.
    let adj: Vec<Vec<usize>> = needed
        .iter()
        .map(|&r| {
            (0..model.constraints.len())
                .filter(|&i| {
                    st.c[n_dyn + i] == st.d[r]
                        && model.constraints[i].expr.contains(Sym::Var(r as u32))
                })
                .collect()
        })
        .collect();
    let mate = max_matching(&adj, model.constraints.len());
    let mut definer = vec![usize::MAX; needed.len()];
    for (i, m) in mate.iter().enumerate() {
        if let Some(k) = m {
            definer[*k] = i;
        }
    }
    for (k, &r) in needed.iter().enumerate() {
        if st.d[r] >= 2 {
            errors.push(
                model.vars[r].span,
                format!(
                    "the hidden constraints need the derivative of order {} of the algebraic unknown `{}`; only first derivatives of algebraic unknowns are supported",
                    st.d[r], model.vars[r].name
                ),
            );
        } else if definer[k] == usize::MAX {
            errors.push(
                model.vars[r].span,
                format!(
                    "the hidden constraints need `der({})`, and no single constraint determines `{}` to give it",
                    model.vars[r].name, model.vars[r].name
                ),
            );
        }
    }
    if !errors.is_empty() {
        return Err(errors.finish(()).unwrap_err());
    }
    let mut rates: Vec<(usize, Expr)> = Vec::new();
    let mut pending: Vec<usize> = (0..needed.len()).collect();
    while !pending.is_empty() {
        let before = pending.len();
        let mut blocked = Vec::new();
        for k in pending {
            let r = needed[k];
            let g = &model.constraints[definer[k]].expr;
            // `r` keeps its der(), which the derivative is solved for.
            let known = |s: Sym| match s {
                Sym::Var(j) if j as usize == r => Ok(Some(Expr::der(r))),
                _ => rate_with(model, &rates, s),
            };
            match expr::time_derivative(g, &known) {
                Ok(dg) => {
                    let (ders, rest) = expr::split_ders(&dg);
                    let own = ders.iter().find(|(j, _)| *j == r).map(|(_, c)| c.clone());
                    match own {
                        Some(coef) if ders.iter().all(|(j, _)| *j == r || model.is_coupled(*j)) => {
                            let others = expr::add_all(
                                ders.iter()
                                    .filter(|(j, _)| *j != r)
                                    .map(|(j, c)| expr::mul(c, &Expr::der(*j))),
                            );
                            let rate = expr::neg(&expr::div(&expr::add(&rest, &others), &coef));
                            rates.push((r, rate));
                        }
                        _ => {
                            errors.push(
                                model.constraints[definer[k]].span,
                                format!(
                                    "this constraint determines `{}`, whose derivative the hidden constraints need, but its time derivative does not give `der({})` alone",
                                    model.vars[r].name, model.vars[r].name
                                ),
                            );
                        }
                    }
                }
                // Another needed rate not derived yet: try again later.
                Err(_) => blocked.push(k),
            }
        }
        if !errors.is_empty() {
            return Err(errors.finish(()).unwrap_err());
        }
        if blocked.len() == before {
            for &k in &blocked {
                errors.push(
                    model.constraints[definer[k]].span,
                    format!(
                        "this constraint determines `{}` together with other algebraic unknowns whose derivatives the hidden constraints need; such coupled blocks are not supported yet",
                        model.vars[needed[k]].name
                    ),
                );
            }
            return Err(errors.finish(()).unwrap_err());
        }
        pending = blocked;
    }
    Ok((rates, definer))
}

/// Located errors for a model the Σ-method finds structurally singular.
fn diagnose(model: &Model, singular: &Singular) -> syn::Error {
    let mut errors = Errors::default();
    let n_dyn = model.dynamics.len();
    match singular {
        Singular::NoTransversal {
            equations,
            unknowns,
            underdetermined_unknowns,
            underdetermined_equations,
            ..
        } => {
            for &e in equations.iter().filter(|&&e| e >= n_dyn) {
                let c = &model.constraints[e - n_dyn];
                let vanishes =
                    expr::time_derivative(&c.expr, &|s| model.rate(s)).is_ok_and(|d| d.is_zero());
                if vanishes {
                    errors.push(
                        c.span,
                        "structurally singular: this constraint's time derivative vanishes identically (it fixes no unknown)",
                    );
                } else {
                    let names: Vec<String> = unknowns
                        .iter()
                        .map(|&j| format!("`{}`", model.vars[j].name))
                        .collect();
                    errors.push(
                        c.span,
                        format!(
                            "structurally singular: this constraint competes with others for {} (more equations than these unknowns, however often they are differentiated)",
                            names.join(", ")
                        ),
                    );
                }
            }
            // Only dynamic rows compete: name the first of them.
            if let Some(&e) = equations
                .iter()
                .find(|&&e| e < n_dyn)
                .filter(|_| errors.is_empty())
            {
                errors.push(
                    model.dynamics[e].span,
                    "structurally singular: this equation competes with others for the same unknowns",
                );
            }
            // The under-determined part follows from the over-determined
            // one when there is one (an equation that fixes nothing leaves
            // an unknown to nobody): named only when it is the cause.
            if errors.is_empty() {
                let names: Vec<String> = underdetermined_unknowns
                    .iter()
                    .map(|&j| format!("`{}`", model.vars[j].name))
                    .collect();
                let fewer = underdetermined_equations.len();
                for &j in underdetermined_unknowns {
                    let why = if fewer == 0 {
                        "no equation contains it".to_string()
                    } else {
                        format!(
                            "the {fewer} equation{} containing {} cannot determine all {} of them",
                            if fewer == 1 { "" } else { "s" },
                            names.join(", "),
                            names.len()
                        )
                    };
                    errors.push(
                        model.vars[j].span,
                        format!(
                            "structurally singular: nothing determines `{}` ({why})",
                            model.vars[j].name
                        ),
                    );
                }
            }
        }
        other => errors.push(model.name_span, format!("structurally singular: {other}")),
    }
    if errors.is_empty() {
        errors.push(model.name_span, "structurally singular model");
    }
    errors.finish(()).unwrap_err()
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
