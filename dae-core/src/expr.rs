//! Symbolic expressions in canonical form.
//!
//! An [`Expr`] is an immutable tree with shared (`Rc`) children, built only
//! through the constructors of this module ([`add`], [`mul`], [`pow`], …),
//! which keep it in a canonical form:
//!
//! * numbers are exact rationals ([`Q`]); there are no floating-point
//!   constants in an expression, so `x/2 + x/2` is `x` exactly;
//! * a sum is a constant plus a sorted list of `(term, coefficient)` pairs,
//!   like terms collected, zero coefficients dropped;
//! * a product is a sorted list of `(base, exponent)` pairs with rational
//!   exponents, like bases merged (`m · m⁻¹ = 1`), the numeric coefficient
//!   living in the enclosing sum;
//! * products of sums are expanded while the result stays small
//!   ([`EXPANSION_LIMIT`] terms), so polynomial identities such as
//!   `d/dt (2xv + 2yw) = 2v² + 2w² + …` are decided by structural equality.
//!   Larger products stay factored: expansion is bounded and never blows up
//!   on user input;
//! * a *linear form in the unknowns* — a sum of at least two terms, each a
//!   rational multiple of one unknown, such as `x₂ − x₁` (not `x − 1` or
//!   `x − p` with a parameter `p`, which are distributed) — is never
//!   expanded as a factor of a product or as the base of an integer
//!   power: `(x₂ − x₁)²` and `λ (x₂ − x₁)` stay as written (see
//!   [`is_linear_form`] for why), with the base normalised (content 1, first
//!   coefficient positive) so that `(x₁ − x₂)²` and `(2x₂ − 2x₁)²/4` are one
//!   expression. A numeric multiple of a linear form is still a sum
//!   (`2 (x₂ − x₁)` is `2x₂ − 2x₁`, exact in floating point for a power of
//!   two and within one rounding of each term otherwise).
//!
//! Ordering is the derived structural order, so everything downstream —
//! printing, code generation, JSON — is deterministic.

use num_bigint::BigInt;
use num_integer::Integer;
use num_rational::BigRational;
use num_traits::{One, Signed, ToPrimitive, Zero};
use std::cmp::Ordering;
use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::hash::{Hash, Hasher};
use std::rc::Rc;

/// Exact rational number.
pub type Q = BigRational;

/// Largest number of terms a product of sums may expand into before it is
/// kept factored.
pub const EXPANSION_LIMIT: usize = 64;

/// Largest positive integer power of a sum that is expanded.
pub const POWER_EXPANSION_LIMIT: i64 = 6;

/// A symbol: something an expression depends on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Sym {
    /// Unknown `y_i` (model order: differential, then algebraic, then any
    /// unknowns a formulation adds such as GGL's `eta`).
    Var(u32),
    /// Its time derivative `der(y_i)`.
    Der(u32),
    /// Model parameter `p_k`.
    Param(u32),
    /// Time `t`.
    Time,
    /// Component `z_i` of an auxiliary direction (for `∂(E(y) z)/∂y`).
    Dir(u32),
}

/// Elementary functions of the model language.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Func {
    /// `sin`
    Sin,
    /// `cos`
    Cos,
    /// `tan`
    Tan,
    /// `exp`
    Exp,
    /// `ln` (natural logarithm)
    Ln,
}

impl Func {
    /// Name in the model language.
    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Exp => "exp",
            Func::Ln => "ln",
        }
    }

    /// Evaluate on a float.
    pub fn apply(self, x: f64) -> f64 {
        match self {
            Func::Sin => x.sin(),
            Func::Cos => x.cos(),
            Func::Tan => x.tan(),
            Func::Exp => x.exp(),
            Func::Ln => x.ln(),
        }
    }
}

/// A canonical sum `constant + Σ coefficient·term`.
#[derive(Clone, Debug)]
pub struct Sum {
    /// Sorted by term, coefficients non-zero; no term is a number or a sum.
    pub terms: Vec<(Expr, Q)>,
    /// Constant part.
    pub constant: Q,
    meta: Meta,
}

/// A canonical product `Π base^exponent` (coefficient 1).
#[derive(Clone, Debug)]
pub struct Prod {
    /// Sorted by base, exponents non-zero; no base is a product.
    pub factors: Vec<(Expr, Q)>,
    meta: Meta,
}

/// A number double precision cannot hold, found by
/// [`Expr::unrepresentable_number`].
///
/// ```
/// use dae_core::expr::Unrepresentable;
/// let u = Unrepresentable { order: -400.0, overflows: false };
/// assert_eq!(u.to_string(), "a number of about 1e-400 underflows to 0 in double precision \
///     (the smallest positive value is 4.9e-324); write 0 if 0 is meant");
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unrepresentable {
    /// Its decimal order of magnitude, rounded (`400` for `1e400`).
    pub order: f64,
    /// `true`: above the largest finite `f64`; `false`: a non-zero value
    /// below the smallest positive one.
    pub overflows: bool,
}

impl fmt::Display for Unrepresentable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.overflows {
            write!(
                f,
                "a number of about 1e{} is too large for double precision (the largest is 1.8e308)",
                self.order
            )
        } else {
            write!(
                f,
                "a number of about 1e{} underflows to 0 in double precision (the smallest positive value is 4.9e-324); write 0 if 0 is meant",
                self.order
            )
        }
    }
}

/// `base ^ exponent` with a non-numeric exponent.
#[derive(Clone, Debug)]
pub struct Power {
    /// The base.
    pub base: Expr,
    /// The exponent (not a number).
    pub exponent: Expr,
    meta: Meta,
}

/// An elementary function applied to an argument.
#[derive(Clone, Debug)]
pub struct Call {
    /// The function.
    pub func: Func,
    /// Its argument.
    pub arg: Expr,
    meta: Meta,
}

/// What every compound node caches about itself when it is built, so that
/// no question about it needs a walk of the tree: its height, a structural
/// hash, and a mask of the symbols below it.
#[derive(Clone, Copy, Debug)]
struct Meta {
    /// Longest path to a leaf (numbers and symbols have height 0).
    height: u32,
    /// Hash of the structure (equal expressions have equal hashes).
    hash: u64,
    /// Bit [`sym_bit`] of every symbol the expression contains.
    syms: u64,
    /// Number of nodes of the expression written out as a tree (shared
    /// children counted at every use), saturating: what a walk that does
    /// not remember shared nodes (printing, evaluation) visits.
    size: u64,
}

impl Meta {
    /// Metadata of a node with tag `tag` over `children`; `extra` hashes
    /// the node's own data (coefficients, exponents, the function).
    fn of<'a>(tag: u8, children: impl Iterator<Item = &'a Expr>, extra: &dyn Fn(&mut Fnv)) -> Meta {
        let mut h = Fnv::new();
        h.write_u8(tag);
        let (mut height, mut syms, mut size, mut work) = (0u32, 0u64, 1u64, 1u64);
        for c in children {
            height = height.max(c.height());
            syms |= c.sym_mask();
            size = size.saturating_add(c.size());
            work += 1;
            h.write_u64(c.structural_hash());
        }
        extra(&mut h);
        add_work(work);
        Meta {
            height: height.saturating_add(1),
            hash: h.finish(),
            syms,
            size,
        }
    }
}

/// FNV-1a, 64 bits: a fixed hash, so nothing depends on a random seed.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Hasher for Fnv {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 ^= u64::from(*b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// Hash a rational: its numerator and denominator as machine integers when
/// they fit (every coefficient and exponent of a real model), else
/// `num_rational`'s hash (a continued fraction, walked term by term: a
/// tenth of the lowering of a large model before this fast path). A value
/// is hashed one way only, so equal rationals hash equally.
fn hash_q(v: &Q, h: &mut Fnv) {
    match (v.numer().to_i64(), v.denom().to_i64()) {
        (Some(n), Some(d)) => {
            h.write_u8(0);
            h.write_i64(n);
            h.write_i64(d);
        }
        _ => {
            h.write_u8(1);
            v.hash(h);
        }
    }
}

/// Bound on the numerator and denominator of a rational that the fast
/// paths below compute with in `i64`: products of two such numbers and
/// sums of two such products stay below `2^63`.
const SMALL_Q: u64 = 1 << 31;

/// `(numerator, denominator)` of `v` when both are below [`SMALL_Q`] in
/// magnitude (the denominator of a [`Q`] is positive).
fn small_q(v: &Q) -> Option<(i64, i64)> {
    let n = v.numer().to_i64()?;
    let d = v.denom().to_i64()?;
    (n.unsigned_abs() < SMALL_Q && d.unsigned_abs() < SMALL_Q).then_some((n, d))
}

