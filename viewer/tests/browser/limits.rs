//! The viewer's limits, each counted in `/stats`: a page beyond the cap is refused with a
//! reason (503) and HTTP connections beyond theirs are closed at once; a page that sends nothing, not
//! even the answer to a ping, is closed after the idle time-out; a connection that does not send
//! a whole request head is closed after the header time-out.

use std::time::Instant;

use futures_util::StreamExt;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::protocol::frame::coding::CloseCode;
use tokio_tungstenite::tungstenite::{Error, Message};
use vas_testkit::{forget_prefix, unique_prefix};

use crate::harness::{PATIENCE, Viewer};
use crate::requests::stats_if_served;

/// Reads `stream` until the viewer closes it; panics if it stays open.
async fn wait_closed(stream: &mut TcpStream) {
    let mut chunk = [0; 4096];
    let closed = tokio::time::timeout(PATIENCE, async {
        while stream.read(&mut chunk).await.is_ok_and(|n| n > 0) {}
    });
    closed.await.expect("the viewer keeps the connection open");
}

#[tokio::test]
async fn pages_beyond_the_cap_are_refused_until_one_closes() {
    let prefix = unique_prefix("viewer_page_cap");
    let args = ["--listen", "127.0.0.1:0", "--max-pages", "2"];
    let viewer = Viewer::start_with(&prefix, &args);
    let connect = || tokio_tungstenite::connect_async(viewer.ws_url());
    let first = connect().await.expect("the first page connects");
    let _second = connect().await.expect("the second page connects");
    match connect().await {
        Err(Error::Http(response)) => {
            assert_eq!(response.status(), 503);
            let reason = String::from_utf8_lossy(response.body().as_deref().unwrap_or_default());
            assert!(reason.contains("too many pages"), "{reason}");
        }
        other => panic!("a third page: {:?}", other.map(|(_, response)| response)),
    }
    let stats = viewer.stats().await;
    assert_eq!(stats["refused_requests"]["pages"], 1, "{stats}");
    assert_eq!(stats["pages_open"], 2, "{stats}");

    drop(first);
    viewer
        .wait_for_stats("the first page gone", |stats| stats["pages_open"] == 1)
        .await;
    let _third = connect()
        .await
        .expect("a page connects once another closed");

    // HTTP connections (not pages): as many as the cap are held; the next is closed on arrival.
    let mut held = Vec::new();
    for _ in 0..vas_viewer::http::MAX_HTTP_CONNECTIONS {
        held.push(TcpStream::connect(viewer.address).await.expect("connect"));
    }
    let mut beyond = TcpStream::connect(viewer.address).await.expect("connect");
    wait_closed(&mut beyond).await;
    drop(held);
    // The held connections' places come free as the viewer sees them end; until then each
    // attempt is refused too.
    let (deadline, mut refused) = (Instant::now() + PATIENCE, 1);
    let stats = loop {
        if let Some(stats) = stats_if_served(viewer.address).await {
            break stats;
        }
        refused += 1;
        assert!(
            Instant::now() < deadline,
            "no /stats after the connections closed"
        );
        tokio::task::yield_now().await;
    };
    assert_eq!(stats["refused_requests"]["connections"], refused, "{stats}");
    drop(viewer);
    // SAFETY: the viewer, the only process on this prefix, has ended.
    unsafe { forget_prefix(&prefix) };
}

#[tokio::test]
async fn a_page_that_sends_nothing_is_closed_after_the_idle_time_out() {
    let prefix = unique_prefix("viewer_idle");
    let args = ["--listen", "127.0.0.1:0", "--idle-timeout", "0.5"];
    let viewer = Viewer::start_with(&prefix, &args);
    // A live page reads all the time, so its WebSocket answers the viewer's pings.
    let (mut live, _) = tokio_tungstenite::connect_async(viewer.ws_url())
        .await
        .expect("connect");
    let live = tokio::spawn(async move { while let Some(Ok(_)) = live.next().await {} });
    // A silent page never reads, so it never answers.
    let (mut silent, _) = tokio_tungstenite::connect_async(viewer.ws_url())
        .await
        .expect("connect");
    let stats = viewer
        .wait_for_stats("the silent page closed", |stats| {
            stats["timed_out"]["pages"] != 0
        })
        .await;
    assert_eq!(stats["timed_out"]["pages"], 1, "{stats}");
    assert_eq!(stats["pages_open"], 1, "the live page stays: {stats}");
    assert!(!live.is_finished());

    // The silent page's connection is closed: with a close frame that says why, unless its
    // answers to the pings, sent as it reads at last, meet the closed connection first.
    let closed = tokio::time::timeout(PATIENCE, async {
        loop {
            match silent.next().await {
                Some(Ok(Message::Close(frame))) => {
                    let frame = frame.expect("a close frame with a reason");
                    assert_eq!(frame.code, CloseCode::Away);
                    assert!(frame.reason.contains("idle"), "{}", frame.reason);
                }
                Some(Ok(_)) => {}
                Some(Err(_)) | None => break,
            }
        }
    });
    closed
        .await
        .expect("the silent page's connection is closed");
    drop(viewer);
    // SAFETY: the viewer, the only process on this prefix, has ended.
    unsafe { forget_prefix(&prefix) };
}

#[tokio::test]
async fn a_half_sent_request_is_closed_after_the_header_time_out() {
    let prefix = unique_prefix("viewer_header");
    let args = ["--listen", "127.0.0.1:0", "--header-timeout", "0.5"];
    let viewer = Viewer::start_with(&prefix, &args);
    let mut half = TcpStream::connect(viewer.address).await.expect("connect");
    let head = format!("GET /stats HTTP/1.1\r\nHost: {}\r\n", viewer.address);
    half.write_all(head.as_bytes())
        .await
        .expect("send half a request");
    let mut silent = TcpStream::connect(viewer.address).await.expect("connect");
    wait_closed(&mut half).await;
    wait_closed(&mut silent).await;
    let stats = viewer
        .wait_for_stats("both counted", |stats| stats["timed_out"]["requests"] == 2)
        .await;
    assert_eq!(stats["timed_out"]["pages"], 0, "{stats}");
    drop(viewer);
    // SAFETY: the viewer, the only process on this prefix, has ended.
    unsafe { forget_prefix(&prefix) };
}
