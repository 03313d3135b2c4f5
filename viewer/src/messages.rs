//! The messages the viewer sends a page, built once for all pages.
//!
//! Text messages are JSON objects with a `type`: `status`, `scene`, `frame`, `event`, `reply`,
//! `warning`. Poses keep the wire's units and order (metres; quaternions x, y, z, w; z up) and
//! its full precision, so a page draws exactly what the server published.

use axum::extract::ws::Message;
use serde::Serialize;
use serde_json::json;
use vas_client::words::grasp_name;
use vas_client::{HandFrame, PartState, PartsFrame, WirePose};

/// `{"type": "status"}`: whether a server answers, and the scenes it offers.
pub fn status(server: bool, scene_names: &[String]) -> Message {
    text(&json!({ "type": "status", "server": server, "scene_names": scene_names }))
}

/// `{"type": "reply"}`: the answer to a page's command.
pub fn reply(command: &str, answer: &Result<String, String>) -> Message {
    let (ok, message) = match answer {
        Ok(message) => (true, message),
        Err(message) => (false, message),
    };
    text(&json!({ "type": "reply", "command": command, "ok": ok, "message": message }))
}

/// `{"type": "warning"}`: something the page's user should know (e.g. events it missed).
pub fn warning(message: &str) -> Message {
    text(&json!({ "type": "warning", "message": message }))
}

/// One part's drawn state in a frame message.
#[derive(Debug, Serialize)]
struct PartView<'a> {
    id: u32,
    flags: u32,
    position: &'a [f64; 3],
    rotation: &'a [f64; 4],
}

/// The newest parts frame in a frame message.
#[derive(Debug, Serialize)]
struct PartsView<'a> {
    frame: u64,
    /// The answered tracker sample's timestamp (ns since the Unix epoch), for the latency.
    tracker_ns: u64,
    /// When the server published the frame (ns since the Unix epoch).
    published_ns: u64,
    parts: Vec<PartView<'a>>,
}

/// One hand's newest frame in a frame message.
#[derive(Debug, Serialize)]
struct HandView<'a> {
    /// The side's code (right 0, left 1), as the scene's hands name it.
    hand: u32,
    frame: u64,
    /// The answered tracker sample's timestamp (ns since the Unix epoch), for the latency.
    tracker_ns: u64,
    published_ns: u64,
    tracked: bool,
    root: &'a WirePose,
    /// Each segment's verified world pose, in the order of the scene's segment meshes.
    segments: &'a [WirePose],
    grasp: &'static str,
    /// Bit per [`vas_client::HandSegment`]: that segment touches a part.
    touching: u32,
}

/// `{"type": "frame"}`: the newest parts frame and each hand's newest frame, for the scene
/// numbered `scene`.
pub fn frame<'a>(
    scene: u64,
    parts: Option<&PartsFrame>,
    hands: impl IntoIterator<Item = &'a HandFrame>,
) -> Message {
    let parts = parts.map(|frame| PartsView {
        frame: frame.header.frame,
        tracker_ns: frame.header.tracker.timestamp_ns,
        published_ns: frame.header.timestamp_ns,
        parts: frame.parts.iter().map(part_view).collect(),
    });
    let hands: Vec<HandView> = hands.into_iter().map(hand_view).collect();
    text(&json!({ "type": "frame", "scene": scene, "parts": parts, "hands": hands }))
}

fn part_view(part: &PartState) -> PartView<'_> {
    PartView {
        id: part.id,
        flags: part.flags,
        position: &part.position,
        rotation: &part.rotation,
    }
}

fn hand_view(hand: &HandFrame) -> HandView<'_> {
    HandView {
        hand: hand.hand,
        frame: hand.frame,
        tracker_ns: hand.tracker.timestamp_ns,
        published_ns: hand.timestamp_ns,
        tracked: hand.tracked != 0,
        root: &hand.root,
        segments: hand.segment_poses(),
        grasp: grasp_name(hand.grasp_type),
        touching: hand.touching,
    }
}

/// A JSON text message.
fn text(value: &impl Serialize) -> Message {
    Message::Text(
        serde_json::to_string(value)
            .expect("viewer messages serialise")
            .into(),
    )
}
