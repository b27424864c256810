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
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::OnceLock;

mod plan;

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

/// The hasher of the symbolic core's look-up tables (the tape builder's,
/// the memo of gradients): one multiply and rotate per word, as rustc's
/// `FxHasher`. Their keys are node ids, float bits and the structural
/// hashes expressions cache (already mixed), so the default SipHash's
/// defence against chosen keys buys nothing but time. Deterministic; what
/// a table holds does not depend on its hasher, only how fast it is
/// found.
#[derive(Clone, Copy, Default)]
pub(crate) struct FastHasher(u64);

impl Hasher for FastHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }
    fn write_u8(&mut self, n: u8) {
        self.write_u64(u64::from(n));
    }
    fn write_u32(&mut self, n: u32) {
        self.write_u64(u64::from(n));
    }
    fn write_usize(&mut self, n: usize) {
        self.write_u64(n as u64);
    }
    fn write_isize(&mut self, n: isize) {
        self.write_u64(n as u64);
    }
    fn write_i32(&mut self, n: i32) {
        self.write_u64(n as u64);
    }
    fn write_u64(&mut self, n: u64) {
        self.0 = (self.0.rotate_left(5) ^ n).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// A hash map with [`FastHasher`].
pub(crate) type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<FastHasher>>;

/// A flat arena with named outputs.
///
/// Two tapes are equal when their nodes and outputs are; the evaluation
/// order [`Tape::eval_outputs`] makes at its first call is kept with the
/// tape (and with its clones) but is not part of it.
#[derive(Clone, Default)]
pub struct Tape {
    /// Nodes, children before parents.
    pub nodes: Vec<Op>,
    /// Output node of each output slot.
    pub outputs: Vec<NodeId>,
    /// The interpreter's evaluation order, made when first needed.
    plan: OnceLock<plan::Plan>,
}

impl PartialEq for Tape {
    fn eq(&self, other: &Self) -> bool {
        self.nodes == other.nodes && self.outputs == other.outputs
    }
}

impl std::fmt::Debug for Tape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Tape")
            .field("nodes", &self.nodes)
            .field("outputs", &self.outputs)
            .finish()
    }
}

/// Builds a tape from expressions, sharing identical subexpressions.
#[derive(Default)]
pub struct TapeBuilder {
    tape: Tape,
    by_key: FastMap<Key, NodeId>,
    by_expr: FastMap<Expr, NodeId>,
    /// The node of every compound expression met, by its address: an
    /// expression met again as the same shared node (a Jacobian's entries
    /// share most of their subexpressions) is found without comparing its
    /// structure with an equal one built apart, a walk of both. `kept`
    /// holds the expressions, so an address is not reused meanwhile.
    by_node: FastMap<usize, NodeId>,
    kept: Vec<Expr>,
}

