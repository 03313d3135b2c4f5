//! vas client library: what a renderer (or any tool) links to talk to a vas server.
//!
//! [`Client`] connects to a server's services on an iceoryx2 prefix, sends tracker, glove and
//! hand-joints samples, keeps the latest parts frame and each hand's latest frame, waits for new frames on a WaitSet, and asks
//! the control service for scene information; its [`Roles`] say which of these it does, so that
//! it holds only the ports it uses (a renderer takes [`Roles::RENDER`]). [`InputTap`] listens to the input streams (what
//! `vas-client record` writes), and [`recording`] is the JSON Lines recording format.
//!
//! ```no_run
//! use std::time::Duration;
//! use vas_client::{Client, Roles, Wake};
//!
//! # fn main() -> Result<(), vas_client::ClientError> {
//! let mut client = Client::builder().roles(Roles::RENDER).connect()?;
//! let scene = client.scene_info(Duration::from_secs(2))?;
//! println!("scene {} with {} parts", scene.name, scene.parts.len());
//! loop {
//!     if client.wait(Duration::from_millis(100))? == Wake::Ready {
//!         client.poll()?;
//!         // The meshes come from the geometry service (a new scene brings a new generation).
//!         let (Some(geometry), Some(frame)) = (client.geometry(), client.latest_parts()) else {
//!             continue;
//!         };
//!         for part in &frame.parts {
//!             let Some(mesh) = geometry.parts.get(part.id as usize) else { continue };
//!             // draw mesh.positions and mesh.triangles at part.position, part.rotation
//!             let _ = (mesh, part.position, part.rotation);
//!         }
//!     }
//! }
//! # }
//! ```

mod client;
mod error;
pub mod latency;
pub mod recording;
mod tap;
mod wait;
pub mod words;

pub use client::{
    Client, ClientBuilder, Frame, HandInfo, PartInfo, PartsFrame, Received, Roles, SceneInfo,
};
pub use error::ClientError;
pub use tap::InputTap;
pub use wait::Wake;
pub use words::SceneWords;

/// The wire types, so that a renderer or input sender needs this crate only; the ones such a
/// program names most are re-exported below as well.
pub use vas_protocol as protocol;
pub use vas_protocol::{
    CLEARANCE_STALE, ClearanceFrame, ClearancePair, ControlStatus, EventKind, FLEX_COUNT,
    FLEX_JOINT_NAMES, FLEX_LIMITS_RAD, ForceFrame, GloveSample, GraspType, HAND_JOINT_COUNT,
    HAND_PART_ID, HAND_SEGMENT_COUNT, HandFrame, HandGeometry, HandJointsSample, HandSegment,
    HandSide, InputStamp, InputStats, JointLocation, MeshData, PART_GRASPED, PART_PUSHED,
    PART_SLIDING, PART_TOUCHING, PartState, PartsFrameHeader, SceneGeometry, SimEvent,
    SlidingMetaphor, TrackerSample, WirePose, wall_clock_ns,
};
