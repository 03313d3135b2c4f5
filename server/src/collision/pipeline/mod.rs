//! The collision-detection pipeline over a scene (PAPER §2, §2.3).
//!
//! Objects (a shared collision model, a pose, a group, a static flag) are added and removed; each
//! frame, the objects moved since the last frame (the front-end queue) send only their pairs down
//! the filters: the bounding-box stage ([`SweepAndPrune`]), the [`InterestMatrix`], the
//! separating-plane pre-check ([`SeparatingPlane`]) and the exact test ([`ExactTest`]). The result
//! is the set of colliding pairs in the whole scene and, on request, their triangle pairs; pairs of
//! objects that did not move keep their last answer. Each stage counts the pairs it took in and let
//! through, and its time.
//!
//! A pair that collided when last tested skips the pre-check (it would most likely fail to find a
//! plane, after many loops) and goes straight to the exact test.
//!
//! The back end is parallel on the current rayon pool: the threads claim the pairs of a frame a
//! chunk at a time until none is left (dynamic load balancing, see [`SharedPairs`]), each pair
//! going through its pre-check and, if need be, its exact test on the same thread (coarse grain);
//! it starts on the pairs that overlapped at the last frame while
//! the bounding-box stage moves the boxes, so that the broad phase, mostly serial, runs beside it
//! instead of before it (see [`CollisionPipeline::run_frame`]); and the traversal of a
//! pair expected to be expensive is itself split across the threads (fine grain; see
//! [`PipelineConfig::split_min_bv_tests`]).

mod exact;

pub use exact::ExactTest;

use super::QueryStats;
use super::broad_phase::{Aabb, SweepAndPrune};
use super::interest::{GroupId, InterestKey, InterestMatrix};
use super::separating_plane::{PlaneSearch, SeparatingPlane};
use crate::geometry::ConvexHull;
use nalgebra::{Isometry3, Vector3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use std::collections::{BTreeSet, VecDeque};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};
use thiserror::Error;

/// Names an object of a pipeline. Ids of removed objects are never valid again.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ObjectId {
    index: u32,
    generation: u32,
}

impl ObjectId {
    /// The slot the object occupies; slots of removed objects are reused.
    pub fn index(self) -> u32 {
        self.index
    }

    #[cfg(test)]
    pub(crate) fn from_parts(index: u32, generation: u32) -> Self {
        ObjectId { index, generation }
    }
}

/// What the pipeline needs of a rigid object's shape, built once and shared between the objects
/// (and loops) that use the same mesh.
#[derive(Debug)]
pub struct CollisionModel<C> {
    exact: C,
    hull: ConvexHull,
    local_bounds: Aabb,
}

impl<C> CollisionModel<C> {
    /// Combines an exact-test structure and the convex hull of the same mesh.
    pub fn new(exact: C, hull: ConvexHull) -> Self {
        let first = hull.vertices()[0];
        let (min, max) = hull
            .vertices()
            .iter()
            .fold((first, first), |(lo, hi), v| (lo.inf(v), hi.sup(v)));
        let local_bounds = Aabb { min, max }.expanded(hull.tolerance());
        CollisionModel {
            exact,
            hull,
            local_bounds,
        }
    }

    /// The exact-test structure.
    pub fn exact(&self) -> &C {
        &self.exact
    }

    /// The convex hull used by the pre-check.
    pub fn hull(&self) -> &ConvexHull {
        &self.hull
    }

    /// A box enclosing the mesh in its own frame.
    pub fn local_bounds(&self) -> &Aabb {
        &self.local_bounds
    }
}

/// An object to add to a pipeline.
#[derive(Debug)]
pub struct ObjectDesc<C> {
    /// Its shape.
    pub model: Arc<CollisionModel<C>>,
    /// Its pose in the scene.
    pub pose: Isometry3<f64>,
    /// Its collision group, for the interest matrix.
    pub group: GroupId,
    /// True for objects that never move: two of them are never tested against each other.
    pub is_static: bool,
}

