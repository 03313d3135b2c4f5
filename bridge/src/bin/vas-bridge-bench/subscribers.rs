//! B13's remote subscribers: remote renderers held subscribed to the outputs of a session, so
//! that B7's local round trip (`vas-bench e2e`) runs beside them: every output at the full rate,
//! or (`--hz`) a renderer's outputs with parts and hand frames thinned to its display's rate.
//!
//! Each subscriber is a zenoh session of its own, as a renderer on another machine is. Before
//! the command runs, each has had the bridge answer a query over its link, which comes after its
//! subscription on that link: every one is attached when B7's first sample goes out. Each one's
//! messages are counted, and a subscriber that received nothing while the command ran makes the
//! run fail, since it measured fewer subscribers than asked.

use std::process::{Command, ExitStatus};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use anyhow::Context;
use vas_bridge::keys::{Keys, Thinned};
use vas_protocol::services;
use zenoh::Wait;

use crate::{open, session_config, zenoh_error};

/// How long a subscriber's session waits for the bridge to answer its query.
const ATTACH_TIMEOUT: Duration = Duration::from_secs(10);

/// Options of `subscribers`.
#[derive(Debug, clap::Args)]
pub struct SubscribersArgs {
    /// How many remote renderers (0: none, the baseline run in the same way).
    #[arg(long, default_value_t = 16)]
    count: usize,
    /// Subscribe as a renderer at HZ frames a second: parts and hand frames thinned to HZ (the
    /// bridge started with `--rate HZ`), every event and clearance frame; without, every output
    /// at the full rate.
    #[arg(long, value_name = "HZ")]
    hz: Option<u32>,
    /// The command to run while they are held, after `--` (e.g. `vas-bench e2e --prefix P`);
    /// its exit status is this one's. Without, they are held until SIGINT or SIGTERM.
    #[arg(last = true, value_name = "COMMAND")]
    command: Vec<String>,
}

/// One remote renderer: its session, its subscription and what it received.
struct Held {
    session: zenoh::Session,
    _subscribers: Vec<zenoh::pubsub::Subscriber<()>>,
    received: Arc<AtomicU64>,
}

/// The keys a remote renderer subscribes to: every output at the full rate (`**` never matches
/// a thinned key's verbatim chunk), or a renderer's at `hz`.
fn subscribed_keys(keys: &Keys, hz: Option<u32>) -> Vec<String> {
    match hz {
        None => vec![format!("vas/{}/output/**", keys.session())],
        Some(hz) => vec![
            keys.thinned(Thinned::Parts, hz),
            keys.thinned(Thinned::Hand, hz),
            keys.service(services::EVENTS),
            keys.service(services::CLEARANCE),
        ],
    }
}

/// A remote renderer subscribed to `subscribed` keys, once the bridge has answered it.
fn attach(endpoint: &str, keys: &Keys, subscribed: &[String]) -> anyhow::Result<Held> {
    // Each connects to the bridge only, as renderers on machines of their own would: without
    // gossip, zenoh's peers would also link every subscriber to every other.
    let mut config = session_config(endpoint)?;
    config
        .insert_json5("scouting/gossip/enabled", "false")
        .map_err(zenoh_error)?;
    let session = open(config)?;
    let received = Arc::new(AtomicU64::new(0));
    let subscribers = (subscribed.iter())
        .map(|key| {
            let counter = Arc::clone(&received);
            (session.declare_subscriber(key))
                .callback(move |_| {
                    counter.fetch_add(1, Ordering::Relaxed);
                })
                .wait()
                .map_err(zenoh_error)
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let replies = (session.get(keys.stats()))
        .timeout(ATTACH_TIMEOUT)
        .wait()
        .map_err(zenoh_error)?;
    replies
        .recv()
        .ok()
        .filter(|reply| reply.result().is_ok())
        .with_context(|| format!("no bridge of session {} answered", keys.session()))?;
    Ok(Held {
        session,
        _subscribers: subscribers,
        received,
    })
}

/// Holds `args.count` remote renderers while `args.command` runs (or until stopped), then
/// reports each one's messages.
pub fn run(endpoint: &str, session_name: &str, args: &SubscribersArgs) -> anyhow::Result<()> {
    let keys = Keys::new(session_name)?;
    let subscribed = subscribed_keys(&keys, args.hz);
    let held = (0..args.count)
        .map(|_| attach(endpoint, &keys, &subscribed))
        .collect::<anyhow::Result<Vec<_>>>()?;
    tracing::info!(count = held.len(), "remote subscribers attached");
    let Some((program, rest)) = args.command.split_first() else {
        loop {
            std::thread::sleep(Duration::from_secs(10));
            let received: u64 = (held.iter())
                .map(|h| h.received.load(Ordering::Relaxed))
                .sum();
            tracing::info!(received, "messages received");
        }
    };
    let status: ExitStatus = Command::new(program)
        .args(rest)
        .status()
        .with_context(|| format!("cannot run {program}"))?;
    let received: Vec<u64> = (held.iter())
        .map(|h| h.received.load(Ordering::Relaxed))
        .collect();
    eprintln!(
        "vas-bridge-bench subscribers: {} remote subscribers received {received:?} messages",
        held.len()
    );
    for Held { session, .. } in held {
        session.close().wait().map_err(zenoh_error)?;
    }
    anyhow::ensure!(
        received.iter().all(|&count| count > 0),
        "a remote subscriber received nothing: {received:?}"
    );
    anyhow::ensure!(status.success(), "{program} failed: {status}");
    Ok(())
}
