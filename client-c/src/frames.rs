//! The newest output a poll kept: parts, hands, force, and the events since the last take.

use vas_protocol::{ForceFrame, HandFrame, HandSide, PartState, PartsFrameHeader, SimEvent};

use crate::client::{VasClient, client_mut};
use crate::pointers::{output, write_optional};
use crate::status::{Failure, VasStatus, guard};

/// The newest parts frame: `*header` gets a copy of its header, `*parts` and `*count` the pose
/// and state of every part, indexed by part id. [`VasStatus::Empty`] before the first parts
/// frame.
///
/// `*parts` belongs to the client and stays valid until the next `vas_client_poll`
/// or `vas_client_free`.
///
/// # Safety
/// `client` is a live handle; `header`, `parts` and `count` point to writable memory of their
/// types.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_latest_parts(
    client: *mut VasClient,
    header: *mut PartsFrameHeader,
    parts: *mut *const PartState,
    count: *mut usize,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees, for each pointer.
        let (client, header, parts, count) = unsafe {
            (
                client_mut(client)?,
                output(header, "header")?,
                output(parts, "parts")?,
                output(count, "count")?,
            )
        };
        let Some(frame) = client.client.latest_parts() else {
            return Ok(VasStatus::Empty);
        };
        *header = frame.header;
        *parts = frame.parts.as_ptr();
        *count = frame.parts.len();
        Ok(VasStatus::Ok)
    })
}

/// The newest frame of every hand of the scene, right hand first: `*hands` and `*count` (0
/// before the first hand frame, which is no error). Each frame carries its side
/// (`VasHandFrame::hand`, a `VAS_HAND_*` code) and each segment's verified world pose, where
/// the segment's mesh of the geometry goes.
///
/// `*hands` belongs to the client and stays valid until the next
/// `vas_client_poll` or `vas_client_free`.
///
/// # Safety
/// `client` is a live handle; `hands` and `count` point to writable memory of their types.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_latest_hands(
    client: *mut VasClient,
    hands: *mut *const HandFrame,
    count: *mut usize,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees, for each pointer.
        let (client, hands, count) = unsafe {
            (
                client_mut(client)?,
                output(hands, "hands")?,
                output(count, "count")?,
            )
        };
        let latest = client.client.latest_hands();
        *hands = latest.as_ptr();
        *count = latest.len();
        Ok(VasStatus::Ok)
    })
}

/// A copy of the newest frame of user `user`'s hand on `side` (a `VAS_HAND_*` code) into
/// `*hand`; [`VasStatus::Empty`] before the first frame of that hand. `user` is the user's
/// index in the scene info's `users` (0 in a scene of one user).
///
/// # Safety
/// `client` is a live handle; `hand` points to a writable `VasHandFrame`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_latest_hand_of(
    client: *mut VasClient,
    user: u32,
    side: u32,
    hand: *mut HandFrame,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees, for each pointer.
        let (client, hand) = unsafe { (client_mut(client)?, output(hand, "hand")?) };
        let side = HandSide::try_from(side)
            .map_err(|_| Failure::invalid(format!("unknown hand side {side}")))?;
        match client.client.latest_hand_of(user, side) {
            Some(latest) => {
                *hand = *latest;
                Ok(VasStatus::Ok)
            }
            None => Ok(VasStatus::Empty),
        }
    })
}

/// A copy of the newest force frame (force and torque for a force-feedback device while a part
/// is held) into `*force`; [`VasStatus::Empty`] before the first.
///
/// # Safety
/// `client` is a live handle; `force` points to a writable `VasForceFrame`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_latest_force(
    client: *mut VasClient,
    force: *mut ForceFrame,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees, for each pointer.
        let (client, force) = unsafe { (client_mut(client)?, output(force, "force")?) };
        match client.latest_force {
            Some(latest) => {
                *force = latest;
                Ok(VasStatus::Ok)
            }
            None => Ok(VasStatus::Empty),
        }
    })
}

/// The events the polls received since the last take, oldest first (grasps, releases,
/// contacts, hand-overs, clearances): `*events` and `*count` (0 when none came). `*dropped`
/// (when not null) counts the events lost meanwhile because more than `VAS_EVENT_CAPACITY` were
/// waiting.
///
/// `*events` belongs to the client and stays valid until the next take or
/// `vas_client_free`.
///
/// # Safety
/// `client` is a live handle; `events` and `count` point to writable memory of their types;
/// `dropped` is null or points to a writable `uint64_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_take_events(
    client: *mut VasClient,
    events: *mut *const SimEvent,
    count: *mut usize,
    dropped: *mut u64,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees, for each pointer.
        let (client, events, count) = unsafe {
            (
                client_mut(client)?,
                output(events, "events")?,
                output(count, "count")?,
            )
        };
        client.taken_events.clear();
        (client.taken_events).extend(client.pending_events.drain(..));
        *events = client.taken_events.as_ptr();
        *count = client.taken_events.len();
        // SAFETY: as the caller guarantees.
        unsafe { write_optional(dropped, std::mem::take(&mut client.dropped_events)) };
        Ok(VasStatus::Ok)
    })
}
