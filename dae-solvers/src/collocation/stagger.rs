//! The staggered corrector of forward sensitivities (IDAS's
//! `IDA_STAGGERED`, here for Radau IIA).
//!
//! A system of a state and its sensitivities
//! ([`dae_core::sensitivity::SensitivitySystem`]) declares
//! [`Blocks`] and offers its state alone
//! ([`DaeSystem::first_block`]). Its stage equations are then solved in
//! two phases per step attempt, both with the state's factorised iteration
//! matrices `γ/h E₀ − J₀` and `(α + iβ)/h E₀ − J₀` (one real and one complex
//! LU of the state's size, [`crate::core::block`]):
//!
//! 1. the state's stages by the simplified Newton iteration of the plain
//!    run — the state's own residual, Jacobian and Newton norm, so that
//!    with the sensitivities out of the error test the state takes the
//!    plain run's steps, to the bit; its kernels run on compact buffers of
//!    the state's rows alone (`Stagger::exchange`), not over all
//!    `N (1 + P)` unknowns;
//! 2. with the state's stages fixed, the sensitivities' stage equations
//!    `E Sᵢ'(c_k) = J(Y_k) Sᵢ(c_k) + ∂f/∂pᵢ(Y_k)`, linear in the
//!    sensitivity stages, by the same simplified Newton iteration with
//!    `J₀` in place of each `J(Y_k)` (a contraction of the order of the
//!    state's: about three iterations a step on the pendulum, BENCHMARKS.md
//!    §13d). `[J | ∂f/∂p]` at the three stage points is evaluated once
//!    ([`DaeSystem::first_block_linearisation`]) and each iteration's
//!    residuals are products with it (a system that offers no
//!    linearisation gets its whole residual, [`DaeSystem::rhs_tangents`]'s
//!    forward pass, instead), then `P` solves by the same LUs. The state's
//!    increment is zero there, so the sub-diagonal blocks `Bᵢ` of the
//!    simultaneous corrector are never formed: a Jacobian is the state's
//!    alone.
//!
//! Phase 2 cannot be one solve with the state's factorisations: those
//! hold `J₀` (the Jacobian the state reuses, often from earlier steps),
//! the sensitivities' equations `J(Y_k)` at each stage point, and the
//! difference couples the three stages. Solved exactly, they are one
//! `3N × 3N` linear system per attempt, shared by the `P` parameters
//! (`Direct`), sparse (`E₀` in every block, `J` in the diagonal ones) and
//! factorised on its non-zeros alone ([`PatternLu`]): for small states
//! (`DIRECT_MAX`) that is cheaper than iterating even one parameter, and
//! it is exact where the iteration stops at its Newton bound. The
//! iteration stays for larger states.
//!
//! The sensitivities' iteration has its own contraction monitor (its `η`
//! carried across steps like the state's) and its own weights: every
//! sensitivity is in its convergence test whether or not it is in the
//! error test, as in IDAS ("in any event, all variables are considered in
//! the convergence tests", `IDASetSensErrCon`). A sensitivity iteration
//! that diverges or is too slow fails the attempt as the state's would.
//! The error estimate is the method's over every component in the test;
//! with the sensitivities out of it, only the state's part is computed.

use super::solve::StageSolveKind;
use super::stages::Newton;
use super::step::Integrator;
use super::tableau::{Collocation, NewtonStop};
use super::UROUND;
use crate::core::block::Part;
use crate::core::matrix::Matrix;
use crate::core::newton::{Contraction, Verdict};
use crate::core::weights::{self, Plain, Weights};
use crate::linalg::{with_size, PatternLu};
use crate::options::Options;
use dae_core::system::{Blocks, DaeSystem};
use nalgebra::DMatrix;

