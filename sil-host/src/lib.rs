//! The command line of the rig (`sil-host`): each command parses its flags into an
//! experiment's settings, calls the experiment ([`experiments`]: the plant, the
//! rig and the analyses under it), and prints and writes what it computed (CSV,
//! Arrow, JSON, SVG figures, the report).
#![warn(missing_docs)]

#[macro_use]
pub mod stdout;

pub mod bench;
pub mod cancel;
pub mod cli;
pub mod commands;
pub mod error;
pub mod features;
pub mod folder_lock;
pub mod link_spec;
#[cfg(feature = "live")]
pub mod live;
#[cfg(not(feature = "live"))]
#[path = "live_off.rs"]
pub mod live;
pub mod output;
pub mod run_tables;
pub mod streamed_run;
pub mod sweep;
pub mod table_out;

use clap::Parser;

/// Runs the command line `args` (program name first) and returns the process
/// exit code: 0 on success, 1 when a run fails, 2 for bad input (unknown flags,
/// invalid values; nothing is written then), 130 or 143 when stopped by Ctrl-C or
/// SIGTERM (what was finished is kept: [`cancel`]), 141 when standard output's
/// reader went away (quietly; a full disk or another write error on standard
/// output is exit 1 with a message: [`stdout`]). `--help` and `--version` print
/// and return 0.
pub fn run<I, T>(args: I) -> i32
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let cli = match cli::Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return e.exit_code();
        }
    };
    let result = match cli.command {
        cli::Command::Simulate(args) => commands::simulate::run(&args),
        cli::Command::Admissible(args) => commands::admissible::run(&args),
        cli::Command::Modes(args) => commands::modes::run(&args),
        cli::Command::Poincare(args) => commands::poincare::run(&args),
        cli::Command::Run(args) => commands::run::run(&args),
        cli::Command::Bench(args) => commands::bench::run(&args),
        cli::Command::Replay(args) => commands::replay::run(&args),
        cli::Command::Report(args) => commands::report::run(&args),
        cli::Command::Sweep(args) => commands::sweep::run(&args),
        cli::Command::Merge(args) => commands::sweep::merge::merge(&args),
        cli::Command::Zmax(args) => commands::zmax::run(&args),
        cli::Command::Sensitivity(args) => commands::sensitivity::run(&args),
        cli::Command::Pil(args) => commands::pil::run(&args),
        #[cfg(feature = "board")]
        cli::Command::Board(args) => commands::board::run(&args),
        #[cfg(feature = "board")]
        cli::Command::BoardTwin(args) => commands::board::twin(&args),
        #[cfg(not(feature = "board"))]
        cli::Command::Board(_) => Err(features::missing("board", "`sil-host board`")),
        #[cfg(not(feature = "board"))]
        cli::Command::BoardTwin(_) => Err(features::missing("board", "`sil-host board-twin`")),
        cli::Command::Firmware(args) => match commands::firmware::firmware(&args) {
            Ok(code) => return code,
            Err(e) => Err(e),
        },
    };
    let stdout_failure = stdout::take_failure();
    match result {
        Ok(()) => match stdout_failure {
            None => 0,
            Some(e) if e.kind() == std::io::ErrorKind::BrokenPipe => stdout::BROKEN_PIPE_EXIT,
            Some(e) => {
                eprintln!("error: cannot write to standard output: {e}");
                1
            }
        },
        Err(e) => {
            eprintln!("error: {e}");
            // Stopped by Ctrl-C or SIGTERM: the shell's 128 + signal (130, 143).
            cancel::exit_code().unwrap_or_else(|| e.exit_code())
        }
    }
}

// The figures (plots, the trace page, the animations) are the `figures` crate's;
// the commands name them by these paths.
pub use figures::{animation, plot, trace_page};
