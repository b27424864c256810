//! `dae sweep [SCENE] [--solvers …] [--formulations …] [--tols …]
//! [--repeats N] [--jobs N] [--out DIR] [--format text|json]`.
//!
//! Every solver × formulation × tolerance of the scene's `[sweep]` table
//! (flags override it). Prints the success matrix, the efficiency table,
//! the Pareto front, the fastest pair per target error and, for S01/S02,
//! the comparison with the paper; writes `results.csv`, `results.json`,
//! the figures (SVG and PNG) and `index.html` to `DIR` (default
//! `out/<scene name in lower case>`). `dae` without arguments runs
//! `dae sweep s01 --out out/s01`.
//!
//! `DIR` is written as one set: into a staging directory beside it, renamed
//! into place when complete. An existing `DIR` is replaced whole, and only
//! if it holds nothing but a sweep's outputs (checked before the sweep
//! runs); see [`sweep::write_outputs`].

use super::run::Format;
use super::Failure;
use crate::scene::Scene;
use crate::stability;
use crate::sweep::{self, SweepOptions};
use dae_solvers::init::InitMode;
use std::path::PathBuf;

/// Flags of `dae sweep`.
#[derive(Clone, Debug, clap::Args)]
pub struct SweepArgs {
    /// Scene file (TOML) or built-in scene name (`s01`, `s02`).
    #[arg(default_value = "s01")]
    pub scene: String,
    /// Solvers, comma-separated (default: the scene's `[sweep]` solvers).
    #[arg(long, value_delimiter = ',')]
    pub solvers: Option<Vec<String>>,
    /// Formulations, comma-separated (default: the scene's).
    #[arg(long, value_delimiter = ',')]
    pub formulations: Option<Vec<String>>,
    /// Tolerances RTOL = ATOL, comma-separated (default: the scene's), each
    /// in [100 ε, 1) = [2.220446049250313e-14, 1).
    #[arg(long, value_delimiter = ',')]
    pub tols: Option<Vec<f64>>,
    /// Timed integrations per run, at least: more (up to 50) while they
    /// total under 0.25 s of CPU time or fewer than 3 lie within 1 % of
    /// their minimum, fewer once they total 1 s; tsim is
    /// their minimum (interference only adds time), in CPU time of the
    /// integrating thread (wall time beside it in results.csv/json).
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Threads for the accuracy pass (timing stays sequential).
    #[arg(long, default_value_t = 1)]
    pub jobs: usize,
    /// Output directory (default: `out/<scene name in lower case>`, e.g.
    /// out/s01; `dae` without arguments writes to out/s01). Replaced as a
    /// whole when the sweep is complete; refused if it holds files a sweep
    /// does not write.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// What to print on stdout: the text tables or the results JSON.
    #[arg(long, value_enum, default_value = "text")]
    pub format: Format,
    /// Refuse inconsistent initial values instead of projecting them.
    #[arg(long)]
    pub strict_init: bool,
    /// No progress on stderr (otherwise a bar on a terminal, plain lines
    /// every 5 % or 10 s when stderr is a pipe or a file).
    #[arg(long)]
    pub quiet: bool,
    /// Build the stability map instead: every scene of DIR (default
    /// scenes/extremes) × its solvers × formulations × tolerances, each run
    /// bounded by --max-steps; writes map.txt, map.json, map.svg and
    /// map.png to --out (default out/extremes). --solvers and --tols
    /// restrict every case; the SCENE argument is not used.
    #[arg(long, value_name = "DIR", num_args = 0..=1,
          default_missing_value = "scenes/extremes")]
    pub extremes: Option<PathBuf>,
    /// Build the literature map instead: every scene of DIR (default
    /// scenes/literature: published problems with published reference
    /// values) × its solvers × formulations × tolerances, like --extremes,
    /// with the accuracy verdict on significant correct digits (accurate
    /// when scd ≥ −log10(tol) − 2) and a scd/steps table per case; writes
    /// to --out (default out/literature).
    #[arg(long, value_name = "DIR", num_args = 0..=1,
          default_missing_value = "scenes/literature", conflicts_with = "extremes")]
    pub literature: Option<PathBuf>,
    /// Steps (accepted + rejected) each run may take before it stops with
    /// a step-limit failure. Sweep: overrides the scene's `[sweep]
    /// max_steps` (default: the library's, 20 000 000). Stability map:
    /// default 5 000 000.
    #[arg(long)]
    pub max_steps: Option<usize>,
}

impl Default for SweepArgs {
    /// `dae sweep s01 --out out/s01`: what `dae` without arguments runs.
    fn default() -> Self {
        SweepArgs {
            scene: "s01".into(),
            solvers: None,
            formulations: None,
            tols: None,
            repeats: 3,
            jobs: 1,
            out: Some(PathBuf::from("out/s01")),
            format: Format::Text,
            strict_init: false,
            quiet: false,
            extremes: None,
            literature: None,
            max_steps: None,
        }
    }
}

