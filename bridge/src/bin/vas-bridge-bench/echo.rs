//! The bare path's far end: answers each ping at once, from zenoh's callback, with a pong as
//! long as an enveloped hand frame that carries the ping's first 16 bytes (its number).

use vas_protocol::HandFrame;
use zenoh::Wait;

use crate::open_session;

/// Bytes of a pong: what the bridge sends for a hand frame.
pub const PONG_BYTES: usize = vas_bridge::wire::ENVELOPE_BYTES + size_of::<HandFrame>();

/// Answers pings on `key`/ping with pongs on `key`/pong until the process is stopped.
pub fn run(endpoint: &str, key: &str) -> anyhow::Result<()> {
    let session = open_session(endpoint)?;
    let error = |error: zenoh::Error| anyhow::anyhow!("{error}");
    let pong = session
        .declare_publisher(format!("{key}/pong"))
        .express(true)
        .wait()
        .map_err(error)?;
    let _pings = session
        .declare_subscriber(format!("{key}/ping"))
        .callback(move |sample| {
            let mut bytes = vec![0; PONG_BYTES];
            let ping = sample.payload().to_bytes();
            let head = ping.len().min(16);
            bytes[..head].copy_from_slice(&ping[..head]);
            if let Err(error) = pong.put(bytes).wait() {
                tracing::warn!(%error, "cannot answer a ping");
            }
        })
        .wait()
        .map_err(error)?;
    tracing::info!(key, "echoing");
    loop {
        std::thread::park();
    }
}
