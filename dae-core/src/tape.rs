//! Flat, topologically ordered arenas of floating-point operations.
//!
//! A [`Tape`] is what both back ends consume: the macro emits one `let` per
//! node (straight-line code), the interpreter evaluates the nodes in order
//! into a scratch buffer. Identical subexpressions are stored once (hash
//! consing), so common subexpressions of a group of outputs — the rows of a
//! Jacobian, say — are computed once. Node order is the depth-first order of
//! the canonical expressions, hence deterministic.

use crate::expr::{q_to_f64, Expr, Func, Sym, Q};
use num_traits::{One, Signed, ToPrimitive};
use std::collections::HashMap;

/// Index of a node in its tape.
pub type NodeId = u32;

/// One operation.
#[derive(Clone, Debug, PartialEq)]
pub enum Op {
    /// A constant.
    Const(f64),
    /// An input: `y_i`, `y'_i`, `p_k`, `t` or `z_i`.
    Input(Sym),
    /// `constant + Σ c_i · x_i`.
    Add(f64, Vec<(f64, NodeId)>),
    /// `Π x_i`.
    Mul(Vec<NodeId>),
    /// `a / b`.
    Div(NodeId, NodeId),
    /// `x^k`, integer `k`.
    Powi(NodeId, i32),
    /// `sqrt(x)`.
    Sqrt(NodeId),
    /// `x^c`, real constant `c`.
    Powf(NodeId, f64),
    /// `a^b`.
    Pow(NodeId, NodeId),
    /// Elementary function.
    Func(Func, NodeId),
}

/// Hashable key of an op (floats by bits).
#[derive(Clone, PartialEq, Eq, Hash)]
enum Key {
    Const(u64),
    Input(Sym),
    Add(u64, Vec<(u64, NodeId)>),
    Mul(Vec<NodeId>),
    Div(NodeId, NodeId),
    Powi(NodeId, i32),
    Sqrt(NodeId),
    Powf(NodeId, u64),
    Pow(NodeId, NodeId),
    Func(Func, NodeId),
}

fn key(op: &Op) -> Key {
    match op {
        Op::Const(c) => Key::Const(c.to_bits()),
        Op::Input(s) => Key::Input(*s),
        Op::Add(c, t) => Key::Add(
            c.to_bits(),
            t.iter().map(|(a, b)| (a.to_bits(), *b)).collect(),
        ),
        Op::Mul(v) => Key::Mul(v.clone()),
        Op::Div(a, b) => Key::Div(*a, *b),
        Op::Powi(a, k) => Key::Powi(*a, *k),
        Op::Sqrt(a) => Key::Sqrt(*a),
        Op::Powf(a, c) => Key::Powf(*a, c.to_bits()),
        Op::Pow(a, b) => Key::Pow(*a, *b),
        Op::Func(f, a) => Key::Func(*f, *a),
    }
}

/// A flat arena with named outputs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tape {
    /// Nodes, children before parents.
    pub nodes: Vec<Op>,
    /// Output node of each output slot.
    pub outputs: Vec<NodeId>,
}

/// Builds a tape from expressions, sharing identical subexpressions.
#[derive(Default)]
pub struct TapeBuilder {
    tape: Tape,
    by_key: HashMap<Key, NodeId>,
    by_expr: HashMap<Expr, NodeId>,
}

impl TapeBuilder {
    /// Empty builder.
    pub fn new() -> Self {
        Self::default()
    }

    fn push(&mut self, op: Op) -> NodeId {
        let k = key(&op);
        if let Some(&id) = self.by_key.get(&k) {
            return id;
        }
        let id = self.tape.nodes.len() as NodeId;
        self.tape.nodes.push(op);
        self.by_key.insert(k, id);
        id
    }

