//! The order in which the interpreter evaluates a tape: by levels, and
//! within a level in runs of equal operations.
//!
//! A tape's nodes are in the depth-first order of its expressions, so
//! consecutive nodes are of unrelated kinds: evaluated in that order, every
//! node costs an indirect jump on a sequence no branch predictor learns,
//! and most nodes wait for the one before (BENCHMARKS.md §16d). A [`Plan`]
//! evaluates the same nodes with the same arithmetic in another order. A
//! node's *level* is 0 for a constant or an input and one more than its
//! deepest operand's otherwise; the nodes of one level depend only on lower
//! levels, so they may run in any order. Each level is split into *runs*:
//! the nodes of one kind (a sum of `k` terms, a product of `k` factors, a
//! quotient, a power with one integer exponent, one function, …), in tape
//! order. Dispatch happens once per run, and a run is a loop over index
//! arrays whose iterations are independent.
//!
//! Every node reachable from an output gets a *slot* in the scratch
//! buffer: the constants first (copied in one block), then the inputs, then
//! the runs in order, so each run writes consecutive slots. Nodes no output
//! reads are left out. Each node's value is computed by the same operations
//! in the same order as [`Tape::eval`](super::Tape::eval) computes it, so
//! the outputs are the same bit for bit.

use super::{FastMap, Inputs, Op, Tape};
use crate::expr::{Func, Sym};

/// Arities of sums and products with a loop specialised to them (longer
/// ones share one loop, still one run per arity).
const UNROLLED: usize = 4;

/// What every node of a run computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
enum Kind {
    /// `y_i`.
    Var,
    /// `y'_i`.
    Der,
    /// `p_k`.
    Param,
    /// `t`.
    Time,
    /// `z_i`.
    Dir,
    /// `constant + Σ c_i · x_i` with this many terms.
    Add(u32),
    /// `Π x_i` with this many factors.
    Mul(u32),
    /// `a / b`.
    Div,
    /// `x^k` with this `k`.
    Powi(i32),
    /// `sqrt(x)`.
    Sqrt,
    /// `x^c`, real `c` (each node's own).
    Powf,
    /// `a^b`.
    Pow,
    /// An elementary function.
    Func(Func),
}

/// Consecutive slots computed by one loop.
#[derive(Clone, Debug, PartialEq)]
struct Run {
    kind: Kind,
    len: u32,
}

/// A tape's evaluation order (see the module's documentation).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Plan {
    /// The tape's node and output counts when it was planned: a tape
    /// changed since (its fields are public) is evaluated node by node.
    nodes: usize,
    outputs_planned: usize,
    /// Values of the first slots.
    consts: Vec<f64>,
    /// The runs, in evaluation order; run `r` writes the slots after run
    /// `r - 1`'s (the first after the constants).
    runs: Vec<Run>,
    /// The operand slots of every node (the index of an input), run after
    /// run, node after node.
    args: Vec<u32>,
    /// Every sum's constant and coefficients, and every `Powf`'s exponent,
    /// in the same order.
    reals: Vec<f64>,
    /// The slot of each output.
    outputs: Vec<u32>,
    /// Slots written: the scratch length an evaluation needs.
    slots: usize,
}

impl Kind {
    fn of(op: &Op) -> Kind {
        match op {
            Op::Const(_) => unreachable!("constants are not in runs"),
            Op::Input(Sym::Var(_)) => Kind::Var,
            Op::Input(Sym::Der(_)) => Kind::Der,
            Op::Input(Sym::Param(_)) => Kind::Param,
            Op::Input(Sym::Time) => Kind::Time,
            Op::Input(Sym::Dir(_)) => Kind::Dir,
            Op::Add(_, terms) => Kind::Add(terms.len() as u32),
            Op::Mul(xs) => Kind::Mul(xs.len() as u32),
            Op::Div(..) => Kind::Div,
            Op::Powi(_, k) => Kind::Powi(*k),
            Op::Sqrt(_) => Kind::Sqrt,
            Op::Powf(..) => Kind::Powf,
            Op::Pow(..) => Kind::Pow,
            Op::Func(f, _) => Kind::Func(*f),
        }
    }
}

