//! The WebSocket: a page that sends something other than a command or an acknowledgement is
//! closed and counted, while another page keeps getting frames and its commands answered; a page
//! that does not acknowledge its frames is sent no more of them, and then the newest; a page
//! that drops its connection without a close frame sent no bad message.

use std::time::Instant;

use futures_util::{SinkExt, StreamExt};
use serde_json::Value;
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::tungstenite::protocol::frame::coding::CloseCode;
use tokio_tungstenite::{MaybeTlsStream, WebSocketStream};
use vas_testkit::{PATIENCE, Server, configs_dir, forget_prefix, unique_prefix};

use crate::harness::Viewer;

type Socket = WebSocketStream<MaybeTlsStream<TcpStream>>;

/// A page's connection, as a tool would open it.
async fn connect(viewer: &Viewer) -> Socket {
    tokio_tungstenite::connect_async(viewer.ws_url())
        .await
        .expect("the WebSocket opens")
        .0
}

/// The next JSON message of `kind` (others skipped).
async fn next_of(socket: &mut Socket, kind: &str) -> Value {
    let deadline = Instant::now() + PATIENCE;
    loop {
        let remaining = deadline.saturating_duration_since(Instant::now());
        let message = tokio::time::timeout(remaining, socket.next())
            .await
            .unwrap_or_else(|_| panic!("no {kind} message in time"))
            .unwrap_or_else(|| panic!("the connection ended before a {kind} message"))
            .expect("a message");
        if let Message::Text(text) = message {
            let value: Value = serde_json::from_str(&text).expect("JSON");
            if value["type"] == kind {
                return value;
            }
        }
    }
}

