//! What the queries of a pair of trees on one thread leave to the next one (temporal
//! coherence): the pair of leaves last in contact (the witness), the last proof that the roots
//! are apart, and the front where the last walk ended. Kept per thread, in a small table of
//! slots indexed by the two trees' ids.

use std::cell::RefCell;

use nalgebra::{Isometry3, Matrix3, Point3, Vector3};

use super::certificates::DueCertificates;
use super::front::{Front, Placement};
use super::parallel::{PARALLEL_MIN_STARTS, SEQUENTIAL_PREFIX_STARTS, top_starts};
use super::query::{LazyPair, affine_pair};
use super::root_separation::RootSeparation;
use super::traverse::{FrontPair, Walk};
use super::tree::DopTree;
use crate::collision::QueryStats;
use crate::collision::triangle::triangles_intersect;

/// What the last first-hit or all-pairs query between a pair of trees on this thread leaves to
/// the next one.
/// Poses change little between frames (temporal coherence): a pair in contact usually stays in
/// contact through the same or nearby triangles, and a pair proved apart stays apart at most of
/// the node pairs where the proof ended, by a margin that only motion towards each other can use
/// up.
#[derive(Default)]
pub(super) struct PairMemory {
    /// A's and B's ids; 0 marks an empty slot.
    ids: (u64, u64),
    /// The pair of leaves whose triangles intersected at the last query that found contact,
    /// kept through one query without (a free pose between two trial poses in contact), and the
    /// queries without contact since.
    witness: Option<[u32; 2]>,
    misses_since_witness: u32,
    /// The last query found the trees apart at its walk from the remembered front, the roots'
    /// probes having failed: the next one walks from the front before it probes the roots.
    apart_by_front: bool,
    /// How [`roots_separated_along_offset`](super::root_separation::roots_separated_along_offset)
    /// last proved the roots apart: checked first next time.
    pub(super) root_separation: Option<RootSeparation>,
    /// B's pose in A's frame at the last traversal that recorded a front, and that front: every
    /// pair of leaves lies under one of its node pairs, proved apart or to be tested again.
    pub(super) front_pose: Option<(Matrix3<f64>, Vector3<f64>)>,
    pub(super) front: Front,
    /// B's pose in A's frame at the last query that reached the memory: a query far from it
    /// and from the front's pose follows no coherent motion
    /// ([`PairMemory::far_from_last_query`]).
    pub(super) last_query: Option<Isometry3<f64>>,
    /// Buffers reused across queries: the pairs to test again, the certificates due among
    /// them and those to renew, and where their tests ended.
    retest: Vec<(u32, u32)>,
    pub(super) due: [DueCertificates; 2],
    ended: Vec<FrontPair>,
}

/// Tree pairs remembered per thread (a power of two).
pub(super) const MEMORY_SLOTS: usize = 64;

/// Levels above the old witness's leaves at which a first-hit query searches first when the
/// witness no longer intersects (subtrees of up to 2^levels triangles each).
const WITNESS_SEARCH_LEVELS: u32 = 4;

/// Queries without contact through which the last witness is kept: sliding alternates trial
/// poses in contact with the free pose found between them, and the next trial pose usually
/// touches where the last one did.
const WITNESS_KEPT_MISSES: u32 = 1;

/// Largest front walked before the roots' probes when it proved the last query apart: scanning a
/// larger one costs more than the probes it would save.
const FRONT_FIRST_MAX_PAIRS: usize = 128;

/// A carried front is used while B moved by at most this fraction of the smaller bounding radius
/// since the previous query; beyond, most of it would be tested again and the roots are cheaper.
const FRONT_MAX_MOTION: f64 = 0.05;

/// A carried front is dropped when it holds more than this many times the pairs of a fresh one
/// (plus [`FRONT_SLACK_PAIRS`]).
const FRONT_MAX_GROWTH: usize = 2;

/// The growth bound of a steady front ([`Front::steady`]).
const FRONT_MAX_GROWTH_STEADY: usize = 4;

/// Share of a front re-tested by a query below which the front is steady.
const STEADY_DUE_SHARE: f64 = 0.1;

