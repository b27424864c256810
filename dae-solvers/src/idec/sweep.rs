//! One interval of IDeC: the linearly implicit Euler solution of the
//! original problem and, for each correction, the neighbouring problem
//! solved by the same scheme and the corrected values (seed 002, (2.1)–
//! (2.5)); every buffer allocated once.
//!
//! With constant steps ([`Sweep::compensated`]) the running sums are
//! compensated: every value the scheme carries from step to step — the
//! basic solution `η^[0]`, each `π^[j]`, and the corrected levels at the
//! nodes — is held as an unevaluated sum `hi + lo` (`lo` at most a few
//! units in the last place of `hi`). `f`, its Jacobian and the linear
//! solves see `hi` only; the updates `y_{k+1} = y_k + Δ`, the corrections
//! `η^[0] − (π^[j] − η^[j])` and the interpolant's derivative are formed
//! from both parts with exact two-sums. Without it the update rounds at
//! `ulp(y)` (1e-16 for values of size 1) every step, and since `Δ` changes
//! slowly the rounding errors of consecutive steps are alike and add up:
//! over the 5·10⁷ steps per level of S01 at h = 3.9e-7 they reach 5e-8,
//! the floor of the third correction (docs/bench_idec.md §5).

use crate::core::control::Failure;
use crate::core::eval;
use crate::core::lagrange::Nodes;
use crate::core::shifted::Shifted;
use crate::linalg::{all_finite, mat_vec, two_sum};
use crate::Stats;
use dae_core::system::{DaeSystem, FormulationInfo};

/// The workspace of one interval of `m` Euler steps with `J` corrections.
pub(super) struct Sweep {
    /// Unknowns `N`.
    n: usize,
    /// Corrections `J`.
    corrections: usize,
    /// The interpolation nodes (degree `m`).
    pub(super) nodes: Nodes,
    /// `η^[l]` at the nodes `k = 0 … m`: entry `(l (m + 1) + k) N + i`.
    eta: Vec<f64>,
    /// `η^[l]` at the start of the interval, `l = 0 … J`.
    pub(super) start: Vec<f64>,
    /// The neighbouring problems' Euler solutions `π^[j]` at the start of
    /// the interval, `j = 0 … J − 1`.
    pub(super) np_start: Vec<f64>,
    /// `π^[j]` at the end of the interval, after [`Sweep::run`].
    pub(super) np_end: Vec<f64>,
    /// The low parts of `eta`, `start`, `np_start`, `np_end` and `pi`
    /// (same layouts; zero unless [`Sweep::compensated`]).
    eta_lo: Vec<f64>,
    start_lo: Vec<f64>,
    np_start_lo: Vec<f64>,
    np_end_lo: Vec<f64>,
    pi_lo: Vec<f64>,
    /// `f` of level `j` (the correction in progress) where the defect is
    /// sampled: `f(t_k, η^[j]_k)` at the nodes `k = 0 … m − 1`, or at
    /// `1 … m` ([`Sweep::at_end`]).
    f_eta: Vec<f64>,
    /// Scratch: the current `π`, `f`, `h p'`, `E h p'`, the right-hand side.
    pi: Vec<f64>,
    f: Vec<f64>,
    dp: Vec<f64>,
    edp: Vec<f64>,
    rhs: Vec<f64>,
    /// The constant leading matrix `E`, the Jacobian `J = ∂f/∂y` and
    /// `E − h J`, factorised.
    pub(super) matrix: Shifted,
    /// Evaluate `J` and factorise `E − hJ` at the start of every Euler
    /// step, at that step's own point (each level and each neighbouring
    /// problem at its own values), instead of once per interval.
    pub(super) every_step: bool,
    /// Carry every running sum as `hi + lo` (module documentation): the
    /// constant-step scheme, whose levels run over the whole horizon. Off
    /// with error control, where every interval restarts from the accepted
    /// value after `m` steps (its results are those of plain sums).
    compensated: bool,
    /// Evaluate `f` of each Euler step at the step's end time and sample
    /// the defect at the step's end node (error control), instead of both
    /// at its start (the seed's scheme): the corrections then tend to
    /// collocation at the nodes `1 … m`, stiffly accurate, not at `0 …
    /// m − 1` (module documentation, "Variable steps").
    at_end: bool,
}

