//! Natural grasping (the paper's section 4): a hand model driven by a tracker and a data glove
//! whose fingers close around parts without entering them, and that knows when it holds one.
//!
//! * [`model`]: the hand model from a config: kinematic tree, flex mapping, joint limits,
//!   collision shapes and semantics; forward kinematics.
//! * [`flex`]: glove samples clamped to the joint limits, bad values refused and counted.
//! * [`segment_mesh`]: the segments' closed collision meshes.
//! * [`clasp`]: the clasp minimisation on a collision copy, with the paper's touch flags, generic
//!   over the collision test.
//! * [`collider`]: the hand's segments against the parts near it (DOP-trees), and contacts.
//! * [`analysis`]: the grasp type from what touches a part, and how.
//! * [`hand`]: one hand's grasping loop state: clasp, contacts, analysis, grasp and release with
//!   hysteresis, cart motion, the hand-over events.
//! * [`retarget`]: tracked OpenXR or WebXR hand joints onto the model: root and flex values,
//!   per-user calibration, fingertip error, captures.

pub mod analysis;
pub mod clasp;
pub mod collider;
pub mod flex;
pub mod hand;
pub mod model;
pub mod retarget;
pub mod segment_mesh;

pub use analysis::{GraspType, PrecisionKind};
pub use clasp::{ClaspParamError, ClaspParams, HandPose};
pub use collider::{Obstacle, PartGeometry, PartId};
pub use hand::{
    GraspEvent, GraspParams, GraspingHand, HandFrame, HandInput, HandMode, SegmentContact,
};
pub use model::{
    FLEX_COUNT, Finger, FlexVector, HandConfigError, HandModel, JointLevel, ROOT_VARIABLE,
    SegmentId, Side, VARIABLE_COUNT, VariableSet,
};
