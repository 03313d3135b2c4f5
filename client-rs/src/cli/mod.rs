//! The subcommands of the `vas-client` tool.

pub mod control;
pub mod named;
pub mod record;
pub mod replay;
pub mod send;
pub mod watch;

use std::io::{IsTerminal, Write};
use std::time::Duration;

use anyhow::Context;
use tracing_subscriber::EnvFilter;
use vas_client::{Client, Roles};

/// How long a control request (scene info) may take before the tool gives up.
pub const CONTROL_TIMEOUT: Duration = Duration::from_secs(5);

/// The longest answer timeout the tools accept, in milliseconds (an hour).
pub const MAX_TIMEOUT_MS: u64 = 3_600_000;

/// Logs to stderr (stdout carries the JSON output), filtered by `RUST_LOG`, `info` by default.
pub fn init_logging() {
    tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .with_env_filter(
            EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new("info")),
        )
        .init();
}

/// Connects with `roles` and with SIGINT and SIGTERM handled, so that long-running commands end
/// cleanly. Each command takes only the roles it uses: a command that only reads or asks holds
/// no input publisher, one that does not read frames no output subscriber, so that watchers
/// and operators do not take each other's places.
pub fn connect(prefix: Option<&str>, roles: Roles) -> anyhow::Result<Client> {
    Client::builder()
        .handle_termination_signals(true)
        .prefix(prefix)
        .roles(roles)
        .connect()
        .context("cannot connect to the vas services")
}

/// `vas-client info`: the scene and the input counters as one JSON document.
pub fn info(prefix: Option<&str>) -> anyhow::Result<()> {
    let client = connect(prefix, Roles::CONTROL)?;
    let scene = client.scene_info(CONTROL_TIMEOUT)?;
    let mut out = std::io::stdout().lock();
    serde_json::to_writer_pretty(&mut out, &scene)?;
    writeln!(out)?;
    Ok(())
}
