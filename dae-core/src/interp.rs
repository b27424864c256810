//! The interpreted implementation of the runtime trait, for models read at
//! run time: the same tapes the macro turns into straight-line code,
//! evaluated node by node.

use crate::compile::{compile_all, compile_selected, Compiled, Sparse};
use crate::derive::Derived;
use crate::expr::Expr;
use crate::system::gather_dense;
use crate::system::{
    check_parameter, BoxedSystem, DaeSystem, FormulationError, FormulationInfo, Model, ModelInfo,
    ParameterError, Pattern, Sparsity,
};
use crate::tape::{Inputs, Tape, TapeBuilder};
use nalgebra::DMatrix;
use std::cell::{OnceCell, RefCell};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};

/// A model loaded at run time.
#[derive(Clone, Debug)]
pub struct InterpretedModel {
    info: ModelInfo,
    /// Every parameter's value: the base ones, then the derived ones.
    params: Vec<f64>,
    /// Number of base parameters.
    n_base: usize,
    /// The derived parameters from the base ones: one output each.
    derived: Tape,
    /// The lowered formulations, shared by clones.
    lowered: Arc<Lowered>,
}

/// The formulations of an [`InterpretedModel`], lowered when first asked
/// for (a model read for one run lowers one).
#[derive(Debug)]
struct Lowered {
    /// The model text, derived again to lower a formulation not lowered
    /// yet (the derived model itself holds `Rc`s and cannot be kept by a
    /// model that moves between threads; the thread that derived it keeps
    /// it in [`KEPT`] instead); `None` when all are lowered.
    source: Option<Arc<str>>,
    /// This model's key in [`KEPT`] (unique in the process).
    id: u64,
    /// One slot per provided formulation, in the order of
    /// `ModelInfo::formulations`.
    slots: Vec<OnceLock<Arc<Compiled>>>,
}

thread_local! {
    /// The derived model of the last [`InterpretedModel::lazy`] made on
    /// this thread, with its [`Lowered::id`], while it has formulations
    /// left to lower: lowering on the thread that derived (a run) then
    /// derives once, not twice (BENCHMARKS.md §10). One model at most, so
    /// the memory held is one derivation's; a model lowered elsewhere, or
    /// after another lazy model was made here, derives its text again.
    static KEPT: RefCell<Option<(u64, Derived)>> = const { RefCell::new(None) };
}

/// Source of [`Lowered::id`]: 0 is a model lowered eagerly.
static NEXT_ID: AtomicU64 = AtomicU64::new(1);

impl Drop for Lowered {
    fn drop(&mut self) {
        // Release the kept derivation with the last clone of its model (on
        // the thread that kept it; elsewhere the next lazy model replaces
        // it). `try_with`: the thread's locals may be gone at its exit.
        let _ = KEPT.try_with(|k| {
            if let Ok(mut k) = k.try_borrow_mut() {
                if k.as_ref().is_some_and(|(kept, _)| *kept == self.id) {
                    *k = None;
                }
            }
        });
    }
}

impl InterpretedModel {
    /// Compile every provided formulation of a derived model now.
    ///
    /// ```
    /// use dae_core::derive::Derived;
    /// use dae_core::interp::InterpretedModel;
    /// use dae_core::system::Model;
    ///
    /// let d = Derived::from_str(
    ///     "pub M { differential { x } algebraic { z } equations { der(x) = -z; 0 = z - x; } }",
    /// )
    /// .unwrap();
    /// let m = InterpretedModel::new(&d);
    /// assert!(m.formulation(&d.formulations[0].name).is_ok());
    /// ```
    pub fn new(d: &Derived) -> Self {
        let slots = compile_all(d)
            .into_iter()
            .map(|c| OnceLock::from(Arc::new(c)))
            .collect();
        Self::with(
            d,
            Lowered {
                source: None,
                id: 0,
                slots,
            },
        )
    }

