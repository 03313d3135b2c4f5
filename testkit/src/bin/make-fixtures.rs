//! Writes the recorded scenarios' fixtures: `cargo run -p vas-testkit --bin make-fixtures --
//! --out tests/fixtures` from the repository root.

use std::path::PathBuf;

use clap::Parser;
use vas_testkit::scenarios::EXPECTED;

/// Generates the replay fixtures from the scripted scenarios and their scenes.
#[derive(Debug, Parser)]
#[command(name = "make-fixtures")]
struct Args {
    /// Folder the recordings are written into (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Folder of the scene configs.
    #[arg(long, default_value_os_t = vas_testkit::configs_dir())]
    configs: PathBuf,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    std::fs::create_dir_all(&args.out)?;
    for scenario in &EXPECTED {
        let path = vas_testkit::fixtures::write_fixture(scenario, &args.configs, &args.out)?;
        println!("{}: {}", scenario.motion, path.display());
    }
    Ok(())
}
