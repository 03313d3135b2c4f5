//! The rendezvous between the loops: a hand-off queue of frames and control changes.
//!
//! A loop hands its output to the next loop through a [`Handoff`]; sending never blocks, so a slow
//! loop never stalls a fast one (the paper's loops run at their own pace). When frames pile up
//! because the receiver is busy, the newer frame absorbs the older one ([`Coalesce`]): the
//! latest poses win and the discrete events of both are kept, so nothing that must be told is
//! lost and the queue never grows. Control changes are never merged and keep their place between
//! frames, so every loop applies them between the same two frames.
//!
//! In lockstep the sender waits for each frame's answer before sending the next, so frames never
//! meet in a queue and are never merged.
//!
//! A mutex and a condition variable suffice for the queue: the hand-off happens at most a few
//! thousand times a second and the lock is held for a queue push or pop. What costs is waking a
//! sleeping thread, about as much as a loop's own work with nothing in contact. So a loop that
//! starts on a frame first [`Handoff::announce`]s its output: the next loop wakes while the
//! frame is being computed and waits for it awake, yielding the processor, for at most
//! [`ANNOUNCED_WAIT`]; the wake-up overlaps the work instead of adding to it.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering, fence};
use std::sync::{Condvar, Mutex, MutexGuard, PoisonError};
use std::time::{Duration, Instant};

pub use crate::simulation::frames::Coalesce;

/// How long a receiver woken by [`Handoff::announce`] waits awake for the frame before it goes
/// back to sleep: several times a loop's frame with nothing in contact, so that the announced
/// frame nearly always arrives within it, and short enough that a long frame (a 50,000-triangle
/// part in contact takes milliseconds) costs little spinning before the receiver sleeps and is
/// woken the ordinary way.
pub const ANNOUNCED_WAIT: Duration = Duration::from_micros(300);

/// Whether the I/O thread waits awake for the collision loop's verified frames, which come
/// through a channel that is not a [`Handoff`]. While it waits awake, the collision loop hands a
/// frame over without waking it through iceoryx2 (a notification costs the collision loop a
/// system call and the I/O thread a WaitSet wake-up); while it sleeps on its WaitSet, the
/// collision loop must wake it.
#[derive(Debug, Default)]
pub struct AwakeWatch(AtomicBool);

impl AwakeWatch {
    /// Calls `done` (which takes the frames handed over so far) until it says true, yielding the
    /// processor in between, for at most [`ANNOUNCED_WAIT`]; then once more after the watch
    /// ends, so that a frame handed over as it ended, without a wake-up, is taken too.
    pub fn wait_awake(&self, mut done: impl FnMut() -> bool) {
        self.0.store(true, Ordering::SeqCst);
        wait_awake_until(Instant::now() + ANNOUNCED_WAIT, &mut done);
        self.0.store(false, Ordering::SeqCst);
        // Pairs with the fence in `must_wake`: either the last `done` below sees a frame handed
        // over concurrently, or its sender sees that nobody is watching and wakes this thread.
        fence(Ordering::SeqCst);
        done();
    }

    /// Whether the receiver must be woken for a frame just handed over: it is not waiting awake.
    pub fn must_wake(&self) -> bool {
        fence(Ordering::SeqCst);
        !self.0.load(Ordering::SeqCst)
    }
}

/// Calls `done` until it says true or `until` passes, yielding the processor in between: how a
/// receiver waits awake for an announced frame.
fn wait_awake_until(until: Instant, mut done: impl FnMut() -> bool) {
    while !done() && Instant::now() < until {
        std::thread::yield_now();
    }
}

/// One item for a loop.
#[derive(Debug)]
pub enum Work<F, C> {
    /// A frame to process.
    Frame(F),
    /// A change of the simulation (reset, new scene, metaphor), applied between frames.
    Control(C),
}

/// What [`Handoff::receive`] found.
#[derive(Debug)]
pub enum Received<F, C> {
    /// The next item.
    Work(Work<F, C>),
    /// The deadline passed with nothing to do.
    Timeout,
    /// The sender closed the hand-off and everything sent was taken.
    Closed,
}