/// The staggered corrector's state (see the [module documentation](self)).
pub(super) struct Stagger {
    /// Unknowns of the state, `N` (its rows too: the state is square).
    pub(super) size: usize,
    /// Whether the sensitivities are in the error test.
    pub(super) error_control: bool,
    /// The state's Newton weights (`N`, all in the norm).
    state_weights: Weights<Plain>,
    /// The sensitivities' Newton weights (all unknowns, the state's out).
    sens_weights: Weights<Plain>,
    /// The state's Jacobian (`N × N`).
    jac: DMatrix<f64>,
    /// `[∂f/∂y | ∂f/∂p]` of the state's rows at the three stage points
    /// (`N × (N + P)` each, [`DaeSystem::first_block_linearisation`]).
    lin: [DMatrix<f64>; 3],
    /// The sensitivities' contraction monitor.
    pub(super) newton: Contraction,
    /// The exact solve of the sensitivities' stage equations, for a state
    /// of at most [`DIRECT_MAX`] unknowns; `None`: the iteration.
    direct: Option<Direct>,
    /// The state phase's stage buffers `Z, G, ΔW, Y, Y'` (`3N` each, the
    /// state's rows alone), exchanged with the step loop's for that phase
    /// ([`Stagger::exchange`]): its kernels run over `N` unknowns, not
    /// `N (1 + P)`.
    compact: [Vec<f64>; 5],
}

/// When the sensitivities' stage equations are solved exactly
/// ([`Direct`]) rather than iterated: a state of at most `DIRECT_MAX`
/// unknowns. The exact solve's `3N × 3N` factorisation is shared by the
/// parameters and each then costs one solve; the iteration costs each
/// parameter about three iterations of products, transforms and two
/// solves. On the pendulum (`N = 5`, rcd0, BENCHMARKS.md §13f, §21) the
/// exact solve on the matrix's non-zeros ([`PatternLu`]: 69 of 225, 167
/// updates in the variable-major order where a dense LU makes 1 015)
/// costs about 3 200 instructions an attempt for the factorisation and
/// 600 for the matrix, and 1 300 a parameter for the solve, where the
/// iteration costs about 8 400 a parameter: the exact solve is cheaper
/// from one parameter on (§13e's dense 15 × 15 LU cost 10 600, and kept
/// the iteration for one). The
/// factorisation grows faster than the iteration with `N`: above 12
/// unknowns (not measured) the iteration stays.
const DIRECT_MAX: usize = 12;

/// With one parameter the exact solve is kept when its elimination makes
/// at most this many updates per `N²` (judged on its first factorisation;
/// the iteration otherwise). Measured on the pendulum (BENCHMARKS.md
/// §13f, §21): rcd0 (`N = 5`, 167 updates, 6.7 `N²`) is cheaper exact
/// (236.7 M instructions; the iteration 265.8 M in §13f), ggl1 (`N = 6`)
/// dearer (259.4 M against the iteration's 254.5 M with §21's solve).
/// Two points: a rough boundary, not a model.
const ONE_PARAMETER_UPDATES: usize = 9;

/// The sensitivities' stage equations with the state's stages fixed,
///
/// ```text
///     Σ_j (a⁻¹_kj / h) E Zᵢ_j − J(Y_k) Zᵢ_k = J(Y_k) sᵢ + ∂f/∂pᵢ(Y_k),   k = 1, 2, 3,
/// ```
///
/// linear in the stage increments `Zᵢ` of each parameter, with one
/// `3N × 3N` matrix shared by the `P` parameters: factorised once per
/// attempt and solved once per parameter, exactly, where the iteration
/// replaces each `J(Y_k)` by `J₀` and iterates on the difference.
struct Direct {
    /// The matrix, then its factors: unknowns and rows variable-major
    /// (the three stages of each unknown, of each equation, together; see
    /// [`Direct::at`]); its pattern is `E₀`'s in every stage block and
    /// `J`'s in the diagonal ones (`N = 5` on the pendulum: 69 non-zeros
    /// of 225).
    lu: PatternLu,
    /// Where `stage_matrix` writes: each structural non-zero of `E₀` (its
    /// place in `E`'s storage, leading dimension `m`) with its nine
    /// entries `(k, j)`, and each of `J` (its place in `[J | ∂f/∂p]`)
    /// with its three diagonal-block entries.
    e_at: Vec<EntryAt<9>>,
    j_at: Vec<EntryAt<3>>,
    /// One stage's right-hand side (`N`).
    rhs: Vec<f64>,
    /// The right-hand side by rows, then the increments by unknowns
    /// (`3N`, variable-major).
    x: Vec<f64>,
    /// Whether its cost for one parameter has been judged
    /// ([`ONE_PARAMETER_UPDATES`]).
    judged: bool,
}

