//! Sliding contact (the paper's §3): a grasped part slides along what it touches and never passes
//! through it.
//!
//! * [`machine`]: the ghost, the visible part and the collision copy, driven by the finite state
//!   machine of the paper's Figure 6 under one of three metaphors ([`params::Metaphor`]).
//! * [`bisection`]: contact approximation between the last free and the first colliding pose.
//! * [`contact`]: contact classification from intersecting triangle pairs, with normals found
//!   from the geometry and oriented against the approach.
//! * [`direction`]: the remaining motion projected onto the free space the contacts leave.
//! * [`force`]: the spring-damper wrench a force-feedback device renders.
//! * [`allowance`]: slide-in units, whose parts may interfere up to a configured depth.
//! * [`motion`]: rigid motions of the part's pivot and their interpolation.
//! * [`world`]: the part's collision copy against the obstacles, queried pair by pair.

pub mod allowance;
pub mod bisection;
pub mod contact;
pub mod direction;
pub mod force;
pub mod machine;
pub mod motion;
pub mod params;
pub mod world;

pub use contact::{Contact, ContactKind};
pub use direction::FreeSpace;
pub use force::{ForceModel, ForceParams, Wrench};
pub use machine::{Event, RestReason, SlideMachine, SlideState, SlideStats, SlideWorld};
pub use motion::{Motion, Pose};
pub use params::{Allowance, Metaphor, ParamError, SlideParams};
