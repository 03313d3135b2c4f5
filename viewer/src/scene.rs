//! The scene message a page is sent when it connects and whenever the scene changes.

use axum::extract::ws::Message;
use serde_json::json;
use vas_client::SceneInfo;

use crate::hub::SceneMessages;

/// The scene numbered `version`, as pages are sent it.
pub fn messages(version: u64, scene: &SceneInfo) -> SceneMessages {
    let parts: Vec<_> = scene
        .parts
        .iter()
        .map(|part| json!({ "id": part.id, "name": part.name, "movable": part.movable, "mesh": null }))
        .collect();
    let description = json!({
        "type": "scene", "version": version, "name": scene.name, "parts": parts, "hands": [],
        "meshes": 0,
    });
    SceneMessages {
        description: Some(Message::Text(description.to_string().into())),
        meshes: Vec::new(),
    }
}
