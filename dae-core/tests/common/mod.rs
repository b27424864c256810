//! Helpers shared by dae-core's integration tests.

use dae_core::expr;
use dae_core::Derived;

/// Derive model text, or fail the test with the located error.
pub fn derive(src: &str) -> Derived {
    Derived::from_str(src).unwrap_or_else(|e| panic!("model does not derive: {e}"))
}

/// `derived − hand` simplifies to zero exactly.
pub fn assert_same(d: &Derived, derived: &expr::Expr, hand: &str) {
    let h = d
        .model
        .parse_expr(hand)
        .unwrap_or_else(|e| panic!("bad hand expression {hand}: {e}"));
    let diff = expr::sub(derived, &h);
    if diff.is_zero() {
        return;
    }
    // The canonical form keeps linear forms such as `x2 - x1` factored
    // (`expr::is_linear_form`), so an identity that needs one multiplied
    // out (`2*(x2 - x1)*vx2` against `2*x2*vx2 - 2*x1*vx2`) is not decided
    // by structure. Decide it by evaluation instead: at five points with
    // every symbol in [0.5, 1.5), the two sides agree to a few roundings of
    // the larger (an expression that differs does not, but for a
    // coincidence at all five points).
    for k in 0..5u64 {
        let env = |s: expr::Sym| {
            let id = match s {
                expr::Sym::Var(i) => u64::from(i),
                expr::Sym::Der(i) => 1_000 + u64::from(i),
                expr::Sym::Param(i) => 2_000 + u64::from(i),
                expr::Sym::Time => 3_000,
                expr::Sym::Dir(i) => 4_000 + u64::from(i),
            };
            let h = (id * 7 + k * 1_013 + 1)
                .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                .rotate_left(29);
            0.5 + (h % 1_000_000) as f64 / 1e6
        };
        let (a, b) = (derived.eval(&env), h.eval(&env));
        assert!(
            (a - b).abs() <= 1e-12 * (1.0 + a.abs().max(b.abs())),
            "derived `{}` differs from `{hand}` by `{}` ({a} against {b} at point {k})",
            d.model.text(derived),
            d.model.text(&diff)
        );
    }
}