/// A structural non-zero's place in its source matrix and its `K`
/// positions in [`Direct`]'s matrix.
type EntryAt<const K: usize> = (usize, [u16; K]);

impl Direct {
    /// The exact solve of a state of `size` unknowns whose `E₀` and `J`
    /// have the structural non-zeros of `first`'s [`DaeSystem::sparsity`]
    /// (`None` above [`PatternLu`]'s size).
    fn new(first: &dyn DaeSystem, size: usize, m: usize) -> Option<Self> {
        let sparsity = first.sparsity();
        let (e, j) = (&sparsity.leading, &sparsity.rhs_jacobian);
        // Variable-major columns: partial pivoting then makes 167 updates
        // on the pendulum's rcd0 where the stage-major order makes 203
        // (`scripts/pattern_lu_order.py`, BENCHMARKS.md §21).
        let lu = PatternLu::new(3 * size, |row, col| {
            let (r, c) = (row / 3, col / 3);
            e.contains(r, c) || (row % 3 == col % 3 && j.contains(r, c))
        })?;
        let big = 3 * size;
        // Positions below `PatternLu`'s capacity (45 × 45) fit in `u16`.
        let pos = |row: usize, col: usize| (col * big + row) as u16;
        let e_at = e
            .entries()
            .map(|(r, c)| {
                let at = std::array::from_fn(|kj| pos(Self::at(r, kj / 3), Self::at(c, kj % 3)));
                (c * m + r, at)
            })
            .collect();
        let j_at = j
            .entries()
            .map(|(r, c)| {
                let at = std::array::from_fn(|k| pos(Self::at(r, k), Self::at(c, k)));
                (c * size + r, at)
            })
            .collect();
        Some(Direct {
            lu,
            e_at,
            j_at,
            rhs: vec![0.0; size],
            x: vec![0.0; big],
            judged: false,
        })
    }

    /// The row (column) of equation (unknown) `i` at stage `k`.
    fn at(i: usize, k: usize) -> usize {
        3 * i + k
    }
}

/// Which unknowns one simplified Newton iteration solves for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Phase {
    /// All of them at once (every system without the staggered corrector).
    Whole,
    /// The state's (the first block), its rows alone.
    State,
    /// The sensitivities' (the later blocks), the state fixed.
    Sensitivities,
}

impl Stagger {
    /// The staggered corrector of `sys` for a method `K` whose stage
    /// solve is square, when `sys` has blocks, offers its first
    /// block, and has a constant `E`; `None` otherwise (the simultaneous
    /// corrector then runs). The contraction monitor is the caller's to
    /// configure ([`Integrator::new`]).
    pub(super) fn of<K: Collocation>(
        sys: &dyn DaeSystem,
        options: &Options,
        solve: StageSolveKind,
        dense: bool,
    ) -> Option<Self> {
        let info = sys.info();
        let n = info.unknowns();
        let b: Blocks = sys.blocks()?;
        let first = sys.first_block()?;
        let usable = solve == StageSolveKind::Square
            && !K::TABLEAU.end.projected()
            && dense
            && info.constant_leading
            && b.size > 0
            && b.count > 1
            && b.unknowns() == n
            && info.equations() == n
            && first.info().unknowns() == b.size
            && first.info().equations() == b.size;
        if !usable {
            return None;
        }
        let factor =
            |i: usize| (K::POLICY.tolerance_factor)(options.tol.rtol(i), options.tol.atol(i));
        let powers = weights::index_powers(info);
        let state_weights = Weights::new(
            &options.tol,
            factor,
            vec![true; b.size],
            powers[..b.size].to_vec(),
        );
        let mut sens = vec![true; n];
        sens[..b.size].fill(false);
        let sens_weights = Weights::new(&options.tol, factor, sens, powers);
        Some(Stagger {
            size: b.size,
            error_control: b.error_control,
            state_weights,
            sens_weights,
            jac: DMatrix::zeros(b.size, b.size),
            lin: std::array::from_fn(|_| DMatrix::zeros(b.size, b.size + b.count - 1)),
            newton: Contraction::new(
                crate::core::newton::Rule::Radau5 { slow_exit: false },
                K::POLICY.max_newton,
                1.0,
                1.0,
            ),
            direct: (b.size <= DIRECT_MAX)
                .then(|| Direct::new(first, b.size, n))
                .flatten(),
            compact: std::array::from_fn(|_| vec![0.0; 3 * b.size]),
        })
    }