/// The rational `n/d` for `d > 0`, reduced as [`Q::new`] reduces it, but
/// with machine integers (no big-integer gcd or division).
fn q_small(n: i64, d: i64) -> Q {
    debug_assert!(d > 0);
    if d == 1 {
        return Q::from_integer(BigInt::from(n));
    }
    let g = n.gcd(&d);
    Q::new_raw(BigInt::from(n / g), BigInt::from(d / g))
}

/// `a · b`, exactly; machine arithmetic when both are small ([`small_q`]).
fn q_mul(a: &Q, b: &Q) -> Q {
    if a.is_one() {
        return b.clone();
    }
    if b.is_one() {
        return a.clone();
    }
    match (small_q(a), small_q(b)) {
        (Some((na, da)), Some((nb, db))) => q_small(na * nb, da * db),
        _ => a * b,
    }
}

/// `a + b`, exactly; machine arithmetic when both are small ([`small_q`]).
fn q_add(a: &Q, b: &Q) -> Q {
    if a.is_zero() {
        return b.clone();
    }
    if b.is_zero() {
        return a.clone();
    }
    match (small_q(a), small_q(b)) {
        (Some((na, da)), Some((nb, db))) => {
            if da == db {
                q_small(na + nb, da)
            } else {
                q_small(na * db + nb * da, da * db)
            }
        }
        _ => a + b,
    }
}

/// `*a += b` through [`q_add`].
fn q_add_to(a: &mut Q, b: &Q) {
    *a = q_add(a, b);
}

/// `*a *= b` through [`q_mul`].
fn q_mul_to(a: &mut Q, b: &Q) {
    if !b.is_one() {
        *a = q_mul(a, b);
    }
}

/// The bit of `s` in a [`Meta::syms`] mask.
fn sym_bit(s: Sym) -> u64 {
    let mut h = Fnv::new();
    s.hash(&mut h);
    1u64 << (h.finish() % 64)
}

/// A symbolic expression in canonical form. Build with the free functions
/// of this module; the variants are public for inspection.
///
/// Equality is structural. The order is the structural order (variant,
/// then fields, children compared the same way) for expressions of height
/// up to [`ORDER_HEIGHT`]; a taller expression is first ordered by height.
/// That keeps the familiar order of every printed term of a real model
/// while making comparisons of deep expressions (the factors of a long
/// chain rule, say) constant-time instead of proportional to their depth.
#[derive(Clone, Debug)]
pub enum Expr {
    /// Exact rational constant.
    Num(Rc<Q>),
    /// A symbol.
    Sym(Sym),
    /// Sum.
    Sum(Rc<Sum>),
    /// Product.
    Prod(Rc<Prod>),
    /// `base ^ exponent` with a non-numeric exponent.
    Pow(Rc<Power>),
    /// Elementary function.
    Func(Rc<Call>),
}

/// Height up to which expressions are ordered purely structurally (see
/// [`Expr`]).
pub const ORDER_HEIGHT: u32 = 16;

impl Expr {
    fn meta(&self) -> Option<&Meta> {
        match self {
            Expr::Num(_) | Expr::Sym(_) => None,
            Expr::Sum(s) => Some(&s.meta),
            Expr::Prod(p) => Some(&p.meta),
            Expr::Pow(p) => Some(&p.meta),
            Expr::Func(c) => Some(&c.meta),
        }
    }

    /// Longest path from the root to a leaf (0 for numbers and symbols).
    pub fn height(&self) -> u32 {
        self.meta().map_or(0, |m| m.height)
    }

    /// Number of nodes of the expression written out as a tree, shared
    /// subexpressions counted at every use (saturating at `u64::MAX`):
    /// numbers and symbols count 1.
    ///
    /// ```
    /// use dae_core::expr::{add, func, Expr, Func};
    /// let s = func(Func::Sin, &Expr::var(0));
    /// assert_eq!(add(&s, &Expr::var(1)).size(), 4); // sum, sin, y0, y1
    /// ```
    pub fn size(&self) -> u64 {
        self.meta().map_or(1, |m| m.size)
    }

    /// Mask of the symbols below (a superset test: a clear bit means the
    /// symbol is absent).
    fn sym_mask(&self) -> u64 {
        match self {
            Expr::Sym(s) => sym_bit(*s),
            _ => self.meta().map_or(0, |m| m.syms),
        }
    }

    /// A hash of the structure, independent of how the expression was
    /// built and of any random seed.
    pub fn structural_hash(&self) -> u64 {
        match self {
            Expr::Num(v) => {
                let mut h = Fnv::new();
                h.write_u8(0);
                hash_q(v, &mut h);
                h.finish()
            }
            Expr::Sym(s) => {
                let mut h = Fnv::new();
                h.write_u8(1);
                s.hash(&mut h);
                h.finish()
            }
            _ => self.meta().map_or(0, |m| m.hash),
        }
    }

    fn variant(&self) -> u8 {
        match self {
            Expr::Num(_) => 0,
            Expr::Sym(_) => 1,
            Expr::Sum(_) => 2,
            Expr::Prod(_) => 3,
            Expr::Pow(_) => 4,
            Expr::Func(_) => 5,
        }
    }

    /// The same node (shared), so equal without a look inside.
    fn same_node(&self, other: &Expr) -> bool {
        match (self, other) {
            (Expr::Num(a), Expr::Num(b)) => Rc::ptr_eq(a, b),
            (Expr::Sum(a), Expr::Sum(b)) => Rc::ptr_eq(a, b),
            (Expr::Prod(a), Expr::Prod(b)) => Rc::ptr_eq(a, b),
            (Expr::Pow(a), Expr::Pow(b)) => Rc::ptr_eq(a, b),
            (Expr::Func(a), Expr::Func(b)) => Rc::ptr_eq(a, b),
            _ => false,
        }
    }
}

thread_local! {
    static WORK: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
    static LIMIT: std::cell::Cell<u64> = const { std::cell::Cell::new(u64::MAX) };
}

/// Symbolic work done on this thread so far: structural comparison steps,
/// derivative steps and node constructions (one per node and child). A
/// measure of cost that does not depend on the machine, for tests that
/// bound how work grows with a model, and what a [`Budget`] limits.
pub fn work() -> u64 {
    WORK.with(std::cell::Cell::get)
}

fn count_work() {
    add_work(1);
}

fn add_work(n: u64) {
    WORK.with(|w| w.set(w.get().saturating_add(n)));
}

/// Work units [`Derived`](crate::Derived) and [`Model::check`](crate::model::Model::check)
/// may spend on a model. The largest shipped model (`andrews_natural`, 0.45 M
/// units), the 60-link chain of BENCHMARKS.md (0.19 M) and the 200-link chain
/// (0.76 M) take at most a thirteenth of it; an optimised build spends it in
/// a few seconds (about 0.4 µs a unit on the products of sums that cost the
/// most per unit), so a model that needs more stops with a located error
/// well inside issue 27's 10 s.
pub const WORK_BUDGET: u64 = 10_000_000;

/// Largest height ([`Expr::height`]) of an expression a model may lower to or
/// derive: the passes over expressions recurse once per level or a few, so
/// this is what keeps them inside a worker thread's 2 MiB stack. An
/// expression nested [`MAX_DEPTH`](crate::dsl::MAX_DEPTH) deep in the text
/// lowers to at most three levels per nesting level (`sin(2*x*…)`: a call, a
/// scaled sum, a product); definitions used inside definitions add their
/// heights.
pub const MAX_HEIGHT: u32 = 3 * crate::dsl::MAX_DEPTH as u32 + 16;

/// Largest size ([`Expr::size`]) of an expression written out: printing,
/// evaluation and code generation visit shared subexpressions at every use,
/// so this bounds their time and output (the report of a model whose
/// constraint is 2 M nodes at its second derivative takes 7 s to print).
/// A constraint holding 199 nested `sin`, differentiated twice, is
/// 4.0 M nodes written out, 80 MB of text: refused.
pub const MAX_SIZE: u64 = 1_000_000;

/// A limit on the work ([`work`]) of this thread, in force while the guard
/// lives. Nested budgets keep the smaller limit; dropping one restores the
/// limit before it.
///
/// Once the limit is passed, [`exhausted`] is `true` and the expensive
/// constructions (derivatives, substitutions, expansions of products of
/// sums) return zero at once, so a derivation that outgrew its budget ends
/// quickly; its result is meaningless and its caller reports [`Grew::Work`].
///
/// ```
/// use dae_core::expr::{self, Budget};
/// let b = Budget::start(10);
/// let mut e = expr::Expr::var(0);
/// for _ in 0..20 {
///     e = expr::func(expr::Func::Sin, &e);
/// }
/// assert!(expr::exhausted());
/// drop(b);
/// assert!(!expr::exhausted());
/// ```
#[derive(Debug)]
pub struct Budget {
    previous: u64,
}

