//! The `metaplate` command-line tool.
//!
//! Each subcommand lives in its own module; this file only parses the command line and dispatches.

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "metaplate",
    version,
    about = "Instrument control and measurement automation for wave-focusing tactile displays"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.command {}
}