    /// Parse, check and derive model text; lower each formulation when it
    /// is first asked for ([`InterpretedModel::system`],
    /// [`Model::formulation`]) or all of a set at once
    /// ([`Model::prepare`], with the gradients of the rows they share
    /// computed once). A run that uses one formulation of a model with
    /// six lowers one: the set-up of a large model is mostly lowering
    /// (BENCHMARKS.md §10). Lowering on the thread that made the model
    /// uses the derivation kept then; on another thread it derives the
    /// text again.
    ///
    /// ```
    /// use dae_core::interp::InterpretedModel;
    /// use dae_core::system::Model;
    ///
    /// let src = "pub M { differential { x, v } algebraic { la } \
    ///            equations { der(x) = v; der(v) = -la*x; 0 = x^2 - 1; } }";
    /// let lazy = InterpretedModel::lazy(src).unwrap();
    /// let eager = InterpretedModel::from_str(src).unwrap();
    /// let (a, b) = (lazy.system("ggl1").unwrap(), eager.system("ggl1").unwrap());
    /// assert_eq!(a.compiled(), b.compiled());
    /// ```
    pub fn lazy(src: &str) -> Result<Self, syn::Error> {
        let d = Derived::from_str(src)?;
        let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
        let m = Self::with(
            &d,
            Lowered {
                source: Some(Arc::from(src)),
                id,
                slots: d.formulations.iter().map(|_| OnceLock::new()).collect(),
            },
        );
        KEPT.with(|k| *k.borrow_mut() = Some((id, d)));
        Ok(m)
    }

    fn with(d: &Derived, lowered: Lowered) -> Self {
        InterpretedModel {
            info: d.model_info(),
            params: d.model.params.iter().map(|p| p.default).collect(),
            n_base: d.model.n_base,
            derived: {
                let mut b = TapeBuilder::new();
                for p in &d.model.params[d.model.n_base..] {
                    b.output(p.derived.as_ref().unwrap_or(&Expr::zero()));
                }
                b.finish()
            },
            lowered: Arc::new(lowered),
        }
    }

    /// Parse, check, derive and compile model text (every formulation,
    /// now; [`InterpretedModel::lazy`] lowers them when asked for).
    #[allow(clippy::should_implement_trait)] // returns `syn::Error` with spans, unlike `str::parse`
    pub fn from_str(src: &str) -> Result<Self, syn::Error> {
        Ok(Self::new(&Derived::from_str(src)?))
    }

    /// Lower the formulations at positions `which` that are not lowered
    /// yet, together (one derivation, one memo of gradients).
    fn lower(&self, which: &[usize]) {
        let slots = &self.lowered.slots;
        let missing: Vec<usize> = which
            .iter()
            .copied()
            .filter(|&k| slots[k].get().is_none())
            .collect();
        let Some(src) = &self.lowered.source else {
            return;
        };
        if missing.is_empty() {
            return;
        }
        let id = self.lowered.id;
        // The derived model this thread kept when it made the model, or the
        // text derived again, to the same formulations (derivation is
        // deterministic).
        let d = KEPT
            .with(|k| {
                let mut k = k.borrow_mut();
                match k.take() {
                    Some((kept, d)) if kept == id => Some(d),
                    other => {
                        *k = other;
                        None
                    }
                }
            })
            .unwrap_or_else(|| Derived::from_str(src).expect("the model's text derived before"));
        for (k, c) in missing.iter().zip(compile_selected(&d, &missing)) {
            // Another thread may have lowered it meanwhile: the same tapes.
            let _ = slots[*k].set(Arc::new(c));
        }
        if slots.iter().any(|s| s.get().is_none()) {
            KEPT.with(|k| *k.borrow_mut() = Some((id, d)));
        }
    }

    /// The interpreted system for `name` (concrete type).
    pub fn system(&self, name: &str) -> Result<InterpretedSystem, FormulationError> {
        let k = self
            .info
            .formulations
            .iter()
            .position(|f| f == name)
            .ok_or_else(|| {
                if crate::system::FORMULATION_NAMES.contains(&name) {
                    FormulationError::NotProvided {
                        model: self.info.name.clone(),
                        name: name.to_string(),
                        available: self.info.formulations.join(", "),
                    }
                } else {
                    FormulationError::Unknown {
                        name: name.to_string(),
                    }
                }
            })?;
        let slot = &self.lowered.slots[k];
        if slot.get().is_none() {
            self.lower(&[k]);
        }
        let c = slot
            .get()
            .expect("a formulation is lowered before its system is made");
        Ok(InterpretedSystem::new(c.clone(), self.params.clone()))
    }
}

