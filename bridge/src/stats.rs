//! The bridge's counters: what it forwarded and what it refused, answered as JSON on
//! `vas/<session>/bridge/stats` and logged when the bridge stops.

use std::sync::atomic::{AtomicU64, Ordering};

use serde::Serialize;

use crate::keys::Input;
use crate::wire::Refusal;

/// Counters shared by the bridge's threads.
#[derive(Debug, Default)]
pub struct Stats {
    forwarded: [AtomicU64; 3],
    refused_size: AtomicU64,
    refused_code: AtomicU64,
    refused_version: AtomicU64,
    refused_user: AtomicU64,
    refused_by_server: AtomicU64,
    published: AtomicU64,
    control_answered: AtomicU64,
    control_refused: AtomicU64,
    servers: AtomicU64,
}

/// A snapshot of [`Stats`], as JSON names it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct StatsSnapshot {
    /// Tracker samples handed to the server.
    pub tracker_forwarded: u64,
    /// Glove samples handed to the server.
    pub glove_forwarded: u64,
    /// Hand-joints samples handed to the server.
    pub hand_joints_forwarded: u64,
    /// Input samples and control requests refused for their length.
    pub refused_size: u64,
    /// Input samples and control requests whose envelope announces another message.
    pub refused_code: u64,
    /// Input samples and control requests in another version of their layout.
    pub refused_version: u64,
    /// Input samples of a user the bridge does not accept (`--user`).
    pub refused_user: u64,
    /// Input samples the server's input streams had no room for, and control requests the
    /// bridge does not pass on (a load by path).
    pub refused_by_server: u64,
    /// Messages published on zenoh (every stream, thinned ones included).
    pub published: u64,
    /// Control queries answered with a response of the server.
    pub control_answered: u64,
    /// Control queries answered with an error.
    pub control_refused: u64,
    /// Servers the bridge has connected to since it started (a server that went away and came
    /// back counts again).
    pub servers: u64,
}

fn add(counter: &AtomicU64) {
    counter.fetch_add(1, Ordering::Relaxed);
}

impl Stats {
    /// A sample of `stream` handed to the server.
    pub fn forwarded(&self, stream: Input) {
        add(&self.forwarded[stream as usize]);
    }

    /// Received bytes refused for `refusal`.
    pub fn refused(&self, refusal: &Refusal) {
        add(match refusal {
            Refusal::Size { .. } | Refusal::Geometry(_) => &self.refused_size,
            Refusal::Code { .. } => &self.refused_code,
            Refusal::Version { .. } => &self.refused_version,
        });
    }

    /// A sample of a user the bridge does not accept.
    pub fn refused_user(&self) {
        add(&self.refused_user);
    }

    /// A sample or request that could not be handed to the server.
    pub fn refused_by_server(&self) {
        add(&self.refused_by_server);
    }

    /// `count` messages published.
    pub fn published(&self, count: usize) {
        self.published.fetch_add(count as u64, Ordering::Relaxed);
    }

    /// A control query answered by the server.
    pub fn control_answered(&self) {
        add(&self.control_answered);
    }

    /// A control query answered with an error.
    pub fn control_refused(&self) {
        add(&self.control_refused);
    }

    /// A server connected.
    pub fn server_connected(&self) {
        add(&self.servers);
    }

    /// The counters now.
    pub fn snapshot(&self) -> StatsSnapshot {
        let get = |counter: &AtomicU64| counter.load(Ordering::Relaxed);
        StatsSnapshot {
            tracker_forwarded: get(&self.forwarded[Input::Tracker as usize]),
            glove_forwarded: get(&self.forwarded[Input::Glove as usize]),
            hand_joints_forwarded: get(&self.forwarded[Input::HandJoints as usize]),
            refused_size: get(&self.refused_size),
            refused_code: get(&self.refused_code),
            refused_version: get(&self.refused_version),
            refused_user: get(&self.refused_user),
            refused_by_server: get(&self.refused_by_server),
            published: get(&self.published),
            control_answered: get(&self.control_answered),
            control_refused: get(&self.control_refused),
            servers: get(&self.servers),
        }
    }
}
