//! vas-server: the simulation library behind the `vas-server` binary.
//!
//! The modules are the paper's, layered so that data flows one way:
//! `geometry` ← `collision` ← `sliding`, `grasping` ← `scene` ← `simulation` ← `runtime`.
//! Only `runtime` knows about threads and IPC; every other module is a plain library.

pub mod collision;
pub mod geometry;
pub mod grasping;
pub mod runtime;
pub mod scene;
pub mod simulation;
pub mod sliding;

#[cfg(test)]
mod layering;