/// Pairs a carried front may exceed its growth bound by (small fronts grow fast in relative terms).
const FRONT_SLACK_PAIRS: usize = 64;

thread_local! {
    /// Boxed, so that taking a memory out of its slot and putting it back moves a pointer, not
    /// the memory's few hundred bytes: a query far apart does little else.
    static PAIR_MEMORIES: RefCell<Vec<Option<Box<PairMemory>>>> =
        const { RefCell::new(Vec::new()) };
}

/// Whether and how a query can start from the remembered front.
pub(super) enum Carry {
    /// From the front, after a further `turn`: its due pairs are in `retest` and `due`.
    Advanced { turn: f64 },
    /// From the roots; with `keep_on_hit`, the old front is kept when the query finds contact
    /// (a far excursion, such as a trial pose deep inside an obstacle, between poses near the
    /// front's own).
    Restart { keep_on_hit: bool },
}

impl PairMemory {
    /// The slot of the tree pair with ids `(a, b)`.
    pub(super) fn slot((a, b): (u64, u64)) -> usize {
        (a.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ b) as usize % MEMORY_SLOTS
    }

    /// Takes this thread's memory of the pair `(a, b)` out of its slot (a blank one, keeping the
    /// slot's buffers, if the slot remembers another pair; a new one if a query of this thread
    /// already holds it).
    pub(super) fn take(a: &DopTree, b: &DopTree) -> Box<PairMemory> {
        PAIR_MEMORIES.with_borrow_mut(|memories| Self::claim(Self::slot_of(memories, a, b), a, b))
    }

    /// Takes the memory as [`Self::take`] does, unless the remembered proof that the roots are
    /// apart still holds with B at `b_to_a` (its bounding centre at `centre_b`): then the memory
    /// records the query in its slot as [`Self::first_hit`] would have, and `None` says the trees
    /// are apart, without the memory's trip out of its slot and back. (Where the proof fails,
    /// [`Self::first_hit`] checks it again: cheap beside the node tests that follow.)
    pub(super) fn take_unless_apart(
        a: &DopTree,
        b: &DopTree,
        b_to_a: &Isometry3<f64>,
        centre_b: &Point3<f64>,
    ) -> Option<Box<PairMemory>> {
        PAIR_MEMORIES.with_borrow_mut(|memories| {
            let slot = Self::slot_of(memories, a, b);
            if let Some(memory) = slot.as_deref_mut()
                && memory.ids == (a.id, b.id)
                && memory.witness.is_none()
                && RootSeparation::still_holds(&memory.root_separation, a, b, b_to_a, centre_b)
            {
                memory.remember_roots_apart();
                memory.last_query = Some(*b_to_a);
                return None;
            }
            Some(Self::claim(slot, a, b))
        })
    }

