//! The grasping, sliding and collision detection loops: each on its own thread, meeting the
//! others only at the hand-offs of [`super::rendezvous`] (the paper's Figure 7).
//!
//! ```text
//! I/O ─InputFrame─> grasping ─GraspedFrame─> sliding ─CandidateFrame─> collision ─VerifiedFrame─> I/O
//!                      ▲                        ▲                          │
//!                      └── verified part poses ─┴── refused part poses ────┘
//! ```
//!
//! Free-running, a loop processes the newest frame it was handed and, between inputs, goes on at
//! its own rate while it has work left: the grasping hand towards a target it has not reached,
//! the held part towards a ghost its last sliding frame ran out of cycles for. In lockstep a loop
//! does exactly one step per frame it is handed and nothing else, so that the outcome depends on
//! the inputs only.

use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, Sender};
use nalgebra::Isometry3;

use super::meter::LoopMeter;
use super::priority::RealtimePriority;
use super::rendezvous::{AwakeWatch, Coalesce, Handoff, Received, Work};
use super::wakeup::Waker;
use crate::grasping::{HandInput, PartId};
use crate::scene::Scene;
use crate::simulation::frames::{
    CandidateFrame, GraspedFrame, GraspedHand, HeldPart, InputFrame, ProposedHand, Stamps,
    VerifiedFrame, wire_grasp,
};
use crate::simulation::grasp_stage::{GraspStage, SteppedHand};
use crate::simulation::restart::Change;
use crate::simulation::slide_stage::SlideStage;
use crate::simulation::verify::Verifier;

/// An item for a loop: a frame, or a change of the simulation between frames.
pub type LoopWork<F> = Work<F, Change>;

/// The verified part poses of the latest frame, for the grasping loop, tagged with the restart
/// they belong to.
#[derive(Default)]
pub struct PoseFeedback {
    latest: Mutex<(u64, Vec<Isometry3<f64>>)>,
}

impl PoseFeedback {
    fn publish(&self, epoch: u64, poses: Vec<Isometry3<f64>>) {
        *self.latest.lock().unwrap_or_else(PoisonError::into_inner) = (epoch, poses);
    }

    /// The poses, if they belong to restart `epoch`.
    fn read(&self, epoch: u64) -> Option<Vec<Isometry3<f64>>> {
        let latest = self.latest.lock().unwrap_or_else(PoisonError::into_inner);
        (latest.0 == epoch).then(|| latest.1.clone())
    }
}

/// A part the collision loop put back, for the sliding loop.
#[derive(Debug, Clone, Copy)]
pub struct Refusal {
    epoch: u64,
    part: PartId,
    pose: Isometry3<f64>,
}

/// The hand-offs and feedback that connect the loops.
pub struct Links {
    /// I/O → grasping.
    pub inputs: Arc<Handoff<InputFrame, Change>>,
    grasped: Arc<Handoff<GraspedFrame, Change>>,
    candidates: Arc<Handoff<CandidateFrame, Change>>,
    /// Whether the I/O thread waits awake for verified frames.
    pub io_watch: Arc<AwakeWatch>,
    feedback: Arc<PoseFeedback>,
    refusals: (Sender<Refusal>, Receiver<Refusal>),
}

impl Default for Links {
    fn default() -> Self {
        Links {
            inputs: Arc::default(),
            grasped: Arc::default(),
            candidates: Arc::default(),
            io_watch: Arc::default(),
            feedback: Arc::default(),
            refusals: crossbeam_channel::unbounded(),
        }
    }
}

/// The three loop threads.
pub struct Loops {
    threads: Vec<JoinHandle<()>>,
}

