//! `dae derive`'s output of every model the repository ships, compared
//! byte for byte with the files in `tests/data/derive/` (text and JSON).
//!
//! A change to the analysis or the formulations that alters what a shipped
//! model derives shows up here as a diff; when the change is intended, name
//! and explain it in the commit and rewrite the files with
//!
//! ```text
//! DAE_BLESS=1 cargo test -p dae-core --test derive_snapshots
//! ```

use dae_core::{report, Derived};
use std::path::{Path, PathBuf};

const BLESS: &str = "DAE_BLESS";

/// Every `.dae` file of the repository's scenes and test data, sorted.
fn models() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut out = Vec::new();
    let mut dirs = vec![root.join("scenes"), root.join("tests/data")];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).expect("read a model directory") {
            let path = entry.expect("a directory entry").path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "dae") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

#[test]
fn every_shipped_model_derives_as_recorded() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/derive");
    let bless = std::env::var_os(BLESS).is_some();
    let mut differ = Vec::new();
    let models = models();
    assert!(models.len() >= 9, "found only {} models", models.len());
    for path in models {
        let src = std::fs::read_to_string(&path).expect("read a model");
        let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
        let outputs = match Derived::from_str(&src) {
            Ok(d) => vec![
                ("txt", report::text(&d)),
                ("json", report::Report::new(&d).to_json() + "\n"),
            ],
            Err(e) => vec![("err", dae_core::derive::render_error(&e, &stem))],
        };
        for (ext, got) in outputs {
            let file = data.join(format!("{stem}.{ext}"));
            if bless {
                std::fs::write(&file, &got).expect("write a snapshot");
                continue;
            }
            match std::fs::read_to_string(&file) {
                Ok(want) if want == got => {}
                _ => differ.push(file.display().to_string()),
            }
        }
    }
    assert!(
        differ.is_empty(),
        "`dae derive` output differs from (or is missing in) {differ:?}; \
         if intended, explain it in the commit and run `{BLESS}=1 cargo test -p dae-core --test derive_snapshots`"
    );
}