/// Why the pipeline refused a call.
#[derive(Debug, Error, PartialEq)]
pub enum PipelineError {
    /// The id names no object (never added, or removed).
    #[error("object {0:?} is not in the pipeline")]
    UnknownObject(ObjectId),
    /// A pose with a NaN or infinite component, or a rotation that is not a unit quaternion.
    #[error("invalid pose for {0}: {1}")]
    InvalidPose(String, &'static str),
    /// More objects than ids can name.
    #[error("the pipeline is full")]
    Full,
}

/// How much a frame should report about colliding pairs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Detail {
    /// Only which pairs collide (the exact test stops at the first intersecting triangle pair).
    Pairs,
    /// Also every intersecting triangle pair of each colliding pair.
    TrianglePairs,
}

/// Pairs taken in and let through by one stage in one frame, and the stage's wall time.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StageCounters {
    /// Pairs that reached the stage.
    pub pairs_in: u64,
    /// Pairs the stage passed on (for the exact test: the colliding ones).
    pub pairs_out: u64,
    /// Time spent in the stage: wall time for the broad phase and the interest matrix; for the
    /// separating-plane and exact stages, which share one parallel pass over the pairs, the sum
    /// of their per-pair times over all threads (their work, not their share of the frame).
    pub time: Duration,
}

/// The counters of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FrameStats {
    /// Objects in the front-end queue.
    pub moved: u64,
    /// Pairs involving a moved object → pairs whose boxes overlap.
    pub broad_phase: StageCounters,
    /// → pairs of interest.
    pub interest: StageCounters,
    /// → pairs no separating plane was found for.
    pub separating_plane: StageCounters,
    /// → colliding pairs.
    pub exact: StageCounters,
    /// Perceptron loops run by the pre-check.
    pub plane_loops: u64,
    /// Exact tests whose traversal was split across threads.
    pub split_tests: u64,
    /// Work counters of the exact tests.
    pub exact_work: QueryStats,
    /// Wall time of the whole frame.
    pub total: Duration,
}

/// A pair of objects whose meshes intersect.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CollidingPair {
    /// The object with the smaller id.
    pub a: ObjectId,
    /// The other object.
    pub b: ObjectId,
    /// `[triangle of a, triangle of b]` for each intersecting triangle pair; empty unless the
    /// frame asked for [`Detail::TrianglePairs`].
    pub triangles: Vec<[u32; 2]>,
}

/// What a frame found: every colliding pair of the scene, sorted, and the stage counters.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FrameReport {
    /// All pairs colliding after this frame, sorted by `(a, b)`.
    pub colliding: Vec<CollidingPair>,
    /// This frame's counters.
    pub stats: FrameStats,
}

/// Settings of the pipeline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PipelineConfig {
    /// The separating-plane search.
    pub plane_search: PlaneSearch,
    /// Whether the separating-plane stage runs at all (off: pairs go from the interest matrix
    /// straight to the exact test; for comparisons).
    pub separating_plane: bool,
    /// Fine grain: a first-hit exact test is split across the threads when the pair's previous
    /// one (the last frame it reached that stage) ran at least this many bounding-volume tests;
    /// other pairs, and pairs never tested, traverse on one thread. See
    /// [`SPLIT_MIN_BV_TESTS`] for why a cost and not the number of pairs decides.
    pub split_min_bv_tests: u64,
}

/// Default of [`PipelineConfig::split_min_bv_tests`].
///
/// Deciding by the number of pairs (split when fewer pairs than threads reach the exact test)
/// split the cheap first-hit tests that make up a sparse frame, and those got several times
/// slower: a split traversal hands rayon tasks over and wakes the idle threads, and even on one
/// thread it takes 1.1-1.6 times as long as the sequential one. Measured on two threads, one
/// DOP-tree pair at a time (500 to 8,000 triangles, random near-contact poses and pegs in holes),
/// with the threads asleep beforehand as between frames: a first hit after 30-130
/// bounding-volume tests took 4.7-5.8 us sequential and 19-24 us split; the split still lost at
/// 1,000-4,000 tests (about 1.6 times the sequential time) and won only beyond about 5,000 tests
/// (0.65-0.95 of the sequential time). A bounding-volume test costs 0.025-0.04 us in a long
/// traversal, and a pair's work changes little from one frame to the next (coherence), so the
/// previous test's count predicts the next one's time; 8,192 (about 200 us of traversal) splits
/// only where the split was measured to win. Those figures are for a split walk from the roots;
/// a split test now keeps the pair's front and splits only a long walk from it (see
/// [`DopTree::intersects_parallel`](crate::collision::DopTree::intersects_parallel)), so the
/// bound errs on the side of not splitting.
pub const SPLIT_MIN_BV_TESTS: u64 = 8192;

