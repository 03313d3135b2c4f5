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
//! A mutex and a condition variable suffice: the hand-off happens at most a few thousand times a
//! second and the lock is held for a queue push or pop (measured with the latency benchmark,
//! where the whole pipeline adds tens of microseconds, most of them collision work).

use std::collections::VecDeque;
use std::sync::{Condvar, Mutex, MutexGuard, PoisonError};
use std::time::Instant;

/// A frame that can absorb an older one it overtook in a queue.
pub trait Coalesce {
    /// Merges `older` into `self`: `self`'s state stands, `older`'s events go first.
    fn absorb_older(&mut self, older: Self);
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
}

/// A queue from one loop to the next (see the module documentation).
pub struct Handoff<F, C> {
    queue: Mutex<Queue<F, C>>,
    ready: Condvar,
}

impl<F: Coalesce, C> Default for Handoff<F, C> {
    fn default() -> Self {
        Handoff {
            queue: Mutex::new(Queue {
                items: VecDeque::new(),
                closed: false,
                merged: 0,
            }),
            ready: Condvar::new(),
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
        queue.items.push_back(work);
        drop(queue);
        self.ready.notify_one();
    }

    /// Waits for the next item until `deadline` (for ever with `None`).
    pub fn receive(&self, deadline: Option<Instant>) -> Received<F, C> {
        let mut queue = self.lock();
        loop {
            if let Some(work) = queue.items.pop_front() {
                return Received::Work(work);
            }
            if queue.closed {
                return Received::Closed;
            }
            queue = match deadline {
                None => self
                    .ready
                    .wait(queue)
                    .unwrap_or_else(PoisonError::into_inner),
                Some(deadline) => {
                    let Some(left) = deadline.checked_duration_since(Instant::now()) else {
                        return Received::Timeout;
                    };
                    self.ready
                        .wait_timeout(queue, left)
                        .unwrap_or_else(PoisonError::into_inner)
                        .0
                }
            };
        }
    }

    /// Ends the hand-off: the receiver takes what is queued, then sees [`Received::Closed`].
    pub fn close(&self) {
        self.lock().closed = true;
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

    #[test]
    fn a_closed_handoff_delivers_what_was_queued_then_reports_closed() {
        let handoff: Arc<Handoff<Frame, &'static str>> = Arc::new(Handoff::default());
        let receiver = {
            let handoff = Arc::clone(&handoff);
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
        };
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
    fn receive_returns_at_the_deadline_when_nothing_comes() {
        let handoff: Handoff<Frame, ()> = Handoff::default();
        let deadline = Instant::now() + Duration::from_millis(5);
        assert!(matches!(handoff.receive(Some(deadline)), Received::Timeout));
        assert!(Instant::now() >= deadline);
    }
}
