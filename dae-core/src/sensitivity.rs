//! Forward sensitivities with respect to named parameters
//! (`docs/design_sensitivities.md`).
//!
//! For a formulation `E y' = f(t, y, p)` with a constant leading matrix the
//! sensitivity `sᵢ = ∂y/∂pᵢ` satisfies the linear DAE
//!
//! ```text
//!     E sᵢ' = J(t, y) sᵢ + ∂f/∂pᵢ(t, y),     J = ∂f/∂y,
//! ```
//!
//! with the state's matrix `E`, and the linearised constraint chain
//! `G(t, y) sᵢ + ∂g/∂pᵢ = 0` (`G = ∂g/∂y`). [`SensitivitySystem`] is that
//! system and the state's side by side, as one formulation of
//! `N (1 + P)` unknowns `[y; s₁; …; s_P]` that every solver integrates and
//! every consistent initialisation starts: the state's rows first, then
//! for each parameter its copy of the rows.
//!
//! # Where `∂f/∂p` comes from
//!
//! From the derivation itself. The model is derived a second time with the
//! named parameters made differential unknowns of the equations
//! `der(p) = 0` ([`parameters_as_unknowns`]): its formulations are the
//! original ones with `p` a symbol like any other, so the columns of their
//! analytic Jacobians for `p` are `∂f/∂p` and `∂g/∂p` — every formulation,
//! every hidden constraint, differentiated symbolically by the code that
//! differentiates everything else. Rows and constraint members of the two
//! derivations are matched by their printed text (the state's rows are
//! printed alike whether `p` is a parameter or an unknown); a formulation
//! whose rows do not match is refused ([`SensitivityError::Rows`]):
//! `ggl1` adds `Gᵀη` also to `der(p)`, a row the sensitivity system drops,
//! and its other rows match.
//!
//! # What a residual costs
//!
//! The rows of the whole system, `f(y)` and every `J sᵢ + ∂f/∂pᵢ`, come
//! from one forward pass over the augmented formulation's tape of `f` at
//! `[y, p]` along the directions `(sᵢ, e_pᵢ)`
//! ([`DaeSystem::rhs_tangents`]): the derivative of `f(y, p)` along
//! `(sᵢ, e_pᵢ)` is `J sᵢ + ∂f/∂pᵢ`. No Jacobian is formed per residual,
//! and the state's rows come from the same pass (BENCHMARKS.md §13c).
//!
//! # What the solvers see
//!
//! The Jacobian the system reports is block lower triangular: `∂f/∂y` of
//! the state on every diagonal block, and below it `Bᵢ = ∂(J sᵢ +
//! ∂f/∂pᵢ)/∂y` (second derivatives of `f`), which by the symmetry of second
//! derivatives is the derivative of the augmented formulation's `J` along
//! `(sᵢ, e_pᵢ)`: one augmented Jacobian per parameter by a directional
//! difference. It declares that structure ([`DaeSystem::blocks`]), and
//! `radau5` and `bdf` then factorise the state's block alone and solve by
//! block forward substitution (bdf's simultaneous corrector). `radau5`
//! instead staggers ([`DaeSystem::first_block`],
//! [`DaeSystem::first_block_linearisation`]): it iterates the state on the
//! state's own formulation, then the sensitivities' linear stage equations
//! with the state fixed, by products with `[J | ∂f/∂p]` at the stage
//! points and the state's factorisations, so that `Bᵢ` is never formed and
//! with the sensitivities out of the error test the state takes the plain
//! run's steps. Leaving `Bᵢ` out (a block-diagonal matrix,
//! as IDA's simultaneous corrector does for its ODE-like index-1 systems)
//! was measured: on the pendulum's `rcd0` the sensitivities' algebraic
//! rows depend on `y` at order one, not `h`, and the simplified Newton
//! iteration then contracts poorly: radau5 at tol 1e-10 rejected every
//! second step with the dense solve, and bdf's sensitivities missed the
//! closed form by 6.7e-6 with the block solve. The constraint chain's
//! Jacobian is built by forward differences (it serves the start only).
//! Refused: formulations whose leading matrix depends on the unknowns or
//! on a sensitivity parameter (`psi1`, `psi0`, a mass `m` in `m·der(v)` as
//! sensitivity parameter: the term `∂(E y')/∂(y, p)` is not built yet), and
//! `mex0` (its run-time choice of dummies could choose a parameter).
//!
//! ```
//! use dae_core::sensitivity::Sensitivities;
//! use dae_core::system::DaeSystem;
//!
//! let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/pendulum.dae")).unwrap();
//! let model = Sensitivities::from_str(&src, &["g", "l"]).unwrap();
//! let sys = model.formulation("rcd0").unwrap();
//! assert_eq!(sys.info().unknowns(), 5 * 3);
//! assert_eq!(sys.info().variables[5].name, "dx/dg");
//! // the linearised constraint at the horizontal release: 2x·sx + 2y·sy − 2l = 0
//! let mut y = vec![0.0; 15];
//! y[0] = 1.0; // x = l = 1, y = 0, at rest
//! y[10] = 1.0; // dx/dl = 1
//! let mut g = vec![0.0; sys.info().constraints.len()];
//! sys.constraints(0.0, &y, &mut g);
//! assert!(g.iter().all(|v| v.abs() < 1e-15));
//! assert!(matches!(
//!     Sensitivities::from_str(&src, &["q"]),
//!     Err(dae_core::sensitivity::SensitivityError::UnknownParameter { .. })
//! ));
//! ```