impl Budget {
    /// Allow `units` more work on this thread (or less, if an enclosing
    /// budget ends earlier).
    pub fn start(units: u64) -> Budget {
        let previous = LIMIT.with(std::cell::Cell::get);
        let limit = work().saturating_add(units).min(previous);
        LIMIT.with(|l| l.set(limit));
        Budget { previous }
    }
}

impl Drop for Budget {
    fn drop(&mut self) {
        LIMIT.with(|l| l.set(self.previous));
    }
}

/// Has this thread's work passed the limit of the innermost [`Budget`]?
pub fn exhausted() -> bool {
    work() > LIMIT.with(std::cell::Cell::get)
}

/// How an expression outgrew what derivation allows: the error that model
/// checking and derivation turn into a message at the definition, equation
/// or constraint being built.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Grew {
    /// The work budget ([`WORK_BUDGET`]) was spent.
    #[error("grew past the derivation budget ({limit} units of symbolic work)")]
    Work {
        /// The budget.
        limit: u64,
    },
    /// Nested deeper than [`MAX_HEIGHT`] (definitions substituted).
    #[error("nests {height} levels deep with its definitions substituted (limit {limit})")]
    Height {
        /// Its height.
        height: u32,
        /// The limit.
        limit: u32,
    },
    /// Larger than [`MAX_SIZE`] nodes written out.
    #[error("grew to {size} nodes written out with its definitions substituted (limit {limit})")]
    Size {
        /// Its size (saturating).
        size: u64,
        /// The limit.
        limit: u64,
    },
}

/// Check `e` against [`MAX_HEIGHT`] and [`MAX_SIZE`], and the work budget
/// against [`exhausted`].
///
/// ```
/// use dae_core::expr::{self, Expr, Func, Grew};
/// let mut e = Expr::var(0);
/// for _ in 0..expr::MAX_HEIGHT {
///     e = expr::func(Func::Sin, &e);
/// }
/// assert!(expr::check_growth(&e).is_ok());
/// let e = expr::func(Func::Sin, &e);
/// assert!(matches!(expr::check_growth(&e), Err(Grew::Height { .. })));
/// ```
pub fn check_growth(e: &Expr) -> Result<(), Grew> {
    if exhausted() {
        return Err(Grew::Work { limit: WORK_BUDGET });
    }
    if e.height() > MAX_HEIGHT {
        return Err(Grew::Height {
            height: e.height(),
            limit: MAX_HEIGHT,
        });
    }
    if e.size() > MAX_SIZE {
        return Err(Grew::Size {
            size: e.size(),
            limit: MAX_SIZE,
        });
    }
    Ok(())
}

impl PartialEq for Expr {
    fn eq(&self, other: &Expr) -> bool {
        if self.same_node(other) {
            return true;
        }
        if self.variant() != other.variant()
            || self.height() != other.height()
            || self.structural_hash() != other.structural_hash()
        {
            return false;
        }
        count_work();
        match (self, other) {
            (Expr::Num(a), Expr::Num(b)) => a == b,
            (Expr::Sym(a), Expr::Sym(b)) => a == b,
            (Expr::Sum(a), Expr::Sum(b)) => a.constant == b.constant && a.terms == b.terms,
            (Expr::Prod(a), Expr::Prod(b)) => a.factors == b.factors,
            (Expr::Pow(a), Expr::Pow(b)) => a.base == b.base && a.exponent == b.exponent,
            (Expr::Func(a), Expr::Func(b)) => a.func == b.func && a.arg == b.arg,
            _ => false,
        }
    }
}

impl Eq for Expr {}

impl PartialOrd for Expr {
    fn partial_cmp(&self, other: &Expr) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Expr {
    fn cmp(&self, other: &Expr) -> Ordering {
        if self.same_node(other) {
            return Ordering::Equal;
        }
        let (ha, hb) = (self.height(), other.height());
        if ha != hb && ha.max(hb) > ORDER_HEIGHT {
            return ha.cmp(&hb);
        }
        count_work();
        match (self, other) {
            (Expr::Num(a), Expr::Num(b)) => a.cmp(b),
            (Expr::Sym(a), Expr::Sym(b)) => a.cmp(b),
            (Expr::Sum(a), Expr::Sum(b)) => a
                .terms
                .cmp(&b.terms)
                .then_with(|| a.constant.cmp(&b.constant)),
            (Expr::Prod(a), Expr::Prod(b)) => a.factors.cmp(&b.factors),
            (Expr::Pow(a), Expr::Pow(b)) => a
                .base
                .cmp(&b.base)
                .then_with(|| a.exponent.cmp(&b.exponent)),
            (Expr::Func(a), Expr::Func(b)) => a.func.cmp(&b.func).then_with(|| a.arg.cmp(&b.arg)),
            _ => self.variant().cmp(&other.variant()),
        }
    }
}

impl Hash for Expr {
    fn hash<H: Hasher>(&self, state: &mut H) {
        state.write_u64(self.structural_hash());
    }
}

fn sum_node(terms: Vec<(Expr, Q)>, constant: Q) -> Expr {
    let meta = Meta::of(2, terms.iter().map(|(t, _)| t), &|h| {
        for (_, c) in &terms {
            hash_q(c, h);
        }
        hash_q(&constant, h);
    });
    Expr::Sum(Rc::new(Sum {
        terms,
        constant,
        meta,
    }))
}

fn prod_node(factors: Vec<(Expr, Q)>) -> Expr {
    let meta = Meta::of(3, factors.iter().map(|(b, _)| b), &|h| {
        for (_, x) in &factors {
            hash_q(x, h);
        }
    });
    Expr::Prod(Rc::new(Prod { factors, meta }))
}

fn pow_node(base: Expr, exponent: Expr) -> Expr {
    let meta = Meta::of(4, [&base, &exponent].into_iter(), &|_| {});
    Expr::Pow(Rc::new(Power {
        base,
        exponent,
        meta,
    }))
}

fn call_node(func: Func, arg: Expr) -> Expr {
    let meta = Meta::of(5, std::iter::once(&arg), &|h| h.write_u8(func as u8));
    Expr::Func(Rc::new(Call { func, arg, meta }))
}

/// The rational `n`.
pub fn q(n: i64) -> Q {
    Q::from_integer(BigInt::from(n))
}

/// The rational `n/d`.
pub fn qr(n: i64, d: i64) -> Q {
    Q::new(BigInt::from(n), BigInt::from(d))
}

impl Expr {
    /// Numeric constant.
    pub fn num(v: Q) -> Expr {
        Expr::Num(Rc::new(v))
    }
    /// Integer constant.
    pub fn int(n: i64) -> Expr {
        Expr::num(q(n))
    }
    /// Zero.
    pub fn zero() -> Expr {
        Expr::int(0)
    }
    /// One.
    pub fn one() -> Expr {
        Expr::int(1)
    }
    /// Symbol.
    pub fn sym(s: Sym) -> Expr {
        Expr::Sym(s)
    }
    /// Unknown `y_i`.
    pub fn var(i: usize) -> Expr {
        Expr::Sym(Sym::Var(i as u32))
    }
    /// `der(y_i)`.
    pub fn der(i: usize) -> Expr {
        Expr::Sym(Sym::Der(i as u32))
    }
    /// Parameter `p_k`.
    pub fn param(k: usize) -> Expr {
        Expr::Sym(Sym::Param(k as u32))
    }

    /// The value if this is a number.
    pub fn as_num(&self) -> Option<&Q> {
        match self {
            Expr::Num(v) => Some(v),
            _ => None,
        }
    }
    /// `true` for the number zero.
    pub fn is_zero(&self) -> bool {
        self.as_num().is_some_and(|v| v.is_zero())
    }
    /// `true` for the number one.
    pub fn is_one(&self) -> bool {
        self.as_num().is_some_and(|v| v.is_one())
    }

    /// Does the expression depend on `s`?
    pub fn contains(&self, s: Sym) -> bool {
        if self.sym_mask() & sym_bit(s) == 0 {
            return false;
        }
        match self {
            Expr::Num(_) => false,
            Expr::Sym(t) => *t == s,
            Expr::Sum(sum) => sum.terms.iter().any(|(t, _)| t.contains(s)),
            Expr::Prod(p) => p.factors.iter().any(|(b, _)| b.contains(s)),
            Expr::Pow(p) => p.base.contains(s) || p.exponent.contains(s),
            Expr::Func(c) => c.arg.contains(s),
        }
    }

    /// Does the expression contain any symbol satisfying `pred`?
    ///
    /// A loop with an explicit stack that visits each shared node once: no
    /// recursion, and time linear in the number of distinct nodes.
    pub fn any_sym(&self, pred: &dyn Fn(Sym) -> bool) -> bool {
        let mut found = false;
        self.visit_syms(&mut |s| {
            found = found || pred(s);
            !found
        });
        found
    }

