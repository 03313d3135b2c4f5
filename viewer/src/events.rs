//! Events as a page is sent them: in words, with where a contact happened.

use axum::extract::ws::Message;
use serde_json::json;
use vas_client::words::{event_name, hand_name};
use vas_client::{EventKind, SceneWords, SimEvent};

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
        "text": words.event(event),
        "frame": event.frame,
        "hand": hand_name(event.hand),
        "part": event.part,
        "other": event.other,
        "point": contact.then_some(event.point),
        "normal": contact.then_some(event.normal),
    });
    Message::Text(value.to_string().into())
}
