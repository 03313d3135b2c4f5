//! The `c` path of `vas-bench e2e --c-library`: B7's round trip through the C library
//! (`vas-client-c`), against the same echo as the `raw` path.
//!
//! The harness calls the library's `extern "C"` functions from Rust rather than running a C echo
//! client: they are the same compiled functions a C program links from `libvas_client`, called
//! through the same C ABI with the same arguments, so a C program would time the same machine
//! code; and calling them here lets the `c` path alternate sample by sample with the `raw` path
//! in one process (both see the same machine load), with no C compiler needed to run B7.

use std::ffi::{CStr, CString};
use std::ptr::{self, NonNull};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use vas_client::recording::InputSample;
use vas_client_c::{
    VAS_ROLE_ALL, VasClient, VasStatus, VasWake, vas_client_connect, vas_client_free,
    vas_client_latest_hands, vas_client_poll, vas_client_send_glove, vas_client_send_hand_joints,
    vas_client_send_tracker, vas_client_wait, vas_last_error_message,
};
use vas_protocol::wall_clock_ns;

/// A client of the C library: its handle, freed when dropped.
pub struct CLibraryClient {
    handle: NonNull<VasClient>,
}

impl CLibraryClient {
    /// Connects on `prefix` with every role and termination signals handled, as the `raw`
    /// path's client does.
    pub fn connect(prefix: &str) -> anyhow::Result<Self> {
        let prefix = CString::new(prefix).context("a prefix without NUL")?;
        let mut handle = ptr::null_mut();
        // SAFETY: a NUL-terminated prefix and a writable place for the handle.
        let status =
            unsafe { vas_client_connect(prefix.as_ptr(), VAS_ROLE_ALL, true, &mut handle) };
        check(status, "connect through the C library")?;
        let handle = NonNull::new(handle).context("the C library connected no client")?;
        Ok(Self { handle })
    }

    /// Sends `input` stamped now and waits for the hand frame answering it, as a C program
    /// does: send the sample, wait, poll, read the hand frames; its round trip, or `None` if
    /// none came within `timeout`. SIGINT or SIGTERM ends the benchmark.
    pub fn round_trip(
        &mut self,
        input: InputSample,
        timeout: Duration,
    ) -> anyhow::Result<Option<Duration>> {
        let client = self.handle.as_ptr();
        let input = input.with_timestamp(wall_clock_ns());
        let sent_at = Instant::now();
        // SAFETY: a live handle on this thread and a sample to read.
        let status = unsafe {
            match &input {
                InputSample::Tracker(sample) => vas_client_send_tracker(client, sample),
                InputSample::Glove(sample) => vas_client_send_glove(client, sample),
                InputSample::HandJoints(sample) => vas_client_send_hand_joints(client, sample),
            }
        };
        check(status, "send a sample through the C library")?;
        let deadline = sent_at + timeout;
        loop {
            let remaining = deadline.saturating_duration_since(Instant::now());
            if remaining.is_zero() {
                return Ok(None);
            }
            let mut wake = VasWake::Timeout;
            // Whole milliseconds, rounded up so that a wait never ends before the deadline.
            let timeout_ms = remaining.as_micros().div_ceil(1000) as u64;
            // SAFETY: a live handle on this thread and a writable wake.
            let status = unsafe { vas_client_wait(client, timeout_ms, &mut wake) };
            check(status, "wait through the C library")?;
            match wake {
                VasWake::Ready => {}
                VasWake::Timeout => return Ok(None),
                VasWake::Terminated => bail!("interrupted"),
            }
            // SAFETY: a live handle on this thread; the counts are not wanted.
            let status = unsafe { vas_client_poll(client, ptr::null_mut()) };
            check(status, "poll through the C library")?;
            let (mut hands, mut count) = (ptr::null(), 0);
            // SAFETY: a live handle on this thread and writable places for the frames.
            let status = unsafe { vas_client_latest_hands(client, &mut hands, &mut count) };
            check(status, "read the hand frames through the C library")?;
            let hands = match count {
                0 => &[][..],
                // SAFETY: `count` frames at `hands`, valid until the next poll.
                _ => unsafe { std::slice::from_raw_parts(hands, count) },
            };
            if hands.iter().any(|hand| input.is_answered_by(hand)) {
                return Ok(Some(sent_at.elapsed()));
            }
        }
    }
}

impl Drop for CLibraryClient {
    fn drop(&mut self) {
        // SAFETY: the handle came from `vas_client_connect` on this thread and is freed once.
        unsafe { vas_client_free(self.handle.as_ptr()) };
    }
}

/// An error for a failed `action`, with the library's message, unless `status` is a success.
fn check(status: VasStatus, action: &str) -> anyhow::Result<()> {
    if matches!(status, VasStatus::Ok | VasStatus::Empty) {
        return Ok(());
    }
    // SAFETY: the library's message of this thread's last error, never null.
    let message = unsafe { CStr::from_ptr(vas_last_error_message()) };
    bail!("cannot {action}: {status:?}: {}", message.to_string_lossy())
}