    /// All symbols, sorted.
    pub fn symbols(&self) -> Vec<Sym> {
        let mut out = std::collections::BTreeSet::new();
        self.visit_syms(&mut |s| {
            out.insert(s);
            true
        });
        out.into_iter().collect()
    }

    /// Call `f` on the symbols below, each distinct node visited once (a
    /// symbol may be reported more than once); stop when `f` returns
    /// `false`.
    /// Push the children onto an explicit walk's stack, last first, so
    /// that they come off it in order.
    fn push_children<'a>(&'a self, stack: &mut Vec<&'a Expr>) {
        match self {
            Expr::Sum(sum) => stack.extend(sum.terms.iter().rev().map(|(t, _)| t)),
            Expr::Prod(p) => stack.extend(p.factors.iter().rev().map(|(b, _)| b)),
            Expr::Pow(p) => {
                stack.push(&p.exponent);
                stack.push(&p.base);
            }
            Expr::Func(c) => stack.push(&c.arg),
            Expr::Num(_) | Expr::Sym(_) => {}
        }
    }

    fn visit_syms(&self, f: &mut dyn FnMut(Sym) -> bool) {
        // Below this size a walk of the tree is cheaper than remembering
        // the shared nodes.
        const SHARED: u64 = 4096;
        let remember = self.size() > SHARED;
        let mut seen: std::collections::HashSet<*const ()> = std::collections::HashSet::new();
        let mut stack: Vec<&Expr> = vec![self];
        while let Some(e) = stack.pop() {
            let ptr = match e {
                Expr::Num(_) => continue,
                Expr::Sym(s) => {
                    if !f(*s) {
                        return;
                    }
                    continue;
                }
                Expr::Sum(x) => Rc::as_ptr(x) as *const (),
                Expr::Prod(x) => Rc::as_ptr(x) as *const (),
                Expr::Pow(x) => Rc::as_ptr(x) as *const (),
                Expr::Func(x) => Rc::as_ptr(x) as *const (),
            };
            if remember && e.size() > 16 && !seen.insert(ptr) {
                continue;
            }
            e.push_children(&mut stack);
        }
    }

    /// A number in the expression — a constant, a coefficient, an
    /// exponent, or a number's power such as `2^2000` — that double
    /// precision cannot hold: its value overflows to an infinity (`1e400`)
    /// or, not zero, underflows to 0 (`1e-400`). Numbers are exact
    /// rationals while an expression is built (`1e-400*1e400*x` is `x`),
    /// but every evaluation uses the `f64` of each number left, so model
    /// checking refuses such a number as it refuses a parameter default of
    /// `1e-400`. A loop over the distinct nodes.
    ///
    /// ```
    /// use dae_core::expr::{mul, Expr, Q};
    /// use num_bigint::BigInt;
    /// let big = Q::from_integer(BigInt::from(10).pow(400));
    /// let e = mul(&Expr::Num(big.clone().into()), &Expr::var(0));
    /// let found = e.unrepresentable_number().unwrap();
    /// assert!(found.overflows && found.order == 400.0);
    /// let tiny = Expr::Num(big.recip().into());
    /// assert!(!tiny.unrepresentable_number().unwrap().overflows);
    /// // Exact arithmetic first: the product of the two is 1.
    /// assert!(mul(&e, &tiny).unrepresentable_number().is_none());
    /// ```
    pub fn unrepresentable_number(&self) -> Option<Unrepresentable> {
        let number = |q: &Q| {
            let f = q_to_f64(q);
            if f.is_finite() && (f != 0.0 || q.is_zero()) {
                return None;
            }
            // The decimal order from the bit lengths (the number may have
            // hundreds of digits).
            let bits = q.numer().bits() as f64 - q.denom().bits() as f64;
            Some(Unrepresentable {
                order: (bits * std::f64::consts::LOG10_2).round(),
                overflows: !f.is_finite(),
            })
        };
        let power = |b: &Expr, x: &Q| {
            let Expr::Num(b) = b else { return None };
            let v = pow_f64(q_to_f64(b), x);
            if v.is_nan() || (v.is_finite() && v != 0.0) {
                return None;
            }
            Some(Unrepresentable {
                order: (q_to_f64(x) * q_to_f64(b).abs().log10()).round(),
                overflows: !v.is_finite(),
            })
        };
        let mut seen: std::collections::HashSet<*const ()> = std::collections::HashSet::new();
        let mut stack: Vec<&Expr> = vec![self];
        while let Some(e) = stack.pop() {
            if let Some(key) = node_key(e) {
                if !seen.insert(key) {
                    continue;
                }
            }
            let bad = match e {
                Expr::Num(q) => number(q),
                Expr::Sum(sum) => std::iter::once(&sum.constant)
                    .chain(sum.terms.iter().map(|(_, c)| c))
                    .find_map(number),
                Expr::Prod(p) => p
                    .factors
                    .iter()
                    .find_map(|(b, x)| number(x).or_else(|| power(b, x))),
                Expr::Pow(_) | Expr::Func(_) | Expr::Sym(_) => None,
            };
            if bad.is_some() {
                return bad;
            }
            e.push_children(&mut stack);
        }
        None
    }

    /// The outermost subexpression free of symbols whose value is not a
    /// finite real number (`sqrt(-1)`, `ln(0)`, `(-8)^(1/3)`), if any.
    /// Such constants are valid expressions (they print and read back), but
    /// a model holding one fails every evaluation, so model checking
    /// refuses it. A loop over the distinct nodes, no recursion beyond
    /// [`Expr::eval`] of a constant.
    ///
    /// ```
    /// use dae_core::expr::{add, sqrt, Expr};
    /// let e = add(&Expr::var(0), &sqrt(&Expr::int(-1)));
    /// assert_eq!(e.non_finite_constant(), Some(sqrt(&Expr::int(-1))));
    /// assert_eq!(sqrt(&Expr::int(4)).non_finite_constant(), None);
    /// ```
    pub fn non_finite_constant(&self) -> Option<Expr> {
        let mut seen: std::collections::HashSet<*const ()> = std::collections::HashSet::new();
        let mut stack: Vec<&Expr> = vec![self];
        while let Some(e) = stack.pop() {
            let Some(key) = node_key(e) else {
                continue;
            };
            if !seen.insert(key) {
                continue;
            }
            if e.sym_mask() == 0 {
                if !e.eval(&|_| f64::NAN).is_finite() {
                    return Some(e.clone());
                }
                continue;
            }
            e.push_children(&mut stack);
        }
        None
    }

    /// Evaluate with `env` giving every symbol's value.
    pub fn eval(&self, env: &dyn Fn(Sym) -> f64) -> f64 {
        match self {
            Expr::Num(v) => q_to_f64(v),
            Expr::Sym(s) => env(*s),
            Expr::Sum(sum) => {
                let mut acc = q_to_f64(&sum.constant);
                for (t, c) in &sum.terms {
                    acc += q_to_f64(c) * t.eval(env);
                }
                acc
            }
            Expr::Prod(p) => p
                .factors
                .iter()
                .map(|(b, e)| pow_f64(b.eval(env), e))
                .product(),
            Expr::Pow(p) => p.base.eval(env).powf(p.exponent.eval(env)),
            Expr::Func(c) => c.func.apply(c.arg.eval(env)),
        }
    }
}

/// Nearest `f64` of a rational.
pub fn q_to_f64(v: &Q) -> f64 {
    if v.denom().is_one() {
        return v.numer().to_f64().unwrap_or(f64::NAN);
    }
    v.to_f64().unwrap_or_else(|| {
        let n = v.numer().to_f64().unwrap_or(f64::NAN);
        let d = v.denom().to_f64().unwrap_or(f64::NAN);
        n / d
    })
}

/// `x^e` for a rational exponent, using `powi`/`sqrt` where exact.
pub fn pow_f64(x: f64, e: &Q) -> f64 {
    if e.denom().is_one() {
        match e.numer().to_i32() {
            Some(1) => x,
            Some(k) => x.powi(k),
            None => x.powf(q_to_f64(e)),
        }
    } else if *e == qr(1, 2) {
        x.sqrt()
    } else if *e == qr(-1, 2) {
        1.0 / x.sqrt()
    } else {
        x.powf(q_to_f64(e))
    }
}

/// Split a term into `(coefficient, rest)` with `rest` not a number and not
/// a single-term sum. A number gives `(value, 1)`.
fn split_coefficient(e: &Expr) -> (Q, Expr) {
    match e {
        Expr::Num(v) => ((**v).clone(), Expr::one()),
        Expr::Sum(s) if s.constant.is_zero() && s.terms.len() == 1 => {
            (s.terms[0].1.clone(), s.terms[0].0.clone())
        }
        _ => (q(1), e.clone()),
    }
}

