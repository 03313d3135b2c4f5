//! What the page's panel and colours tell its user: a state for every part flag, the hands seen,
//! and menus that show what the server has, also to a page opened later.

use serde_json::Value;
use vas_testkit::{Server, configs_dir};

use crate::harness::{Browser, Viewer};
use crate::replay::{recording_halves, replay};

/// The page's panel, as `window.vasViewer.panel()` reports it.
async fn panel(browser: &Browser) -> Value {
    browser.eval("window.vasViewer.panel()").await
}

/// Chooses `value` in the page's `<select id=…>`, as a user does.
async fn choose(browser: &Browser, select: &str, value: &str) {
    let _: bool = browser
        .eval(&format!(
            "(() => {{ const select = document.getElementById('{select}'); \
             select.value = '{value}'; select.dispatchEvent(new Event('change')); \
             return true; }})()"
        ))
        .await;
}

#[tokio::test]
async fn sliding_and_pushed_parts_have_colours_of_their_own() {
    let server = Server::start("viewer_states");
    let viewer = Viewer::start(server.prefix());
    let browser = Browser::start(640, 480).await;
    browser.client.goto(&viewer.url()).await.expect("open");
    browser.wait_for("window.vasViewer").await;
    // PartState flags, as in protocol/src/output.rs.
    let (grasped, touching, sliding, pushed) = (1, 2, 4, 8);
    for (flags, state) in [
        (0, "resting"),
        (touching, "touching"),
        (grasped | touching, "grasped"),
        (grasped | touching | sliding, "sliding"),
        (pushed | touching, "pushed"),
    ] {
        let drawn: String = browser
            .eval(&format!("window.vasViewer.stateOf({flags})"))
            .await;
        assert_eq!(drawn, state, "flags {flags}");
    }
    let colours: Value = browser.eval("window.vasViewer.colours").await;
    let states =
        ["resting", "touching", "grasped", "sliding", "pushed"].map(|state| &colours[state]);
    for (index, colour) in states.iter().enumerate() {
        assert!(colour.is_string(), "{colours}");
        assert!(
            !states[..index].contains(colour),
            "a colour twice: {colours}"
        );
    }
    browser.close().await;
}

#[tokio::test]
async fn the_panel_says_which_hands_were_seen_and_shows_the_servers_scene_and_metaphor() {
    let scene = configs_dir().join("peg_insert.toml");
    let server = Server::start_with(
        "viewer_panel",
        &["--lockstep", "--scene", scene.to_str().expect("UTF-8")],
    );
    let viewer = Viewer::start(server.prefix());
    let browser = Browser::start(800, 600).await;
    browser.client.goto(&viewer.url()).await.expect("open");
    browser
        .wait_for("window.vasViewer?.server && window.vasViewer.scene")
        .await;
    let shown = panel(&browser).await;
    assert_eq!(shown["hands"], "no hand seen yet", "{shown}");
    assert_eq!(shown["scene"], "peg_insert", "the served scene: {shown}");
    assert_eq!(
        shown["metaphor"], "rubber-band",
        "the scene's own metaphor: {shown}"
    );

    // A metaphor chosen on one page is what a page opened afterwards shows.
    choose(&browser, "metaphor", "incremental").await;
    browser
        .wait_for("window.vasViewer.metaphor === 'incremental'")
        .await;
    browser
        .client
        .goto(&viewer.url())
        .await
        .expect("open again");
    browser
        .wait_for("window.vasViewer?.metaphor === 'incremental'")
        .await;
    assert_eq!(panel(&browser).await["metaphor"], "incremental");

    let (_halves, files) = recording_halves();
    replay(&server, &files[0]);
    browser
        .wait_for("window.vasViewer.handsSeen.includes('right')")
        .await;
    assert_eq!(panel(&browser).await["hands"], "hands seen: right");

    // Another scene: the menu follows, its own metaphor is in force, and no hand is seen yet.
    choose(&browser, "scenes", "peg_in_hole").await;
    let _: bool = browser
        .eval("(document.getElementById('load').click(), true)")
        .await;
    browser
        .wait_for("window.vasViewer.currentScene === 'peg_in_hole'")
        .await;
    browser
        .client
        .goto(&viewer.url())
        .await
        .expect("open again");
    browser
        .wait_for("window.vasViewer?.currentScene === 'peg_in_hole'")
        .await;
    let shown = panel(&browser).await;
    assert_eq!(
        (&shown["scene"], &shown["metaphor"], &shown["hands"]),
        (
            &Value::from("peg_in_hole"),
            &Value::from("rubber-band"),
            &Value::from("no hand seen yet")
        ),
        "{shown}"
    );
    browser.close().await;
}
