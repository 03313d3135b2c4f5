//! The HTTP side: the embedded assets, the WebSocket endpoint, the counters, and what every
//! request passes first: the `Host` check ([`crate::host`]) and, when the viewer asks for a
//! token, the access check ([`crate::access`]).
//!
//! Nothing here touches the file system: a path is either in the asset table or a 404, so no
//! request can reach a file the viewer did not embed.

use std::io::Write;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use anyhow::Context;
use axum::Router;
use axum::body::Bytes;
use axum::extract::{Request, State, WebSocketUpgrade};
use axum::http::{HeaderMap, Method, StatusCode, Uri, header};
use axum::middleware::{Next, from_fn_with_state};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use tokio::sync::Semaphore;

use crate::access::Access;
use crate::assets;
use crate::connections;
use crate::host::Hosts;
use crate::hub::Hub;
use crate::page;
use crate::settings::Settings;
use crate::stats::Stats;

/// HTTP connections (those not upgraded to a page's WebSocket, which the page cap counts) open
/// at once: a browser holds up to six per host, and the header time-out ends idle ones.
pub const MAX_HTTP_CONNECTIONS: usize = 64;

/// The largest login form read.
const MAX_LOGIN_BYTES: usize = 1024;

/// What every request is answered with.
#[derive(Debug)]
pub struct App {
    /// The link thread's side.
    pub hub: Arc<Hub>,
    /// The hosts requests may name.
    pub hosts: Hosts,
    /// The token pages must give, if the viewer asks for one.
    pub access: Option<Access>,
    /// One permit per page that may connect.
    pub pages: Arc<Semaphore>,
    /// See [`Settings::idle_timeout`].
    pub idle_timeout: Duration,
}

/// The routes, behind the `Host` and access checks.
pub fn router(app: Arc<App>) -> Router {
    Router::new()
        .route("/ws", get(websocket))
        .route("/stats", get(stats))
        .route("/login", post(login))
        .fallback(asset)
        .layer(from_fn_with_state(Arc::clone(&app), guard))
        .with_state(app)
}

/// Serves the page as `settings` say until SIGINT or SIGTERM.
pub async fn serve(settings: Settings, hub: Arc<Hub>) -> anyhow::Result<()> {
    let mut listeners = Vec::new();
    let mut port = settings.listen.port;
    for address in &settings.addresses {
        // With port 0, every address of a name gets the port the first one was given.
        let address = SocketAddr::new(address.ip(), port);
        match tokio::net::TcpListener::bind(address).await {
            Ok(listener) => {
                port = listener
                    .local_addr()
                    .context("the listening address")?
                    .port();
                tracing::info!(%address, "serving the viewer");
                listeners.push(listener);
            }
            Err(error) => tracing::warn!(%address, %error, "cannot listen here"),
        }
    }
    anyhow::ensure!(
        !listeners.is_empty(),
        "cannot listen on --listen {} (see the warnings above)",
        settings.listen
    );
    let https = settings.tls.is_some();
    let access = (settings.token.as_ref())
        .map(|token| Access::new(token.token.clone(), port, https))
        .transpose()?;
    // The URL goes to stdout, the one line a script (or a test) reads to find the page; a token
    // the viewer made follows it.
    let mut stdout = std::io::stdout().lock();
    let scheme = if https { "https" } else { "http" };
    writeln!(
        stdout,
        "vas-viewer: open {scheme}://{}:{port}/",
        settings.listen.host
    )
    .context("print the URL")?;
    if let Some(token) = settings.token.as_ref().filter(|token| token.generated) {
        writeln!(stdout, "vas-viewer: access token {}", token.token).context("print the token")?;
    }
    stdout.flush().context("print the URL")?;
    drop(stdout);

    let app = Arc::new(App {
        hub: Arc::clone(&hub),
        hosts: Hosts::new(&settings.listen, port, https),
        access,
        pages: Arc::new(Semaphore::new(settings.max_pages)),
        idle_timeout: settings.idle_timeout,
    });
    let routes = router(app);
    let connections = Arc::new(Semaphore::new(MAX_HTTP_CONNECTIONS));
    for listener in listeners {
        tokio::spawn(connections::accept(
            listener,
            settings.tls.clone(),
            routes.clone(),
            Arc::clone(&hub),
            Arc::clone(&connections),
            settings.header_timeout,
        ));
    }
    termination().await;
    Ok(())
}

