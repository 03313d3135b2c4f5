//! A scene of two users: the page draws each user's hands in that user's own colour, with the
//! user's name over them, and a headset sends the hands of the user the page's address names
//! (`?user=NAME`); a name the scene lacks is refused on the page, and no hands go out.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use serde::Deserialize;
use vas_client::protocol::ControlRequest;
use vas_client::{Client, Frame, HandFrame, HandSide};
use vas_testkit::{PATIENCE, Server, configs_dir, fixtures_dir};

use crate::harness::{Browser, Viewer};
use crate::replay::replay;
use crate::xr::{enter_vr, open_with_headset};

/// How high a user's name label floats over the palm, in metres (view.js `NAME_ABOVE_PALM`).
const NAME_ABOVE_PALM: f64 = 0.06;

/// A hand as the page reports it on `window.vasViewer.hands()`.
#[derive(Debug, Deserialize)]
struct DrawnHand {
    hand: u32,
    segments: Vec<DrawnSegment>,
}

#[derive(Debug, Deserialize)]
struct DrawnSegment {
    visible: bool,
    position: [f64; 3],
    colour: String,
}

/// A name label as the page reports it on `window.vasViewer.names()`.
#[derive(Debug, Deserialize)]
struct DrawnName {
    hand: u32,
    text: String,
    colour: String,
    visible: bool,
    position: [f64; 3],
}

/// The page's key of a user's hand (view.js `handKey`).
fn hand_key(frame: &HandFrame) -> u32 {
    frame.user * 2 + frame.hand
}

/// The lockstep server of a test, on the two-user hand-over's scene (anna's right hand, ben's
/// left).
fn two_user_server(test: &str) -> Server {
    let scene = configs_dir().join("two_user_handover.toml");
    Server::start_with(
        test,
        &["--lockstep", "--scene", scene.to_str().expect("UTF-8")],
    )
}

/// The scene's users' names.
fn user_names(client: &Client) -> Vec<String> {
    let scene = (client.control(ControlRequest::scene_info(), PATIENCE)).expect("scene info");
    scene.user_names().map(str::to_owned).collect()
}

#[tokio::test]
async fn each_users_hands_are_drawn_in_their_colour_under_their_name() {
    let mut server = two_user_server("viewer_two_users");
    let mut client = server.connect();
    let users = user_names(&client);
    assert_eq!(users, ["anna", "ben"]);
    let viewer = Viewer::start(server.prefix());
    let browser = Browser::start(1280, 800).await;
    (browser.client.goto(&viewer.url()).await).expect("open the page");
    browser
        .wait_for("window.vasViewer?.server && window.vasViewer.drawn.lastParts > 0")
        .await;

    // The whole hand-over, and the hand frames that end it: anna's and ben's hand of one frame.
    replay(&server, &fixtures_dir().join("two_user_handover.jsonl"));
    assert_eq!(
        client.wait(PATIENCE).expect("wait"),
        vas_client::Wake::Ready
    );
    client.poll().expect("poll");
    let published = client.latest_hands().to_vec();
    assert_eq!(published.len(), 2, "anna's and ben's hand");
    let last = published[0].frame;
    assert!(published.iter().all(|hand| hand.frame == last));
    browser
        .wait_for(&format!("window.vasViewer.drawn.lastHand >= {last}"))
        .await;
    let drawn: Vec<DrawnHand> = browser.eval("window.vasViewer.hands()").await;
    let names: Vec<DrawnName> = browser.eval("window.vasViewer.names()").await;
    let palette_hand: String = browser.eval("window.vasViewer.colours.hand").await;
    let touching_colour: String = browser.eval("window.vasViewer.colours.handTouching").await;

    // Each hand's segments not touching anything are all in one colour, its user's; the first
    // user's is the palette's hand colour, the second's another.
    let mut colours = BTreeMap::new();
    for frame in &published {
        let key = hand_key(frame);
        let hand = (drawn.iter().find(|hand| hand.hand == key))
            .unwrap_or_else(|| panic!("no hand {key} drawn: {drawn:?}"));
        assert_eq!(hand.segments.len(), frame.segment_poses().len());
        let mut own = Vec::new();
        for (index, segment) in hand.segments.iter().enumerate() {
            assert!(segment.visible, "hand {key} segment {index}");
            match frame.touching >> index & 1 {
                1 => assert_eq!(
                    segment.colour, touching_colour,
                    "hand {key} segment {index}"
                ),
                _ => own.push(segment.colour.clone()),
            }
        }
        own.dedup();
        assert_eq!(own.len(), 1, "hand {key}: one colour, {own:?}");
        colours.insert(frame.user, own.remove(0));

        // The user's name over the palm, in the hand's colour.
        let name = (names.iter().find(|name| name.hand == key))
            .unwrap_or_else(|| panic!("no name over hand {key}: {names:?}"));
        assert_eq!(name.text, users[frame.user as usize]);
        assert_eq!(name.colour, colours[&frame.user]);
        assert!(name.visible, "{name:?}");
        let [x, y, z] = hand.segments[0].position;
        let above = [x, y, z + NAME_ABOVE_PALM];
        let off = (0..3).map(|i| (name.position[i] - above[i]).abs());
        assert!(off.fold(0.0, f64::max) < 1e-6, "{name:?} over {above:?}");
    }
    assert_eq!(
        colours[&0], palette_hand,
        "anna's hands: the palette's hand colour"
    );
    assert_ne!(
        colours[&1], colours[&0],
        "ben's hands: a colour of their own"
    );
    assert_ne!(colours[&1], touching_colour);
    browser.close().await;
}

