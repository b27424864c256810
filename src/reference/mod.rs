//! Exact reference solutions.
//!
//! # The pendulum released at rest
//!
//! A mass `m` on a massless rod of length `L` under gravity `g`, released at
//! rest at the angle `θ₀ ∈ (0, π)` measured from the downward vertical, moves
//! by `θ'' = −(g/L) sin θ`. With the modulus `k = sin(θ₀/2)`, the
//! complementary modulus `k' = cos(θ₀/2)` and `ω = √(g/L)` the solution is
//! (SPEC §3; Lawden, *Elliptic Functions and Applications*, §5.2)
//!
//! ```text
//! sin(θ/2) = k·sn(K(k) − ωt | k²),   cos(θ/2) = dn(K(k) − ωt | k²),
//! θ'       = −2kω·cn(K(k) − ωt | k²),
//! ```
//!
//! and the DAE unknowns of the paper's model are
//!
//! ```text
//! x = L sin θ = 2Lk·sn·dn              v = L cos θ·θ'
//! y = −L cos θ = −L(cos θ₀ + 2k²cn²)   w = L sin θ·θ'
//! λ = m(v² + w² − g y)/(2L²)
//! ```
//!
//! The period is `T = 4K(k)/ω`.
//!
//! # Any start: swings and loops
//!
//! [`PendulumExact::from_state`] takes any point on the circle and any
//! tangent velocity. With `θ'₀ = (x0 w0 − y0 v0)/L²` the modulus is
//! `k² = sin²(θ₀/2) + θ'₀²/(4ω²)` (energy `E = m g L (2k² − 1)`):
//!
//! ```text
//! k < 1, swing:  sin(θ/2) = k·sn(u | k²),  cos(θ/2) = dn(u | k²),    θ' = ±2kω·cn(u | k²),   u = u₀ ± ωt
//! k > 1, loop:   sin(θ/2) = sn(u | 1/k²),  cos(θ/2) = cn(u | 1/k²),  θ' = ±2kω·dn(u | 1/k²), u = u₀ ± kωt
//! ```
//!
//! (the loop with the reciprocal modulus `1/k`, Lawden §5.2; the sign is
//! that of `θ'₀`). A loop's revolution takes `2K(1/k)/(kω)`. The phase `u₀`
//! is the incomplete integral `F(φ₀ | m)`, by Carlson's `R_F`; the release
//! at rest is the case `u₀ = K`, `u = K − ωt` above, computed exactly as
//! before. `k = 1` (the separatrix: upright at rest, or just the speed to
//! creep up to the top) has no periodic solution and is refused, within
//! [`SEPARATRIX_GAP`]; just off it both motions stay exact.
//!
//! # Numerics
//!
//! * `K(k) = π / (2·AGM(1, k'))` (Abramowitz & Stegun 17.6), evaluated in
//!   double-double arithmetic (≈ 32 significant digits).
//! * `sn`, `cn`, `dn` by the descending Landen transformation / AGM scheme
//!   of Abramowitz & Stegun 16.4 on an argument already reduced to
//!   `[−K, K]`; `dn = √(k'² + k²cn²)`, a sum of non-negative terms, so it
//!   keeps full relative accuracy even when `k → 1`. Within `K/2` of `±K`
//!   the functions are taken from the distance `ε = K − |r|` (itself formed
//!   in double-double) by `sn(K − ε) = cd ε`, `cn(K − ε) = k'·sd ε`,
//!   `dn(K − ε) = k'·nd ε` (A&S 16.8), so that `cn`, and with it `θ'`, `v`,
//!   `w`, `λ` and `y = −L(cos θ₀ + 2k²cn²)`, keep full *relative* accuracy
//!   at the turning points: at `t = 2000` the computed `w = −1.2887…·10⁻⁶`
//!   and `v = −7.78…·10⁻²⁰` are correct to a few ulps.
//! * The argument `u = K − ωt` is formed and reduced modulo `2K` (using
//!   `sn(u + 2K) = −sn u`, `cn(u + 2K) = −cn u`, `dn(u + 2K) = dn u`) in
//!   double-double: `ω`, `K`, `ωt` and `n·2K` each carry ≈ 32 digits, so
//!   the reduced argument is correct to the last bit of an `f64` even after
//!   10⁴ periods. With plain `f64` the one-ulp error of `K` alone, multiplied
//!   by the number of periods, would shift the phase by ~10⁻¹² at `t = 2000`.
//! * The moduli `k` and `k'` themselves are obtained to double-double
//!   accuracy — from `θ₀` by a double-double Taylor series of `sin` (`k'` as
//!   `sin((π − θ₀)/2)`, so that it stays accurate as `θ₀ → π`), or from a
//!   start point `(x₀, y₀)` by the half-angle formulas, which for the
//!   paper's start `(1, 0)` give `k² = k'² = ½` exactly.
//!
//! The solution is the exact one *for the given `f64` inputs*. Note that
//! `std::f64::consts::FRAC_PI_2` is not `π/2`: it is smaller by 6.1·10⁻¹⁷, which
//! changes the period by 2.8·10⁻¹⁷ s and hence `w` at `t = 2000` by
//! ≈ 4·10⁻¹³. To reproduce the paper's start `x = 1, y = 0` exactly use
//! [`PendulumExact::from_start`].

#[cfg(feature = "cli")]
#[cfg_attr(docsrs, doc(cfg(feature = "cli")))]
pub mod data;

use std::fmt;

