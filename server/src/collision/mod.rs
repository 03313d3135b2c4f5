//! Collision detection: the pipeline of filters of PAPER §2 and its stages.

pub mod broad_phase;
pub mod interest;
pub mod pipeline;
pub mod separating_plane;
