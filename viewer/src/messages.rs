//! The messages the viewer sends a page, built once for all pages.
//!
//! Text messages are JSON objects with a `type`: `status`, `scene`, `frame` (parts, hands and
//! clearance pairs), `event`, `reply`, `warning`. Poses keep the wire's units and order (metres; quaternions x, y, z, w; z up) and
//! its full precision, so a page draws exactly what the server published.

use axum::extract::ws::Message;
use serde::Serialize;
use serde_json::json;
use vas_client::words::grasp_name;
use vas_client::{
    ClearanceFrame, ClearancePair, HandFrame, PartState, PartsFrame, SlidingMetaphor, WirePose,
};

/// What a page is told of the server in a `status` message.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ServerStatus {
    /// Whether a server answers.
    pub server: bool,
    /// The scenes it offers by name.
    pub scene_names: Vec<String>,
    /// The name among `scene_names` of the scene it serves; `None` when it serves one it does
    /// not offer.
    pub scene: Option<String>,
    /// The sliding metaphor the server uses: the scene's own, or the one a client set since.
    pub metaphor: SlidingMetaphor,
}

/// `{"type": "status"}`: the server as [`ServerStatus`] describes it.
pub fn status(status: &ServerStatus) -> Message {
    let mut value = json!(status);
    value["type"] = json!("status");
    text(&value)
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
    /// The user's index, as the scene's hands name it.
    user: u32,
    frame: u64,
    /// The answered tracker sample's timestamp (ns since the Unix epoch), for the latency.
    tracker_ns: u64,
    published_ns: u64,
    tracked: bool,
    /// The frame answers an input sample (tracker, glove or hand joints): the hand has been seen.
    answered: bool,
    root: &'a WirePose,
    /// Each segment's verified world pose, in the order of the scene's segment meshes.
    segments: &'a [WirePose],
    grasp: &'static str,
    /// Bit per [`vas_client::HandSegment`]: that segment touches a part.
    touching: u32,
}

/// One pair of the newest clearance frame in a frame message.
#[derive(Debug, Serialize)]
struct PairView<'a> {
    part: u32,
    other: u32,
    /// Metres.
    distance: f64,
    /// The closest points on `part` and on `other`, in the world.
    point: &'a [f64; 3],
    other_point: &'a [f64; 3],
    /// Measured on an earlier frame than `frame`.
    stale: bool,
}

/// The newest clearance frame in a frame message: the pairs closer than the threshold.
#[derive(Debug, Serialize)]
struct ClearanceView<'a> {
    /// The parts frame measured.
    frame: u64,
    /// Metres: a page colours each pair by its distance over this.
    threshold: f64,
    pairs: Vec<PairView<'a>>,
}

/// A frame message: serialised as is, in this field order. A page's link reads `published_ns`
/// from the start of the text (`{"type":"frame","published_ns":`) without parsing the rest.
#[derive(Debug, Serialize)]
struct FrameView<'a> {
    #[serde(rename = "type")]
    kind: &'static str,
    /// When the server published the newest state in the message (ns since the Unix epoch).
    published_ns: u64,
    scene: u64,
    parts: Option<PartsView<'a>>,
    hands: Vec<HandView<'a>>,
    clearance: Option<ClearanceView<'a>>,
}

/// `{"type": "frame"}`: the newest parts frame, each hand's newest frame and the newest
/// clearance frame, for the scene numbered `scene`, with the newest of the parts' and hands'
/// publish stamps first.
pub fn frame<'a>(
    scene: u64,
    parts: Option<&'a PartsFrame>,
    hands: impl IntoIterator<Item = &'a HandFrame>,
    clearance: Option<&'a ClearanceFrame>,
) -> Message {
    let parts = parts.map(|frame| PartsView {
        frame: frame.header.frame,
        tracker_ns: frame.header.tracker.timestamp_ns,
        published_ns: frame.header.timestamp_ns,
        parts: frame.parts.iter().map(part_view).collect(),
    });
    let hands: Vec<HandView> = hands.into_iter().map(hand_view).collect();
    let published_ns = hands
        .iter()
        .map(|hand| hand.published_ns)
        .chain(parts.as_ref().map(|parts| parts.published_ns))
        .max()
        .unwrap_or(0);
    text(&FrameView {
        kind: "frame",
        published_ns,
        scene,
        parts,
        hands,
        clearance: clearance.map(|frame| ClearanceView {
            frame: frame.frame,
            threshold: frame.threshold,
            pairs: frame.listed().iter().map(pair_view).collect(),
        }),
    })
}