/// Why an exact reference could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReferenceError {
    /// The release angle is not in the open interval `(0, π)`.
    #[error(
        "release angle theta0 = {theta0} is outside the open interval (0, pi): \
         the exact pendulum reference needs a start strictly right of the \
         downward vertical and below the upward vertical"
    )]
    AngleOutOfRange {
        /// The offending angle (radians, from the downward vertical).
        theta0: f64,
    },
    /// A physical parameter is not a finite positive number.
    #[error("parameter {name} = {value} must be finite and positive")]
    InvalidParameter {
        /// `"g"`, `"l"` (the rod length L) or `"m"`.
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A start coordinate or velocity is not finite.
    #[error("start value {name} = {value} is not finite")]
    NonFiniteStart {
        /// `"x0"`, `"y0"`, `"v0"` or `"w0"`.
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The start point is not on the circle of radius `L` around the pivot.
    #[error(
        "start point ({x0}, {y0}) is at distance {radius} from the pivot, \
         not on the circle of radius L = {length} (relative tolerance {tol:e})"
    )]
    NotOnCircle {
        /// Start abscissa.
        x0: f64,
        /// Start ordinate.
        y0: f64,
        /// `√(x0² + y0²)`.
        radius: f64,
        /// The rod length `L`.
        length: f64,
        /// The relative tolerance applied, [`START_RADIUS_RTOL`].
        tol: f64,
    },
    /// The start velocity is not tangent to the circle: a motion on the rod
    /// has `x0·v0 + y0·w0 = 0`.
    #[error(
        "start velocity (v0, w0) = ({v0:e}, {w0:e}) is not tangent to the circle: its radial part \
         (x0 v0 + y0 w0)/r = {radial:e} exceeds {tol:e} of the speed"
    )]
    VelocityNotTangent {
        /// Start velocity, abscissa.
        v0: f64,
        /// Start velocity, ordinate.
        w0: f64,
        /// Radial velocity.
        radial: f64,
        /// The relative tolerance applied, [`START_RADIUS_RTOL`].
        tol: f64,
    },
    /// The start is on the separatrix (`k = 1`, e.g. at rest at the top, or
    /// with exactly the speed to reach it), to the precision of the
    /// computation ([`SEPARATRIX_GAP`]): the pendulum creeps toward the
    /// upright position and whether it swings back or loops is not
    /// determined.
    #[error(
        "the start is on the separatrix: k^2 - 1 = {k2_minus_1:e}, within {gap:e} of the energy that just \
         reaches the top (upright at rest, or exactly the speed to creep up to it); there is no exact \
         reference there"
    )]
    NearSeparatrix {
        /// `k² − 1`.
        k2_minus_1: f64,
        /// [`SEPARATRIX_GAP`].
        gap: f64,
    },
    /// A start coordinate so large that the start point's distance from
    /// the pivot overflows.
    #[error("start point (x0, y0) = ({x0:e}, {y0:e}) is too far from the pivot to be represented")]
    StartNotRepresentable {
        /// Start abscissa.
        x0: f64,
        /// Start ordinate.
        y0: f64,
    },
    /// A time so far from the start (more than 2⁵¹ periods) that the phase
    /// is lost even in double-double arithmetic: [`PendulumExact::state`]
    /// gives NaNs there.
    #[error("the exact solution cannot be evaluated {t:e} s after the start: beyond 2^51 periods the phase is lost")]
    PhaseLost {
        /// Time after the start.
        t: f64,
    },
    /// `g`, `L` and `m` are valid but `√(g/L)`, the period, or a value of
    /// the motion (the speed at the bottom, the multiplier) over- or
    /// underflows in double precision.
    #[error(
        "with g = {g:e}, L = {length:e}, m = {mass:e} the motion is not representable in double \
         precision: sqrt(g/L), the period 4K/sqrt(g/L), the speed or the multiplier overflows or underflows"
    )]
    Unrepresentable {
        /// Gravity.
        g: f64,
        /// Rod length.
        length: f64,
        /// Mass.
        mass: f64,
    },
}

impl ReferenceError {
    /// The input to blame, in the reference's own names: `"theta0"`,
    /// `"x0"`, `"y0"`, `"g"`, `"l"`, `"m"`, or `"t"` (a time too far from the
    /// start).
    pub fn input(&self) -> &'static str {
        match self {
            ReferenceError::AngleOutOfRange { .. } => "theta0",
            ReferenceError::InvalidParameter { name, .. }
            | ReferenceError::NonFiniteStart { name, .. } => name,
            ReferenceError::NotOnCircle { .. }
            | ReferenceError::StartNotRepresentable { .. }
            | ReferenceError::NearSeparatrix { .. } => "x0",
            ReferenceError::VelocityNotTangent { .. } => "v0",
            ReferenceError::Unrepresentable { .. } => "l",
            ReferenceError::PhaseLost { .. } => "t",
        }
    }
}

/// Relative tolerance on `|√(x0² + y0²) − L|` accepted by
/// [`PendulumExact::from_start`].
pub const START_RADIUS_RTOL: f64 = 1e-9;

/// The exact solution of the simple pendulum released at rest from
/// `θ₀ ∈ (0, π)` (see the [module documentation](self)).
///
/// ```
/// use dae::reference::PendulumExact;
///
/// // The paper's scenario: x0 = 1, y0 = 0, L = m = 1, g = 13.7503716373294544.
/// let p = PendulumExact::from_start(1.0, 0.0, 1.0, 13.7503716373294544, 1.0).unwrap();
/// assert!((p.period() - 1.99999999990628).abs() < 1e-14);
/// let [x, y, v, w, lambda] = p.state(20.0);
/// assert!((x - 1.0).abs() < 1e-15 && y.abs() < 1e-15 && v.abs() < 1e-15);
/// assert!((w + 1.2887087450500034e-8).abs() < 1e-15); // 10 periods are not 20 s
/// assert!(lambda.abs() < 1e-15);
/// ```
#[derive(Clone, Copy, PartialEq)]
pub struct PendulumExact {
    theta0: f64,
    g: f64,
    l: f64,
    m: f64,
    /// Modulus `k`: `k² = sin²(θ₀/2) + θ'₀²/(4ω²)` (`sin(θ₀/2)` for a
    /// release at rest); above 1 for a loop.
    k: Dd,
    /// Complementary modulus `k' = √(1 − k²)` of a swing (`cos(θ₀/2)` for
    /// a release at rest); 0 for a loop.
    kc: Dd,
    /// `ω = √(g/L)`.
    omega: Dd,
    /// Complete elliptic integral of the first kind of the Jacobi modulus:
    /// `K(k)` for a swing, `K(1/k)` for a loop.
    big_k: Dd,
    /// `k'² − k² = 1 − 2k²`, rounded once: the cosine of the amplitude of
    /// a swing (`cos θ₀` for a release at rest); `E = −m g L · cos_amp`.
    cos_theta0: f64,
    /// Swing or loop.
    motion: Motion,
    /// Phase at `t = 0`; `u(t) = u0 + dir · rate · t`.
    u0: Dd,
    /// `ω` for a swing, `kω` for a loop.
    rate: Dd,
    /// `±1`: the sense in which the phase runs.
    dir: f64,
    /// The Jacobi modulus and its complement in `f64`: `(k, k')` for a
    /// swing, `(1/k, √(1 − 1/k²))` for a loop.
    jk: f64,
    jkc: f64,
}

/// How the pendulum moves: to and fro, or over the top.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Motion {
    /// Oscillation about the bottom (`k < 1`): `sin(θ/2) = k·sn(u | k²)`.
    Swing,
    /// Rotation over the top (`k > 1`): `sin(θ/2) = sn(u | 1/k²)`,
    /// `cos(θ/2) = cn(u | 1/k²)`.
    Loop,
}

/// Starts whose `|k² − 1|` is at most this are refused
/// ([`ReferenceError::NearSeparatrix`]): `k²` is formed in double-double
/// (≈ 32 digits), so within `10⁻²⁸` of 1 its distance from the separatrix,
/// which sets the period (`K ≈ ln(4/√|1 − k²|)`), is not known to even
/// three digits, nor whether the pendulum swings back or goes over the
/// top. Outside it the reference stays exact: tested at `k² − 1 = ±10⁻¹⁰`
/// and `±4.4·10⁻¹⁶` (the speeds one ulp either side of the critical one)
/// against RADAU5 while the pendulum climbs, and for energy and the
/// constraints up to `t = 10⁴`.
pub const SEPARATRIX_GAP: f64 = 1e-28;