impl Loops {
    /// Starts the loops, in lockstep or not and at the realtime priority given, if any; verified
    /// frames go to `verified`, and the collision loop wakes the I/O thread with `waker` after
    /// each frame the I/O thread is not waiting for awake, so that it notices.
    pub fn spawn(
        links: &Links,
        lockstep: bool,
        realtime: Option<RealtimePriority>,
        verified: Sender<VerifiedFrame>,
        waker: Waker,
    ) -> std::io::Result<Loops> {
        let grasping = GraspingLoop {
            inbox: Arc::clone(&links.inputs),
            outbox: Arc::clone(&links.grasped),
            feedback: Arc::clone(&links.feedback),
            lockstep,
            stage: None,
            epoch: 0,
            period: Duration::ZERO,
            last: None,
            stepped_at: Instant::now(),
        };
        let sliding = SlidingLoop {
            inbox: Arc::clone(&links.grasped),
            outbox: Arc::clone(&links.candidates),
            refusals: links.refusals.1.clone(),
            lockstep,
            stage: None,
            epoch: 0,
            period: Duration::ZERO,
            last: None,
            slid_at: Instant::now(),
        };
        let collision = CollisionLoop {
            inbox: Arc::clone(&links.candidates),
            verified,
            io_watch: Arc::clone(&links.io_watch),
            waker,
            feedback: Arc::clone(&links.feedback),
            refusals: links.refusals.0.clone(),
            verifier: None,
            epoch: 0,
        };
        // Each thread raises itself to the realtime priority, if one is given.
        let raise = move || {
            if let Some(priority) = realtime
                && let Err(error) = priority.raise_this_thread()
            {
                tracing::error!(%error, "this loop stays at the normal priority");
            }
        };
        let spawn = |name: &str, body: Box<dyn FnOnce() + Send>| {
            std::thread::Builder::new()
                .name(name.into())
                .spawn(move || {
                    raise();
                    body();
                })
        };
        // The collision pipeline runs its back end on the current rayon pool. Here it gets a pool
        // of one thread, so it tests sequentially: a frame moves a handful of objects, and the
        // pool's idle workers spin and yield for a while after each parallel stage, taking the
        // cores the other loops need. The loops themselves are the parallelism.
        let sequential = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .thread_name(|_| "collision".into())
            .build()
            .map_err(std::io::Error::other)?;
        Ok(Loops {
            threads: vec![
                spawn("grasping", Box::new(move || grasping.run()))?,
                spawn("sliding", Box::new(move || sliding.run()))?,
                // The collision loop runs on its pool's thread, which raises itself too.
                spawn(
                    "collision-pool",
                    Box::new(move || {
                        sequential.install(move || {
                            raise();
                            collision.run();
                        });
                    }),
                )?,
            ],
        })
    }

    /// True when a loop has ended (it panicked: loops end only after the inputs close).
    pub fn any_ended(&self) -> bool {
        self.threads.iter().any(JoinHandle::is_finished)
    }

    /// Waits for every loop to end (close the inputs first), for at most `patience`: a loop
    /// busy building a large part's tree or hull on its first frame is left behind (the process
    /// is ending, and loops hold no shared memory), so that a
    /// termination request is honoured within a second whatever the loops are doing.
    pub fn join(self, patience: Duration) {
        let deadline = Instant::now() + patience;
        while self.threads.iter().any(|thread| !thread.is_finished()) {
            if Instant::now() >= deadline {
                tracing::warn!("a loop is still preparing the scene; leaving it");
                return;
            }
            std::thread::sleep(JOIN_POLL);
        }
        for thread in self.threads {
            let name = thread.thread().name().unwrap_or("loop").to_owned();
            if thread.join().is_err() {
                tracing::error!(thread = name, "a loop ended by panicking");
            }
        }
    }
}

/// How often [`Loops::join`] looks whether the loops have ended.
const JOIN_POLL: Duration = Duration::from_millis(10);

/// The period of a loop rate (validated by the scene: positive and finite).
fn period(hz: f64) -> Duration {
    Duration::try_from_secs_f64(1.0 / hz).unwrap_or(Duration::from_millis(10))
}

/// A loop that goes on at its own pace between inputs, as the grasping and sliding loops do:
/// what it does with a frame, with a change, and when its time to go on comes.
/// [`run_at_own_pace`] drives it.
trait OwnPace {
    /// What the loop is handed.
    type Frame: Coalesce;
    /// When to go on without new input; `None` waits for input.
    fn wake_at(&self) -> Option<Instant>;
    /// Processes a frame handed over.
    fn take_frame(&mut self, frame: Self::Frame);
    /// Applies a change handed over, between frames.
    fn take_change(&mut self, change: Change);
    /// Goes on without new input; false when there was nothing to do.
    fn go_on(&mut self) -> bool;
}

