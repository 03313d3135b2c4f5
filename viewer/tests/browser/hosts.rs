//! The `Host` a request names: another site's (DNS rebinding) gets no page, no `/stats` and no
//! WebSocket, and is counted; the viewer's own names are served, including a host name given to
//! `--listen`, which is resolved.

use crate::harness::Viewer;
use crate::requests::{request, send, upgrade_headers};
use vas_testkit::{forget_prefix, unique_prefix};

#[tokio::test]
async fn a_foreign_host_gets_no_page_no_stats_and_no_websocket() {
    let prefix = unique_prefix("viewer_rebinding");
    let viewer = Viewer::start(&prefix);
    let port = viewer.address.port();
    // A page of attacker.example, its name rebound to 127.0.0.1: same origin as far as the
    // browser knows, so it sends its own host and origin.
    let foreign = format!("attacker.example:{port}");
    let origin = format!("http://{foreign}");
    let wrong_port = format!("127.0.0.1:{}", port.wrapping_add(1));
    let attempts = [
        request("GET", "/ws", &foreign, &upgrade_headers(&origin)),
        request("GET", "/stats", &foreign, ""),
        request("GET", "/", &foreign, ""),
        request("GET", "/stats", &wrong_port, ""),
        request(
            "GET",
            "/ws",
            &wrong_port,
            &upgrade_headers(&format!("http://{wrong_port}")),
        ),
        // An absolute URI naming another site, with the right Host.
        request(
            "GET",
            &format!("http://{foreign}/stats"),
            &format!("127.0.0.1:{port}"),
            "",
        ),
    ];
    for attempt in &attempts {
        let (status, answer) = send(viewer.address, attempt).await;
        assert_eq!(status, 421, "{attempt:?} was answered {answer:?}");
        assert!(!answer.contains("pages_open"), "{answer}");
    }

    // The viewer's own names are served: its page, its counters and its WebSocket.
    for host in [format!("127.0.0.1:{port}"), format!("localhost:{port}")] {
        let (status, _) = send(viewer.address, &request("GET", "/", &host, "")).await;
        assert_eq!(status, 200, "{host}");
        let origin = format!("http://{host}");
        let (status, _) = send(
            viewer.address,
            &request("GET", "/ws", &host, &upgrade_headers(&origin)),
        )
        .await;
        assert_eq!(status, 101, "{host}");
    }
    let stats = viewer.stats().await;
    assert_eq!(stats["refused_requests"]["host"], attempts.len(), "{stats}");
    drop(viewer);
    // SAFETY: the viewer, the only process on this prefix, has ended.
    unsafe { forget_prefix(&prefix) };
}

#[tokio::test]
async fn a_host_name_to_listen_on_is_resolved() {
    let prefix = unique_prefix("viewer_localhost");
    let viewer = Viewer::start_with(&prefix, &["--listen", "localhost:0"]);
    let port = viewer.address.port();
    assert_eq!(viewer.url(), format!("http://localhost:{port}/"));
    assert!(viewer.address.ip().is_loopback(), "{}", viewer.address);
    let (status, answer) = send(
        viewer.address,
        &request("GET", "/stats", &format!("localhost:{port}"), ""),
    )
    .await;
    assert_eq!(status, 200, "{answer}");
    assert!(answer.contains("\"pages_open\":0"), "{answer}");
    drop(viewer);
    // SAFETY: the viewer, the only process on this prefix, has ended.
    unsafe { forget_prefix(&prefix) };
}