struct Queue<F, C> {
    items: VecDeque<Work<F, C>>,
    closed: bool,
    merged: u64,
    /// A frame was announced and the receiver has not started waiting for it yet.
    announced: bool,
    /// When the frame being made was announced.
    announced_at: Option<Instant>,
    /// How long the last announced frame took to come: when that is longer than
    /// [`ANNOUNCED_WAIT`], frames are not announced to the receiver (it would only spin and then
    /// sleep anyway) until a frame comes quickly again.
    announce_lead: Duration,
    /// The receiver sleeps on the condition variable: only then does a sender signal it (a
    /// signal is a system call, and a receiver waiting awake polls `pending` instead).
    sleeping: bool,
}

/// A queue from one loop to the next (see the module documentation).
pub struct Handoff<F, C> {
    queue: Mutex<Queue<F, C>>,
    ready: Condvar,
    /// Set with every item queued (and on closing), cleared when the queue is emptied: what a
    /// receiver waiting awake polls without taking the lock.
    pending: AtomicBool,
}

impl<F: Coalesce, C> Default for Handoff<F, C> {
    fn default() -> Self {
        Handoff {
            queue: Mutex::new(Queue {
                items: VecDeque::new(),
                closed: false,
                merged: 0,
                announced: false,
                announced_at: None,
                announce_lead: Duration::ZERO,
                sleeping: false,
            }),
            ready: Condvar::new(),
            pending: AtomicBool::new(false),
        }
    }
}

impl<F: Coalesce, C> Handoff<F, C> {
    /// Queues `work`; a frame absorbs the frame at the back of the queue, if that is one.
    pub fn send(&self, work: Work<F, C>) {
        let mut queue = self.lock();
        let work = match work {
            Work::Frame(mut newer) if matches!(queue.items.back(), Some(Work::Frame(_))) => {
                if let Some(Work::Frame(older)) = queue.items.pop_back() {
                    newer.absorb_older(older);
                    queue.merged += 1;
                }
                Work::Frame(newer)
            }
            work => work,
        };
        if let Some(announced_at) = queue.announced_at.take() {
            queue.announce_lead = announced_at.elapsed();
        }
        queue.items.push_back(work);
        self.pending.store(true, Ordering::Release);
        let sleeping = queue.sleeping;
        drop(queue);
        if sleeping {
            self.ready.notify_one();
        }
    }

    /// Tells the receiver that a frame is on its way: a sleeping receiver wakes now and waits for
    /// it awake (at most [`ANNOUNCED_WAIT`]), so that the wake-up overlaps the frame's making.
    /// Frames slower than [`ANNOUNCED_WAIT`] are not announced to the receiver.
    pub fn announce(&self) {
        let mut queue = self.lock();
        queue.announced_at = Some(Instant::now());
        if queue.items.is_empty() && !queue.closed && queue.announce_lead <= ANNOUNCED_WAIT {
            queue.announced = true;
            let sleeping = queue.sleeping;
            drop(queue);
            if sleeping {
                self.ready.notify_one();
            }
        }
    }

    /// Waits for the next item until `deadline` (for ever with `None`).
    pub fn receive(&self, deadline: Option<Instant>) -> Received<F, C> {
        let mut queue = self.lock();
        loop {
            if let Some(work) = queue.items.pop_front() {
                queue.announced = false;
                if queue.items.is_empty() {
                    self.pending.store(false, Ordering::Relaxed);
                }
                return Received::Work(work);
            }
            if queue.closed {
                return Received::Closed;
            }
            if std::mem::take(&mut queue.announced) {
                drop(queue);
                let awake_until = Instant::now() + ANNOUNCED_WAIT;
                let awake_until =
                    deadline.map_or(awake_until, |deadline| deadline.min(awake_until));
                wait_awake_until(awake_until, || self.pending.load(Ordering::Acquire));
                queue = self.lock();
                continue;
            }
            let left = match deadline {
                None => None,
                Some(deadline) => match deadline.checked_duration_since(Instant::now()) {
                    Some(left) => Some(left),
                    None => return Received::Timeout,
                },
            };
            queue.sleeping = true;
            queue = match left {
                None => self
                    .ready
                    .wait(queue)
                    .unwrap_or_else(PoisonError::into_inner),
                Some(left) => {
                    self.ready
                        .wait_timeout(queue, left)
                        .unwrap_or_else(PoisonError::into_inner)
                        .0
                }
            };
            queue.sleeping = false;
        }
    }

