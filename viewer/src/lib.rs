//! The reference renderer, `vas-viewer`. A vas client that serves a browser page (and a WebXR
//! session on a headset) drawing the scene, over HTTP and one WebSocket per page.
//!
//! Two halves meet in the [`hub::Hub`]: the link thread ([`link`]) owns the vas client (its
//! iceoryx2 ports cannot leave their thread) and writes the newest state into the hub; the tokio
//! side ([`http`], [`page`]) serves the embedded assets and sends each page what the hub holds,
//! and passes a headset's hand joints ([`hand_joints`]) back to the link thread to publish.
//! Before any of that, [`settings`] decides where and how it listens ([`listen`], [`tls`]),
//! [`connections`] accepts and times out connections, and every request must name this viewer
//! ([`host`]) and, beyond loopback, carry its access token ([`access`]).

pub mod access;
pub mod assets;
pub mod commands;
pub mod connections;
pub mod events;
pub mod hand_joints;
pub mod host;
pub mod http;
pub mod hub;
pub mod link;
pub mod listen;
pub mod messages;
pub mod page;
pub mod scene;
pub mod settings;
pub mod stats;
pub mod tls;