use crate::derive::Derived;
use crate::dsl::{Ast, Equation, ModelAst, Name};
use crate::expr::Q;
use crate::interp::InterpretedModel;
use crate::system::{
    Blocks, BoxedSystem, ConstraintInfo, DaeSystem, FormulationError, FormulationInfo, Model,
    ParameterError, RowInfo, VarInfo, SKIP,
};
use nalgebra::DMatrix;
use std::cell::RefCell;

/// Why sensitivities cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SensitivityError {
    /// No base parameter has this name.
    #[error(
        "no parameter `{name}` to differentiate with respect to (the model's parameters: {known})"
    )]
    UnknownParameter {
        /// The name asked for.
        name: String,
        /// The model's base parameters.
        known: String,
    },
    /// A derived parameter (`derived { k = m * l^2; }`): a function of the
    /// base parameters, differentiated through them.
    #[error(
        "`{name}` is a derived parameter: ask for the sensitivities with respect to the base \
         parameters it is computed from"
    )]
    DerivedParameter {
        /// The name asked for.
        name: String,
    },
    /// A name asked for twice.
    #[error("parameter `{name}` is named twice")]
    Duplicate {
        /// The name.
        name: String,
    },
    /// The model with the parameters as unknowns does not derive (e.g. a
    /// derived parameter depends on one of them).
    #[error("sensitivities with respect to {params}: {message}")]
    Model {
        /// The parameters asked for.
        params: String,
        /// The derivation's error.
        message: String,
    },
    /// The formulation cannot carry sensitivities.
    #[error("no sensitivities on formulation `{name}`: {reason}")]
    Formulation {
        /// Formulation name.
        name: String,
        /// Why.
        reason: String,
    },
    /// The two derivations' rows of a formulation do not correspond.
    #[error("formulation `{name}`: its rows with the parameters as unknowns do not match its own ({detail})")]
    Rows {
        /// Formulation name.
        name: String,
        /// The first row without a partner.
        detail: String,
    },
    /// The formulation does not exist or is not provided.
    #[error(transparent)]
    NotProvided(#[from] FormulationError),
    /// A parameter value could not be set.
    #[error(transparent)]
    Parameter(#[from] ParameterError),
}

/// The model `ast` with the base parameters `params` made differential
/// unknowns, appended after the others, each with the equation
/// `der(p) = 0` appended after the others.
pub fn parameters_as_unknowns(
    ast: &ModelAst,
    params: &[&str],
) -> Result<ModelAst, SensitivityError> {
    let mut out = ast.clone();
    for (i, &name) in params.iter().enumerate() {
        if params[..i].contains(&name) {
            return Err(SensitivityError::Duplicate {
                name: name.to_string(),
            });
        }
        let Some(k) = out.parameters.iter().position(|p| p.name.name == name) else {
            if let Some(d) = ast.derived.iter().find(|d| d.name.name == name) {
                return Err(SensitivityError::DerivedParameter {
                    name: d.name.name.clone(),
                });
            }
            return Err(SensitivityError::UnknownParameter {
                name: name.to_string(),
                known: ast
                    .parameters
                    .iter()
                    .map(|p| p.name.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        };
        let decl = out.parameters.remove(k);
        let span = decl.name.span;
        out.differential.push(Name {
            name: name.to_string(),
            span,
        });
        out.equations.push(Equation {
            lhs: Ast::Call("der".into(), span, vec![Ast::Ident(name.to_string(), span)]),
            rhs: Ast::Num(Q::from_integer(0.into()), span),
            span,
        });
    }
    Ok(out)
}

/// A model read at run time, derived twice: as written, and with the
/// sensitivity parameters as unknowns.
#[derive(Clone, Debug)]
pub struct Sensitivities {
    state: InterpretedModel,
    augmented: InterpretedModel,
    params: Vec<String>,
}

impl Sensitivities {
    /// Parse and derive model text, with sensitivities with respect to
    /// the base parameters `params`.
    #[allow(clippy::should_implement_trait)] // two arguments, a typed error
    pub fn from_str(src: &str, params: &[&str]) -> Result<Self, SensitivityError> {
        let model_error = |e: syn::Error| SensitivityError::Model {
            params: params.join(", "),
            message: e.to_string(),
        };
        let ast = crate::dsl::parse_str(src).map_err(model_error)?;
        let augmented = parameters_as_unknowns(&ast, params)?;
        Ok(Sensitivities {
            state: InterpretedModel::new(&Derived::from_ast(&ast).map_err(model_error)?),
            augmented: InterpretedModel::new(&Derived::from_ast(&augmented).map_err(model_error)?),
            params: params.iter().map(|p| p.to_string()).collect(),
        })
    }

    /// The model as written (its parameters, its formulations).
    pub fn model(&self) -> &InterpretedModel {
        &self.state
    }

    /// The sensitivity parameters, in order.
    pub fn parameters(&self) -> &[String] {
        &self.params
    }

    /// Set a parameter of the model (a sensitivity parameter or another).
    pub fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), SensitivityError> {
        self.state.set_parameter(name, value)?;
        if !self.params.iter().any(|p| p == name) {
            self.augmented.set_parameter(name, value)?;
        }
        Ok(())
    }

    /// The sensitivity system of formulation `name`.
    pub fn formulation(&self, name: &str) -> Result<SensitivitySystem, SensitivityError> {
        if name == crate::dummy::NAME {
            return Err(SensitivityError::Formulation {
                name: name.into(),
                reason: "its dummy derivatives are chosen at run time among the unknowns, \
                         which would include the parameters"
                    .into(),
            });
        }
        let state = self.state.formulation(name)?;
        let augmented = self.augmented.formulation(name)?;
        SensitivitySystem::new(state, augmented, &self.params)
    }
}

/// A formulation and its sensitivities, as one formulation (see the
/// module's documentation).
pub struct SensitivitySystem {
    state: BoxedSystem,
    augmented: BoxedSystem,
    info: FormulationInfo,
    /// The state's unknowns' columns in the augmented formulation.
    var_cols: Vec<usize>,
    /// The sensitivity parameters' columns in the augmented formulation.
    param_cols: Vec<usize>,
    /// The state's rows' rows in the augmented formulation.
    row_of: Vec<usize>,
    /// `E` of the state (constant).
    e: DMatrix<f64>,
    /// Its non-zeros `(row, column, value)`, for the residuals.
    e_entries: Vec<(usize, usize, f64)>,
    /// Whether the sensitivities are in the methods' error test.
    error_control: bool,
    /// The linearisation from the augmented Jacobian's non-zeros
    /// ([`Linearisation`]); `None` for an augmented formulation that
    /// reports no structure (its dense Jacobian is gathered instead).
    lin: Option<Linearisation>,
    scratch: RefCell<Scratch>,
}

/// [`DaeSystem::first_block_linearisation`] from the augmented
/// formulation's Jacobian on its own pattern
/// ([`DaeSystem::rhs_jacobian_values`]): no dense augmented matrix is
/// zeroed, written and gathered per stage point.
struct Linearisation {
    /// Where each value of the augmented formulation's `∂f/∂y` pattern
    /// goes in `[∂f/∂y | ∂f/∂p]` of the state's rows (column-major, `N`
    /// rows), or [`SKIP`] ([`DaeSystem::rhs_jacobian_scatter`]).
    to: Vec<usize>,
}

impl Linearisation {
    /// The map of `augmented`'s Jacobian pattern onto `[∂f/∂y | ∂f/∂p]`
    /// (the columns `cols`, the rows `row_of`); `None` when the pattern is
    /// dense (a system that knows no structure evaluates its values from
    /// the dense matrix, allocating).
    fn new(augmented: &dyn DaeSystem, cols: &[usize], row_of: &[usize]) -> Option<Self> {
        let pattern = augmented.sparsity().rhs_jacobian;
        if pattern.nnz() == pattern.rows * pattern.cols {
            return None;
        }
        let mut to = vec![SKIP; pattern.nnz()];
        for (oc, &ac) in cols.iter().enumerate() {
            let (from, end) = (pattern.col_ptr[ac], pattern.col_ptr[ac + 1]);
            for (slot, &ar) in to[from..end].iter_mut().zip(&pattern.row_idx[from..end]) {
                if let Some(r) = row_of.iter().position(|&x| x == ar) {
                    *slot = oc * row_of.len() + r;
                }
            }
        }
        Some(Linearisation { to })
    }
}

struct Scratch {
    /// The augmented point `[y, p]` (the parameters' columns set once).
    point: Vec<f64>,
    /// Three more such points ([`DaeSystem::first_block_linearisations`]).
    points: [Vec<f64>; 3],
    /// The augmented formulation's Jacobian (rows × unknowns).
    jac: DMatrix<f64>,
    /// The augmented constraint chain's Jacobian.
    cjac: DMatrix<f64>,
    /// The state's Jacobian.
    block: DMatrix<f64>,
    /// The state's constraint Jacobian.
    cblock: DMatrix<f64>,
    /// The augmented Jacobian at a moved point, and that point (`Bᵢ`).
    moved: DMatrix<f64>,
    dir: Vec<f64>,
    /// The directions `(sᵢ, e_pᵢ)` in the augmented unknowns, one after
    /// the other (the parameters' unit entries set once).
    dirs: Vec<f64>,
    /// The augmented formulation's `f` and its derivatives along `dirs`.
    fa: Vec<f64>,
    dfa: Vec<f64>,
}

impl std::fmt::Debug for SensitivitySystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SensitivitySystem")
            .field("formulation", &self.info.name)
            .field("unknowns", &self.info.unknowns())
            .finish()
    }
}

/// The positions of `wanted` in `have`, in order, each after the last:
/// `None` at the first one missing.
fn match_in_order<'a>(
    wanted: impl Iterator<Item = &'a str>,
    have: &[&str],
) -> Result<Vec<usize>, String> {
    let mut at = 0;
    let mut out = Vec::new();
    for w in wanted {
        match have[at..].iter().position(|h| *h == w) {
            Some(k) => {
                out.push(at + k);
                at += k + 1;
            }
            None => return Err(format!("`{w}`")),
        }
    }
    Ok(out)
}

