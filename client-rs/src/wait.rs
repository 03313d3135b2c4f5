//! Waiting for data on a WaitSet: the readers' side of the event services paired with each
//! publish-subscribe service.

use std::time::{Duration, Instant};

use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::*;
use iceoryx2::waitset::WaitSetRunResult;

use crate::ClientError;

/// How a wait ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wake {
    /// New data is ready to be received.
    Ready,
    /// The timeout passed without new data.
    Timeout,
    /// SIGINT or SIGTERM arrived (only reported when termination signals are handled, see
    /// [`crate::ClientBuilder::handle_termination_signals`]).
    Terminated,
}

/// Waits until `ready` says data is there, the timeout passes, or a termination signal arrives.
///
/// `ready` is asked before every sleep, so data that arrived before the call (or whose
/// notification was lost) is never missed; the listeners are attached only for the sleep and
/// drained after it, so that a notification wakes the WaitSet once.
pub(crate) fn wait_until_ready(
    waitset: &WaitSet<ipc::Service>,
    listeners: &[&Listener<ipc::Service>],
    timeout: Duration,
    mut ready: impl FnMut() -> Result<bool, ClientError>,
) -> Result<Wake, ClientError> {
    let deadline = deadline_after(timeout);
    loop {
        if ready()? {
            return Ok(Wake::Ready);
        }
        let remaining = deadline.saturating_duration_since(Instant::now());
        if remaining.is_zero() {
            return Ok(Wake::Timeout);
        }
        let guards = listeners
            .iter()
            .map(|listener| waitset.attach_notification(*listener))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|error| ClientError::ipc("attach a listener to the WaitSet", error))?;
        let outcome = waitset
            .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, remaining)
            .map_err(|error| ClientError::ipc("wait on the WaitSet", error))?;
        drop(guards);
        empty_listeners(listeners)?;
        if outcome == WaitSetRunResult::TerminationRequest {
            return Ok(Wake::Terminated);
        }
    }
}

/// Takes every notification the `listeners` hold, without blocking: afterwards their file
/// descriptors are not readable until a notifier wakes them again.
pub(crate) fn empty_listeners(listeners: &[&Listener<ipc::Service>]) -> Result<(), ClientError> {
    for listener in listeners {
        listener
            .try_wait(|_| {})
            .map_err(|error| ClientError::ipc("drain a listener", error))?;
    }
    Ok(())
}

/// The instant `timeout` from now; a timeout too long to represent (such as `Duration::MAX`,
/// "wait forever") ends a century from now instead of overflowing.
pub(crate) fn deadline_after(timeout: Duration) -> Instant {
    const CENTURY: Duration = Duration::from_secs(100 * 365 * 24 * 3600);
    let now = Instant::now();
    now.checked_add(timeout.min(CENTURY)).unwrap_or(now)
}

/// Creates a WaitSet that reports termination signals or leaves them alone.
pub(crate) fn new_waitset(handle_signals: bool) -> Result<WaitSet<ipc::Service>, ClientError> {
    WaitSetBuilder::new()
        .signal_handling_mode(signal_mode(handle_signals))
        .create::<ipc::Service>()
        .map_err(|error| ClientError::ipc("create a WaitSet", error))
}

/// The iceoryx2 signal handling mode for the choice "handle termination signals".
pub(crate) fn signal_mode(handle_signals: bool) -> SignalHandlingMode {
    if handle_signals {
        SignalHandlingMode::HandleTerminationRequests
    } else {
        SignalHandlingMode::Disabled
    }
}