impl fmt::Debug for PendulumExact {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("PendulumExact")
            .field("theta0", &self.theta0)
            .field("g", &self.g)
            .field("l", &self.l)
            .field("m", &self.m)
            .field("k", &self.k.hi)
            .field("k_complement", &self.kc.hi)
            .field("omega", &self.omega.hi)
            .field("big_k", &self.big_k.hi)
            .field("motion", &self.motion)
            .field("u0", &self.u0.hi)
            .field("dir", &self.dir)
            .finish()
    }
}

fn check_param(name: &'static str, value: f64) -> Result<(), ReferenceError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ReferenceError::InvalidParameter { name, value })
    }
}

impl PendulumExact {
    /// The unknowns [`PendulumExact::state`] gives, in its order: the
    /// names the paper's model (and `scenes/pendulum.dae`) uses.
    pub const COMPONENTS: [&'static str; 5] = ["x", "y", "v", "w", "lambda"];

    /// The pendulum released at rest from the angle `theta0` (radians, from
    /// the downward vertical, `0 < θ₀ < π`), with gravity `g`, rod length `l`
    /// and mass `m` (all finite and positive).
    ///
    /// ```
    /// use dae::reference::{PendulumExact, ReferenceError};
    ///
    /// let p = PendulumExact::new(0.3, 9.81, 2.0, 0.5).unwrap();
    /// let [x, y, ..] = p.state(0.0);
    /// assert!((x - 2.0 * 0.3f64.sin()).abs() < 1e-15);
    /// assert!((y + 2.0 * 0.3f64.cos()).abs() < 1e-15);
    ///
    /// assert!(matches!(
    ///     PendulumExact::new(3.5, 9.81, 1.0, 1.0),
    ///     Err(ReferenceError::AngleOutOfRange { .. })
    /// ));
    /// ```
    pub fn new(theta0: f64, g: f64, l: f64, m: f64) -> Result<Self, ReferenceError> {
        if !(theta0 > 0.0 && theta0 < std::f64::consts::PI) {
            // The f64 `PI` is 1.2e-16 below π, but a caller passing it means
            // π — the unstable equilibrium at the top — so it is rejected;
            // the largest f64 below it is accepted.
            return Err(ReferenceError::AngleOutOfRange { theta0 });
        }
        check_param("g", g)?;
        check_param("l", l)?;
        check_param("m", m)?;
        let k = sin_dd(Dd::from(theta0).mul_f64(0.5));
        let kc = sin_dd(PI_DD.sub(Dd::from(theta0)).mul_f64(0.5));
        Self::build_rest(theta0, k, kc, g, l, m)
    }

    /// The pendulum released at rest from the point `(x0, y0)` (pivot at the
    /// origin, `y` upwards), i.e. `θ₀ = atan2(x0, −y0)`, with rod length `l`,
    /// gravity `g` and mass `m`.
    ///
    /// The point must lie on the circle of radius `l` up to the relative
    /// tolerance [`START_RADIUS_RTOL`]; its direction defines `θ₀` and `l`
    /// the length. `k` and `k'` are computed from the coordinates by the
    /// half-angle formulas `k'² = (r − y0)/(2r)`, `k = x0/(2rk')` (or the
    /// mirror pair when `y0 > 0`), so `(1, 0)` gives `k = k' = 1/√2` to
    /// double-double accuracy — unlike `θ₀ = FRAC_PI_2`.
    ///
    /// ```
    /// use dae::reference::PendulumExact;
    ///
    /// let p = PendulumExact::from_start(0.6, -0.8, 1.0, 9.81, 1.0).unwrap();
    /// assert!((p.theta0() - 0.6f64.atan2(0.8)).abs() < 1e-16);
    /// assert!(PendulumExact::from_start(0.6, -0.9, 1.0, 9.81, 1.0).is_err());
    /// ```
    pub fn from_start(x0: f64, y0: f64, l: f64, g: f64, m: f64) -> Result<Self, ReferenceError> {
        if !x0.is_finite() {
            return Err(ReferenceError::NonFiniteStart {
                name: "x0",
                value: x0,
            });
        }
        if !y0.is_finite() {
            return Err(ReferenceError::NonFiniteStart {
                name: "y0",
                value: y0,
            });
        }
        check_param("g", g)?;
        check_param("l", l)?;
        check_param("m", m)?;
        let theta0 = x0.atan2(-y0);
        if x0 <= 0.0 {
            return Err(ReferenceError::AngleOutOfRange { theta0 });
        }
        // Scale by max(|x0|, |y0|) so the squares neither overflow nor
        // underflow; the scaling by a power of two is exact. (x0 > 0 here.)
        let Some(scale) = pow2_at_least(x0.abs().max(y0.abs())) else {
            return Err(ReferenceError::StartNotRepresentable { x0, y0 });
        };
        let (xs, ys) = (x0 / scale, y0 / scale);
        let r_s = Dd::from_prod(xs, xs).add(Dd::from_prod(ys, ys)).sqrt();
        let radius = r_s.hi * scale;
        let on_circle = (radius - l).abs() <= START_RADIUS_RTOL * l;
        if !on_circle {
            return Err(ReferenceError::NotOnCircle {
                x0,
                y0,
                radius,
                length: l,
                tol: START_RADIUS_RTOL,
            });
        }
        let two_r = r_s.mul_f64(2.0);
        let (k, kc) = if ys <= 0.0 {
            // k'² = (1 + cos θ₀)/2 = (r − y0)/(2r) with cos θ₀ = −y0/r ≥ 0:
            // no cancellation in r − y0.
            let kc = r_s.sub(Dd::from(ys)).div(two_r).sqrt();
            let k = Dd::from(xs).div(two_r.mul(kc));
            (k, kc)
        } else {
            let k = r_s.add(Dd::from(ys)).div(two_r).sqrt();
            let kc = Dd::from(xs).div(two_r.mul(k));
            (k, kc)
        };
        Self::build_rest(theta0, k, kc, g, l, m)
    }

    /// The pendulum started from any point `(x0, y0)` on the circle with
    /// any tangent velocity `(v0, w0)`: it swings (`k < 1`) or loops over
    /// the top (`k > 1`), with
    ///
    /// ```text
    /// k² = sin²(θ₀/2) + θ'₀²/(4ω²),   θ'₀ = (x0 w0 − y0 v0)/r²,   ω = √(g/L)
    /// swing: sin(θ/2) = k·sn(u | k²),  cos(θ/2) = dn(u | k²),   θ' = ±2kω·cn(u | k²),  u = u₀ ± ωt
    /// loop:  sin(θ/2) = sn(u | 1/k²),  cos(θ/2) = cn(u | 1/k²), θ' = ±2kω·dn(u | 1/k²), u = u₀ ± kωt
    /// ```
    ///
    /// (Lawden §5.2; the sign is that of `θ'₀`), the phase `u₀` an
    /// incomplete elliptic integral of the first kind `F(φ₀ | m)` by
    /// Carlson's `R_F`. `k²` and `k² − 1` are formed in double-double
    /// from the inputs, and so are the phase and its reduction, as for the
    /// release at rest. A release at rest right of the vertical is exactly
    /// [`from_start`](Self::from_start).
    ///
    /// The velocity must be tangent up to [`START_RADIUS_RTOL`] of the
    /// speed; a start within [`SEPARATRIX_GAP`] of `k = 1` (upright at
    /// rest, or with exactly the speed to creep up to it) is
    /// [`ReferenceError::NearSeparatrix`].
    ///
    /// ```
    /// use dae::reference::{Motion, PendulumExact};
    ///
    /// // From the bottom at speed 10 on g = 9.81: over the top.
    /// let p = PendulumExact::from_state(0.0, -1.0, 10.0, 0.0, 1.0, 9.81, 1.0).unwrap();
    /// assert_eq!(p.motion(), Motion::Loop);
    /// assert!(p.modulus() > 1.0);
    /// let [x, y, v, w, _] = p.state(0.0);
    /// assert!(x.abs() < 1e-15 && (y + 1.0).abs() < 1e-15 && (v - 10.0).abs() < 1e-14 && w.abs() < 1e-15);
    /// // After one revolution it is back.
    /// let [x, y, v, ..] = p.state(p.period());
    /// assert!(x.abs() < 1e-13 && (y + 1.0).abs() < 1e-13 && (v - 10.0).abs() < 1e-12);
    /// ```
    pub fn from_state(
        x0: f64,
        y0: f64,
        v0: f64,
        w0: f64,
        l: f64,
        g: f64,
        m: f64,
    ) -> Result<Self, ReferenceError> {
        for (name, value) in [("x0", x0), ("y0", y0), ("v0", v0), ("w0", w0)] {
            if !value.is_finite() {
                return Err(ReferenceError::NonFiniteStart { name, value });
            }
        }
        if v0 == 0.0 && w0 == 0.0 && x0 > 0.0 {
            return Self::from_start(x0, y0, l, g, m);
        }
        check_param("g", g)?;
        check_param("l", l)?;
        check_param("m", m)?;
        let theta0 = x0.atan2(-y0);
        let not_on_circle = |radius: f64| ReferenceError::NotOnCircle {
            x0,
            y0,
            radius,
            length: l,
            tol: START_RADIUS_RTOL,
        };
        let far = x0.abs().max(y0.abs());
        if far == 0.0 {
            return Err(not_on_circle(0.0));
        }
        let Some(scale) = pow2_at_least(far) else {
            return Err(ReferenceError::StartNotRepresentable { x0, y0 });
        };
        let (xs, ys) = (x0 / scale, y0 / scale);
        let r_s = Dd::from_prod(xs, xs).add(Dd::from_prod(ys, ys)).sqrt();
        let radius = r_s.hi * scale;
        if (radius - l).abs() > START_RADIUS_RTOL * l || radius.is_nan() {
            return Err(not_on_circle(radius));
        }
        // The velocity must be along the circle: radial part within the
        // tolerance of the speed.
        let radial = Dd::from_prod(xs, v0).add(Dd::from_prod(ys, w0)).div(r_s).hi;
        if radial.abs() > START_RADIUS_RTOL * v0.hypot(w0) || radial.is_nan() {
            return Err(ReferenceError::VelocityNotTangent {
                v0,
                w0,
                radial,
                tol: START_RADIUS_RTOL,
            });
        }
        // Half angles: c = cos(θ₀/2) ≥ 0, s = sin(θ₀/2) with the sign of x0,
        // each from the formula free of cancellation on its side.
        let two_r = r_s.mul_f64(2.0);
        let (s, c) = if ys <= 0.0 {
            let c = r_s.sub(Dd::from(ys)).div(two_r).sqrt();
            (Dd::from(xs).div(two_r.mul(c)), c)
        } else {
            let s_abs = r_s.add(Dd::from(ys)).div(two_r).sqrt();
            let s = if xs < 0.0 { s_abs.neg() } else { s_abs };
            (s, Dd::from(xs.abs()).div(two_r.mul(s_abs)))
        };
        // θ'₀ = (x0 w0 − y0 v0)/r², and q = θ'₀/(2ω): k² = s² + q².
        let omega = Dd::from(g).div(Dd::from(l)).sqrt();
        let theta_dot0 = Dd::from_prod(xs, w0)
            .sub(Dd::from_prod(ys, v0))
            .div(r_s.mul(r_s))
            .div(Dd::from(scale));
        let q = theta_dot0.div(omega.mul_f64(2.0));
        let k2 = s.mul(s).add(q.mul(q));
        let unrepresentable = ReferenceError::Unrepresentable {
            g,
            length: l,
            mass: m,
        };
        if !(k2.hi.is_finite() && omega.hi.is_finite() && omega.hi > 0.0) {
            return Err(unrepresentable);
        }
        let d = k2.sub(Dd::from(1.0)); // k² − 1, exactly as far as dd goes
        if d.hi.abs() <= SEPARATRIX_GAP {
            return Err(ReferenceError::NearSeparatrix {
                k2_minus_1: d.hi,
                gap: SEPARATRIX_GAP,
            });
        }
        let k = k2.sqrt();
        let dir = if theta_dot0.hi < 0.0 { -1.0 } else { 1.0 };
        let cos_theta0 = Dd::from(1.0).sub(k2.mul_f64(2.0)).hi;
        let p = if d.hi < 0.0 {
            // Swing: sn(u₀) = s/k, cn(u₀) = |q|/k (θ'₀ = 2kω·dir·cn(u₀)),
            // dn(u₀) = c; u₀ = F(φ₀ | k²) = sin φ₀ · R_F(cos²φ₀, 1 − k² sin²φ₀, 1).
            let kc = d.neg().sqrt();
            let big_k = complete_k_dd(kc);
            let u0 = if k.hi == 0.0 {
                0.0 // at rest at the bottom: any phase
            } else {
                let cos_phi = q.div(k).hi;
                s.div(k).hi * carlson_rf(cos_phi * cos_phi, c.hi * c.hi, 1.0)
            };
            PendulumExact {
                theta0,
                g,
                l,
                m,
                k,
                kc,
                omega,
                big_k,
                cos_theta0,
                motion: Motion::Swing,
                u0: Dd::from(u0),
                rate: omega,
                dir,
                jk: k.hi,
                jkc: kc.hi,
            }
        } else {
            // Loop: Jacobi modulus κ = 1/k, κ' = √(k² − 1)/k; sn(u₀) = s,
            // cn(u₀) = c ≥ 0, dn(u₀) = |q|/k; u₀ = F(θ₀/2 | κ²) = s·R_F(c², 1 − s²/k², 1).
            let kappa = Dd::from(1.0).div(k);
            let kappa_c = d.sqrt().div(k);
            let big_k = complete_k_dd(kappa_c);
            let dn0 = q.div(k).hi;
            let u0 = s.hi * carlson_rf(c.hi * c.hi, dn0 * dn0, 1.0);
            PendulumExact {
                theta0,
                g,
                l,
                m,
                k,
                kc: Dd::from(0.0),
                omega,
                big_k,
                cos_theta0,
                motion: Motion::Loop,
                u0: Dd::from(u0),
                rate: omega.mul(k),
                dir,
                jk: kappa.hi,
                jkc: kappa_c.hi,
            }
        };
        Self::checked(p)
    }

    /// Released at rest: `u = K − ωt` (the turning point at `t = 0`).
    fn build_rest(
        theta0: f64,
        k: Dd,
        kc: Dd,
        g: f64,
        l: f64,
        m: f64,
    ) -> Result<Self, ReferenceError> {
        let valid = theta0 > 0.0 && theta0 < std::f64::consts::PI && kc.hi > 0.0 && k.hi >= 0.0;
        if !valid {
            return Err(ReferenceError::AngleOutOfRange { theta0 });
        }
        let omega = Dd::from(g).div(Dd::from(l)).sqrt();
        let big_k = complete_k_dd(kc);
        let cos_theta0 = kc.mul(kc).sub(k.mul(k)).hi;
        Self::checked(PendulumExact {
            theta0,
            g,
            l,
            m,
            k,
            kc,
            omega,
            big_k,
            cos_theta0,
            motion: Motion::Swing,
            u0: big_k,
            rate: omega,
            dir: -1.0,
            jk: k.hi,
            jkc: kc.hi,
        })
    }

    /// Refuse a motion whose values cannot be represented.
    fn checked(p: PendulumExact) -> Result<Self, ReferenceError> {
        let (g, l, m, omega) = (p.g, p.l, p.m, p.omega);
        let period = p.period();
        // The largest values of the motion: the start, and the bottom of
        // the swing (u = 0: the greatest speed and multiplier). Anything that
        // overflows there (L² or (Lθ')² in λ, say) is refused now rather
        // than returned later as NaN or ∞.
        let representable = omega.hi.is_finite()
            && omega.hi > 0.0
            && period.is_finite()
            && period > 0.0
            && p.state(0.0).iter().all(|v| v.is_finite())
            && p.state_from(0.0, 1.0, 1.0).iter().all(|v| v.is_finite());
        if !representable {
            return Err(ReferenceError::Unrepresentable {
                g,
                length: l,
                mass: m,
            });
        }
        Ok(p)
    }

    /// Release angle `θ₀` (radians, from the downward vertical).
    pub fn theta0(&self) -> f64 {
        self.theta0
    }

    /// Gravity `g`.
    pub fn gravity(&self) -> f64 {
        self.g
    }

    /// Rod length `L`.
    pub fn length(&self) -> f64 {
        self.l
    }

    /// Mass `m`.
    pub fn mass(&self) -> f64 {
        self.m
    }

    /// Modulus `k` (`sin(θ₀/2)` for a release at rest; `k² = sin²(θ₀/2) +
    /// θ'₀²/(4ω²)` in general; above 1 for a loop).
    pub fn modulus(&self) -> f64 {
        self.k.hi
    }

    /// Whether the pendulum swings or loops over the top.
    pub fn motion(&self) -> Motion {
        self.motion
    }

    /// Angular frequency scale `ω = √(g/L)` (not the frequency of the swing,
    /// which is `2π/T`).
    pub fn omega(&self) -> f64 {
        self.omega.hi
    }

    /// Complete elliptic integral of the first kind of the Jacobi modulus:
    /// `K(k)` for a swing, `K(1/k)` for a loop.
    pub fn quarter_period_k(&self) -> f64 {
        self.big_k.hi
    }

    /// Period: `T = 4K(k)/ω` of a swing, `T = 2K(1/k)/(kω)` of one
    /// revolution of a loop.
    ///
    /// ```
    /// use dae::reference::PendulumExact;
    ///
    /// // Small amplitude: T → 2π √(L/g) (1 + θ₀²/16).
    /// let p = PendulumExact::new(1e-3, 9.81, 1.0, 1.0).unwrap();
    /// let t0 = 2.0 * std::f64::consts::PI / 9.81f64.sqrt();
    /// assert!((p.period() - t0 * (1.0 + 1e-6 / 16.0)).abs() < 1e-12);
    /// ```
    pub fn period(&self) -> f64 {
        let quarters = match self.motion {
            Motion::Swing => 4.0,
            Motion::Loop => 2.0,
        };
        self.big_k.mul_f64(quarters).div(self.rate).hi
    }

    /// Total energy `E = ½m(v² + w²) + m g y`, conserved along the motion;
    /// equals `m g L (2k² − 1)` (`−m g L cos θ₀` for a release at rest).
    pub fn energy(&self) -> f64 {
        -self.m * self.g * self.l * self.cos_theta0
    }

    /// Jacobi functions `(sn, cn, dn)` of `u = u0 ± rate·t` (`K − ωt` for a
    /// release at rest), with `u` formed and reduced in double-double
    /// arithmetic.
    fn jacobi_at(&self, t: f64) -> Option<(f64, f64, f64)> {
        if !t.is_finite() {
            return None;
        }
        let advance = self.rate.mul_f64(t);
        let u = if self.dir < 0.0 {
            self.u0.sub(advance)
        } else {
            self.u0.add(advance)
        };
        jacobi_dd(u, self.big_k, self.jk, self.jkc)
    }

    /// `θ'` from the Jacobi functions: `2kω·dir·cn` (swing), `2kω·dir·dn`
    /// (loop).
    fn theta_dot(&self, cn: f64, dn: f64) -> f64 {
        let f = match self.motion {
            Motion::Swing => cn,
            Motion::Loop => dn,
        };
        2.0 * self.dir * self.k.hi * self.omega.hi * f
    }

    /// Angle `θ(t)` (from the downward vertical; in `(−π, π]` for a loop,
    /// which passes the top) and angular velocity `θ'(t)`. NaNs where
    /// [`state`](Self::state) gives NaNs.
    pub fn angle(&self, t: f64) -> [f64; 2] {
        let Some((sn, cn, dn)) = self.jacobi_at(t) else {
            return [f64::NAN; 2];
        };
        let theta = match self.motion {
            // sin(θ/2) = k sn, cos(θ/2) = dn ≥ 0.
            Motion::Swing => 2.0 * (self.k.hi * sn).atan2(dn),
            // sin(θ/2) = sn, cos(θ/2) = cn: θ from sin θ and cos θ.
            Motion::Loop => (2.0 * sn * cn).atan2((cn - sn) * (cn + sn)),
        };
        [theta, self.theta_dot(cn, dn)]
    }

    /// The exact state `[x, y, v, w, λ]` at time `t` (released at `t = 0`).
    /// Negative `t` runs the motion backwards. A non-finite `t`, or one more
    /// than 2⁵¹ periods away from 0 (where the phase is lost even in
    /// double-double), gives NaNs.
    ///
    /// ```
    /// use dae::reference::PendulumExact;
    ///
    /// let p = PendulumExact::new(2.0, 9.81, 1.5, 2.0).unwrap();
    /// let [x, y, v, w, _] = p.state(123.4);
    /// assert!((x * x + y * y - 1.5 * 1.5).abs() < 1e-14);
    /// assert!((x * v + y * w).abs() < 1e-13);
    /// ```
    pub fn state(&self, t: f64) -> [f64; 5] {
        let Some((sn, cn, dn)) = self.jacobi_at(t) else {
            return [f64::NAN; 5];
        };
        self.state_from(sn, cn, dn)
    }

    /// `[x, y, v, w, λ]` from the Jacobi functions of the phase.
    fn state_from(&self, sn: f64, cn: f64, dn: f64) -> [f64; 5] {
        let (k, l) = (self.k.hi, self.l);
        let (sin_theta, cos_theta) = match self.motion {
            Motion::Swing => {
                // cos θ = 1 − 2k²sn² = cos θ₀ + 2k²cn²: the second form is
                // exact at the turning points (cn = 0) and keeps y, v, λ
                // accurate to the last digit there, however small they are.
                let kcn = k * cn;
                (2.0 * k * sn * dn, self.cos_theta0 + 2.0 * kcn * kcn)
            }
            // sin θ = 2 sin(θ/2) cos(θ/2), cos θ = cos²(θ/2) − sin²(θ/2),
            // the latter as a product: no cancellation near θ = ±π/2.
            Motion::Loop => (2.0 * sn * cn, (cn - sn) * (cn + sn)),
        };
        let theta_dot = self.theta_dot(cn, dn);
        let x = l * sin_theta;
        let y = -l * cos_theta;
        let v = l * cos_theta * theta_dot;
        let w = l * sin_theta * theta_dot;
        // v² + w² = L²θ'² (exactly, not up to rounding).
        let speed2 = (l * theta_dot) * (l * theta_dot);
        let lambda = self.m * (speed2 - self.g * y) / (2.0 * l * l);
        [x, y, v, w, lambda]
    }
}

/// Complete elliptic integral of the first kind `K(k) = ∫₀^{π/2} dφ/√(1 − k² sin²φ)`
/// by the arithmetic–geometric mean, `K = π/(2·AGM(1, √(1 − k²)))`
/// (Abramowitz & Stegun 17.6). Depends on `k²` only; `K(±1) = ∞`; NaN for
/// `|k| > 1` or NaN `k`.
///
/// ```
/// use dae::reference::complete_elliptic_k;
///
/// assert!((complete_elliptic_k(0.0) - std::f64::consts::FRAC_PI_2).abs() < 1e-16);
/// assert!((complete_elliptic_k(0.5f64.sqrt()) - 1.8540746773013719).abs() < 1e-15);
/// ```
pub fn complete_elliptic_k(k: f64) -> f64 {
    let k = k.abs();
    if k.is_nan() || k > 1.0 {
        return f64::NAN;
    }
    if k == 1.0 {
        return f64::INFINITY;
    }
    complete_k_dd(Dd::from(complementary_modulus(k))).hi
}

/// Jacobi elliptic functions `(sn(u|k²), cn(u|k²), dn(u|k²))` for a modulus
/// `0 ≤ |k| ≤ 1`, by the descending Landen transformation (Abramowitz &
/// Stegun 16.4) after reducing `u` modulo `2K(k)` in double-double
/// arithmetic. `k = 1` gives `(tanh u, sech u, sech u)`. NaNs for a
/// non-finite `u`, `|u|` beyond 2⁵² half periods, `|k| > 1` or NaN `k`.
///
/// The reduction is exact for the `f64` arguments given; when `k` is the
/// rounded value of some exact modulus, the one-ulp error of `k` makes
/// `K(k)` — and hence the phase after `n` periods — uncertain by `n` ulps.
/// [`PendulumExact`] avoids this by carrying `k` in double-double.
///
/// ```
/// use dae::reference::jacobi_sn_cn_dn;
///
/// let (sn, cn, dn) = jacobi_sn_cn_dn(0.7, 0.0);
/// assert!((sn - 0.7f64.sin()).abs() < 1e-16 && (cn - 0.7f64.cos()).abs() < 1e-16);
/// assert_eq!(dn, 1.0);
/// let (sn, cn, dn) = jacobi_sn_cn_dn(0.7, 0.8);
/// assert!((sn * sn + cn * cn - 1.0).abs() < 1e-15);
/// assert!((dn * dn + 0.64 * sn * sn - 1.0).abs() < 1e-15);
/// ```
pub fn jacobi_sn_cn_dn(u: f64, k: f64) -> (f64, f64, f64) {
    let k = k.abs();
    if k.is_nan() || k > 1.0 || !u.is_finite() {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    if k == 1.0 {
        let sech = 1.0 / u.cosh();
        return (u.tanh(), sech, sech);
    }
    let kc = complementary_modulus(k);
    let big_k = complete_k_dd(Dd::from(kc));
    jacobi_dd(Dd::from(u), big_k, k, kc).unwrap_or((f64::NAN, f64::NAN, f64::NAN))
}

/// `√(1 − k²) = √((1 − k)(1 + k))`, accurate for `k` near 1.
fn complementary_modulus(k: f64) -> f64 {
    ((1.0 - k) * (1.0 + k)).sqrt()
}

/// Carlson's symmetric elliptic integral of the first kind
/// `R_F(x, y, z) = ½∫₀^∞ dt/√((t + x)(t + y)(t + z))` for `x, y, z ≥ 0`, at
/// most one of them zero, by the duplication theorem (Carlson 1995,
/// *Numer. Algorithms* 10, algorithm of §2): each step shrinks the spread
/// of the arguments fourfold; once it is below `10⁻³` the fifth-order
/// series leaves a relative error below `10⁻¹⁷`. `F(φ | m) = sin φ ·
/// R_F(cos²φ, 1 − m sin²φ, 1)` for `|φ| ≤ π/2` (DLMF 19.25.5).
fn carlson_rf(x: f64, y: f64, z: f64) -> f64 {
    let (mut x, mut y, mut z) = (x, y, z);
    let mut mean = (x + y + z) / 3.0;
    // 60 steps shrink any spread of doubles by 4⁶⁰; the loop ends far sooner.
    for _ in 0..60 {
        let spread = (mean - x).abs().max((mean - y).abs()).max((mean - z).abs());
        if spread <= 1e-3 * mean.abs() {
            break;
        }
        let (sx, sy, sz) = (x.sqrt(), y.sqrt(), z.sqrt());
        let lambda = sx * sy + sx * sz + sy * sz;
        x = 0.25 * (x + lambda);
        y = 0.25 * (y + lambda);
        z = 0.25 * (z + lambda);
        mean = (x + y + z) / 3.0;
    }
    let (dx, dy) = ((mean - x) / mean, (mean - y) / mean);
    let dz = -(dx + dy);
    let e2 = dx * dy - dz * dz;
    let e3 = dx * dy * dz;
    (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / mean.sqrt()
}

/// `K = π / (2·AGM(1, k'))` in double-double (A&S 17.6.1 with 17.6.2–17.6.3).
fn complete_k_dd(kc: Dd) -> Dd {
    let (mut a, mut b) = (Dd::from(1.0), kc);
    // Quadratic convergence: ~6 steps for k' = 1/√2, ~10 for k' = 10⁻¹⁶.
    for _ in 0..64 {
        let diff = a.sub(b);
        if diff.hi.is_nan() || diff.hi.abs() <= 1e-33 * a.hi {
            break;
        }
        let next_a = a.add(b).mul_f64(0.5);
        b = a.mul(b).sqrt();
        a = next_a;
    }
    PI_DD.div(a.mul_f64(2.0))
}

/// `(sn, cn, dn)(u)` with `u` given in double-double.
///
/// `u` is reduced to `r = u − n·2K ∈ [−K, K]`, with `sn u = (−1)ⁿ sn r`,
/// `cn u = (−1)ⁿ cn r`, `dn u = dn r` (A&S 16.8). When `|r| > K/2` the
/// distance `ε = K − |r|` to the quarter period is formed in double-double
/// too and `sn(K − ε) = cn ε/dn ε`, `cn(K − ε) = k'·sn ε/dn ε`,
/// `dn(K − ε) = k'/dn ε` (A&S 16.8.1) are used, so `cn` keeps full relative
/// accuracy near its zeros — for the pendulum, near the turning points.
fn jacobi_dd(u: Dd, big_k: Dd, k: f64, kc: f64) -> Option<(f64, f64, f64)> {
    let two_k = big_k.mul_f64(2.0);
    let n = (u.hi / two_k.hi).round();
    // Beyond 2⁵² half-periods `n` is no longer an exact integer in
    // floating point and the phase is meaningless: NaN, not noise.
    if n.is_nan() || n.abs() > MAX_HALF_PERIODS {
        return None;
    }
    let r = u.sub(two_k.mul_f64(n));
    if !r.hi.is_finite() {
        return None;
    }
    let (sn, cn, dn) = if r.hi.abs() > 0.5 * big_k.hi {
        let eps = big_k.sub(if r.hi < 0.0 { r.neg() } else { r }).hi;
        let (s, c, d) = landen(eps, k, kc);
        let sn = (c / d).copysign(r.hi);
        (sn, kc * s / d, kc / d)
    } else {
        landen(r.hi, k, kc)
    };
    if n % 2.0 != 0.0 {
        Some((-sn, -cn, dn))
    } else {
        Some((sn, cn, dn))
    }
}

/// Descending Landen transformation / AGM scheme, Abramowitz & Stegun 16.4:
///
/// ```text
/// a₀ = 1, b₀ = k', c₀ = k;  aₙ = (aₙ₋₁ + bₙ₋₁)/2, bₙ = √(aₙ₋₁bₙ₋₁), cₙ = cₙ₋₁²/(4aₙ)
/// φ_N = 2ᴺ a_N u,   φₙ₋₁ = (φₙ + asin((cₙ/aₙ) sin φₙ))/2,
/// sn = sin φ₀,  cn = cos φ₀,  dn = √(k'² + k² cn²).
/// ```
///
/// `cₙ = (aₙ₋₁ − bₙ₋₁)/2` is computed as `cₙ₋₁²/(4aₙ)` (equal since
/// `aₙ² − bₙ² = cₙ²`) to avoid the cancellation of the difference. Intended
/// for `|u| ≤ K`; `0 ≤ k < 1`, `k' = √(1 − k²) > 0`.
fn landen(u: f64, k: f64, kc: f64) -> (f64, f64, f64) {
    const MAX_LEVELS: usize = 32;
    let mut a = [0.0f64; MAX_LEVELS + 1];
    let mut c = [0.0f64; MAX_LEVELS + 1];
    a[0] = 1.0;
    c[0] = k;
    let mut b = kc;
    let mut n = 0;
    while n < MAX_LEVELS && c[n] > f64::EPSILON * 0.25 * a[n] {
        let a_next = 0.5 * (a[n] + b);
        b = (a[n] * b).sqrt();
        c[n + 1] = c[n] * c[n] / (4.0 * a_next);
        a[n + 1] = a_next;
        n += 1;
    }
    let mut phi = a[n] * u * 2f64.powi(n as i32);
    for level in (1..=n).rev() {
        let s = (c[level] / a[level]) * phi.sin();
        phi = 0.5 * (phi + s.clamp(-1.0, 1.0).asin());
    }
    let (sn, cn) = phi.sin_cos();
    let dn = (kc * kc + (k * cn) * (k * cn)).sqrt();
    (sn, cn, dn)
}

/// Smallest power of two `≥ v`, used for exact scaling; `None` when `v` is
/// not finite and positive or the power is above `f64::MAX` (`v > 2¹⁰²³`).
///
/// Read off the exponent bits, not searched for: a doubling search from 1
/// reached infinity for `v > 2¹⁰²³` and then halved infinity forever.
fn pow2_at_least(v: f64) -> Option<f64> {
    if !(v.is_finite() && v > 0.0) {
        return None;
    }
    let bits = v.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let fraction = bits & ((1u64 << 52) - 1);
    // v = 1.f·2^(biased − 1023), or f·2^−1074 for a subnormal (biased = 0).
    let e = if biased == 0 {
        let bits_used = 64 - fraction.leading_zeros() as i32; // ≥ 1: v > 0
        -1074
            + if fraction.is_power_of_two() {
                bits_used - 1
            } else {
                bits_used
            }
    } else {
        biased - 1023 + i32::from(fraction != 0)
    };
    if e > 1023 {
        None
    } else if e >= -1022 {
        Some(f64::from_bits(((e + 1023) as u64) << 52))
    } else {
        Some(f64::from_bits(1u64 << (e + 1074)))
    }
}

/// `sin x` in double-double by its Taylor series, for `0 ≤ x ≤ π/2`
/// (terms decrease from the first on and alternate: no cancellation beyond
/// a factor 2/π).
fn sin_dd(x: Dd) -> Dd {
    let x2 = x.mul(x);
    let mut term = x;
    let mut sum = x;
    for n in 1..40u32 {
        let denom = f64::from((2 * n) * (2 * n + 1));
        term = term.mul(x2).div(Dd::from(denom)).neg();
        sum = sum.add(term);
        if term.hi.is_nan() || term.hi.abs() <= 1e-35 * sum.hi.abs() {
            break;
        }
    }
    sum
}

/// Largest number of half periods `2K` the argument reduction accepts.
const MAX_HALF_PERIODS: f64 = 4_503_599_627_370_496.0; // 2⁵²

/// π in double-double.
const PI_DD: Dd = Dd {
    hi: std::f64::consts::PI,
    lo: 1.224_646_799_147_353_2e-16,
};

/// An unevaluated sum `hi + lo` with `|lo| ≤ ulp(hi)/2` (Dekker 1971;
/// Knuth TAOCP vol. 2 §4.2.2): about 106 significant bits.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Dd {
    hi: f64,
    lo: f64,
}

/// Error-free sum: `a + b = s + e` exactly (Knuth).
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    let e = (a - (s - bb)) + (b - bb);
    (s, e)
}

/// Error-free sum for `|a| ≥ |b|` (Dekker).
fn quick_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let e = b - (s - a);
    (s, e)
}

