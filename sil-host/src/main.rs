//! `sil-host`: see `sil-host --help`.

use clap::Parser;
use sil_host::{
    cli::{Cli, Command},
    commands,
};

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Simulate(args) => commands::simulate::run(&args),
        Command::Admissible(args) => commands::admissible::run(&args),
        Command::Modes(args) => commands::modes::run(&args),
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(e.exit_code());
    }
}