/// Runs `stage` on what `inbox` hands it until the inbox is closed, timing each frame on the
/// meter named `name` (a restart ends the meter's window).
fn run_at_own_pace<L: OwnPace>(
    name: &'static str,
    inbox: &Handoff<L::Frame, Change>,
    stage: &mut L,
) {
    let mut meter = LoopMeter::new(name);
    loop {
        let received = inbox.receive(stage.wake_at());
        let started = Instant::now();
        let stepped = match received {
            Received::Work(Work::Frame(frame)) => {
                stage.take_frame(frame);
                true
            }
            Received::Work(Work::Control(change)) => {
                let restart = matches!(change, Change::Restart(_));
                stage.take_change(change);
                if restart {
                    meter.log();
                }
                false
            }
            Received::Timeout => stage.go_on(),
            Received::Closed => break,
        };
        if stepped {
            meter.frame_done(started);
        }
    }
    meter.log();
}

impl OwnPace for GraspingLoop {
    type Frame = InputFrame;

    fn wake_at(&self) -> Option<Instant> {
        match &self.last {
            Some((_, true)) if !self.lockstep => Some(self.stepped_at + self.period),
            _ => None,
        }
    }

    fn take_frame(&mut self, input: InputFrame) {
        self.step(input);
    }

    fn take_change(&mut self, change: Change) {
        self.apply(change);
    }

    /// Steps the hands towards the latest targets again.
    fn go_on(&mut self) -> bool {
        let Some((input, _)) = &self.last else {
            return false;
        };
        let input = input.clone();
        self.step(input);
        true
    }
}

impl OwnPace for SlidingLoop {
    type Frame = GraspedFrame;

    fn wake_at(&self) -> Option<Instant> {
        match &self.last {
            Some((_, _, true)) if !self.lockstep => Some(self.slid_at + self.period),
            _ => None,
        }
    }

    fn take_frame(&mut self, frame: GraspedFrame) {
        self.slide(frame);
    }

    fn take_change(&mut self, change: Change) {
        self.apply(change);
    }

    fn go_on(&mut self) -> bool {
        self.keep_sliding();
        true
    }
}

struct GraspingLoop {
    inbox: Arc<Handoff<InputFrame, Change>>,
    outbox: Arc<Handoff<GraspedFrame, Change>>,
    feedback: Arc<PoseFeedback>,
    lockstep: bool,
    /// The hands among the parts (none in a scene without a hand model); `None` before the
    /// first restart.
    stage: Option<GraspStage>,
    epoch: u64,
    period: Duration,
    /// The latest targets and whether a hand has not reached its target yet.
    last: Option<(InputFrame, bool)>,
    stepped_at: Instant,
}

impl GraspingLoop {
    fn run(mut self) {
        let inbox = Arc::clone(&self.inbox);
        run_at_own_pace("grasping", &inbox, &mut self);
        self.outbox.close();
    }

    fn apply(&mut self, mut change: Change) {
        if let Change::Restart(restart) = &mut change {
            let hands = std::mem::take(&mut restart.hands);
            self.stage = Some(GraspStage::new(hands, &restart.scene.parts));
            self.epoch = restart.epoch;
            self.period = period(restart.scene.rates.grasping_hz);
            self.last = None;
        }
        self.outbox.send(Work::Control(change));
    }

    fn step(&mut self, input: InputFrame) {
        self.outbox.announce();
        self.stepped_at = Instant::now();
        let mut stepped = match &mut self.stage {
            Some(stage) => {
                if let Some(poses) = self.feedback.read(self.epoch) {
                    stage.set_part_poses(&poses);
                }
                stage.step(&input.hands)
            }
            None => Vec::new(),
        }
        .into_iter();
        let hands: Vec<GraspedHand> = (input.hands.iter())
            .map(|&target| match stepped.next() {
                Some(SteppedHand { frame, handed_over }) => GraspedHand {
                    target,
                    frame: Some(frame),
                    handed_over,
                },
                None => GraspedHand {
                    target,
                    frame: None,
                    handed_over: Vec::new(),
                },
            })
            .collect();
        let unreached = hands.iter().any(|hand| {
            (hand.frame.as_ref()).is_some_and(|frame| !reached(&frame.pose, &hand.target.input))
        });
        self.outbox.send(Work::Frame(GraspedFrame {
            stamps: input.stamps,
            hands,
        }));
        self.last = Some((input, unreached));
    }
}

