//! The wake-up descriptors: what an engine's own event loop (poll, epoll, select, a run loop)
//! waits on instead of `vas_client_wait`.

use std::ffi::c_int;

use crate::client::{VasClient, client_mut};
use crate::pointers::output;
use crate::status::{Failure, VasStatus, guard};

/// Writes the file descriptors of the client's wake-up listeners, one per output service, to
/// `fds` (room for `capacity`) and their number to `*count`. Each becomes readable when the
/// server publishes on its service: register them all with poll, epoll or select (or an engine's
/// run loop: an Unreal `FRunnable`, a Unity thread) and call `vas_client_poll` when one is.
/// The poll empties them, so they stay quiet until the server publishes again; one that wakes
/// with nothing new to poll is harmless. Poll once after connecting: the frames a new client
/// finds queued do not make them readable. Needs the render role.
///
/// A null `fds` with a `capacity` of 0 asks for their number only. With a `capacity` smaller
/// than their number, `*count` gets the number, `fds` is left alone and the status is
/// `VAS_STATUS_INVALID_ARGUMENT`.
///
/// The descriptors belong to the client: never read, write or close them; they stay valid
/// until `vas_client_free`. Where the system has no file descriptors (Windows), the status is
/// `VAS_STATUS_UNSUPPORTED`: use `vas_client_wait` there.
///
/// # Safety
/// `client` is a live handle from `vas_client_connect`; `fds` is null or points to `capacity`
/// writable `int`s; `count` points to a writable `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_wake_descriptors(
    client: *mut VasClient,
    fds: *mut c_int,
    capacity: usize,
    count: *mut usize,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees.
        let (client, count) = unsafe { (client_mut(client)?, output(count, "count")?) };
        let descriptors = descriptors_of(client)?;
        *count = descriptors.len();
        if fds.is_null() && capacity == 0 {
            return Ok(VasStatus::Ok);
        }
        if capacity < descriptors.len() {
            return Err(Failure::invalid(format!(
                "fds has room for {capacity} descriptors of {}",
                descriptors.len()
            )));
        }
        if fds.is_null() {
            return Err(Failure::null("fds"));
        }
        // SAFETY: `fds` points to `capacity` writable ints, as the caller guarantees, and
        // `capacity` is at least the descriptors' number.
        let room = unsafe { std::slice::from_raw_parts_mut(fds, descriptors.len()) };
        room.copy_from_slice(&descriptors);
        Ok(VasStatus::Ok)
    })
}

/// The client's wake-up descriptors.
#[cfg(unix)]
fn descriptors_of(client: &VasClient) -> Result<Vec<c_int>, Failure> {
    Ok(client.client.wake_descriptors()?)
}

/// No file descriptors to hand out on this system.
#[cfg(not(unix))]
fn descriptors_of(_client: &VasClient) -> Result<Vec<c_int>, Failure> {
    Err(Failure {
        status: VasStatus::Unsupported,
        message: "wake-up descriptors exist on Unix only: use vas_client_wait".into(),
    })
}
