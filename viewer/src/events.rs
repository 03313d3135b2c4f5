//! Events as a page is sent them: in words, with where they happened.

use axum::extract::ws::Message;
use serde_json::json;
use vas_client::{EventKind, GraspType, HAND_PART_ID, SceneInfo, SimEvent};

/// `{"type": "event"}` for `event` of the scene numbered `scene_version`.
pub fn message(scene_version: u64, event: &SimEvent, scene: &SceneInfo) -> Message {
    let kind = EventKind::try_from(event.kind).ok();
    let value = json!({
        "type": "event",
        "scene": scene_version,
        "kind": kind,
        "text": describe(event, scene),
        "frame": event.frame,
        "part": event.part,
        "other": event.other,
    });
    Message::Text(value.to_string().into())
}

fn describe(event: &SimEvent, scene: &SceneInfo) -> String {
    let name = |id: u32| {
        if id == HAND_PART_ID {
            "hand".to_owned()
        } else {
            scene
                .parts
                .get(id as usize)
                .map_or_else(|| format!("part {id}"), |part| part.name.clone())
        }
    };
    match EventKind::try_from(event.kind) {
        Ok(EventKind::Grasp) => format!(
            "grasp {} ({:?}) at sample {}",
            name(event.part),
            GraspType::try_from(event.grasp_type).unwrap_or(GraspType::None),
            event.tracker.seq
        ),
        Ok(EventKind::Release) => format!("release {}", name(event.part)),
        Ok(EventKind::ContactBegin) => {
            format!("contact begin {} – {}", name(event.part), name(event.other))
        }
        Ok(EventKind::ContactEnd) => {
            format!("contact end {} – {}", name(event.part), name(event.other))
        }
        Err(_) => format!("event {}", event.kind),
    }
}