impl Default for PipelineConfig {
    fn default() -> Self {
        PipelineConfig {
            plane_search: PlaneSearch::default(),
            separating_plane: true,
            split_min_bv_tests: SPLIT_MIN_BV_TESTS,
        }
    }
}

struct Object<C> {
    model: Arc<CollisionModel<C>>,
    pose: Isometry3<f64>,
    key: InterestKey,
}

struct Slot<C> {
    generation: u32,
    object: Option<Object<C>>,
}

/// A pair of object slots, smaller index first.
type PairKey = (u32, u32);

/// A pair of interest whose boxes overlap: what is kept of it between frames, and what the last
/// frame that tested it found. The pipeline keeps one for every such pair (see
/// [`CollisionPipeline::run_frame`]), and the back end tests it in place, so that no serial pass
/// copies the kept state into a frame's work and the results back out.
#[derive(Debug, Clone)]
struct PairEntry {
    pair: PairKey,
    plane: SeparatingPlane,
    /// `Some` while the pair collides, with its triangle pairs if they were asked for.
    contact: Option<Option<Vec<[u32; 2]>>>,
    /// Bounding-volume tests of the pair's last first-hit exact test (0 before the first): the
    /// expected cost of the next one.
    exact_bv_tests: u64,
    /// The last test's pose of the second object in the first one's frame.
    b_to_a: Isometry3<f64>,
    /// The last test: the pre-check separated the pair.
    separated: bool,
}

impl PairEntry {
    /// A pair whose overlap just started: nothing kept yet.
    fn new(pair: PairKey) -> Self {
        PairEntry {
            pair,
            plane: SeparatingPlane::new(),
            contact: None,
            exact_bv_tests: 0,
            b_to_a: Isometry3::identity(),
            separated: false,
        }
    }
}

/// What the back end's tests of a frame add up to, for the frame's counters. Each test adds its
/// share as it ends, while its entry is still in the cache, rather than in a serial pass over the
/// pairs after the frame's parallel part.
///
/// The pair counts leave out the carried pairs whose overlap ended during the frame (see
/// [`Tally::forget`]), so that each stage takes in what the one before let through; the loops, the
/// work and the times count every test the back end ran.
#[derive(Debug, Default, Clone, Copy)]
struct Tally {
    /// Pairs tested.
    pairs: u64,
    /// Of those, pairs the pre-check did not separate.
    unseparated: u64,
    /// Of those, pairs the exact test found colliding.
    colliding: u64,
    /// Perceptron loops of the pre-checks.
    plane_loops: u64,
    /// Exact tests split across the threads.
    split_tests: u64,
    /// Work counters of the exact tests.
    exact_work: QueryStats,
    /// Time of the pre-checks, summed over the threads.
    plane_time: Duration,
    /// Time of the exact tests, summed over the threads.
    exact_time: Duration,
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
    fn forget(&mut self, entry: &PairEntry) {
        self.pairs -= 1;
        self.unseparated -= u64::from(!entry.separated);
        self.colliding -= u64::from(entry.contact.is_some());
    }
}

/// Pairs a thread of the back end claims at a time: a pre-check costs about 0.25 us, so much
/// smaller chunks would let the claims dominate, and much larger ones would leave a thread idle
/// behind a chunk that happens to hold several exact tests.
const PAIRS_PER_TASK: usize = 8;