    /// Exchange the step loop's stage buffers (`Z, G, ΔW, Y, Y'` of `n`
    /// unknowns, stage-major) with the state's compact ones, and carry the
    /// state's stages `Z` across: `into` the state phase, from the loop's
    /// `Z` into the compact one; out of it, back into the loop's.
    fn exchange(&mut self, [z, rest @ ..]: [&mut Vec<f64>; 5], n: usize, into: bool) {
        let size = self.size;
        let [cz, crest @ ..] = &mut self.compact;
        for (big, small) in rest.into_iter().zip(crest) {
            std::mem::swap(big, small);
        }
        std::mem::swap(z, cz);
        // `cz` now holds the stages to carry, `z` the buffer they go to.
        let (from, to) = if into { (n, size) } else { (size, n) };
        for k in 0..3 {
            z[k * to..k * to + size].copy_from_slice(&cz[k * from..k * from + size]);
        }
    }

    /// The Newton weights for step size `h` at `y` (every unknown): the
    /// state's, and the sensitivities' where they are iterated.
    pub(super) fn update_weights(&mut self, y: &[f64], h: f64) {
        self.state_weights.update_scaled(y, h);
        if self.direct.is_none() {
            self.sens_weights.update_scaled(y, h);
        }
    }

    /// The Newton norm of phase `phase` of the stage increments `dw`
    /// (three blocks `m` apart).
    pub(super) fn norm(&self, phase: Phase, dw: &[f64], m: usize) -> f64 {
        match phase {
            Phase::Sensitivities => self.sens_weights.norm_blocks(dw, m, 3),
            Phase::State | Phase::Whole => self.state_weights.norm_blocks(dw, m, 3),
        }
    }
}

