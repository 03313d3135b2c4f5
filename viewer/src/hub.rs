//! Where the link thread leaves what pages are sent, and where pages leave their commands.
//!
//! State (the scene, the newest frame, the server's status) lives in `watch` channels: each page
//! is woken when it changes and sends only the newest value, so a slow page skips frames and
//! nothing queues behind it. Events are not state and must not be skipped, so they go through a
//! `broadcast` channel: each page has its own place in a ring of [`EVENT_QUEUE`] events, and a
//! page that falls that far behind loses the oldest (counted, and the page is told).
//! Every message is built once, as the WebSocket message all pages are sent. A headset's hand
//! joints go the other way, from a page to the link thread, through a short queue that drops
//! rather than grows when the link falls behind (a newer sample follows within one XR frame).

use std::sync::mpsc;

use axum::extract::ws::Message;
use tokio::sync::{broadcast, oneshot, watch};

use crate::commands::Command;
use crate::hand_joints::HandJoints;
use crate::stats::Stats;

/// Events a page may fall behind by before it loses the oldest.
pub const EVENT_QUEUE: usize = 1024;

/// Commands waiting for the link thread, from all pages (each page has at most one waiting).
const COMMAND_QUEUE: usize = 64;

/// Hand-joints messages waiting for the link thread: a few XR frames of both hands.
const HAND_JOINTS_QUEUE: usize = 16;

/// The scene as pages are sent it: one JSON message describing it, then one binary message per
/// mesh.
#[derive(Debug, Clone, Default)]
pub struct SceneMessages {
    /// The description (`"type": "scene"`).
    pub description: Option<Message>,
    /// The meshes, in the order the description numbers them.
    pub meshes: Vec<Message>,
}

/// What the link thread takes from the pages.
#[derive(Debug)]
pub struct Inbox {
    /// Commands, each with the place its answer goes.
    pub commands: mpsc::Receiver<CommandRequest>,
    /// Hand joints, each with the wall-clock time it arrived (ns).
    pub hand_joints: mpsc::Receiver<(HandJoints, u64)>,
}

/// A page's command with the place its answer goes: `Ok` with the server's word, or the reason
/// it was not done.
#[derive(Debug)]
pub struct CommandRequest {
    /// What the page asked for.
    pub command: Command,
    /// Where the answer goes.
    pub reply: oneshot::Sender<Result<String, String>>,
}

/// Shared by the link thread and every page.
#[derive(Debug)]
pub struct Hub {
    /// The current scene.
    pub scene: watch::Sender<SceneMessages>,
    /// The newest frame (parts and hands), once one came.
    pub frame: watch::Sender<Option<Message>>,
    /// Whether a server answers, and the scenes it offers.
    pub status: watch::Sender<Option<Message>>,
    /// Events, in order.
    pub events: broadcast::Sender<Message>,
    /// Commands for the link thread.
    commands: mpsc::SyncSender<CommandRequest>,
    /// Hand joints for the link thread, each with the wall-clock time it arrived (ns).
    hand_joints: mpsc::SyncSender<(HandJoints, u64)>,
    /// Counters.
    pub stats: Stats,
}

impl Hub {
    /// A hub, and the receiving end of its commands and hand joints for the link thread.
    pub fn new() -> (Self, Inbox) {
        let (commands, command_receiver) = mpsc::sync_channel(COMMAND_QUEUE);
        let (hand_joints, hand_joints_receiver) = mpsc::sync_channel(HAND_JOINTS_QUEUE);
        let hub = Self {
            scene: watch::Sender::new(SceneMessages::default()),
            frame: watch::Sender::new(None),
            status: watch::Sender::new(None),
            events: broadcast::Sender::new(EVENT_QUEUE),
            commands,
            hand_joints,
            stats: Stats::default(),
        };
        let inbox = Inbox {
            commands: command_receiver,
            hand_joints: hand_joints_receiver,
        };
        (hub, inbox)
    }

    /// Hands `joints`, which arrived at `arrived_ns` (wall clock), to the link thread to
    /// publish; counted as dropped when the link thread is too far behind to take them.
    pub fn submit_hand_joints(&self, joints: HandJoints, arrived_ns: u64) {
        Stats::count(&self.stats.hand_joints_accepted);
        if self.hand_joints.try_send((joints, arrived_ns)).is_err() {
            Stats::count(&self.stats.hand_joints_dropped);
        }
    }

    /// Hands `command` to the link thread; its answer arrives on the returned channel (at once,
    /// as a refusal, when the link thread is too far behind to take it).
    pub fn submit(&self, command: Command) -> oneshot::Receiver<Result<String, String>> {
        let (reply, answer) = oneshot::channel();
        if let Err(error) = self.commands.try_send(CommandRequest { command, reply }) {
            let refusal = match error {
                mpsc::TrySendError::Full(_) => "the viewer is busy; try again",
                mpsc::TrySendError::Disconnected(_) => "the viewer is stopping",
            };
            let request = match error {
                mpsc::TrySendError::Full(request) | mpsc::TrySendError::Disconnected(request) => {
                    request
                }
            };
            let _ = request.reply.send(Err(refusal.to_owned()));
        }
        answer
    }
}
