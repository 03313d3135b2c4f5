//! The C interface of the vas client library: what a renderer or input device written in C,
//! C++ or C# (Unity, Unreal, OpenSceneGraph, VTK) links to talk to a vas server on the same
//! machine. It wraps [`vas_client_rs::Client`] behind an opaque handle; `include/vas_client.h`,
//! generated from these sources by cbindgen, is its whole contract.
//!
//! Every function returns a [`VasStatus`] (or a value that cannot fail); an error's words are
//! the calling thread's [`vas_last_error_message`]. Nothing unwinds into C: a panic becomes
//! [`VasStatus::Panic`]. Null pointers and codes out of range are errors, never crashes. Every
//! pointer the library hands out says in its function's documentation how long it lives and that
//! the client owns it.
//!
//! The wire's frames ([`vas_protocol::PartState`], [`vas_protocol::HandFrame`],
//! [`vas_protocol::SimEvent`], the input samples) are `#[repr(C)]` already and reach C as they
//! are, renamed `Vas…`: a renderer reads shared-memory layouts without a conversion.

mod client;
mod control;
mod coordinates;
mod descriptors;
mod frames;
mod geometry;
mod input;
mod names;
mod pointers;
mod status;
mod wire;

pub use client::{
    VAS_EVENT_CAPACITY, VAS_ROLE_ALL, VAS_ROLE_CONTROL, VAS_ROLE_INPUT, VAS_ROLE_RENDER, VasClient,
    VasReceived, VasWake, vas_client_connect, vas_client_free, vas_client_poll,
    vas_client_take_roles, vas_client_wait,
};
pub use control::{
    VasHandInfo, VasPartInfo, VasSceneInfo, vas_client_load_named_scene, vas_client_reset,
    vas_client_scene_info, vas_client_set_metaphor,
};
pub use coordinates::{
    vas_point_from_unity, vas_point_from_unreal, vas_point_to_unity, vas_point_to_unreal,
    vas_pose_from_unity, vas_pose_from_unreal, vas_pose_to_unity, vas_pose_to_unreal,
};
pub use descriptors::vas_client_wake_descriptors;
pub use frames::{
    vas_client_latest_force, vas_client_latest_hand_of, vas_client_latest_hands,
    vas_client_latest_parts, vas_client_take_events,
};
pub use geometry::{VasGeometry, VasHandGeometry, VasMesh, vas_client_geometry};
pub use input::{
    vas_client_flush_inputs, vas_client_send_glove, vas_client_send_hand_joints,
    vas_client_send_tracker,
};
pub use names::{
    vas_event_kind_name, vas_grasp_type_name, vas_hand_segment_name, vas_hand_side_name,
};
pub use status::{VasStatus, vas_last_error_message};
pub use wire::*;
