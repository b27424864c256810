//! Lowering a symbolic formulation to tapes: the analytic Jacobians are
//! differentiated here, once, and both back ends (macro and interpreter)
//! consume the result.

use crate::derive::Derived;
use crate::expr::{self, Expr, Func, Sym};
use crate::formulation::Formulation;
use crate::system::{ConstraintInfo, FormulationInfo, RowInfo};
use crate::tape::{FastMap, Tape, TapeBuilder};
use std::collections::{BTreeMap, BTreeSet};
use std::rc::Rc;

/// A sparse matrix whose entries are the outputs of a tape.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sparse {
    /// `(row, column)` of each output, in output order.
    pub entries: Vec<(u32, u32)>,
    /// The entries' values.
    pub tape: Tape,
}

impl Sparse {
    fn build(cells: Vec<(usize, usize, Expr)>) -> Sparse {
        let mut b = TapeBuilder::new();
        let mut entries = Vec::new();
        for (i, j, e) in cells {
            if e.is_zero() {
                continue;
            }
            b.output(&e);
            entries.push((i as u32, j as u32));
        }
        Sparse {
            entries,
            tape: b.finish(),
        }
    }
}

/// Everything needed to evaluate one formulation numerically.
#[derive(Clone, Debug, PartialEq)]
pub struct Compiled {
    /// Static description.
    pub info: FormulationInfo,
    /// `E(t, y) y' − f(t, y)` (inputs `t, y, yp, p`), M outputs.
    pub residual: Tape,
    /// `f(t, y)`, M outputs.
    pub rhs: Tape,
    /// Entries of `E(t, y)` (inputs `t, y, p`): a der() coefficient may
    /// contain the time.
    pub leading: Sparse,
    /// Entries of `∂f/∂y`.
    pub rhs_jacobian: Sparse,
    /// Entries of `∂(E(t, y) z)/∂y` (inputs `t, y, z, p`).
    pub leading_jacobian: Sparse,
    /// The model's constraint chain, K outputs.
    pub constraints: Tape,
    /// Entries of `∂g/∂y` (K×N).
    pub constraints_jacobian: Sparse,
    /// The invariants.
    pub invariants: Tape,
    /// The event functions, one output each.
    pub events: Tape,
    /// Names of the event functions.
    pub event_names: Vec<String>,
    /// Default parameter values.
    pub parameter_defaults: Vec<f64>,
    /// For a model with a mass matrix whose chain holds der(): the model's
    /// dynamic rows, for eliminating the accelerations ([`crate::accel`]).
    /// `constraints` and `constraints_jacobian` then read der() from `yp`.
    pub accel: Option<AccelTapes>,
}

/// The tapes of [`crate::accel::AccelParts`].
#[derive(Clone, Debug, PartialEq)]
pub struct AccelTapes {
    /// Number of differential unknowns `n_d`.
    pub n_diff: usize,
    /// Entries of `E_d(t, y)` (n_d × n_d).
    pub leading: Sparse,
    /// `f_d(t, y)`, n_d outputs.
    pub rhs: Tape,
    /// Entries of `∂f_d/∂y` (n_d × N).
    pub rhs_jacobian: Sparse,
    /// Entries of `∂(E_d(t, y) z)/∂y` (n_d × N).
    pub leading_jacobian: Sparse,
    /// Entries of `∂g/∂y'` (K × n_d).
    pub chain_der: Sparse,
}

/// Lower formulation `f` of `d`.
///
/// To lower several formulations of one model, [`compile_all`] is cheaper:
/// it differentiates each distinct row once.
///
/// ```
/// use dae_core::compile::compile;
/// use dae_core::derive::Derived;
///
/// let d = Derived::from_str(
///     "pub M { differential { x } algebraic { z } equations { der(x) = -z; 0 = z - x; } }",
/// )
/// .unwrap();
/// let c = compile(&d, &d.formulations[0]);
/// assert_eq!(c.info.variables.len(), 2);
/// ```
pub fn compile(d: &Derived, f: &Formulation) -> Compiled {
    compile_with(d, f, &mut Gradients::default())
}

