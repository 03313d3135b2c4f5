//! The collision-detection pipeline over a scene (PAPER §2, §2.3).
//!
//! Objects (a shared collision model, a pose, a group, a static flag) are added and removed; each
//! frame, the objects moved since the last frame (the front-end queue) send only their pairs down
//! the filters: the bounding-box stage ([`SweepAndPrune`], in `box_stage`), the
//! [`InterestMatrix`], the separating-plane pre-check ([`SeparatingPlane`]) and the exact test
//! ([`ExactTest`]), the last two in the parallel back end (`back_end`). The result is the set of
//! colliding pairs in the whole scene and, on request, their triangle pairs (`report`); pairs of
//! objects that did not move keep their last answer. Each stage counts the pairs it took in and
//! let through, and its time.
//!
//! A pair that collided when last tested skips the pre-check (it would most likely fail to find a
//! plane, after many loops) and goes straight to the exact test. A pair the caller knows to be
//! apart at the objects' current poses ([`CollisionPipeline::set_known_apart`]) skips both.
//!
//! The back end is parallel on the current rayon pool: the threads claim the pairs of a frame a
//! chunk at a time until none is left (dynamic load balancing), each pair going through its
//! pre-check and, if need be, its exact test on the same thread (coarse grain); it starts on the
//! pairs that overlapped at the last frame while the bounding-box stage moves the boxes, so that
//! the broad phase, mostly serial, runs beside it instead of before it (see
//! [`CollisionPipeline::run_frame`]); and the traversal of a pair expected to be expensive is
//! itself split across the threads (fine grain; see [`PipelineConfig::split_min_bv_tests`]).
//! `pool` keeps the pool's threads awake from a frame's first move to the end of its back end.

mod back_end;
mod box_stage;
mod exact;
pub mod interest;
mod objects;
mod pool;
mod report;

pub use exact::ExactTest;
pub use objects::{CollisionModel, ObjectDesc, ObjectId, PipelineError};
pub use report::{CollidingPair, Detail, FrameReport, FrameStats, StageCounters};

use super::QueryStats;
use super::broad_phase::{Aabb, SweepAndPrune};
use super::separating_plane::{PlaneSearch, SeparatingPlane};
use back_end::{BackEnd, Tally};
use box_stage::{BoxStage, BoxUpdate};
use interest::{InterestKey, InterestMatrix};
use nalgebra::Isometry3;
use objects::{Object, Slot, check_pose, live, models, relative_pose};
use pool::{PoolWarmer, help_until};
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use std::collections::BTreeSet;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

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
/// A split traversal hands tasks over and wakes idle threads, so it pays only for long tests; a
/// pair's work changes little from frame to frame, so its last test's count predicts the next
/// one's cost. The bound sits where splitting starts to win, erring towards not splitting.
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

/// A pair of object slots, smaller index first.
type PairKey = (u32, u32);

/// Two objects proved apart outside the pipeline, by the same exact test on the same models, at
/// the poses given: a grasped part's sliding world tests every pose it shows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KnownApart {
    /// One object and the pose it was tested at.
    pub a: (ObjectId, Isometry3<f64>),
    /// The other object and the pose it was tested at.
    pub b: (ObjectId, Isometry3<f64>),
}

