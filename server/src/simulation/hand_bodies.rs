//! A hand's kinematics and segment meshes as the collision loop's verifier needs them.

use std::sync::Arc;

use crate::collision::DopTree;
use crate::geometry::TriMesh;
use crate::grasping::{GraspingHand, HandModel};

/// A hand's kinematics and segment meshes, for the verifier.
#[derive(Clone)]
pub struct HandBodies {
    /// The kinematic model.
    pub model: Arc<HandModel>,
    /// Each segment's collision mesh, in the segment's frame, in segment order.
    pub meshes: Vec<TriMesh>,
    /// The DOP-tree over each mesh, with the scene's orientations (the grasping hand's own).
    pub trees: Vec<DopTree>,
}

impl HandBodies {
    /// The segments of `hand` (whose kinematics are `model`), sharing its meshes' trees.
    pub fn of(model: Arc<HandModel>, hand: &GraspingHand) -> HandBodies {
        let geometry = hand.geometry();
        let segments = 0..model.segments().len();
        HandBodies {
            meshes: segments
                .clone()
                .map(|segment| geometry.mesh(segment).clone())
                .collect(),
            trees: segments
                .map(|segment| geometry.tree(segment).clone())
                .collect(),
            model,
        }
    }
}
