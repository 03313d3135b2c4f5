//! "Enter VR" in an emulated headset: Meta's iwer stands in for WebXR in headless Chromium,
//! injected before the page's own scripts. The page's XR loop must draw frames, and, while the
//! recorded peg insertion replays, every part where the server last published it, the held peg
//! in the grasped colour. With the headset's hands tracked, the page sends both hands' joints
//! each XR frame, and the server's hands follow them.

use std::time::{Duration, Instant};

use serde_json::json;
use vas_client::{Client, HandFrame, HandSide, PART_GRASPED};
use vas_testkit::{PATIENCE, Server, configs_dir};

use crate::harness::{Browser, Viewer};
use crate::replay::{
    ALL_RELEASED, GRASPED, drawn_as_published, newest_parts, recording_halves, replay,
};

/// iwer's build, which defines `window.IWER` (see `vendor/README.md`).
const IWER: &str = include_str!("vendor/iwer/iwer.min.js");

/// Installs an emulated Meta Quest 3 as the page's `navigator.xr`, over Chromium's own (which
/// has no headset to offer), and keeps the device as `window.iwerDevice` for the tests to move
/// its hands.
const INSTALL: &str = "window.iwerDevice = new IWER.XRDevice(IWER.metaQuest3);
window.iwerDevice.installRuntime({ forceInstall: true });";

/// Opens the viewer's page at `url` in headless Chromium with the emulated headset installed,
/// and waits until it has drawn the scene's parts and offers "Enter VR".
pub async fn open_with_headset(url: &str) -> Browser {
    let browser = Browser::start(1280, 800).await;
    browser
        .cdp(
            "Page.addScriptToEvaluateOnNewDocument",
            json!({ "source": format!("{IWER}\n{INSTALL}") }),
        )
        .await;
    browser.client.goto(url).await.expect("open the page");
    browser
        .wait_for("window.vasViewer?.drawn.lastParts > 0")
        .await;
    browser
        .wait_for("document.getElementById('VRButton')?.textContent === 'ENTER VR'")
        .await;
    browser
}

/// Presses "Enter VR" and waits for the session's first frame.
pub async fn enter_vr(browser: &Browser) {
    browser
        .client
        .find(fantoccini::Locator::Id("VRButton"))
        .await
        .expect("the VR button")
        .click()
        .await
        .expect("click it");
    browser.wait_for("window.vasViewer.xrFrames > 0").await;
}

