//! What `vas/scene/geometry` publishes: the render meshes of a scene's parts (own frame, scale
//! applied) and of its hand's segments (segment frame), so that a renderer never reads the
//! server's files.
//!
//! A scene's meshes are converted to render precision once, the parts in parallel; each
//! publication encodes them straight into its shared-memory sample (see
//! [`Ports::publish_geometry`](super::ports::Ports::publish_geometry)), and a reset publishes the
//! same meshes under a new generation.

use std::sync::Arc;

use rayon::prelude::*;
use vas_protocol::{HandGeometry, MeshData, SceneGeometry};

use crate::geometry::TriMesh;
use crate::scene::Scene;
use crate::simulation::restart::Restart;

/// The render geometry of the scene being served.
pub(super) struct ServedGeometry {
    /// The scene it was made from: a restart on the same scene (a reset) converts nothing.
    scene: Arc<Scene>,
    geometry: SceneGeometry,
}

impl ServedGeometry {
    /// The geometry of `restart`'s scene and hand, as generation `restart.epoch`.
    pub(super) fn of(restart: &Restart) -> Self {
        let owners = restart.scene.hands.iter().map(|hand| hand.user);
        let hands = (restart.hand_bodies.iter().zip(owners)).map(|(bodies, user)| HandGeometry {
            user,
            side: bodies.model.side(),
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
            parts: (restart.scene.parts.par_iter())
                .map(|part| mesh_data(&part.name, &part.mesh))
                .collect(),
            hands: hands.collect(),
        };
        Self {
            scene: Arc::clone(&restart.scene),
            geometry,
        }
    }

    /// Moves on to `restart`: converts the meshes again only when its scene is another one.
    pub(super) fn restart(&mut self, restart: &Restart) {
        if Arc::ptr_eq(&self.scene, &restart.scene) {
            self.geometry.generation = restart.epoch;
        } else {
            *self = Self::of(restart);
        }
    }

    /// What to publish.
    pub(super) fn geometry(&self) -> &SceneGeometry {
        &self.geometry
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
