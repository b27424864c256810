//! The `dae` command: derive formulations, run a scene, sweep the
//! speed/accuracy trade.

use clap::{Parser, Subcommand};
use dae::cli::{self, derive::Format, Failure};
use std::io::Write;

#[derive(Parser)]
#[command(
    name = "dae",
    version,
    about = "Constrained dynamics: every formulation, measured",
    after_help = "Exit codes: 0 done (dae sweep: the new complete set is in --out); 2 bad input \
                  (nothing run, --out untouched); 3 dae run: the solver stopped before the end or \
                  could not start (the record is printed); 4 dae sweep: the outputs could not be \
                  written, or another sweep holds --out (the previous set is kept); 130 \
                  interrupted (the previous set is kept)."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Hidden constraints, formulations and structural numbers of a model.
    Derive {
        /// A `.dae` file, or a built-in model name.
        #[arg(default_value = "pendulum")]
        model: String,
        /// Output format.
        #[arg(long, value_enum, default_value = "text")]
        format: Format,
    },
    /// Run one scene with one solver, formulation and tolerance.
    Run(cli::run::RunArgs),
    /// Sweep solvers × formulations × tolerances: tables, figures, index.html.
    Sweep(cli::sweep::SweepArgs),
}

/// Run a sweep; print its report and exit with its code.
fn sweep(args: &cli::sweep::SweepArgs) -> Result<String, Failure> {
    let (out, code) = cli::sweep::run(args)?;
    print!("{out}");
    let _ = std::io::stdout().flush();
    std::process::exit(code);
}

fn main() {
    // SIGINT: a sweep's staging directory is removed and the previous
    // output set kept (exit 130); once the new set is in place the
    // command finishes with its own code.
    let _ = ctrlc::set_handler(|| {
        if dae::sweep::write::interrupt() {
            std::process::exit(cli::EXIT_INTERRUPTED);
        }
    });
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Derive { model, format }) => cli::derive::run(&model, format),
        Some(Command::Run(args)) => match cli::run::run(&args) {
            Ok((out, code)) => {
                // A closed stdout (`dae run | head -1`) is not a failure
                // of the run: the exit code stays the run's.
                let mut stdout = std::io::stdout().lock();
                let _ = stdout.write_all(out.as_bytes());
                let _ = stdout.flush();
                std::process::exit(code);
            }
            Err(f) => Err(f),
        },
        Some(Command::Sweep(args)) => sweep(&args),
        // No arguments: the built-in S01 sweep into out/s01.
        None => sweep(&cli::sweep::SweepArgs::default()),
    };
    match result {
        Ok(out) => {
            let mut stdout = std::io::stdout().lock();
            let _ = stdout.write_all(out.as_bytes());
        }
        Err(Failure { code, message }) => {
            eprintln!("{message}");
            std::process::exit(code);
        }
    }
}
