//! One step of the simulation as plain state: what the runtime's loops drive frame by frame and
//! what an offline replay drives in sequence.
//!
//! A frame passes three stages, each a loop's work in the server: `grasp_stage` steps the
//! hands against the parts, `slide_stage` slides the parts they hold, and [`verify`] checks the
//! candidate frame scene-wide so that nothing leaves at a colliding pose; [`clearance`] then
//! watches the verified poses for part pairs closer than the scene's threshold, beside the
//! loops; the sliding stage also pushes and settles parts no hand holds (`unheld`). [`frames`]
//! are what the stages hand each other, [`restart`] the changes between frames. [`interaction`]
//! runs the first two stages in sequence, as the loops do in lockstep.
//!
//! No threads and no ports here: those are the runtime's.

pub mod clearance;
pub mod filter;
pub mod frames;
pub(crate) mod grasp_stage;
pub mod hand_bodies;
pub mod interaction;
pub mod restart;
pub(crate) mod slide_stage;
mod unheld;
pub mod verify;