/// A frame's pairs shared out among the pool's threads.
///
/// The thread that runs [`BackEnd::run`] claims chunks of [`PAIRS_PER_TASK`] pairs from the front
/// of the list and the others from the back, each running the pre-checks of its chunk and, while
/// unclaimed chunks remain, the chunk's exact tests; the exact tests of the last chunks go to a
/// common list that every thread takes from one at a time, so that no thread is left working
/// alone at the end for more than one exact test.
///
/// Measured in B4 on two threads against rayon's parallel iterator over the same chunks: claiming
/// from both ends keeps most pairs on the core that tested them at the last frame (the
/// pre-checks' time 89-90 us against 93-94 claiming all from the front), and a thread that runs
/// out of work waits awake (see [`help_until`]).
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
struct BackEnd<'a, C> {
    slots: &'a [Slot<C>],
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
    fn new(slots: &'a [Slot<C>], config: &PipelineConfig, detail: Detail) -> Self {
        BackEnd {
            slots,
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
    /// Measured in B4 on two threads: the pre-checks' time 78-83 us against 87-91 us without,
    /// 71-77 us on one thread.
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
    fn into_contact_changes(self) -> Vec<PairKey> {
        self.contact_changes
            .into_inner()
            .unwrap_or_else(PoisonError::into_inner)
    }

    /// Takes the pairs down the back end, spread over the current rayon pool, leaving each one's
    /// results in its entry, and returns what the tests add up to.
    ///
    /// The calling thread and one task for each other thread of the pool take the pairs from a
    /// [`SharedPairs`], and the caller returns once every pair is tested: exact tests cost from one
    /// to tens of microseconds, against a quarter of one for a pre-check, so the last ones are
    /// shared out one at a time.
    fn run(&self, entries: &mut [&mut PairEntry]) -> Tally {
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
    /// it: the pre-check would most likely fail, after many loops.
    fn pre_check(&self, entries: &mut [&mut PairEntry]) -> Tally {
        let start = Instant::now();
        let mut tally = Tally {
            pairs: entries.len() as u64,
            ..Tally::default()
        };
        for entry in entries.iter_mut() {
            entry.b_to_a = relative_pose(self.slots, entry.pair);
            entry.separated = false;
            if let Some(search) = &self.plane_search
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

/// The pipeline over one scene, generic over the exact test `C`.
pub struct CollisionPipeline<C> {
    slots: Vec<Slot<C>>,
    free: Vec<u32>,
    broad_phase: SweepAndPrune,
    interest: InterestMatrix,
    /// Every pair of interest whose boxes overlap: a pair enters when its overlap starts (or the
    /// interest rules come to allow it) and leaves when the overlap ends (or the rules forbid it).
    pairs: FxHashMap<PairKey, PairEntry>,
    /// The keys of the entries in contact, in the order a frame reports them: kept up to date
    /// from the few pairs whose contact started or ended, so that a frame's report costs in
    /// proportion to the colliding pairs, not to all the pairs of the table.
    colliding: BTreeSet<PairKey>,
    queue: Vec<u32>,
    queued: Vec<bool>,
    warmer: PoolWarmer,
    config: PipelineConfig,
}

impl<C: ExactTest> CollisionPipeline<C> {
    /// An empty scene.
    pub fn new(config: PipelineConfig) -> Self {
        CollisionPipeline {
            slots: Vec::new(),
            free: Vec::new(),
            broad_phase: SweepAndPrune::new(),
            interest: InterestMatrix::new(),
            pairs: FxHashMap::default(),
            colliding: BTreeSet::new(),
            queue: Vec::new(),
            queued: Vec::new(),
            warmer: PoolWarmer::default(),
            config,
        }
    }

    /// Adds an object; it enters the front-end queue, so the next frame tests its pairs.
    pub fn add(&mut self, desc: ObjectDesc<C>) -> Result<ObjectId, PipelineError> {
        check_pose(&desc.pose, || "a new object".to_owned())?;
        let index = match self.free.pop() {
            Some(index) => index,
            None => {
                let index = u32::try_from(self.slots.len())
                    .ok()
                    .filter(|&i| i < u32::MAX >> 1)
                    .ok_or(PipelineError::Full)?;
                self.slots.push(Slot {
                    generation: 0,
                    object: None,
                });
                self.queued.push(false);
                index
            }
        };
        let slot = &mut self.slots[index as usize];
        let id = ObjectId {
            index,
            generation: slot.generation,
        };
        let bounds = Aabb::transformed(desc.model.local_bounds(), &desc.pose);
        slot.object = Some(Object {
            model: desc.model,
            pose: desc.pose,
            key: InterestKey {
                object: id,
                group: desc.group,
                is_static: desc.is_static,
            },
        });
        self.broad_phase.insert(index, bounds);
        // The new object's overlaps enter the pair table now; it is queued, so the next frame
        // tests them.
        for [a, b] in self.broad_phase.drain_started() {
            let pair = ordered(a, b);
            if is_interesting(&self.slots, &self.interest, pair) {
                self.pairs.insert(pair, PairEntry::new(pair));
            }
        }
        self.enqueue(index);
        Ok(id)
    }

    /// Removes an object and every pair it was part of.
    pub fn remove(&mut self, id: ObjectId) -> Result<(), PipelineError> {
        self.object(id)?;
        let slot = &mut self.slots[id.index as usize];
        slot.object = None;
        slot.generation = slot.generation.wrapping_add(1);
        self.broad_phase.remove(id.index);
        self.drop_ended_pairs();
        if std::mem::take(&mut self.queued[id.index as usize]) {
            self.queue.retain(|&index| index != id.index);
        }
        self.interest.forget_object(id);
        self.free.push(id.index);
        Ok(())
    }

    /// Sets an object's pose and puts it in the front-end queue; the next frame tests its pairs.
    /// Moving it again before that frame just replaces the pose.
    pub fn queue_move(&mut self, id: ObjectId, pose: Isometry3<f64>) -> Result<(), PipelineError> {
        self.object(id)?;
        check_pose(&pose, || format!("{id:?}"))?;
        if let Some(object) = &mut self.slots[id.index as usize].object {
            object.pose = pose;
        }
        self.enqueue(id.index);
        Ok(())
    }

    /// The pose an object has in the pipeline.
    pub fn pose(&self, id: ObjectId) -> Result<Isometry3<f64>, PipelineError> {
        Ok(self.object(id)?.pose)
    }

    /// The interest rules in force.
    pub fn interest(&self) -> &InterestMatrix {
        &self.interest
    }

    /// Replaces the interest rules: the pairs they forbid are forgotten, the overlapping pairs they
    /// come to allow are taken in, and every object is queued, so the next frame re-evaluates the
    /// whole scene under the new rules.
    pub fn set_interest(&mut self, interest: InterestMatrix) {
        self.interest = interest;
        let (slots, rules) = (&self.slots, &self.interest);
        self.pairs
            .retain(|&pair, _| is_interesting(slots, rules, pair));
        let pairs = &self.pairs;
        self.colliding.retain(|pair| pairs.contains_key(pair));
        for index in 0..self.slots.len() as u32 {
            if self.slots[index as usize].object.is_none() {
                continue;
            }
            for &other in self.broad_phase.overlaps(index) {
                let pair = (index, other);
                if index < other && is_interesting(&self.slots, &self.interest, pair) {
                    self.pairs
                        .entry(pair)
                        .or_insert_with(|| PairEntry::new(pair));
                }
            }
            self.enqueue(index);
        }
    }

    /// Number of objects in the scene.
    pub fn len(&self) -> usize {
        self.slots.len() - self.free.len()
    }

    /// True when the scene has no object.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn object(&self, id: ObjectId) -> Result<&Object<C>, PipelineError> {
        self.slots
            .get(id.index as usize)
            .filter(|slot| slot.generation == id.generation)
            .and_then(|slot| slot.object.as_ref())
            .ok_or(PipelineError::UnknownObject(id))
    }

    fn live(&self, index: u32) -> &Object<C> {
        live(&self.slots, index)
    }

    fn enqueue(&mut self, index: u32) {
        if self.queue.is_empty() {
            self.warmer.wake();
        }
        if !self.queued[index as usize] {
            self.queued[index as usize] = true;
            self.queue.push(index);
        }
    }

    fn drop_ended_pairs(&mut self) {
        for [a, b] in self.broad_phase.drain_ended() {
            let pair = ordered(a, b);
            self.pairs.remove(&pair);
            self.colliding.remove(&pair);
        }
    }

    /// Runs one frame over the front-end queue and reports every colliding pair of the scene.
    /// Parallel stages run on the current rayon pool (call it inside `ThreadPool::install` to
    /// choose the threads; best around the whole loop that queues moves and runs frames, so
    /// that no frame waits for a hand-over to the pool).
    ///
    /// The pairs whose boxes overlapped at the last frame and involve a moved object mostly still
    /// overlap (coherence), so the back end starts on them while the broad phase moves the boxes,
    /// the two running side by side; the pairs whose overlap ended are then dropped, and those
    /// whose overlap started go down the back end after them. A frame's answers are those of
    /// running the stages one after the other; only the wall time differs.
    ///
    /// The pair table holds only pairs of interest: the interest matrix judges a pair when its
    /// overlap starts and when the rules change, not at every frame. The back end tests the
    /// table's entries in place. Both keep the serial parts of a frame short: on two threads, a
    /// serial pass over the pairs costs more than on one, each entry having been written last by
    /// the other core (B4 in the README).
    pub fn run_frame(&mut self, detail: Detail) -> FrameReport {
        let frame_start = Instant::now();
        let moved = self.queue.len() as u64;
        let objects = self.len() as u64;
        let mut stats = FrameStats {
            moved,
            ..FrameStats::default()
        };
        // When everything moved, every pair is carried: taking them without reading their keys
        // leaves the entries in the cache of the core that tested them last.
        let everything_moved = moved == objects;
        let queued = &self.queued;
        let mut carried: Vec<&mut PairEntry> = self
            .pairs
            .values_mut()
            .filter(|entry| {
                everything_moved || queued[entry.pair.0 as usize] || queued[entry.pair.1 as usize]
            })
            .collect();
        let back_end = BackEnd::new(&self.slots, &self.config, detail);
        let boxes = BoxStage {
            broad_phase: &mut self.broad_phase,
            slots: &self.slots,
            queue: &self.queue,
            queued,
            interest: &self.interest,
        };
        self.warmer.release();
        let carried_done = AtomicBool::new(false);
        let (mut update, carried_tally) = rayon::join(
            || {
                let update = boxes.update(&back_end);
                if rayon::current_num_threads() > 1 {
                    help_until(|| carried_done.load(Ordering::Acquire));
                }
                update
            },
            || {
                let tally = back_end.run(&mut carried);
                carried_done.store(true, Ordering::Release);
                tally
            },
        );
        let contact_changes = back_end.into_contact_changes();
        let mut tally = carried_tally;
        tally += update.started_tally;
        for &index in &self.queue {
            self.queued[index as usize] = false;
        }
        self.queue.clear();
        // Ended pairs go before the started ones come in: a pair whose overlap ended and started
        // again within the update has a fresh entry among the started pairs.
        for pair in &update.ended {
            if let Some(entry) = self.pairs.remove(pair) {
                tally.forget(&entry);
            }
        }
        for entry in update.started.drain(..) {
            self.pairs.insert(entry.pair, entry);
        }
        // The table is now the truth for every pair whose membership may have changed.
        for pair in update.ended.iter().chain(&contact_changes) {
            if self
                .pairs
                .get(pair)
                .is_some_and(|entry| entry.contact.is_some())
            {
                self.colliding.insert(*pair);
            } else {
                self.colliding.remove(pair);
            }
        }
        stats.broad_phase = StageCounters {
            pairs_in: moved * (objects - moved) + moved * moved.saturating_sub(1) / 2,
            pairs_out: update.overlapping as u64,
            time: update.time,
        };
        stats.interest = StageCounters {
            pairs_in: stats.broad_phase.pairs_out,
            pairs_out: tally.pairs,
            time: update.interest_time,
        };
        stats.separating_plane = StageCounters {
            pairs_in: tally.pairs,
            pairs_out: tally.unseparated,
            time: tally.plane_time,
        };
        stats.exact = StageCounters {
            pairs_in: tally.unseparated,
            pairs_out: tally.colliding,
            time: tally.exact_time,
        };
        stats.plane_loops = tally.plane_loops;
        stats.split_tests = tally.split_tests;
        stats.exact_work = tally.exact_work;
        if detail == Detail::TrianglePairs {
            self.fill_missing_triangles();
        }
        stats.total = frame_start.elapsed();
        FrameReport {
            colliding: self.colliding_pairs(detail),
            stats,
        }
    }

    /// Computes triangle pairs for colliding pairs that were last tested without them.
    fn fill_missing_triangles(&mut self) {
        let slots = &self.slots;
        let mut missing: Vec<&mut PairEntry> = self
            .pairs
            .values_mut()
            .filter(|entry| matches!(entry.contact, Some(None)))
            .collect();
        missing.par_iter_mut().for_each(|entry| {
            let [a, b] = models(slots, entry.pair);
            let b_to_a = relative_pose(slots, entry.pair);
            let mut triangles = Vec::new();
            a.exact().intersecting_pairs(
                b.exact(),
                &b_to_a,
                &mut triangles,
                &mut QueryStats::default(),
            );
            entry.contact = Some(Some(triangles));
        });
    }

    /// Every colliding pair of the scene, sorted: the pair keys are ordered as the ids are.
    fn colliding_pairs(&self, detail: Detail) -> Vec<CollidingPair> {
        debug_assert!(
            self.colliding.iter().all(|pair| self
                .pairs
                .get(pair)
                .is_some_and(|entry| entry.contact.is_some()))
                && self.colliding.len()
                    == self.pairs.values().filter(|e| e.contact.is_some()).count(),
            "the set of colliding pairs is the pair table's entries in contact"
        );
        self.colliding
            .iter()
            .map(|&(a, b)| CollidingPair {
                a: self.live(a).key.object,
                b: self.live(b).key.object,
                triangles: match detail {
                    Detail::Pairs => Vec::new(),
                    Detail::TrianglePairs => self.pairs[&(a, b)]
                        .contact
                        .as_ref()
                        .and_then(Option::as_ref)
                        .cloned()
                        .unwrap_or_default(),
                },
            })
            .collect()
    }
}

/// The bounding-box stage of a frame, with what it reads: the half of
/// [`CollisionPipeline::run_frame`] that runs beside the back end's carried pairs.
struct BoxStage<'a, C> {
    broad_phase: &'a mut SweepAndPrune,
    slots: &'a [Slot<C>],
    queue: &'a [u32],
    queued: &'a [bool],
    interest: &'a InterestMatrix,
}

/// What the bounding-box stage changed, and the back end's results for the started pairs.
struct BoxUpdate {
    /// Wall time of moving the boxes.
    time: Duration,
    /// Pairs whose boxes overlap after the update and that involve a queued object.
    overlapping: usize,
    /// Pairs whose overlap ended, sorted.
    ended: Vec<PairKey>,
    /// The pairs of interest whose overlap started, tested.
    started: Vec<PairEntry>,
    /// Time of the interest matrix on the started pairs.
    interest_time: Duration,
    /// What the tests of the started pairs add up to.
    started_tally: Tally,
}

impl<C: ExactTest> BoxStage<'_, C> {
    /// Moves the boxes of the queued objects to their objects' poses, then gathers the pairs
    /// whose overlap ended and tests those of interest whose overlap started: here rather than
    /// after the join, so that this work too runs beside the carried pairs instead of after them.
    fn update(self, back_end: &BackEnd<'_, C>) -> BoxUpdate {
        let start = Instant::now();
        let updates: Vec<(u32, Aabb)> = self
            .queue
            .iter()
            .filter_map(|&index| {
                let object = self.slots[index as usize].object.as_ref()?;
                Some((
                    index,
                    Aabb::transformed(object.model.local_bounds(), &object.pose),
                ))
            })
            .collect();
        self.broad_phase.update_many(&updates);
        let time = start.elapsed();

        let overlapping = self
            .queue
            .iter()
            .map(|&index| {
                let overlaps = self.broad_phase.overlaps(index);
                overlaps
                    .iter()
                    .filter(|&&other| !self.queued[other as usize] || index < other)
                    .count()
            })
            .sum();
        let mut ended: Vec<PairKey> = self
            .broad_phase
            .drain_ended()
            .map(|[a, b]| ordered(a, b))
            .collect();
        ended.sort_unstable();
        let mut started: Vec<PairKey> = self
            .broad_phase
            .drain_started()
            .map(|[a, b]| ordered(a, b))
            .collect();
        // An overlap can start and end again within one update of several boxes.
        started.retain(|&(a, b)| self.broad_phase.overlaps(a).contains(&b));

        let interest_start = Instant::now();
        let mut started: Vec<PairEntry> = started
            .into_iter()
            .filter(|&pair| is_interesting(self.slots, self.interest, pair))
            .map(PairEntry::new)
            .collect();
        let interest_time = interest_start.elapsed();
        let started_tally = back_end.run(&mut started.iter_mut().collect::<Vec<_>>());
        BoxUpdate {
            time,
            overlapping,
            ended,
            started,
            interest_time,
            started_tally,
        }
    }
}

/// Keeps the other threads of the current rayon pool awake from a frame's first queued move until
/// the frame's back end starts.
///
/// A pool thread asleep between frames took 23-31 us to take up the back end once a two-thread
/// frame handed it work (measured in B4). Woken by the first move but left idle, it often fell
/// asleep again while the moves were queued: its first pair came 6.7-26 us after the back end's
/// start (means over the frames of seven runs), against 1.4-1.9 us in most runs when it waited
/// awake. So it is handed a task that spins until the back end starts, or [`WARM_SPIN_LIMIT`]
/// passes (a frame that is queued but not run soon). Only from inside a pool of several threads:
/// elsewhere there is no pool of the pipeline's to wake.
#[derive(Default)]
struct PoolWarmer {
    /// Counts the back ends started: a spinning task stops when it changes.
    back_ends: Arc<AtomicU64>,
}

/// The cores of this machine: a [`PoolWarmer`] keeps no more threads spinning than there are
/// cores besides the caller's, so that they never take the core the caller queues moves on.
fn cores() -> usize {
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, usize::from))
}

