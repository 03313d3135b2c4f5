//! Natural grasping (the paper's section 4): a hand model driven by a tracker and a data glove
//! whose fingers close around parts without entering them, and that knows when it holds one.
//!
//! * [`model`]: the hand model from a config (`configs/hands/`): kinematic tree, flex mapping,
//!   joint limits, collision shapes and semantics; forward kinematics; mirroring.
//! * `flex`: glove samples clamped to the joint limits, bad values refused and counted.
//! * `segment_mesh`: the segments' closed collision meshes.
//! * [`clasp`]: the clasp minimisation on a collision copy, with the paper's touch flags, generic
//!   over the collision test.
//! * [`collider`]: the hand's segments against the parts near it (DOP-trees), and contacts.
//! * [`analysis`]: the grasp class from what touches a part, and how.
//! * [`push`]: how far a hand's motion into a part it pushes would carry the part.
//! * [`hand`]: one hand's grasping loop state: clasp, contacts, analysis, grasp and release with
//!   hysteresis, cart motion, the hand-over events.
//! * [`retarget`]: tracked OpenXR or WebXR hand joints onto the model: root and flex values,
//!   per-user calibration, fingertip distances, captures.
//!
//! # Model
//!
//! `configs/hands/right.toml` is a 22-DOF right hand in metres and degrees: a palm and five
//! digits of three segments each. A segment has a joint (origin, base rotation, revolute degrees
//! of freedom whose angles are linear combinations of the 22 flex values in CyberGlove order), a
//! collision shape (the convex hull of spheres around 2 or 4 centres) and its semantics (palm /
//! thumb / finger, inner / middle / outer). `left.toml` is `mirror_of = "right.toml"`: the mirror
//! image in x = 0, flex values keeping their meaning. Loading validates everything and refuses
//! with the file, the key and the reason. Segment meshes are hulls refined so that no edge exceeds
//! 8 mm: long rim triangles have loose bounding volumes, which make near misses costly.
//!
//! # Retargeting
//!
//! A hand-tracking sample (OpenXR's 26 joints, or WebXR's 25 with the palm derived) is validated
//! (non-finite joints, non-unit quaternions, impossible bones, knuckles in the wrong order are
//! refused), then becomes a root (the wrist joint turned into the model's frame) and a flex
//! vector: each joint's angles turn its segment onto the measured bone, the flex values are the
//! least-squares combination of those angles, and at most three Levenberg-Marquardt steps bring
//! the fingertips to the tracked tips. `calibrated` resizes the model to one sample; `synthesize`
//! gives the joints a tracker would report for a posed model (the round-trip tests use it). The
//! wrist angles cannot be seen and stay at rest.
//!
//! # Clasp minimisation
//!
//! The 23 variables (root and flex values) are interpolated between the last valid and the
//! target configuration. Each step tries one configuration; a variable is colliding if a segment
//! depending on it collides; colliding variables lower their invalid end, the others raise their
//! valid end (except where a segment depends on both), so the configuration of valid ends is
//! always free and the result collision-free by construction. A variable is fixed when its
//! interval is narrower than its tolerance; a step cap fixes the rest. Beyond the paper:
//!
//! * two stages, the root first, then the flex values (interpolated together, the root would be
//!   blamed for every finger's collision and a held part could not be carried);
//! * segments checked palm first, then from the fingertips in, skipping a segment whose moving
//!   variables are all blamed already (near misses are the costliest queries);
//! * a motion cap per minimisation, so a tracker or glove jump cannot carry a segment through a
//!   thin part; the hand catches up over a few frames.
//!
//! Touch flags follow the paper; variables fixed in the same step are taken fingertips first, so
//! a fingertip pressing on a part is marked before its parents clear its flag.
//!
//! # Contacts, analysis, grasp and release
//!
//! A segment touches a part when its contact probe (the segment grown by 1 mm) cuts the part and
//! it was marked touching this frame or touched the part in the last one (so a resting or carrying
//! hand keeps its contacts). The probe gives thinned contact points and the segment's outward
//! normal there (palmar, dorsal, lateral, tip). The analysis then decides, in this order: a dorsal
//! contact is a push; a palm under the part holding its centre of mass is gravity; one segment is
//! a push; without the palm, a thumb opposing fingers is a precision grasp (tip pinch, key,
//! three-jaw chuck) or a 3-point pinch, two neighbouring fingers are a cigarette grasp; with the
//! palm, a segment opposing it is a power grasp. A part is grasped after a few consecutive holding
//! frames and released after more without; the held part is analysed with relaxed thresholds, so
//! a grasp near a threshold does not flicker. While the cart moves there is no clasping: the hand
//! follows its root if that is free, else waits (`AwaitingFreeHand`). The visible hand is never
//! at a colliding pose.
//!
//! # Hand-over to sliding, two hands
//!
//! [`GraspingHand::step`] emits [`GraspEvent::Grasp`] and [`GraspEvent::Release`]; while a part is
//! held, its pose in the hand is `root · hand_to_part`, the pose the sliding module's ghost takes.
//! The clasp treats the held part at that pose, so moving the hand never collides with it. The
//! `simulation` layer connects the two (creating the slide machine on the grasp, feeding it every
//! frame, moving the visible hand with the visible part). A scene may have a left and a right hand;
//! a part is held by one hand at a time: a hand grasping the part the other holds makes the other
//! let go ([`GraspingHand::let_go`]). A released part is not grasped again by the same hand until no
//! segment touches it. A hand whose tracking is lost stays where it was and keeps what it holds;
//! untracked past `params.tracking.grace`, it lets go.
//!
//! # Tests
//!
//! `cargo test -p vas-server grasping` and `server/tests/grasping/`: scripted glove and tracker
//! trajectories (from `vas-testkit`) checked every frame with parry (power, precision, push,
//! gravity, cart, a hand walked into a wall, both hands); clasp properties on random hands among
//! random balls; analysis rules, hysteresis, refused input and config errors. Time per clasp and
//! per frame: benchmark B6 in `BENCHMARKS.md`.

pub mod analysis;
pub mod clasp;
pub mod collider;
pub(crate) mod flex;
pub mod hand;
pub mod model;
pub mod push;
pub mod retarget;
pub(crate) mod segment_mesh;

pub use analysis::{GraspClass, PrecisionKind};
pub use clasp::{ClaspParamError, ClaspParams, HandPose};
pub use collider::{Obstacle, PartGeometry, PartId};
pub use hand::{
    GraspEvent, GraspParams, GraspingHand, HandInput, HandMode, HandStep, SegmentContact,
};
pub use model::{
    FLEX_COUNT, Finger, FlexVector, HandConfigError, HandModel, JointLevel, ROOT_VARIABLE,
    SegmentId, VARIABLE_COUNT, VariableSet,
};
pub use push::Push;