/// Error-free product `a·b = p + e` exactly, by a fused multiply-add.
fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let e = a.mul_add(b, -p);
    (p, e)
}

impl Dd {
    fn from(v: f64) -> Dd {
        Dd { hi: v, lo: 0.0 }
    }

    fn from_prod(a: f64, b: f64) -> Dd {
        let (hi, lo) = two_prod(a, b);
        Dd { hi, lo }
    }

    fn norm(s: f64, e: f64) -> Dd {
        let (hi, lo) = quick_two_sum(s, e);
        Dd { hi, lo }
    }

    fn neg(self) -> Dd {
        Dd {
            hi: -self.hi,
            lo: -self.lo,
        }
    }

    fn add(self, o: Dd) -> Dd {
        let (s, e) = two_sum(self.hi, o.hi);
        let (t, f) = two_sum(self.lo, o.lo);
        let r = Dd::norm(s, e + t);
        Dd::norm(r.hi, r.lo + f)
    }

    fn sub(self, o: Dd) -> Dd {
        self.add(o.neg())
    }

    fn mul(self, o: Dd) -> Dd {
        let (p, e) = two_prod(self.hi, o.hi);
        Dd::norm(p, e + (self.hi * o.lo + self.lo * o.hi))
    }

    fn mul_f64(self, b: f64) -> Dd {
        let (p, e) = two_prod(self.hi, b);
        Dd::norm(p, e + self.lo * b)
    }

