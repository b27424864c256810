//! The nine formulations of a semi-explicit mechanical model, built
//! symbolically as quasi-linear systems `E(y) y' = f(t, y)`.
//!
//! | name | rows | applies to |
//! |---|---|---|
//! | `ori2` | dynamics + constraints as written | every model |
//! | `rcd1` | dynamics + each constraint at level `max(d_i − 1, 0)` | some `d_i ≥ 2` |
//! | `rcd0` | dynamics + each constraint at level `d_i` | every model |
//! | `ovd1` | dynamics + levels `0 … max(d_i − 1, 0)` (overdetermined) | some `d_i ≥ 2` |
//! | `ovd0` | dynamics + levels `0 … d_i` (overdetermined) | every model |
//! | `ggl1` | `c u' = f − c Σ η_i ∂g_i/∂u`, levels 0 and 1 | mechanical (`d_i = 2`) |
//! | `psi1` | position rows projected by a selector, levels 0, 1 | mechanical |
//! | `psi0` | position and velocity rows projected, levels 0, 1, 2 | mechanical |
//! | `mex0` | dynamics of the states not chosen as dummies + levels `0 … d_i` (square, chosen at run time, [`crate::dummy`]) | some `d_i ≥ 1`, one derivative per row |
//!
//! `d_i` is the level at which constraint `i` determines the multipliers
//! (see [`crate::index`]); for a mechanical system with position
//! constraints every `d_i = 2`.
//!
//! **Selectors.** `psi1`/`psi0` apply a selector `S(q)` with `S Gᵀ = 0` to the
//! kinematic rows (`G = ∂g/∂q`, `q` the positions) and, for `psi0`, to the
//! dynamic rows (`H = ∂ġ/∂v`). It is built symbolically, without division:
//! with `G = [G_F | G_P]` split into free and pivot columns (`G_P` square and
//! structurally nonsingular, pivots chosen from the last positions),
//! `S = [det(G_P) I | −(adj(G_P) G_F)ᵀ]`, each row divided by its numeric
//! content. For the pendulum this is exactly the paper's `S = [y, −x]`.
//! `S Gᵀ = 0` holds everywhere; the selector is valid where `S` has full row
//! rank, which it has wherever `det(G_P) ≠ 0`. With one constraint in the
//! plane (the pendulum) `S` never vanishes on the constraint manifold; in
//! general it can lose rank where `det(G_P) = 0` — the spherical pendulum's
//! `[[z, 0, −x], [0, z, −y]]` at `z = 0`, the double pendulum's at `y1 = 0` or
//! `y2 = y1` — and a solver meeting such a configuration reports a singular
//! iteration matrix. A selector that would depend on `t` (a time-dependent
//! constraint) is refused: `E(y)` may not depend on `t`. In both cases the
//! runner (`dae run`, `dae sweep`) runs the projected formulation with a
//! selector computed numerically instead ([`crate::selector`]).

use crate::expr::{self, Expr, Sym};
use crate::index::{max_matching, Analysis};
use crate::model::Model;
use crate::system::{RowKind, VarInfo, VarKind, FORMULATION_NAMES};
use std::collections::HashMap;

/// One row `Σ_j E_ij y_j' = f_i`.
#[derive(Clone, Debug)]
pub struct SymRow {
    /// Differential or constraint of some level.
    pub kind: RowKind,
    /// Non-zero entries of the row of `E`: `(column, entry)`.
    pub e: Vec<(usize, Expr)>,
    /// Right-hand side.
    pub f: Expr,
}

/// A formulation, symbolically.
#[derive(Clone, Debug)]
pub struct Formulation {
    /// One of [`FORMULATION_NAMES`].
    pub name: &'static str,
    /// Unknowns (the model's, plus GGL multipliers).
    pub vars: Vec<VarInfo>,
    /// Names of unknowns past the model's own.
    pub extra_names: Vec<String>,
    /// Rows.
    pub rows: Vec<SymRow>,
    /// Differentiation index (`None` when overdetermined).
    pub d_index: Option<u8>,
    /// Strangeness index.
    pub s_index: u8,
    /// Maximal constraint level.
    pub c_level: u8,
    /// `E` independent of `y` and of `t`.
    pub constant_leading: bool,
    /// The differential rows' part of `E` independent of `y` and of `t`.
    pub constant_differential_leading: bool,
}

