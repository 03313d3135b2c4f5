//! "Enter VR" in an emulated headset: Meta's iwer stands in for WebXR in headless Chromium,
//! injected before the page's own scripts, and the page's XR loop must draw frames.

use serde_json::json;
use vas_tests::{Server, configs_dir};

use crate::harness::{Browser, Viewer};

/// iwer's build, which defines `window.IWER` (see `vendor/README.md`).
const IWER: &str = include_str!("vendor/iwer/iwer.min.js");

/// Installs an emulated Meta Quest 3 as the page's `navigator.xr`, over Chromium's own (which
/// has no headset to offer).
const INSTALL: &str = "new IWER.XRDevice(IWER.metaQuest3).installRuntime({ forceInstall: true });";

#[tokio::test]
async fn entering_vr_draws_the_scene_in_an_xr_session() {
    let scene = configs_dir().join("peg_insert.toml");
    let mut server = Server::start_with("viewer_xr", &["--scene", scene.to_str().expect("UTF-8")]);
    let _client = server.connect();
    let viewer = Viewer::start(server.prefix());
    let browser = Browser::start(1280, 800).await;
    browser
        .cdp(
            "Page.addScriptToEvaluateOnNewDocument",
            json!({ "source": format!("{IWER}\n{INSTALL}") }),
        )
        .await;
    browser
        .client
        .goto(&viewer.url())
        .await
        .expect("open the page");
    browser
        .wait_for("window.vasViewer?.drawn.lastParts > 0")
        .await;
    browser
        .wait_for("document.getElementById('VRButton')?.textContent === 'ENTER VR'")
        .await;
    assert_eq!(browser.eval::<u64>("window.vasViewer.xrFrames").await, 0);

    browser
        .client
        .find(fantoccini::Locator::Id("VRButton"))
        .await
        .expect("the VR button")
        .click()
        .await
        .expect("click it");
    browser.wait_for("window.vasViewer.xrFrames > 0").await;
    let (xr_frames, drawn): (u64, u64) = browser
        .eval("[window.vasViewer.xrFrames, window.vasViewer.drawn.frames]")
        .await;
    // The XR loop goes on, and draws the frames the server keeps publishing.
    browser
        .wait_for(&format!(
            "window.vasViewer.xrFrames > {xr_frames} + 10 && window.vasViewer.drawn.frames > {drawn}"
        ))
        .await;
    assert_eq!(
        browser
            .eval::<String>("document.getElementById('VRButton').textContent")
            .await,
        "EXIT VR"
    );
    browser.close().await;
}
