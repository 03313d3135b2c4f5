//! The client handle: connecting, roles, waiting and polling.

use std::collections::VecDeque;
use std::ffi::c_char;
use std::thread::ThreadId;
use std::time::Duration;

use vas_client_rs::{Client, Frame, Roles, Wake};
use vas_protocol::{ForceFrame, SimEvent};

use crate::control::SceneView;
use crate::geometry::GeometryView;
use crate::pointers::{output, text, write_optional};
use crate::status::{Failure, VasStatus, guard};

/// Role bit: the control service only (scene info, reset, loads, metaphor). Every client has it.
pub const VAS_ROLE_CONTROL: u32 = 0;
/// Role bit: reads the server's output (geometry, parts, hands, events, force): a renderer.
pub const VAS_ROLE_RENDER: u32 = 1;
/// Role bit: sends tracker, glove and hand-joints samples: an input device.
pub const VAS_ROLE_INPUT: u32 = 2;
/// Every role: renders and sends.
pub const VAS_ROLE_ALL: u32 = VAS_ROLE_RENDER | VAS_ROLE_INPUT;

/// Events a client keeps for `vas_client_take_events`; beyond this the oldest
/// are dropped (and counted), so that a program that never takes them does not grow without end.
pub const VAS_EVENT_CAPACITY: usize = 4096;

/// How a [`vas_client_wait`] ended.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VasWake {
    /// New output is ready: call [`vas_client_poll`].
    Ready = 0,
    /// The time-out passed without new output.
    Timeout = 1,
    /// SIGINT or SIGTERM arrived (only when the client was connected with
    /// `handle_termination_signals`): the program should end.
    Terminated = 2,
}

/// How many frames of each kind a [`vas_client_poll`] received.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct VasReceived {
    /// Parts frames.
    pub parts: usize,
    /// Hand frames (of every hand).
    pub hands: usize,
    /// Events.
    pub events: usize,
    /// Force frames.
    pub force: usize,
    /// Clearance frames.
    pub clearance: usize,
    /// Geometry generations.
    pub geometry: usize,
}

/// A connection to a vas server, opaque to C: made by [`vas_client_connect`], freed by
/// [`vas_client_free`]. It also keeps what the C side reads through pointers (events, the
/// geometry's and the scene's views), so that those pointers stay valid for as long as the header
/// says.
pub struct VasClient {
    pub(crate) client: Client,
    /// The thread that connected: iceoryx2's ports are bound to it.
    thread: ThreadId,
    /// Events received and not taken yet, oldest first.
    pub(crate) pending_events: VecDeque<SimEvent>,
    /// The events the last take handed out.
    pub(crate) taken_events: Vec<SimEvent>,
    /// Events dropped since the last take because [`VAS_EVENT_CAPACITY`] were pending.
    pub(crate) dropped_events: u64,
    pub(crate) latest_force: Option<ForceFrame>,
    pub(crate) geometry: Option<GeometryView>,
    pub(crate) scene: Option<SceneView>,
}

impl VasClient {
    /// Takes in the frames of a poll: events are kept for the next take, the newest force frame
    /// for its accessor (the client keeps the newest of every other kind itself).
    fn take_in(&mut self, frames: Vec<Frame>) -> VasReceived {
        let mut received = VasReceived::default();
        for frame in frames {
            match frame {
                Frame::Parts(_) => received.parts += 1,
                Frame::Hand(_) => received.hands += 1,
                Frame::Clearance(_) => received.clearance += 1,
                Frame::Geometry(_) => received.geometry += 1,
                Frame::Force(force) => {
                    received.force += 1;
                    self.latest_force = Some(force);
                }
                Frame::Event(event) => {
                    received.events += 1;
                    if self.pending_events.len() == VAS_EVENT_CAPACITY {
                        self.pending_events.pop_front();
                        self.dropped_events += 1;
                    }
                    self.pending_events.push_back(event);
                }
            }
        }
        received
    }
}