impl Formulation {
    /// Text of row `i` in the model language, e.g. `m*der(v) = -2*x*lambda`.
    pub fn row_text(&self, model: &Model, i: usize) -> String {
        let names = |s: Sym| model.sym_name(s, &self.extra_names);
        let row = &self.rows[i];
        let lhs = expr::add_all(row.e.iter().map(|(j, c)| expr::mul(c, &Expr::der(*j))));
        format!(
            "{} = {}",
            crate::print::text(&lhs, &names),
            crate::print::text(&row.f, &names)
        )
    }

    /// LaTeX of row `i`.
    pub fn row_latex(&self, model: &Model, i: usize) -> String {
        let names = |s: Sym| model.sym_name(s, &self.extra_names);
        let row = &self.rows[i];
        let lhs = expr::add_all(row.e.iter().map(|(j, c)| expr::mul(c, &Expr::der(*j))));
        format!(
            "{} = {}",
            crate::print::latex(&lhs, &names),
            crate::print::latex(&row.f, &names)
        )
    }

    /// `E y' − f` for row `i` as an expression in `Var` and `Der` symbols.
    pub fn residual(&self, i: usize) -> Expr {
        let row = &self.rows[i];
        let lhs = expr::add_all(row.e.iter().map(|(j, c)| expr::mul(c, &Expr::der(*j))));
        expr::sub(&lhs, &row.f)
    }

    /// Number of differential rows.
    pub fn differential_rows(&self) -> usize {
        self.rows
            .iter()
            .filter(|r| r.kind == RowKind::Differential)
            .count()
    }
}

/// Largest number of Laplace-expansion steps spent on a selector.
const SELECTOR_BUDGET: usize = 20_000;

/// Most constraints for which a selector is derived symbolically. Selector
/// rows of coupled systems are products over the whole coupling chain (for
/// a chain of `n` pendulums a row touches every link), and their Jacobians
/// grow with the square of that: at 16 links deriving `psi1` alone takes
/// seconds and hundreds of MB. Beyond this bound the model offers no
/// symbolic projected formulations; [`crate::selector`] computes a selector
/// numerically instead.
pub const SELECTOR_MAX_CONSTRAINTS: usize = 8;

/// Why a formulation does not apply to a model, or `Ok`.
pub fn applicable(model: &Model, an: &Analysis, name: &str) -> Result<(), String> {
    check(model, an, name).map(|_| ())
}

/// [`applicable`], with the selector split it derives for `psi1`/`psi0`
/// (for [`build`] to use instead of deriving it again).
fn check(model: &Model, an: &Analysis, name: &str) -> Result<Option<SelectorSplit>, String> {
    match name {
        "ori2" | "rcd0" | "ovd0" => Ok(None),
        "rcd1" | "ovd1" if an.max_level() >= 2 => Ok(None),
        "rcd1" | "ovd1" if an.max_level() == 1 => Err(format!(
            "`{name}` would repeat `ori2`: no constraint is differentiated more than once (d-index 2)"
        )),
        "rcd1" | "ovd1" => Err(format!("`{name}` needs a constraint with a hidden velocity level (d-index ≥ 2)")),
        "ggl1" | "psi1" | "psi0" if !an.is_mechanical() => Err(format!(
            "`{name}` needs position-level constraints of a mechanical system (each constraint determining its multiplier after two differentiations)"
        )),
        "ggl1" => Ok(None),
        "mex0" => crate::dummy::symbolic_blocks(model, an).map(|_| None),
        "psi0" if model.has_mass_matrix() => Err(
            "`psi0` projects the multipliers out of the velocity rows and finds them in the acceleration-level constraint; with a mass matrix that constraint holds `v'`, not the multipliers (`M` is not inverted symbolically), so nothing would determine them: use `psi1`, `rcd0` or `ovd0`".into(),
        ),
        "psi1" | "psi0" => {
            let split = selector_split(model, an)?;
            let timed = |s: &[Vec<Expr>]| s.iter().flatten().any(|e| e.contains(Sym::Time));
            if timed(&split.sq) || (name == "psi0" && timed(&split.sv)) {
                return Err(format!(
                    "the symbolic selector depends on `t` (a time-dependent constraint) and `E(y)` may not; `dae run` and `dae sweep` run `{name}` with a numerical selector (from `ovd{}`)",
                    &name[3..]
                ));
            }
            Ok(Some(split))
        }
        other => Err(format!("unknown formulation `{other}`")),
    }
}

