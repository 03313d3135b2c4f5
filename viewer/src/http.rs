//! The HTTP side: the embedded assets, the WebSocket endpoint and the counters.
//!
//! Nothing here touches the file system: a path is either in the asset table or a 404, so no
//! request can reach a file the viewer did not embed.

use std::io::Write;
use std::net::SocketAddr;
use std::sync::Arc;

use anyhow::Context;
use axum::Router;
use axum::extract::{State, WebSocketUpgrade};
use axum::http::{HeaderMap, StatusCode, Uri, header};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::serve::ListenerExt;

use crate::assets;
use crate::hub::Hub;
use crate::page;

/// Serves the page on `listen` until SIGINT or SIGTERM.
pub async fn serve(listen: SocketAddr, hub: Arc<Hub>) -> anyhow::Result<()> {
    let listener = tokio::net::TcpListener::bind(listen)
        .await
        .with_context(|| format!("listen on {listen}"))?;
    let address = listener.local_addr().context("the listening address")?;
    // The URL goes to stdout, the one line a script (or a test) reads to find the page.
    let mut stdout = std::io::stdout().lock();
    writeln!(stdout, "vas-viewer: open http://{address}/").context("print the URL")?;
    stdout.flush().context("print the URL")?;
    drop(stdout);
    tracing::info!(%address, "serving the viewer");

    let app = Router::new()
        .route("/ws", get(websocket))
        .route("/stats", get(stats))
        .fallback(asset)
        .with_state(hub);
    // Frames are small messages a page must have at once: without TCP_NODELAY, Nagle's
    // algorithm holds one back while the one before is unacknowledged.
    let listener = listener.tap_io(|stream| {
        if let Err(error) = stream.set_nodelay(true) {
            tracing::warn!(%error, "cannot set TCP_NODELAY on a page's connection");
        }
    });
    axum::serve(listener, app)
        .with_graceful_shutdown(termination())
        .await
        .context("serve HTTP")
}

/// One of the embedded assets, or 404.
async fn asset(uri: Uri) -> Response {
    match assets::find(uri.path()) {
        Some(asset) => (
            [
                (header::CONTENT_TYPE, asset.content_type),
                // The assets change with the binary: a browser must not keep an old page.
                (header::CACHE_CONTROL, "no-cache"),
            ],
            asset.body,
        )
            .into_response(),
        None => (StatusCode::NOT_FOUND, "not found\n").into_response(),
    }
}

/// The viewer's counters as JSON.
async fn stats(State(hub): State<Arc<Hub>>) -> Response {
    axum::Json(hub.stats.snapshot()).into_response()
}

/// Upgrades a page's connection. A browser always sends its page's origin; one whose host is
/// not the host this request was sent to is another site's page, which may not drive the
/// viewer (cross-site WebSocket hijacking).
async fn websocket(
    State(hub): State<Arc<Hub>>,
    headers: HeaderMap,
    upgrade: WebSocketUpgrade,
) -> Response {
    if !same_origin(&headers) {
        return (StatusCode::FORBIDDEN, "cross-origin WebSocket refused\n").into_response();
    }
    upgrade
        .max_message_size(page::MAX_READ_BYTES)
        .max_frame_size(page::MAX_READ_BYTES)
        .on_upgrade(move |socket| page::serve(socket, hub))
}

/// True unless an `Origin` header names another host than `Host` (tools without an origin are
/// let through: they are not a browser page of another site).
fn same_origin(headers: &HeaderMap) -> bool {
    let Some(origin) = headers.get(header::ORIGIN) else {
        return true;
    };
    let host = headers
        .get(header::HOST)
        .and_then(|host| host.to_str().ok());
    let origin_host = origin
        .to_str()
        .ok()
        .and_then(|origin| origin.split_once("://"))
        .map(|(_, host)| host);
    matches!((origin_host, host), (Some(origin), Some(host)) if origin.eq_ignore_ascii_case(host))
}

/// Resolves on SIGINT or SIGTERM.
async fn termination() {
    let interrupt = tokio::signal::ctrl_c();
    match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
        Ok(mut terminate) => {
            tokio::select! {
                _ = interrupt => {}
                _ = terminate.recv() => {}
            }
        }
        Err(error) => {
            tracing::warn!(%error, "cannot handle SIGTERM; stop with SIGINT");
            let _ = interrupt.await;
        }
    }
    tracing::info!("stopping");
}

#[cfg(test)]
mod tests {
    use super::*;
    use axum::http::HeaderValue;

    fn headers(host: &str, origin: Option<&str>) -> HeaderMap {
        let mut headers = HeaderMap::new();
        headers.insert(header::HOST, HeaderValue::from_str(host).unwrap());
        if let Some(origin) = origin {
            headers.insert(header::ORIGIN, HeaderValue::from_str(origin).unwrap());
        }
        headers
    }

    #[test]
    fn a_page_of_the_viewer_itself_may_connect() {
        assert!(same_origin(&headers(
            "localhost:8080",
            Some("http://localhost:8080")
        )));
        assert!(same_origin(&headers("127.0.0.1:8080", None)));
    }

    #[test]
    fn a_page_of_another_site_may_not() {
        assert!(!same_origin(&headers(
            "127.0.0.1:8080",
            Some("https://example.org")
        )));
        assert!(!same_origin(&headers("127.0.0.1:8080", Some("null"))));
    }
}