/// True when the visible hand is at the target (to a micrometre and a microradian).
fn reached(pose: &crate::grasping::HandPose, input: &HandInput) -> bool {
    let target = input.cart * input.tracker;
    (pose.root.translation.vector - target.translation.vector).norm() < 1e-6
        && pose.root.rotation.angle_to(&target.rotation) < 1e-6
        && pose
            .flex
            .iter()
            .zip(&input.flex)
            .all(|(a, b)| (a - f64::from(*b)).abs() < 1e-6)
}

struct SlidingLoop {
    inbox: Arc<Handoff<GraspedFrame, Change>>,
    outbox: Arc<Handoff<CandidateFrame, Change>>,
    refusals: Receiver<Refusal>,
    lockstep: bool,
    stage: Option<SlideStage>,
    epoch: u64,
    period: Duration,
    /// The latest frame's stamps and hands (their roots the tracked ones, their events taken),
    /// and whether a held part has sliding left to do.
    last: Option<(Stamps, Vec<ProposedHand>, bool)>,
    slid_at: Instant,
}

impl SlidingLoop {
    fn run(mut self) {
        let inbox = Arc::clone(&self.inbox);
        run_at_own_pace("sliding", &inbox, &mut self);
        self.outbox.close();
    }

    fn apply(&mut self, change: Change) {
        match &change {
            Change::Restart(restart) => {
                let scene: &Scene = &restart.scene;
                self.period = period(scene.rates.sliding_hz);
                self.stage = Some(SlideStage::new(
                    &scene.parts,
                    scene.params.sliding.clone(),
                    scene.params.unheld(),
                    self.period.as_secs_f64(),
                    scene.hands.len(),
                ));
                self.epoch = restart.epoch;
                self.last = None;
            }
            Change::SlidingMetaphor(metaphor) => {
                if let Some(stage) = &mut self.stage {
                    stage.set_metaphor(*metaphor);
                }
            }
        }
        self.outbox.send(Work::Control(change));
    }

    /// Puts refused parts back where the collision loop verified them.
    fn take_refusals(&mut self) {
        while let Ok(refusal) = self.refusals.try_recv() {
            if let Some(stage) = self.stage.as_mut().filter(|_| refusal.epoch == self.epoch) {
                stage.restore(refusal.part, refusal.pose);
            }
        }
    }

    fn slide(&mut self, frame: GraspedFrame) {
        self.take_refusals();
        let Some(stage) = &mut self.stage else {
            return;
        };
        self.outbox.announce();
        self.slid_at = Instant::now();
        let frames: Vec<&crate::grasping::HandStep> = frame
            .hands
            .iter()
            .filter_map(|hand| hand.frame.as_ref())
            .collect();
        let mut held = stage.apply(&frames).into_iter();
        let mut hand_index = 0..;
        let hands: Vec<ProposedHand> = (frame.hands.into_iter())
            .map(|hand| {
                let target = hand.target;
                match hand.frame {
                    Some(hand_frame) => ProposedHand {
                        pushing: (hand_index.next())
                            .map_or_else(Vec::new, |index| stage.pushed_by(index).to_vec()),
                        root: hand_frame.pose.root,
                        flex: hand_frame.pose.flex.map(|v| v as f32),
                        touching: hand_frame.touching.to_vec(),
                        grasp: wire_grasp(hand_frame.grasp),
                        tracked: target.tracked,
                        joints: target.joints,
                        held: held.next().flatten(),
                        events: hand_frame.events,
                        handed_over: hand.handed_over,
                    },
                    None => ProposedHand {
                        root: target.input.cart * target.input.tracker,
                        flex: target.input.flex,
                        touching: Vec::new(),
                        grasp: wire_grasp(None),
                        tracked: target.tracked,
                        joints: target.joints,
                        held: None,
                        pushing: Vec::new(),
                        events: Vec::new(),
                        handed_over: Vec::new(),
                    },
                }
            })
            .collect();
        let part_poses = stage.part_poses().to_vec();
        let unheld_moving = stage.has_motion_left();
        self.remember(frame.stamps, &hands, unheld_moving);
        let candidate = CandidateFrame {
            stamps: frame.stamps,
            epoch: self.epoch,
            hands: hands.into_iter().map(holding).collect(),
            part_poses,
        };
        self.outbox.send(Work::Frame(candidate));
    }