/// Build a sum from a collected map.
fn make_sum(constant: Q, map: BTreeMap<Expr, Q>) -> Expr {
    let terms: Vec<(Expr, Q)> = map.into_iter().filter(|(_, c)| !c.is_zero()).collect();
    if terms.is_empty() {
        return Expr::num(constant);
    }
    if constant.is_zero() && terms.len() == 1 && terms[0].1.is_one() {
        return terms
            .into_iter()
            .next()
            .map(|(t, _)| t)
            .unwrap_or_else(Expr::zero);
    }
    sum_node(terms, constant)
}

fn add_into(constant: &mut Q, map: &mut BTreeMap<Expr, Q>, e: &Expr, scale: &Q) {
    match e {
        Expr::Num(v) => q_add_to(constant, &q_mul(v, scale)),
        Expr::Sum(s) => {
            q_add_to(constant, &q_mul(&s.constant, scale));
            for (t, c) in &s.terms {
                q_add_to(
                    map.entry(t.clone()).or_insert_with(Q::zero),
                    &q_mul(c, scale),
                );
            }
        }
        _ => q_add_to(map.entry(e.clone()).or_insert_with(Q::zero), scale),
    }
}

/// `Σ c_k t_k` for the terms `[(c_k, t_k)]`, collected.
fn sum_of_terms(terms: &[(Q, Expr)]) -> Expr {
    let mut constant = Q::zero();
    let mut map = BTreeMap::new();
    for (c, t) in terms {
        add_into(&mut constant, &mut map, t, c);
    }
    make_sum(constant, map)
}

/// `Σ items`.
pub fn add_all<I: IntoIterator<Item = Expr>>(items: I) -> Expr {
    let mut constant = Q::zero();
    let mut map = BTreeMap::new();
    let one = q(1);
    for e in items {
        add_into(&mut constant, &mut map, &e, &one);
    }
    make_sum(constant, map)
}

/// `a + b`.
pub fn add(a: &Expr, b: &Expr) -> Expr {
    add_all([a.clone(), b.clone()])
}

/// `a − b`.
pub fn sub(a: &Expr, b: &Expr) -> Expr {
    let mut constant = Q::zero();
    let mut map = BTreeMap::new();
    add_into(&mut constant, &mut map, a, &q(1));
    add_into(&mut constant, &mut map, b, &q(-1));
    make_sum(constant, map)
}

/// `c · e` for a rational `c`.
pub fn scale(c: &Q, e: &Expr) -> Expr {
    if c.is_zero() {
        return Expr::zero();
    }
    let mut constant = Q::zero();
    let mut map = BTreeMap::new();
    add_into(&mut constant, &mut map, e, c);
    make_sum(constant, map)
}

/// `−e`.
pub fn neg(e: &Expr) -> Expr {
    scale(&q(-1), e)
}

/// Collected product factors: coefficient, bases with exponents, and sums
/// still to be distributed.
struct ProdBuilder {
    coef: Q,
    factors: BTreeMap<Expr, Q>,
    sums: Vec<Expr>,
}

impl ProdBuilder {
    fn new() -> Self {
        ProdBuilder {
            coef: q(1),
            factors: BTreeMap::new(),
            sums: Vec::new(),
        }
    }

    fn push_factor(&mut self, base: Expr, exp: Q) {
        q_add_to(self.factors.entry(base).or_insert_with(Q::zero), &exp);
    }

    fn push(&mut self, e: &Expr) {
        match e {
            Expr::Num(v) => q_mul_to(&mut self.coef, v),
            Expr::Prod(p) => {
                for (b, x) in &p.factors {
                    self.push_factor(b.clone(), x.clone());
                }
            }
            Expr::Sum(_) => {
                let (c, rest) = split_coefficient(e);
                if !matches!(rest, Expr::Sum(_)) {
                    q_mul_to(&mut self.coef, &c);
                    self.push(&rest);
                } else if self.factors.contains_key(e) {
                    // (a+b)^k · (a+b) merges exponents instead of expanding.
                    self.push_factor(e.clone(), q(1));
                } else if is_linear_form(e) {
                    // Kept as a factor, never distributed (see `is_linear_form`).
                    let (c, base) = normalise_linear(e);
                    q_mul_to(&mut self.coef, &c);
                    self.push_factor(base, q(1));
                } else {
                    self.sums.push(e.clone());
                }
            }
            _ => self.push_factor(e.clone(), q(1)),
        }
    }

    fn finish(mut self) -> Expr {
        if self.coef.is_zero() {
            return Expr::zero();
        }
        // A sum that also appears as a factor base merges with it.
        let mut sums = Vec::new();
        for s in std::mem::take(&mut self.sums) {
            if let Some(x) = self.factors.get_mut(&s) {
                q_add_to(x, &q(1));
            } else {
                sums.push(s);
            }
        }
        let mut factors: Vec<(Expr, Q)> = Vec::new();
        for (b, x) in std::mem::take(&mut self.factors) {
            if x.is_zero() {
                continue;
            }
            if let Expr::Num(v) = &b {
                // Integer powers of numbers fold into the coefficient.
                if x.denom().is_one() {
                    if let Some(k) = x.numer().to_i64() {
                        if let Some(p) = pow_q(v, k) {
                            q_mul_to(&mut self.coef, &p);
                            continue;
                        }
                    }
                }
            }
            factors.push((b, x));
        }
        let monomial = make_prod(factors);
        if sums.is_empty() {
            return scale(&self.coef, &monomial);
        }
        // Distribute over the sums while the result stays small. The
        // monomial is one term even when it is a lone linear form (a sum
        // node kept as a factor), so `acc` is a list of terms until the end.
        let mut acc: Vec<(Q, Expr)> = vec![(self.coef, monomial)];
        let mut kept = Vec::new();
        for s in sums {
            if acc.len() * term_count(&s) <= EXPANSION_LIMIT {
                acc = distribute(&acc, &s);
            } else {
                kept.push(s);
            }
        }
        if kept.is_empty() {
            return sum_of_terms(&acc);
        }
        // Keep the remaining sums as factors (bounded expansion).
        let (c, rest) = match acc.len() {
            1 => acc.swap_remove(0),
            _ => split_coefficient(&sum_of_terms(&acc)),
        };
        let mut factors: BTreeMap<Expr, Q> = BTreeMap::new();
        let mut push = |b: Expr| *factors.entry(b).or_insert_with(Q::zero) += q(1);
        match rest {
            Expr::Prod(p) => {
                for (b, x) in &p.factors {
                    q_add_to(factors.entry(b.clone()).or_insert_with(Q::zero), x);
                }
            }
            e if e.is_one() => {}
            e => push(e),
        }
        for s in kept {
            *factors.entry(s).or_insert_with(Q::zero) += q(1);
        }
        scale(
            &c,
            &make_prod(factors.into_iter().filter(|(_, x)| !x.is_zero()).collect()),
        )
    }
}

fn term_count(e: &Expr) -> usize {
    match e {
        Expr::Sum(s) => s.terms.len() + usize::from(!s.constant.is_zero()),
        _ => 1,
    }
}

/// Expand `(Σ c_k t_k) · b` for the terms `a = [(c_k, t_k)]` (each `t_k` one
/// monomial, possibly a lone linear form) and a sum `b`; the collected terms
/// of the product, its constant as a term `(c, 1)`.
fn distribute(a: &[(Q, Expr)], b: &Expr) -> Vec<(Q, Expr)> {
    if exhausted() {
        return Vec::new();
    }
    let parts = |e: &Expr| -> Vec<(Q, Expr)> {
        match e {
            Expr::Sum(s) => {
                let mut v: Vec<(Q, Expr)> = s
                    .terms
                    .iter()
                    .map(|(t, c)| (c.clone(), t.clone()))
                    .collect();
                if !s.constant.is_zero() {
                    v.push((s.constant.clone(), Expr::one()));
                }
                v
            }
            _ => {
                let (c, r) = split_coefficient(e);
                vec![(c, r)]
            }
        }
    };
    let pb = parts(b);
    let mut constant = Q::zero();
    let mut map = BTreeMap::new();
    for (ca, ta) in a {
        for (cb, tb) in &pb {
            let prod = mul_monomials(ta, tb);
            add_into(&mut constant, &mut map, &prod, &q_mul(ca, cb));
        }
    }
    let mut terms: Vec<(Q, Expr)> = map
        .into_iter()
        .filter(|(_, c)| !c.is_zero())
        .map(|(t, c)| (c, t))
        .collect();
    if !constant.is_zero() {
        terms.push((constant, Expr::one()));
    }
    terms
}

