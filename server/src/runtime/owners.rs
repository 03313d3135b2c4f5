//! Whose hand an output names: each of the scene's hands belongs to a user and a side, which
//! the hand frames, events and force frames that the I/O thread publishes carry.

use std::sync::Arc;

use vas_protocol::HandSide;

use crate::scene::Scene;

/// Whose hand an output names: the user's index and the side.
#[derive(Debug, Clone, Copy)]
pub(super) struct HandOwner {
    pub(super) user: u32,
    pub(super) side: HandSide,
}

impl Default for HandOwner {
    /// The first user's right hand: the hand a scene without hand models tracks.
    fn default() -> Self {
        HandOwner {
            user: 0,
            side: HandSide::Right,
        }
    }
}

/// The user and side of each of `scene`'s hands, in its order; the first user's right hand for
/// a scene without a hand model (its tracked hand).
pub(super) fn hand_owners(scene: &Scene) -> Arc<[HandOwner]> {
    if scene.hands.is_empty() {
        return Arc::new([HandOwner::default()]);
    }
    (scene.hands.iter())
        .map(|hand| HandOwner {
            user: hand.user,
            side: hand.model.side(),
        })
        .collect()
}
