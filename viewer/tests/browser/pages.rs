//! Sixteen pages at once, in windows of one headless Chromium: each gets the scene and keeps
//! getting frames, and draws them.

use vas_testkit::{Server, configs_dir};

use crate::harness::{Browser, Viewer};

const PAGES: usize = 16;

#[tokio::test]
async fn sixteen_pages_each_get_frames() {
    let scene = configs_dir().join("peg_insert.toml");
    let mut server =
        Server::start_with("viewer_pages", &["--scene", scene.to_str().expect("UTF-8")]);
    let _client = server.connect();
    let viewer = Viewer::start(server.prefix());
    // Small windows: sixteen pages each draw with SwiftShader on the CPU.
    let browser = Browser::start(320, 240).await;
    let windows = browser.open_windows(&viewer.url(), PAGES).await;
    let stats = viewer
        .wait_for_stats("sixteen pages connected", |stats| {
            stats["pages_open"] == PAGES as u64
        })
        .await;
    assert_eq!(stats["refused"]["malformed"], 0, "{stats}");

    // Every page has the scene and frames; then each gets newer ones and draws them.
    let mut seen = Vec::new();
    for window in &windows {
        browser.switch_to(window).await;
        browser
            .wait_for("window.vasViewer?.scene?.name === 'peg insert' && window.vasViewer.received.frames > 0")
            .await;
        seen.push(
            browser
                .eval::<u64>("window.vasViewer.received.lastParts")
                .await,
        );
    }
    for (window, seen) in windows.iter().zip(seen) {
        browser.switch_to(window).await;
        browser
            .wait_for(&format!("window.vasViewer.drawn.lastParts > {seen}"))
            .await;
    }
    browser.close().await;
}