/// The default output directory of a scene: `out/<name in lower case>`,
/// with characters other than letters, digits, `-` and `_` replaced.
pub fn default_out_dir(scene_name: &str) -> PathBuf {
    let name: String = scene_name
        .to_lowercase()
        .chars()
        .map(|c| {
            if c.is_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    PathBuf::from("out").join(if name.is_empty() {
        "sweep".into()
    } else {
        name
    })
}

/// Before any work: refuse an `--out` the sweep may not replace (exit 2:
/// files that are not a sweep's, a mount point) or that another process is
/// writing (exit 4), and take its lock.
fn lock_out(dir: &std::path::Path) -> Result<sweep::write::OutputLock, Failure> {
    let lock = sweep::write::OutputLock::acquire(dir).map_err(|e| {
        let f = Failure::sweep(&e.into());
        Failure {
            message: format!("--out: {}", f.message),
            ..f
        }
    })?;
    sweep::check_replaceable(dir).map_err(|e| Failure::input(format!("--out: {e}")))?;
    Ok(lock)
}

/// Run the sweep; `Ok((stdout, exit code))`.
pub fn run(args: &SweepArgs) -> Result<(String, i32), Failure> {
    if let Some(tols) = &args.tols {
        for t in tols {
            super::run::check_tol(*t, "--tols")?;
        }
    }
    if args.max_steps == Some(0) {
        return Err(Failure::input("--max-steps 0: at least one step is needed"));
    }
    if let Some(dir) = &args.extremes {
        return map(args, dir, MapKind::Extremes);
    }
    if let Some(dir) = &args.literature {
        return map(args, dir, MapKind::Literature);
    }
    if args.repeats == 0 {
        return Err(Failure::input(
            "--repeats 0: at least one timed run is needed",
        ));
    }
    let scene = Scene::load(&args.scene).map_err(|e| Failure::input(e.to_string()))?;
    let mut opts = SweepOptions::from_scene(&scene);
    if let Some(s) = &args.solvers {
        opts.solvers = s.clone();
    }
    if let Some(f) = &args.formulations {
        opts.formulations = f.clone();
    }
    if let Some(t) = &args.tols {
        opts.tolerances = t.clone();
    }
    opts.repeats = args.repeats;
    opts.jobs = args.jobs.max(1);
    opts.init_mode = if args.strict_init {
        InitMode::Strict
    } else {
        InitMode::Project
    };
    opts.progress = !args.quiet;
    if args.max_steps.is_some() {
        opts.max_steps = args.max_steps;
    }
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| default_out_dir(&scene.name));
    // Refuse an output directory the sweep may not replace, or that
    // another sweep is writing, before the work; hold it until written.
    let lock = lock_out(&dir)?;
    let report = sweep::run(&scene, &opts).map_err(|e| match &e {
        sweep::SweepError::Run(r) => Failure::input(format!("{}: {r}", scene.origin)),
        _ => Failure::input(e.to_string()),
    })?;
    let summary = sweep::Summary::of(&report);
    // Outputs that cannot be written (a full disk): exit 4, the previous
    // set kept.
    let written = sweep::write_outputs(&report, &summary, &dir, Some(&lock))
        .map_err(|e| Failure::sweep(&e))?;
    for n in &written.notes {
        eprintln!("note: {n}");
    }
    let index = dir.join("index.html");
    let out = match args.format {
        Format::Json => {
            eprintln!(
                "wrote {} files to {} (open {})",
                written.files.len(),
                dir.display(),
                index.display()
            );
            sweep::results_json_string(&report, &summary)
        }
        Format::Text => {
            let mut s = sweep::table::text_report(&report, &summary);
            s.push_str(&format!(
                "\nWrote results.csv, results.json, {} figure file(s) and index.html to {}\nOpen {}\n",
                written.files.iter().filter(|p| p.extension().is_some_and(|e| e == "svg" || e == "png")).count(),
                dir.display(),
                index.display()
            ));
            s
        }
    };
    Ok((out, 0))
}

/// Which map `dae sweep` builds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum MapKind {
    /// `--extremes`: the pendulum's extremes, the run's own verdict.
    Extremes,
    /// `--literature`: published problems, the verdict on digits.
    Literature,
}

impl MapKind {
    fn flag(self) -> &'static str {
        match self {
            MapKind::Extremes => "--extremes",
            MapKind::Literature => "--literature",
        }
    }
}

/// `dae sweep --extremes [DIR]` or `--literature [DIR]`: the stability map.
fn map(args: &SweepArgs, cases: &std::path::Path, kind: MapKind) -> Result<(String, i32), Failure> {
    let flag = kind.flag();
    if args.formulations.is_some() {
        return Err(Failure::input(
            "--formulations: the stability map runs every formulation of each case",
        ));
    }
    let files = stability::case_files(cases).map_err(|e| Failure::input(format!("{flag}: {e}")))?;
    if files.is_empty() {
        return Err(Failure::input(format!(
            "{flag} {}: no scene files (*.toml) there",
            cases.display()
        )));
    }
    let opts = stability::MapOptions {
        jobs: args.jobs.max(1),
        max_steps: args.max_steps.unwrap_or(crate::stability::MAP_MAX_STEPS),
        solvers: args.solvers.clone(),
        tolerances: args.tols.clone(),
        progress: !args.quiet,
        verdict: match kind {
            MapKind::Extremes => stability::Verdict::Accuracy,
            MapKind::Literature => stability::Verdict::Digits,
        },
    };
    let dir = args.out.clone().unwrap_or_else(|| {
        PathBuf::from("out").join(match kind {
            MapKind::Extremes => "extremes",
            MapKind::Literature => "literature",
        })
    });
    let lock = lock_out(&dir)?;
    let map = stability::build(&files, &opts).map_err(|e| Failure::input(e.to_string()))?;
    let files = stability::write(&map, &dir, Some(&lock)).map_err(|e| Failure::sweep(&e))?;
    let out = match args.format {
        Format::Json => {
            eprintln!("wrote {} files to {}", files.len(), dir.display());
            stability::json(&map)
        }
        Format::Text => format!(
            "{}\nWrote map.txt, map.json, map.svg and map.png to {}\n",
            stability::text(&map),
            dir.display()
        ),
    };
    Ok((out, 0))
}
