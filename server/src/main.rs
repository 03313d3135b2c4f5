//! The `vas-server` command line.

use anyhow::Result;
use clap::{Parser, Subcommand};
use vas_server::bench;

/// vas: headless virtual-assembly simulation server.
#[derive(Debug, Parser)]
#[command(version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Runs a benchmark of BENCHMARKS.md.
    #[command(subcommand)]
    Bench(Bench),
}

#[derive(Debug, Subcommand)]
enum Bench {
    /// B5: sliding contact, time per contact point and sliding frame rate.
    Slide(bench::slide::SlideBenchArgs),
}

fn main() -> Result<()> {
    match Cli::parse().command {
        Command::Bench(Bench::Slide(args)) => bench::slide::run_bench(&args).map(drop),
    }
}
