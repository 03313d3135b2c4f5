//! The clearance stage's thread, beside the loops: it measures each published frame's part
//! poses ([`ClearanceStage`]) and hands the pairs below the threshold and their events back to
//! the I/O thread, which publishes them on `vas/output/clearance` and `vas/output/events`.
//!
//! Why a thread of its own, fed after publication: the loops never wait for it, so a slow
//! measurement can only make clearance late, never a pose. The I/O thread hands it a frame once
//! that frame's parts, events and hand are out; the thread measures while the collision loop
//! verifies the next one. A frame's report carries the number of the parts frame it measured.
//! When the next frame is already waiting, the stage stops between pairs (the pairs left keep
//! their last reading, flagged stale, and go first next time), and a frame that finds the next
//! one already waiting is reported all stale without a query, so that the reports keep up with
//! the frames however slow one query is, and every frame gets one. The thread runs at the normal priority even when the
//! loops run under `SCHED_FIFO`: it takes only the time they leave.
//!
//! In lockstep it measures every pair of every frame (no deadline), and the I/O thread hands the
//! loops the next sample's frame only after this frame's report is published, so that a replay
//! gives the same clearance frames and events every time; the frame itself is still published
//! before it is measured.

use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, Sender, TryRecvError};
use nalgebra::Isometry3;
use vas_protocol::{
    CLEARANCE_STALE, ClearanceFrame, ClearancePair, EventKind, HandSide, MAX_CLEARANCE_PAIRS,
    SimEvent, wall_clock_ns,
};

use super::RuntimeError;
use super::meter::LoopMeter;
use super::ports::Ports;
use super::wakeup::Waker;
use crate::grasping::PartId;
use crate::scene::Scene;
use crate::simulation::clearance::{
    ClearanceKind, ClearanceOutcome, ClearanceReading, ClearanceStage,
};
use crate::simulation::frames::Stamps;

/// A published frame to measure.
pub(super) struct ClearanceJob {
    /// The restart the frame belongs to.
    pub(super) epoch: u64,
    /// The parts frame that published the poses (the latest one, if they did not change).
    pub(super) parts_frame: u64,
    /// The hand frame published with them: the clearance events' frame.
    pub(super) hand_frame: u64,
    /// The samples the frame answers.
    pub(super) stamps: Stamps,
    /// Every part's pose, by id.
    pub(super) poses: Vec<Isometry3<f64>>,
    /// The grasped parts.
    pub(super) held: Vec<PartId>,
}

/// A measured frame, for the I/O thread to publish.
pub(super) struct ClearanceReport {
    parts_frame: u64,
    hand_frame: u64,
    stamps: Stamps,
    threshold: f64,
    /// `None` when the frame was not measured (its restart is over, or the scene has no
    /// threshold): nothing is published for it.
    outcome: Option<ClearanceOutcome>,
}

enum Work {
    Restart { scene: Arc<Scene>, epoch: u64 },
    Frame(ClearanceJob),
}

/// The I/O thread's end of the clearance thread.
pub(super) struct ClearanceWatch {
    jobs: Sender<Work>,
    reports: Receiver<ClearanceReport>,
    /// Whether the served scene has a threshold: frames are handed over only then.
    active: bool,
    /// Frames handed over whose reports have not been taken.
    pending: usize,
    /// Ends when `jobs` is dropped; joined on drop, so that it logs its last window.
    thread: Option<JoinHandle<()>>,
}

/// How long a dropped [`ClearanceWatch`] waits for its thread to log and end.
const JOIN_PATIENCE: Duration = Duration::from_millis(500);

impl Drop for ClearanceWatch {
    /// Closes the thread's inbox and waits for it (for at most [`JOIN_PATIENCE`]: a thread
    /// still in a long first query is left behind; it holds no shared memory).
    fn drop(&mut self) {
        drop(std::mem::replace(
            &mut self.jobs,
            crossbeam_channel::bounded(0).0,
        ));
        let deadline = Instant::now() + JOIN_PATIENCE;
        if let Some(thread) = self.thread.take() {
            while !thread.is_finished() && Instant::now() < deadline {
                std::thread::sleep(Duration::from_millis(5));
            }
            if thread.is_finished() && thread.join().is_err() {
                tracing::error!("the clearance stage ended by panicking");
            }
        }
    }
}

impl ClearanceWatch {
    /// Starts the thread; it wakes the I/O thread with `waker` after each report.
    pub(super) fn spawn(waker: Waker, lockstep: bool) -> std::io::Result<ClearanceWatch> {
        let (jobs, inbox) = crossbeam_channel::unbounded();
        let (outbox, reports) = crossbeam_channel::unbounded();
        let thread = std::thread::Builder::new()
            .name("clearance".into())
            .spawn(move || run(&inbox, &outbox, &waker, lockstep))?;
        Ok(ClearanceWatch {
            jobs,
            reports,
            active: false,
            pending: 0,
            thread: Some(thread),
        })
    }