/// Whether `e` is a linear form in the unknowns: a sum of at least two
/// terms, each a rational multiple of one unknown `y_i` (`x₂ − x₁`,
/// `2u − v`, `λ₁ + λ₃ + λ₅`), with no constant, parameter, time or `der()`.
///
/// Such a sum is kept whole as a factor of a product and as the base of an
/// integer power, instead of being distributed: the form a model writes,
/// `(x₂ − x₁)² + (y₂ − y₁)² − l²`, is then evaluated as written. Expanded,
/// it is `x₂² + x₁² − 2x₁x₂ + …`, whose terms are of the size of the
/// coordinates squared and cancel to `l²`: with coordinates of 400 and links
/// of 1, the residual cannot be evaluated below about 2⁻³⁴, and a
/// constrained solver amplifies that floor into its multipliers (BENCHMARKS
/// §14, "Why radau5(ggl1) fails at N = 400"). Derivatives keep the form too:
/// `∂/∂x₂ (x₂ − x₁)² = 2x₂ − 2x₁` and the hidden constraint is
/// `2u₂(x₂ − x₁) − 2u₁(x₂ − x₁) + …`, whose terms are of the size of the
/// velocities, not of the coordinates times the velocities.
///
/// Only unknowns: a sum holding a number, a parameter or time (`x − 1`,
/// `e − eₐ`, `η + 1`) is distributed as before. The accuracy the factored
/// form buys is that of a difference of two states that grow together (the
/// chain's coordinates), and keeping the other sums was measured to cost (BENCHMARKS §14,
/// "Linear forms kept factored, restricted to the unknowns"): Andrews'
/// squeezer writes `m₆ u (z_f − f_a) ω̈ sin ω` with parameters `z_f`, `f_a`,
/// and kept factored there its `mex0` rows stop `radau5` at 1e-10 on a
/// Newton stall of `ω̈` (`tests/mex0.rs`); and a model mixing `η y₂` with
/// `(1 + η) y₂`, as Gear–Hsu–Petzold does, no longer cancels `η y₂` in
/// its hidden constraint.
///
/// What this gives up: a polynomial identity that needs a linear form in
/// the unknowns multiplied out (`(x + y)(x − y) = x² − y²`,
/// `λ(x₂ − x₁) = λx₂ − λx₁`) is no longer decided by structural equality.
/// The identities the derivation relies on — the cancellations of
/// monomials after substituting a dynamics, as in the pendulum's
/// `d/dt (2xu + 2yv)` — are still decided: a product with a sum that is not
/// a linear form is distributed as before, the linear forms staying factors
/// of every term.
///
/// ```
/// use dae_core::expr::{is_linear_form, mul, pow, sub, Expr};
/// let d = sub(&Expr::var(1), &Expr::var(0));
/// assert!(is_linear_form(&d));
/// // Its square stays a power of the (normalised) difference.
/// assert!(matches!(pow(&d, &Expr::int(2)), Expr::Prod(_)));
/// assert!(!is_linear_form(&mul(&d, &Expr::var(2))));
/// // A sum with a number or a parameter is not one, and is distributed.
/// assert!(!is_linear_form(&sub(&Expr::var(0), &Expr::int(1))));
/// assert!(!is_linear_form(&sub(&Expr::var(0), &Expr::param(0))));
/// assert!(matches!(pow(&sub(&Expr::var(0), &Expr::int(1)), &Expr::int(2)), Expr::Sum(_)));
/// ```
pub fn is_linear_form(e: &Expr) -> bool {
    let Expr::Sum(s) = e else {
        return false;
    };
    s.constant.is_zero()
        && s.terms.len() >= 2
        && s.terms
            .iter()
            .all(|(t, _)| matches!(t, Expr::Sym(Sym::Var(_))))
}

/// A linear form `e` as `c · base`, with `base` of content 1 and its first
/// term's coefficient positive, so that every multiple of one form is a
/// multiple of the same `base`.
fn normalise_linear(e: &Expr) -> (Q, Expr) {
    let Expr::Sum(s) = e else {
        return (q(1), e.clone());
    };
    let mut c = content(e);
    if s.terms.first().is_some_and(|(_, k)| k.is_negative()) {
        c = -c;
    }
    if c.is_one() {
        return (c, e.clone());
    }
    (c.clone(), scale(&c.recip(), e))
}

/// Product of two non-sum expressions.
fn mul_monomials(a: &Expr, b: &Expr) -> Expr {
    let mut pb = ProdBuilder::new();
    pb.push(a);
    pb.push(b);
    pb.finish()
}

fn make_prod(factors: Vec<(Expr, Q)>) -> Expr {
    if factors.is_empty() {
        return Expr::one();
    }
    if factors.len() == 1 && factors[0].1.is_one() {
        return factors
            .into_iter()
            .next()
            .map(|(b, _)| b)
            .unwrap_or_else(Expr::one);
    }
    prod_node(factors)
}

/// `v^k` exactly, for moderate integer `k`; `None` for `0^negative` or huge
/// exponents.
fn pow_q(v: &Q, k: i64) -> Option<Q> {
    if k.abs() > 64 {
        return None;
    }
    if v.is_zero() && k < 0 {
        return None;
    }
    let mut r = q(1);
    for _ in 0..k.abs() {
        q_mul_to(&mut r, v);
    }
    if k < 0 {
        r = r.recip();
    }
    Some(r)
}

/// `Π items`.
pub fn mul_all<I: IntoIterator<Item = Expr>>(items: I) -> Expr {
    let mut pb = ProdBuilder::new();
    for e in items {
        if e.is_zero() {
            return Expr::zero();
        }
        pb.push(&e);
    }
    pb.finish()
}

/// `a · b`.
pub fn mul(a: &Expr, b: &Expr) -> Expr {
    mul_all([a.clone(), b.clone()])
}

/// `a / b`.
pub fn div(a: &Expr, b: &Expr) -> Expr {
    mul(a, &pow(b, &Expr::int(-1)))
}

/// `base ^ exponent`.
pub fn pow(base: &Expr, exponent: &Expr) -> Expr {
    let Some(x) = exponent.as_num() else {
        if base.is_one() {
            return Expr::one();
        }
        return pow_node(base.clone(), exponent.clone());
    };
    pow_rational(base, x)
}

/// `base ^ x` for a rational exponent.
pub fn pow_rational(base: &Expr, x: &Q) -> Expr {
    if x.is_zero() {
        return Expr::one();
    }
    if x.is_one() {
        return base.clone();
    }
    let integer = x.denom().is_one();
    match base {
        Expr::Num(v) => {
            if integer {
                if let Some(k) = x.numer().to_i64() {
                    if let Some(p) = pow_q(v, k) {
                        return Expr::num(p);
                    }
                }
            } else if let Some(r) = exact_root(v, x) {
                return Expr::num(r);
            }
            make_prod(vec![(base.clone(), x.clone())])
        }
        Expr::Prod(p) if integer => {
            let factors = p
                .factors
                .iter()
                .map(|(b, e)| (b.clone(), q_mul(e, x)))
                .collect::<Vec<_>>();
            let mut pb = ProdBuilder::new();
            for (b, e) in factors {
                pb.push_factor(b, e);
            }
            pb.finish()
        }
        Expr::Sum(_) => {
            let (c, rest) = split_coefficient(base);
            if !matches!(rest, Expr::Sum(_)) && integer {
                let k = x.numer().to_i64().unwrap_or(i64::MAX);
                if let Some(ck) = pow_q(&c, k) {
                    return scale(&ck, &pow_rational(&rest, x));
                }
            }
            if integer && is_linear_form(base) {
                // An integer power of a linear form stays factored (see
                // `is_linear_form`), on the normalised base.
                let (c, b) = normalise_linear(base);
                if let Some(ck) = x.numer().to_i64().and_then(|k| pow_q(&c, k)) {
                    return scale(&ck, &make_prod(vec![(b, x.clone())]));
                }
            }
            if integer {
                if let Some(k) = x.numer().to_i64() {
                    if (2..=POWER_EXPANSION_LIMIT).contains(&k) {
                        let mut acc = base.clone();
                        for _ in 1..k {
                            acc = mul(&acc, base);
                        }
                        return acc;
                    }
                    if (2..=POWER_EXPANSION_LIMIT).contains(&-k) {
                        // `s^-k` is `1/(s^k)` with `s^k` expanded as above,
                        // so that `1/(x+y)^2` has one canonical form however
                        // it was built.
                        let expanded = pow_rational(base, &-x);
                        return pow_rational(&expanded, &q(-1));
                    }
                }
            }
            make_prod(vec![(base.clone(), x.clone())])
        }
        Expr::Prod(_) => pow_node(base.clone(), Expr::num(x.clone())),
        _ => make_prod(vec![(base.clone(), x.clone())]),
    }
}