/// The parts frame number of the next frame message, acknowledged as a page does.
async fn next_frame_number(socket: &mut Socket) -> u64 {
    let number = next_of(socket, "frame").await["parts"]["frame"]
        .as_u64()
        .expect("a parts frame number");
    socket
        .send(Message::text(r#"{"type":"ack"}"#))
        .await
        .expect("send the ack");
    number
}

#[tokio::test]
async fn bad_messages_close_their_page_only_and_are_counted() {
    let scene = configs_dir().join("peg_insert.toml");
    let mut server = Server::start_with("viewer_ws", &["--scene", scene.to_str().expect("UTF-8")]);
    let _client = server.connect();
    let viewer = Viewer::start(server.prefix());

    let mut good = connect(&viewer).await;
    let scene = next_of(&mut good, "scene").await;
    assert_eq!(scene["name"], "peg insert");
    let before = next_frame_number(&mut good).await;

    let oversized = format!(r#"{{"type":"load_scene","name":"{}"}}"#, "x".repeat(5000));
    let bad = [
        Message::text("not json"),
        Message::text(r#"{"type":"reset","extra":1}"#),
        Message::binary(vec![1, 2, 3]),
        Message::text(oversized),
        Message::text(r#"{"type":"shutdown"}"#),
        Message::text(r#"{"type":"ack","frame":1}"#),
    ];
    for message in bad {
        let mut page = connect(&viewer).await;
        page.send(message.clone()).await.expect("send");
        let deadline = Instant::now() + PATIENCE;
        let close = loop {
            let remaining = deadline.saturating_duration_since(Instant::now());
            let next = tokio::time::timeout(remaining, page.next())
                .await
                .unwrap_or_else(|_| panic!("the viewer did not close the page after {message:?}"));
            match next {
                Some(Ok(Message::Close(frame))) => break frame,
                Some(Ok(_)) => {}
                Some(Err(_)) | None => panic!("the page was dropped without a close frame"),
            }
        };
        let close = close.expect("a close frame with a reason");
        assert_eq!(close.code, CloseCode::Policy, "closing after {message:?}");
    }

    let stats = viewer
        .wait_for_stats("the refusals counted", |stats| {
            stats["pages_open"] == 1 && stats["refused"]["malformed"] == 4
        })
        .await;
    assert_eq!(stats["refused"]["oversized"], 1, "{stats}");
    assert_eq!(stats["refused"]["unknown"], 1, "{stats}");

    // The good page still gets frames, newer ones.
    let mut after = next_frame_number(&mut good).await;
    while after <= before {
        after = next_frame_number(&mut good).await;
    }

    // And its commands are answered: done, or refused with the server's reason.
    good.send(Message::text(r#"{"type":"reset"}"#))
        .await
        .expect("send");
    let reply = next_of(&mut good, "reply").await;
    assert_eq!(reply["ok"], true, "{reply}");
    good.send(Message::text(
        r#"{"type":"set_metaphor","metaphor":"incremental"}"#,
    ))
    .await
    .expect("send");
    let reply = next_of(&mut good, "reply").await;
    assert_eq!(reply["ok"], true, "{reply}");
    good.send(Message::text(
        r#"{"type":"load_scene","name":"no such scene"}"#,
    ))
    .await
    .expect("send");
    let reply = next_of(&mut good, "reply").await;
    assert_eq!(reply["ok"], false, "{reply}");
    assert!(
        !reply["message"].as_str().unwrap_or_default().is_empty(),
        "a refusal says why: {reply}"
    );
}

#[tokio::test]
async fn a_page_that_does_not_acknowledge_is_sent_no_more_frames_then_the_newest() {
    let scene = configs_dir().join("peg_insert.toml");
    let mut server = Server::start_with("viewer_ack", &["--scene", scene.to_str().expect("UTF-8")]);
    let _client = server.connect();
    let viewer = Viewer::start(server.prefix());

    let mut slow = connect(&viewer).await;
    next_of(&mut slow, "scene").await;
    // The fast page sees the server publish a hundred frames more.
    let mut fast = connect(&viewer).await;
    let first = next_frame_number(&mut fast).await;
    let mut newest = first;
    while newest < first + 100 {
        newest = next_frame_number(&mut fast).await;
    }

    // Meanwhile the slow page, which acknowledged nothing, was sent no more than its window.
    let mut unacknowledged = Vec::new();
    while let Ok(Some(message)) =
        tokio::time::timeout(std::time::Duration::from_millis(300), slow.next()).await
    {
        if let Message::Text(text) = message.expect("a message") {
            let value: Value = serde_json::from_str(&text).expect("JSON");
            if value["type"] == "frame" {
                unacknowledged.push(value["parts"]["frame"].as_u64().expect("a frame number"));
            }
        }
    }
    assert_eq!(
        unacknowledged.len(),
        vas_viewer::page::FRAMES_IN_FLIGHT as usize,
        "frames sent to a page that acknowledged none: {unacknowledged:?}"
    );

    // Once it acknowledges one, it is sent the newest frame, not the next of a backlog.
    slow.send(Message::text(r#"{"type":"ack"}"#))
        .await
        .expect("send the ack");
    let next = next_frame_number(&mut slow).await;
    assert!(
        next >= newest,
        "after the ack the page got frame {next}; the newest it could have had is {newest} or later"
    );
}

#[tokio::test]
async fn a_page_that_drops_its_connection_sent_no_bad_message() {
    let prefix = unique_prefix("viewer_dropped");
    let viewer = Viewer::start(&prefix);
    const PAGES: u64 = 20;
    for _ in 0..PAGES {
        // Dropped at once: its TCP connection ends without a WebSocket close frame, as when a
        // tab is killed or the network goes.
        drop(connect(&viewer).await);
    }
    let stats = viewer
        .wait_for_stats("the pages gone", |stats| {
            stats["pages_served"] == PAGES && stats["pages_open"] == 0
        })
        .await;
    assert_eq!(stats["refused"]["malformed"], 0, "{stats}");
    assert_eq!(stats["refused"]["oversized"], 0, "{stats}");
    drop(viewer);
    // SAFETY: the viewer, the only process on this prefix, has ended.
    unsafe { forget_prefix(&prefix) };
}