    /// Lower `e` and return its node.
    ///
    /// A walk with an explicit stack, so an expression of any height is
    /// lowered in constant native stack; nodes come out in the order a
    /// recursive depth-first walk would give them (each product factor's
    /// power right after its base).
    pub fn node(&mut self, e: &Expr) -> NodeId {
        enum Step<'a> {
            /// Lower this expression (or find it lowered).
            Visit(&'a Expr),
            /// Its children are on the value stack: build the node.
            Build(&'a Expr),
            /// The base of a product factor is on the value stack: raise it.
            Factor(&'a Q),
        }
        let mut steps = vec![Step::Visit(e)];
        let mut values: Vec<NodeId> = Vec::new();
        while let Some(step) = steps.pop() {
            match step {
                Step::Visit(e) => {
                    if let Some(&id) = self.by_expr.get(e) {
                        values.push(id);
                        continue;
                    }
                    match e {
                        Expr::Num(v) => {
                            let id = self.push(Op::Const(q_to_f64(v)));
                            values.push(id);
                        }
                        Expr::Sym(s) => {
                            let id = self.push(Op::Input(*s));
                            values.push(id);
                        }
                        Expr::Sum(s) => {
                            steps.push(Step::Build(e));
                            steps.extend(s.terms.iter().rev().map(|(t, _)| Step::Visit(t)));
                        }
                        Expr::Prod(p) => {
                            steps.push(Step::Build(e));
                            for (b, x) in p.factors.iter().rev() {
                                steps.push(Step::Factor(x));
                                steps.push(Step::Visit(b));
                            }
                        }
                        Expr::Pow(p) => {
                            steps.push(Step::Build(e));
                            steps.push(Step::Visit(&p.exponent));
                            steps.push(Step::Visit(&p.base));
                        }
                        Expr::Func(c) => {
                            steps.push(Step::Build(e));
                            steps.push(Step::Visit(&c.arg));
                        }
                    }
                }
                Step::Factor(x) => {
                    let nb = values.pop().unwrap_or_default();
                    let ax = x.abs();
                    let f = if ax.is_one() {
                        nb
                    } else if ax.denom().is_one() {
                        match ax.numer().to_i32() {
                            Some(k) => self.push(Op::Powi(nb, k)),
                            None => self.push(Op::Powf(nb, q_to_f64(&ax))),
                        }
                    } else if ax == crate::expr::qr(1, 2) {
                        self.push(Op::Sqrt(nb))
                    } else {
                        self.push(Op::Powf(nb, q_to_f64(&ax)))
                    };
                    values.push(f);
                }
                Step::Build(e) => {
                    let id = self.build(e, &mut values);
                    self.by_expr.insert(e.clone(), id);
                    values.push(id);
                }
            }
        }
        values.pop().unwrap_or_default()
    }

    /// The node of compound `e` whose children's nodes (product factors
    /// already raised to their powers) end `values`.
    fn build(&mut self, e: &Expr, values: &mut Vec<NodeId>) -> NodeId {
        let mut children = |n: usize| values.split_off(values.len().saturating_sub(n));
        match e {
            Expr::Num(_) | Expr::Sym(_) => values.pop().unwrap_or_default(),
            Expr::Sum(s) => {
                let ids = children(s.terms.len());
                let terms: Vec<(f64, NodeId)> = s
                    .terms
                    .iter()
                    .zip(ids)
                    .map(|((_, c), id)| (q_to_f64(c), id))
                    .collect();
                self.push(Op::Add(q_to_f64(&s.constant), terms))
            }
            Expr::Prod(p) => {
                let ids = children(p.factors.len());
                let mut num = Vec::new();
                let mut den = Vec::new();
                for ((_, x), f) in p.factors.iter().zip(ids) {
                    if x.is_negative() {
                        den.push(f);
                    } else {
                        num.push(f);
                    }
                }
                let n = match num.len() {
                    0 => self.push(Op::Const(1.0)),
                    1 => num[0],
                    _ => self.push(Op::Mul(num)),
                };
                match den.len() {
                    0 => n,
                    1 => self.push(Op::Div(n, den[0])),
                    _ => {
                        let d = self.push(Op::Mul(den));
                        self.push(Op::Div(n, d))
                    }
                }
            }
            Expr::Pow(_) => {
                let ids = children(2);
                self.push(Op::Pow(ids[0], ids[1]))
            }
            Expr::Func(c) => {
                let ids = children(1);
                self.push(Op::Func(c.func, ids[0]))
            }
        }
    }

    /// Add an output.
    pub fn output(&mut self, e: &Expr) {
        let id = self.node(e);
        self.tape.outputs.push(id);
    }

    /// The finished tape.
    pub fn finish(self) -> Tape {
        self.tape
    }
}

/// Values of the inputs of a tape evaluation.
#[derive(Clone, Copy)]
pub struct Inputs<'a> {
    /// Time.
    pub t: f64,
    /// Unknowns.
    pub y: &'a [f64],
    /// Derivatives (may be empty when unused).
    pub yp: &'a [f64],
    /// Parameters.
    pub p: &'a [f64],
    /// Direction (may be empty when unused).
    pub z: &'a [f64],
}

impl Inputs<'_> {
    fn get(&self, s: Sym) -> f64 {
        match s {
            Sym::Var(i) => self.y[i as usize],
            Sym::Der(i) => self.yp[i as usize],
            Sym::Param(k) => self.p[k as usize],
            Sym::Time => self.t,
            Sym::Dir(i) => self.z[i as usize],
        }
    }
}

impl Tape {
    /// Evaluate every node into `scratch` (resized only if too short).
    pub fn eval(&self, inputs: &Inputs<'_>, scratch: &mut Vec<f64>) {
        if scratch.len() < self.nodes.len() {
            scratch.resize(self.nodes.len(), 0.0);
        }
        for (i, op) in self.nodes.iter().enumerate() {
            let v = match op {
                Op::Const(c) => *c,
                Op::Input(s) => inputs.get(*s),
                Op::Add(c, terms) => terms
                    .iter()
                    .fold(*c, |acc, (k, x)| acc + k * scratch[*x as usize]),
                Op::Mul(xs) => xs.iter().fold(1.0, |acc, x| acc * scratch[*x as usize]),
                Op::Div(a, b) => scratch[*a as usize] / scratch[*b as usize],
                Op::Powi(a, k) => scratch[*a as usize].powi(*k),
                Op::Sqrt(a) => scratch[*a as usize].sqrt(),
                Op::Powf(a, c) => scratch[*a as usize].powf(*c),
                Op::Pow(a, b) => scratch[*a as usize].powf(scratch[*b as usize]),
                Op::Func(f, a) => f.apply(scratch[*a as usize]),
            };
            scratch[i] = v;
        }
    }

    /// Value of output `k` after [`Tape::eval`].
    pub fn output(&self, scratch: &[f64], k: usize) -> f64 {
        scratch[self.outputs[k] as usize]
    }
}