/// Exact rational root `v^x` when `v` is a perfect power (e.g. `4^(1/2)`).
fn exact_root(v: &Q, x: &Q) -> Option<Q> {
    if v.is_negative() {
        return None;
    }
    let d = x.denom().to_u32()?;
    if d > 8 {
        return None;
    }
    let root = |n: &BigInt| -> Option<BigInt> {
        let r = n.nth_root(d);
        if r.pow(d) == *n {
            Some(r)
        } else {
            None
        }
    };
    let rn = root(v.numer())?;
    let rd = root(v.denom())?;
    let base = Q::new(rn, rd);
    pow_q(&base, x.numer().to_i64()?)
}

/// `sqrt(e)` = `e^(1/2)`.
pub fn sqrt(e: &Expr) -> Expr {
    pow_rational(e, &qr(1, 2))
}

/// Apply an elementary function, folding the exact cases
/// (`sin 0 = 0`, `cos 0 = 1`, `exp 0 = 1`, `ln 1 = 0`).
pub fn func(f: Func, arg: &Expr) -> Expr {
    match (f, arg.as_num()) {
        (Func::Sin | Func::Tan, Some(v)) if v.is_zero() => Expr::zero(),
        (Func::Cos | Func::Exp, Some(v)) if v.is_zero() => Expr::one(),
        (Func::Ln, Some(v)) if v.is_one() => Expr::zero(),
        _ => call_node(f, arg.clone()),
    }
}

/// `∂e/∂s`.
pub fn diff(e: &Expr, s: Sym) -> Expr {
    // Below this size a walk of the tree costs less than remembering the
    // shared nodes (the tree's size bounds the work without the memo).
    const SHARED: u64 = 4096;
    let mut memo = Memo {
        on: e.size() > SHARED,
        map: HashMap::new(),
    };
    diff_memo(e, s, &mut memo)
}

/// Derivatives of shared nodes met so far in one [`diff`], when on.
struct Memo {
    on: bool,
    map: HashMap<*const (), Expr>,
}

/// Key of a compound node for the memo of [`diff_memo`]: its address (the
/// node is alive for the whole call, borrowed from `e`).
fn node_key(e: &Expr) -> Option<*const ()> {
    match e {
        Expr::Num(_) | Expr::Sym(_) => None,
        Expr::Sum(x) => Some(Rc::as_ptr(x) as *const ()),
        Expr::Prod(x) => Some(Rc::as_ptr(x) as *const ()),
        Expr::Pow(x) => Some(Rc::as_ptr(x) as *const ()),
        Expr::Func(x) => Some(Rc::as_ptr(x) as *const ()),
    }
}

/// [`diff`] remembering the derivative of every shared node it has met
/// (pasted definitions make a tree share its subtrees: without the memo a
/// chain `d_i = sin(d_{i-1}) + d_{i-1}*x` differentiates `2^n` times).
fn diff_memo(e: &Expr, s: Sym, memo: &mut Memo) -> Expr {
    // Small subtrees are cheaper to differentiate again than to remember.
    let key = node_key(e).filter(|_| memo.on && e.size() > 64);
    if let Some(d) = key.and_then(|k| memo.map.get(&k)) {
        return d.clone();
    }
    let d = diff_node(e, s, memo);
    if let Some(k) = key {
        memo.map.insert(k, d.clone());
    }
    d
}

fn diff_node(e: &Expr, s: Sym, memo: &mut Memo) -> Expr {
    // A subtree without `s` differentiates to zero; the mask says so
    // without a walk (a walk per level would make a deep chain quadratic).
    if e.sym_mask() & sym_bit(s) == 0 || exhausted() {
        return Expr::zero();
    }
    count_work();
    match e {
        Expr::Num(_) => Expr::zero(),
        Expr::Sym(t) => {
            if *t == s {
                Expr::one()
            } else {
                Expr::zero()
            }
        }
        Expr::Sum(sum) => add_all(
            sum.terms
                .iter()
                .map(|(t, c)| scale(c, &diff_memo(t, s, memo))),
        ),
        Expr::Prod(p) => {
            let mut terms = Vec::new();
            for (i, (b, x)) in p.factors.iter().enumerate() {
                let db = diff_memo(b, s, memo);
                if db.is_zero() {
                    continue;
                }
                let mut items = vec![Expr::num(x.clone()), pow_rational(b, &q_add(x, &q(-1))), db];
                for (j, (bj, xj)) in p.factors.iter().enumerate() {
                    if j != i {
                        items.push(pow_rational(bj, xj));
                    }
                }
                terms.push(mul_all(items));
            }
            add_all(terms)
        }
        Expr::Pow(p) => {
            // d(b^e) = b^e · (e' ln b + e b'/b)
            let (b, x) = (&p.base, &p.exponent);
            let inner = add(
                &mul(&diff_memo(x, s, memo), &func(Func::Ln, b)),
                &mul_all([x.clone(), diff_memo(b, s, memo), pow_rational(b, &q(-1))]),
            );
            mul(e, &inner)
        }
        Expr::Func(_) => {
            // The chain rule along a whole chain f(g(h(…))) at once: one
            // product of the outer derivatives, instead of a product per
            // link rebuilt from the one below it.
            let mut factors = Vec::new();
            let mut link = e;
            while let Expr::Func(c) = link {
                factors.push(outer_derivative(c, link));
                link = &c.arg;
            }
            factors.push(diff_memo(link, s, memo));
            mul_all(factors)
        }
    }
}

/// `f'(a)` for the call `e = f(a)`.
pub(crate) fn outer_derivative(c: &Call, e: &Expr) -> Expr {
    let a = &c.arg;
    match c.func {
        Func::Sin => func(Func::Cos, a),
        Func::Cos => neg(&func(Func::Sin, a)),
        Func::Tan => add(&Expr::one(), &pow_rational(e, &q(2))),
        Func::Exp => e.clone(),
        Func::Ln => pow_rational(a, &q(-1)),
    }
}

/// An expression linear in der() split into its der() terms and the rest:
/// `e = Σ_j c_j der(y_j) + r` gives `([(j, c_j)], r)`, `j` ascending, with
/// `c_j = ∂e/∂der(y_j)` and `r = e` at every der() zero. (Linearity is the
/// caller's to check: a `c_j` that still holds der() means `e` is not.)
pub fn split_ders(e: &Expr) -> (Vec<(usize, Expr)>, Expr) {
    let is_der = |s: Sym| matches!(s, Sym::Der(_));
    if !e.any_sym(&is_der) {
        return (Vec::new(), e.clone());
    }
    let terms = e
        .symbols()
        .into_iter()
        .filter_map(|s| match s {
            Sym::Der(j) => Some((j as usize, diff(e, s))),
            _ => None,
        })
        .collect();
    (terms, subs(e, &|s| is_der(s).then(Expr::zero)))
}

/// Replace symbols: `map(s)` returns the replacement or `None` to keep `s`.
pub fn subs(e: &Expr, map: &dyn Fn(Sym) -> Option<Expr>) -> Expr {
    if exhausted() {
        return Expr::zero();
    }
    count_work();
    match e {
        Expr::Num(_) => e.clone(),
        Expr::Sym(s) => map(*s).unwrap_or_else(|| e.clone()),
        Expr::Sum(sum) => {
            let mut items: Vec<Expr> = sum
                .terms
                .iter()
                .map(|(t, c)| scale(c, &subs(t, map)))
                .collect();
            items.push(Expr::num(sum.constant.clone()));
            add_all(items)
        }
        Expr::Prod(p) => mul_all(
            p.factors
                .iter()
                .map(|(b, x)| pow_rational(&subs(b, map), x)),
        ),
        Expr::Pow(p) => pow(&subs(&p.base, map), &subs(&p.exponent, map)),
        Expr::Func(c) => func(c.func, &subs(&c.arg, map)),
    }
}

/// The numeric content of an expression: a positive rational `c` such that
/// `e / c` has integer coefficients with gcd 1 (1 where there is none).
pub fn content(e: &Expr) -> Q {
    match e {
        Expr::Num(v) => v.abs(),
        Expr::Sum(s) => {
            let mut g: Option<Q> = None;
            let all = s
                .terms
                .iter()
                .map(|(_, c)| c)
                .chain(std::iter::once(&s.constant));
            for c in all.filter(|c| !c.is_zero()) {
                g = Some(match g {
                    None => c.abs(),
                    Some(g) => gcd_q(&g, c),
                });
            }
            g.unwrap_or_else(|| q(1))
        }
        _ => q(1),
    }
}

/// gcd of two rationals: gcd of numerators over lcm of denominators.
pub fn gcd_q(a: &Q, b: &Q) -> Q {
    let n = a.numer().gcd(b.numer());
    let d = a.denom().lcm(b.denom());
    Q::new(n, d)
}

