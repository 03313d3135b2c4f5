//! The parallel back end: each pair of a frame goes through its separating-plane pre-check and,
//! if need be, its exact test on one thread, the pairs shared out among the pool's threads a chunk
//! at a time ([`SharedPairs`]) and the last exact tests one at a time.

use super::objects::{Slot, live, models, relative_pose};
use super::pool::help_once;
use super::{Detail, ExactTest, KnownApartPairs, PairEntry, PairKey, PipelineConfig};
use crate::collision::QueryStats;
use crate::collision::separating_plane::PlaneSearch;
use std::collections::VecDeque;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};
use std::time::{Duration, Instant};

/// What the back end's tests of a frame add up to, for the frame's counters. Each test adds its
/// share as it ends, while its entry is still in the cache, rather than in a serial pass over the
/// pairs after the frame's parallel part.
///
/// The pair counts leave out the carried pairs whose overlap ended during the frame (see
/// [`Tally::forget`]), so that each stage takes in what the one before let through; the loops, the
/// work and the times count every test the back end ran.
#[derive(Debug, Default, Clone, Copy)]
pub(super) struct Tally {
    /// Pairs tested.
    pub(super) pairs: u64,
    /// Of those, pairs the pre-check did not separate.
    pub(super) unseparated: u64,
    /// Of those, pairs the exact test found colliding.
    pub(super) colliding: u64,
    /// Perceptron loops of the pre-checks.
    pub(super) plane_loops: u64,
    /// Exact tests split across the threads.
    pub(super) split_tests: u64,
    /// Work counters of the exact tests.
    pub(super) exact_work: QueryStats,
    /// Time of the pre-checks, summed over the threads.
    pub(super) plane_time: Duration,
    /// Time of the exact tests, summed over the threads.
    pub(super) exact_time: Duration,
}

impl std::ops::AddAssign for Tally {
    fn add_assign(&mut self, other: Tally) {
        self.pairs += other.pairs;
        self.unseparated += other.unseparated;
        self.colliding += other.colliding;
        self.plane_loops += other.plane_loops;
        self.split_tests += other.split_tests;
        self.exact_work += other.exact_work;
        self.plane_time += other.plane_time;
        self.exact_time += other.exact_time;
    }
}

impl std::iter::Sum for Tally {
    fn sum<I: Iterator<Item = Tally>>(tallies: I) -> Tally {
        tallies.fold(Tally::default(), |mut sum, tally| {
            sum += tally;
            sum
        })
    }
}

impl Tally {
    /// Takes out of the pair counts a pair tested in this frame and then dropped, its overlap
    /// having ended.
    pub(super) fn forget(&mut self, entry: &PairEntry) {
        self.pairs -= 1;
        self.unseparated -= u64::from(!entry.separated);
        self.colliding -= u64::from(entry.contact.is_some());
    }
}

/// Pairs a thread of the back end claims at a time: pre-checks are cheap, so much smaller chunks
/// would let the claims dominate, and much larger ones would leave a thread idle behind a chunk
/// that happens to hold several exact tests.
pub(super) const PAIRS_PER_TASK: usize = 8;

/// A frame's pairs shared out among the pool's threads.
///
/// The thread that runs [`BackEnd::run`] claims chunks of [`PAIRS_PER_TASK`] pairs from the front
/// of the list and the others from the back, each running the pre-checks of its chunk and, while
/// unclaimed chunks remain, the chunk's exact tests; the exact tests of the last chunks go to a
/// common list that every thread takes from one at a time, so that no thread is left working
/// alone at the end for more than one exact test.
///
/// Claiming from both ends keeps most pairs on the core that tested them at the last frame, and a
/// thread that runs out of work waits awake (see [`help_once`]), where rayon's parallel iterator
/// would put it to sleep.
struct SharedPairs<'s, 'e> {
    unclaimed: Mutex<VecDeque<&'s mut [&'e mut PairEntry]>>,
    deferred_exacts: Mutex<Vec<&'s mut PairEntry>>,
    /// Chunks and deferred exact tests that a thread has claimed, or is about to claim, and not
    /// finished: counted before the claim, so that no thread sees zero while another one works.
    in_flight: AtomicUsize,
}

