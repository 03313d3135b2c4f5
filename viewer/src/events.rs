//! Events as a page is sent them: in words, with where a contact happened.

use axum::extract::ws::Message;
use serde_json::json;
use vas_client::words::{event_name, hand_name};
use vas_client::{EventKind, HAND_PART_ID, SceneWords, SimEvent};

/// The event in words, naming the hand where it is about one that the words leave unnamed (a
/// page may show two): "right hand: grasp peg (power) at sample 44". The rest of the sentence
/// is `vas-client`'s, so that its sample number reads as `vas-client replay` prints it; in a
/// scene of several users it names the user's hand itself ("anna's right hand grasps ...").
fn text(event: &SimEvent, words: &SceneWords) -> String {
    if words.names_users() {
        return words.event(event);
    }
    let about_a_hand = match EventKind::try_from(event.kind) {
        Ok(EventKind::Grasp | EventKind::Release) => true,
        Ok(EventKind::ContactBegin | EventKind::ContactEnd) => {
            event.part == HAND_PART_ID || event.other == HAND_PART_ID
        }
        _ => false,
    };
    let sentence = words.event(event);
    if about_a_hand {
        format!("{} hand: {sentence}", hand_name(event.hand))
    } else {
        sentence
    }
}

/// `{"type": "event"}` for `event` of the scene numbered `scene_version`.
pub fn message(scene_version: u64, event: &SimEvent, words: &SceneWords) -> Message {
    let contact = matches!(
        EventKind::try_from(event.kind),
        Ok(EventKind::ContactBegin | EventKind::ContactEnd)
    );
    let value = json!({
        "type": "event",
        "scene": scene_version,
        "kind": event_name(event.kind),
        "text": text(event, words),
        "frame": event.frame,
        "hand": hand_name(event.hand),
        "user": words.user(event.user),
        "part": event.part,
        "other": event.other,
        "point": contact.then_some(event.point),
        "normal": contact.then_some(event.normal),
    });
    Message::Text(value.to_string().into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use vas_client::{GraspType, HandSide, InputStamp};

    fn event(kind: EventKind, part: u32, other: u32) -> SimEvent {
        SimEvent {
            frame: 3,
            tracker: InputStamp::default(),
            glove: InputStamp {
                seq: 44,
                timestamp_ns: 1,
            },
            joints: InputStamp::default(),
            timestamp_ns: 5,
            kind: kind as u32,
            grasp_type: GraspType::Power as u32,
            part,
            other,
            hand: HandSide::Left as u32,
            segment: 0,
            point: [0.0; 3],
            normal: [0.0; 3],
            other_point: [0.0; 3],
            distance: 0.0,
            user: 0,
            reserved: 0,
        }
    }

    #[test]
    fn events_about_a_hand_name_it() {
        let words = SceneWords::default();
        assert_eq!(
            text(&event(EventKind::Grasp, 1, HAND_PART_ID), &words),
            "left hand: grasp part 1 (power) at sample 44"
        );
        assert_eq!(
            text(&event(EventKind::ContactBegin, 1, HAND_PART_ID), &words),
            "left hand: contact begin part 1 – hand at sample 44"
        );
        assert_eq!(
            text(&event(EventKind::ContactBegin, 1, 2), &words),
            "contact begin part 1 – part 2 at sample 44"
        );
    }
}
