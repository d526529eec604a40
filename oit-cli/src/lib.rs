//! oit-cli: the command line of oit — render one technique, compare techniques with the exact
//! reference, sweep the camera around the scene, write the bench report, list the backends
//! compiled in, and (with the `view` feature, on by default) show the scene live in a window.
//! The `oit` binary (`main.rs`) is [`main`]; [`validate`] makes every check a command makes before
//! it works, without working, for the fuzz harness (`oit-fuzz`).
//!
//! Contract: every failure prints one line `error: <message>` on stderr and exits with code 1
//! (clap's own usage errors keep clap's format and exit code 2). Reports go to stdout — a table,
//! or with `--json` JSON and nothing else — and progress to stderr.
//!
//! Scene, camera and shading options are one flattened struct (`options::SceneArgs`) shared by
//! `render`, `compare` and `sweep`; backends are chosen by name in one place, oit-bench's
//! registry (`oit_bench::backends`), and `compare`, `sweep` and `bench` run one loop, oit-bench's
//! `oit_bench::experiment`.
//!
//! A command line parsed and checked as `oit` would, nothing rendered:
//!
//! ```
//! use clap::Parser;
//!
//! let cli = oit_cli::Cli::try_parse_from(["oit", "compare", "--size", "32x32", "-t", "dp,wavg"]).unwrap();
//! let checked = oit_cli::validate(&cli)?;
//! assert_eq!(checked.techniques.len(), 2);
//! assert_eq!(checked.prepared.expect("compare renders").scene.name, "default");
//!
//! let typo = oit_cli::Cli::try_parse_from(["oit", "render", "--technique", "fabs:0"]).unwrap();
//! assert!(oit_cli::validate(&typo).is_err()); // the error `oit` would print, nothing rendered
//! # Ok::<(), oit_core::OitError>(())
//! ```

mod bench;
mod compare;
mod info;
mod options;
mod output;
mod plot;
mod render;
#[cfg(all(unix, any(feature = "wgpu", feature = "vulkan")))]
mod runtime_dir;
mod sweep;
#[cfg(feature = "view")]
mod view;

#[cfg(not(feature = "view"))]
use std::ffi::OsString;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use oit_core::{OitError, Technique};

pub use options::Prepared;

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
        error pixel rate (EPR: the share of covered pixels off by more than 1 in 8 bits; tables \
        print it in per cent, JSON holds the fraction), PSNR, fragments lost, memory and time.\n\n\
        Which technique for which scene (exact and small, fastest exact on a GPU, one pass but \
        approximate, ...): the README's guide, \"Which technique for which scene\", with the \
        measured trade; `oit compare --scene YOURS` measures it on your own scene.\n\n\
        Run `oit info` for the backends compiled in and what each runs, and `oit <command> \
        --help` for a command's options.",
    propagate_version = true
)]
pub struct Cli {
    /// The command and its arguments.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands, one variant each with its arguments: `render` (`render::RenderArgs`),
/// `compare`, `sweep`, `info`, `bench` and `view` (with the `view` feature, on by default; a build
/// without it keeps the name, to say which feature to build with).
///
/// Each command's help, its line in `oit --help` and the paragraph atop `oit <command> --help`,
/// is its arguments' `about` and `long_about`. The variants carry no doc comment on purpose: clap
/// takes a variant's doc comment over its arguments' help (it had put `` `oit render` `` in
/// `oit --help` and left `oit render --help` without its paragraph).
#[derive(Subcommand, Debug)]
#[allow(missing_docs, reason = "a variant's doc comment would replace its command's help; see above")]
pub enum Command {
    Render(render::RenderArgs),
    Compare(compare::CompareArgs),
    Sweep(sweep::SweepArgs),
    Info(info::InfoArgs),
    Bench(bench::BenchArgs),
    #[cfg(feature = "view")]
    View(view::ViewArgs),
    #[cfg(not(feature = "view"))]
    View(NoView),
}

/// `oit view` in a build without the `view` feature: takes whatever follows and answers which
/// feature to build with, where clap alone would say "unrecognized subcommand".
#[cfg(not(feature = "view"))]
#[derive(clap::Args, Debug)]
#[command(
    about = "Show the scene in a window, live (not in this build: rebuild with the view feature)",
    long_about = "Show the scene in a window, live (not in this build: rebuild with the view feature).\n\n\
        The viewer (orbit, zoom, switch techniques and compare with the reference in a window \
        drawn by oit-wgpu) needs the `view` feature, which this binary was built without. Rebuild \
        with it: `cargo install --path oit-cli --features view` (on by default; \
        `--no-default-features` leaves it out)."
)]
pub struct NoView {
    /// The viewer's options, not read.
    #[arg(trailing_var_arg = true, allow_hyphen_values = true, hide = true)]
    pub args: Vec<OsString>,
}

