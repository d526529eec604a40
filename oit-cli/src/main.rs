//! `oit`: the command line of oit — render one technique, compare techniques with the exact
//! reference, sweep the camera around the scene, write the bench report, and list the backends
//! compiled in.
//!
//! Contract: every failure prints one line `error: <message>` on stderr and exits with code 1
//! (clap's own usage errors keep clap's format and exit code 2). Reports go to stdout — a table,
//! or with `--json` JSON and nothing else — and progress to stderr.
//!
//! Scene, camera and shading options are one flattened struct ([`options::SceneArgs`]) shared by
//! `render`, `compare` and `sweep`; backends are chosen by name in one place, oit-bench's
//! registry (`oit_bench::backends`), and `compare`, `sweep` and `bench` run one loop, oit-bench's
//! `oit_bench::experiment`.

mod bench;
mod compare;
mod info;
mod options;
mod output;
mod plot;
mod render;
mod sweep;

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use oit_core::OitError;

/// Order-independent transparency techniques, measured against an exact reference.
#[derive(Parser, Debug)]
#[command(
    name = "oit",
    version,
    about = "Order-independent transparency techniques, measured against an exact reference",
    long_about = "Order-independent transparency techniques, measured against an exact reference.\n\n\
        oit renders a scene of transparent objects with one of many ways of capturing and \
        ordering the fragments of every pixel (depth peeling, bucket depth peeling, weighted \
        averages, fixed A-buffers, ...) and measures each against an exact A-buffer reference: \
        error pixel rate (EPR), PSNR, fragments lost, memory and time.\n\n\
        Run `oit info` for the backends compiled in and what each runs, and `oit <command> \
        --help` for a command's options.",
    propagate_version = true
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    Render(render::RenderArgs),
    Compare(compare::CompareArgs),
    Sweep(sweep::SweepArgs),
    Info(info::InfoArgs),
    Bench(bench::BenchArgs),
}

/// How a command ended when it did not fail outright.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Outcome {
    /// Everything asked for was done.
    Success,
    /// The command went on past failures it has already reported (one `error:` line each).
    Failed,
}

fn run(cli: Cli) -> Result<Outcome, OitError> {
    match cli.command {
        Command::Render(args) => render::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Sweep(args) => sweep::run(&args),
        Command::Info(args) => info::run(&args),
        Command::Bench(args) => bench::run(&args),
    }
}

/// Prints one `error:` line for a panic instead of Rust's message and backtrace note: a panic is
/// a bug in oit, and the user still gets the one-line contract.
fn install_panic_hook() {
    std::panic::set_hook(Box::new(|info| {
        let payload = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| (*s).to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown cause".into());
        let place = info.location().map(|l| format!(" at {}:{}", l.file(), l.line())).unwrap_or_default();
        let line = format!("internal error{place}: {payload}; this is a bug in oit, please report it");
        eprintln!("error: {}", line.replace('\n', " "));
    }));
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    install_panic_hook();
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(cli))) {
        Ok(Ok(Outcome::Success)) => ExitCode::SUCCESS,
        Ok(Ok(Outcome::Failed)) => ExitCode::FAILURE,
        Ok(Err(e)) => {
            output::error_line(&e.to_string());
            ExitCode::FAILURE
        }
        // The hook has already printed the one line.
        Err(_) => ExitCode::FAILURE,
    }
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    use super::Cli;

    #[test]
    fn clap_definition_is_consistent() {
        Cli::command().debug_assert();
    }
}