/// Lets a request through only when it names this viewer as its host (421 otherwise: DNS
/// rebinding) and, when the viewer asks for a token, carries it or its session (else the form
/// asking for it, 401), or is the form's answer.
async fn guard(State(app): State<Arc<App>>, request: Request, next: Next) -> Response {
    if !names_this_viewer(&app.hosts, &request) {
        Stats::count(&app.hub.stats.refused_host);
        let refusal = "this viewer does not serve the host this request names\n";
        return (StatusCode::MISDIRECTED_REQUEST, refusal).into_response();
    }
    if let Some(access) = &app.access {
        let login = request.method() == Method::POST && request.uri().path() == "/login";
        if !login && !access.admits(request.headers()) {
            Stats::count(&app.hub.stats.refused_token);
            let note = "This viewer asks for its access token once (it printed it on starting).";
            return access.form(StatusCode::UNAUTHORIZED, note);
        }
    }
    next.run(request).await
}

/// Whether `request` has a `Host` (HTTP/1.1 asks for one, and browsers always send it) and every
/// host it names (in `Host`, and in its URI if that is absolute) is one of `hosts`.
fn names_this_viewer(hosts: &Hosts, request: &Request) -> bool {
    let headers = request.headers().get_all(header::HOST);
    let named = (request.uri().authority().map(|a| a.as_str()))
        .into_iter()
        .chain(headers.iter().map(|host| host.to_str().unwrap_or_default()));
    headers.iter().next().is_some() && named.into_iter().all(|host| hosts.accepts(host))
}

/// The access form's answer: to the page with a session, or the form again.
async fn login(State(app): State<Arc<App>>, headers: HeaderMap, body: Bytes) -> Response {
    let Some(access) = &app.access else {
        return (StatusCode::NOT_FOUND, "not found\n").into_response();
    };
    if !same_origin(&headers) || body.len() > MAX_LOGIN_BYTES {
        return (StatusCode::FORBIDDEN, "refused\n").into_response();
    }
    if access.takes(&body) {
        return access.session();
    }
    Stats::count(&app.hub.stats.refused_token);
    access.form(StatusCode::UNAUTHORIZED, "That is not the token.")
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
async fn stats(State(app): State<Arc<App>>) -> Response {
    axum::Json(app.hub.stats.snapshot()).into_response()
}

/// Upgrades a page's connection, while fewer pages than the cap are connected (503 beyond it).
/// A browser always sends its page's origin; one whose host is not the host this request was
/// sent to is another site's page, which may not drive the viewer (cross-site WebSocket
/// hijacking).
async fn websocket(
    State(app): State<Arc<App>>,
    headers: HeaderMap,
    upgrade: WebSocketUpgrade,
) -> Response {
    if !same_origin(&headers) {
        return (StatusCode::FORBIDDEN, "cross-origin WebSocket refused\n").into_response();
    }
    let Ok(permit) = Arc::clone(&app.pages).try_acquire_owned() else {
        Stats::count(&app.hub.stats.refused_pages);
        let refusal = "too many pages are connected to this viewer; close one and reload\n";
        return (StatusCode::SERVICE_UNAVAILABLE, refusal).into_response();
    };
    let (hub, idle) = (Arc::clone(&app.hub), app.idle_timeout);
    upgrade
        .max_message_size(page::MAX_READ_BYTES)
        .max_frame_size(page::MAX_READ_BYTES)
        .on_upgrade(move |socket| async move {
            page::serve(socket, hub, idle).await;
            drop(permit);
        })
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
