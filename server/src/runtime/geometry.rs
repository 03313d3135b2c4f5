//! What `vas/scene/geometry` publishes: the render meshes of a scene's parts (own frame, scale
//! applied) and of its hand's segments (segment frame), so that a renderer never reads the
//! server's files.
//!
//! A scene's meshes are encoded once; a reset sends the same bytes again under a new generation.

use std::sync::Arc;

use vas_protocol::{GeometryHeader, HandGeometry, HandSide, MeshData, SceneGeometry};

use super::frames::Restart;
use crate::geometry::TriMesh;
use crate::grasping::Side;
use crate::scene::Scene;

/// The encoded geometry of the scene being served.
pub(super) struct ServedGeometry {
    /// The scene it was encoded from: a restart on the same scene (a reset) encodes nothing.
    scene: Arc<Scene>,
    header: GeometryHeader,
    bytes: Vec<u8>,
}

impl ServedGeometry {
    /// The geometry of `restart`'s scene and hand, as generation `restart.epoch`.
    pub(super) fn of(restart: &Restart) -> Self {
        let hands = restart.hand_bodies.iter().map(|bodies| HandGeometry {
            side: wire_side(bodies.model.side()),
            model: bodies.model.name().to_owned(),
            segments: bodies
                .model
                .segments()
                .iter()
                .zip(&bodies.meshes)
                .map(|(segment, mesh)| mesh_data(&segment.name, mesh))
                .collect(),
        });
        let geometry = SceneGeometry {
            generation: restart.epoch,
            parts: (restart.scene.parts.iter())
                .map(|part| mesh_data(&part.name, &part.mesh))
                .collect(),
            hands: hands.collect(),
        };
        let (header, bytes) = geometry.encode();
        Self {
            scene: Arc::clone(&restart.scene),
            header,
            bytes,
        }
    }

    /// Moves on to `restart`: re-encodes only when its scene is another one.
    pub(super) fn restart(&mut self, restart: &Restart) {
        if Arc::ptr_eq(&self.scene, &restart.scene) {
            self.header.generation = restart.epoch;
        } else {
            *self = Self::of(restart);
        }
    }

    /// The sample to publish.
    pub(super) fn sample(&self) -> (GeometryHeader, &[u8]) {
        (self.header, &self.bytes)
    }
}

/// A hand model's side as the wire names it.
pub(super) fn wire_side(side: Side) -> HandSide {
    match side {
        Side::Right => HandSide::Right,
        Side::Left => HandSide::Left,
    }
}

fn mesh_data(name: &str, mesh: &TriMesh) -> MeshData {
    MeshData {
        name: name.to_owned(),
        // Render precision: f32 keeps a micrometre within ten metres of the part's origin.
        positions: (mesh.vertices().iter())
            .map(|v| v.coords.map(|c| c as f32).into())
            .collect(),
        normals: Vec::new(),
        triangles: mesh.triangles().to_vec(),
    }
}
