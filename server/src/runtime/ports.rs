//! The server's iceoryx2 ports, all owned by the I/O thread (iceoryx2 ports are not `Send`).

use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::{Publisher, PublisherCreateError};
use iceoryx2::port::server::Server;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::*;
use vas_protocol::services::{self, output};
use vas_protocol::{
    ClearanceFrame, ControlRequest, ControlResponse, ForceFrame, GeometryHeader, GloveSample,
    HandFrame, HandJointsSample, PartState, PartsFrameHeader, SceneGeometry, SimEvent,
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
    /// Hand-joints samples were sent.
    pub(super) hand_joints: Listener<ipc::Service>,
    /// Control requests were sent.
    pub(super) control: Listener<ipc::Service>,
}

impl Wakeups {
    /// How many listeners there are.
    pub(super) const COUNT: usize = 4;
    /// How many of them, first in [`Wakeups::listeners`], announce input samples.
    pub(super) const INPUTS: usize = 3;

    /// Every listener, in a fixed order: the input streams', then the control service's.
    pub(super) fn listeners(&self) -> [&Listener<ipc::Service>; Self::COUNT] {
        [&self.tracker, &self.glove, &self.hand_joints, &self.control]
    }

    /// Clears the pending notifications of the listeners that `fired` (in the order of
    /// [`Wakeups::listeners`]), so that the WaitSet sleeps until the next one. The others have
    /// none to clear, and each clearing is a system call on the way from an input to its frame; a
    /// notification that arrives after the wait is left for the next wait, which then returns at
    /// once.
    pub(super) fn drain(&self, fired: [bool; Self::COUNT]) -> Result<(), RuntimeError> {
        for (listener, _) in self.listeners().into_iter().zip(fired).filter(|(_, f)| *f) {
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
    /// Hand-joints samples from the clients.
    pub(super) hand_joints: Subscriber<ipc::Service, HandJointsSample, ()>,
    parts: Publisher<ipc::Service, [PartState], PartsFrameHeader>,
    parts_notifier: Notifier<ipc::Service>,
    geometry: Publisher<ipc::Service, [u8], GeometryHeader>,
    geometry_notifier: Notifier<ipc::Service>,
    hand: Publisher<ipc::Service, HandFrame, ()>,
    hand_notifier: Notifier<ipc::Service>,
    events: Publisher<ipc::Service, SimEvent, ()>,
    events_notifier: Notifier<ipc::Service>,
    force: Publisher<ipc::Service, ForceFrame, ()>,
    force_notifier: Notifier<ipc::Service>,
    clearance: Publisher<ipc::Service, ClearanceFrame, ()>,
    clearance_notifier: Notifier<ipc::Service>,
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
    /// frames and `geometry_bytes` the geometry samples (both grow if a larger scene is loaded
    /// later), so that shared memory is sized to the scene.
    pub(super) fn open(
        node: &Node<ipc::Service>,
        part_count: usize,
        geometry_bytes: usize,
    ) -> Result<(Self, Wakeups), RuntimeError> {
        use services::{
            CLEARANCE, CONTROL, EVENTS, FORCE, GEOMETRY, GLOVE, HAND, HAND_JOINTS, PARTS, TRACKER,
        };
        let wakeup = |name| services::open_wakeup(node, name);
        let listener = |name| port(name, wakeup(name)?.listener_builder().create());
        let notifier = |name| port(name, wakeup(name)?.notifier_builder().create());
        let wakeups = Wakeups {
            tracker: listener(TRACKER)?,
            glove: listener(GLOVE)?,
            hand_joints: listener(HAND_JOINTS)?,
            control: listener(CONTROL)?,
        };
        // The parts service allows one publisher: the first to fail when another server serves
        // this prefix, so its refusal says so in words.
        let parts = services::open_parts(node)?
            .publisher_builder()
            .initial_max_slice_len(part_count.max(output::INITIAL_MAX_PARTS))
            .allocation_strategy(AllocationStrategy::PowerOfTwo)
            .create()
            .map_err(|error| match error {
                PublisherCreateError::ExceedsMaxSupportedPublishers => RuntimeError::PrefixInUse,
                other => RuntimeError::Port {
                    service: PARTS,
                    reason: format!("{other:?}"),
                },
            })?;
        let ports = Self {
            tracker: port(
                TRACKER,
                services::open_tracker(node)?.subscriber_builder().create(),
            )?,
            glove: port(
                GLOVE,
                services::open_glove(node)?.subscriber_builder().create(),
            )?,
            hand_joints: port(
                HAND_JOINTS,
                services::open_hand_joints(node)?
                    .subscriber_builder()
                    .create(),
            )?,
            parts,
            parts_notifier: notifier(PARTS)?,
            geometry: port(
                GEOMETRY,
                services::open_geometry(node)?
                    .publisher_builder()
                    .initial_max_slice_len(geometry_bytes.max(1))
                    .allocation_strategy(AllocationStrategy::PowerOfTwo)
                    .create(),
            )?,
            geometry_notifier: notifier(GEOMETRY)?,
            hand: port(
                HAND,
                services::open_hand(node)?.publisher_builder().create(),
            )?,
            hand_notifier: notifier(HAND)?,
            events: port(
                EVENTS,
                services::open_events(node)?.publisher_builder().create(),
            )?,
            events_notifier: notifier(EVENTS)?,
            force: port(
                FORCE,
                services::open_force(node)?.publisher_builder().create(),
            )?,
            force_notifier: notifier(FORCE)?,
            clearance: port(
                CLEARANCE,
                services::open_clearance(node)?.publisher_builder().create(),
            )?,
            clearance_notifier: notifier(CLEARANCE)?,
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

    /// Publishes a scene generation's geometry, encoded straight into the sample (a large
    /// assembly's meshes are a hundred megabytes: no copy between), and wakes its readers.
    pub(super) fn publish_geometry(&self, geometry: &SceneGeometry) -> Result<(), RuntimeError> {
        let header = geometry.header();
        let mut sample = self
            .geometry
            .loan_slice(header.byte_len as usize)
            .map_err(|error| RuntimeError::ipc("loan a geometry sample", error))?;
        *sample.user_header_mut() = header;
        geometry.encode_into(sample.payload_mut());
        sample
            .send()
            .map_err(|error| RuntimeError::ipc("send the geometry", error))?;
        self.geometry_notifier
            .notify()
            .map_err(|error| RuntimeError::ipc("notify geometry readers", error))?;
        Ok(())
    }

    /// Publishes a frame's hand frames (one per hand) and wakes their readers once: a reader
    /// woken by the notification finds every hand's frame (a wake-up per hand would wake it
    /// before the last one is sent, and each notification is a system call).
    pub(super) fn publish_hands(
        &self,
        frames: impl IntoIterator<Item = HandFrame>,
    ) -> Result<(), RuntimeError> {
        send_all(
            &self.hand,
            &self.hand_notifier,
            frames,
            ("send a hand frame", "notify hand readers"),
        )
    }

    /// Publishes a frame's events and wakes their readers once.
    pub(super) fn publish_events(
        &self,
        events: impl IntoIterator<Item = SimEvent>,
    ) -> Result<(), RuntimeError> {
        send_all(
            &self.events,
            &self.events_notifier,
            events,
            ("send an event", "notify event readers"),
        )
    }

    /// Publishes a frame's force frames (one per hand holding a part) and wakes their readers
    /// once.
    pub(super) fn publish_forces(
        &self,
        frames: impl IntoIterator<Item = ForceFrame>,
    ) -> Result<(), RuntimeError> {
        send_all(
            &self.force,
            &self.force_notifier,
            frames,
            ("send a force frame", "notify force readers"),
        )
    }

    /// Publishes a clearance frame and wakes its readers.
    pub(super) fn publish_clearance(&self, frame: &ClearanceFrame) -> Result<(), RuntimeError> {
        send_all(
            &self.clearance,
            &self.clearance_notifier,
            [*frame],
            ("send a clearance frame", "notify clearance readers"),
        )
    }

    /// Wakes the control clients after responses were sent.
    pub(super) fn notify_control_clients(&self) -> Result<(), RuntimeError> {
        self.control_notifier
            .notify()
            .map_err(|error| RuntimeError::ipc("notify control clients", error))?;
        Ok(())
    }

    /// Connects readers that appeared since the last send and hands them the history (the
    /// latest hand, force and clearance frames), so that a reader that (re)connects while no
    /// input arrives still gets it.
    pub(super) fn update_connections(&self) -> Result<(), RuntimeError> {
        self.hand
            .update_connections()
            .map_err(|error| RuntimeError::ipc("connect new hand readers", error))?;
        self.force
            .update_connections()
            .map_err(|error| RuntimeError::ipc("connect new force readers", error))?;
        self.clearance
            .update_connections()
            .map_err(|error| RuntimeError::ipc("connect new clearance readers", error))?;
        self.geometry
            .update_connections()
            .map_err(|error| RuntimeError::ipc("connect new geometry readers", error))?;
        self.parts
            .update_connections()
            .map_err(|error| RuntimeError::ipc("connect new parts readers", error))
    }
}

/// Sends `items` on `publisher` and then notifies its readers once; nothing (no notification
/// either) for no items. `send` and `notify` name the two steps in errors.
fn send_all<T: std::fmt::Debug + ZeroCopySend>(
    publisher: &Publisher<ipc::Service, T, ()>,
    notifier: &Notifier<ipc::Service>,
    items: impl IntoIterator<Item = T>,
    (send, notify): (&'static str, &'static str),
) -> Result<(), RuntimeError> {
    let mut sent = false;
    for item in items {
        publisher
            .send_copy(item)
            .map_err(|error| RuntimeError::ipc(send, error))?;
        sent = true;
    }
    if sent {
        notifier
            .notify()
            .map_err(|error| RuntimeError::ipc(notify, error))?;
    }
    Ok(())
}
