//! Fuzz targets for the viewer's network side: HTTP requests as any client could send them, and
//! a page's WebSocket frames after its handshake. Each input is served by the viewer's own
//! connection code and routes (`Host` check, access token, page cap, pages) over an in-memory
//! stream, on a runtime of its own whose clock runs ahead whenever all waits (so that the
//! header and idle time-outs end a stalled input at once). A panic, a hang, an answer that is
//! not HTTP, or a page or place left behind is a failure.

use std::panic::AssertUnwindSafe;
use std::sync::Arc;
use std::time::Duration;

use axum::Router;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::sync::Semaphore;
use vas_viewer::access::Access;
use vas_viewer::connections::serve_connection;
use vas_viewer::host::Hosts;
use vas_viewer::http::{App, router};
use vas_viewer::hub::{Hub, Inbox};

/// The token of the fuzzed viewer.
const TOKEN: &str = "fuzzing-token-0123456789";
/// The pages the fuzzed viewer takes at once.
const PAGES: usize = 2;

/// A viewer on 127.0.0.1:8080 that asks for [`TOKEN`], without a link thread (its inbox is
/// kept, so that commands wait rather than fail).
struct Viewer {
    app: Router,
    hub: Arc<Hub>,
    pages: Arc<Semaphore>,
    _inbox: Inbox,
}

impl Viewer {
    fn new() -> Self {
        let (hub, inbox) = Hub::new();
        let hub = Arc::new(hub);
        let listen = "127.0.0.1:8080".parse().expect("an address");
        let pages = Arc::new(Semaphore::new(PAGES));
        let app = App {
            hub: Arc::clone(&hub),
            hosts: Hosts::new(&listen, 8080, false),
            access: Some(Access::new(TOKEN.into(), 8080, false).expect("a token")),
            pages: Arc::clone(&pages),
            idle_timeout: Duration::from_secs(5),
        };
        Self {
            app: router(Arc::new(app)),
            hub,
            pages,
            _inbox: inbox,
        }
    }

    /// Sends `input` on one connection and returns all the viewer answered until it closed the
    /// connection (at the latest after its header or idle time-out, at once on the paused
    /// clock); then checks that nothing was left behind. The sending side stays open, as a
    /// browser's does.
    fn exchange(&self, input: &[u8]) -> Vec<u8> {
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_time()
            .start_paused(true)
            .build()
            .expect("a runtime");
        let answer = runtime.block_on(async {
            let (mut client, server) = tokio::io::duplex(64 * 1024);
            let (app, hub) = (self.app.clone(), Arc::clone(&self.hub));
            let served = tokio::spawn(serve_connection(server, app, Duration::from_secs(1), hub));
            let mut answer = Vec::new();
            let (mut reading, mut writing) = tokio::io::split(&mut client);
            // The viewer may stop reading (a refusal closes the connection): not an error.
            let write = async {
                let _ = writing.write_all(input).await;
            };
            let read = reading.read_to_end(&mut answer);
            let (_, read) = tokio::join!(write, read);
            read.expect("read the answer");
            served.await.expect("the connection's task");
            // A page ends on its own task; it is done once its place is back.
            let _ = self
                .pages
                .acquire_many(PAGES as u32)
                .await
                .expect("the pages' places");
            answer
        });
        drop(runtime);
        let open = self
            .hub
            .stats
            .pages_open
            .load(std::sync::atomic::Ordering::Relaxed);
        assert_eq!(open, 0, "a page left open");
        answer
    }
}

/// The HTTP status of each answer in `answer` (one per request, several when pipelined), and
/// panics unless `answer` is a sequence of HTTP/1.x answers up to a `101` (after which the
/// WebSocket speaks). An HTTP/1.0 request is answered in HTTP/1.0.
fn statuses(answer: &[u8]) -> Vec<u16> {
    let text = String::from_utf8_lossy(answer);
    let mut statuses = Vec::new();
    for (at, _) in text.match_indices("HTTP/1.") {
        let Some(line) = text[at..].get(..12) else {
            continue;
        };
        if !(line.starts_with("HTTP/1.0 ") || line.starts_with("HTTP/1.1 ")) {
            continue;
        }
        let code = line[9..].parse();
        statuses.push(code.unwrap_or_else(|_| panic!("no status at {at} of {text:?}")));
        if statuses.last() == Some(&101) {
            break;
        }
    }
    assert!(
        answer.is_empty() || text.starts_with("HTTP/1.1 ") || text.starts_with("HTTP/1.0 "),
        "not HTTP: {text:?}"
    );
    statuses
}

/// A request built from `bytes`, and what its headers were: the first byte picks the method
/// (bits 1-2), the WebSocket upgrade (bit 3), the credentials (bits 4-5: none, the token, a
/// wrong token, a made-up session) and the origin (bits 6-7: none, the host's, another site's,
/// `null`); the rest is the path, the host and the body, split at line feeds (carriage returns
/// dropped, so that these are the request's only headers).
struct Built {
    request: Vec<u8>,
    host_is_the_viewers: bool,
    has_the_token: bool,
}