/// Which row of `augmented` each row of `state` is, in order, found by
/// evaluating both at two pseudo-random points (the state's rows are the
/// augmented formulation's with the parameters' values in their columns,
/// though the terms may print in another order), and whether the two
/// constraint chains agree there member by member.
fn match_numerically(
    state: &dyn DaeSystem,
    augmented: &dyn DaeSystem,
    var_cols: &[usize],
    parameters_point: &[f64],
) -> Result<(Vec<usize>, bool), String> {
    let (si, ai) = (state.info(), augmented.info());
    let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
    let mut random = move || {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        0.5 + (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-10 * (1.0 + a.abs().max(b.abs()));
    let mut candidates: Vec<Vec<bool>> = vec![vec![true; ai.equations()]; si.equations()];
    let mut same_chain = si.constraints.len() == ai.constraints.len();
    for _ in 0..2 {
        let t = random();
        let y: Vec<f64> = (0..si.unknowns()).map(|_| random()).collect();
        let yp: Vec<f64> = (0..si.unknowns()).map(|_| random()).collect();
        let (mut ya, mut ypa) = (parameters_point.to_vec(), vec![0.0; ai.unknowns()]);
        for (j, &c) in var_cols.iter().enumerate() {
            ya[c] = y[j];
            ypa[c] = yp[j];
        }
        let (mut rs, mut ra) = (vec![0.0; si.equations()], vec![0.0; ai.equations()]);
        state.residual(t, &y, &yp, &mut rs);
        augmented.residual(t, &ya, &ypa, &mut ra);
        for (r, c) in candidates.iter_mut().enumerate() {
            for (a, ok) in c.iter_mut().enumerate() {
                *ok &= close(rs[r], ra[a]);
            }
        }
        if same_chain {
            let (mut gs, mut ga) = (
                vec![0.0; si.constraints.len()],
                vec![0.0; ai.constraints.len()],
            );
            state.constraints(t, &y, &mut gs);
            augmented.constraints(t, &ya, &mut ga);
            same_chain = gs.iter().zip(&ga).all(|(a, b)| close(*a, *b));
        }
    }
    let mut at = 0;
    let mut row_of = Vec::with_capacity(si.equations());
    for (r, c) in candidates.iter().enumerate() {
        match (at..ai.equations()).find(|&a| c[a]) {
            Some(a) => {
                row_of.push(a);
                at = a + 1;
            }
            None => return Err(format!("row `{}`", si.rows[r].text)),
        }
    }
    Ok((row_of, same_chain))
}

impl SensitivitySystem {
    /// Pair a formulation with the same formulation derived with the
    /// parameters `params` as unknowns.
    pub fn new(
        state: BoxedSystem,
        augmented: BoxedSystem,
        params: &[String],
    ) -> Result<Self, SensitivityError> {
        let si = state.info();
        let ai = augmented.info();
        let refuse = |reason: &str| SensitivityError::Formulation {
            name: si.name.clone(),
            reason: reason.to_string(),
        };
        if !ai.constant_leading || !si.constant_leading {
            return Err(refuse(
                "its leading matrix depends on the unknowns, the time or a sensitivity \
                 parameter (the term d(E y')/d(y, p) of the sensitivity equations is not built)",
            ));
        }
        let rows_error = |detail: String| SensitivityError::Rows {
            name: si.name.clone(),
            detail,
        };
        let names: Vec<&str> = ai.variables.iter().map(|v| v.name.as_str()).collect();
        let var_cols = match_in_order(si.variables.iter().map(|v| v.name.as_str()), &names)
            .map_err(|w| rows_error(format!("unknown {w}")))?;
        let param_cols = params
            .iter()
            .map(|p| {
                names
                    .iter()
                    .position(|n| n == p)
                    .ok_or_else(|| rows_error(format!("parameter `{p}`")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        // The augmented point with the state's parameter values in the
        // sensitivity parameters' columns: they never change (a system's
        // parameters are fixed), so the scratch point keeps them and each
        // evaluation writes only the state's columns.
        let values = state.parameter_values();
        let mut point = vec![0.0; ai.unknowns()];
        for (p, &c) in params.iter().zip(&param_cols) {
            let k = si
                .parameters
                .iter()
                .position(|q| q == p)
                .ok_or_else(|| rows_error(format!("parameter `{p}` of the state")))?;
            point[c] = values[k];
        }
        let (row_of, same_chain) =
            match_numerically(&*state, &*augmented, &var_cols, &point).map_err(rows_error)?;
        if !same_chain {
            return Err(rows_error("the constraint chains differ".into()));
        }
        let (n, m, k, np) = (
            si.unknowns(),
            si.equations(),
            si.constraints.len(),
            params.len(),
        );
        let sources = si
            .constraints
            .iter()
            .map(|c| c.source + 1)
            .max()
            .unwrap_or(0);
        let mut info = si.clone();
        for (i, p) in params.iter().enumerate() {
            info.variables.extend(si.variables.iter().map(|v| VarInfo {
                name: format!("d{}/d{p}", v.name),
                kind: v.kind,
                index: v.index,
            }));
            info.rows.extend(si.rows.iter().map(|r| RowInfo {
                kind: r.kind,
                text: format!("d/d{p}: {}", r.text),
            }));
            info.constraints
                .extend(si.constraints.iter().map(|c| ConstraintInfo {
                    level: c.level,
                    source: c.source + (i as u16 + 1) * sources,
                    expr: format!("d/d{p}: {}", c.expr),
                }));
        }
        let mut e = DMatrix::zeros(m, n);
        state.leading(0.0, &vec![0.0; n], &mut e);
        let e_entries = (0..n)
            .flat_map(|c| (0..m).map(move |r| (r, c)))
            .filter(|&(r, c)| e[(r, c)] != 0.0)
            .map(|(r, c)| (r, c, e[(r, c)]))
            .collect();
        let na = ai.unknowns();
        let mut dirs = vec![0.0; np * na];
        for (i, &c) in param_cols.iter().enumerate() {
            dirs[i * na + c] = 1.0;
        }
        let lin_cols: Vec<usize> = var_cols.iter().chain(&param_cols).copied().collect();
        let lin = Linearisation::new(&*augmented, &lin_cols, &row_of);
        let scratch = RefCell::new(Scratch {
            points: [point.clone(), point.clone(), point.clone()],
            point,
            jac: DMatrix::zeros(ai.equations(), na),
            cjac: DMatrix::zeros(k, na),
            block: DMatrix::zeros(m, n),
            cblock: DMatrix::zeros(k, n),
            moved: DMatrix::zeros(ai.equations(), na),
            dir: vec![0.0; na],
            dirs,
            fa: vec![0.0; ai.equations()],
            dfa: vec![0.0; ai.equations() * np],
        });
        Ok(SensitivitySystem {
            state,
            augmented,
            info,
            var_cols,
            param_cols,
            row_of,
            e,
            e_entries,
            error_control: true,
            lin,
            scratch,
        })
    }

    /// Take the sensitivities out of the methods' error test (`false`) or
    /// put them back in (`true`, the default here): declared to the
    /// solvers by [`DaeSystem::blocks`]. Out of it, the step sizes are the
    /// state's alone and the sensitivities are as accurate as the state's
    /// steps make them (BENCHMARKS.md §13, §13d). SUNDIALS' default is the
    /// other one: `IDASetSensErrCon` and `CVodeSetSensErrCon` default to
    /// `SUNFALSE` (sensitivities out of the error test, always in the
    /// Newton convergence test), which radau5's staggered corrector also
    /// does.
    ///
    /// ```
    /// use dae_core::sensitivity::Sensitivities;
    /// use dae_core::system::DaeSystem;
    ///
    /// let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/pendulum.dae")).unwrap();
    /// let mut sys = Sensitivities::from_str(&src, &["g"]).unwrap().formulation("rcd0").unwrap();
    /// assert!(sys.blocks().unwrap().error_control);
    /// sys.set_error_control(false);
    /// assert_eq!(sys.blocks().unwrap().count, 2);
    /// assert!(!sys.blocks().unwrap().error_control);
    /// ```
    pub fn set_error_control(&mut self, on: bool) {
        self.error_control = on;
    }

    /// The state's formulation.
    pub fn state(&self) -> &dyn DaeSystem {
        &*self.state
    }

    /// The sensitivities alone with the state frozen at `y` (its
    /// consistent start): a linear DAE in `[s₁; …; s_P]` whose constraint
    /// chain is `G(y) sᵢ + ∂g/∂pᵢ(y) = 0`, so that the consistent
    /// initialisation of it is the least-change projection of the given
    /// sensitivities onto the linearised constraints, with the algebraic
    /// sensitivities from the highest members. Starting the whole system
    /// at once would also move the state to satisfy the sensitivities'
    /// constraints (their rows depend on `y`): start the state first, then
    /// this.
    pub fn frozen(&self, y: &[f64]) -> Frozen<'_> {
        let (n, m, k) = (
            self.state_unknowns(),
            self.state.info().equations(),
            self.state.info().constraints.len(),
        );
        let mut info = self.info.clone();
        info.variables.drain(..n);
        info.rows.drain(..m);
        info.constraints.drain(..k);
        info.invariants.clear();
        Frozen {
            sys: self,
            y: y[..n].to_vec(),
            info,
        }
    }

    /// Unknowns of the state.
    pub fn state_unknowns(&self) -> usize {
        self.state.info().unknowns()
    }

    /// The sensitivity parameters' count.
    pub fn parameters(&self) -> usize {
        self.param_cols.len()
    }

    /// The augmented point `[y, p]` of the state's `y` into `point`, a
    /// scratch point (the parameters' columns hold their values from the
    /// start).
    fn lift(&self, point: &mut [f64], y: &[f64]) {
        for (j, &c) in self.var_cols.iter().enumerate() {
            point[c] = y[j];
        }
    }

    /// `f` of the whole system for `y = [y; s₁; …; s_P]` into `out`
    /// (length `m (1 + P)`): the state's rows `f(y)` and each parameter's
    /// `J sᵢ + ∂f/∂pᵢ`, both from one forward pass of the augmented
    /// formulation at `[y, p]` along the directions `(sᵢ, e_pᵢ)`
    /// ([`DaeSystem::rhs_tangents`]): the derivative of `f(y, p)` along
    /// `(sᵢ, e_pᵢ)` is `J sᵢ + ∂f/∂pᵢ`, and no Jacobian is formed.
    fn whole_rhs(&self, s: &mut Scratch, t: f64, y: &[f64], out: &mut [f64]) {
        let n = self.var_cols.len();
        let m = self.row_of.len();
        let np = self.param_cols.len();
        let (point, dirs) = (&mut s.point, &mut s.dirs);
        let na = point.len();
        for (&c, &v) in self.var_cols.iter().zip(&y[..n]) {
            point[c] = v;
        }
        for (dir, si) in dirs.chunks_exact_mut(na).zip(y[n..].chunks_exact(n)) {
            for (&c, &v) in self.var_cols.iter().zip(si) {
                dir[c] = v;
            }
        }
        self.augmented
            .rhs_tangents(t, point, dirs, np, &mut s.fa, &mut s.dfa);
        let ma = s.fa.len();
        let (state, sens) = out.split_at_mut(m);
        for (o, &ar) in state.iter_mut().zip(&self.row_of) {
            *o = s.fa[ar];
        }
        for (block, d) in sens.chunks_exact_mut(m).zip(s.dfa.chunks_exact(ma)) {
            for (o, &ar) in block.iter_mut().zip(&self.row_of) {
                *o = d[ar];
            }
        }
    }
}

impl DaeSystem for SensitivitySystem {
    fn info(&self) -> &FormulationInfo {
        &self.info
    }

    fn parameter_values(&self) -> Vec<f64> {
        self.state.parameter_values()
    }

    fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]) {
        let s = &mut *self.scratch.borrow_mut();
        self.whole_rhs(s, t, y, f);
    }

    /// `blockdiag(E, …, E) y' − f`, `f` from [`SensitivitySystem::rhs`]'s
    /// one pass (the state's rows included: `E` is constant).
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        let (n, m) = (self.var_cols.len(), self.row_of.len());
        self.whole_rhs(&mut self.scratch.borrow_mut(), t, y, r);
        for (rb, ypb) in r.chunks_exact_mut(m).zip(yp.chunks_exact(n)) {
            for v in rb.iter_mut() {
                *v = -*v;
            }
            for &(row, col, e) in &self.e_entries {
                rb[row] += e * ypb[col];
            }
        }
    }

    fn leading(&self, _t: f64, _y: &[f64], e: &mut DMatrix<f64>) {
        let (n, m) = (self.state_unknowns(), self.state.info().equations());
        e.fill(0.0);
        for b in 0..=self.parameters() {
            e.view_mut((m * b, n * b), (m, n)).copy_from(&self.e);
        }
    }

    fn rhs_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        let (n, m) = (self.state_unknowns(), self.state.info().equations());
        let s = &mut *self.scratch.borrow_mut();
        j.fill(0.0);
        // The diagonal blocks: the augmented Jacobian's state rows and
        // columns (the one the sensitivity rows are formed with).
        self.lift(&mut s.point, &y[..n]);
        self.augmented.rhs_jacobian(t, &s.point, &mut s.jac);
        for (r, &ar) in self.row_of.iter().enumerate() {
            for (c, &ac) in self.var_cols.iter().enumerate() {
                s.block[(r, c)] = s.jac[(ar, ac)];
            }
        }
        for b in 0..=self.parameters() {
            j.view_mut((m * b, n * b), (m, n)).copy_from(&s.block);
        }
        // Below the diagonal: Bᵢ = ∂(J sᵢ + ∂f/∂pᵢ)/∂y, which by the
        // symmetry of second derivatives is the derivative of J along
        // dᵢ = (sᵢ, e_pᵢ) in the augmented unknowns: one augmented Jacobian
        // per parameter by a directional difference.
        let (base, moved, dir) = (&s.jac, &mut s.moved, &mut s.dir);
        let scale = s.point.iter().fold(1.0_f64, |a, v| a.max(v.abs()));
        for (i, &pc) in self.param_cols.iter().enumerate() {
            let si = &y[n * (i + 1)..n * (i + 2)];
            let size = si.iter().fold(1.0_f64, |a, v| a.max(v.abs()));
            let eps = f64::EPSILON.sqrt() * scale / size;
            dir.copy_from_slice(&s.point);
            for (k, &c) in self.var_cols.iter().enumerate() {
                dir[c] += eps * si[k];
            }
            dir[pc] += eps;
            self.augmented.rhs_jacobian(t, dir, moved);
            for (r, &ar) in self.row_of.iter().enumerate() {
                for (c, &ac) in self.var_cols.iter().enumerate() {
                    j[(m * (i + 1) + r, c)] = (moved[(ar, ac)] - base[(ar, ac)]) / eps;
                }
            }
        }
    }

    fn leading_jacobian(&self, _t: f64, _y: &[f64], _z: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
    }

    fn constraints(&self, t: f64, y: &[f64], g: &mut [f64]) {
        let n = self.state_unknowns();
        let k = self.state.info().constraints.len();
        self.state.constraints(t, &y[..n], &mut g[..k]);
        let s = &mut *self.scratch.borrow_mut();
        self.lift(&mut s.point, &y[..n]);
        self.augmented
            .constraints_jacobian(t, &s.point, &mut s.cjac);
        for (i, &pc) in self.param_cols.iter().enumerate() {
            let si = &y[n * (i + 1)..n * (i + 2)];
            for row in 0..k {
                let mut v = s.cjac[(row, pc)];
                for (j, &c) in self.var_cols.iter().enumerate() {
                    v += s.cjac[(row, c)] * si[j];
                }
                g[k * (i + 1) + row] = v;
            }
        }
    }

    fn constraints_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        let n = self.state_unknowns();
        let k = self.state.info().constraints.len();
        {
            let s = &mut *self.scratch.borrow_mut();
            self.state.constraints_jacobian(t, &y[..n], &mut s.cblock);
            j.fill(0.0);
            for b in 0..=self.parameters() {
                j.view_mut((k * b, n * b), (k, n)).copy_from(&s.cblock);
            }
        }
        // Below the diagonal: d(G sᵢ + ∂g/∂pᵢ)/dy by forward differences.
        let mut base = vec![0.0; k * (1 + self.parameters())];
        let mut moved = base.clone();
        self.constraints(t, y, &mut base);
        let mut yd = y.to_vec();
        for c in 0..n {
            let h = f64::EPSILON.sqrt() * y[c].abs().max(1.0);
            yd[c] = y[c] + h;
            self.constraints(t, &yd, &mut moved);
            yd[c] = y[c];
            for r in k..base.len() {
                j[(r, c)] = (moved[r] - base[r]) / h;
            }
        }
    }

    fn invariants(&self, t: f64, y: &[f64], out: &mut [f64]) {
        self.state.invariants(t, &y[..self.state_unknowns()], out);
    }

    /// `1 + P` blocks of the state's size, for a square state.
    fn blocks(&self) -> Option<Blocks> {
        let si = self.state.info();
        (si.equations() == si.unknowns()).then_some(Blocks {
            size: si.unknowns(),
            count: 1 + self.parameters(),
            error_control: self.error_control,
        })
    }

    /// The state's own formulation: the first block's rows and Jacobian
    /// (the diagonal blocks and the state's rows this system reports come
    /// from the augmented formulation's tape, equal up to the order of the
    /// terms).
    fn first_block(&self) -> Option<&dyn DaeSystem> {
        self.blocks().map(|_| &*self.state as &dyn DaeSystem)
    }

    /// The augmented formulation's Jacobian at `[y, p]`, its state rows,
    /// the state's columns then the parameters'.
    fn first_block_linearisation(&self, t: f64, y: &[f64], out: &mut DMatrix<f64>) -> bool {
        let (n, np) = (self.var_cols.len(), self.param_cols.len());
        if y.len() != n || out.nrows() != self.row_of.len() || out.ncols() != n + np {
            return false;
        }
        let s = &mut *self.scratch.borrow_mut();
        self.lift(&mut s.point, y);
        if let Some(lin) = &self.lin {
            let out = out.as_mut_slice();
            out.fill(0.0);
            self.augmented
                .rhs_jacobian_scatter(t, &s.point, &lin.to, out);
            return true;
        }
        self.augmented.rhs_jacobian(t, &s.point, &mut s.jac);
        // Column-major: each column of `out` gathers the state's rows of
        // one column of the augmented Jacobian.
        let rows = s.jac.nrows();
        let (src, dst) = (s.jac.as_slice(), out.as_mut_slice());
        let cols = self.var_cols.iter().chain(&self.param_cols);
        for (o, &ac) in dst.chunks_exact_mut(self.row_of.len()).zip(cols) {
            let col = &src[ac * rows..(ac + 1) * rows];
            for (v, &ar) in o.iter_mut().zip(&self.row_of) {
                *v = col[ar];
            }
        }
        true
    }

    /// The three points' linearisations in one pass of the augmented
    /// formulation's Jacobian ([`DaeSystem::rhs_jacobian_scatter3`]) where
    /// its pattern is known; three calls otherwise.
    fn first_block_linearisations(
        &self,
        t: [f64; 3],
        y: [&[f64]; 3],
        out: &mut [DMatrix<f64>; 3],
    ) -> bool {
        let (n, np) = (self.var_cols.len(), self.param_cols.len());
        let fits = y.iter().zip(out.iter()).all(|(y, out)| {
            y.len() == n && out.nrows() == self.row_of.len() && out.ncols() == n + np
        });
        let Some(lin) = self.lin.as_ref().filter(|_| fits) else {
            return t
                .into_iter()
                .zip(y)
                .zip(out.iter_mut())
                .all(|((t, y), out)| self.first_block_linearisation(t, y, out));
        };
        let s = &mut *self.scratch.borrow_mut();
        for (point, y) in s.points.iter_mut().zip(y) {
            self.lift(point, y);
        }
        let out = out.each_mut().map(|out| {
            let out = out.as_mut_slice();
            out.fill(0.0);
            out
        });
        let points = s.points.each_ref().map(|p| &p[..]);
        self.augmented
            .rhs_jacobian_scatter3(t, points, &lin.to, out);
        true
    }

    fn event_names(&self) -> &[String] {
        self.state.event_names()
    }

    fn events(&self, t: f64, y: &[f64], out: &mut [f64]) {
        self.state.events(t, &y[..self.state_unknowns()], out)
    }
}

