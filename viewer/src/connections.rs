//! The viewer's connections: accepted up to a cap, over TLS or not, each served as HTTP/1.1
//! (with the WebSocket's upgrade) with a time-out for reading a request's head.
//!
//! The viewer runs hyper itself rather than `axum::serve` for that time-out: without it, a
//! client that sends half a request (or a TLS handshake's beginning) holds its connection
//! forever. The same time-out closes keep-alive connections that stay idle between requests.

use std::sync::Arc;
use std::time::Duration;

use axum::Router;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::service::TowerToHyperService;
use tokio::io::{AsyncRead, AsyncWrite};
use tokio::net::TcpListener;
use tokio::sync::Semaphore;
use tokio_rustls::TlsAcceptor;

use crate::hub::Hub;
use crate::stats::Stats;

/// Serves `io`, one client's connection, with `app` until it ends: HTTP/1.1 whose request heads
/// must arrive within `header_timeout`, and the upgrade to a WebSocket. Time-outs are counted
/// in `hub`'s counters.
pub async fn serve_connection<I>(io: I, app: Router, header_timeout: Duration, hub: Arc<Hub>)
where
    I: AsyncRead + AsyncWrite + Unpin + Send + 'static,
{
    let served = hyper::server::conn::http1::Builder::new()
        .timer(TokioTimer::new())
        .header_read_timeout(header_timeout)
        .serve_connection(TokioIo::new(io), TowerToHyperService::new(app))
        .with_upgrades()
        .await;
    match served {
        Err(error) if error.is_timeout() => Stats::count(&hub.stats.timed_out_requests),
        Err(error) => tracing::debug!(%error, "a connection failed"),
        Ok(()) => {}
    }
}

/// Accepts connections on `listener` forever, each served by [`serve_connection`] (over TLS
/// when `tls` is given, whose handshake must end within `header_timeout` too). Each holds one of
/// the `connections` permits until it ends or becomes a page's WebSocket (hyper is done with it
/// then); a connection beyond them is closed at once, and counted.
pub async fn accept(
    listener: TcpListener,
    tls: Option<TlsAcceptor>,
    app: Router,
    hub: Arc<Hub>,
    connections: Arc<Semaphore>,
    header_timeout: Duration,
) {
    loop {
        let stream = match listener.accept().await {
            Ok((stream, _)) => stream,
            Err(error) => {
                // Out of file descriptors, say: wait for some to close rather than spin.
                tracing::warn!(%error, "cannot accept a connection");
                tokio::time::sleep(Duration::from_millis(100)).await;
                continue;
            }
        };
        let Ok(permit) = Arc::clone(&connections).try_acquire_owned() else {
            Stats::count(&hub.stats.refused_connections);
            tracing::warn!("too many connections; closed a new one");
            continue;
        };
        // Frames are small messages a page must have at once: without TCP_NODELAY, Nagle's
        // algorithm holds one back while the one before is unacknowledged.
        if let Err(error) = stream.set_nodelay(true) {
            tracing::warn!(%error, "cannot set TCP_NODELAY on a page's connection");
        }
        let (tls, app, hub) = (tls.clone(), app.clone(), Arc::clone(&hub));
        tokio::spawn(async move {
            match tls {
                None => serve_connection(stream, app, header_timeout, hub).await,
                Some(tls) => match tokio::time::timeout(header_timeout, tls.accept(stream)).await {
                    Ok(Ok(stream)) => serve_connection(stream, app, header_timeout, hub).await,
                    Ok(Err(error)) => tracing::debug!(%error, "a TLS handshake failed"),
                    Err(_) => Stats::count(&hub.stats.timed_out_requests),
                },
            }
            drop(permit);
        });
    }
}
