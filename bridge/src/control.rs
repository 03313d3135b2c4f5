//! The control thread: the control service as a zenoh queryable.
//!
//! A query on `vas/<session>/control` carries a `ControlRequest` (envelope and fields); the
//! answer is the server's `ControlResponse`, with its status, whether the server did what was
//! asked or refused it (a refusal's response carries the scene summary and counters of the
//! moment, as every response does). What the bridge itself refuses is answered with a zenoh
//! error reply holding a sentence in UTF-8: bytes that are no request, and a load by path,
//! which names a file on the server's machine: a remote client loads one of the scenes the
//! server offers, by name, as the viewer's pages do.
//!
//! Requests are answered one at a time, in order, on a thread of their own, so that a scene
//! that takes long to load holds back neither frames nor input.

use std::sync::atomic::Ordering;
use std::time::Duration;

use vas_client::{Client, ClientError, Roles};
use vas_protocol::{
    ControlRequest, ControlRequestKind, ControlResponse, MAX_STATUS_MESSAGE_BYTES, WireText,
};
use zenoh::Wait;
use zenoh::handlers::FifoChannelHandler;
use zenoh::query::{Query, Queryable};

use crate::server::{CONTROL_TIMEOUT, Follower, Shared};
use crate::wire;

/// How long a scene may take to load or reset (a reset rebuilds the scene's state).
const LOAD_TIMEOUT: Duration = Duration::from_secs(60);

/// Answers queries on `queryable` until the bridge stops.
pub fn run(
    queryable: Queryable<FifoChannelHandler<Query>>,
    key: &str,
    prefix: Option<&str>,
    shared: &Shared,
) {
    let mut follower = Follower::new(prefix, Roles::CONTROL);
    while let Some(query) = shared.next(&queryable, "control queryable") {
        let answer = match follower.client(shared) {
            Some(client) => answer(&query, client, shared),
            None => Err("the bridge cannot reach the vas services".to_owned()),
        };
        let replied = match answer {
            Ok(response) => {
                shared.stats.control_answered();
                query.reply(key, wire::encode(&response)).wait()
            }
            Err(reason) => {
                shared.stats.control_refused();
                tracing::debug!(reason, "control query refused");
                query.reply_err(reason).wait()
            }
        };
        if let Err(error) = replied {
            tracing::debug!(%error, "cannot answer a control query");
        }
    }
}

/// The server's response to the request `query` carries, or why there is none.
fn answer(query: &Query, client: &Client, shared: &Shared) -> Result<ControlResponse, String> {
    let bytes = query
        .payload()
        .map(|payload| payload.to_bytes())
        .unwrap_or_default();
    let request = wire::decode::<ControlRequest>(&bytes).map_err(|refusal| {
        shared.stats.refused(&refusal);
        format!("not a control request: {refusal}")
    })?;
    let kind = ControlRequestKind::try_from(request.kind).map_err(|error| error.to_string())?;
    if kind == ControlRequestKind::LoadScene {
        shared.stats.refused_by_server();
        return Err(
            "a scene file is loaded on the server's machine only: load one of the \
                    scenes it offers by name (LoadNamedScene)"
                .to_owned(),
        );
    }
    let loads = matches!(
        kind,
        ControlRequestKind::LoadNamedScene | ControlRequestKind::Reset
    );
    let timeout = if loads { LOAD_TIMEOUT } else { CONTROL_TIMEOUT };
    shared.loading.store(loads, Ordering::Relaxed);
    let answered = client.control(request, timeout);
    shared.loading.store(false, Ordering::Relaxed);
    match answered {
        Ok(response) => Ok(response),
        Err(ClientError::Refused {
            request: kind,
            status,
            message,
        }) => {
            // The response of the moment, with the refusal's status and reason.
            let mut response = client
                .control(ControlRequest::scene_info(), CONTROL_TIMEOUT)
                .map_err(|error| error.to_string())?;
            response.status = status as u32;
            response.kind = kind as u32;
            response.message = WireText::<MAX_STATUS_MESSAGE_BYTES>::truncated(&message).0;
            Ok(response)
        }
        Err(error) => Err(error.to_string()),
    }
}