fn build(flags: u8, rest: &[u8]) -> Built {
    let clean: Vec<u8> = rest.iter().copied().filter(|&b| b != b'\r').collect();
    let mut fields = clean.splitn(3, |&b| b == b'\n');
    let (path, host, body) = (
        fields.next().unwrap_or_default(),
        fields.next().unwrap_or_default(),
        fields.next().unwrap_or_default(),
    );
    let method = ["GET", "POST", "HEAD", "PUT"][usize::from(flags >> 1 & 3)];
    // As the server reads it: without the spaces and tabs around it.
    let host_text = String::from_utf8_lossy(host).to_ascii_lowercase();
    let host_text = host_text.trim_matches([' ', '\t']);
    let mut request = [method.as_bytes(), b" ", path, b" HTTP/1.1\r\n"].concat();
    if !host.is_empty() {
        request.extend_from_slice(&[b"Host: ", host, b"\r\n"].concat());
    }
    if flags & 8 != 0 {
        request.extend_from_slice(
            b"Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Version: 13\r\n\
              Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n",
        );
    }
    let credentials = match flags >> 4 & 3 {
        1 => format!("Authorization: Bearer {TOKEN}\r\n"),
        2 => "Authorization: Bearer fuzzing-token-9876543210\r\n".to_owned(),
        3 => "Cookie: vas_viewer_8080=00ff\r\n".to_owned(),
        _ => String::new(),
    };
    request.extend_from_slice(credentials.as_bytes());
    let origin = match flags >> 6 {
        1 => [b"Origin: http://", host, b"\r\n"].concat(),
        2 => b"Origin: http://attacker.example:8080\r\n".to_vec(),
        3 => b"Origin: null\r\n".to_vec(),
        _ => Vec::new(),
    };
    request.extend_from_slice(&origin);
    let length = format!("Content-Length: {}\r\n\r\n", body.len());
    request.extend_from_slice(length.as_bytes());
    request.extend_from_slice(body);
    Built {
        request,
        host_is_the_viewers: ["127.0.0.1:8080", "localhost:8080", "[::1]:8080"]
            .contains(&host_text),
        has_the_token: flags >> 4 & 3 == 1,
    }
}

/// HTTP requests: raw bytes (odd first byte), or one request built by [`build`] (even), whose
/// answer must keep the viewer's promises: no page, counters or WebSocket (200, 101) and no
/// session (303) for a request that does not name the viewer as its host; no page, counters or
/// WebSocket without the token.
#[test]
fn viewer_http_requests() {
    // Unwind-safe: a panic fails the target, and nothing of the viewer is looked at after it.
    let viewer = AssertUnwindSafe(Viewer::new());
    bolero::check!().for_each(|bytes: &[u8]| {
        let Some((&flags, rest)) = bytes.split_first() else {
            return;
        };
        if flags & 1 == 1 {
            statuses(&viewer.exchange(rest));
            return;
        }
        let built = build(flags, rest);
        let answered = statuses(&viewer.exchange(&built.request));
        let Some(&status) = answered.first() else {
            return;
        };
        if [101, 200, 303].contains(&status) {
            assert!(
                built.host_is_the_viewers,
                "{status} for {:?}",
                built.request
            );
        }
        if [101, 200].contains(&status) {
            assert!(built.has_the_token, "{status} for {:?}", built.request);
        }
    });
}

/// A page's WebSocket frames after a well-formed handshake: the input is read as frames, each a
/// byte of flags (bit 7 FIN, bit 6 RSV1, bits 0-3 the opcode, any of the 16), a little-endian
/// `u16` length and that many bytes of payload (fewer at the end), sent masked as a browser
/// sends them. Whatever the frames, the viewer answers in WebSocket frames and closes the page
/// once the input ends (checked by [`Viewer::exchange`]).
#[test]
fn viewer_websocket_frames() {
    // Unwind-safe: a panic fails the target, and nothing of the viewer is looked at after it.
    let viewer = AssertUnwindSafe(Viewer::new());
    let handshake = format!(
        "GET /ws HTTP/1.1\r\nHost: 127.0.0.1:8080\r\nOrigin: http://127.0.0.1:8080\r\n\
         Authorization: Bearer {TOKEN}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n"
    );
    bolero::check!().for_each(|bytes: &[u8]| {
        let mut input = handshake.as_bytes().to_vec();
        let mut rest = bytes;
        while let Some((&flags, after)) = rest.split_first() {
            let length = match after {
                [low, high, ..] => usize::from(u16::from_le_bytes([*low, *high])),
                _ => 0,
            };
            let after = after.get(2..).unwrap_or_default();
            let (payload, after) = after.split_at(length.min(after.len()));
            push_frame(&mut input, flags, payload);
            rest = after;
        }
        let answer = viewer.exchange(&input);
        assert_eq!(
            statuses(&answer),
            [101],
            "{:?}",
            String::from_utf8_lossy(&answer)
        );
    });
}

/// Appends one masked client frame.
fn push_frame(input: &mut Vec<u8>, flags: u8, payload: &[u8]) {
    const MASK: [u8; 4] = [0x37, 0xfa, 0x21, 0x3d];
    input.push(flags & 0b1100_1111);
    match payload.len() {
        length @ 0..=125 => input.push(0x80 | length as u8),
        length => {
            input.push(0x80 | 126);
            input.extend_from_slice(&(length as u16).to_be_bytes());
        }
    }
    input.extend_from_slice(&MASK);
    input.extend(payload.iter().zip(MASK.iter().cycle()).map(|(b, m)| b ^ m));
}