/// Receives hand frames until the newest of `user`'s hand of `side` is tracked; returns the
/// newest frame of every hand by (user, side).
fn wait_until_tracked(
    client: &mut Client,
    user: u32,
    side: HandSide,
) -> BTreeMap<(u32, u32), HandFrame> {
    let mut newest = BTreeMap::new();
    let deadline = Instant::now() + PATIENCE;
    loop {
        let key = (user, side as u32);
        if newest
            .get(&key)
            .is_some_and(|hand: &HandFrame| hand.tracked == 1)
        {
            return newest;
        }
        assert!(
            Instant::now() < deadline,
            "the hand {key:?} never followed the headset: {newest:?}"
        );
        client.wait(Duration::from_millis(100)).expect("wait");
        for frame in client.receive().expect("receive") {
            if let Frame::Hand(hand) = frame {
                newest.insert((hand.user, hand.hand), hand);
            }
        }
    }
}

#[tokio::test]
async fn the_headset_sends_the_hands_of_the_user_the_address_names() {
    let mut server = two_user_server("viewer_xr_user");
    let mut client = server.connect();
    let viewer = Viewer::start(server.prefix());
    let browser = open_with_headset(&format!("{}?user=ben", viewer.url())).await;
    let chosen: serde_json::Value = browser.eval("window.vasViewer.xrUser").await;
    assert_eq!(chosen, serde_json::json!({ "name": "ben", "index": 1 }));
    let mode: String = (browser.eval("window.iwerDevice.primaryInputMode = 'hand'")).await;
    assert_eq!(mode, "hand");
    enter_vr(&browser).await;

    // Ben's left hand follows the headset's; anna's hand has had no hand joints.
    let newest = wait_until_tracked(&mut client, 1, HandSide::Left);
    let anna = newest.get(&(0, HandSide::Right as u32));
    assert!(anna.is_none_or(|hand| hand.joints.seq == 0), "{anna:?}");
    let stats = (client.input_stats(PATIENCE)).expect("the server's input counters");
    assert!(stats.joints_accepted > 0, "{stats:?}");
    assert_eq!(stats.rejected_no_such_user, 0, "{stats:?}");
    // The headset's right hand went out as ben's too, and ben has none: refused and counted.
    assert!(stats.joints_rejected_no_such_hand > 0, "{stats:?}");
    browser.close().await;
}

#[tokio::test]
async fn a_user_the_scene_lacks_is_refused_and_no_hands_are_sent() {
    let server = two_user_server("viewer_xr_no_user");
    let viewer = Viewer::start(server.prefix());
    let browser = open_with_headset(&format!("{}?user=zoe", viewer.url())).await;
    let chosen: serde_json::Value = browser.eval("window.vasViewer.xrUser").await;
    assert_eq!(chosen, serde_json::json!({ "name": "zoe", "index": null }));
    let warnings: Vec<String> = browser.eval("window.vasViewer.warnings").await;
    assert!(
        (warnings.iter())
            .any(|text| text.starts_with("no user \"zoe\" in this scene (its users: anna, ben)")),
        "{warnings:?}"
    );
    let mode: String = (browser.eval("window.iwerDevice.primaryInputMode = 'hand'")).await;
    assert_eq!(mode, "hand");
    enter_vr(&browser).await;
    // Many XR frames with both hands tracked, and not one message sent for them.
    browser.wait_for("window.vasViewer.xrFrames > 60").await;
    let posted: [u64; 2] = browser
        .eval("[window.vasViewer.handJoints.posted.right, window.vasViewer.handJoints.posted.left]")
        .await;
    assert_eq!(posted, [0, 0]);
    let stats = viewer.stats().await;
    assert_eq!(stats["hand_joints"]["published"], 0, "{stats}");
    browser.close().await;
}
