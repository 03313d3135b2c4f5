//! vas-bridge: a vas server's services carried over Eclipse zenoh, for renderers, input devices
//! and users on other machines.
//!
//! iceoryx2 ends at the machine's edge; zenoh crosses it (peer to peer or through routers, over
//! TCP, UDP, QUIC or TLS, with bindings for C, C++, Python, TypeScript and more). The bridge is a
//! vas client on the server's machine, and a zenoh peer:
//!
//! * outputs out: every frame of every output service on the key named as the service
//!   ([`keys`]), and parts and hand frames thinned to the rates given with `--rate` as well
//!   ([`thinning`]); events are never thinned; the geometry, the latest parts frame, each
//!   hand's latest frame and the latest clearance frame are answered to queries ([`latest`]), so
//!   that a renderer that joins late has them at once;
//! * inputs in: tracker, glove and hand-joints samples published on zenoh go into the server's
//!   input streams, where the server validates and counts them as local input; the bridge
//!   refuses bytes of the wrong length, message or version, and users it does not accept;
//! * control: the control service as a queryable ([`control`]).
//!
//! The bytes on zenoh are the wire types' own little-endian layout behind an 8-byte envelope
//! ([`wire`]); `docs/wire.md` specifies them for clients in any language.
//!
//! Three threads, each with its own vas client (iceoryx2 ports live on one thread): outputs
//! (this one), inputs and control. Each blocks on its own source, so that no kind of traffic
//! waits for another. A server that goes away and comes back, and zenoh peers that come and go,
//! are served again without a restart ([`server`]).

pub mod control;
pub mod inputs;
pub mod keys;
pub mod latest;
pub mod options;
pub mod outputs;
pub mod server;
pub mod stats;
pub mod thinning;
pub mod wire;

use std::sync::Arc;

use anyhow::Context;
use zenoh::Wait;

use keys::Keys;
use options::Options;
use server::Shared;

/// Runs the bridge until a termination signal.
pub fn run(options: &Options) -> anyhow::Result<()> {
    let keys = Keys::new(&options.session)?;
    let config = options.zenoh_config()?;
    let session = zenoh::open(config)
        .wait()
        .map_err(|error| anyhow::anyhow!("{error}"))
        .context("cannot open the zenoh session")?;
    let zenoh_error = |error: zenoh::Error| anyhow::anyhow!("{error}");
    let shared = Arc::new(Shared::default());

    let _latest = latest::declare(&session, &keys, &shared).map_err(zenoh_error)?;
    let stats_shared = Arc::clone(&shared);
    let stats_key = keys.stats();
    let _stats = session
        .declare_queryable(keys.stats())
        .callback(move |query| {
            let json = serde_json::to_string(&stats_shared.stats.snapshot()).unwrap_or_default();
            if let Err(error) = query.reply(&stats_key, json).wait() {
                tracing::debug!(%error, "cannot answer a stats query");
            }
        })
        .wait()
        .map_err(zenoh_error)?;
    let inputs = session
        .declare_subscriber(keys.inputs())
        .wait()
        .map_err(zenoh_error)?;
    let control = session
        .declare_queryable(keys.control())
        .wait()
        .map_err(zenoh_error)?;
    let mut outputs =
        outputs::Outputs::declare(&session, &keys, &options.rates, &shared).map_err(zenoh_error)?;

    let prefix = options.prefix.as_deref();
    std::thread::scope(|scope| {
        let (input_shared, control_shared) = (&*shared, &*shared);
        let users = options.users.clone();
        let control_key = keys.control();
        let threads = [
            scope.spawn(move || inputs::run(inputs, prefix, users, input_shared)),
            scope.spawn(move || control::run(control, &control_key, prefix, control_shared)),
        ];
        tracing::info!(
            prefix,
            session = keys.session(),
            zid = %session.zid(),
            rates = ?options.rates,
            users = ?options.users,
            "bridging vas/{}/** on zenoh",
            keys.session()
        );
        outputs.run(prefix);
        shared
            .stop
            .store(true, std::sync::atomic::Ordering::Relaxed);
        for thread in threads {
            if thread.join().is_err() {
                tracing::error!("a bridge thread panicked");
            }
        }
    });
    tracing::info!(stats = ?shared.stats.snapshot(), "bridge stopped");
    drop(outputs);
    session.close().wait().map_err(zenoh_error)?;
    Ok(())
}
