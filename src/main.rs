//! The `dae` command: derive formulations, run a scene, sweep the
//! speed/accuracy trade.

use clap::{Parser, Subcommand};
use dae::cli::{self, derive::Format, Failure};
use std::io::Write;

#[derive(Parser)]
#[command(
    name = "dae",
    version,
    about = "Constrained dynamics: every formulation, measured"
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