impl<'s, 'e> SharedPairs<'s, 'e> {
    fn new(entries: &'s mut [&'e mut PairEntry]) -> Self {
        SharedPairs {
            unclaimed: Mutex::new(entries.chunks_mut(PAIRS_PER_TASK).collect()),
            deferred_exacts: Mutex::new(Vec::new()),
            in_flight: AtomicUsize::new(0),
        }
    }

    /// The next chunk from the front or the back, in flight until [`Self::finish_item`].
    fn claim_chunk(&self, from_front: bool) -> Option<&'s mut [&'e mut PairEntry]> {
        self.claim(|| {
            let mut unclaimed = lock(&self.unclaimed);
            if from_front {
                unclaimed.pop_front()
            } else {
                unclaimed.pop_back()
            }
        })
    }

    fn chunks_remain(&self) -> bool {
        !lock(&self.unclaimed).is_empty()
    }

    /// Leaves an exact test to whichever thread is free first.
    fn defer_exact(&self, entry: &'s mut PairEntry) {
        lock(&self.deferred_exacts).push(entry);
    }

    /// A deferred exact test, in flight until [`Self::finish_item`].
    fn claim_exact(&self) -> Option<&'s mut PairEntry> {
        self.claim(|| lock(&self.deferred_exacts).pop())
    }

    /// Runs `take` counted in flight: before it, so that no thread sees nothing in flight while
    /// another one is taking an item, and after it if it took one, until [`Self::finish_item`].
    fn claim<T>(&self, take: impl FnOnce() -> Option<T>) -> Option<T> {
        self.in_flight.fetch_add(1, Ordering::SeqCst);
        let claimed = take();
        if claimed.is_none() {
            self.in_flight.fetch_sub(1, Ordering::SeqCst);
        }
        claimed
    }

    fn finish_item(&self) {
        self.in_flight.fetch_sub(1, Ordering::SeqCst);
    }

    /// Every chunk and deferred exact test finished, once no chunk is left to claim.
    fn all_done(&self) -> bool {
        self.in_flight.load(Ordering::SeqCst) == 0 && lock(&self.deferred_exacts).is_empty()
    }
}

/// Locks a mutex of the pipeline's, whose data stay sound if a holder panicked.
fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(PoisonError::into_inner)
}

/// What the back end reads while it tests the pairs of a frame, on any thread.
pub(super) struct BackEnd<'a, C> {
    slots: &'a [Slot<C>],
    known_apart: &'a KnownApartPairs,
    /// `None` when the separating-plane stage is off.
    plane_search: Option<PlaneSearch>,
    split_min_bv_tests: u64,
    detail: Detail,
    /// The pool thread that runs the frame, and queued its moves (`None` outside a pool).
    frame_thread: Option<usize>,
    /// The pairs whose contact an exact test started or ended: the pipeline's set of colliding
    /// pairs is brought up to date from these alone.
    contact_changes: Mutex<Vec<PairKey>>,
}

impl<'a, C: ExactTest> BackEnd<'a, C> {
    /// The back end of a frame over `slots`.
    pub(super) fn new(
        slots: &'a [Slot<C>],
        known_apart: &'a KnownApartPairs,
        config: &PipelineConfig,
        detail: Detail,
    ) -> Self {
        BackEnd {
            slots,
            known_apart,
            plane_search: config.separating_plane.then_some(config.plane_search),
            // On one thread, a split traversal would only add its overhead.
            split_min_bv_tests: if rayon::current_num_threads() > 1 {
                config.split_min_bv_tests
            } else {
                u64::MAX
            },
            detail,
            frame_thread: rayon::current_thread_index(),
            contact_changes: Mutex::new(Vec::new()),
        }
    }

    /// Reads every object's pose once, in memory order, on a thread other than the one that
    /// queued the moves: the pre-checks then find in this core's cache the poses they read in
    /// the pairs' scattered order, where each would otherwise wait for the other core's.
    fn fetch_poses_if_elsewhere(&self) {
        if rayon::current_thread_index() == self.frame_thread {
            return;
        }
        let poses = self
            .slots
            .iter()
            .filter_map(|slot| slot.object.as_ref())
            .map(|object| object.pose.translation.vector.x + object.pose.rotation.w);
        std::hint::black_box(poses.sum::<f64>());
    }

    /// The pairs whose contact started or ended in this frame's tests (a pair may come twice).
    pub(super) fn into_contact_changes(self) -> Vec<PairKey> {
        self.contact_changes
            .into_inner()
            .unwrap_or_else(PoisonError::into_inner)
    }