    /// This thread's slot for the pair `(a, b)` (the slots made on first use).
    fn slot_of<'m>(
        memories: &'m mut Vec<Option<Box<PairMemory>>>,
        a: &DopTree,
        b: &DopTree,
    ) -> &'m mut Option<Box<PairMemory>> {
        if memories.is_empty() {
            memories.resize_with(MEMORY_SLOTS, || Some(Box::default()));
        }
        &mut memories[Self::slot((a.id, b.id))]
    }

    /// Takes the memory out of `slot` for the pair `(a, b)`: a blank one (keeping the slot's
    /// buffers) if the slot remembers another pair, a new one if the slot is empty.
    fn claim(slot: &mut Option<Box<PairMemory>>, a: &DopTree, b: &DopTree) -> Box<PairMemory> {
        let mut memory = slot.take().unwrap_or_default();
        if memory.ids != (a.id, b.id) {
            memory.ids = (a.id, b.id);
            memory.witness = None;
            memory.root_separation = None;
            memory.front_pose = None;
            memory.apart_by_front = false;
            memory.last_query = None;
        }
        memory
    }

    /// Puts the memory back in its slot.
    pub(super) fn put_back(memory: Box<PairMemory>) {
        PAIR_MEMORIES.with_borrow_mut(|memories| {
            let slot = Self::slot(memory.ids);
            memories[slot] = Some(memory);
        });
    }

    /// A first-hit query that starts from what the previous ones left: the old witness, the
    /// subtrees around it, the old front where the motion may have closed its gaps; the roots
    /// only when there is nothing usable. Remembers what this query found.
    pub(super) fn first_hit<const K: usize>(
        &mut self,
        a: &DopTree,
        b: &DopTree,
        b_to_a: &Isometry3<f64>,
        centre_b: &Point3<f64>,
        stats: &mut QueryStats,
        parallel: bool,
    ) -> bool {
        if let Some(leaves) = self.witness
            && witness_still_intersects(a, b, b_to_a, leaves, stats)
        {
            return true;
        }
        // Near a pair apart, the probes of the roots usually fail again where they failed last
        // time, and the front settles the query alone.
        if self.apart_by_front
            && self.front.len() <= FRONT_FIRST_MAX_PAIRS
            && self.witness.is_none()
            && !RootSeparation::still_holds(&self.root_separation, a, b, b_to_a, centre_b)
        {
            let pair = LazyPair::<K>::new(a, b, b_to_a);
            let (carry, placement) = self.carry_front(&pair);
            if let Carry::Advanced { .. } = carry {
                let hit = self.search_carried::<K>(&pair, carry, placement, stats, parallel);
                return self.remember_walk(hit);
            }
        }
        let Some(pair) = affine_pair::<K>(a, b, b_to_a, centre_b, &mut self.root_separation) else {
            stats.bv_tests += 1;
            self.remember_roots_apart();
            return false;
        };
        // The contact usually moved only a few triangles along: search the subtrees around the
        // old witness before the whole trees.
        let near = self.witness.and_then(|[leaf_a, leaf_b]| {
            let start = (
                a.ancestor(leaf_a, WITNESS_SEARCH_LEVELS),
                b.ancestor(leaf_b, WITNESS_SEARCH_LEVELS),
            );
            pair.get().run_walk::<K>(Walk::from(&[start]), stats)
        });
        let mut detached = false;
        let hit = near.or_else(|| {
            let (carry, placement) = self.carry_front(&pair);
            // A restart that keeps the front on a hit: B moved too far from the front's pose.
            if let Carry::Restart { keep_on_hit: true } = carry
                && self.far_from_last_query(&pair)
            {
                detached = true;
                return pair.get().run::<false, K>(stats, &mut Vec::new(), parallel);
            }
            self.search_carried::<K>(&pair, carry, placement, stats, parallel)
        });
        let found = self.remember_walk(hit);
        // A detached walk proved nothing about the front: the next query must not start there.
        self.apart_by_front &= !detached;
        found
    }

    /// Remembers a query that the roots' test proved apart. The front, if any, stays valid: its
    /// pose is kept with it.
    fn remember_roots_apart(&mut self) {
        self.apart_by_front = false;
        self.remember_witness(None);
    }

    /// Remembers what a query's walk found (its hit, if any) and returns whether it found
    /// contact: the witness, and whether the walk proved the trees apart, which sends the next
    /// query to the front first.
    fn remember_walk(&mut self, hit: Option<[u32; 2]>) -> bool {
        self.apart_by_front = hit.is_none();
        self.remember_witness(hit);
        hit.is_some()
    }

    /// Keeps a query's witness, or the old one through [`WITNESS_KEPT_MISSES`] queries without.
    fn remember_witness(&mut self, hit: Option<[u32; 2]>) {
        if hit.is_some() {
            self.witness = hit;
            self.misses_since_witness = 0;
        } else {
            self.misses_since_witness += 1;
            if self.misses_since_witness > WITNESS_KEPT_MISSES {
                self.witness = None;
            }
        }
    }

    /// The traversal of a first-hit query from the remembered front (or from the roots), as
    /// [`PairMemory::carry_front`] decided, split across rayon's threads when `parallel` and
    /// long. A query without a hit leaves the front where it ended; one with a hit leaves the
    /// front as it was when it came from it.
    fn search_carried<const K: usize>(
        &mut self,
        pair: &LazyPair<'_, K>,
        carry: Carry,
        placement: Placement,
        stats: &mut QueryStats,
        parallel: bool,
    ) -> Option<[u32; 2]> {
        let (a, b) = (pair.a, pair.b);
        // A restart costs about as much as the last complete front was large.
        let split = parallel
            && rayon::current_num_threads() > 1
            && match carry {
                Carry::Advanced { .. } => self.retest.len() >= PARALLEL_MIN_STARTS,
                Carry::Restart { .. } => self.front.fresh_len.unwrap_or(0) >= PARALLEL_MIN_STARTS,
            };
        let top_cut;
        let (starts, sequential): (&[(u32, u32)], usize) = match carry {
            Carry::Advanced { .. } => (&self.retest, SEQUENTIAL_PREFIX_STARTS),
            Carry::Restart { .. } if split => {
                top_cut = top_starts(a, b);
                (&top_cut, 0)
            }
            Carry::Restart { .. } => (&[(0, 0)], 0),
        };
        // Nothing due: the front proves the trees apart without a test (nor the set-up of one).
        let hit = if starts.is_empty() {
            None
        } else if split {
            pair.get()
                .run_walk_parallel::<K>(starts, sequential, &mut self.ended, stats)
        } else {
            let walk = Walk {
                starts,
                stop: None,
                front: Some(&mut self.ended),
            };
            pair.get().run_walk::<K>(walk, stats)
        };
        match carry {
            Carry::Advanced { .. } | Carry::Restart { keep_on_hit: true } if hit.is_some() => {
                return hit;
            }
            // A split walk stopped by a hit leaves no complete front: the next query restarts.
            Carry::Restart { .. } if split && hit.is_some() => {
                self.front_pose = None;
                return hit;
            }
            // A first hit leaves unexplored pairs high up in the trees, so its front
            // understates a complete one: the measure is the first front since the restart
            // that has no hit.
            _ => self.keep_front(&carry, &placement, hit.is_none(), pair),
        }
        hit
    }

    /// An all-pairs query from the remembered front (or from the roots): every pair of leaves
    /// the front holds without a certificate, or whose certificate the motion may have expired,
    /// is walked again; the pairs of intersecting triangles go to `out`. The walk is complete
    /// whatever it finds, so its front is kept. Returns whether any pair intersects.
    pub(super) fn all_pairs<const K: usize>(
        &mut self,
        pair: &LazyPair<'_, K>,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
    ) -> bool {
        let (carry, placement) = self.carry_front(pair);
        let starts: &[(u32, u32)] = match carry {
            Carry::Advanced { .. } => &self.retest,
            Carry::Restart { .. } => &[(0, 0)],
        };
        let walk = Walk {
            starts,
            stop: None,
            front: Some(&mut self.ended),
        };
        let found = out.len();
        if !starts.is_empty() {
            pair.get().sequential::<true, K>(walk, stats, out);
        }
        self.keep_front(&carry, &placement, true, pair);
        out.len() > found
    }

    /// Makes the front where this query's walk ended (`ended`): settled into the old one when
    /// the walk came from it, a new one after a restart. `complete`: the walk covered every pair
    /// of leaves, so its front measures the fresh size if none is known since the restart.
    fn keep_front<const K: usize>(
        &mut self,
        carry: &Carry,
        placement: &Placement,
        complete: bool,
        pair: &LazyPair<'_, K>,
    ) {
        match *carry {
            Carry::Advanced { turn } => {
                self.front.steady =
                    (self.retest.len() as f64) < STEADY_DUE_SHARE * self.front.len() as f64;
                self.front
                    .settle([pair.a, pair.b], turn, &self.due, &self.ended, placement);
            }
            Carry::Restart { .. } => {
                self.front.restart();
                self.front.add([pair.a, pair.b], &self.ended, placement);
                self.front.fresh_len = None;
            }
        }
        if complete && self.front.fresh_len.is_none() {
            self.front.fresh_len = Some(self.front.len());
        }
        self.front_pose = Some((pair.rotation, pair.translation));
    }

    /// Whether the old front is usable at `pair`'s pose, and if so its due pairs in `retest`
    /// and `due`; also where the trees are for the certificates, and `ended` emptied for the
    /// walk. Says to restart when there is no front, B moved too far (beyond a fraction of the
    /// smaller radius), or the front grew too large.
    pub(super) fn carry_front<const K: usize>(
        &mut self,
        pair: &LazyPair<'_, K>,
    ) -> (Carry, Placement) {
        let (a, b) = (pair.a, pair.b);
        let placement = Placement::new(a, b, &pair.rotation, &pair.translation);
        self.ended.clear();
        let Some((old_rotation, old_translation)) = &self.front_pose else {
            return (Carry::Restart { keep_on_hit: false }, placement);
        };
        let growth = if self.front.steady {
            FRONT_MAX_GROWTH_STEADY
        } else {
            FRONT_MAX_GROWTH
        };
        if let Some(fresh_len) = self.front.fresh_len
            && self.front.len() > growth * fresh_len + FRONT_SLACK_PAIRS
        {
            return (Carry::Restart { keep_on_hit: false }, placement);
        }
        let (turn, far) = motion_since(pair, old_rotation, old_translation);
        if far {
            return (Carry::Restart { keep_on_hit: true }, placement);
        }
        self.front
            .due(turn, &placement, &mut self.retest, &mut self.due);
        (Carry::Advanced { turn }, placement)
    }

    /// Whether a query at `pair`'s pose is far ([`motion_since`]) from the last query's. A
    /// first-hit query far from both the front's pose and the last query's is detached (trees
    /// shared by many pairs of objects, or random poses): no motion connects it to the queries
    /// around it, so it walks from the roots without paying for a front, and leaves the old one.
    fn far_from_last_query<const K: usize>(&self, pair: &LazyPair<'_, K>) -> bool {
        self.last_query.is_some_and(|last| {
            let rotation = last.rotation.to_rotation_matrix();
            motion_since(pair, rotation.matrix(), &last.translation.vector).1
        })
    }
}

