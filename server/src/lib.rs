//! vas-server: the simulation library behind the `vas-server` binary.
//!
//! The modules are the paper's, layered so that data flows one way:
//! `geometry` ← `collision` ← `sliding`, `grasping` ← `scene` ← `simulation` ← `runtime` ←
//! `replay`, `report`. Only `runtime` knows about threads and IPC; every other module is a plain
//! library.
//!
//! * [`geometry`]: triangle meshes, loading OBJ, STL, PLY and glTF/GLB, convex hulls, shapes.
//! * [`collision`]: the DOP-tree, the separating-plane pre-check and the collision pipeline.
//! * [`sliding`]: a grasped part sliding along what it touches.
//! * [`grasping`]: the hand model, the clasp minimisation and the grasp analysis.
//! * [`scene`]: scene configs, the parts and their shared DOP-trees.
//! * [`simulation`]: one step of the whole simulation as plain state.
//! * [`runtime`]: the server's threads, loops and iceoryx2 ports ([`runtime::run`]).
//! * [`replay`]: input samples stepped in-process, one frame per sample, as in lockstep.
//! * [`report`]: a session's clearance, contact and clash report per part pair.
//!
//! A renderer does not link this crate: it links `vas-client` and draws from the wire (the
//! geometry service carries every mesh). `ARCHITECTURE.md` at the repository root shows how the
//! crates, modules and threads fit together.

pub mod collision;
pub mod geometry;
pub mod grasping;
pub mod replay;
pub mod report;
pub mod runtime;
pub mod scene;
pub mod simulation;
pub mod sliding;

#[cfg(test)]
mod layering;
