//! Built-in models and loading models by name or path.

use dae_core::derive::{render_error, Derived};
use dae_core::interp::InterpretedModel;
use dae_core::system::Model;
use std::path::Path;

/// Model-language source of the built-in pendulum (also `scenes/pendulum.dae`).
pub const PENDULUM_SOURCE: &str = include_str!("../scenes/pendulum.dae");

/// The built-in pendulum, compiled by the `dae!` macro from the same text.
pub mod builtin {
    crate::dae! { include "scenes/pendulum.dae" }
}

/// Names of the built-in models.
pub const BUILTIN_MODELS: [&str; 1] = ["pendulum"];

/// Why a model could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The file could not be read.
    #[error("cannot read model file {path}: {source}")]
    Io {
        /// The path tried.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The path is a directory.
    #[error("model file {path} is a directory, not a model file")]
    IsDirectory {
        /// The path given.
        path: String,
    },
    /// Neither a built-in model nor an existing file.
    #[error(
        "no model `{spec}`: neither a built-in model (built-in: {}) nor an existing model file",
        BUILTIN_MODELS.join(", ")
    )]
    NotFound {
        /// What was given.
        spec: String,
    },
    /// The model text has errors (rendered with `file:line:column`).
    #[error("{0}")]
    Invalid(String),
}

/// A model's text and the name its messages show (what [`derive()`] reads).
#[derive(Clone, Debug)]
pub struct ModelText {
    /// Name shown in messages (`pendulum` or the path).
    pub label: String,
    /// The model text.
    pub text: String,
}

/// Resolve a built-in name (`pendulum`) or read a `.dae` file.
pub fn source(spec: &str) -> Result<ModelText, ModelError> {
    if let Some(&name) = BUILTIN_MODELS.iter().find(|n| **n == spec) {
        return Ok(ModelText {
            label: name.to_string(),
            text: PENDULUM_SOURCE.to_string(),
        });
    }
    let path = Path::new(spec);
    if path.is_dir() {
        return Err(ModelError::IsDirectory { path: spec.into() });
    }
    let looks_like_path = spec.ends_with(".dae") || spec.contains('/') || spec.contains('\\');
    if !looks_like_path && !path.exists() {
        return Err(ModelError::NotFound { spec: spec.into() });
    }
    let text = std::fs::read_to_string(path).map_err(|source| ModelError::Io {
        path: spec.to_string(),
        source,
    })?;
    Ok(ModelText {
        label: spec.to_string(),
        text,
    })
}

/// Parse, check and derive a model source.
pub fn derive(src: &ModelText) -> Result<Derived, ModelError> {
    Derived::from_str(&src.text).map_err(|e| ModelError::Invalid(render_error(&e, &src.label)))
}

/// A runnable model by built-in name or path: the compiled built-in or an
/// interpreted file.
pub fn load(spec: &str) -> Result<Box<dyn Model + Send + Sync>, ModelError> {
    if spec == "pendulum" {
        return Ok(Box::new(builtin::Pendulum::default()));
    }
    let src = source(spec)?;
    lazy(&src)
}

/// The interpreted model of `src`, each formulation lowered when first
/// asked for.
fn lazy(src: &ModelText) -> Result<Box<dyn Model + Send + Sync>, ModelError> {
    let m = InterpretedModel::lazy(&src.text)
        .map_err(|e| ModelError::Invalid(render_error(&e, &src.label)))?;
    Ok(Box::new(m))
}

/// The runnable model a scene names: a built-in by name, a file by its
/// path — also a file whose path reads like a built-in's name (`pendulum`).
#[cfg(feature = "cli")]
#[cfg_attr(docsrs, doc(cfg(feature = "cli")))]
pub fn load_source(
    source: &crate::scene::ModelSource,
) -> Result<Box<dyn Model + Send + Sync>, ModelError> {
    match source {
        crate::scene::ModelSource::Builtin(name) => load(name),
        crate::scene::ModelSource::File(path) => {
            let label = path.display().to_string();
            if path.is_dir() {
                return Err(ModelError::IsDirectory { path: label });
            }
            let text = std::fs::read_to_string(path).map_err(|source| ModelError::Io {
                path: label.clone(),
                source,
            })?;
            lazy(&ModelText { label, text })
        }
    }
}