/// The pairs known apart, by pair, with the two poses (in the pair's order) they were tested at.
type KnownApartPairs = FxHashMap<PairKey, [Isometry3<f64>; 2]>;

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
    known_apart: KnownApartPairs,
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
            known_apart: FxHashMap::default(),
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

    /// Replaces the pairs known to be apart: from now on, a pair among them whose two objects
    /// are exactly at the poses given, and which did not collide when last tested, counts as
    /// separated without a pre-check or an exact test. Facts naming a removed object are dropped.
    /// The test that proved them must be the pipeline's own exact test on the same models: the
    /// pipeline then answers as it would have.
    pub fn set_known_apart(&mut self, facts: impl IntoIterator<Item = KnownApart>) {
        self.known_apart.clear();
        for KnownApart { a, b } in facts {
            if self.object(a.0).is_err() || self.object(b.0).is_err() || a.0 == b.0 {
                continue;
            }
            let (pair, poses) = if a.0.index < b.0.index {
                ((a.0.index, b.0.index), [a.1, b.1])
            } else {
                ((b.0.index, a.0.index), [b.1, a.1])
            };
            self.known_apart.insert(pair, poses);
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
    /// table's entries in place. Both keep the serial parts of a frame short: on several threads,
    /// a serial pass over the pairs waits for entries last written by other cores.
    pub fn run_frame(&mut self, detail: Detail) -> FrameReport {
        let frame_start = Instant::now();
        let moved = self.queue.len() as u64;
        let objects = self.len() as u64;
        let (mut update, mut tally, contact_changes) = self.boxes_beside_back_end(detail);
        self.clear_queue();
        self.apply_box_update(&mut update, &mut tally);
        self.update_colliding(&update.ended, &contact_changes);
        let mut stats = FrameStats::counted(moved, objects, &update, &tally);
        if detail == Detail::TrianglePairs {
            self.fill_missing_triangles();
        }
        stats.total = frame_start.elapsed();
        FrameReport {
            colliding: self.colliding_pairs(detail),
            stats,
        }
    }

    /// The bounding-box stage and the back end side by side: the back end tests the carried
    /// pairs (those of the table that involve a queued object) while the box stage moves the
    /// boxes, then tests the pairs of interest whose overlap started. Returns the box stage's
    /// changes, what all the tests add up to, and the pairs whose contact started or ended.
    fn boxes_beside_back_end(&mut self, detail: Detail) -> (BoxUpdate, Tally, Vec<PairKey>) {
        // When everything moved, every pair is carried: taking them without reading their keys
        // leaves the entries in the cache of the core that tested them last.
        let everything_moved = self.queue.len() == self.len();
        let queued = &self.queued;
        let mut carried: Vec<&mut PairEntry> = self
            .pairs
            .values_mut()
            .filter(|entry| {
                everything_moved || queued[entry.pair.0 as usize] || queued[entry.pair.1 as usize]
            })
            .collect();
        let back_end = BackEnd::new(&self.slots, &self.known_apart, &self.config, detail);
        let boxes = BoxStage {
            broad_phase: &mut self.broad_phase,
            slots: &self.slots,
            queue: &self.queue,
            queued,
            interest: &self.interest,
        };
        self.warmer.release();
        let carried_done = AtomicBool::new(false);
        let (update, carried_tally) = rayon::join(
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
        (update, tally, contact_changes)
    }

    /// Empties the front-end queue: its objects' pairs are tested.
    fn clear_queue(&mut self) {
        for &index in &self.queue {
            self.queued[index as usize] = false;
        }
        self.queue.clear();
    }

    /// Brings the pair table up to date with the box stage: the pairs whose overlap ended leave it
    /// (and the pair counts of `tally`), the tested pairs whose overlap started enter it.
    fn apply_box_update(&mut self, update: &mut BoxUpdate, tally: &mut Tally) {
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
    }

    /// Brings the set of colliding pairs up to date from the pairs whose membership may have
    /// changed: those whose overlap ended and those whose contact started or ended. The pair
    /// table is the truth for them.
    fn update_colliding(&mut self, ended: &[PairKey], contact_changes: &[PairKey]) {
        for pair in ended.iter().chain(contact_changes) {
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

/// Whether the interest rules let a pair of live objects be tested.
fn is_interesting<C>(slots: &[Slot<C>], rules: &InterestMatrix, (a, b): PairKey) -> bool {
    rules.is_interesting(&live(slots, a).key, &live(slots, b).key)
}

fn ordered(a: u32, b: u32) -> PairKey {
    if a < b { (a, b) } else { (b, a) }
}

#[cfg(test)]
mod tests;