/// The client behind a handle from C, checked for null and for the thread it belongs to.
///
/// # Safety
/// A non-null `client` must come from [`vas_client_connect`] and not be freed.
pub(crate) unsafe fn client_mut<'a>(client: *mut VasClient) -> Result<&'a mut VasClient, Failure> {
    // SAFETY: as the caller guarantees.
    let client = unsafe { output(client, "client") }?;
    if client.thread != std::thread::current().id() {
        return Err(Failure {
            status: VasStatus::WrongThread,
            message: "a vas client is used on another thread than the one that connected it".into(),
        });
    }
    Ok(client)
}

/// The [`Roles`] of a `VAS_ROLE_*` combination.
fn roles_of(bits: u32) -> Result<Roles, Failure> {
    if bits & !VAS_ROLE_ALL != 0 {
        return Err(Failure::invalid(format!("unknown role bits {bits:#x}")));
    }
    let mut roles = Roles::CONTROL;
    if bits & VAS_ROLE_RENDER != 0 {
        roles |= Roles::RENDER;
    }
    if bits & VAS_ROLE_INPUT != 0 {
        roles |= Roles::INPUT;
    }
    Ok(roles)
}

/// A time-out in milliseconds; `UINT64_MAX` waits without end.
pub(crate) fn millis(timeout_ms: u64) -> Duration {
    Duration::from_millis(timeout_ms)
}

/// Connects to the vas server on `prefix` (its `--prefix`; null for the iceoryx2
/// configuration's default) with `roles` (`VAS_ROLE_*` bits combined with `|`).
///
/// With `handle_termination_signals`, iceoryx2 catches SIGINT and SIGTERM and
/// [`vas_client_wait`] reports [`VasWake::Terminated`]; without, the application's own handling
/// stays in place. On success `*client` is a new handle that the caller owns and frees with
/// [`vas_client_free`]; it must be used on the calling thread only. On an error `*client` is
/// left unchanged.
///
/// # Safety
/// `prefix` is null or a NUL-terminated string; `client` points to writable memory for a
/// pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_connect(
    prefix: *const c_char,
    roles: u32,
    handle_termination_signals: bool,
    client: *mut *mut VasClient,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees.
        let out = unsafe { output(client, "client") }?;
        let prefix = match prefix.is_null() {
            true => None,
            // SAFETY: non-null and NUL-terminated as the caller guarantees.
            false => Some(unsafe { text(prefix, "prefix") }?),
        };
        let connected = Client::builder()
            .prefix(prefix)
            .roles(roles_of(roles)?)
            .handle_termination_signals(handle_termination_signals)
            .connect()?;
        *out = Box::into_raw(Box::new(VasClient {
            client: connected,
            thread: std::thread::current().id(),
            pending_events: VecDeque::new(),
            taken_events: Vec::new(),
            dropped_events: 0,
            latest_force: None,
            geometry: None,
            scene: None,
        }));
        Ok(VasStatus::Ok)
    })
}

/// Closes the connection and frees the handle and everything it handed out (frames, geometry,
/// events, scene info). Null is allowed and does nothing. The handle must not be used again.
/// On another thread than the one that connected, nothing is freed (the ports cannot be closed
/// there) and the thread's last error says so.
///
/// # Safety
/// `client` is null or a handle from [`vas_client_connect`] not freed yet.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_free(client: *mut VasClient) {
    guard(|| {
        if !client.is_null() {
            // SAFETY: a live handle from `vas_client_connect`, as the caller guarantees.
            unsafe { client_mut(client) }?;
            // SAFETY: as above, and on the thread that owns it.
            drop(unsafe { Box::from_raw(client) });
        }
        Ok(VasStatus::Ok)
    });
}

