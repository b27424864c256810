//! The `dae!` macro: a constrained-dynamics model in, its formulations with
//! analytic Jacobians out, as straight-line Rust.
//!
//! This crate is thin on purpose: `dae_core` parses, checks and derives the
//! model and lowers every formulation to tapes; the `expand` module
//! turns tapes into tokens. Use the macro through the `dae` facade crate
//! (`dae::dae!`); the generated code refers to `::dae::__private`.
//!
//! Set `DAE_MACRO_TIMING=1` in the environment of a build to have every
//! expansion print its time and the number of generated tokens to stderr
//! (cargo does not track the variable: touch the invoking file to force a
//! re-expansion).

extern crate proc_macro;

mod codegen;
mod expand;

/// Define a model and generate its formulations.
///
/// The body is the model language (see `dae_core::dsl`), or
/// `include "path/to/model.dae"` with a path relative to the invoking
/// crate's `CARGO_MANIFEST_DIR`.
///
/// ```ignore
/// dae::dae! {
///     /// A point mass on a rod.
///     pub Pendulum {
///         parameters { m = 1.0, l = 1.0, g = 9.81 }
///         differential { x, y, v, w }
///         algebraic { lambda }
///         equations {
///             der(x) = v;
///             der(y) = w;
///             m * der(v) = -2 * x * lambda;
///             m * der(w) = -2 * y * lambda - m * g;
///             0 = x^2 + y^2 - l^2;
///         }
///         formulations { rcd1, ggl1 }
///     }
/// }
/// ```
///
/// generates `pub struct Pendulum { pub m: f64, pub l: f64, pub g: f64 }`
/// (`Default` gives the defaults), `PendulumRcd1` and `PendulumGgl1`
/// implementing `DaeSystem` and `StaticSize`, constructors
/// `Pendulum::rcd1(&self)`, `Pendulum::ggl1(&self)`, and `Model` for
/// `Pendulum`. A model that fails to check is one compile error per
/// problem, each at the offending token.
///
/// `definitions { r2 = x^2 + y^2; }` leave no trace in the items: each use
/// is the expression pasted in, computed once per call like any shared
/// subexpression (one `let` per tape node). Derived parameters
/// (`derived { l2 = l^2; }`) are not fields of the struct: each
/// formulation's constructor computes them once from the fields and stores
/// them (its fields are then private, so they cannot go stale);
/// `Model::parameter` reads them and `Model::set_parameter` refuses them
/// with `ParameterError::Derived`.
#[proc_macro]
pub fn dae(input: proc_macro::TokenStream) -> proc_macro::TokenStream {
    let timing = std::env::var_os("DAE_MACRO_TIMING").is_some_and(|v| v == "1");
    let start = std::time::Instant::now();
    let out = expand::expand(input.into());
    if timing {
        eprintln!(
            "dae!: expanded in {:.3} ms, {} tokens",
            start.elapsed().as_secs_f64() * 1e3,
            expand::count_tokens(&out)
        );
    }
    out.into()
}
