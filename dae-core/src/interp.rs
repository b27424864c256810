//! The interpreted implementation of the runtime trait, for models read at
//! run time: the same tapes the macro turns into straight-line code,
//! evaluated node by node.

use crate::compile::{compile_all, Compiled, Sparse};
use crate::derive::Derived;
use crate::expr::Expr;
use crate::system::{
    check_parameter, BoxedSystem, DaeSystem, FormulationError, FormulationInfo, Model, ModelInfo,
    ParameterError,
};
use crate::tape::{Inputs, Tape, TapeBuilder};
use nalgebra::DMatrix;
use std::cell::RefCell;
use std::sync::Arc;

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
    formulations: Vec<Arc<Compiled>>,
}

impl InterpretedModel {
    /// Compile every provided formulation of a derived model.
    pub fn new(d: &Derived) -> Self {
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
            formulations: compile_all(d).into_iter().map(Arc::new).collect(),
        }
    }

    /// Parse, check, derive and compile model text.
    #[allow(clippy::should_implement_trait)] // returns `syn::Error` with spans, unlike `str::parse`
    pub fn from_str(src: &str) -> Result<Self, syn::Error> {
        Ok(Self::new(&Derived::from_str(src)?))
    }

    /// The interpreted system for `name` (concrete type).
    pub fn system(&self, name: &str) -> Result<InterpretedSystem, FormulationError> {
        let c = self
            .formulations
            .iter()
            .find(|c| c.info.name == name)
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
        let mut scratch = vec![0.0; self.derived.nodes.len()];
        let inputs = Inputs {
            t: 0.0,
            y: &[],
            yp: &[],
            p: &base,
            z: &[],
        };
        self.derived.eval(&inputs, &mut scratch);
        let mut derived = Vec::with_capacity(self.derived.outputs.len());
        for j in 0..self.derived.outputs.len() {
            let v = self.derived.output(&scratch, j);
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
        }
    }

    fn dense(&self, tape: &Tape, inputs: Inputs<'_>, out: &mut [f64]) {
        let mut s = self.scratch.borrow_mut();
        tape.eval(&inputs, &mut s);
        for (k, o) in out.iter_mut().enumerate() {
            *o = tape.output(&s, k);
        }
    }

    fn sparse(&self, sp: &Sparse, inputs: Inputs<'_>, out: &mut DMatrix<f64>) {
        out.fill(0.0);
        let mut s = self.scratch.borrow_mut();
        sp.tape.eval(&inputs, &mut s);
        for (k, &(i, j)) in sp.entries.iter().enumerate() {
            out[(i as usize, j as usize)] = sp.tape.output(&s, k);
        }
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