/// Takes `roles` as well (`VAS_ROLE_*` bits), opening the ports of those the client lacks: e.g.
/// a renderer that starts forwarding a headset's hand joints takes [`VAS_ROLE_INPUT`]. On an
/// error the client keeps the roles it had.
///
/// # Safety
/// `client` is a live handle from [`vas_client_connect`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_take_roles(client: *mut VasClient, roles: u32) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees.
        let client = unsafe { client_mut(client) }?;
        client.client.take_roles(roles_of(roles)?)?;
        Ok(VasStatus::Ok)
    })
}

/// Blocks until output is ready to be polled, `timeout_ms` milliseconds pass (`UINT64_MAX`:
/// no end), or a handled termination signal arrives; `*wake` says which. Output that arrived
/// before the call counts: nothing is missed between a poll and the next wait. Needs the render
/// role.
///
/// An engine with its own loop calls it with a time-out of 0 once per frame, or waits on
/// `vas_client_wake_descriptors` in that loop instead.
///
/// # Safety
/// `client` is a live handle from [`vas_client_connect`]; `wake` points to a writable
/// [`VasWake`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_wait(
    client: *mut VasClient,
    timeout_ms: u64,
    wake: *mut VasWake,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees.
        let client = unsafe { client_mut(client) }?;
        // SAFETY: as the caller guarantees.
        let wake = unsafe { output(wake, "wake") }?;
        *wake = match client.client.wait(millis(timeout_ms))? {
            Wake::Ready => VasWake::Ready,
            Wake::Timeout => VasWake::Timeout,
            Wake::Terminated => VasWake::Terminated,
        };
        Ok(VasStatus::Ok)
    })
}

/// Receives every queued output frame without blocking: the newest geometry, parts frame, hand
/// frames and force frame are kept for their accessors, events for
/// `vas_client_take_events`. `*received` (when not null) counts what came.
/// Needs the render role.
///
/// A poll ends the validity of the parts and hand pointers handed out before it, and quiets the
/// `vas_client_wake_descriptors` until the server publishes again.
///
/// # Safety
/// `client` is a live handle from [`vas_client_connect`]; `received` is null or points to a
/// writable [`VasReceived`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_poll(
    client: *mut VasClient,
    received: *mut VasReceived,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees.
        let client = unsafe { client_mut(client) }?;
        let frames = client.client.receive()?;
        let counts = client.take_in(frames);
        // SAFETY: as the caller guarantees.
        unsafe { write_optional(received, counts) };
        Ok(VasStatus::Ok)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn role_bits_are_the_client_roles() {
        assert_eq!(roles_of(VAS_ROLE_CONTROL).unwrap(), Roles::CONTROL);
        assert_eq!(roles_of(VAS_ROLE_RENDER).unwrap(), Roles::RENDER);
        assert_eq!(roles_of(VAS_ROLE_INPUT).unwrap(), Roles::INPUT);
        assert_eq!(roles_of(VAS_ROLE_ALL).unwrap(), Roles::ALL);
        let unknown = roles_of(4).unwrap_err();
        assert_eq!(unknown.status, VasStatus::InvalidArgument);
    }

    #[test]
    fn null_handles_are_errors() {
        let mut wake = VasWake::Ready;
        // SAFETY: null handles are what is tested; `wake` is writable.
        let status = unsafe { vas_client_wait(std::ptr::null_mut(), 0, &mut wake) };
        assert_eq!(status, VasStatus::NullArgument);
        // SAFETY: as above.
        let status = unsafe { vas_client_poll(std::ptr::null_mut(), std::ptr::null_mut()) };
        assert_eq!(status, VasStatus::NullArgument);
        // SAFETY: null is allowed.
        unsafe { vas_client_free(std::ptr::null_mut()) };
        // SAFETY: a null out-pointer is what is tested.
        let status = unsafe {
            vas_client_connect(std::ptr::null(), VAS_ROLE_ALL, false, std::ptr::null_mut())
        };
        assert_eq!(status, VasStatus::NullArgument);
    }
}