/// The operands of `op`, in order.
fn operands(op: &Op, mut each: impl FnMut(u32)) {
    match op {
        Op::Const(_) | Op::Input(_) => {}
        Op::Add(_, terms) => terms.iter().for_each(|&(_, x)| each(x)),
        Op::Mul(xs) => xs.iter().for_each(|&x| each(x)),
        Op::Div(a, b) | Op::Pow(a, b) => {
            each(*a);
            each(*b);
        }
        Op::Powi(a, _) | Op::Sqrt(a) | Op::Powf(a, _) | Op::Func(_, a) => each(*a),
    }
}

impl Plan {
    /// The plan of `tape`: linear passes for liveness, levels, the order
    /// and the slots.
    pub(super) fn new(tape: &Tape) -> Plan {
        let n = tape.nodes.len();
        // Liveness, parents before children (children come first in the
        // tape, so one backward sweep).
        let mut live = vec![false; n];
        for &o in &tape.outputs {
            live[o as usize] = true;
        }
        for i in (0..n).rev() {
            if live[i] {
                operands(&tape.nodes[i], |x| live[x as usize] = true);
            }
        }
        // Levels, children before parents.
        let mut level = vec![0u32; n];
        for (i, op) in tape.nodes.iter().enumerate() {
            if matches!(op, Op::Const(_) | Op::Input(_)) {
                continue;
            }
            let mut deepest = 0;
            operands(op, |x| deepest = deepest.max(level[x as usize]));
            level[i] = deepest + 1;
        }
        let mut slot = vec![u32::MAX; n];
        let mut consts = Vec::new();
        for (i, op) in tape.nodes.iter().enumerate() {
            if let (true, Op::Const(c)) = (live[i], op) {
                slot[i] = consts.len() as u32;
                consts.push(*c);
            }
        }
        let order = schedule(tape, &live, &level);
        let mut plan = Plan {
            nodes: n,
            outputs_planned: tape.outputs.len(),
            consts,
            runs: Vec::new(),
            args: Vec::new(),
            reals: Vec::new(),
            outputs: Vec::new(),
            slots: 0,
        };
        let mut next = plan.consts.len() as u32;
        for &(_, kind, i) in &order {
            match plan.runs.last_mut() {
                Some(run) if run.kind == kind => run.len += 1,
                _ => plan.runs.push(Run { kind, len: 1 }),
            }
            let op = &tape.nodes[i as usize];
            match op {
                Op::Input(s) => plan.args.push(match *s {
                    Sym::Var(k) | Sym::Der(k) | Sym::Param(k) | Sym::Dir(k) => k,
                    Sym::Time => 0,
                }),
                Op::Add(c, terms) => {
                    plan.reals.push(*c);
                    plan.reals.extend(terms.iter().map(|&(w, _)| w));
                }
                Op::Powf(_, c) => plan.reals.push(*c),
                _ => {}
            }
            operands(op, |x| plan.args.push(slot[x as usize]));
            slot[i as usize] = next;
            next += 1;
        }
        plan.slots = next as usize;
        plan.outputs = tape.outputs.iter().map(|&o| slot[o as usize]).collect();
        plan
    }

    /// Whether this plan was made for `tape` as it is now.
    pub(super) fn fits(&self, tape: &Tape) -> bool {
        self.nodes == tape.nodes.len() && self.outputs_planned == tape.outputs.len()
    }

    /// Scratch slots an evaluation writes.
    pub(super) fn slots(&self) -> usize {
        self.slots
    }

    /// The slot of each output.
    pub(super) fn outputs(&self) -> &[u32] {
        &self.outputs
    }