/// Longest a [`PoolWarmer`] task spins.
const WARM_SPIN_LIMIT: Duration = Duration::from_micros(300);

impl PoolWarmer {
    /// Wakes the other threads of the current pool and keeps them awake until [`Self::release`].
    fn wake(&self) {
        if rayon::current_thread_index().is_none() {
            return;
        }
        let started = self.back_ends.load(Ordering::Relaxed);
        for _ in 1..rayon::current_num_threads().min(cores()) {
            let back_ends = Arc::clone(&self.back_ends);
            rayon::spawn(move || {
                let deadline = Instant::now() + WARM_SPIN_LIMIT;
                while back_ends.load(Ordering::Relaxed) == started && Instant::now() < deadline {
                    std::hint::spin_loop();
                }
            });
        }
    }

    /// Lets the spinning tasks end: the back end's work is about to be handed out.
    fn release(&self) {
        self.back_ends.fetch_add(1, Ordering::Relaxed);
    }
}

/// Waits for `done` awake: runs the current pool's pending tasks meanwhile, or spins.
///
/// Rayon's own waits (at the end of a `join` or a `scope`) put a thread to sleep after a few
/// microseconds without work, and waking it takes microseconds more, often tens on a virtual
/// machine: measured in B4, the last of a frame's tests ended 11-15 us before the frame's
/// parallel part did, on both threads, against 3-5 us waiting this way. Only for waits that end
/// within a frame: a thread kept spinning from frame to frame was taken off its core by the
/// host more often (B4 in the README).
fn help_until(done: impl Fn() -> bool) {
    while !done() {
        help_once();
    }
}