/// Lower every formulation `d` provides, in its order.
///
/// The formulations of a model share most of their rows (the dynamics, the
/// constraint chain, whose level-2 members are a mechanical model's largest
/// expressions): each distinct row is differentiated once here, not once
/// per formulation. The result is that of [`compile`] on each formulation.
///
/// ```
/// use dae_core::compile::{compile, compile_all};
/// use dae_core::derive::Derived;
///
/// let d = Derived::from_str(
///     "pub M { differential { x, v } algebraic { la } \
///      equations { der(x) = v; der(v) = -la*x; 0 = x^2 - 1; } }",
/// )
/// .unwrap();
/// let all = compile_all(&d);
/// assert_eq!(all.len(), d.formulations.len());
/// assert_eq!(all[1], compile(&d, &d.formulations[1]));
/// ```
pub fn compile_all(d: &Derived) -> Vec<Compiled> {
    let mut grads = Gradients::default();
    d.formulations
        .iter()
        .map(|f| compile_with(d, f, &mut grads))
        .collect()
}

/// Lower the formulations of `d` at positions `which` (into
/// `d.formulations`), in that order, with one memo of gradients as
/// [`compile_all`]: what a run that uses some of a model's formulations
/// needs, without the cost of the others.
///
/// ```
/// use dae_core::compile::{compile, compile_selected};
/// use dae_core::derive::Derived;
///
/// let d = Derived::from_str(
///     "pub M { differential { x, v } algebraic { la } \
///      equations { der(x) = v; der(v) = -la*x; 0 = x^2 - 1; } }",
/// )
/// .unwrap();
/// let last = d.formulations.len() - 1;
/// let some = compile_selected(&d, &[last, 0]);
/// assert_eq!(some.len(), 2);
/// assert_eq!(some[0], compile(&d, &d.formulations[last]));
/// assert_eq!(some[1], compile(&d, &d.formulations[0]));
/// ```
///
/// # Panics
///
/// If a position is out of range (a programming error).
pub fn compile_selected(d: &Derived, which: &[usize]) -> Vec<Compiled> {
    let mut grads = Gradients::default();
    which
        .iter()
        .map(|&k| compile_with(d, &d.formulations[k], &mut grads))
        .collect()
}

/// The partial derivatives of expressions with respect to the unknowns,
/// each distinct subexpression differentiated once (the key's hash is
/// cached in the expression, so a look-up does not walk it).
///
/// A node's gradient is assembled from its children's, by the rule
/// [`expr::diff`] applies to the node, with the same constructions in the
/// same order — so every derivative is the expression `expr::diff` gives
/// (a test compares them), but a subexpression shared by several rows, or
/// met under several unknowns of one row (the distance of a pair of
/// points under each of its six coordinates), is differentiated once, not
/// once per row and unknown.
#[derive(Default)]
struct Gradients {
    memo: FastMap<Expr, Rc<[(usize, Expr)]>>,
}

