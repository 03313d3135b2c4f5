//! The scene as a page is sent it: one JSON description, then one binary message per mesh.
//!
//! Meshes go as binary because they are most of the bytes (a 50 000-triangle part is 1.2 MB
//! this way, several times that as JSON). Each is little-endian and 4-byte aligned, so the page
//! views it in place with typed arrays:
//! `u32 mesh index, u32 vertex count, u32 normal count (0 or the vertex count), u32 triangle
//! count, f32 positions[3 × vertices], f32 normals[3 × normals], u32 indices[3 × triangles]`.

use axum::body::Bytes;
use axum::extract::ws::Message;
use serde_json::json;
use vas_client::{MeshData, SceneGeometry, SceneInfo};

use crate::hub::SceneMessages;

/// The scene numbered `version`: `info` names it, `geometry` is what is drawn.
pub fn messages(version: u64, info: &SceneInfo, geometry: &SceneGeometry) -> SceneMessages {
    let mut meshes = Vec::new();
    let mut add = |mesh: &MeshData| {
        meshes.push(Message::Binary(encode(meshes.len(), mesh)));
        meshes.len() - 1
    };
    let parts: Vec<_> = (geometry.parts.iter().enumerate())
        .map(|(id, mesh)| {
            let movable = info.parts.get(id).is_some_and(|part| part.movable);
            json!({ "id": id, "name": mesh.name, "movable": movable, "mesh": add(mesh) })
        })
        .collect();
    let hands: Vec<_> = (geometry.hands.iter())
        .map(|hand| {
            let segments: Vec<usize> = hand.segments.iter().map(&mut add).collect();
            json!({
                "hand": hand.side as u32, "side": hand.side.name(), "model": hand.model,
                "user": hand.user, "user_name": info.user_name(hand.user), "segments": segments,
            })
        })
        .collect();
    let description = json!({
        "type": "scene", "version": version, "generation": geometry.generation,
        "name": info.name, "parts": parts, "users": info.users, "hands": hands,
        "meshes": meshes.len(),
    });
    SceneMessages {
        description: Some(Message::Text(description.to_string().into())),
        meshes,
    }
}

/// One mesh as a binary message (see the module's documentation).
fn encode(index: usize, mesh: &MeshData) -> Bytes {
    let normals = if mesh.normals.len() == mesh.positions.len() {
        mesh.normals.as_slice()
    } else {
        &[]
    };
    let counts = [
        index,
        mesh.positions.len(),
        normals.len(),
        mesh.triangles.len(),
    ];
    let floats = 3 * (mesh.positions.len() + normals.len());
    let mut bytes = Vec::with_capacity(4 * (counts.len() + floats + 3 * mesh.triangles.len()));
    for count in counts {
        let count = u32::try_from(count).expect("mesh counts fit the wire's u32");
        bytes.extend_from_slice(&count.to_le_bytes());
    }
    for value in mesh.positions.iter().chain(normals).flatten() {
        bytes.extend_from_slice(&value.to_le_bytes());
    }
    for index in mesh.triangles.iter().flatten() {
        bytes.extend_from_slice(&index.to_le_bytes());
    }
    bytes.into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mesh_is_its_counts_then_its_arrays() {
        let mesh = MeshData {
            name: "tri".into(),
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            normals: Vec::new(),
            triangles: vec![[0, 1, 2]],
        };
        let bytes = encode(7, &mesh);
        let words: Vec<u32> = bytes
            .chunks_exact(4)
            .map(|word| u32::from_le_bytes(word.try_into().unwrap()))
            .collect();
        assert_eq!(words[..4], [7, 3, 0, 1]);
        assert_eq!(f32::from_bits(words[4 + 3]), 1.0, "second vertex x");
        assert_eq!(words[4 + 9..], [0, 1, 2]);
    }
}
