//! One hand's input state: whose hand it is, and the latest targets of the streams that drive
//! it.

use nalgebra::Isometry3;
use vas_protocol::{FLEX_COUNT, GloveTarget, HandSide, TrackerTarget};

use crate::grasping::{HandInput, HandModel};
use crate::runtime::hand_joints::JointsHand;
use crate::scene::TrackingParams;
use crate::simulation::filter::StreamFilter;

/// One hand of the scene as its input streams drive it.
#[derive(Debug)]
pub(super) struct HandInputs {
    /// The user's index in the scene.
    pub(super) user: u32,
    /// Which of the user's hands.
    pub(super) side: HandSide,
    /// The latest accepted tracker sample for this hand, its root smoothed.
    pub(super) tracker: Option<TrackerTarget>,
    /// The filter of the tracker's hand root.
    pub(super) tracker_filter: StreamFilter<0>,
    /// The latest accepted glove sample for this hand.
    pub(super) glove: Option<GloveTarget>,
    /// The hand as hand-joints samples drive it; `None` without a model, or for a model the
    /// retargeting cannot take.
    pub(super) joints: Option<JointsHand>,
}

impl HandInputs {
    /// The hand of `user` whose model is `model`.
    pub(super) fn of_model(user: u32, model: &HandModel, tracking: &TrackingParams) -> Self {
        HandInputs {
            joints: JointsHand::new(model, tracking),
            ..HandInputs::without_model(user, model.side(), tracking)
        }
    }

    /// The hand of `user` and `side` in a scene without a hand model: tracker and glove alone
    /// place it.
    pub(super) fn without_model(user: u32, side: HandSide, tracking: &TrackingParams) -> Self {
        HandInputs {
            user,
            side,
            tracker: None,
            tracker_filter: StreamFilter::new(tracking),
            glove: None,
            joints: None,
        }
    }

    /// The hand as its tracker and glove drive it, on `cart` (at the cart's origin and flat
    /// before their first samples).
    pub(super) fn glove_driven(&self, cart: Isometry3<f64>) -> HandInput {
        HandInput {
            cart,
            tracker: (self.tracker).map_or_else(Isometry3::identity, |target| target.hand),
            flex: self.glove.map_or([0.0; FLEX_COUNT], |target| target.flex),
        }
    }
}