/// What `oit view` answers in a build without the viewer.
#[cfg(not(feature = "view"))]
fn no_view() -> OitError {
    OitError::InvalidSettings(
        "`oit view` is not compiled into this oit: rebuild with `--features view` \
         (`cargo install --path oit-cli --features view`; on by default, left out by --no-default-features)"
            .into(),
    )
}

/// How a command ended when it did not fail outright.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Everything asked for was done.
    Success,
    /// The command went on past failures it has already reported (one `error:` line each).
    Failed,
}

/// Runs the command.
pub fn run(cli: Cli) -> Result<Outcome, OitError> {
    match cli.command {
        Command::Render(args) => render::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Sweep(args) => sweep::run(&args),
        Command::Info(args) => info::run(&args),
        Command::Bench(args) => bench::run(&args),
        #[cfg(feature = "view")]
        Command::View(args) => view::run(&args),
        #[cfg(not(feature = "view"))]
        Command::View(_) => Err(no_view()),
    }
}

/// What a command would run, every option checked: [`validate`]'s answer.
pub struct Validated {
    /// The techniques the command would render, in order (none for `info` and `bench --replot`).
    pub techniques: Vec<Technique>,
    /// The scene, settings, camera angles and backends of `render`, `compare` and `sweep`.
    pub prepared: Option<Prepared>,
}

/// Every check the command makes before it does any work (each command's `check`, which its run
/// starts with): options parsed and in range, scenes loaded and framed, output paths checked,
/// backends built; nothing rendered, nothing written. What passes here is what the command would
/// start on; an error here is the error the command would print.
pub fn validate(cli: &Cli) -> Result<Validated, OitError> {
    let rendering = |(techniques, prepared)| Validated { techniques, prepared: Some(prepared) };
    Ok(match &cli.command {
        Command::Render(args) => {
            // `auto` names no technique until its counting pass has run
            let (requested, prepared) = render::check(args)?;
            Validated { techniques: requested.fixed().into_iter().collect(), prepared: Some(prepared) }
        }
        Command::Compare(args) => rendering(compare::check(args)?),
        Command::Sweep(args) => rendering(sweep::check(args)?),
        Command::Info(args) => {
            info::check(args)?;
            Validated { techniques: Vec::new(), prepared: None }
        }
        Command::Bench(args) => match bench::check(args)? {
            bench::Checked::Replot(..) => Validated { techniques: Vec::new(), prepared: None },
            bench::Checked::Measure(config) => Validated { techniques: config.techniques, prepared: None },
        },
        #[cfg(feature = "view")]
        Command::View(args) => {
            let checked = view::check(args)?;
            Validated { techniques: vec![checked.state.technique], prepared: None }
        }
        #[cfg(not(feature = "view"))]
        Command::View(_) => return Err(no_view()),
    })
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

/// The `oit` binary: parses the command line, runs it, and turns the result (or a panic) into
/// the exit code and the one `error:` line.
pub fn main() -> ExitCode {
    // First, before anything can load a Vulkan driver: without XDG_RUNTIME_DIR, Mesa's
    // device-select layer has libwayland print "error: XDG_RUNTIME_DIR is invalid or not set in
    // the environment." on every GPU backend's start, which reads as oit's error. This runs oit
    // again with a private runtime directory instead (setting the variable here would take
    // `unsafe`, which the workspace forbids; `runtime_dir` says why and what it costs).
    #[cfg(all(unix, any(feature = "wgpu", feature = "vulkan")))]
    if let Some(code) = runtime_dir::rerun_with_private_runtime_dir() {
        return code;
    }
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
