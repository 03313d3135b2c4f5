//! [`InputTap`]: listens to the input streams that clients send to the server.

use std::time::Duration;

use iceoryx2::port::listener::Listener;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use vas_protocol::services;
use vas_protocol::{GloveSample, HandJointsSample, TrackerSample};

use crate::ClientError;
use crate::client::create_node;
use crate::recording::InputSample;
use crate::wait::{Wake, new_waitset, wait_until_ready};

/// A second reader of the input streams (tracker, glove, hand joints), beside the server: what a recorder or an
/// input monitor uses. It sees every sample the senders publish, valid or not.
pub struct InputTap {
    // Keeps the ports' node alive.
    _node: Node<ipc::Service>,
    tracker: Subscriber<ipc::Service, TrackerSample, ()>,
    tracker_listener: Listener<ipc::Service>,
    glove: Subscriber<ipc::Service, GloveSample, ()>,
    glove_listener: Listener<ipc::Service>,
    hand_joints: Subscriber<ipc::Service, HandJointsSample, ()>,
    hand_joints_listener: Listener<ipc::Service>,
    waitset: WaitSet<ipc::Service>,
}

impl InputTap {
    /// Connects on `prefix`; with `handle_termination_signals`, SIGINT and SIGTERM end
    /// [`InputTap::wait`] with [`Wake::Terminated`] instead of the process.
    pub fn connect(
        prefix: Option<&str>,
        handle_termination_signals: bool,
    ) -> Result<Self, ClientError> {
        let node = create_node(prefix, handle_termination_signals)?;
        let tracker = services::open_tracker(&node)?;
        let glove = services::open_glove(&node)?;
        let tracker_wakeup = services::open_wakeup(&node, services::TRACKER)?;
        let glove_wakeup = services::open_wakeup(&node, services::GLOVE)?;
        let hand_joints = services::open_hand_joints(&node)?;
        let hand_joints_wakeup = services::open_wakeup(&node, services::HAND_JOINTS)?;
        Ok(Self {
            tracker: tracker
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            tracker_listener: tracker_wakeup
                .listener_builder()
                .create()
                .map_err(ClientError::port)?,
            glove: glove
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            glove_listener: glove_wakeup
                .listener_builder()
                .create()
                .map_err(ClientError::port)?,
            hand_joints: hand_joints
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            hand_joints_listener: hand_joints_wakeup
                .listener_builder()
                .create()
                .map_err(ClientError::port)?,
            waitset: new_waitset(handle_termination_signals)?,
            _node: node,
        })
    }

    /// Blocks until a sample is ready, the timeout passes or a handled termination signal
    /// arrives.
    pub fn wait(&mut self, timeout: Duration) -> Result<Wake, ClientError> {
        let (tracker, glove, hand_joints) = (&self.tracker, &self.glove, &self.hand_joints);
        wait_until_ready(
            &self.waitset,
            &[
                &self.tracker_listener,
                &self.glove_listener,
                &self.hand_joints_listener,
            ],
            timeout,
            || {
                let has = |result: Result<bool, _>| {
                    result.map_err(|error| ClientError::ipc("check a subscriber", error))
                };
                Ok(has(tracker.has_samples())?
                    || has(glove.has_samples())?
                    || has(hand_joints.has_samples())?)
            },
        )
    }

    /// Every queued sample of every stream, ordered by their timestamps.
    pub fn receive(&mut self) -> Result<Vec<InputSample>, ClientError> {
        let mut samples = Vec::new();
        while let Some(sample) = self
            .tracker
            .receive()
            .map_err(|error| ClientError::ipc("receive a tracker sample", error))?
        {
            samples.push(InputSample::Tracker(*sample.payload()));
        }
        while let Some(sample) = self
            .glove
            .receive()
            .map_err(|error| ClientError::ipc("receive a glove sample", error))?
        {
            samples.push(InputSample::Glove(*sample.payload()));
        }
        while let Some(sample) = self
            .hand_joints
            .receive()
            .map_err(|error| ClientError::ipc("receive a hand-joints sample", error))?
        {
            samples.push(InputSample::HandJoints(*sample.payload()));
        }
        samples.sort_by_key(InputSample::timestamp_ns);
        Ok(samples)
    }
}