impl<K: Collocation> Integrator<'_, K> {
    /// The staggered corrector of one attempt: the state's stages, then
    /// the sensitivities' (see the [module documentation](self)). The
    /// iterations reported are the state's (they steer the step size as
    /// in the plain run); the sensitivities' are not in the statistics
    /// (BENCHMARKS.md §13d counts them from a profile).
    pub(super) fn newton_staggered(&mut self, t: f64, h: f64, may_shorten: bool) -> Newton {
        self.exchange(true, h);
        let state = self.iterate(t, h, may_shorten, Phase::State);
        self.exchange(false, h);
        let Newton::Converged(k) = state else {
            return state;
        };
        let direct = self
            .w
            .stagger
            .as_ref()
            .is_some_and(|st| st.direct.is_some());
        if direct && self.linearise(t, h) {
            return match self.solve_sensitivities(h) {
                Ok(()) => Newton::Converged(k),
                // A singular stage system: retried as a diverged iteration.
                Err(Exact::Singular) => Newton::Diverged(k),
                Err(Exact::NonFinite) => Newton::NonFinite(k),
            };
        }
        match self.iterate(t, h, may_shorten, Phase::Sensitivities) {
            Newton::Converged(_) => Newton::Converged(k),
            Newton::TooSlow { factor, .. } => Newton::TooSlow {
                iterations: k,
                factor,
            },
            Newton::Diverged(_) => Newton::Diverged(k),
            Newton::NonFinite(_) => Newton::NonFinite(k),
        }
    }

    /// Into (`into`) or out of the state phase: the step loop's stage
    /// buffers exchanged with the state's compact ones
    /// ([`Stagger::exchange`]); on the way in, the Newton weights for `h`.
    fn exchange(&mut self, into: bool, h: f64) {
        let n = self.n;
        let w = &mut self.w;
        if let Some(st) = &mut w.stagger {
            if into {
                st.update_weights(&w.y, h);
            }
            let loop_buffers = [&mut w.z, &mut w.res, &mut w.dw, &mut w.ys, &mut w.yd];
            st.exchange(loop_buffers, n, into);
        }
    }

    /// The contraction monitor of `phase`.
    fn monitor(&mut self, phase: Phase) -> &mut Contraction {
        match (phase, &mut self.w.stagger) {
            (Phase::Sensitivities, Some(st)) => &mut st.newton,
            _ => &mut self.newton,
        }
    }

    /// One simplified Newton iteration over the unknowns of `phase`
    /// (RADAU5's loop at label 40). `may_shorten` allows the early exit on
    /// slow convergence; without it (fixed-step mode) up to `NIT_FIXED`
    /// iterations are made.
    ///
    /// Inlined into its three callers, each with its `phase` a constant:
    /// the plain run's loop carries no dispatch on the phase.
    #[inline(always)]
    pub(super) fn iterate(&mut self, t: f64, h: f64, may_shorten: bool, phase: Phase) -> Newton {
        let size = self.w.stagger.as_ref().map_or(self.n, |st| st.size);
        // The state phase runs on the compact buffers of its rows alone.
        let (n, m) = if phase == Phase::State {
            (size, size)
        } else {
            (self.n, self.m)
        };
        let max_iter = if may_shorten {
            K::POLICY.max_newton
        } else {
            super::NIT_FIXED
        };
        let monitor = self.monitor(phase);
        let eta = monitor.eta.max(UROUND).powf(0.8);
        monitor.restart(max_iter, eta, K::POLICY.thet);
        if matches!(K::POLICY.newton, NewtonStop::RoundOff { .. }) {
            self.newton.kappa = self.newton_floor.max(self.newton_drift * h * h);
        }
        // The sensitivities' rows are linear in them: with the state's
        // stages fixed, their matrices at the three stage points once, and
        // each iteration's residuals by products.
        let linear = phase == Phase::Sensitivities && self.linearise(t, h);
        loop {
            match phase {
                Phase::State => self.state_stage_residuals(t, h),
                Phase::Sensitivities if linear => self.linear_stage_residuals(h),
                Phase::Whole | Phase::Sensitivities => self.stage_residuals(t, h),
            }
            let w = &mut self.w;
            if phase == Phase::Sensitivities {
                // The state fixed: its rows are not iterated on.
                for g in w.res.chunks_exact_mut(m) {
                    g[..size].fill(0.0);
                }
            }
            // R = −(T⁻¹ ⊗ I) G.
            if !super::kernels::transform_residuals::<K>(&w.res, &mut w.dw, m) {
                return Newton::NonFinite(self.monitor(phase).iterations());
            }
            let part = match phase {
                Phase::Whole => None,
                Phase::State => Some(Part::First),
                Phase::Sensitivities => Some(Part::Rest),
            };
            let (real, complex) = w.dw.split_at_mut(m);
            let (re, im) = complex.split_at_mut(m);
            match part {
                None => {
                    w.stages.solve_real(real);
                    w.stages.solve_complex(re, im);
                }
                Some(part) => {
                    w.stages.solve_real_part(real, part);
                    w.stages.solve_complex_part(re, im, part);
                }
            }
            let dyno = match (&w.stagger, phase) {
                (Some(st), Phase::State | Phase::Sensitivities) => st.norm(phase, &w.dw, m),
                _ => w.weights.norm_blocks(&w.dw, m, 3),
            };
            if !dyno.is_finite() {
                return Newton::NonFinite(self.monitor(phase).iterations() + 1);
            }
            let monitor = self.monitor(phase);
            let mut verdict = monitor.observe(dyno, 0.0);
            let iterations = monitor.iterations();
            // Towards round-off (`gauss`) with a leading matrix that is not
            // constant: the first increment is not taken for the last on
            // the strength of the contraction carried from the step
            // before. The iteration matrix holds `E` of the Jacobian's
            // point, the stages `E` of their own, and it may contract far
            // worse on this step than on the last: Gear–Hsu–Petzold's
            // `rcd0` (`E(t)`) contracts at 0.46, stopped after one
            // increment with `y1` 2.5·10⁻³ off at tol 1e-4. A constant `E`
            // keeps the old rule (the pendulum's `rcd0` unchanged).
            if matches!(K::POLICY.newton, NewtonStop::RoundOff { .. })
                && !self.constant_leading
                && verdict == Verdict::Converged
                && iterations == 1
                && dyno > self.newton_floor
            {
                verdict = Verdict::Continue;
            }
            if matches!(verdict, Verdict::Diverged | Verdict::TooSlow { .. }) {
                // What `Stall` judges: the state's increments (a
                // sensitivity phase's failure starts its count again).
                self.newton_last = if phase == Phase::Sensitivities {
                    (0.0, 0)
                } else {
                    (
                        dyno,
                        weights::largest_weighted(&self.w.dw, self.w.weights.get(), m, 3),
                    )
                };
            }
            match verdict {
                Verdict::Diverged => return Newton::Diverged(iterations),
                Verdict::TooSlow { factor } => {
                    return Newton::TooSlow { iterations, factor };
                }
                Verdict::Continue | Verdict::Converged => {}
            }

            // Z += (T ⊗ I) ΔW   (T₃₂ = 1, T₃₃ = 0): zero increments outside
            // the phase's unknowns.
            let w = &mut self.w;
            super::kernels::add_increments::<K>(&w.dw, m, &mut w.z, n);
            if verdict == Verdict::Converged {
                return Newton::Converged(iterations);
            }
        }
    }

    /// The state's stage residuals `G_i(Z) = E Y'_i − f(t + c_i h, Y_i)`
    /// from its own formulation, on the compact buffers of the state phase
    /// (`N` apart, [`Stagger::exchange`]).
    fn state_stage_residuals(&mut self, t: f64, h: f64) {
        let w = &mut self.w;
        let (Some(first), Some(st)) = (self.sys.first_block(), &w.stagger) else {
            // Not reached: a staggered corrector exists only for a system
            // with a first block.
            return;
        };
        let size = st.size;
        super::kernels::stage_points::<K>(&w.y[..size], &w.z, h, &mut w.ys, &mut w.yd);
        for (i, &ci) in K::TABLEAU.c.iter().enumerate() {
            let at = i * size..(i + 1) * size;
            first.residual(
                t + ci * h,
                &w.ys[at.clone()],
                &w.yd[at.clone()],
                &mut w.res[at],
            );
        }
        self.stats.residual_evals += 3;
    }

    /// `[∂f/∂y | ∂f/∂p]` at the state's three stage points `Y_k = y + Z_k`
    /// (the stages as the state's iteration left them, into the state's
    /// rows of `ys`); whether the system offers it.
    fn linearise(&mut self, t: f64, h: f64) -> bool {
        let n = self.n;
        let w = &mut self.w;
        let Some(st) = &mut w.stagger else {
            return false;
        };
        let size = st.size;
        for k in 0..3 {
            let point = &mut w.ys[k * n..k * n + size];
            for ((p, &y), &z) in point.iter_mut().zip(&w.y).zip(&w.z[k * n..]) {
                *p = y + z;
            }
        }
        let c = &K::TABLEAU.c;
        let points = [0, 1, 2].map(|k| &w.ys[k * n..k * n + size]);
        let times = [0, 1, 2].map(|k| t + c[k] * h);
        self.sys
            .first_block_linearisations(times, points, &mut st.lin)
    }

    /// The sensitivities' stage increments by [`Direct`]'s exact solve,
    /// with `[J | ∂f/∂p]` of [`Self::linearise`], into their rows of `Z`.
    fn solve_sensitivities(&mut self, h: f64) -> Result<(), Exact> {
        let n = self.n;
        let w = &mut self.w;
        let Some(st) = &mut w.stagger else {
            return Ok(());
        };
        let Some(d) = &mut st.direct else {
            return Ok(());
        };
        let size = st.size;
        let e = w.e_n.dense().as_slice();
        let lin = st.lin.each_ref().map(|l| l.as_slice());
        let (e_at, j_at) = (&d.e_at[..], &d.j_at[..]);
        d.lu.factor(|a| stage_matrix::<K>(a, e, lin, (e_at, j_at), h))
            .map_err(|_| Exact::Singular)?;
        let params = st.lin[0].ncols() - size;
        for i in 1..=params {
            let s = &w.y[size * i..size * (i + 1)];
            for (k, lin) in st.lin.iter().enumerate() {
                let rhs = &mut d.rhs[..];
                with_size!(size, |N| sensitivity_rhs(rhs, s, lin.as_slice(), i, N));
                for (r, &v) in d.rhs.iter().enumerate() {
                    d.x[Direct::at(r, k)] = v;
                }
            }
            d.lu.solve(&mut d.x);
            // `x · 0` is zero for a finite `x` only.
            if d.x.iter().fold(0.0, |acc, &x| acc + x * 0.0) != 0.0 {
                return Err(Exact::NonFinite);
            }
            for (c, x) in d.x.chunks_exact(3).enumerate() {
                for (k, &v) in x.iter().enumerate() {
                    w.z[k * n + size * i + c] = v;
                }
            }
        }
        // One parameter: the exact solve stays only where its elimination
        // is cheaper than the iteration (judged on the first one).
        if params == 1 && !d.judged {
            d.judged = true;
            if d.lu.updates() > ONE_PARAMETER_UPDATES * size * size {
                st.direct = None;
            }
        }
        Ok(())
    }

    /// The sensitivities' stage residuals `E Sᵢ'(c_k) − J(Y_k) Sᵢ(c_k) −
    /// ∂f/∂pᵢ(Y_k)` by products with the matrices of [`Self::linearise`],
    /// into each stage's block of `res` after its first `N` rows (`E` is
    /// constant and block diagonal: its first block is every block's).
    fn linear_stage_residuals(&mut self, h: f64) {
        let (n, m) = (self.n, self.m);
        let w = &mut self.w;
        let Some(st) = &w.stagger else {
            return;
        };
        super::kernels::stage_points::<K>(&w.y, &w.z, h, &mut w.ys, &mut w.yd);
        let size = st.size;
        // Column-major slices: `E`'s first block (leading dimension `m`)
        // and each `[J | ∂f/∂p]` (leading dimension `N`).
        let e = w.e_n.dense().as_slice();
        for (k, lin) in st.lin.iter().enumerate() {
            let lin = lin.as_slice();
            let (ys, yd) = (&w.ys[k * n..(k + 1) * n], &w.yd[k * n..(k + 1) * n]);
            let res = &mut w.res[k * m..(k + 1) * m];
            for (i, r) in res[size..n].chunks_exact_mut(size).enumerate() {
                let at = size * (i + 1);
                let point = (&ys[at..at + size], &yd[at..at + size]);
                with_size!(size, |N| linear_rows(r, point, e, m, lin, i, N));
            }
        }
    }

    /// `J₀` of a staggered run: the state's Jacobian at `(t, y_n)` into
    /// the first block of `jac` (the rest of `jac` stays zero: no `Bᵢ`).
    /// Whether it applied (a staggered run with a dense `jac`).
    pub(super) fn staggered_jacobian(&mut self, t: f64) -> bool {
        let w = &mut self.w;
        let (Some(st), Matrix::Dense(jac)) = (&mut w.stagger, &mut w.jac) else {
            return false;
        };
        let Some(first) = self.sys.first_block() else {
            return false;
        };
        let size = st.size;
        first.rhs_jacobian(t, &w.y[..size], &mut st.jac);
        jac.view_mut((0, 0), (size, size)).copy_from(&st.jac);
        true
    }

    /// The part of the error estimate's solve: the state's alone when the
    /// sensitivities are out of the error test.
    pub(super) fn error_part(&self) -> Option<Part> {
        match &self.w.stagger {
            Some(st) if !st.error_control => Some(Part::First),
            _ => None,
        }
    }
}

