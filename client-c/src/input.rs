//! Input samples a device sends: tracker, glove and hand joints.

use vas_protocol::{GloveSample, HandJointsSample, TrackerSample};

use crate::client::{VasClient, client_mut, millis};
use crate::pointers::input;
use crate::status::{VasStatus, guard};

/// Sends a tracker sample (hand root in the cart's frame, cart in the world) and wakes the
/// server. The sample is copied; needs the input role. The server checks it: a non-finite or
/// out-of-range value is rejected and counted there, not here.
///
/// # Safety
/// `client` is a live handle; `sample` points to a readable `VasTrackerSample`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_send_tracker(
    client: *mut VasClient,
    sample: *const TrackerSample,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees, for each pointer.
        let (client, sample) = unsafe { (client_mut(client)?, input(sample, "sample")?) };
        client.client.send_tracker(sample)?;
        Ok(VasStatus::Ok)
    })
}

/// Sends a glove sample (22 flex angles in radians, CyberGlove order) and wakes the server. The
/// sample is copied; needs the input role.
///
/// # Safety
/// `client` is a live handle; `sample` points to a readable `VasGloveSample`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_send_glove(
    client: *mut VasClient,
    sample: *const GloveSample,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees, for each pointer.
        let (client, sample) = unsafe { (client_mut(client)?, input(sample, "sample")?) };
        client.client.send_glove(sample)?;
        Ok(VasStatus::Ok)
    })
}

/// Sends one hand's 26 OpenXR joints and wakes the server. The sample is copied; needs the
/// input role.
///
/// # Safety
/// `client` is a live handle; `sample` points to a readable `VasHandJointsSample`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_send_hand_joints(
    client: *mut VasClient,
    sample: *const HandJointsSample,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees, for each pointer.
        let (client, sample) = unsafe { (client_mut(client)?, input(sample, "sample")?) };
        client.client.send_hand_joints(sample)?;
        Ok(VasStatus::Ok)
    })
}

/// Returns once the server has taken in every sample this client sent before the call (waiting
/// up to `timeout_ms`): a sent sample lives in the sender's shared memory until then, so a
/// program that sends and exits calls this before `vas_client_free`.
///
/// # Safety
/// `client` is a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn vas_client_flush_inputs(
    client: *mut VasClient,
    timeout_ms: u64,
) -> VasStatus {
    guard(|| {
        // SAFETY: as the caller guarantees.
        let client = unsafe { client_mut(client) }?;
        client.client.flush_inputs(millis(timeout_ms))?;
        Ok(VasStatus::Ok)
    })
}
