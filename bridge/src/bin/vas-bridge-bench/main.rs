//! `vas-bridge-bench`: B13 in BENCHMARKS.md, vas over zenoh through `vas-bridge`.
//!
//! The harness lives with the bridge rather than in `vas-bench`, so that the benchmarks of the
//! simulation do not build zenoh: it is a zenoh peer of a running bridge, as a remote renderer
//! or input device is.
//!
//! * `round-trip`: a hand-joints sample put on zenoh to the hand frame that answers it, through
//!   the bridge and the server, against the bare zenoh round trip of payloads of the same sizes
//!   (to an echo peer, a second process of this binary), the two paths by turns;
//! * `rates`: what one remote renderer receives, at the full rate and thinned to 90 Hz, while a
//!   recording plays into the server over zenoh;
//! * `subscribers`: holds remote renderers subscribed to every output while a command runs (B7's
//!   local round trip, `vas-bench e2e`) or until stopped;
//! * `echo`: the bare path's other end.

mod echo;
mod rates;
mod round_trip;
mod subscribers;

use std::time::Duration;

use clap::{Parser, Subcommand};
use zenoh::Wait;

/// B13: vas over zenoh, through vas-bridge.
#[derive(Debug, Parser)]
#[command(name = "vas-bridge-bench", version)]
struct Args {
    /// The bridge's zenoh endpoint, e.g. tcp/127.0.0.1:7447.
    #[arg(long, global = true, default_value = "tcp/127.0.0.1:7447")]
    connect: String,
    /// The bridge's session name.
    #[arg(long, global = true, default_value = "default")]
    session: String,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Remote round trip against the bare zenoh round trip.
    RoundTrip(round_trip::RoundTripArgs),
    /// Messages and bytes a second of one remote renderer, full rate and thinned.
    Rates(rates::RatesArgs),
    /// Hold COUNT remote renderers subscribed to every output while a command runs (B7:
    /// `-- vas-bench e2e ...`), or until stopped.
    Subscribers(subscribers::SubscribersArgs),
    /// Answer every ping with a pong of a hand frame's size (the bare path's far end).
    Echo {
        /// The key expression of the pings; pongs go to the same key with `/pong` for `/ping`.
        #[arg(long)]
        key: String,
    },
}

/// A zenoh peer connected to `endpoint` only (no multicast scouting).
fn open_session(endpoint: &str) -> anyhow::Result<zenoh::Session> {
    open(session_config(endpoint)?)
}

/// A peer's configuration that connects to `endpoint`, without multicast scouting.
fn session_config(endpoint: &str) -> anyhow::Result<zenoh::Config> {
    let mut config = zenoh::Config::default();
    config
        .insert_json5("connect/endpoints", &serde_json::to_string(&[endpoint])?)
        .map_err(zenoh_error)?;
    config
        .insert_json5("scouting/multicast/enabled", "false")
        .map_err(zenoh_error)?;
    Ok(config)
}

fn open(config: zenoh::Config) -> anyhow::Result<zenoh::Session> {
    zenoh::open(config).wait().map_err(zenoh_error)
}

fn zenoh_error(error: zenoh::Error) -> anyhow::Error {
    anyhow::anyhow!("{error}")
}

/// The nearest-rank percentile `p` (0-100) of sorted `values`.
fn percentile(sorted: &[Duration], p: f64) -> Duration {
    if sorted.is_empty() {
        return Duration::ZERO;
    }
    let rank = ((p / 100.0) * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// Microseconds, for tables.
fn micros(duration: Duration) -> f64 {
    duration.as_secs_f64() * 1e6
}

fn main() -> anyhow::Result<()> {
    tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| "info,zenoh=warn".into()),
        )
        .init();
    let args = Args::parse();
    match args.command {
        Command::RoundTrip(round_trip) => {
            round_trip::run(&args.connect, &args.session, &round_trip)
        }
        Command::Rates(rates) => rates::run(&args.connect, &args.session, &rates),
        Command::Subscribers(held) => subscribers::run(&args.connect, &args.session, &held),
        Command::Echo { key } => echo::run(&args.connect, &key),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_are_nearest_rank() {
        let values: Vec<Duration> = (1..=100).map(Duration::from_micros).collect();
        assert_eq!(percentile(&values, 50.0), Duration::from_micros(50));
        assert_eq!(percentile(&values, 99.0), Duration::from_micros(99));
        assert_eq!(percentile(&values, 100.0), Duration::from_micros(100));
        assert_eq!(percentile(&values[..1], 99.0), Duration::from_micros(1));
    }
}