    /// Starts over on `scene` (restart `epoch`): watched when it has a threshold.
    pub(super) fn restart(&mut self, scene: &Arc<Scene>, epoch: u64) {
        self.active = scene.params.clearance.threshold.is_some();
        let scene = Arc::clone(scene);
        if self.jobs.send(Work::Restart { scene, epoch }).is_err() {
            self.lost();
        }
    }

    /// Hands a published frame over to be measured; false when the scene is not watched.
    pub(super) fn hand(&mut self, job: ClearanceJob) -> bool {
        if !self.active {
            return false;
        }
        if self.jobs.send(Work::Frame(job)).is_err() {
            self.lost();
            return false;
        }
        self.pending += 1;
        true
    }

    /// A report that came back, if any.
    pub(super) fn take(&mut self) -> Option<ClearanceReport> {
        match self.reports.try_recv() {
            Ok(report) => {
                self.pending = self.pending.saturating_sub(1);
                Some(report)
            }
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => {
                self.lost();
                None
            }
        }
    }

    /// True while a frame handed over has not been reported.
    pub(super) fn is_pending(&self) -> bool {
        self.pending > 0
    }

    /// The thread ended (it panicked; the log says where): the server goes on without the
    /// watch rather than waiting for reports that will not come.
    fn lost(&mut self) {
        if self.active || self.pending > 0 {
            tracing::error!("the clearance stage ended; clearance is no longer reported");
        }
        self.active = false;
        self.pending = 0;
    }
}

/// The thread: measures each frame handed over and reports it, until the I/O thread's end is
/// dropped. Free-running, a frame is measured until the next one waits; in lockstep, fully.
fn run(inbox: &Receiver<Work>, outbox: &Sender<ClearanceReport>, waker: &Waker, lockstep: bool) {
    let mut meter = LoopMeter::new("clearance");
    let (mut stage, mut epoch) = (None::<ClearanceStage>, 0);
    while let Ok(work) = inbox.recv() {
        match work {
            Work::Restart { scene, epoch: next } => {
                meter.log();
                stage = ClearanceStage::new(scene);
                epoch = next;
            }
            Work::Frame(job) => {
                let started = Instant::now();
                let measured = stage.as_mut().filter(|_| job.epoch == epoch);
                let threshold = measured.as_ref().map_or(0.0, |stage| stage.threshold());
                // A frame that finds the next one waiting is not measured at all: one slow pair
                // (a peg deep in its hole) must not let the frames pile up behind it.
                let outcome = measured.map(|stage| {
                    if lockstep || inbox.is_empty() {
                        stage.measure(&job.poses, &job.held, || lockstep || inbox.is_empty())
                    } else {
                        stage.unmeasured()
                    }
                });
                if outcome.is_some() {
                    meter.frame_done(started);
                }
                let report = ClearanceReport {
                    parts_frame: job.parts_frame,
                    hand_frame: job.hand_frame,
                    stamps: job.stamps,
                    threshold,
                    outcome,
                };
                if outbox.send(report).is_err() {
                    break;
                }
                waker.wake();
            }
        }
    }
    meter.log();
}

/// Publishes a report: its clearance frame, then its events.
pub(super) fn publish(ports: &Ports, report: &ClearanceReport) -> Result<(), RuntimeError> {
    let Some(outcome) = &report.outcome else {
        return Ok(());
    };
    let stamps = report.stamps;
    let now = wall_clock_ns();
    let listed = outcome.below.len().min(MAX_CLEARANCE_PAIRS);
    let mut frame = ClearanceFrame {
        frame: report.parts_frame,
        tracker: stamps.tracker,
        glove: stamps.glove,
        joints: stamps.joints,
        timestamp_ns: now,
        threshold: report.threshold,
        pair_count: listed as u32,
        more: u32::try_from(outcome.below.len() - listed).unwrap_or(u32::MAX),
        ..ClearanceFrame::default()
    };
    for (slot, reading) in frame.pairs.iter_mut().zip(&outcome.below) {
        *slot = wire_pair(reading);
    }
    ports.publish_clearance(&frame)?;
    ports.publish_events(outcome.events.iter().map(|event| {
        let kind = match event.kind {
            ClearanceKind::Below => EventKind::ClearanceBelow,
            ClearanceKind::Restored => EventKind::ClearanceRestored,
        };
        let reading = &event.reading;
        SimEvent {
            frame: report.hand_frame,
            tracker: stamps.tracker,
            glove: stamps.glove,
            joints: stamps.joints,
            timestamp_ns: now,
            kind: kind as u32,
            grasp_type: 0,
            part: reading.part,
            other: reading.other,
            hand: HandSide::Right as u32,
            segment: 0,
            user: 0,
            reserved: 0,
            point: reading.point.into(),
            normal: [0.0; 3],
            other_point: reading.other_point.into(),
            distance: reading.distance,
        }
    }))
}

fn wire_pair(reading: &ClearanceReading) -> ClearancePair {
    ClearancePair {
        part: reading.part,
        other: reading.other,
        triangles: reading.triangles,
        flags: if reading.stale { CLEARANCE_STALE } else { 0 },
        reserved: 0,
        distance: reading.distance,
        point: reading.point.into(),
        other_point: reading.other_point.into(),
    }
}
