//! Requests exactly as written, for what the viewer answers to headers a client would not send
//! (another site's `Host`, half a request), over TCP or TLS.

use std::net::SocketAddr;

use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::net::TcpStream;

use crate::harness::PATIENCE;

/// A request for `path` naming `host`, with `headers` (each line ending in CRLF), that asks
/// the viewer to close the connection after answering.
pub fn request(method: &str, path: &str, host: &str, headers: &str) -> String {
    format!("{method} {path} HTTP/1.1\r\nHost: {host}\r\n{headers}Connection: close\r\n\r\n")
}

/// The headers of a WebSocket handshake from a page of `origin`.
pub fn upgrade_headers(origin: &str) -> String {
    format!(
        "Origin: {origin}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
    )
}

/// Sends `request` on `stream` and reads the answer: its status and all of it as text (the
/// head alone for a `101`, whose connection stays open).
pub async fn exchange<S: AsyncRead + AsyncWrite + Unpin>(
    mut stream: S,
    request: &str,
) -> (u16, String) {
    stream
        .write_all(request.as_bytes())
        .await
        .expect("send the request");
    let mut answer = Vec::new();
    let read = async {
        let mut chunk = [0; 16 * 1024];
        loop {
            let n = stream.read(&mut chunk).await.unwrap_or(0);
            answer.extend_from_slice(&chunk[..n]);
            let switching =
                answer.starts_with(b"HTTP/1.1 101") && answer.windows(4).any(|w| w == b"\r\n\r\n");
            if n == 0 || switching {
                break;
            }
        }
    };
    tokio::time::timeout(PATIENCE, read)
        .await
        .unwrap_or_else(|_| panic!("no answer to {request:?}"));
    let text = String::from_utf8_lossy(&answer).into_owned();
    let status = (text.split(' ').nth(1))
        .and_then(|code| code.parse().ok())
        .unwrap_or_else(|| panic!("no status in {text:?} (to {request:?})"));
    (status, text)
}

/// [`exchange`] on a new TCP connection to `address`.
pub async fn send(address: SocketAddr, request: &str) -> (u16, String) {
    let stream = TcpStream::connect(address).await.expect("connect");
    exchange(stream, request).await
}

/// `GET /stats` on a new connection, or `None` when the viewer closed it without an answer
/// (at its connection cap).
pub async fn stats_if_served(address: SocketAddr) -> Option<serde_json::Value> {
    let mut stream = TcpStream::connect(address).await.ok()?;
    let asked = request("GET", "/stats", &address.to_string(), "");
    stream.write_all(asked.as_bytes()).await.ok()?;
    let mut answer = Vec::new();
    let read = tokio::time::timeout(PATIENCE, stream.read_to_end(&mut answer));
    read.await.expect("an answer or the end").ok()?;
    let text = String::from_utf8_lossy(&answer);
    let (head, body) = text.split_once("\r\n\r\n")?;
    assert!(head.starts_with("HTTP/1.1 200"), "{text}");
    Some(serde_json::from_str(body).expect("/stats is JSON"))
}