/// [`SensitivitySystem::frozen`]: the sensitivities with the state fixed.
pub struct Frozen<'a> {
    sys: &'a SensitivitySystem,
    y: Vec<f64>,
    info: FormulationInfo,
}

impl Frozen<'_> {
    /// `[y; s]` from the sensitivities `s`.
    fn whole(&self, s: &[f64]) -> Vec<f64> {
        let mut v = self.y.clone();
        v.extend_from_slice(s);
        v
    }
}

impl DaeSystem for Frozen<'_> {
    fn info(&self) -> &FormulationInfo {
        &self.info
    }
    fn parameter_values(&self) -> Vec<f64> {
        self.sys.parameter_values()
    }
    fn rhs(&self, t: f64, s: &[f64], f: &mut [f64]) {
        let m = self.sys.state.info().equations();
        let mut all = vec![0.0; self.sys.info.equations()];
        self.sys.rhs(t, &self.whole(s), &mut all);
        f.copy_from_slice(&all[m..]);
    }
    fn residual(&self, t: f64, s: &[f64], sp: &[f64], r: &mut [f64]) {
        let m = self.sys.state.info().equations();
        let mut yp = vec![0.0; self.y.len()];
        yp.extend_from_slice(sp);
        let mut all = vec![0.0; self.sys.info.equations()];
        self.sys.residual(t, &self.whole(s), &yp, &mut all);
        r.copy_from_slice(&all[m..]);
    }
    fn leading(&self, t: f64, s: &[f64], e: &mut DMatrix<f64>) {
        let (n, m) = (self.y.len(), self.sys.state.info().equations());
        let mut all = DMatrix::zeros(self.sys.info.equations(), self.sys.info.unknowns());
        self.sys.leading(t, &self.whole(s), &mut all);
        e.copy_from(&all.view((m, n), (e.nrows(), e.ncols())));
    }
    fn rhs_jacobian(&self, t: f64, _s: &[f64], j: &mut DMatrix<f64>) {
        // Linear in s: the state's Jacobian on every block, exactly.
        let (n, m) = (self.y.len(), self.sys.state.info().equations());
        let mut block = DMatrix::zeros(m, n);
        self.sys.state.rhs_jacobian(t, &self.y, &mut block);
        j.fill(0.0);
        for b in 0..self.sys.parameters() {
            j.view_mut((m * b, n * b), (m, n)).copy_from(&block);
        }
    }
    fn leading_jacobian(&self, _t: f64, _s: &[f64], _z: &[f64], j: &mut DMatrix<f64>) {
        j.fill(0.0);
    }
    fn constraints(&self, t: f64, s: &[f64], g: &mut [f64]) {
        let k = self.sys.state.info().constraints.len();
        let mut all = vec![0.0; self.sys.info.constraints.len()];
        self.sys.constraints(t, &self.whole(s), &mut all);
        g.copy_from_slice(&all[k..]);
    }
    fn constraints_jacobian(&self, t: f64, _s: &[f64], j: &mut DMatrix<f64>) {
        let (n, k) = (self.y.len(), self.sys.state.info().constraints.len());
        let mut block = DMatrix::zeros(k, n);
        self.sys.state.constraints_jacobian(t, &self.y, &mut block);
        j.fill(0.0);
        for b in 0..self.sys.parameters() {
            j.view_mut((k * b, n * b), (k, n)).copy_from(&block);
        }
    }
    fn invariants(&self, _t: f64, _s: &[f64], _out: &mut [f64]) {}
}