/// The formulations a model provides: those it lists (each checked for
/// applicability, errors at the listed name) or all that apply.
pub fn provided(model: &Model, an: &Analysis) -> Result<Vec<&'static str>, syn::Error> {
    let mut errors = crate::dsl::Errors::default();
    let mut out = Vec::new();
    match &model.requested {
        Some(list) => {
            for n in list {
                if let Some(&name) = FORMULATION_NAMES.iter().find(|f| **f == n.name) {
                    match applicable(model, an, name) {
                        Ok(()) => out.push(name),
                        Err(why) => errors.push(
                            n.span,
                            format!("formulation `{name}` does not apply to this model: {why}"),
                        ),
                    }
                }
            }
        }
        None => out.extend(
            FORMULATION_NAMES
                .iter()
                .copied()
                .filter(|n| applicable(model, an, n).is_ok()),
        ),
    }
    errors.finish(out)
}

/// For each unknown of `model`, how many more differentiations of the
/// formulation (which keeps `levels[c]` of chain `c`) it takes before the
/// unknown is determined: for the algebraic unknown that chain `c`
/// determines (`an.matching`), the differentiations chain `c` still needs to
/// reach its top level, or those of any chain whose unknown its top level
/// involves, whichever is more (the closure over that dependency graph, which
/// is the block-triangular order of the top-level system); zero for the
/// differential unknowns.
///
/// The first appearance of an unknown in a chain (see [`build`]) misses
/// multipliers that enter only through other algebraic equations: in the
/// IVP Test Set's form of Andrews' squeezer, `0 = M(q) a − f + Gᵀλ` are
/// seven constraints of top level 0 holding `a` and `λ`, and `a` appears at
/// level 2 of `g(q) = 0`. `λ` is determined with `a`, by both, so in `ori2`
/// it has index 3 like `a` (the Test Set's `andrews`: the 13 accelerations
/// and multipliers of index 3), not 1.
fn differentiations_to_determine(
    model: &Model,
    an: &Analysis,
    levels: &[Vec<usize>],
) -> Vec<usize> {
    let chains = &an.chains;
    let mut owner = vec![usize::MAX; model.vars.len()];
    for (c, &v) in an.matching.iter().enumerate() {
        if v < owner.len() {
            owner[v] = c;
        }
    }
    // Chain `c`'s top level waits for the chains whose unknowns it holds.
    let needs: Vec<Vec<usize>> = chains
        .iter()
        .map(|chain| {
            let top = &chain.levels[chain.top()];
            (model.n_diff..model.vars.len())
                .filter(|&v| owner[v] != usize::MAX && model.involves(top, Sym::Var(v as u32)))
                .map(|v| owner[v])
                .collect()
        })
        .collect();
    let mut depth: Vec<usize> = chains
        .iter()
        .zip(levels)
        .map(|(chain, ls)| {
            chain
                .top()
                .saturating_sub(ls.iter().copied().max().unwrap_or(0))
        })
        .collect();
    // Longest wait along the dependencies; every pass either raises a depth
    // or ends, and depths are bounded by the largest, so this terminates.
    loop {
        let mut changed = false;
        for c in 0..chains.len() {
            let wait = needs[c].iter().map(|&d| depth[d]).max().unwrap_or(0);
            if wait > depth[c] {
                depth[c] = wait;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    owner
        .iter()
        .map(|&c| if c == usize::MAX { 0 } else { depth[c] })
        .collect()
}

/// For each unknown of `model`, the differentiations of the formulation
/// (which keeps `levels[c]` of chain `c`) before the first level that
/// holds it — Hairer & Wanner's index of a variable for Hessenberg forms
/// (the pendulum's positions 0, velocities 1) — counting only the levels
/// that constrain it:
///
/// - a level below its chain's top constrains the unknowns it holds (the
///   velocity constraint fixes the velocities' normal part);
/// - a chain's top level is solved for the chain's own algebraic unknown
///   (whose count is [`differentiations_to_determine`]); the other
///   unknowns it holds are inputs to it. The double pendulum's second
///   mass enters the first rod's top level through `λ2` but is a position
///   of the second rod's (0, as the IVP Test Set's car axis counts its
///   four positions), and a circuit's node potential entering a
///   differentiated source constraint through the mass matrix is a state
///   (`scenes/mna_cv_loop.dae`);
/// - an unknown that only top levels hold is determined by one of them when
///   that level's own unknown is fixed by a lower level elsewhere: the
///   CSTR's temperature `T` is fixed by the rate law `R = k5 e^(−k4/T) C`
///   once `R` is known from the derivative of `C`'s constraint, so `T`
///   counts what `R` does (1 in `ori2`).
fn differentiations_by_appearance(
    model: &Model,
    an: &Analysis,
    levels: &[Vec<usize>],
) -> Vec<usize> {
    let n = model.vars.len();
    let firsts: Vec<_> = an.chains.iter().map(|c| c.first_levels(model)).collect();
    let kept = |c: usize| levels[c].iter().copied().max().unwrap_or(0);
    let mut depth = vec![0usize; n];
    let mut below_top = vec![false; n];
    for (c, chain) in an.chains.iter().enumerate() {
        for (j, (d, below)) in depth.iter_mut().zip(&mut below_top).enumerate() {
            let Some(&first) = firsts[c].get(&Sym::Var(j as u32)) else {
                continue;
            };
            if first < chain.top() {
                *below = true;
            }
            if first == chain.top() && first > kept(c) {
                continue;
            }
            *d = (*d).max(first.saturating_sub(kept(c)));
        }
    }
    let owned = |j: usize| an.matching.contains(&j);
    let mut out = depth.clone();
    for (j, out) in out.iter_mut().enumerate() {
        if below_top[j] || owned(j) {
            continue;
        }
        for (c, &owner) in an.matching.iter().enumerate() {
            let top = an.chains[c].top();
            if owner < n && firsts[c].get(&Sym::Var(j as u32)) == Some(&top) {
                *out = (*out).max(depth[owner]);
            }
        }
    }
    out
}

/// Build formulation `name` (must be applicable).
pub fn build(model: &Model, an: &Analysis, name: &str) -> Result<Formulation, String> {
    let split = check(model, an, name)?;
    let &name = FORMULATION_NAMES
        .iter()
        .find(|f| **f == name)
        .ok_or_else(|| format!("unknown formulation `{name}`"))?;
    let n = model.vars.len();
    // Which levels of each chain the formulation keeps.
    let levels: Vec<Vec<usize>> = an
        .chains
        .iter()
        .map(|c| {
            let d = c.top();
            match name {
                "ori2" => vec![0],
                // A constraint that determines its unknowns as written
                // (level 0: an algebraic equation) stays as written.
                "rcd1" => vec![d.saturating_sub(1)],
                "rcd0" => vec![d],
                "ovd1" => (0..d.max(1)).collect(),
                "ovd0" | "psi0" | "mex0" => (0..=d).collect(),
                _ => vec![0, 1], // ggl1, psi1
            }
        })
        .collect();

    let through = differentiations_to_determine(model, an, &levels);
    let appearance = differentiations_by_appearance(model, an, &levels);
    let mut vars: Vec<VarInfo> = model
        .vars
        .iter()
        .enumerate()
        .map(|(j, v)| VarInfo {
            name: v.name.clone(),
            kind: v.kind,
            index: (1 + appearance[j].max(through[j])) as u8,
        })
        .collect();

    // Dynamic rows, as written.
    let mut dyn_rows: Vec<SymRow> = model
        .dynamics
        .iter()
        .map(|d| {
            let mut e: Vec<(usize, Expr)> = d.terms().map(|(j, c)| (j, c.clone())).collect();
            e.sort_by_key(|(j, _)| *j);
            SymRow {
                kind: RowKind::Differential,
                e,
                f: d.rhs.clone(),
            }
        })
        .collect();

    let mut extra_names = Vec::new();
    if name == "ggl1" {
        let taken = |s: &str| {
            model.vars.iter().any(|v| v.name == s)
                || model.params.iter().any(|p| p.name == s)
                || model.definitions.iter().any(|d| d.name == s)
        };
        for (i, c) in an.chains.iter().enumerate() {
            let mut base = if an.chains.len() == 1 {
                "eta".to_string()
            } else {
                format!("eta{}", i + 1)
            };
            while taken(&base) {
                base.push('_');
            }
            extra_names.push(base.clone());
            let eta = Expr::var(n + i);
            // `E u' = f − E Gᵀ η` on the rows whose unknowns the constraint
            // contains (the kinematic rows `q' = v`).
            for row in dyn_rows.iter_mut() {
                let terms: Vec<Expr> = row
                    .e
                    .iter()
                    .filter_map(|(j, coef)| {
                        let g = expr::diff(&c.levels[0], Sym::Var(*j as u32));
                        (!g.is_zero()).then(|| expr::mul_all([coef.clone(), eta.clone(), g]))
                    })
                    .collect();
                if !terms.is_empty() {
                    row.f = expr::sub(&row.f, &expr::add_all(terms));
                }
            }
            vars.push(VarInfo {
                name: base,
                kind: VarKind::Algebraic,
                index: 2,
            });
        }
    }

    let rows_dyn = match name {
        "psi1" | "psi0" => {
            let split = split.ok_or("a projected formulation without a selector")?;
            let mut rows = Vec::new();
            let mut emitted_q = false;
            let mut emitted_v = false;
            for (j, row) in dyn_rows.iter().enumerate() {
                if split.q.contains(&j) {
                    if !emitted_q {
                        rows.extend(project(&split.sq, &split.q, &dyn_rows));
                        emitted_q = true;
                    }
                } else if name == "psi0" && split.v.contains(&j) {
                    if !emitted_v {
                        rows.extend(project(&split.sv, &split.v, &dyn_rows));
                        emitted_v = true;
                    }
                } else {
                    rows.push(row.clone());
                }
            }
            rows
        }
        _ => dyn_rows,
    };

    let mut rows = rows_dyn;
    let max_level = levels.iter().flatten().copied().max().unwrap_or(0);
    for level in 0..=max_level {
        for (c, ls) in an.chains.iter().zip(&levels) {
            if ls.contains(&level) {
                rows.push(constraint_row(&c.levels[level], level, c.source));
            }
        }
    }

    let c_level = an
        .chains
        .iter()
        .zip(&levels)
        .map(|(c, ls)| c.top() - ls.iter().max().copied().unwrap_or(0))
        .max()
        .unwrap_or(0) as u8;
    let square = rows.len() == vars.len();
    let constant_row = |r: &SymRow| {
        r.e.iter()
            .all(|(_, c)| !c.any_sym(&|s| matches!(s, Sym::Var(_) | Sym::Time)))
    };
    let constant_leading = rows.iter().all(constant_row);
    let constant_differential_leading = rows
        .iter()
        .filter(|r| r.kind == RowKind::Differential)
        .all(constant_row);
    if name == crate::dummy::NAME {
        // The rows `mex0` selects from at run time (those of `ovd0`); the
        // numbers are those of the square formulation it selects
        // (`crate::dummy`).
        return Ok(Formulation {
            name,
            vars,
            extra_names,
            rows,
            d_index: Some(1),
            s_index: 0,
            c_level: 0,
            constant_leading: false,
            constant_differential_leading: false,
        });
    }
    Ok(Formulation {
        name,
        vars,
        extra_names,
        rows,
        d_index: square.then_some(c_level + 1),
        s_index: if square { c_level } else { c_level.max(1) },
        c_level,
        constant_leading,
        constant_differential_leading,
    })
}

/// The row `0 = g` of a constraint level. A level that holds der() (the
/// acceleration level of a model with a mass matrix, `G v' + … = 0`) is
/// linear in them and becomes a row of `E`: `Σ ∂g/∂u_j' · u_j' = −g|_{u'=0}`.
fn constraint_row(g: &Expr, level: usize, source: usize) -> SymRow {
    let (e, rest) = expr::split_ders(g);
    SymRow {
        kind: RowKind::Constraint {
            level: level as u8,
            source: source as u16,
        },
        f: if e.is_empty() { rest } else { expr::neg(&rest) },
        e,
    }
}

/// Positions, velocities and their selectors.
struct SelectorSplit {
    q: Vec<usize>,
    v: Vec<usize>,
    sq: Vec<Vec<Expr>>,
    sv: Vec<Vec<Expr>>,
}

fn selector_split(model: &Model, an: &Analysis) -> Result<SelectorSplit, String> {
    let diff_in = |level: usize, exclude: &[usize]| -> Vec<usize> {
        (0..model.n_diff)
            .filter(|j| !exclude.contains(j))
            .filter(|&j| {
                an.chains
                    .iter()
                    .any(|c| c.levels[level].contains(Sym::Var(j as u32)))
            })
            .collect()
    };
    let q = diff_in(0, &[]);
    let v = diff_in(1, &q);
    let nc = an.chains.len();
    if q.len() <= nc || v.len() < nc {
        return Err(format!(
            "the projected formulations need more positions than constraints ({} positions, {} velocities, {nc} constraints)",
            q.len(),
            v.len()
        ));
    }
    let jac = |level: usize, cols: &[usize]| -> Vec<Vec<Expr>> {
        an.chains
            .iter()
            .map(|c| {
                cols.iter()
                    .map(|&j| expr::diff(&c.levels[level], Sym::Var(j as u32)))
                    .collect()
            })
            .collect()
    };
    let sq = selector(&jac(0, &q))?;
    // The velocity rows are projected so that the multipliers drop out:
    // `S_v Λ = 0` with `Λ = ∂f/∂λ` of those rows. With one der() per row
    // (`m v' = f − Gᵀλ`) `Λ` is `−Gᵀ` up to row scaling and `∂ġ/∂v = G`
    // serves; the rows of a mass matrix are assigned to velocities by a
    // matching, so there `Λ` is read off the rows themselves.
    let sv = if v.iter().any(|&j| model.is_coupled(j)) {
        let lam: Vec<Vec<Expr>> = an
            .matching
            .iter()
            .map(|&a| {
                v.iter()
                    .map(|&j| {
                        model
                            .dynamic(j)
                            .map_or_else(Expr::zero, |d| expr::diff(&d.rhs, Sym::Var(a as u32)))
                    })
                    .collect()
            })
            .collect();
        selector(&lam)?
    } else {
        selector(&jac(1, &v))?
    };
    Ok(SelectorSplit { q, v, sq, sv })
}

/// Apply selector rows to the dynamic rows of `cols`.
fn project(s: &[Vec<Expr>], cols: &[usize], rows: &[SymRow]) -> Vec<SymRow> {
    s.iter()
        .map(|srow| {
            let mut e = Vec::new();
            let mut f = Vec::new();
            for (k, &j) in cols.iter().enumerate() {
                if srow[k].is_zero() {
                    continue;
                }
                let r = &rows[j];
                for (col, c) in &r.e {
                    e.push((*col, expr::mul(&srow[k], c)));
                }
                f.push(expr::mul(&srow[k], &r.f));
            }
            e.sort_by_key(|(c, _)| *c);
            SymRow {
                kind: RowKind::Differential,
                e,
                f: expr::add_all(f),
            }
        })
        .collect()
}

/// A selector `S` (`(n − m) × n`) with `S Gᵀ = 0` for `G` (`m × n`), built
/// from a pivot block of the last columns.
fn selector(g: &[Vec<Expr>]) -> Result<Vec<Vec<Expr>>, String> {
    let m = g.len();
    let n = g.first().map_or(0, Vec::len);
    if m > SELECTOR_MAX_CONSTRAINTS {
        return Err(format!(
            "a symbolic selector is derived for at most {SELECTOR_MAX_CONSTRAINTS} constraints, this model has {m}"
        ));
    }
    // Pivot columns: a structural matching that prefers the last columns.
    let adj: Vec<Vec<usize>> = (0..m)
        .map(|i| (0..n).rev().filter(|&k| !g[i][k].is_zero()).collect())
        .collect();
    let mate = max_matching(&adj, n);
    let pivots: Vec<usize> = (0..n).filter(|&k| mate[k].is_some()).collect();
    if pivots.len() != m {
        return Err("the constraint Jacobian is structurally rank deficient".into());
    }
    let free: Vec<usize> = (0..n).filter(|k| !pivots.contains(k)).collect();
    let gp: Vec<Vec<Expr>> = (0..m)
        .map(|i| pivots.iter().map(|&k| g[i][k].clone()).collect())
        .collect();
    let mut det = Det::new(&gp);
    let all_rows: Vec<usize> = (0..m).collect();
    let all_cols: Vec<usize> = (0..m).collect();
    let d = det.det(&all_rows, &all_cols)?;
    if d.is_zero() {
        return Err("the pivot block of the constraint Jacobian is singular".into());
    }
    // adj(G_P)[a][b] = (−1)^(a+b) det(G_P without row b and column a).
    let mut adjm = vec![vec![Expr::zero(); m]; m];
    for (a, row) in adjm.iter_mut().enumerate() {
        for (b, entry) in row.iter_mut().enumerate() {
            let rows: Vec<usize> = (0..m).filter(|&r| r != b).collect();
            let cols: Vec<usize> = (0..m).filter(|&c| c != a).collect();
            let minor = det.det(&rows, &cols)?;
            *entry = if (a + b) % 2 == 0 {
                minor
            } else {
                expr::neg(&minor)
            };
        }
    }
    let mut s = Vec::new();
    for &f in &free {
        let mut row = vec![Expr::zero(); n];
        row[f] = d.clone();
        for (a, &p) in pivots.iter().enumerate() {
            let v = expr::add_all((0..m).map(|b| expr::mul(&adjm[a][b], &g[b][f])));
            row[p] = expr::neg(&v);
        }
        // Divide by the numeric content of the row.
        let mut content: Option<expr::Q> = None;
        for e in row.iter().filter(|e| !e.is_zero()) {
            let c = expr::content(e);
            content = Some(match content {
                None => c,
                Some(g0) => expr::gcd_q(&g0, &c),
            });
        }
        if let Some(c) = content {
            let inv = num_traits::Inv::inv(c);
            row = row.iter().map(|e| expr::scale(&inv, e)).collect();
        }
        s.push(row);
    }
    Ok(s)
}

/// Symbolic determinants by Laplace expansion along the first row, skipping
/// zeros and memoising minors; bounded by [`SELECTOR_BUDGET`].
struct Det<'a> {
    a: &'a [Vec<Expr>],
    memo: HashMap<(Vec<usize>, Vec<usize>), Expr>,
    steps: usize,
}

impl<'a> Det<'a> {
    fn new(a: &'a [Vec<Expr>]) -> Self {
        Det {
            a,
            memo: HashMap::new(),
            steps: 0,
        }
    }

    fn det(&mut self, rows: &[usize], cols: &[usize]) -> Result<Expr, String> {
        if rows.is_empty() {
            return Ok(Expr::one());
        }
        let key = (rows.to_vec(), cols.to_vec());
        if let Some(v) = self.memo.get(&key) {
            return Ok(v.clone());
        }
        self.steps += 1;
        if self.steps > SELECTOR_BUDGET {
            return Err("the selector's determinant is too large to derive symbolically".into());
        }
        let r = rows[0];
        let mut terms = Vec::new();
        for (k, &c) in cols.iter().enumerate() {
            let entry = &self.a[r][c];
            if entry.is_zero() {
                continue;
            }
            let sub_cols: Vec<usize> = cols.iter().copied().filter(|&x| x != c).collect();
            let minor = self.det(&rows[1..], &sub_cols)?;
            if minor.is_zero() {
                continue;
            }
            let t = expr::mul(entry, &minor);
            terms.push(if k % 2 == 0 { t } else { expr::neg(&t) });
        }
        let v = expr::add_all(terms);
        self.memo.insert(key, v.clone());
        Ok(v)
    }
}
