//! `vas-bench echo` (hidden): answers every tracker, glove and hand-joints sample at once with a
//! hand frame carrying its stamp (and, for joints, its hand's side), with no simulation in
//! between.
//!
//! It opens the very services a server opens (same payloads, quality of service and paired
//! event services) and sleeps on a WaitSet as the server does, so that a client measures the
//! bare iceoryx2 round trip against it. `vas-bench e2e` starts one in a child process on a
//! private prefix.

use std::io::Write;
use std::time::Duration;

use anyhow::{Context, anyhow};
use iceoryx2::prelude::*;
use iceoryx2::waitset::WaitSetRunResult;
use vas_protocol::services::{self, GLOVE, HAND, HAND_JOINTS, TRACKER, config_with_prefix};
use vas_protocol::{HandFrame, wall_clock_ns};

/// The line the echo prints on stdout once its ports exist, so that a parent knows samples
/// sent from then on are answered.
pub const READY_LINE: &str = "echo ready";

/// How often the echo checks that the process that started it still runs; it ends with it.
const PARENT_CHECK: Duration = Duration::from_millis(500);

/// An iceoryx2 failure while doing `action`.
fn ipc(action: &'static str, error: impl std::fmt::Debug) -> anyhow::Error {
    anyhow!("cannot {action}: {error:?}")
}

/// Serves until SIGINT or SIGTERM, or until its parent process ends.
pub fn run(prefix: Option<&str>) -> anyhow::Result<()> {
    let config = config_with_prefix(prefix)?;
    let name = NodeName::new("vas-echo").map_err(|e| ipc("name the node", e))?;
    let node = NodeBuilder::new()
        .name(&name)
        .config(&config)
        .signal_handling_mode(SignalHandlingMode::HandleTerminationRequests)
        .create::<ipc::Service>()
        .map_err(|e| ipc("create the node", e))?;
    let tracker = services::open_tracker(&node)?
        .subscriber_builder()
        .create()
        .map_err(|e| ipc("create a port", e))?;
    let glove = services::open_glove(&node)?
        .subscriber_builder()
        .create()
        .map_err(|e| ipc("create a port", e))?;
    let hand_joints = services::open_hand_joints(&node)?
        .subscriber_builder()
        .create()
        .map_err(|e| ipc("create a port", e))?;
    let hand = services::open_hand(&node)?
        .publisher_builder()
        .create()
        .map_err(|e| ipc("create a port", e))?;
    let listener = |service| -> anyhow::Result<_> {
        services::open_wakeup(&node, service)?
            .listener_builder()
            .create()
            .map_err(|e| ipc("create a port", e))
    };
    let tracker_wakeup = listener(TRACKER)?;
    let glove_wakeup = listener(GLOVE)?;
    let hand_joints_wakeup = listener(HAND_JOINTS)?;
    let hand_notifier = services::open_wakeup(&node, HAND)?
        .notifier_builder()
        .create()
        .map_err(|e| ipc("create a port", e))?;

    let waitset = WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::HandleTerminationRequests)
        .create::<ipc::Service>()
        .map_err(|e| ipc("create the WaitSet", e))?;
    let _tracker_guard = waitset
        .attach_notification(&tracker_wakeup)
        .map_err(|e| ipc("attach to the WaitSet", e))?;
    let _glove_guard = waitset
        .attach_notification(&glove_wakeup)
        .map_err(|e| ipc("attach to the WaitSet", e))?;
    let _hand_joints_guard = waitset
        .attach_notification(&hand_joints_wakeup)
        .map_err(|e| ipc("attach to the WaitSet", e))?;
    let _parent_guard = waitset
        .attach_interval(PARENT_CHECK)
        .map_err(|e| ipc("attach to the WaitSet", e))?;
    let parent = std::os::unix::process::parent_id();

    let mut out = std::io::stdout().lock();
    writeln!(out, "{READY_LINE}")
        .and_then(|()| out.flush())
        .context("announcing readiness")?;
    drop(out);

    let mut frame = HandFrame::default();
    let answer = |frame: &mut HandFrame| -> anyhow::Result<()> {
        frame.frame += 1;
        frame.timestamp_ns = wall_clock_ns();
        hand.send_copy(*frame)
            .map_err(|e| ipc("send a hand frame", e))?;
        hand_notifier
            .notify()
            .map_err(|e| ipc("notify hand readers", e))?;
        Ok(())
    };
    loop {
        let outcome = waitset
            .wait_and_process_once(|_| CallbackProgression::Continue)
            .map_err(|e| ipc("wait on the WaitSet", e))?;
        if outcome == WaitSetRunResult::TerminationRequest
            || std::os::unix::process::parent_id() != parent
        {
            return Ok(());
        }
        for wakeup in [&tracker_wakeup, &glove_wakeup, &hand_joints_wakeup] {
            wakeup
                .try_wait(|_| {})
                .map_err(|e| ipc("drain a listener", e))?;
        }
        while let Some(sample) = tracker
            .receive()
            .map_err(|e| ipc("receive a tracker sample", e))?
        {
            frame.tracker = sample.stamp();
            frame.root = sample.hand;
            answer(&mut frame)?;
        }
        while let Some(sample) = glove
            .receive()
            .map_err(|e| ipc("receive a glove sample", e))?
        {
            frame.glove = sample.stamp();
            frame.flex = sample.flex;
            answer(&mut frame)?;
        }
        while let Some(sample) = hand_joints
            .receive()
            .map_err(|e| ipc("receive a hand-joints sample", e))?
        {
            frame.joints = sample.stamp();
            frame.hand = sample.side;
            answer(&mut frame)?;
        }
    }
}