/// `f(t, y)` of `sys` where the error estimate needs it: with a staggered
/// corrector whose sensitivities are out of the error test, the state's
/// rows alone from the state's formulation (the rest of `f` is then not
/// read); every row otherwise.
pub(super) fn rhs_for_error(
    sys: &dyn DaeSystem,
    stagger: Option<&Stagger>,
    t: f64,
    y: &[f64],
    f: &mut [f64],
) {
    // The stagger first: a plain run makes no `first_block` call.
    if let Some(st) = stagger.filter(|st| !st.error_control) {
        if let Some(first) = sys.first_block() {
            return first.rhs(t, &y[..st.size], &mut f[..st.size]);
        }
    }
    sys.rhs(t, y, f)
}

/// Why [`Direct`]'s solve failed.
enum Exact {
    /// The stage system is singular.
    Singular,
    /// An increment is not finite.
    NonFinite,
}

/// [`Direct`]'s matrix into `a` (`3N × 3N`, column-major, variable-major
/// unknowns and rows): block `(k, j)` of stages is `(a⁻¹_kj / h) E −
/// δ_kj J(Y_k)`, `e` is `E`'s storage (its first block `E₀`), `lin[k]` is
/// `[J(Y_k) | ∂f/∂p]`; only the structural non-zeros of `E₀` and `J` are
/// written, at the positions `e_at`, `j_at` of [`Direct`], into zeros
/// ([`PatternLu::factor`] clears them).
fn stage_matrix<K: Collocation>(
    a: &mut [f64],
    e: &[f64],
    lin: [&[f64]; 3],
    (e_at, j_at): (&[EntryAt<9>], &[EntryAt<3>]),
    h: f64,
) {
    let coef: [f64; 9] = std::array::from_fn(|kj| K::TABLEAU.ainv[kj / 3][kj % 3] / h);
    for &(from, at) in e_at {
        let ev = e[from];
        for (&pos, &c) in at.iter().zip(&coef) {
            a[usize::from(pos)] = c * ev;
        }
    }
    for &(from, at) in j_at {
        for (&pos, jac) in at.iter().zip(lin) {
            a[usize::from(pos)] -= jac[from];
        }
    }
}

