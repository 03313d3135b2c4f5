//! The frames a client receives, as copies out of shared memory.

use std::sync::Arc;

use serde::Serialize;
use vas_protocol::{
    ClearanceFrame, ForceFrame, HandFrame, MeshData, PartState, PartsFrameHeader, SceneGeometry,
    SimEvent,
};

/// A parts frame, copied out of shared memory.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PartsFrame {
    /// Frame number, input stamps, publish time and part count.
    #[serde(flatten)]
    pub header: PartsFrameHeader,
    /// Pose and state of every part, indexed by part id.
    pub parts: Vec<PartState>,
}

/// One received output frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
#[expect(
    clippy::large_enum_variant,
    reason = "a hand frame is the common case; boxing it would allocate per frame"
)]
pub enum Frame {
    /// A parts frame.
    Parts(PartsFrame),
    /// A hand frame.
    Hand(HandFrame),
    /// A grasp, release, contact begin or contact end.
    Event(SimEvent),
    /// The force and torque for a force-feedback device.
    Force(ForceFrame),
    /// The part pairs closer than the scene's clearance threshold on a parts frame; in JSON,
    /// the listed pairs only.
    Clearance(#[serde(serialize_with = "clearance_listed")] Box<ClearanceFrame>),
    /// The render meshes of a new scene generation (after a start, load or reset); in JSON, a
    /// summary.
    Geometry(#[serde(serialize_with = "geometry_summary")] Arc<SceneGeometry>),
}

/// A geometry frame in JSON: its generation and what it holds, not every vertex.
fn geometry_summary<S: serde::Serializer>(
    geometry: &Arc<SceneGeometry>,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeStruct;
    let triangles = |mesh: &MeshData| mesh.triangles.len();
    let mut summary = serializer.serialize_struct("Geometry", 4)?;
    summary.serialize_field("generation", &geometry.generation)?;
    summary.serialize_field("parts", &geometry.parts.len())?;
    summary.serialize_field("hands", &geometry.hands.len())?;
    let total: usize = (geometry.parts.iter())
        .chain(geometry.hands.iter().flat_map(|hand| &hand.segments))
        .map(triangles)
        .sum();
    summary.serialize_field("triangles", &total)?;
    summary.end()
}

/// A clearance frame in JSON: its header and the pairs it lists, not its empty slots.
fn clearance_listed<S: serde::Serializer>(
    frame: &ClearanceFrame,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeStruct;
    let mut listed = serializer.serialize_struct("Clearance", 9)?;
    listed.serialize_field("frame", &frame.frame)?;
    listed.serialize_field("tracker", &frame.tracker)?;
    listed.serialize_field("glove", &frame.glove)?;
    listed.serialize_field("joints", &frame.joints)?;
    listed.serialize_field("timestamp_ns", &frame.timestamp_ns)?;
    listed.serialize_field("threshold", &frame.threshold)?;
    listed.serialize_field("pair_count", &frame.pair_count)?;
    listed.serialize_field("more", &frame.more)?;
    listed.serialize_field("pairs", frame.listed())?;
    listed.end()
}

/// How many frames a [`Client::poll`](super::Client::poll) received.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Received {
    /// Parts frames received.
    pub parts: usize,
    /// Hand frames received.
    pub hand: usize,
    /// Events received.
    pub events: usize,
    /// Force frames received.
    pub force: usize,
    /// Clearance frames received.
    pub clearance: usize,
    /// Geometry generations received.
    pub geometry: usize,
}