/// How far B turned since it was at `(rotation, translation)` in A's frame (a bound on `|R' - R|`
/// in the spectral norm), and whether it moved too far since for a front kept there to pay off
/// ([`FRONT_MAX_MOTION`]).
fn motion_since<const K: usize>(
    pair: &LazyPair<'_, K>,
    rotation: &Matrix3<f64>,
    translation: &Vector3<f64>,
) -> (f64, bool) {
    let (a, b) = (pair.a, pair.b);
    // |R' - R| in the spectral norm is at most the Frobenius norm over sqrt 2 (twice the sine of
    // half the angle between them); the small term covers matrices that are orthogonal only to
    // rounding.
    let turn = (pair.rotation - rotation).norm() * std::f64::consts::FRAC_1_SQRT_2 + 1e-12;
    // How far any point of B moved in A's frame.
    let shift = (pair.translation - translation).norm();
    let reach_b = b.bounding_centre.coords.norm() + b.bounding_radius;
    let far = turn * reach_b + shift > FRONT_MAX_MOTION * a.bounding_radius.min(b.bounding_radius);
    (turn, far)
}

/// True when the pair of leaves that proved two trees in contact at the previous query still has
/// intersecting triangles at `b_to_a`.
fn witness_still_intersects(
    a: &DopTree,
    b: &DopTree,
    b_to_a: &Isometry3<f64>,
    [leaf_a, leaf_b]: [u32; 2],
    stats: &mut QueryStats,
) -> bool {
    if leaf_a as usize >= a.nodes.len() || leaf_b as usize >= b.nodes.len() {
        return false;
    }
    // Moved exactly as the traversal moves B's triangles, so both give the same answer.
    let rotation = b_to_a.rotation.to_rotation_matrix();
    let translation = b_to_a.translation.vector;
    let (triangles_a, triangles_b) = (a.node_triangles(leaf_a), b.node_triangles(leaf_b));
    triangles_b.iter().any(|tb| {
        let tb = tb.map(|p| Point3::from(rotation.matrix() * p.coords + translation));
        triangles_a.iter().any(|ta| {
            stats.tri_tests += 1;
            triangles_intersect(ta, &tb)
        })
    })
}
