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
    assert!(
        diff.is_zero(),
        "derived `{}` differs from `{hand}` by `{}`",
        d.model.text(derived),
        d.model.text(&diff)
    );
}
