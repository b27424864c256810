//! `dae derive [MODEL] [--format text|latex|json]`.

use super::Failure;
use crate::models;
use dae_core::report;

/// Output format of `dae derive`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Human-readable text.
    Text,
    /// LaTeX `align*` blocks.
    Latex,
    /// JSON (contract shape, deterministic).
    Json,
}

/// Derive and render a model given by built-in name or path.
pub fn run(model: &str, format: Format) -> Result<String, Failure> {
    let src = models::source(model).map_err(|e| Failure::input(e.to_string()))?;
    let d = models::derive(&src).map_err(|e| Failure::input(e.to_string()))?;
    Ok(match format {
        Format::Text => report::text(&d),
        Format::Latex => report::latex(&d),
        Format::Json => report::Report::new(&d).to_json() + "\n",
    })
}