/// Runs one pending task of the current pool, or spins once if there is none.
fn help_once() {
    if rayon::yield_now() != Some(rayon::Yield::Executed) {
        std::hint::spin_loop();
    }
}

/// The object in slot `index`, which a pair names: pairs name only live objects.
fn live<C>(slots: &[Slot<C>], index: u32) -> &Object<C> {
    slots[index as usize]
        .object
        .as_ref()
        .expect("pairs name live objects")
}

/// Whether the interest rules let a pair of live objects be tested.
fn is_interesting<C>(slots: &[Slot<C>], rules: &InterestMatrix, (a, b): PairKey) -> bool {
    rules.is_interesting(&live(slots, a).key, &live(slots, b).key)
}

fn models<C>(slots: &[Slot<C>], (a, b): PairKey) -> [&CollisionModel<C>; 2] {
    [a, b].map(|index| &*live(slots, index).model)
}

/// The pose of a pair's second object in its first one's frame.
fn relative_pose<C>(slots: &[Slot<C>], (a, b): PairKey) -> Isometry3<f64> {
    live(slots, a).pose.inv_mul(&live(slots, b).pose)
}

fn ordered(a: u32, b: u32) -> PairKey {
    if a < b { (a, b) } else { (b, a) }
}

/// Refuses poses with non-finite components or a rotation far from unit length.
fn check_pose(pose: &Isometry3<f64>, name: impl Fn() -> String) -> Result<(), PipelineError> {
    let translation: &Vector3<f64> = &pose.translation.vector;
    let quaternion = pose.rotation.quaternion();
    if !translation
        .iter()
        .chain(quaternion.coords.iter())
        .all(|v| v.is_finite())
    {
        return Err(PipelineError::InvalidPose(
            name(),
            "a component is not finite",
        ));
    }
    if (quaternion.norm() - 1.0).abs() > 1e-6 {
        return Err(PipelineError::InvalidPose(
            name(),
            "the rotation is not a unit quaternion",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