    /// Ends the hand-off: the receiver takes what is queued, then sees [`Received::Closed`].
    pub fn close(&self) {
        self.lock().closed = true;
        self.pending.store(true, Ordering::Release);
        self.ready.notify_all();
    }

    /// How many frames were merged into newer ones so far.
    pub fn merged(&self) -> u64 {
        self.lock().merged
    }

    /// The queue; a loop that panicked while holding the lock left it consistent (every change
    /// is a single push or pop), so a poisoned lock is taken over.
    fn lock(&self) -> MutexGuard<'_, Queue<F, C>> {
        self.queue.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;
    use std::time::Duration;

    use super::*;

    /// A frame: the latest value, and every event of the frames it absorbed.
    #[derive(Debug, PartialEq)]
    struct Frame {
        value: u32,
        events: Vec<u32>,
    }

    impl Coalesce for Frame {
        fn absorb_older(&mut self, older: Self) {
            let mut events = older.events;
            events.append(&mut self.events);
            self.events = events;
        }
    }

    fn frame(value: u32) -> Work<Frame, &'static str> {
        Work::Frame(Frame {
            value,
            events: vec![value],
        })
    }

    fn next(handoff: &Handoff<Frame, &'static str>) -> Work<Frame, &'static str> {
        match handoff.receive(Some(Instant::now())) {
            Received::Work(work) => work,
            other => panic!("expected work, got {other:?}"),
        }
    }

    #[test]
    fn piled_up_frames_merge_but_keep_every_event_and_controls_keep_their_place() {
        let handoff = Handoff::default();
        handoff.send(frame(1));
        handoff.send(frame(2));
        handoff.send(Work::Control("reset"));
        handoff.send(frame(3));
        handoff.send(frame(4));
        handoff.send(frame(5));
        assert_eq!(handoff.merged(), 3);
        match next(&handoff) {
            Work::Frame(f) => assert_eq!(
                f,
                Frame {
                    value: 2,
                    events: vec![1, 2]
                }
            ),
            other => panic!("{other:?}"),
        }
        assert!(matches!(next(&handoff), Work::Control("reset")));
        match next(&handoff) {
            Work::Frame(f) => assert_eq!(
                f,
                Frame {
                    value: 5,
                    events: vec![3, 4, 5]
                }
            ),
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            handoff.receive(Some(Instant::now())),
            Received::Timeout
        ));
    }

    /// A receiver thread that gathers the events of every frame until the hand-off is closed.
    fn collect_events(
        handoff: Arc<Handoff<Frame, &'static str>>,
    ) -> std::thread::JoinHandle<Vec<u32>> {
        std::thread::spawn(move || {
            let mut values = Vec::new();
            loop {
                match handoff.receive(None) {
                    Received::Work(Work::Frame(f)) => values.extend(f.events),
                    Received::Work(Work::Control(_)) => {}
                    Received::Timeout => panic!("no deadline was given"),
                    Received::Closed => return values,
                }
            }
        })
    }

    #[test]
    fn a_closed_handoff_delivers_what_was_queued_then_reports_closed() {
        let handoff: Arc<Handoff<Frame, &'static str>> = Arc::new(Handoff::default());
        let receiver = collect_events(Arc::clone(&handoff));
        for value in 0..100 {
            handoff.send(frame(value));
            if value % 10 == 0 {
                std::thread::yield_now();
            }
        }
        handoff.close();
        let values = receiver.join().expect("the receiver ends");
        assert_eq!(
            values,
            (0..100).collect::<Vec<_>>(),
            "nothing lost, in order"
        );
    }

    #[test]
    fn a_receiver_asleep_on_the_condition_variable_is_woken_by_a_send() {
        let handoff: Arc<Handoff<Frame, &'static str>> = Arc::new(Handoff::default());
        let (woken, wake_report) = std::sync::mpsc::channel();
        let receiver = {
            let handoff = Arc::clone(&handoff);
            std::thread::spawn(move || {
                let received = handoff.receive(None);
                let _ =
                    woken.send(matches!(received, Received::Work(Work::Frame(f)) if f.value == 5));
            })
        };
        // Senders signal only a sleeping receiver: send once it sleeps.
        while !handoff.lock().sleeping {
            std::thread::yield_now();
        }
        handoff.send(frame(5));
        assert_eq!(
            wake_report.recv_timeout(Duration::from_secs(30)),
            Ok(true),
            "the sleeping receiver is woken and takes the frame"
        );
        receiver.join().expect("the receiver ends");
    }

    #[test]
    fn receive_returns_at_the_deadline_when_nothing_comes() {
        let handoff: Handoff<Frame, ()> = Handoff::default();
        let deadline = Instant::now() + Duration::from_millis(5);
        assert!(matches!(handoff.receive(Some(deadline)), Received::Timeout));
        assert!(Instant::now() >= deadline);
    }

    #[test]
    fn announced_frames_arrive_and_an_announcement_without_a_frame_is_outwaited() {
        let handoff: Arc<Handoff<Frame, &'static str>> = Arc::new(Handoff::default());
        let receiver = collect_events(Arc::clone(&handoff));
        for value in 0..200 {
            handoff.announce();
            if value % 50 == 7 {
                // An announced frame that never comes: the receiver must go back to waiting
                // and still take the next one.
                handoff.announce();
                std::thread::sleep(ANNOUNCED_WAIT * 2);
            }
            handoff.send(frame(value));
        }
        handoff.close();
        let values = receiver.join().expect("the receiver ends");
        assert_eq!(values, (0..200).collect::<Vec<_>>());
    }

    #[test]
    fn frames_slower_than_the_awake_wait_are_not_announced_until_one_is_quick_again() {
        let handoff: Handoff<Frame, &'static str> = Handoff::default();
        handoff.announce();
        assert!(handoff.lock().announced);
        // The frame takes longer than a receiver would wait awake.
        std::thread::sleep(ANNOUNCED_WAIT + Duration::from_millis(1));
        handoff.send(frame(1));
        assert!(matches!(next(&handoff), Work::Frame(_)));
        handoff.announce();
        assert!(
            !handoff.lock().announced,
            "a slow producer wakes nobody early"
        );
        handoff.send(frame(2));
        assert!(matches!(next(&handoff), Work::Frame(_)));
        handoff.announce();
        assert!(
            handoff.lock().announced,
            "a quick frame re-enables announcements"
        );
    }

    #[test]
    fn a_frame_handed_over_during_an_awake_wait_is_taken_with_or_without_a_wake_up() {
        for _ in 0..200 {
            let watch = Arc::new(AwakeWatch::default());
            let (sender, receiver) = crossbeam_channel::unbounded();
            let producer = {
                let watch = Arc::clone(&watch);
                std::thread::spawn(move || {
                    sender.send(1).unwrap();
                    watch.must_wake()
                })
            };
            let mut taken = Vec::new();
            watch.wait_awake(|| {
                taken.extend(receiver.try_iter());
                !taken.is_empty()
            });
            let woken = producer.join().unwrap();
            // The frame came within the wait, or the last take after it found it, or the
            // producer saw that nobody watched and wakes the receiver, which then takes it.
            if woken {
                taken.extend(receiver.try_iter());
            }
            assert_eq!(taken, vec![1]);
            assert!(watch.must_wake(), "nobody watches after the wait");
        }
    }
}