fn pair_view(pair: &ClearancePair) -> PairView<'_> {
    PairView {
        part: pair.part,
        other: pair.other,
        distance: pair.distance,
        point: &pair.point,
        other_point: &pair.other_point,
        stale: pair.is_stale(),
    }
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
        user: hand.user,
        frame: hand.frame,
        tracker_ns: hand.tracker.timestamp_ns,
        published_ns: hand.timestamp_ns,
        tracked: hand.tracked != 0,
        answered: [hand.tracker, hand.glove, hand.joints]
            .iter()
            .any(|stamp| stamp.seq > 0),
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

#[cfg(test)]
mod tests {
    use super::*;
    use vas_client::PartsFrameHeader;

    #[test]
    fn a_frame_message_starts_with_its_newest_publish_stamp() {
        let parts = PartsFrame {
            header: PartsFrameHeader {
                timestamp_ns: 1_700_000_000_000_000_200,
                ..PartsFrameHeader::default()
            },
            parts: Vec::new(),
        };
        let hand = HandFrame {
            timestamp_ns: 1_700_000_000_000_000_100,
            ..HandFrame::default()
        };
        let mut clearance = ClearanceFrame {
            frame: 9,
            threshold: 0.005,
            pair_count: 1,
            ..ClearanceFrame::default()
        };
        clearance.pairs[0] = ClearancePair {
            part: 1,
            distance: 0.0008,
            point: [0.1, 0.0, 0.0],
            flags: vas_client::CLEARANCE_STALE,
            ..ClearancePair::default()
        };
        let Message::Text(text) = frame(3, Some(&parts), [&hand], Some(&clearance)) else {
            panic!("a frame is a text message");
        };
        let text = text.as_str();
        assert!(
            text.starts_with(r#"{"type":"frame","published_ns":1700000000000000200,"scene":3,"#),
            "{text}"
        );
        let value: serde_json::Value = serde_json::from_str(text).expect("JSON");
        assert_eq!(
            value["hands"][0]["published_ns"],
            1_700_000_000_000_000_100_u64
        );
        assert_eq!(value["hands"][0]["answered"], false, "no sample answered");
        assert_eq!(
            value["parts"]["published_ns"],
            1_700_000_000_000_000_200_u64
        );
        let pairs = &value["clearance"]["pairs"];
        assert_eq!(pairs.as_array().map(Vec::len), Some(1), "listed pairs only");
        assert_eq!(
            (&pairs[0]["distance"], &pairs[0]["stale"]),
            (&serde_json::json!(0.0008), &serde_json::json!(true))
        );
    }

    #[test]
    fn a_hand_frame_that_answers_a_sample_says_so() {
        let hand = HandFrame {
            glove: vas_client::InputStamp {
                seq: 3,
                timestamp_ns: 1,
            },
            ..HandFrame::default()
        };
        let Message::Text(text) = frame(1, None, [&hand], None) else {
            panic!("a frame is a text message");
        };
        let value: serde_json::Value = serde_json::from_str(text.as_str()).expect("JSON");
        assert_eq!(value["hands"][0]["answered"], true);
    }

    #[test]
    fn a_status_names_the_served_scene_and_the_metaphor_in_use() {
        let status = ServerStatus {
            server: true,
            scene_names: vec!["a".into(), "b".into()],
            scene: Some("b".into()),
            metaphor: SlidingMetaphor::SpiralSpring,
        };
        let Message::Text(text) = super::status(&status) else {
            panic!("a status is a text message");
        };
        let value: serde_json::Value = serde_json::from_str(text.as_str()).expect("JSON");
        assert_eq!(
            value,
            serde_json::json!({
                "type": "status", "server": true, "scene_names": ["a", "b"], "scene": "b",
                "metaphor": "spiral-spring",
            })
        );
    }
}