    /// Keeps the latest hands to go on sliding from: their tracked roots and held parts, their
    /// events taken (they are sent once); `unheld_moving` when a part no hand holds moves on
    /// without input (settling).
    fn remember(&mut self, stamps: Stamps, hands: &[ProposedHand], unheld_moving: bool) {
        let more = unheld_moving
            || hands
                .iter()
                .any(|hand| hand.held.as_ref().is_some_and(HeldPart::has_sliding_left));
        let hands = hands
            .iter()
            .map(|hand| ProposedHand {
                events: Vec::new(),
                handed_over: Vec::new(),
                ..hand.clone()
            })
            .collect();
        self.last = Some((stamps, hands, more));
    }

    /// Another sliding frame towards the latest ghosts, between inputs; a hand whose part came
    /// to rest keeps it where it is.
    fn keep_sliding(&mut self) {
        self.take_refusals();
        let (Some(stage), Some((stamps, hands, _))) = (&mut self.stage, &self.last) else {
            return;
        };
        self.outbox.announce();
        self.slid_at = Instant::now();
        let mut slid = stage.keep_sliding().into_iter();
        let hands: Vec<ProposedHand> = hands
            .iter()
            .map(|hand| ProposedHand {
                held: slid.next().flatten().or_else(|| hand.held.clone()),
                ..hand.clone()
            })
            .collect();
        let stamps = *stamps;
        let part_poses = stage.part_poses().to_vec();
        let unheld_moving = stage.has_motion_left();
        self.remember(stamps, &hands, unheld_moving);
        self.outbox.send(Work::Frame(CandidateFrame {
            stamps,
            epoch: self.epoch,
            hands: hands.into_iter().map(holding).collect(),
            part_poses,
        }));
    }
}

/// The hand as published: while it holds a part, where it keeps its grip on the part's visible
/// pose.
fn holding(mut hand: ProposedHand) -> ProposedHand {
    if let Some(held) = &hand.held {
        hand.root = held.hand_root;
    }
    hand
}

struct CollisionLoop {
    inbox: Arc<Handoff<CandidateFrame, Change>>,
    verified: Sender<VerifiedFrame>,
    io_watch: Arc<AwakeWatch>,
    /// Wakes the I/O thread when it sleeps and a frame is verified.
    waker: Waker,
    feedback: Arc<PoseFeedback>,
    refusals: Sender<Refusal>,
    verifier: Option<Verifier>,
    epoch: u64,
}

impl CollisionLoop {
    fn run(mut self) {
        let mut meter = LoopMeter::new("collision");
        loop {
            match self.inbox.receive(None) {
                Received::Work(Work::Frame(candidate)) => {
                    let started = Instant::now();
                    if self.verify(candidate) && self.io_watch.must_wake() {
                        self.waker.wake();
                    }
                    meter.frame_done(started);
                }
                Received::Work(Work::Control(Change::Restart(restart))) => {
                    let bodies = restart.hand_bodies.clone();
                    self.verifier = Some(Verifier::new(&restart.scene, &bodies));
                    self.epoch = restart.epoch;
                    meter.log();
                }
                Received::Work(Work::Control(Change::SlidingMetaphor(_))) => {}
                Received::Timeout => {}
                Received::Closed => break,
            }
        }
        meter.log();
    }

    /// Verifies a frame and hands it to the I/O thread; false for a frame of an older restart,
    /// which is dropped.
    fn verify(&mut self, candidate: CandidateFrame) -> bool {
        let Some(verifier) = self
            .verifier
            .as_mut()
            .filter(|_| candidate.epoch == self.epoch)
        else {
            return false;
        };
        let (frame, refused) = verifier.verify(candidate);
        for (part, pose) in refused {
            tracing::warn!(
                part,
                "a proposed part pose collides; the part stays where it was"
            );
            // The sliding loop only ends after this one, so the receiver is alive.
            let _ = self.refusals.send(Refusal {
                epoch: self.epoch,
                part,
                pose,
            });
        }
        self.feedback.publish(self.epoch, verifier.part_poses());
        self.verified.send(frame).is_ok()
    }
}

#[cfg(test)]
mod tests;