    fn div(self, o: Dd) -> Dd {
        let q1 = self.hi / o.hi;
        let r = self.sub(o.mul_f64(q1));
        let q2 = r.hi / o.hi;
        let r = r.sub(o.mul_f64(q2));
        let q3 = r.hi / o.hi;
        Dd::norm(q1, q2).add(Dd::from(q3))
    }

    /// Square root by one Newton step on the `f64` root (Karp & Markstein).
    fn sqrt(self) -> Dd {
        if self.hi.is_nan() || self.hi <= 0.0 {
            return Dd::from(self.hi.sqrt());
        }
        let s = self.hi.sqrt();
        let residual = self.sub(Dd::from_prod(s, s));
        Dd::norm(s, residual.hi / (2.0 * s))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dd_pi_over_two_sine_is_one() {
        let half_pi = PI_DD.mul_f64(0.5);
        let s = sin_dd(half_pi);
        assert_eq!(s.hi, 1.0);
        assert!(s.lo.abs() < 1e-31);
    }

    #[test]
    fn dd_sqrt_half_squares_back() {
        let r = Dd::from(0.5).sqrt();
        let back = r.mul(r).sub(Dd::from(0.5));
        assert!(back.hi.abs() < 1e-31);
    }

    #[test]
    fn carlson_rf_gives_complete_and_incomplete_integrals() {
        // R_F(0, k'², 1) = K(k); R_F(x, x, x) = 1/√x; F(φ | 0) = φ.
        for k in [0.0f64, 0.3, 0.5f64.sqrt(), 0.99, 1.0 - 1e-12] {
            let kc = complementary_modulus(k);
            let rf = carlson_rf(0.0, kc * kc, 1.0);
            let big_k = complete_elliptic_k(k);
            assert!(
                (rf - big_k).abs() <= 4e-16 * big_k,
                "k = {k}: {rf} vs {big_k}"
            );
        }
        assert!((carlson_rf(4.0, 4.0, 4.0) - 0.5).abs() < 1e-16);
        for phi in [0.1f64, 0.7, 1.5] {
            let (s, c) = phi.sin_cos();
            assert!((s * carlson_rf(c * c, 1.0, 1.0) - phi).abs() < 4e-16);
        }
        // F(π/4 | 1/2) = 0.826017876249245… (mpmath.ellipf).
        let (s, c) = std::f64::consts::FRAC_PI_4.sin_cos();
        let f = s * carlson_rf(c * c, 1.0 - 0.5 * s * s, 1.0);
        assert!((f - 0.826_017_876_249_245).abs() < 1e-15, "{f}");
    }

    #[test]
    fn pow2_scaling() {
        assert_eq!(pow2_at_least(1.0), Some(1.0));
        assert_eq!(pow2_at_least(3.0), Some(4.0));
        assert_eq!(pow2_at_least(0.3), Some(0.5));
        assert_eq!(pow2_at_least(0.25), Some(0.25));
        // The whole range, including where a doubling search never ended.
        assert_eq!(pow2_at_least(8e307), Some(2f64.powi(1023)));
        assert_eq!(pow2_at_least(1e308), None); // 2^1024 overflows
        assert_eq!(pow2_at_least(2f64.powi(1023)), Some(2f64.powi(1023)));
        assert_eq!(pow2_at_least(f64::MAX), None);
        assert_eq!(pow2_at_least(f64::MIN_POSITIVE), Some(f64::MIN_POSITIVE));
        assert_eq!(pow2_at_least(5e-324), Some(5e-324));
        assert_eq!(pow2_at_least(3.0 * 5e-324), Some(4.0 * 5e-324));
        assert_eq!(pow2_at_least(1e-310), Some(2f64.powi(-1029)));
        for v in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(pow2_at_least(v), None);
        }
        for v in [1e-300, 7.0, 1e100, 123.456e200] {
            let p = pow2_at_least(v).unwrap();
            assert!(p >= v && p * 0.5 < v, "{v}: {p}");
        }
    }
}
