//! The server's iceoryx2 ports, all owned by the I/O thread (iceoryx2 ports are not `Send`).

use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::server::Server;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
use vas_protocol::services::{self, output};
use vas_protocol::{
    ControlRequest, ControlResponse, GloveSample, HandFrame, PartState, PartsFrameHeader,
    TrackerSample,
};

use super::RuntimeError;

/// The listeners that wake the server: attached to its WaitSet for the whole run, so kept
/// apart from the ports the loop uses mutably.
pub(super) struct Wakeups {
    /// Tracker samples were sent.
    pub(super) tracker: Listener<ipc::Service>,
    /// Glove samples were sent.
    pub(super) glove: Listener<ipc::Service>,
    /// Control requests were sent.
    pub(super) control: Listener<ipc::Service>,
}

impl Wakeups {
    /// Clears pending notifications, so that the WaitSet sleeps until the next one.
    pub(super) fn drain(&self) -> Result<(), RuntimeError> {
        for listener in [&self.tracker, &self.glove, &self.control] {
            listener
                .try_wait(|_| {})
                .map_err(|error| RuntimeError::ipc("drain a listener", error))?;
        }
        Ok(())
    }
}

/// The ports the server reads and writes: input subscribers, output publishers with their
/// notifiers, the control server.
pub(super) struct Ports {
    /// Tracker samples from the clients.
    pub(super) tracker: Subscriber<ipc::Service, TrackerSample, ()>,
    /// Glove samples from the clients.
    pub(super) glove: Subscriber<ipc::Service, GloveSample, ()>,
    parts: Publisher<ipc::Service, [PartState], PartsFrameHeader>,
    parts_notifier: Notifier<ipc::Service>,
    hand: Publisher<ipc::Service, HandFrame, ()>,
    hand_notifier: Notifier<ipc::Service>,
    /// Control requests from the clients.
    pub(super) control: Server<ipc::Service, ControlRequest, (), ControlResponse, ()>,
    control_notifier: Notifier<ipc::Service>,
}

/// A port of `service`, or the error naming the service: e.g. a second publisher where the
/// service allows one, when another server runs on the same prefix.
fn port<T>(
    service: &'static str,
    created: Result<T, impl std::fmt::Debug>,
) -> Result<T, RuntimeError> {
    created.map_err(|error| RuntimeError::Port {
        service,
        reason: format!("{error:?}"),
    })
}

impl Ports {
    /// Opens every service and creates the ports and listeners; `part_count` sizes the parts
    /// frames (they grow if a larger scene is loaded later).
    pub(super) fn open(
        node: &Node<ipc::Service>,
        part_count: usize,
    ) -> Result<(Self, Wakeups), RuntimeError> {
        use services::{CONTROL, GLOVE, HAND, PARTS, TRACKER};
        let wakeup = |name| services::open_wakeup(node, name);
        let listener = |name| port(name, wakeup(name)?.listener_builder().create());
        let notifier = |name| port(name, wakeup(name)?.notifier_builder().create());
        let wakeups = Wakeups {
            tracker: listener(TRACKER)?,
            glove: listener(GLOVE)?,
            control: listener(CONTROL)?,
        };
        let parts = services::open_parts(node)?
            .publisher_builder()
            .initial_max_slice_len(part_count.max(output::INITIAL_MAX_PARTS))
            .allocation_strategy(AllocationStrategy::PowerOfTwo)
            .create();
        let ports = Self {
            tracker: port(
                TRACKER,
                services::open_tracker(node)?.subscriber_builder().create(),
            )?,
            glove: port(
                GLOVE,
                services::open_glove(node)?.subscriber_builder().create(),
            )?,
            parts: port(PARTS, parts)?,
            parts_notifier: notifier(PARTS)?,
            hand: port(
                HAND,
                services::open_hand(node)?.publisher_builder().create(),
            )?,
            hand_notifier: notifier(HAND)?,
            control: port(
                CONTROL,
                services::open_control(node)?.server_builder().create(),
            )?,
            control_notifier: notifier(CONTROL)?,
        };
        Ok((ports, wakeups))
    }

    /// Publishes a parts frame and wakes its readers.
    pub(super) fn publish_parts(
        &self,
        header: PartsFrameHeader,
        states: &[PartState],
    ) -> Result<(), RuntimeError> {
        let mut sample = self
            .parts
            .loan_slice_uninit(states.len())
            .map_err(|error| RuntimeError::ipc("loan a parts frame", error))?;
        *sample.user_header_mut() = header;
        sample
            .write_from_slice(states)
            .send()
            .map_err(|error| RuntimeError::ipc("send a parts frame", error))?;
        self.parts_notifier
            .notify()
            .map_err(|error| RuntimeError::ipc("notify parts readers", error))?;
        Ok(())
    }

    /// Publishes a hand frame and wakes its readers.
    pub(super) fn publish_hand(&self, frame: HandFrame) -> Result<(), RuntimeError> {
        self.hand
            .send_copy(frame)
            .map_err(|error| RuntimeError::ipc("send a hand frame", error))?;
        self.hand_notifier
            .notify()
            .map_err(|error| RuntimeError::ipc("notify hand readers", error))?;
        Ok(())
    }

    /// Wakes the control clients after responses were sent.
    pub(super) fn notify_control_clients(&self) -> Result<(), RuntimeError> {
        self.control_notifier
            .notify()
            .map_err(|error| RuntimeError::ipc("notify control clients", error))?;
        Ok(())
    }

    /// Connects readers that appeared since the last send and hands them the history (the
    /// latest hand frame), so that a reader that (re)connects while no input arrives still gets
    /// it.
    pub(super) fn update_connections(&self) -> Result<(), RuntimeError> {
        self.hand
            .update_connections()
            .map_err(|error| RuntimeError::ipc("connect new hand readers", error))?;
        self.parts
            .update_connections()
            .map_err(|error| RuntimeError::ipc("connect new parts readers", error))
    }
}
