//! The `iscene` command line: parse, dispatch to one function per subcommand, print. Exit codes:
//! 0 success, 2 bad input, 1 internal failure.

use std::process::ExitCode;

use clap::Parser;
use iscene::error::IsceneError;

mod args;
mod batch;
mod bench;
mod cad;
mod reconstruct;
mod scene_commands;
mod simulate;
mod view;

use args::{Cli, Command};

#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn run(cli: Cli) -> Result<(), IsceneError> {
    // Progress bars only where a person watches.
    let interactive = std::io::IsTerminal::is_terminal(&std::io::stderr());
    match cli.command {
        None => reconstruct::reconstruct(reconstruct::default_args()?, interactive),
        Some(Command::Reconstruct(args)) => reconstruct::reconstruct(args, interactive),
        Some(Command::Render(args)) => scene_commands::render(args, interactive),
        Some(Command::Generate(args)) => scene_commands::generate(args),
        Some(Command::Eval(args)) => scene_commands::eval(args),
        Some(Command::Benchmark(args)) => batch::benchmark(args),
        Some(Command::Batch(args)) => batch::batch(args),
        Some(Command::Simulate(args)) => simulate::simulate(args),
        Some(Command::View(args)) => view::view(args, interactive),
        Some(Command::Bench { command }) => bench::bench(command),
        Some(Command::Cad { command }) => cad::cad(command),
    }
}

#[expect(clippy::print_stdout, reason = "machine-readable results go to stdout")]
pub(crate) fn print_json(value: &impl serde::Serialize) -> Result<(), IsceneError> {
    let text =
        serde_json::to_string_pretty(value).map_err(|e| IsceneError::Internal(e.to_string()))?;
    println!("{text}");
    Ok(())
}

/// Warnings the library logs (what it skipped or recovered from) go to stderr; `RUST_LOG` asks for
/// more or less (`RUST_LOG=iscene=debug`, `RUST_LOG=error`). The viewer logs through it too.
fn init_logging() {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn"));
    let installed = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .try_init();
    if let Err(e) = installed {
        eprintln!("iscene: warnings will not be shown: {e}");
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    init_logging();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("iscene: error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