impl Model for InterpretedModel {
    fn model_info(&self) -> &ModelInfo {
        &self.info
    }
    fn parameter(&self, name: &str) -> Option<f64> {
        self.info
            .parameters
            .iter()
            .position(|p| p.name == name)
            .map(|k| self.params[k])
    }
    fn set_parameter(&mut self, name: &str, value: f64) -> Result<(), ParameterError> {
        let k = self
            .info
            .parameters
            .iter()
            .position(|p| p.name == name)
            .ok_or_else(|| ParameterError::Unknown {
                model: self.info.name.clone(),
                name: name.to_string(),
                known: self
                    .info
                    .parameters
                    .iter()
                    .map(|p| p.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            })?;
        check_parameter(name, value)?;
        if let Some(expr) = &self.info.parameters[k].derived {
            return Err(ParameterError::Derived {
                model: self.info.name.clone(),
                name: name.to_string(),
                expr: expr.clone(),
            });
        }
        // Recompute the derived parameters from the new base values; keep
        // the old ones if any would not be finite.
        let mut base = self.params[..self.n_base].to_vec();
        base[k] = value;
        let inputs = Inputs {
            t: 0.0,
            y: &[],
            yp: &[],
            p: &base,
            z: &[],
        };
        let mut values = Vec::with_capacity(self.derived.outputs.len());
        self.derived
            .eval_outputs(&inputs, &mut Vec::new(), |_, v| values.push(v));
        let mut derived = Vec::with_capacity(values.len());
        for (j, v) in values.into_iter().enumerate() {
            if !v.is_finite() {
                return Err(ParameterError::DerivedNotFinite {
                    name: name.to_string(),
                    value,
                    derived: self.info.parameters[self.n_base + j].name.clone(),
                    result: v,
                });
            }
            derived.push(v);
        }
        base.extend(derived);
        self.params = base;
        Ok(())
    }
    fn prepare(&self, names: &[&str]) {
        let which: Vec<usize> = names
            .iter()
            .filter_map(|n| self.info.formulations.iter().position(|f| f == n))
            .collect();
        self.lower(&which);
    }
    fn formulation(&self, name: &str) -> Result<BoxedSystem, FormulationError> {
        let sys = self.system(name)?;
        if name == crate::dummy::NAME {
            return crate::dummy::boxed(sys, &self.info);
        }
        Ok(Box::new(sys))
    }
}

/// One formulation, interpreted.
#[derive(Debug)]
pub struct InterpretedSystem {
    c: Arc<Compiled>,
    params: Vec<f64>,
    scratch: RefCell<Vec<f64>>,
    /// The nodes' derivatives of [`DaeSystem::rhs_tangents`].
    dots: RefCell<Vec<f64>>,
    /// The patterns of the sparse tapes, made when first asked for.
    structure: OnceCell<Structure>,
}

/// The patterns of a formulation's sparse tapes and where each tape output
/// goes in its pattern's order.
#[derive(Debug)]
struct Structure {
    sparsity: Sparsity,
    leading: Vec<usize>,
    rhs_jacobian: Vec<usize>,
    leading_jacobian: Vec<usize>,
}

/// The pattern of `sp` (`m × n`) and the position of each output in it.
fn pattern_of(sp: &Sparse, m: usize, n: usize) -> (Pattern, Vec<usize>) {
    let cells = || sp.entries.iter().map(|&(i, j)| (i as usize, j as usize));
    let p = Pattern::from_entries(m, n, cells());
    let at = cells()
        .map(|(i, j)| p.position(i, j).expect("every entry is in its pattern"))
        .collect();
    (p, at)
}

impl InterpretedSystem {
    /// A system for compiled formulation `c` with parameter values `params`.
    pub fn new(c: Arc<Compiled>, params: Vec<f64>) -> Self {
        let size = [
            &c.residual,
            &c.rhs,
            &c.leading.tape,
            &c.rhs_jacobian.tape,
            &c.leading_jacobian.tape,
            &c.constraints,
            &c.constraints_jacobian.tape,
            &c.invariants,
            &c.events,
        ]
        .iter()
        .map(|t| t.nodes.len())
        .chain(c.accel.iter().flat_map(|a| {
            [
                &a.leading.tape,
                &a.rhs,
                &a.rhs_jacobian.tape,
                &a.leading_jacobian.tape,
                &a.chain_der.tape,
            ]
            .map(|t| t.nodes.len())
        }))
        .max()
        .unwrap_or(0);
        InterpretedSystem {
            c,
            params,
            scratch: RefCell::new(vec![0.0; size]),
            dots: RefCell::new(Vec::new()),
            structure: OnceCell::new(),
        }
    }