/// Total time derivative along the dynamics: `dt(e) = ∂e/∂t + Σ ∂e/∂s · ṡ`,
/// where `rate(s)` gives `ṡ` for every symbol `e` depends on (`None` for
/// constants such as parameters). Returns the offending symbol if a rate is
/// needed but unavailable.
pub fn time_derivative(
    e: &Expr,
    rate: &dyn Fn(Sym) -> Result<Option<Expr>, Sym>,
) -> Result<Expr, Sym> {
    let mut terms = Vec::new();
    for s in e.symbols() {
        let r = match s {
            Sym::Time => Some(Expr::one()),
            Sym::Param(_) => None,
            _ => rate(s)?,
        };
        if let Some(r) = r {
            terms.push(mul(&diff(e, s), &r));
        }
    }
    Ok(add_all(terms))
}

impl fmt::Display for Sym {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Sym::Var(i) => write!(f, "y{i}"),
            Sym::Der(i) => write!(f, "der(y{i})"),
            Sym::Param(k) => write!(f, "p{k}"),
            Sym::Time => write!(f, "t"),
            Sym::Dir(i) => write!(f, "z{i}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn x() -> Expr {
        Expr::var(0)
    }
    fn y() -> Expr {
        Expr::var(1)
    }

    /// The machine-integer paths of `q_mul` and `q_add` give `num_rational`'s
    /// exact, reduced results, and their hash is that of the same value
    /// built the slow way: at zero, one, signs, common denominators, at the
    /// edge of [`SMALL_Q`] and past it, where the big-integer path takes
    /// over.
    #[test]
    fn small_rational_fast_paths_agree_with_big_rationals() {
        let edge = SMALL_Q as i64;
        let values = [
            q(0),
            q(1),
            q(-1),
            q(7),
            qr(-3, 2),
            qr(1, 2),
            qr(5, 6),
            qr(-4, 9),
            q(edge - 1),
            qr(1, edge - 1),
            qr(-(edge - 1), 3),
            q(edge),
            qr(edge + 1, 2),
            Q::new(BigInt::from(i64::MAX) * 3, BigInt::from(5)),
        ];
        let hash = |v: &Q| {
            let mut h = Fnv::new();
            hash_q(v, &mut h);
            h.finish()
        };
        for a in &values {
            for b in &values {
                let (m, s) = (q_mul(a, b), q_add(a, b));
                assert_eq!(m, a * b, "{a} · {b}");
                assert_eq!(s, a + b, "{a} + {b}");
                // Reduced as `Q::new` reduces: the same numerator and
                // denominator, so the same hash.
                assert_eq!((m.numer(), m.denom()), ((a * b).numer(), (a * b).denom()));
                assert_eq!((s.numer(), s.denom()), ((a + b).numer(), (a + b).denom()));
                assert_eq!(hash(&m), hash(&(a * b)), "{a} · {b}");
                let mut acc = a.clone();
                q_add_to(&mut acc, b);
                q_mul_to(&mut acc, b);
                assert_eq!(acc, (a + b) * b, "({a} + {b}) · {b}");
            }
        }
    }

    #[test]
    fn like_terms_collect() {
        let e = add_all([
            mul(&Expr::int(2), &x()),
            x(),
            neg(&mul(&Expr::int(3), &x())),
        ]);
        assert!(e.is_zero());
        let half = div(&x(), &Expr::int(2));
        assert_eq!(add(&half, &half), x());
    }

    #[test]
    fn products_merge_and_cancel() {
        let m = Expr::param(0);
        let e = mul(&mul(&m, &x()), &div(&Expr::one(), &m));
        assert_eq!(e, x());
    }

    #[test]
    fn expansion_decides_polynomial_identities() {
        // Sums that are not linear forms are expanded: (x² + y)² …
        let x2 = pow(&x(), &Expr::int(2));
        let s = add(&x2, &y());
        let lhs = pow(&s, &Expr::int(2));
        let rhs = add_all([
            pow(&x(), &Expr::int(4)),
            mul_all([Expr::int(2), x2.clone(), y()]),
            pow(&y(), &Expr::int(2)),
        ]);
        assert_eq!(lhs, rhs);
        // … and so is a product of a monomial with one:
        // x (x² − y) = x³ − xy.
        let prod = mul(&x(), &sub(&x2, &y()));
        let expanded = sub(&pow(&x(), &Expr::int(3)), &mul(&x(), &y()));
        assert!(sub(&prod, &expanded).is_zero());
        // A linear form times such a sum distributes the sum, keeping the
        // form as a factor of every term: (x − y)(x² − y) = x²(x − y) − y(x − y).
        let l = sub(&x(), &y());
        let prod = mul(&l, &sub(&x2, &y()));
        let kept = sub(&mul(&x2, &l), &mul(&y(), &l));
        assert!(sub(&prod, &kept).is_zero());
    }

    #[test]
    fn linear_forms_stay_factored_and_normalised() {
        let d = sub(&y(), &x());
        assert!(is_linear_form(&d));
        // (y − x)² is one power of the normalised base, however it is built.
        let sq = pow(&d, &Expr::int(2));
        assert!(matches!(&sq, Expr::Prod(p) if p.factors.len() == 1));
        assert_eq!(sq, pow(&sub(&x(), &y()), &Expr::int(2)));
        assert_eq!(sq, mul(&d, &d));
        let twice = scale(&q(2), &d);
        assert_eq!(sq, mul(&Expr::num(qr(1, 4)), &pow(&twice, &Expr::int(2))));
        // Odd powers keep the sign in the coefficient.
        assert_eq!(
            pow(&d, &Expr::int(3)),
            neg(&pow(&sub(&x(), &y()), &Expr::int(3)))
        );
        // A symbol times a linear form is a product, a number times one a sum.
        let p = Expr::param(0);
        assert!(matches!(mul(&p, &sub(&x(), &y())), Expr::Prod(_)));
        assert!(matches!(&twice, Expr::Sum(s) if s.terms.len() == 2));
        // The derivative of the square is a multiple of the form.
        assert_eq!(diff(&sq, Sym::Var(1)), twice);
        // Evaluated as written: at x = 400.1, y = 401.3 the square is the
        // square of the rounded difference to a few ulps, where the
        // expanded x² − 2xy + y² would cancel terms of 1.6e5 to about 1.44.
        let env = |s: Sym| match s {
            Sym::Var(0) => 400.1,
            Sym::Var(1) => 401.3,
            _ => 1.0,
        };
        let dv = 401.3f64 - 400.1;
        assert!((sq.eval(&env) - dv * dv).abs() <= 4.0 * f64::EPSILON * dv * dv);
        // A quotient by a linear form cancels against it.
        assert_eq!(
            mul(&d, &pow(&sub(&x(), &y()), &Expr::int(-1))),
            Expr::int(-1)
        );
    }

    #[test]
    fn sums_with_numbers_or_parameters_are_distributed() {
        let (e, ea) = (Expr::param(0), Expr::param(1));
        // A difference of parameters (Andrews' `e − ea`) is expanded, as a
        // factor and as a square …
        let d = sub(&e, &ea);
        assert!(!is_linear_form(&d));
        assert_eq!(mul(&d, &x()), sub(&mul(&e, &x()), &mul(&ea, &x())));
        assert_eq!(
            pow(&d, &Expr::int(2)),
            add_all([
                pow(&e, &Expr::int(2)),
                mul_all([Expr::int(-2), e.clone(), ea.clone()]),
                pow(&ea, &Expr::int(2)),
            ])
        );
        // … and so are `x − 1` and `x − p`.
        for b in [sub(&x(), &Expr::one()), sub(&x(), &e)] {
            assert!(!is_linear_form(&b));
            assert!(matches!(pow(&b, &Expr::int(2)), Expr::Sum(s) if s.terms.len() >= 2));
        }
        // Gear–Hsu–Petzold's hidden constraint: η y₂ − (η + 1) y₂ = −y₂.
        let (eta, y2) = (Expr::param(2), y());
        let mixed = sub(&mul(&eta, &y2), &mul(&add(&eta, &Expr::one()), &y2));
        assert_eq!(mixed, neg(&y2));
        // A sum of unknowns with a constant is not a linear form either.
        assert!(!is_linear_form(&add(&sub(&x(), &y()), &Expr::one())));
    }

    #[test]
    fn derivatives() {
        let e = mul(&func(Func::Sin, &x()), &pow(&x(), &Expr::int(2)));
        let d = diff(&e, Sym::Var(0));
        let v = d.eval(&|_| 0.7);
        let exact = 0.7f64.cos() * 0.49 + 0.7f64.sin() * 1.4;
        assert!((v - exact).abs() < 1e-15);
        assert!(diff(&e, Sym::Var(1)).is_zero());
    }

    #[test]
    fn exact_roots_and_content() {
        assert_eq!(sqrt(&Expr::int(4)), Expr::int(2));
        let e = add(&mul(&Expr::int(4), &x()), &mul(&Expr::int(6), &y()));
        assert_eq!(content(&e), q(2));
    }
}