#[tokio::test]
async fn entering_vr_draws_the_scene_in_an_xr_session() {
    let scene = configs_dir().join("peg_insert.toml");
    let mut server = Server::start_with(
        "viewer_xr",
        &["--lockstep", "--scene", scene.to_str().expect("UTF-8")],
    );
    let mut client = server.connect();
    let viewer = Viewer::start(server.prefix());
    let browser = open_with_headset(&viewer.url()).await;
    assert_eq!(browser.eval::<u64>("window.vasViewer.xrFrames").await, 0);
    enter_vr(&browser).await;
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

/// How far the server's hand root may be from where the emulated hand is, in metres: the root
/// is the model's (at its wrist), the emulated hand's position its grip, a few centimetres
/// apart; a joint left in WebXR's frame (y up, no table) would be most of a metre off.
const NEAR_M: f64 = 0.15;

/// How closely the server's hand root follows a move of the emulated hand, in metres.
const FOLLOW_M: f64 = 0.002;

#[tokio::test]
async fn the_headsets_tracked_hands_drive_both_of_the_servers_hands() {
    let scene = configs_dir().join("two_hand_handover.toml");
    let mut server = Server::start_with(
        "viewer_xr_hands",
        &["--lockstep", "--scene", scene.to_str().expect("UTF-8")],
    );
    let mut client = server.connect();
    let viewer = Viewer::start(server.prefix());
    let browser = open_with_headset(&viewer.url()).await;
    let mode: String = browser
        .eval("window.iwerDevice.primaryInputMode = 'hand'")
        .await;
    assert_eq!(mode, "hand");
    enter_vr(&browser).await;

    // Both hands tracked, each where the emulated hand is in the drawn scene (the collision
    // loop takes a hand there from where it was over a few verified steps).
    let mut hands = NewestHands::default();
    let mut expected = [[0.0; 3]; 2];
    for side in [HandSide::Right, HandSide::Left] {
        expected[side as usize] = in_vas_world(emulated_hand(&browser, side).await);
    }
    let what = format!("both hands tracked near the emulated hands at {expected:?} (vas world)");
    hands.wait_until(&mut client, &what, |frames| {
        both_tracked(frames)
            && (0..2).all(|side| distance(frames[side].root.position, expected[side]) < NEAR_M)
    });
    let first = hands.settled(&mut client);
    let stats = client
        .input_stats(PATIENCE)
        .expect("the server's input counters");
    assert!(stats.joints_accepted > 0, "{stats:?}");
    assert_eq!(stats.joints_rejected(), 0, "{stats:?}");
    let accepted_first = stats.joints_accepted;

    // Each hand moved (WebXR: right, up, toward the user) follows, the other stays.
    for (side, shift) in [
        (HandSide::Right, [0.05, 0.1, 0.05]),
        (HandSide::Left, [-0.04, -0.05, -0.08]),
    ] {
        let (moving, other) = (side as usize, 1 - side as usize);
        let settled = hands.settled(&mut client);
        let before = settled[moving].root.position;
        let other_before = settled[other].root.position;
        move_emulated_hand(&browser, side, shift).await;
        let [dx, dy, dz] = shift;
        // WebXR's x, y up, z toward the user are vas's x, z up, -y.
        let target = [before[0] + dx, before[1] - dz, before[2] + dy];
        let what = format!("the {} hand moved to {target:?}", side.name());
        let moved = hands.wait_until(&mut client, &what, |frames| {
            both_tracked(frames) && distance(frames[moving].root.position, target) < FOLLOW_M
        });
        let stayed = distance(moved[other].root.position, other_before);
        assert!(stayed < FOLLOW_M, "the other hand moved {stayed} m");
    }
    // Samples of both sides kept coming, and every one was accepted.
    hands.wait_until(&mut client, "newer samples of both hands", |frames| {
        both_tracked(frames)
            && (0..2).all(|side| frames[side].joints.seq > first[side].joints.seq + 10)
    });
    let stats = client
        .input_stats(PATIENCE)
        .expect("the server's input counters");
    assert!(stats.joints_accepted > accepted_first + 20, "{stats:?}");
    assert_eq!(stats.joints_rejected(), 0, "{stats:?}");

    // The right hand goes away: the page says so once, and the server's right hand is
    // untracked while the left still follows its joints.
    let untracked_before = stats.joints_untracked;
    let _: bool = browser
        .eval("(window.iwerDevice.hands.right.connected = false) === false")
        .await;
    hands.wait_until(&mut client, "the right hand untracked", |frames| {
        let [right, left] = frames.map(|frame| frame.tracked);
        (right, left) == (0, 1)
    });
    let stats = client
        .input_stats(PATIENCE)
        .expect("the server's input counters");
    assert!(stats.joints_untracked > untracked_before, "{stats:?}");
    assert_eq!(stats.joints_rejected(), 0, "{stats:?}");

    let stats = viewer
        .wait_for_stats("hand joints published", |stats| {
            stats["hand_joints"]["published"].as_u64() > Some(0)
        })
        .await;
    assert_eq!(stats["hand_joints"]["rejected"], 0, "{stats}");
    assert_eq!(stats["refused"]["malformed"], 0, "{stats}");
    let posted: [u64; 2] = browser
        .eval("[window.vasViewer.handJoints.posted.right, window.vasViewer.handJoints.posted.left]")
        .await;
    assert!(posted.iter().all(|&count| count > 10), "{posted:?}");
    browser.close().await;
}

/// The newest hand frame of each side the server published, as a renderer receives them.
#[derive(Default)]
struct NewestHands([Option<HandFrame>; 2]);

impl NewestHands {
    /// Receives hand frames until both hands are tracked and at rest: each root where it was
    /// five samples of its hand before (within 0.1 mm), and returns those.
    fn settled(&mut self, client: &mut Client) -> [HandFrame; 2] {
        let deadline = Instant::now() + PATIENCE;
        loop {
            let before = self.wait_until(client, "both hands tracked", both_tracked);
            let after = self.wait_until(client, "five newer samples of each hand", |frames| {
                (0..2).all(|side| frames[side].joints.seq >= before[side].joints.seq + 5)
            });
            let at_rest = (0..2)
                .all(|side| distance(after[side].root.position, before[side].root.position) < 1e-4);
            if both_tracked(&after) && at_rest {
                return after;
            }
            assert!(
                Instant::now() < deadline,
                "waited for both hands to come to rest"
            );
        }
    }

    /// Receives hand frames until `condition` holds of the newest of each hand (indexed by side
    /// code), and returns those.
    fn wait_until(
        &mut self,
        client: &mut Client,
        what: &str,
        condition: impl Fn(&[HandFrame; 2]) -> bool,
    ) -> [HandFrame; 2] {
        let deadline = Instant::now() + PATIENCE;
        loop {
            if let [Some(right), Some(left)] = self.0
                && condition(&[right, left])
            {
                return [right, left];
            }
            let summary: Vec<_> = (self.0.iter().flatten())
                .map(|frame| {
                    (
                        frame.hand,
                        frame.tracked,
                        frame.joints.seq,
                        frame.root.position,
                    )
                })
                .collect();
            assert!(
                Instant::now() < deadline,
                "waited for {what}; newest hand frames (side, tracked, joints seq, root): {summary:?}"
            );
            client
                .wait(Duration::from_millis(100))
                .expect("wait for frames");
            for frame in client.receive().expect("receive frames") {
                if let vas_client::Frame::Hand(hand) = frame
                    && let Some(slot) = self.0.get_mut(hand.hand as usize)
                {
                    *slot = Some(hand);
                }
            }
        }
    }
}

/// Whether both hands follow their joints.
fn both_tracked(frames: &[HandFrame; 2]) -> bool {
    frames.iter().all(|frame| frame.tracked == 1)
}

/// Where the emulated hand of `side` is in the session's local-floor space.
async fn emulated_hand(browser: &Browser, side: HandSide) -> [f64; 3] {
    let name = side.name();
    browser
        .eval(&format!(
            "(({{ x, y, z }}) => [x, y, z])(window.iwerDevice.hands.{name}.position)"
        ))
        .await
}

/// Moves the emulated hand of `side` by `shift` (metres, local-floor space).
async fn move_emulated_hand(browser: &Browser, side: HandSide, [dx, dy, dz]: [f64; 3]) {
    let name = side.name();
    let _: bool = browser
        .eval(&format!(
            "((p) => (p.set(p.x + {dx}, p.y + {dy}, p.z + {dz}), true))(window.iwerDevice.hands.{name}.position)"
        ))
        .await;
}

/// A point of the session's local-floor space in the vas world, as the page places the world
/// (xr.js): z up turned to WebXR's y up, the origin on a table 0.8 m high, 0.4 m ahead.
fn in_vas_world([x, y, z]: [f64; 3]) -> [f64; 3] {
    [x, -(z + 0.4), y - 0.8]
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}