    /// Evaluate every planned node at `L` points at once: slot `i` of point `l` in
    /// `s[i L + l]` (`s` at least `L` [`Plan::slots`] long). Each run is
    /// dispatched, and each node's operand slots read, once for the `L`
    /// points; each point's value is computed by the same operations in the
    /// same order as [`Tape::eval`] computes it, bit for bit. A staggered
    /// corrector's three stage-point Jacobians (BENCHMARKS.md §21) cost
    /// about half of three evaluations.
    pub(super) fn eval_lanes<const L: usize>(&self, inputs: &[Inputs<'_>; L], s: &mut [f64]) {
        for (lanes, &c) in s.chunks_exact_mut(L).zip(&self.consts) {
            lanes.fill(c);
        }
        let mut at = self.consts.len() * L;
        let (mut a, mut r) = (0, 0);
        for run in &self.runs {
            let len = run.len as usize;
            let (done, rest) = s.split_at_mut(at);
            let out = &mut rest[..len * L];
            at += len * L;
            let mut args = |per: usize| {
                let x = &self.args[a..a + per * len];
                a += per * len;
                x
            };
            match run.kind {
                Kind::Var => gather_lanes(out, args(1), inputs.each_ref().map(|i| i.y)),
                Kind::Der => gather_lanes(out, args(1), inputs.each_ref().map(|i| i.yp)),
                Kind::Param => gather_lanes(out, args(1), inputs.each_ref().map(|i| i.p)),
                Kind::Dir => gather_lanes(out, args(1), inputs.each_ref().map(|i| i.z)),
                Kind::Time => {
                    let _ = args(1);
                    for o in out.chunks_exact_mut(L) {
                        for (o, inputs) in o.iter_mut().zip(inputs) {
                            *o = inputs.t;
                        }
                    }
                }
                Kind::Add(k) => {
                    let k = k as usize;
                    let c = &self.reals[r..r + (k + 1) * len];
                    r += (k + 1) * len;
                    let x = args(k);
                    match k {
                        0 => {
                            for (o, &c) in out.chunks_exact_mut(L).zip(c) {
                                o.fill(c);
                            }
                        }
                        1 => add_lanes::<L>(out, x, c, done, 1),
                        2 => add_lanes::<L>(out, x, c, done, 2),
                        3 => add_lanes::<L>(out, x, c, done, 3),
                        UNROLLED => add_lanes::<L>(out, x, c, done, UNROLLED),
                        _ => add_n_lanes::<L>(out, x, c, done, k),
                    }
                }
                Kind::Mul(k) => {
                    let k = k as usize;
                    let x = args(k);
                    match k {
                        0 => out.fill(1.0),
                        2 => mul_lanes::<L>(out, x, done, 2),
                        3 => mul_lanes::<L>(out, x, done, 3),
                        UNROLLED => mul_lanes::<L>(out, x, done, UNROLLED),
                        _ => mul_n_lanes::<L>(out, x, done, k),
                    }
                }
                Kind::Div => binary_lanes::<L>(out, args(2), done, |a, b| a / b),
                Kind::Powi(2) => unary_lanes::<L>(out, args(1), done, |v| v * v),
                Kind::Powi(e) => unary_lanes::<L>(out, args(1), done, |v| v.powi(e)),
                Kind::Sqrt => unary_lanes::<L>(out, args(1), done, f64::sqrt),
                Kind::Powf => {
                    let c = &self.reals[r..r + len];
                    r += len;
                    for ((o, &x), &c) in out.chunks_exact_mut(L).zip(args(1)).zip(c) {
                        let v = &done[x as usize * L..][..L];
                        for (o, &v) in o.iter_mut().zip(v) {
                            *o = v.powf(c);
                        }
                    }
                }
                Kind::Pow => binary_lanes::<L>(out, args(2), done, f64::powf),
                Kind::Func(f) => match f {
                    Func::Sin => unary_lanes::<L>(out, args(1), done, f64::sin),
                    Func::Cos => unary_lanes::<L>(out, args(1), done, f64::cos),
                    Func::Tan => unary_lanes::<L>(out, args(1), done, f64::tan),
                    Func::Exp => unary_lanes::<L>(out, args(1), done, f64::exp),
                    Func::Ln => unary_lanes::<L>(out, args(1), done, f64::ln),
                },
            }
        }
    }
}

/// `out[j L + l] = from[l][at[j]]`: the inputs at `L` points.
#[inline(always)]
fn gather_lanes<const L: usize>(out: &mut [f64], at: &[u32], from: [&[f64]; L]) {
    for (o, &k) in out.chunks_exact_mut(L).zip(at) {
        for (o, from) in o.iter_mut().zip(from) {
            *o = from[k as usize];
        }
    }
}

/// `out[j L + l] = f(v[x[j] L + l])`.
#[inline(always)]
fn unary_lanes<const L: usize>(out: &mut [f64], x: &[u32], v: &[f64], f: impl Fn(f64) -> f64) {
    for (o, &x) in out.chunks_exact_mut(L).zip(x) {
        let v = &v[x as usize * L..][..L];
        for (o, &v) in o.iter_mut().zip(v) {
            *o = f(v);
        }
    }
}

/// `f(a, b)` of two operands at `L` points.
#[inline(always)]
fn binary_lanes<const L: usize>(
    out: &mut [f64],
    x: &[u32],
    v: &[f64],
    f: impl Fn(f64, f64) -> f64,
) {
    for (o, x) in out.chunks_exact_mut(L).zip(x.chunks_exact(2)) {
        let (a, b) = (&v[x[0] as usize * L..][..L], &v[x[1] as usize * L..][..L]);
        for ((o, &a), &b) in o.iter_mut().zip(a).zip(b) {
            *o = f(a, b);
        }
    }
}

/// Sums of `k` terms, `c_0 + c_1 x_1 + …`, at `L` points, added left to
/// right as [`Tape::eval`] adds them (`k` a constant where inlined with
/// one).
#[inline(always)]
fn add_lanes<const L: usize>(out: &mut [f64], x: &[u32], c: &[f64], v: &[f64], k: usize) {
    for ((o, x), c) in out
        .chunks_exact_mut(L)
        .zip(x.chunks_exact(k))
        .zip(c.chunks_exact(k + 1))
    {
        let mut acc = [c[0]; L];
        for (&x, &w) in x.iter().zip(&c[1..]) {
            let v = &v[x as usize * L..][..L];
            for (acc, &v) in acc.iter_mut().zip(v) {
                *acc += w * v;
            }
        }
        o.copy_from_slice(&acc);
    }
}

/// [`add_lanes`] for sums of more terms than [`UNROLLED`] (not inlined).
fn add_n_lanes<const L: usize>(out: &mut [f64], x: &[u32], c: &[f64], v: &[f64], k: usize) {
    add_lanes::<L>(out, x, c, v, k)
}

/// Products of `k` factors at `L` points, multiplied left to right from 1
/// as [`Tape::eval`] multiplies them (`k` a constant where inlined with
/// one).
#[inline(always)]
fn mul_lanes<const L: usize>(out: &mut [f64], x: &[u32], v: &[f64], k: usize) {
    for (o, x) in out.chunks_exact_mut(L).zip(x.chunks_exact(k)) {
        let mut acc = [1.0; L];
        for &x in x {
            let v = &v[x as usize * L..][..L];
            for (acc, &v) in acc.iter_mut().zip(v) {
                *acc *= v;
            }
        }
        o.copy_from_slice(&acc);
    }
}

/// [`mul_lanes`] for products of other lengths (not inlined).
fn mul_n_lanes<const L: usize>(out: &mut [f64], x: &[u32], v: &[f64], k: usize) {
    mul_lanes::<L>(out, x, v, k)
}

/// The live nodes other than constants ordered by level, kind and tape
/// order, as `(level, kind, node)`: two stable counting sorts (by kind,
/// then by level) of the nodes in tape order, linear in their number.
fn schedule(tape: &Tape, live: &[bool], level: &[u32]) -> Vec<(u32, Kind, u32)> {
    let nodes: Vec<(u32, Kind, u32)> = (0..tape.nodes.len())
        .filter(|&i| live[i] && !matches!(tape.nodes[i], Op::Const(_)))
        .map(|i| (level[i], Kind::of(&tape.nodes[i]), i as u32))
        .collect();
    // The kinds present, ranked.
    let mut rank: FastMap<Kind, usize> = FastMap::default();
    for &(_, kind, _) in &nodes {
        rank.entry(kind).or_default();
    }
    let mut kinds: Vec<Kind> = rank.keys().copied().collect();
    kinds.sort_unstable();
    for (r, kind) in kinds.iter().enumerate() {
        rank.insert(*kind, r);
    }
    let by_kind = counting_sort(&nodes, kinds.len(), |&(_, kind, _)| rank[&kind]);
    let levels = nodes
        .iter()
        .map(|&(l, _, _)| l as usize + 1)
        .max()
        .unwrap_or(0);
    counting_sort(&by_kind, levels, |&(l, _, _)| l as usize)
}

/// `items` stably sorted by `key` (below `keys`).
fn counting_sort<T: Copy>(items: &[T], keys: usize, key: impl Fn(&T) -> usize) -> Vec<T> {
    let mut start = vec![0usize; keys + 1];
    for x in items {
        start[key(x) + 1] += 1;
    }
    for k in 0..keys {
        start[k + 1] += start[k];
    }
    let mut out = items.to_vec();
    for x in items {
        let k = key(x);
        out[start[k]] = *x;
        start[k] += 1;
    }
    out
}