impl Sweep {
    /// Buffers for `info` with `corrections` corrections and degree `m`,
    /// for constant steps (`fixed`: the running sums compensated, since
    /// every level runs over the whole horizon) or error control (the
    /// defect sampled at the end of each Euler step, module documentation,
    /// "Variable steps").
    pub(super) fn new(info: &FormulationInfo, corrections: usize, m: usize, fixed: bool) -> Self {
        let n = info.unknowns();
        Sweep {
            n,
            corrections,
            nodes: Nodes::new(m),
            eta: vec![0.0; (corrections + 1) * (m + 1) * n],
            start: vec![0.0; (corrections + 1) * n],
            np_start: vec![0.0; corrections * n],
            np_end: vec![0.0; corrections * n],
            eta_lo: vec![0.0; (corrections + 1) * (m + 1) * n],
            start_lo: vec![0.0; (corrections + 1) * n],
            np_start_lo: vec![0.0; corrections * n],
            np_end_lo: vec![0.0; corrections * n],
            pi_lo: vec![0.0; n],
            f_eta: vec![0.0; m * n],
            pi: vec![0.0; n],
            f: vec![0.0; n],
            dp: vec![0.0; n],
            edp: vec![0.0; n],
            rhs: vec![0.0; n],
            matrix: Shifted::new(n),
            every_step: false,
            compensated: fixed,
            at_end: !fixed,
        }
    }

    /// `η^[l]` at node `k` of the last interval.
    pub(super) fn node(&self, l: usize, k: usize) -> &[f64] {
        let m = self.nodes.degree();
        let at = (l * (m + 1) + k) * self.n;
        &self.eta[at..at + self.n]
    }

    /// Every level and every `π^[j]` starts the next interval at `y`
    /// (variable steps: the accepted, best value; the first interval).
    pub(super) fn restart_at(&mut self, y: &[f64]) {
        for chunk in self
            .start
            .chunks_exact_mut(self.n)
            .chain(self.np_start.chunks_exact_mut(self.n))
        {
            chunk.copy_from_slice(y);
        }
        self.start_lo.fill(0.0);
        self.np_start_lo.fill(0.0);
    }

    /// After an accepted interval with constant steps: each level and each
    /// `π^[j]` continues from its own value at the end (the global
    /// connection of the seed, (2.7) and (3.6)).
    pub(super) fn carry_over(&mut self) {
        let (n, m) = (self.n, self.nodes.degree());
        for l in 0..=self.corrections {
            let at = (l * (m + 1) + m) * n;
            self.start[l * n..(l + 1) * n].copy_from_slice(&self.eta[at..at + n]);
            self.start_lo[l * n..(l + 1) * n].copy_from_slice(&self.eta_lo[at..at + n]);
        }
        self.np_start.copy_from_slice(&self.np_end);
        self.np_start_lo.copy_from_slice(&self.np_end_lo);
    }