/// The right-hand side `J sᵢ + ∂f/∂pᵢ` of parameter `i` (from 1) at one
/// stage point: `lin` is `[J | ∂f/∂p]` column-major with leading
/// dimension `size`.
#[inline(always)]
fn sensitivity_rhs(rhs: &mut [f64], s: &[f64], lin: &[f64], i: usize, size: usize) {
    let (rhs, s) = (&mut rhs[..size], &s[..size]);
    rhs.copy_from_slice(&lin[(size + i - 1) * size..(size + i) * size]);
    for (c, &sc) in s.iter().enumerate() {
        let jc = &lin[c * size..(c + 1) * size];
        for k in 0..size {
            rhs[k] += jc[k] * sc;
        }
    }
}

/// One sensitivity's stage residual `r = E₀ s' − J s − ∂f/∂pᵢ` at the
/// stage point `(s, s')`: `e` is `E` column-major with leading dimension
/// `m` (its first block `E₀`), `lin` is `[J | ∂f/∂p]` column-major with
/// leading dimension `size` (the sizes of the formulations the solvers
/// meet most made constants by [`with_size!`]).
#[inline(always)]
fn linear_rows(
    r: &mut [f64],
    (s, sd): (&[f64], &[f64]),
    e: &[f64],
    m: usize,
    lin: &[f64],
    i: usize,
    size: usize,
) {
    let (r, s, sd) = (&mut r[..size], &s[..size], &sd[..size]);
    let fp = &lin[(size + i) * size..(size + i + 1) * size];
    for k in 0..size {
        r[k] = -fp[k];
    }
    for c in 0..size {
        let (sc, sdc) = (s[c], sd[c]);
        let ec = &e[c * m..c * m + size];
        let jc = &lin[c * size..(c + 1) * size];
        for k in 0..size {
            r[k] += ec[k] * sdc - jc[k] * sc;
        }
    }
}