    fn structure(&self) -> &Structure {
        self.structure.get_or_init(|| {
            let (m, n) = (self.c.info.equations(), self.c.info.unknowns());
            let (leading, l) = pattern_of(&self.c.leading, m, n);
            let (rhs_jacobian, r) = pattern_of(&self.c.rhs_jacobian, m, n);
            let (leading_jacobian, lj) = pattern_of(&self.c.leading_jacobian, m, n);
            Structure {
                sparsity: Sparsity {
                    leading,
                    rhs_jacobian,
                    leading_jacobian,
                },
                leading: l,
                rhs_jacobian: r,
                leading_jacobian: lj,
            }
        })
    }

    /// `∂f/∂y` at `L` points in one pass of its tape, its value `v` at
    /// point `l` into `out[l][to[v]]` ([`DaeSystem::rhs_jacobian_scatter`]).
    fn scatter_jacobian<const L: usize>(
        &self,
        t: [f64; L],
        y: [&[f64]; L],
        to: &[usize],
        mut out: [&mut [f64]; L],
    ) {
        let at = &self.structure().rhs_jacobian;
        let inputs: [Inputs<'_>; L] = std::array::from_fn(|l| self.inputs(t[l], y[l], &[], &[]));
        let mut s = self.scratch.borrow_mut();
        self.c
            .rhs_jacobian
            .tape
            .eval_outputs_lanes(&inputs, &mut s, |l, k, v| {
                let at = to[at[k]];
                if at != crate::system::SKIP {
                    out[l][at] = v;
                }
            });
    }

    /// The outputs of `sp` into `values` at positions `at`.
    fn values(&self, sp: &Sparse, at: &[usize], inputs: Inputs<'_>, values: &mut [f64]) {
        let mut s = self.scratch.borrow_mut();
        sp.tape
            .eval_outputs(&inputs, &mut s, |k, v| values[at[k]] = v);
    }

    /// The tapes this system evaluates.
    ///
    /// ```
    /// use dae_core::interp::InterpretedModel;
    ///
    /// let m = InterpretedModel::from_str(
    ///     "pub M { differential { x } algebraic { z } equations { der(x) = -z; 0 = z - x; } }",
    /// )
    /// .unwrap();
    /// let name = m.system("rcd0").map(|s| s.compiled().info.name.clone());
    /// assert_eq!(name.as_deref(), Ok("rcd0"));
    /// ```
    pub fn compiled(&self) -> &Compiled {
        &self.c
    }

    fn dense(&self, tape: &Tape, inputs: Inputs<'_>, out: &mut [f64]) {
        let mut s = self.scratch.borrow_mut();
        tape.eval_outputs(&inputs, &mut s, |k, v| out[k] = v);
    }

    fn sparse(&self, sp: &Sparse, inputs: Inputs<'_>, out: &mut DMatrix<f64>) {
        out.fill(0.0);
        let mut s = self.scratch.borrow_mut();
        sp.tape.eval_outputs(&inputs, &mut s, |k, v| {
            let (i, j) = sp.entries[k];
            out[(i as usize, j as usize)] = v;
        });
    }

    fn inputs<'a>(&'a self, t: f64, y: &'a [f64], yp: &'a [f64], z: &'a [f64]) -> Inputs<'a> {
        Inputs {
            t,
            y,
            yp,
            p: &self.params,
            z,
        }
    }
}

impl DaeSystem for InterpretedSystem {
    fn info(&self) -> &FormulationInfo {
        &self.c.info
    }
    fn parameter_values(&self) -> Vec<f64> {
        self.params.clone()
    }
    fn rhs(&self, t: f64, y: &[f64], f: &mut [f64]) {
        self.dense(&self.c.rhs, self.inputs(t, y, &[], &[]), f)
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) {
        self.dense(&self.c.residual, self.inputs(t, y, yp, &[]), r)
    }
    fn leading(&self, t: f64, y: &[f64], e: &mut DMatrix<f64>) {
        self.sparse(&self.c.leading, self.inputs(t, y, &[], &[]), e)
    }
    fn rhs_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        self.sparse(&self.c.rhs_jacobian, self.inputs(t, y, &[], &[]), j)
    }
    fn rhs_tangents(
        &self,
        t: f64,
        y: &[f64],
        dy: &[f64],
        count: usize,
        f: &mut [f64],
        df: &mut [f64],
    ) {
        let tape = &self.c.rhs;
        let (mut s, mut dots) = (self.scratch.borrow_mut(), self.dots.borrow_mut());
        tape.eval_tangents(&self.inputs(t, y, &[], &[]), dy, count, &mut s, &mut dots);
        let m = f.len();
        for (r, (o, &node)) in f.iter_mut().zip(&tape.outputs).enumerate() {
            let node = node as usize;
            *o = s[node];
            for (k, &d) in dots[node * count..(node + 1) * count].iter().enumerate() {
                df[k * m + r] = d;
            }
        }
    }
    fn leading_jacobian(&self, t: f64, y: &[f64], z: &[f64], j: &mut DMatrix<f64>) {
        self.sparse(&self.c.leading_jacobian, self.inputs(t, y, &[], z), j)
    }
    fn constraints(&self, t: f64, y: &[f64], g: &mut [f64]) {
        match self.c.accel {
            Some(_) => crate::accel::constraints(self, t, y, g),
            None => self.dense(&self.c.constraints, self.inputs(t, y, &[], &[]), g),
        }
    }
    fn constraints_jacobian(&self, t: f64, y: &[f64], j: &mut DMatrix<f64>) {
        match self.c.accel {
            Some(_) => crate::accel::constraints_jacobian(self, t, y, j),
            None => self.sparse(&self.c.constraints_jacobian, self.inputs(t, y, &[], &[]), j),
        }
    }
    fn invariants(&self, t: f64, y: &[f64], out: &mut [f64]) {
        self.dense(&self.c.invariants, self.inputs(t, y, &[], &[]), out)
    }
    fn event_names(&self) -> &[String] {
        &self.c.event_names
    }
    fn events(&self, t: f64, y: &[f64], out: &mut [f64]) {
        self.dense(&self.c.events, self.inputs(t, y, &[], &[]), out)
    }
    fn sparsity(&self) -> Sparsity {
        self.structure().sparsity.clone()
    }
    fn rhs_jacobian_values(&self, t: f64, y: &[f64], pattern: &Pattern, values: &mut [f64]) {
        let s = self.structure();
        if *pattern != s.sparsity.rhs_jacobian {
            return gather_dense(pattern, values, |j| self.rhs_jacobian(t, y, j));
        }
        let inputs = self.inputs(t, y, &[], &[]);
        self.values(&self.c.rhs_jacobian, &s.rhs_jacobian, inputs, values)
    }
    fn rhs_jacobian_scatter(&self, t: f64, y: &[f64], to: &[usize], out: &mut [f64]) {
        self.scatter_jacobian([t], [y], to, [out])
    }
    fn rhs_jacobian_scatter3(
        &self,
        t: [f64; 3],
        y: [&[f64]; 3],
        to: &[usize],
        out: [&mut [f64]; 3],
    ) {
        self.scatter_jacobian(t, y, to, out)
    }
    fn leading_values(&self, t: f64, y: &[f64], pattern: &Pattern, values: &mut [f64]) {
        let s = self.structure();
        if *pattern != s.sparsity.leading {
            return gather_dense(pattern, values, |e| self.leading(t, y, e));
        }
        let inputs = self.inputs(t, y, &[], &[]);
        self.values(&self.c.leading, &s.leading, inputs, values)
    }
    fn leading_jacobian_values(
        &self,
        t: f64,
        y: &[f64],
        z: &[f64],
        pattern: &Pattern,
        values: &mut [f64],
    ) {
        let s = self.structure();
        if *pattern != s.sparsity.leading_jacobian {
            return gather_dense(pattern, values, |j| self.leading_jacobian(t, y, z, j));
        }
        let inputs = self.inputs(t, y, &[], z);
        self.values(
            &self.c.leading_jacobian,
            &s.leading_jacobian,
            inputs,
            values,
        )
    }
}

impl InterpretedSystem {
    fn accel_tapes(&self) -> &crate::compile::AccelTapes {
        self.c
            .accel
            .as_ref()
            .expect("the acceleration tapes exist for a model with a mass matrix")
    }
}

impl crate::accel::AccelParts for InterpretedSystem {
    fn accel_dim(&self) -> usize {
        self.c.accel.as_ref().map_or(0, |a| a.n_diff)
    }
    fn accel_leading(&self, t: f64, y: &[f64], out: &mut DMatrix<f64>) {
        self.sparse(
            &self.accel_tapes().leading,
            self.inputs(t, y, &[], &[]),
            out,
        )
    }
    fn accel_rhs(&self, t: f64, y: &[f64], out: &mut [f64]) {
        self.dense(&self.accel_tapes().rhs, self.inputs(t, y, &[], &[]), out)
    }
    fn accel_rhs_jacobian(&self, t: f64, y: &[f64], out: &mut DMatrix<f64>) {
        self.sparse(
            &self.accel_tapes().rhs_jacobian,
            self.inputs(t, y, &[], &[]),
            out,
        )
    }
    fn accel_leading_jacobian(&self, t: f64, y: &[f64], z: &[f64], out: &mut DMatrix<f64>) {
        self.sparse(
            &self.accel_tapes().leading_jacobian,
            self.inputs(t, y, &[], z),
            out,
        )
    }
    fn chain_at(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        self.dense(&self.c.constraints, self.inputs(t, y, yp, &[]), out)
    }
    fn chain_jacobian_at(&self, t: f64, y: &[f64], yp: &[f64], out: &mut DMatrix<f64>) {
        self.sparse(
            &self.c.constraints_jacobian,
            self.inputs(t, y, yp, &[]),
            out,
        )
    }
    fn chain_der(&self, t: f64, y: &[f64], out: &mut DMatrix<f64>) {
        self.sparse(
            &self.accel_tapes().chain_der,
            self.inputs(t, y, &[], &[]),
            out,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::work;

    const SRC: &str = "pub M { differential { x, v } algebraic { la } \
                       equations { der(x) = v; der(v) = -la*x; 0 = x^2 - 1; } }";

    /// A lazy model lowered on the thread that made it lowers from the
    /// derivation kept then (the symbolic work of lowering alone, counted
    /// by `expr::work`); on another thread it derives the text again. Both
    /// give the eager model's tapes.
    #[test]
    fn a_lazy_model_derives_once_on_its_thread() {
        let d = Derived::from_str(SRC).expect("derives");
        let k = d
            .formulations
            .iter()
            .position(|f| f.name == "ggl1")
            .expect("ggl1 provided");
        let w = work();
        let eager = compile_selected(&d, &[k]).remove(0);
        let lowering = work() - w;
        let w = work();
        let _ = Derived::from_str(SRC).expect("derives");
        let deriving = work() - w;
        assert!(lowering > 0 && deriving > 0);

        let here = InterpretedModel::lazy(SRC).expect("derives");
        let w = work();
        let sys = here.system("ggl1").expect("provided");
        assert_eq!(work() - w, lowering, "lowered without deriving again");
        assert_eq!(*sys.compiled(), eager);
        // The kept derivation serves the next formulation too, and goes
        // with the model.
        let kept = || KEPT.with(|k| k.borrow().as_ref().map(|(id, _)| *id));
        assert_eq!(kept(), Some(here.lowered.id));
        let other = &d.formulations[(k + 1) % d.formulations.len()].name;
        let _ = here.system(other).expect("provided");
        assert_eq!(kept(), Some(here.lowered.id));
        drop(here);
        assert!(KEPT.with(|k| k.borrow().is_none()));

        let there = InterpretedModel::lazy(SRC).expect("derives");
        let (spent, same) = std::thread::scope(|s| {
            s.spawn(|| {
                let w = work();
                let sys = there.system("ggl1").expect("provided");
                (work() - w, *sys.compiled() == eager)
            })
            .join()
            .expect("the other thread lowers")
        });
        assert!(same);
        assert_eq!(spent, deriving + lowering, "derived again elsewhere");
    }
}