    /// One interval of `m` Euler steps of size `h` from `t`, with `E − hJ`
    /// factorised for this `h` (or, [`Sweep::every_step`], at each step):
    /// every level `η^[l]` at the `m + 1` nodes, from [`Sweep::start`] and
    /// [`Sweep::np_start`]; `π^[j]` at the end into [`Sweep::np_end`].
    pub(super) fn run(
        &mut self,
        sys: &dyn DaeSystem,
        stats: &mut Stats,
        t: f64,
        h: f64,
    ) -> Result<(), Failure> {
        let (n, m) = (self.n, self.nodes.degree());
        let block = (m + 1) * n;
        let compensated = self.compensated;
        // The linearly implicit Euler solution of the original problem,
        // (E − hJ)(η_{k+1} − η_k) = h f(t_k, η_k) (f at t_{k+1} if
        // `at_end`; the defect of level 0 is then sampled afresh below).
        self.eta[..n].copy_from_slice(&self.start[..n]);
        self.eta_lo[..n].copy_from_slice(&self.start_lo[..n]);
        for k in 0..m {
            let tk = t + k as f64 * h;
            let (done, next) = self.eta.split_at_mut((k + 1) * n);
            let eta_k = &done[k * n..];
            if self.every_step {
                self.matrix.checked_jacobian(sys, stats, tk, eta_k)?;
                self.matrix.factor(1.0, h, stats)?;
            }
            let f_k = &mut self.f_eta[k * n..(k + 1) * n];
            let tf = if self.at_end { tk + h } else { tk };
            eval::rhs(sys, stats, tf, eta_k, f_k)?;
            for (r, f) in self.rhs.iter_mut().zip(f_k.iter()) {
                *r = h * f;
            }
            self.matrix.solve(&mut self.rhs);
            if compensated {
                let (lo_done, lo_next) = self.eta_lo.split_at_mut((k + 1) * n);
                let lo_k = &lo_done[k * n..];
                for i in 0..n {
                    (next[i], lo_next[i]) = two_sum(eta_k[i], self.rhs[i] + lo_k[i]);
                }
            } else {
                for ((y1, y0), d) in next[..n].iter_mut().zip(eta_k).zip(&self.rhs) {
                    *y1 = y0 + d;
                }
            }
        }
        // The corrections: the neighbouring problem E y' = f(t, y) + d(t),
        // d(t) = E p'(t) − f(t, p(t)), p the interpolant of η^[j], solved
        // by the same scheme (f and d at t_k, or both at t_{k+1}) from
        // π^[j](t_start); then
        // η^[j+1] = η^[0] − (π^[j] − η^[j]) at the nodes.
        for j in 0..self.corrections {
            let (lower, upper) = self.eta.split_at_mut((j + 1) * block);
            let eta0 = &lower[..block];
            let eta_j = &lower[j * block..];
            let eta_next = &mut upper[..block];
            let (lower_lo, upper_lo) = self.eta_lo.split_at_mut((j + 1) * block);
            let eta0_lo = &lower_lo[..block];
            let eta_j_lo = &lower_lo[j * block..];
            let eta_next_lo = &mut upper_lo[..block];
            if j > 0 || self.at_end {
                let shift = usize::from(self.at_end);
                for k in 0..m {
                    let tk = t + (k + shift) as f64 * h;
                    let f_k = &mut self.f_eta[k * n..(k + 1) * n];
                    let at = (k + shift) * n;
                    eval::rhs(sys, stats, tk, &eta_j[at..at + n], f_k)?;
                }
            }
            self.pi.copy_from_slice(&self.np_start[j * n..(j + 1) * n]);
            self.pi_lo
                .copy_from_slice(&self.np_start_lo[j * n..(j + 1) * n]);
            eta_next[..n].copy_from_slice(&self.start[(j + 1) * n..(j + 2) * n]);
            eta_next_lo[..n].copy_from_slice(&self.start_lo[(j + 1) * n..(j + 2) * n]);
            for k in 0..m {
                let tk = t + k as f64 * h;
                let (kd, tf) = if self.at_end {
                    (k + 1, tk + h)
                } else {
                    (k, tk)
                };
                if compensated {
                    self.nodes.derivative_compensated(
                        kd,
                        |l| &eta_j[l * n..(l + 1) * n],
                        |l| &eta_j_lo[l * n..(l + 1) * n],
                        &mut self.dp,
                    );
                } else {
                    self.nodes
                        .derivative(kd, |l| &eta_j[l * n..(l + 1) * n], &mut self.dp);
                }
                mat_vec(&self.matrix.lead, &self.dp, &mut self.edp);
                eval::rhs(sys, stats, tf, &self.pi, &mut self.f)?;
                if self.every_step {
                    self.matrix.checked_jacobian(sys, stats, tk, &self.pi)?;
                    self.matrix.factor(1.0, h, stats)?;
                }
                let f_k = &self.f_eta[k * n..(k + 1) * n];
                for (i, r) in self.rhs.iter_mut().enumerate() {
                    *r = h * (self.f[i] - f_k[i]) + self.edp[i];
                }
                self.matrix.solve(&mut self.rhs);
                let at = (k + 1) * n;
                if compensated {
                    for i in 0..n {
                        let (pi, pi_lo) = two_sum(self.pi[i], self.rhs[i] + self.pi_lo[i]);
                        (self.pi[i], self.pi_lo[i]) = (pi, pi_lo);
                        // η^[0] − (π − η^[j]) = q + (e_q − e_r), exactly,
                        // with r + e_r = π − η^[j] and q + e_q = η^[0] − r;
                        // the low parts of the three operands added.
                        let (r, e_r) = two_sum(pi, -eta_j[at + i]);
                        let (q, e_q) = two_sum(eta0[at + i], -r);
                        let lo = (e_q - e_r) + (eta0_lo[at + i] - (pi_lo - eta_j_lo[at + i]));
                        (eta_next[at + i], eta_next_lo[at + i]) = two_sum(q, lo);
                    }
                } else {
                    for i in 0..n {
                        self.pi[i] += self.rhs[i];
                        eta_next[at + i] = eta0[at + i] - (self.pi[i] - eta_j[at + i]);
                    }
                }
            }
            self.np_end[j * n..(j + 1) * n].copy_from_slice(&self.pi);
            self.np_end_lo[j * n..(j + 1) * n].copy_from_slice(&self.pi_lo);
        }
        let last = self.node(self.corrections, m);
        if all_finite(last) {
            Ok(())
        } else {
            Err(Failure::NonFinite("solution"))
        }
    }
}