    /// Takes the pairs down the back end, spread over the current rayon pool, leaving each one's
    /// results in its entry, and returns what the tests add up to.
    ///
    /// The calling thread and one task for each other thread of the pool take the pairs from a
    /// [`SharedPairs`], and the caller returns once every pair is tested: an exact test costs far
    /// more than a pre-check, so the last ones are shared out one at a time.
    pub(super) fn run(&self, entries: &mut [&mut PairEntry]) -> Tally {
        if rayon::current_num_threads() == 1 || entries.len() <= PAIRS_PER_TASK {
            let mut tally = self.pre_check(entries);
            for entry in entries.iter_mut().filter(|entry| !entry.separated) {
                tally += self.exact(entry);
            }
            return tally;
        }
        let shared = SharedPairs::new(entries);
        let helpers_tally = Mutex::new(Tally::default());
        let mut tally = rayon::scope(|scope| {
            for _ in 1..rayon::current_num_threads() {
                scope.spawn(|_| {
                    let tally = self.drain(&shared, false);
                    *lock(&helpers_tally) += tally;
                });
            }
            self.drain(&shared, true)
        });
        tally += helpers_tally
            .into_inner()
            .unwrap_or_else(PoisonError::into_inner);
        tally
    }

    /// Tests chunks of `shared` until none is left, from the front for the thread that owns it
    /// (`owner`) and from the back for the others, then deferred exact tests until there are no
    /// more; the owner then waits, awake, until the other threads have finished theirs too. Only
    /// the owner waits: a helper task may run inside a wait of a thread that holds a pair of the
    /// same frame (rayon runs pending tasks there), and would then wait for itself.
    fn drain(&self, shared: &SharedPairs<'_, '_>, owner: bool) -> Tally {
        self.fetch_poses_if_elsewhere();
        let mut tally = Tally::default();
        while let Some(chunk) = shared.claim_chunk(owner) {
            tally += self.pre_check(chunk);
            let chunk = chunk.iter_mut();
            let chunks_remain = shared.chunks_remain();
            for entry in chunk.filter(|entry| !entry.separated) {
                if chunks_remain {
                    tally += self.exact(entry);
                } else {
                    shared.defer_exact(entry);
                }
            }
            shared.finish_item();
        }
        loop {
            if let Some(entry) = shared.claim_exact() {
                tally += self.exact(entry);
                shared.finish_item();
            } else if !owner || shared.all_done() {
                return tally;
            } else {
                help_once();
            }
        }
    }

    /// Runs the separating-plane stage on the pairs. A pair that collided when last tested skips
    /// it: the pre-check would most likely fail, after many loops. A pair known apart at its
    /// objects' current poses counts as separated.
    fn pre_check(&self, entries: &mut [&mut PairEntry]) -> Tally {
        let start = Instant::now();
        let mut tally = Tally {
            pairs: entries.len() as u64,
            ..Tally::default()
        };
        for entry in entries.iter_mut() {
            entry.b_to_a = relative_pose(self.slots, entry.pair);
            entry.separated = false;
            if entry.contact.is_none() && self.is_known_apart(entry.pair) {
                entry.separated = true;
            } else if let Some(search) = &self.plane_search
                && entry.contact.is_none()
            {
                let [a, b] = models(self.slots, entry.pair);
                let check = entry.plane.check(a.hull(), b.hull(), &entry.b_to_a, search);
                entry.separated = check.separated;
                tally.plane_loops += u64::from(check.loops);
            }
            tally.unseparated += u64::from(!entry.separated);
        }
        tally.plane_time = start.elapsed();
        tally
    }

    /// Whether the pair was proved apart outside the pipeline with both objects where they are.
    fn is_known_apart(&self, pair: PairKey) -> bool {
        self.known_apart.get(&pair).is_some_and(|[pose_a, pose_b]| {
            live(self.slots, pair.0).pose == *pose_a && live(self.slots, pair.1).pose == *pose_b
        })
    }

    /// The exact test of a pair the pre-check did not separate.
    fn exact(&self, entry: &mut PairEntry) -> Tally {
        let start = Instant::now();
        let mut tally = Tally::default();
        let [a, b] = models(self.slots, entry.pair);
        let (a, b) = (a.exact(), b.exact());
        let was_colliding = entry.contact.is_some();
        let stats = &mut tally.exact_work;
        entry.contact = match self.detail {
            Detail::Pairs => {
                let split = entry.exact_bv_tests >= self.split_min_bv_tests;
                let colliding = if split {
                    a.intersects_split(b, &entry.b_to_a, stats)
                } else {
                    a.intersects(b, &entry.b_to_a, stats)
                };
                tally.split_tests = u64::from(split);
                entry.exact_bv_tests = stats.bv_tests;
                colliding.then_some(None)
            }
            Detail::TrianglePairs => {
                let mut triangles = Vec::new();
                a.intersecting_pairs(b, &entry.b_to_a, &mut triangles, stats);
                (!triangles.is_empty()).then_some(Some(triangles))
            }
        };
        tally.colliding = u64::from(entry.contact.is_some());
        if entry.contact.is_some() != was_colliding {
            lock(&self.contact_changes).push(entry.pair);
        }
        tally.exact_time = start.elapsed();
        tally
    }
}
