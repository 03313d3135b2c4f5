//! The ports each role holds: subscribers on the outputs, publishers on the inputs.

use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::{event, publish_subscribe};
use vas_protocol::services;
use vas_protocol::{
    ClearanceFrame, ForceFrame, GeometryHeader, GloveSample, HandFrame, HandJointsSample,
    PartState, PartsFrameHeader, SimEvent, TrackerSample,
};

use crate::ClientError;

/// The ports of the render role: a subscriber on each output service, and a listener on its
/// wake-up service.
pub(super) struct Outputs {
    pub(super) parts: Subscriber<ipc::Service, [PartState], PartsFrameHeader>,
    pub(super) parts_listener: Listener<ipc::Service>,
    pub(super) hand: Subscriber<ipc::Service, HandFrame, ()>,
    pub(super) hand_listener: Listener<ipc::Service>,
    pub(super) events: Subscriber<ipc::Service, SimEvent, ()>,
    pub(super) events_listener: Listener<ipc::Service>,
    pub(super) force: Subscriber<ipc::Service, ForceFrame, ()>,
    pub(super) force_listener: Listener<ipc::Service>,
    pub(super) clearance: Subscriber<ipc::Service, ClearanceFrame, ()>,
    pub(super) clearance_listener: Listener<ipc::Service>,
    pub(super) geometry: Subscriber<ipc::Service, [u8], GeometryHeader>,
    pub(super) geometry_listener: Listener<ipc::Service>,
}

impl Outputs {
    pub(super) fn open(node: &Node<ipc::Service>) -> Result<Self, ClientError> {
        let listener = |name| -> Result<Listener<ipc::Service>, ClientError> {
            services::open_wakeup(node, name)?
                .listener_builder()
                .create()
                .map_err(ClientError::port)
        };
        Ok(Outputs {
            parts: services::open_parts(node)?
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            parts_listener: listener(services::PARTS)?,
            hand: services::open_hand(node)?
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            hand_listener: listener(services::HAND)?,
            events: services::open_events(node)?
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            events_listener: listener(services::EVENTS)?,
            force: services::open_force(node)?
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            force_listener: listener(services::FORCE)?,
            clearance: services::open_clearance(node)?
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            clearance_listener: listener(services::CLEARANCE)?,
            geometry: services::open_geometry(node)?
                .subscriber_builder()
                .create()
                .map_err(ClientError::port)?,
            geometry_listener: listener(services::GEOMETRY)?,
        })
    }

    /// The wake-up listener of every output service.
    pub(super) fn listeners(&self) -> [&Listener<ipc::Service>; 6] {
        [
            &self.geometry_listener,
            &self.parts_listener,
            &self.hand_listener,
            &self.events_listener,
            &self.force_listener,
            &self.clearance_listener,
        ]
    }

    /// Whether any output service holds a sample not received yet.
    pub(super) fn has_samples(&self) -> Result<bool, ClientError> {
        let has = |result: Result<bool, _>| {
            result.map_err(|error| ClientError::ipc("check a subscriber", error))
        };
        Ok(has(self.geometry.has_samples())?
            || has(self.parts.has_samples())?
            || has(self.hand.has_samples())?
            || has(self.events.has_samples())?
            || has(self.force.has_samples())?
            || has(self.clearance.has_samples())?)
    }
}

/// The ports of the input role: each input stream's sending end.
pub(super) struct Inputs {
    pub(super) tracker: InputPort<TrackerSample>,
    pub(super) glove: InputPort<GloveSample>,
    pub(super) hand_joints: InputPort<HandJointsSample>,
}

impl Inputs {
    pub(super) fn open(node: &Node<ipc::Service>) -> Result<Self, ClientError> {
        Ok(Inputs {
            tracker: InputPort::open(
                &services::open_tracker(node)?,
                &services::open_wakeup(node, services::TRACKER)?,
                ["send a tracker sample", "notify the tracker service"],
            )?,
            glove: InputPort::open(
                &services::open_glove(node)?,
                &services::open_wakeup(node, services::GLOVE)?,
                ["send a glove sample", "notify the glove service"],
            )?,
            hand_joints: InputPort::open(
                &services::open_hand_joints(node)?,
                &services::open_wakeup(node, services::HAND_JOINTS)?,
                [
                    "send a hand-joints sample",
                    "notify the hand-joints service",
                ],
            )?,
        })
    }
}

/// An input stream's sending end: its publisher, and the notifier that wakes the server after
/// each sample.
pub(super) struct InputPort<T: std::fmt::Debug + ZeroCopySend + 'static> {
    publisher: Publisher<ipc::Service, T, ()>,
    notifier: Notifier<ipc::Service>,
    /// What errors say was being done: sending a sample, then waking the server.
    actions: [&'static str; 2],
}

impl<T: std::fmt::Debug + ZeroCopySend + Copy + 'static> InputPort<T> {
    fn open(
        service: &publish_subscribe::PortFactory<ipc::Service, T, ()>,
        wakeup: &event::PortFactory<ipc::Service>,
        actions: [&'static str; 2],
    ) -> Result<Self, ClientError> {
        Ok(InputPort {
            publisher: service
                .publisher_builder()
                .create()
                .map_err(ClientError::port)?,
            notifier: wakeup
                .notifier_builder()
                .create()
                .map_err(ClientError::port)?,
            actions,
        })
    }

    /// Sends `sample` and wakes the server.
    pub(super) fn send(&self, sample: &T) -> Result<(), ClientError> {
        let [sending, notifying] = self.actions;
        self.publisher
            .send_copy(*sample)
            .map_err(|error| ClientError::ipc(sending, error))?;
        self.notifier
            .notify()
            .map_err(|error| ClientError::ipc(notifying, error))?;
        Ok(())
    }
}