/// One step of the walk of [`Gradients::of`].
enum Visit<'a> {
    /// Find or build this expression's gradient.
    Enter(&'a Expr),
    /// Its children's gradients are remembered: build its own.
    Build(&'a Expr),
}

impl Gradients {
    /// `(k, ∂e/∂y_k)` for every unknown `y_k` that `e` contains, ascending
    /// in `k` (a derivative may be zero where the terms cancel).
    ///
    /// A walk with an explicit stack, children before parents, so an
    /// expression of any height is differentiated in constant native
    /// stack.
    fn of(&mut self, e: &Expr) -> Rc<[(usize, Expr)]> {
        let mut steps = vec![Visit::Enter(e)];
        while let Some(step) = steps.pop() {
            match step {
                Visit::Enter(e) => {
                    if self.memo.contains_key(e) {
                        continue;
                    }
                    match e {
                        Expr::Num(_) | Expr::Sym(_) => {
                            let g = self.build(e);
                            self.memo.insert(e.clone(), g);
                        }
                        Expr::Sum(s) => {
                            steps.push(Visit::Build(e));
                            steps.extend(s.terms.iter().map(|(t, _)| Visit::Enter(t)));
                        }
                        Expr::Prod(p) => {
                            steps.push(Visit::Build(e));
                            steps.extend(p.factors.iter().map(|(b, _)| Visit::Enter(b)));
                        }
                        Expr::Pow(p) => {
                            steps.push(Visit::Build(e));
                            steps.push(Visit::Enter(&p.base));
                            steps.push(Visit::Enter(&p.exponent));
                        }
                        Expr::Func(_) => {
                            steps.push(Visit::Build(e));
                            steps.push(Visit::Enter(chain_link(e)));
                        }
                    }
                }
                Visit::Build(e) => {
                    // A child may be the expression's equal met twice.
                    if !self.memo.contains_key(e) {
                        let g = self.build(e);
                        self.memo.insert(e.clone(), g);
                    }
                }
            }
        }
        self.memo
            .get(e)
            .cloned()
            .unwrap_or_else(|| Rc::from(Vec::new()))
    }

    /// The remembered gradient of a child of a node being built.
    fn child(&self, e: &Expr) -> Rc<[(usize, Expr)]> {
        self.memo
            .get(e)
            .cloned()
            .unwrap_or_else(|| Rc::from(Vec::new()))
    }

    /// The gradient of `e` from its children's, which are remembered.
    fn build(&self, e: &Expr) -> Rc<[(usize, Expr)]> {
        match e {
            Expr::Num(_) => Rc::from(Vec::new()),
            Expr::Sym(Sym::Var(k)) => Rc::from(vec![(*k as usize, Expr::one())]),
            Expr::Sym(_) => Rc::from(Vec::new()),
            Expr::Sum(sum) => {
                // `∂(Σ c_i t_i)/∂y_k = Σ c_i ∂t_i/∂y_k` over the terms
                // holding `y_k`, added by `add_all` as `expr::diff` adds
                // them (the terms without `y_k` add zeros).
                let mut parts: BTreeMap<usize, Vec<Expr>> = BTreeMap::new();
                for (t, c) in &sum.terms {
                    for (k, d) in self.child(t).iter() {
                        parts.entry(*k).or_default().push(expr::scale(c, d));
                    }
                }
                parts
                    .into_iter()
                    .map(|(k, ds)| (k, expr::add_all(ds)))
                    .collect()
            }
            Expr::Prod(p) => {
                // The product rule of `expr::diff`: for each factor `b^x`
                // whose derivative is not zero, in order, the product
                // `x · b^(x−1) · b' · Π_(j≠i) b_j^(x_j)`. The powers do not
                // depend on the unknown: built once for all of them.
                let grads: Vec<Rc<[(usize, Expr)]>> =
                    p.factors.iter().map(|(b, _)| self.child(b)).collect();
                let lowered: Vec<Expr> = p
                    .factors
                    .iter()
                    .map(|(b, x)| expr::pow_rational(b, &(x - expr::q(1))))
                    .collect();
                let powers: Vec<Expr> = p
                    .factors
                    .iter()
                    .map(|(b, x)| expr::pow_rational(b, x))
                    .collect();
                let mut parts: BTreeMap<usize, Vec<Expr>> = BTreeMap::new();
                for (i, g) in grads.iter().enumerate() {
                    for (k, db) in g.iter() {
                        let terms = parts.entry(*k).or_default();
                        if db.is_zero() {
                            continue;
                        }
                        let mut items = Vec::with_capacity(p.factors.len() + 2);
                        items.push(Expr::num(p.factors[i].1.clone()));
                        items.push(lowered[i].clone());
                        items.push(db.clone());
                        items.extend(
                            powers
                                .iter()
                                .enumerate()
                                .filter(|(j, _)| *j != i)
                                .map(|(_, x)| x.clone()),
                        );
                        terms.push(expr::mul_all(items));
                    }
                }
                parts
                    .into_iter()
                    .map(|(k, ts)| (k, expr::add_all(ts)))
                    .collect()
            }
            Expr::Pow(p) => {
                // `d(b^e) = b^e · (e' ln b + e b'/b)`, as `expr::diff`.
                let (b, x) = (&p.base, &p.exponent);
                let (gb, gx) = (self.child(b), self.child(x));
                let ln_b = expr::func(Func::Ln, b);
                let inv_b = expr::pow_rational(b, &expr::q(-1));
                let ks: BTreeSet<usize> = gb.iter().chain(gx.iter()).map(|(k, _)| *k).collect();
                let at = |g: &[(usize, Expr)], k: usize| {
                    g.iter()
                        .find(|(j, _)| *j == k)
                        .map_or_else(Expr::zero, |(_, d)| d.clone())
                };
                ks.into_iter()
                    .map(|k| {
                        let inner = expr::add(
                            &expr::mul(&at(&gx, k), &ln_b),
                            &expr::mul_all([x.clone(), at(&gb, k), inv_b.clone()]),
                        );
                        (k, expr::mul(e, &inner))
                    })
                    .collect()
            }
            Expr::Func(_) => {
                // The chain rule along the whole chain `f(g(h(…)))` at
                // once, as `expr::diff`: the outer derivatives, then the
                // innermost argument's derivative.
                let mut outer = Vec::new();
                let mut link = e;
                while let Expr::Func(c) = link {
                    outer.push(expr::outer_derivative(c, link));
                    link = &c.arg;
                }
                self.child(link)
                    .iter()
                    .map(|(k, d)| {
                        let mut factors = outer.clone();
                        factors.push(d.clone());
                        (*k, expr::mul_all(factors))
                    })
                    .collect()
            }
        }
    }

    /// Row `i` of `∂f/∂y` into `out`: `(i, k, ∂f/∂y_k)` for the unknowns
    /// `y_k`, `k < n`, that `f` contains (only those have non-zero
    /// derivatives: a row costs its own size, not the model's).
    fn row(&mut self, i: usize, f: &Expr, n: usize, out: &mut Vec<(usize, usize, Expr)>) {
        for (k, d) in self.of(f).iter() {
            if *k < n {
                out.push((i, *k, d.clone()));
            }
        }
    }
}

/// The innermost argument of a chain of calls `f(g(h(a)))`: `a`.
fn chain_link(e: &Expr) -> &Expr {
    let mut link = e;
    while let Expr::Func(c) = link {
        link = &c.arg;
    }
    link
}

fn compile_with(d: &Derived, f: &Formulation, grads: &mut Gradients) -> Compiled {
    let model = &d.model;
    let n = f.vars.len();
    let m = f.rows.len();
    let info = FormulationInfo {
        model: model.name.clone(),
        name: f.name.to_string(),
        variables: f.vars.clone(),
        rows: (0..m)
            .map(|i| RowInfo {
                kind: f.rows[i].kind,
                text: f.row_text(model, i),
            })
            .collect(),
        d_index: f.d_index,
        s_index: f.s_index,
        c_level: f.c_level,
        constant_leading: f.constant_leading,
        constant_differential_leading: f.constant_differential_leading,
        constraints: d.constraint_infos(),
        invariants: model.invariants.iter().map(|i| i.name.clone()).collect(),
        parameters: model.params.iter().map(|p| p.name.clone()).collect(),
    };

    let mut res = TapeBuilder::new();
    let mut rhs = TapeBuilder::new();
    let mut e_cells = Vec::new();
    let mut fj_cells = Vec::new();
    let mut ej_cells = Vec::new();
    for (i, row) in f.rows.iter().enumerate() {
        res.output(&f.residual(i));
        rhs.output(&row.f);
        for (j, c) in &row.e {
            e_cells.push((i, *j, c.clone()));
        }
        grads.row(i, &row.f, n, &mut fj_cells);
        if !f.constant_leading {
            leading_jacobian_cells(i, &row.e, n, &mut ej_cells);
        }
    }
    let chain = d.analysis.flat();
    let mut cons = TapeBuilder::new();
    let mut cj_cells = Vec::new();
    for (r, (_, _, e)) in chain.iter().enumerate() {
        cons.output(e);
        grads.row(r, e, n, &mut cj_cells);
    }
    // The accelerations are eliminated only where the chain holds der():
    // the implied constraints of a singular mass matrix (which has no
    // inverse to eliminate with) hold none.
    let holds_der = chain
        .iter()
        .any(|(_, _, e)| e.any_sym(&|s| matches!(s, Sym::Der(_))));
    let accel = (model.has_mass_matrix() && holds_der).then(|| accel_tapes(d, n, grads));
    let mut inv = TapeBuilder::new();
    for i in &model.invariants {
        inv.output(&i.expr);
    }
    let mut events = TapeBuilder::new();
    for e in &model.events {
        events.output(&e.expr);
    }
    Compiled {
        info,
        residual: res.finish(),
        rhs: rhs.finish(),
        leading: Sparse::build(e_cells),
        rhs_jacobian: Sparse::build(fj_cells),
        leading_jacobian: Sparse::build(ej_cells),
        constraints: cons.finish(),
        constraints_jacobian: Sparse::build(cj_cells),
        invariants: inv.finish(),
        events: events.finish(),
        event_names: model.events.iter().map(|e| e.name.clone()).collect(),
        parameter_defaults: model.params.iter().map(|p| p.default).collect(),
        accel,
    }
}

/// The model's dynamic rows and the chain's der() coefficients, for a model
/// with a mass matrix (`n` unknowns in the formulation).
fn accel_tapes(d: &Derived, n: usize, grads: &mut Gradients) -> AccelTapes {
    let model = &d.model;
    let mut e_cells = Vec::new();
    let mut rhs = TapeBuilder::new();
    let mut fj_cells = Vec::new();
    let mut ej_cells = Vec::new();
    for (i, dy) in model.dynamics.iter().enumerate() {
        let terms: Vec<(usize, Expr)> = dy.terms().map(|(j, c)| (j, c.clone())).collect();
        for (j, c) in &terms {
            e_cells.push((i, *j, c.clone()));
        }
        rhs.output(&dy.rhs);
        grads.row(i, &dy.rhs, n, &mut fj_cells);
        leading_jacobian_cells(i, &terms, n, &mut ej_cells);
    }
    let mut cd_cells = Vec::new();
    for (r, (_, _, e)) in d.analysis.flat().iter().enumerate() {
        for j in 0..model.n_diff {
            let s = Sym::Der(j as u32);
            if e.contains(s) {
                cd_cells.push((r, j, expr::diff(e, s)));
            }
        }
    }
    AccelTapes {
        n_diff: model.n_diff,
        leading: Sparse::build(e_cells),
        rhs: rhs.finish(),
        rhs_jacobian: Sparse::build(fj_cells),
        leading_jacobian: Sparse::build(ej_cells),
        chain_der: Sparse::build(cd_cells),
    }
}

/// Row `i` of `∂(E(y) z)/∂y` for the row `terms` of `E`: `(i, k, Σ_j
/// ∂E_ij/∂y_k z_j)` for the unknowns the coefficients contain.
fn leading_jacobian_cells(
    i: usize,
    terms: &[(usize, Expr)],
    n: usize,
    out: &mut Vec<(usize, usize, Expr)>,
) {
    for k in unknowns(terms.iter().map(|(_, c)| c), n) {
        let s = Sym::Var(k as u32);
        let ez = expr::add_all(
            terms
                .iter()
                .map(|(j, c)| expr::mul(&expr::diff(c, s), &Expr::sym(Sym::Dir(*j as u32)))),
        );
        out.push((i, k, ez));
    }
}

/// The unknowns `y_k`, `k < n`, that any of `exprs` contains, ascending.
fn unknowns<'a>(exprs: impl Iterator<Item = &'a Expr>, n: usize) -> Vec<usize> {
    let mut all = std::collections::BTreeSet::new();
    for e in exprs {
        for s in e.symbols() {
            if let Sym::Var(k) = s {
                if (k as usize) < n {
                    all.insert(k as usize);
                }
            }
        }
    }
    all.into_iter().collect()
}

