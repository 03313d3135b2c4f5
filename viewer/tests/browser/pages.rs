//! Sixteen pages at once, in one headless Chromium: each gets the scene and keeps getting
//! frames.

use vas_tests::{Server, configs_dir};

use crate::harness::{Browser, Viewer};

const PAGES: usize = 16;

#[tokio::test]
async fn sixteen_pages_each_get_frames() {
    let scene = configs_dir().join("peg_insert.toml");
    let mut server =
        Server::start_with("viewer_pages", &["--scene", scene.to_str().expect("UTF-8")]);
    let _client = server.connect();
    let viewer = Viewer::start(server.prefix());
    let browser = Browser::start(800, 600).await;

    let mut windows = vec![browser.client.window().await.expect("the first window")];
    for _ in 1..PAGES {
        let tab = browser.client.new_window(true).await.expect("a new tab");
        windows.push(tab.handle);
    }
    for window in &windows {
        browser
            .client
            .switch_to_window(window.clone())
            .await
            .expect("switch tabs");
        browser
            .client
            .goto(&viewer.url())
            .await
            .expect("open the page");
    }
    let stats = viewer
        .wait_for_stats("sixteen pages connected", |stats| {
            stats["pages_open"] == PAGES as u64
        })
        .await;
    assert_eq!(stats["refused"]["malformed"], 0, "{stats}");

    // Every page has the scene and frames; then each gets newer ones.
    let mut seen = Vec::new();
    for window in &windows {
        browser
            .client
            .switch_to_window(window.clone())
            .await
            .expect("switch tabs");
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
        browser
            .client
            .switch_to_window(window.clone())
            .await
            .expect("switch tabs");
        browser
            .wait_for(&format!("window.vasViewer.received.lastParts > {seen}"))
            .await;
    }
    browser.close().await;
}
