//! The changes that travel down the loops between frames: a restart on a scene (new, or the same
//! one for a reset) and a change of the sliding metaphor.

use std::sync::Arc;

use nalgebra::Isometry3;
use vas_protocol::FLEX_COUNT;

use super::hand_bodies::HandBodies;
use crate::grasping::{GraspingHand, HandPose};
use crate::scene::Scene;
use crate::sliding::SlidingMetaphor;

/// A change of the simulation, sent down the loops between frames.
pub enum Change {
    /// Start over on a scene (a new one, or the same one for a reset): every loop rebuilds its
    /// state from it and takes the parts of the hand it needs.
    Restart(Box<Restart>),
    /// Held and later grasped parts follow the hand by this metaphor.
    SlidingMetaphor(SlidingMetaphor),
}

/// What a restart carries.
pub struct Restart {
    /// The scene.
    pub scene: Arc<Scene>,
    /// The grasping hands, in the scene's order, built and validated by the I/O thread; the
    /// grasping loop takes them.
    pub hands: Vec<GraspingHand>,
    /// The same hands' kinematics and segment meshes, for the collision loop.
    pub hand_bodies: Vec<HandBodies>,
    /// Numbers the restarts, so that feedback from before one is ignored after it.
    pub epoch: u64,
}

/// Why a scene's hand could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum HandSetupError {
    /// A segment's collision mesh could not be built.
    #[error("a hand model's segment meshes cannot be built: {0}")]
    Segments(String),
}

impl Restart {
    /// Everything the loops need to start over on `scene`: the hand models it names (loaded and
    /// validated with it) built, parked flat at the origin.
    pub fn new(scene: Arc<Scene>, epoch: u64) -> Result<Restart, HandSetupError> {
        let params = scene.params.grasp();
        let parked = HandPose {
            root: Isometry3::identity(),
            flex: [0.0; FLEX_COUNT],
        };
        let mut hands = Vec::with_capacity(scene.hands.len());
        let mut hand_bodies = Vec::with_capacity(scene.hands.len());
        for scene_hand in &scene.hands {
            let model = Arc::clone(&scene_hand.model);
            let hand = GraspingHand::new(Arc::clone(&model), params, parked)
                .map_err(|error| HandSetupError::Segments(error.to_string()))?;
            hand_bodies.push(HandBodies::of(model, &hand));
            hands.push(hand);
        }
        Ok(Restart {
            scene,
            hands,
            hand_bodies,
            epoch,
        })
    }

    /// The change that carries this restart down the loops.
    pub fn into_change(self) -> Change {
        Change::Restart(Box::new(self))
    }
}

impl std::fmt::Debug for Change {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Change::Restart(restart) => f
                .debug_struct("Restart")
                .field("scene", &restart.scene.name)
                .field("hands", &restart.hands.len())
                .field("epoch", &restart.epoch)
                .finish(),
            Change::SlidingMetaphor(metaphor) => {
                f.debug_tuple("SlidingMetaphor").field(metaphor).finish()
            }
        }
    }
}