impl Derived {
    /// The constraint chain as reported (source-major, then level).
    pub fn constraint_infos(&self) -> Vec<ConstraintInfo> {
        self.analysis
            .flat()
            .into_iter()
            .map(|(source, level, e)| ConstraintInfo {
                level: level as u8,
                source: source as u16,
                expr: self.model.text(e),
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interp::InterpretedSystem;
    use crate::system::DaeSystem;
    use nalgebra::DMatrix;
    use std::sync::Arc;

    /// Each formulation of a two-link chain reports the structural
    /// non-zeros of its matrices (no non-zero outside them at a generic
    /// point; far fewer than all entries), and the sparse evaluations give
    /// the dense ones' entries, also for a pattern that is not the
    /// system's own.
    #[test]
    #[allow(clippy::type_complexity)] // a table of three closures, once
    fn sparsity_covers_the_matrices_and_the_values_are_the_dense_entries() {
        use crate::system::{Model, Pattern};
        let m = crate::interp::InterpretedModel::from_str(
            "pub C { parameters { g = 9.81 } differential { x1, y1, x2, y2, u1, v1, u2, v2 } \
             algebraic { a1, a2 } equations { der(x1) = u1; der(y1) = v1; der(x2) = u2; \
             der(y2) = v2; der(u1) = -2*a1*x1 + 2*a2*(x2 - x1); \
             der(v1) = -2*a1*y1 + 2*a2*(y2 - y1) - g; der(u2) = -2*a2*(x2 - x1); \
             der(v2) = -2*a2*(y2 - y1) - g; 0 = x1^2 + y1^2 - 1; \
             0 = (x2 - x1)^2 + (y2 - y1)^2 - 1; } }",
        )
        .expect("the chain derives");
        let names = m.model_info().formulations.clone();
        assert!(names.iter().any(|n| n == "rcd0"), "{names:?}");
        for name in &names {
            let sys = m.system(name).expect("provided");
            let info = sys.info();
            let (rows, cols) = (info.equations(), info.unknowns());
            let y: Vec<f64> = (0..cols).map(|k| 0.3 + 0.17 * k as f64).collect();
            let z: Vec<f64> = (0..cols).map(|k| 1.0 - 0.11 * k as f64).collect();
            let sp = sys.sparsity();
            let dense = Pattern::dense(rows, cols);
            let mut j = DMatrix::zeros(rows, cols);
            let checks: [(
                &Pattern,
                &dyn Fn(&mut DMatrix<f64>),
                &dyn Fn(&Pattern, &mut [f64]),
            ); 3] = [
                (
                    &sp.rhs_jacobian,
                    &|j| sys.rhs_jacobian(0.5, &y, j),
                    &|p, v| sys.rhs_jacobian_values(0.5, &y, p, v),
                ),
                (&sp.leading, &|j| sys.leading(0.5, &y, j), &|p, v| {
                    sys.leading_values(0.5, &y, p, v)
                }),
                (
                    &sp.leading_jacobian,
                    &|j| sys.leading_jacobian(0.5, &y, &z, j),
                    &|p, v| sys.leading_jacobian_values(0.5, &y, &z, p, v),
                ),
            ];
            for (k, (p, eval, values)) in checks.iter().enumerate() {
                eval(&mut j);
                for r in 0..rows {
                    for c in 0..cols {
                        assert!(
                            j[(r, c)] == 0.0 || p.contains(r, c),
                            "{name} matrix {k}: ({r}, {c}) = {} outside the pattern",
                            j[(r, c)]
                        );
                    }
                }
                for pat in [*p, &dense] {
                    let mut v = vec![f64::NAN; pat.nnz()];
                    values(pat, &mut v);
                    for (v, (r, c)) in v.iter().zip(pat.entries()) {
                        assert_eq!(*v, j[(r, c)], "{name} matrix {k} at ({r}, {c})");
                    }
                }
            }
            // The projected formulations (psi1, psi0) mix rows and are
            // denser; the others hold each row's own unknowns only.
            let iteration = sp.iteration();
            assert!(
                name.starts_with("psi") || iteration.nnz() * 2 < rows * cols,
                "{name}: {} of {} entries",
                iteration.nnz(),
                rows * cols
            );
        }
    }

    /// The remembered gradients, built term by term for a sum, are the
    /// derivatives `expr::diff` gives, expression for expression, for every
    /// row and constraint of every formulation of a three-point model with
    /// pair forces (terms shared between rows and with the chain).
    #[test]
    fn gradients_are_the_derivatives_of_diff() {
        let d = Derived::from_str(
            "pub P { parameters { a = 0.5 } \
             differential { x1, y1, x2, y2, x3, y3, u1, v1, u2, v2, u3, v3 } \
             algebraic { l1, l2, l3 } \
             definitions { r12 = (x1 - x2)^2 + (y1 - y2)^2; r13 = (x1 - x3)^2 + (y1 - y3)^2; \
             r23 = (x2 - x3)^2 + (y2 - y3)^2; } \
             equations { der(x1) = u1; der(y1) = v1; der(x2) = u2; der(y2) = v2; \
             der(x3) = u3; der(y3) = v3; \
             der(u1) = (x1 - x2)/r12^(3/2) + (x1 - x3)/r13^(3/2) - 2*l1*x1 - a*u1; \
             der(v1) = (y1 - y2)/r12^(3/2) + (y1 - y3)/r13^(3/2) - 2*l1*y1 - a*v1; \
             der(u2) = (x2 - x1)/r12^(3/2) + (x2 - x3)/r23^(3/2) - 2*l2*x2 - a*u2; \
             der(v2) = (y2 - y1)/r12^(3/2) + (y2 - y3)/r23^(3/2) - 2*l2*y2 - a*v2; \
             der(u3) = (x3 - x1)/r13^(3/2) + (x3 - x2)/r23^(3/2) - 2*l3*x3 - a*u3; \
             der(v3) = (y3 - y1)/r13^(3/2) + (y3 - y2)/r23^(3/2) - 2*l3*y3 - a*v3; \
             0 = x1^2 + y1^2 - 1; 0 = x2^2 + y2^2 - 1; 0 = x3^2 + y3^2 - 1; } }",
        )
        .expect("the model derives");
        let mut grads = Gradients::default();
        let mut exprs: Vec<Expr> = d
            .analysis
            .flat()
            .into_iter()
            .map(|(_, _, e)| e.clone())
            .collect();
        for f in &d.formulations {
            exprs.extend(f.rows.iter().map(|r| r.f.clone()));
        }
        let mut sums = 0;
        for e in &exprs {
            sums += usize::from(matches!(e, Expr::Sum(_)));
            assert_eq!(&*grads.of(e), &by_diff(e)[..], "{e:?}");
        }
        assert!(sums > 20, "{sums} sums among {} rows", exprs.len());
    }

    /// The gradient of `e` by `expr::diff`, one unknown at a time: the
    /// independent check of [`Gradients`].
    fn by_diff(e: &Expr) -> Vec<(usize, Expr)> {
        e.symbols()
            .into_iter()
            .filter_map(|s| match s {
                Sym::Var(k) => Some((k as usize, expr::diff(e, s))),
                _ => None,
            })
            .collect()
    }

    /// The gradients built node by node from the children's are the
    /// derivatives of `expr::diff` through every kind of node: calls and
    /// chains of calls, symbolic powers, products of sums with rational
    /// exponents, parameters, the time and der() held fixed, a subtree met
    /// twice, and one row sharing the memo with the others.
    #[test]
    fn gradients_of_every_kind_of_node_are_those_of_diff() {
        use crate::expr::{add, func, mul, mul_all, pow, pow_rational, qr, sub};
        let (x, y, z) = (Expr::var(0), Expr::var(1), Expr::var(2));
        let (p, t, dx) = (Expr::param(0), Expr::sym(Sym::Time), Expr::der(0));
        let r = add(&mul(&x, &x), &mul(&y, &y));
        let exprs = [
            func(Func::Sin, &func(Func::Cos, &mul(&x, &y))),
            pow(&x, &y),
            pow(&add(&x, &z), &mul(&p, &y)),
            mul_all([sub(&x, &y), pow_rational(&r, &qr(-3, 2)), p.clone()]),
            mul_all([func(Func::Exp, &x), func(Func::Ln, &y), t.clone()]),
            add(
                &func(Func::Tan, &pow_rational(&r, &qr(1, 2))),
                &mul(&dx, &z),
            ),
            mul(&pow_rational(&r, &qr(1, 3)), &func(Func::Sin, &r)),
            add(&mul(&p, &t), &dx),
            Expr::int(7),
            x.clone(),
        ];
        let mut grads = Gradients::default();
        for e in &exprs {
            assert_eq!(&*grads.of(e), &by_diff(e)[..], "{e:?}");
        }
    }

    /// A formulation whose row of `E` holds the time: `(1 + t)·x·der(x)`,
    /// made by hand from the model's `x·der(x)` (the model checker does not
    /// take `t` in a der() coefficient yet). Its tapes read `t` in `E` and in
    /// `∂(E z)/∂y`, and the interpreter passes the time it is given.
    #[test]
    fn a_time_dependent_leading_matrix_is_evaluated_at_the_given_time() {
        let d = Derived::from_str(
            "pub M { differential { x } algebraic { z } \
             equations { x * der(x) = -x + z; 0 = z - t * x; } }",
        )
        .expect("the model derives");
        let mut f = d.formulations[0].clone();
        let one_plus_t = expr::add(&Expr::one(), &Expr::sym(Sym::Time));
        for (_, c) in &mut f.rows[0].e {
            *c = expr::mul(c, &one_plus_t);
        }
        f.constant_leading = false;
        f.constant_differential_leading = false;
        let c = compile(&d, &f);
        let sys = InterpretedSystem::new(Arc::new(c), Vec::new());
        let y = [2.0, 0.5];
        let (mut e0, mut e1) = (DMatrix::zeros(2, 2), DMatrix::zeros(2, 2));
        sys.leading(0.0, &y, &mut e0);
        sys.leading(1.5, &y, &mut e1);
        // (1 + t)·x at x = 2: 2 at t = 0, 5 at t = 1.5; the algebraic row
        // stays zero.
        assert_eq!((e0[(0, 0)], e1[(0, 0)]), (2.0, 5.0));
        assert_eq!((e0[(1, 0)], e0[(1, 1)], e1[(1, 1)]), (0.0, 0.0, 0.0));
        // ∂((1 + t)·x·z_x)/∂x = (1 + t)·z_x.
        let (mut j0, mut j1) = (DMatrix::zeros(2, 2), DMatrix::zeros(2, 2));
        sys.leading_jacobian(0.0, &y, &[3.0, 0.0], &mut j0);
        sys.leading_jacobian(1.5, &y, &[3.0, 0.0], &mut j1);
        assert_eq!((j0[(0, 0)], j1[(0, 0)]), (3.0, 7.5));
        // The residual is E(t, y) y' − f(t, y) at the same time, and every
        // analytic Jacobian matches central differences at random times.
        let worst = crate::check::check_jacobians(&sys, 10, 3, 1e-7).expect("Jacobians agree");
        assert!(worst < 1e-7, "{worst:e}");
    }
}
