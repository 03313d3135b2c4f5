//! "Enter VR" in an emulated headset: Meta's iwer stands in for WebXR in headless Chromium,
//! injected before the page's own scripts. The page's XR loop must draw frames, and, while the
//! recorded peg insertion replays, every part where the server last published it, the held peg
//! in the grasped colour.

use serde_json::json;
use vas_client::PART_GRASPED;
use vas_tests::{Server, configs_dir};

use crate::harness::{Browser, Viewer};
use crate::replay::{
    ALL_RELEASED, GRASPED, drawn_as_published, newest_parts, recording_halves, replay,
};

/// iwer's build, which defines `window.IWER` (see `vendor/README.md`).
const IWER: &str = include_str!("vendor/iwer/iwer.min.js");

/// Installs an emulated Meta Quest 3 as the page's `navigator.xr`, over Chromium's own (which
/// has no headset to offer).
const INSTALL: &str = "new IWER.XRDevice(IWER.metaQuest3).installRuntime({ forceInstall: true });";

#[tokio::test]
async fn entering_vr_draws_the_scene_in_an_xr_session() {
    let scene = configs_dir().join("peg_insert.toml");
    let mut server = Server::start_with(
        "viewer_xr",
        &["--lockstep", "--scene", scene.to_str().expect("UTF-8")],
    );
    let mut client = server.connect();
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
    // In lockstep the server publishes only what input asks for: the replay's frames are drawn
    // in the session, the peg held after the first half and released after the second.
    let (_halves, files) = recording_halves();
    replay(&server, &files[0]);
    let published = newest_parts(&mut client);
    let peg = (published.parts.iter())
        .find(|part| part.flags & PART_GRASPED != 0)
        .expect("the peg is held halfway through the recording");
    let held = drawn_as_published(&browser, &published).await;
    let drawn_peg = &held[peg.id as usize];
    assert_eq!(
        (drawn_peg.state.as_str(), drawn_peg.colour.as_str()),
        ("grasped", GRASPED)
    );
    replay(&server, &files[1]);
    let published = newest_parts(&mut client);
    drawn_as_published(&browser, &published).await;
    browser.wait_for(ALL_RELEASED).await;
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