/// The address of a compound expression's node; `None` for a number or a
/// symbol (cheap to look up by value).
fn address(e: &Expr) -> Option<usize> {
    match e {
        Expr::Num(_) | Expr::Sym(_) => None,
        Expr::Sum(x) => Some(std::rc::Rc::as_ptr(x) as *const () as usize),
        Expr::Prod(x) => Some(std::rc::Rc::as_ptr(x) as *const () as usize),
        Expr::Pow(x) => Some(std::rc::Rc::as_ptr(x) as *const () as usize),
        Expr::Func(x) => Some(std::rc::Rc::as_ptr(x) as *const () as usize),
    }
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
                    let at = address(e);
                    if let Some(&id) = at.and_then(|a| self.by_node.get(&a)) {
                        values.push(id);
                        continue;
                    }
                    if let Some(&id) = self.by_expr.get(e) {
                        if let Some(a) = at {
                            self.by_node.insert(a, id);
                            self.kept.push(e.clone());
                        }
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
                    if let Some(a) = address(e) {
                        self.by_node.insert(a, id);
                    }
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
    #[inline]
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

    /// Evaluate the tape and hand each output to `put` as `put(k, value)`,
    /// `k` ascending: the interpreter's fast path (BENCHMARKS.md §16e).
    ///
    /// The values are [`Tape::eval`]'s bit for bit, in another order: by
    /// levels (a node after all its operands), a level in runs of nodes of
    /// one kind, each run one loop over compact operand indices, and only
    /// the nodes some output reads. The order is made at the first call
    /// (one pass and one sort over the nodes) and kept with the tape; a
    /// tape whose nodes or outputs were added to since is evaluated by
    /// [`Tape::eval`]. `scratch` is working space, resized only if too
    /// short; what it holds afterwards is not indexed by node (use
    /// [`Tape::eval`] and [`Tape::output`] for that).
    ///
    /// ```
    /// use dae_core::expr::{add, mul, Expr};
    /// use dae_core::tape::{Inputs, TapeBuilder};
    ///
    /// // (x y, x + y) at (3, 2).
    /// let (x, y) = (Expr::var(0), Expr::var(1));
    /// let mut b = TapeBuilder::new();
    /// b.output(&mul(&x, &y));
    /// b.output(&add(&x, &y));
    /// let tape = b.finish();
    /// let inputs = Inputs { t: 0.0, y: &[3.0, 2.0], yp: &[], p: &[], z: &[] };
    /// let (mut scratch, mut out) = (Vec::new(), [0.0; 2]);
    /// tape.eval_outputs(&inputs, &mut scratch, |k, v| out[k] = v);
    /// assert_eq!(out, [6.0, 5.0]);
    /// ```
    pub fn eval_outputs(
        &self,
        inputs: &Inputs<'_>,
        scratch: &mut Vec<f64>,
        mut put: impl FnMut(usize, f64),
    ) {
        self.eval_outputs_lanes(std::array::from_ref(inputs), scratch, |_, k, v| put(k, v))
    }

    /// [`Tape::eval_outputs`] at `L` points at once: output `k` at point
    /// `l` is `put(l, k, value)`, the same value bit for bit, with each
    /// operation dispatched once for the `L` points (`Plan::eval_lanes`).
    ///
    /// ```
    /// use dae_core::expr::{add, mul, Expr};
    /// use dae_core::tape::{Inputs, TapeBuilder};
    ///
    /// // (x y, x + y) at (3, 2) and at (1, 5).
    /// let (x, y) = (Expr::var(0), Expr::var(1));
    /// let mut b = TapeBuilder::new();
    /// b.output(&mul(&x, &y));
    /// b.output(&add(&x, &y));
    /// let tape = b.finish();
    /// let points = [[3.0, 2.0], [1.0, 5.0]];
    /// let inputs = points.each_ref().map(|y| Inputs { t: 0.0, y, yp: &[], p: &[], z: &[] });
    /// let (mut scratch, mut out) = (Vec::new(), [[0.0; 2]; 2]);
    /// tape.eval_outputs_lanes(&inputs, &mut scratch, |l, k, v| out[l][k] = v);
    /// assert_eq!(out, [[6.0, 5.0], [5.0, 6.0]]);
    /// ```
    pub fn eval_outputs_lanes<const L: usize>(
        &self,
        inputs: &[Inputs<'_>; L],
        scratch: &mut Vec<f64>,
        mut put: impl FnMut(usize, usize, f64),
    ) {
        let plan = self.plan.get_or_init(|| plan::Plan::new(self));
        if !plan.fits(self) {
            for (l, inputs) in inputs.iter().enumerate() {
                self.eval(inputs, scratch);
                for (k, &o) in self.outputs.iter().enumerate() {
                    put(l, k, scratch[o as usize]);
                }
            }
            return;
        }
        if scratch.len() < L * plan.slots() {
            scratch.resize(L * plan.slots(), 0.0);
        }
        plan.eval_lanes(inputs, scratch);
        for (k, &o) in plan.outputs().iter().enumerate() {
            for (l, &v) in scratch[o as usize * L..][..L].iter().enumerate() {
                put(l, k, v);
            }
        }
    }

    /// Evaluate every node into `scratch`, as [`Tape::eval`], and its
    /// derivatives along `count` directions in the unknowns into `dots`
    /// (forward mode, one pass for all directions): `dy[k N..(k + 1) N]`
    /// is direction `k` of the `N = inputs.y.len()` unknowns, and node
    /// `i`'s derivative along it lands in `dots[i · count + k]`. Every
    /// other input (time, derivatives, parameters, directions `z`) is held
    /// fixed. Buffers are resized only if too short.
    ///
    /// Each node costs its value and `count` applications of its own
    /// derivative rule (a product's by the running product, a quotient's
    /// from its value), so the directional derivatives of all outputs
    /// cost a small multiple of one evaluation however many outputs there
    /// are — where a Jacobian costs one derivative expression per
    /// non-zero.
    ///
    /// ```
    /// use dae_core::expr::{mul_all, Expr};
    /// use dae_core::tape::{Inputs, TapeBuilder};
    ///
    /// // f = x² y along (1, 0) and (0, 1): (2xy, x²).
    /// let (x, y) = (Expr::var(0), Expr::var(1));
    /// let mut b = TapeBuilder::new();
    /// b.output(&mul_all([x.clone(), x, y]));
    /// let tape = b.finish();
    /// let inputs = Inputs { t: 0.0, y: &[3.0, 2.0], yp: &[], p: &[], z: &[] };
    /// let (mut values, mut dots) = (Vec::new(), Vec::new());
    /// tape.eval_tangents(&inputs, &[1.0, 0.0, 0.0, 1.0], 2, &mut values, &mut dots);
    /// assert_eq!(tape.output(&values, 0), 18.0);
    /// assert_eq!(tape.output_tangents(&dots, 0, 2), [12.0, 9.0]);
    /// ```
    pub fn eval_tangents(
        &self,
        inputs: &Inputs<'_>,
        dy: &[f64],
        count: usize,
        scratch: &mut Vec<f64>,
        dots: &mut Vec<f64>,
    ) {
        let nodes = self.nodes.len();
        if scratch.len() < nodes {
            scratch.resize(nodes, 0.0);
        }
        if dots.len() < nodes * count {
            dots.resize(nodes * count, 0.0);
        }
        // The direction counts of one and two parameters as constants.
        match count {
            1 => self.forward(inputs, dy, 1, scratch, dots),
            2 => self.forward(inputs, dy, 2, scratch, dots),
            _ => self.forward(inputs, dy, count, scratch, dots),
        }
    }

    /// [`Tape::eval_tangents`] for `c` directions (a constant where the
    /// caller makes it one). Children come before their parents: node
    /// `i`'s derivatives `d[i c..(i + 1) c]` are written after the ones it
    /// reads.
    #[inline(always)]
    fn forward(&self, inputs: &Inputs<'_>, dy: &[f64], c: usize, v: &mut [f64], d: &mut [f64]) {
        let ny = inputs.y.len();
        for (i, op) in self.nodes.iter().enumerate() {
            let o = i * c;
            let value = match op {
                Op::Const(x) => {
                    d[o..o + c].fill(0.0);
                    *x
                }
                Op::Input(s) => {
                    if let Sym::Var(j) = s {
                        for k in 0..c {
                            d[o + k] = dy[k * ny + *j as usize];
                        }
                    } else {
                        d[o..o + c].fill(0.0);
                    }
                    inputs.get(*s)
                }
                Op::Add(c0, terms) => {
                    d[o..o + c].fill(0.0);
                    let mut acc = *c0;
                    for &(w, x) in terms {
                        let x = x as usize;
                        acc += w * v[x];
                        for k in 0..c {
                            d[o + k] += w * d[x * c + k];
                        }
                    }
                    acc
                }
                Op::Mul(xs) => {
                    // (u x)' = u' x + u x', along the running product u.
                    d[o..o + c].fill(0.0);
                    let mut u = 1.0;
                    for &x in xs {
                        let x = x as usize;
                        let vx = v[x];
                        for k in 0..c {
                            d[o + k] = d[o + k] * vx + u * d[x * c + k];
                        }
                        u *= vx;
                    }
                    u
                }
                Op::Div(a, b) => {
                    let (a, b) = (*a as usize, *b as usize);
                    let q = v[a] / v[b];
                    for k in 0..c {
                        d[o + k] = (d[a * c + k] - q * d[b * c + k]) / v[b];
                    }
                    q
                }
                Op::Powi(a, e) => {
                    let a = *a as usize;
                    let lower = v[a].powi(*e - 1);
                    let slope = f64::from(*e) * lower;
                    for k in 0..c {
                        d[o + k] = slope * d[a * c + k];
                    }
                    lower * v[a]
                }
                Op::Sqrt(a) => {
                    let a = *a as usize;
                    let r = v[a].sqrt();
                    for k in 0..c {
                        d[o + k] = d[a * c + k] / (2.0 * r);
                    }
                    r
                }
                Op::Powf(a, e) => {
                    let a = *a as usize;
                    let slope = e * v[a].powf(e - 1.0);
                    for k in 0..c {
                        d[o + k] = slope * d[a * c + k];
                    }
                    v[a].powf(*e)
                }
                Op::Pow(a, b) => {
                    let (a, b) = (*a as usize, *b as usize);
                    let r = v[a].powf(v[b]);
                    for k in 0..c {
                        // Only the moving operands: a fixed base at 0 or
                        // below (ln undefined) with a moving exponent is
                        // the only NaN, as in the symbolic derivative.
                        let (da, db) = (d[a * c + k], d[b * c + k]);
                        let mut s = 0.0;
                        if da != 0.0 {
                            s += v[b] * v[a].powf(v[b] - 1.0) * da;
                        }
                        if db != 0.0 {
                            s += r * v[a].ln() * db;
                        }
                        d[o + k] = s;
                    }
                    r
                }
                Op::Func(f, a) => {
                    let a = *a as usize;
                    let r = f.apply(v[a]);
                    let slope = match f {
                        Func::Sin => v[a].cos(),
                        Func::Cos => -v[a].sin(),
                        Func::Tan => 1.0 + r * r,
                        Func::Exp => r,
                        Func::Ln => 1.0 / v[a],
                    };
                    for k in 0..c {
                        d[o + k] = slope * d[a * c + k];
                    }
                    r
                }
            };
            v[i] = value;
        }
    }

    /// The derivatives of output `k` along the `count` directions after
    /// [`Tape::eval_tangents`].
    pub fn output_tangents<'a>(&self, dots: &'a [f64], k: usize, count: usize) -> &'a [f64] {
        let at = self.outputs[k] as usize * count;
        &dots[at..at + count]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::{add, diff, func, mul, mul_all, pow, pow_rational, qr};

    /// A tape of `n` pseudo-random nodes of every kind over three
    /// unknowns, their derivatives, two parameters, time and a direction,
    /// with sums and products of 0 to 7 operands and integer powers from
    /// -3 to 3 (square roots, real powers and logarithms of positive
    /// values); every fifth node an output, some nodes read by none.
    fn random_tape(n: usize, seed: u64) -> Tape {
        let mut state = seed;
        let mut next = move |m: usize| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((state >> 33) as usize) % m
        };
        let mut nodes = vec![
            Op::Input(Sym::Var(0)),
            Op::Input(Sym::Var(1)),
            Op::Input(Sym::Var(2)),
            Op::Input(Sym::Der(1)),
            Op::Input(Sym::Param(0)),
            Op::Input(Sym::Param(1)),
            Op::Input(Sym::Time),
            Op::Input(Sym::Dir(2)),
            Op::Const(0.75),
        ];
        let funcs = [Func::Sin, Func::Cos, Func::Tan, Func::Exp, Func::Ln];
        while nodes.len() < n {
            let len = nodes.len();
            let x = next(len) as NodeId;
            // A positive operand for square roots, real powers and
            // logarithms (most values stay finite): 1/2 + x².
            let positive = |nodes: &mut Vec<Op>| {
                nodes.push(Op::Powi(x, 2));
                nodes.push(Op::Add(0.5, vec![(1.0, nodes.len() as NodeId - 1)]));
                nodes.len() as NodeId - 1
            };
            let op = match next(11) {
                0 | 1 => {
                    let k = next(8);
                    Op::Add(
                        next(3) as f64 - 1.0,
                        (0..k)
                            .map(|j| (0.5 * j as f64 - 1.0, next(len) as NodeId))
                            .collect(),
                    )
                }
                2 | 3 => Op::Mul((0..next(8)).map(|_| next(len) as NodeId).collect()),
                4 => Op::Div(x, next(len) as NodeId),
                5 => Op::Powi(x, next(7) as i32 - 3),
                6 => Op::Sqrt(positive(&mut nodes)),
                7 => Op::Powf(positive(&mut nodes), 0.5 + 0.25 * next(5) as f64),
                8 => Op::Pow(positive(&mut nodes), next(len) as NodeId),
                9 => match funcs[next(5)] {
                    Func::Ln => Op::Func(Func::Ln, positive(&mut nodes)),
                    f => Op::Func(f, x),
                },
                _ => Op::Const(next(100) as f64 / 7.0),
            };
            nodes.push(op);
        }
        let outputs = (0..n as NodeId).filter(|i| i % 5 == 3).collect();
        Tape {
            nodes,
            outputs,
            plan: OnceLock::new(),
        }
    }

    /// Equal bits, or both NaN: the sign and payload of a NaN are not
    /// specified (IEEE 754, and Rust's floating-point semantics), and the
    /// compiler may swap a product's operands, which changes which NaN
    /// propagates.
    fn same(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    /// The planned evaluation gives every output of the node-by-node one,
    /// bit for bit (infinities included; NaN for NaN), at several points;
    /// and a tape added to after its plan was made is still evaluated
    /// right.
    #[test]
    fn the_planned_order_gives_the_tapes_values_bit_for_bit() {
        for seed in 0..20 {
            let mut tape = random_tape(400, seed);
            for point in 0..4 {
                let x = 0.3 + 0.4 * point as f64;
                let y = [x, 1.0 - x, 2.0 * x];
                let inputs = Inputs {
                    t: 0.25 * x,
                    y: &y,
                    yp: &[0.0, -x, 0.0],
                    p: &[1.5, -0.5],
                    z: &[0.0, 0.0, 3.0],
                };
                let mut reference = Vec::new();
                tape.eval(&inputs, &mut reference);
                let mut got = Vec::new();
                tape.eval_outputs(&inputs, &mut Vec::new(), |k, v| {
                    assert_eq!(k, got.len());
                    got.push(v)
                });
                assert_eq!(got.len(), tape.outputs.len());
                for (k, v) in got.iter().enumerate() {
                    let want = tape.output(&reference, k);
                    assert!(
                        same(*v, want),
                        "seed {seed}, output {k}: {v} against {want}"
                    );
                }
                let finite = got.iter().filter(|v| v.is_finite()).count();
                assert!(2 * finite > got.len(), "seed {seed}: {finite} finite");
            }
            // Nodes added after planning: the node-by-node evaluation.
            let last = tape.nodes.len() as NodeId - 1;
            tape.nodes.push(Op::Add(1.0, vec![(2.0, last)]));
            tape.outputs.push(last + 1);
            let inputs = Inputs {
                t: 0.0,
                y: &[0.5, 0.5, 0.5],
                yp: &[0.5; 3],
                p: &[1.0, 1.0],
                z: &[1.0; 3],
            };
            let mut reference = Vec::new();
            tape.eval(&inputs, &mut reference);
            let mut got = Vec::new();
            tape.eval_outputs(&inputs, &mut Vec::new(), |_, v| got.push(v));
            for (k, v) in got.iter().enumerate() {
                assert!(same(*v, tape.output(&reference, k)));
            }
        }
    }

    /// The evaluation at three points at once gives every output of the
    /// node-by-node evaluation at each point, bit for bit (NaN for NaN),
    /// through every kind of node; a tape added to after its plan was
    /// made too.
    #[test]
    fn three_points_at_once_give_each_points_values_bit_for_bit() {
        for seed in 0..20 {
            let mut tape = random_tape(400, seed);
            for round in 0..2 {
                let ys = [0, 1, 2].map(|l| {
                    let x = 0.3 + 0.4 * l as f64;
                    [x, 1.0 - x, 2.0 * x]
                });
                let yps = [0, 1, 2].map(|l| [0.0, -0.1 * l as f64, 0.0]);
                let inputs = [0, 1, 2].map(|l| Inputs {
                    t: 0.25 * l as f64,
                    y: &ys[l],
                    yp: &yps[l],
                    p: &[1.5, -0.5],
                    z: &[0.0, 0.0, 3.0],
                });
                let mut got = vec![Vec::new(); 3];
                tape.eval_outputs_lanes(&inputs, &mut Vec::new(), |l, k, v| {
                    assert_eq!(k, got[l].len());
                    got[l].push(v)
                });
                for (l, (got, inputs)) in got.iter().zip(&inputs).enumerate() {
                    let mut reference = Vec::new();
                    tape.eval(inputs, &mut reference);
                    assert_eq!(got.len(), tape.outputs.len());
                    for (k, v) in got.iter().enumerate() {
                        let want = tape.output(&reference, k);
                        assert!(
                            same(*v, want),
                            "seed {seed}, round {round}, point {l}, output {k}: {v} against {want}"
                        );
                    }
                }
                // Nodes added after planning: the node-by-node evaluation.
                let last = tape.nodes.len() as NodeId - 1;
                tape.nodes.push(Op::Add(1.0, vec![(2.0, last)]));
                tape.outputs.push(last + 1);
            }
        }
    }

    /// The forward pass's derivatives are the symbolic derivatives'
    /// values along each direction, through every kind of node; time and
    /// parameters are held fixed.
    #[test]
    fn tangents_are_the_symbolic_directional_derivatives() {
        let (x, y, z) = (Expr::var(0), Expr::var(1), Expr::var(2));
        let (p, t) = (Expr::param(0), Expr::sym(Sym::Time));
        let exprs = [
            mul_all([
                x.clone(),
                x.clone(),
                y.clone(),
                pow_rational(&z, &qr(-1, 1)),
            ]),
            add(
                &mul(&func(Func::Sin, &x), &func(Func::Exp, &y)),
                &func(Func::Ln, &z),
            ),
            pow_rational(&mul(&x, &y), &qr(1, 2)),
            pow_rational(&x, &qr(3, 2)),
            pow(&x, &y),
            add(&func(Func::Tan, &z), &func(Func::Cos, &x)),
            mul_all([p.clone(), t.clone(), x.clone()]),
            Expr::int(3),
        ];
        let mut b = TapeBuilder::new();
        for e in &exprs {
            b.output(e);
        }
        let tape = b.finish();
        let point = [1.3, 0.7, 2.1];
        let (pv, tv) = ([1.9], 0.4);
        let inputs = Inputs {
            t: tv,
            y: &point,
            yp: &[],
            p: &pv,
            z: &[],
        };
        let env = |s: Sym| match s {
            Sym::Var(i) => point[i as usize],
            Sym::Param(_) => pv[0],
            Sym::Time => tv,
            _ => f64::NAN,
        };
        for count in [1, 2, 3] {
            let dirs: Vec<f64> = (0..3 * count).map(|k| 0.3 + 0.17 * k as f64).collect();
            let (mut v, mut d) = (Vec::new(), Vec::new());
            tape.eval_tangents(&inputs, &dirs, count, &mut v, &mut d);
            let mut plain = Vec::new();
            tape.eval(&inputs, &mut plain);
            for (o, e) in exprs.iter().enumerate() {
                assert_eq!(tape.output(&v, o), tape.output(&plain, o));
                for k in 0..count {
                    let exact: f64 = (0..3)
                        .map(|j| diff(e, Sym::Var(j as u32)).eval(&env) * dirs[k * 3 + j])
                        .sum();
                    let got = tape.output_tangents(&d, o, count)[k];
                    assert!(
                        (got - exact).abs() <= 1e-13 * (1.0 + exact.abs()),
                        "output {o}, direction {k}: {got} against {exact}"
                    );
                }
            }
        }
    }
}
