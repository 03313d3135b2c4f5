//! What a pair's distance queries carry from one to the next: the pose and the closest triangles
//! of the last query, and the front where the last walk ended.

use nalgebra::{Matrix3, Vector3};

use super::super::node_bounds::NodeSphere;
use super::super::tree::DopTree;
use super::queue::OpenQueue;
use super::walk::Closest;

/// A node pair with a lower bound on its distance.
pub(super) type BoundedPair = (u32, u32, f64);

/// What the last distance queries between two objects found: keep one per pair of objects (it is
/// `Send`, and cheap when empty) and pass it to every query of that pair.
///
/// At a nearby pose, the last closest triangles are still (nearly) the closest, so their distance
/// is an upper bound that prunes most of the walk; and the front where the last walk ended (every
/// node pair it did not open, with its lower bound) still holds, less how far the motion since
/// can have brought each pair closer: the next walk opens only the pairs whose bound no longer
/// exceeds the best distance, instead of walking down from the roots. After a jump (B moved by
/// more than a quarter of the last distance plus its size) none of it helps, and measuring the
/// old triangles would only mislead the walk's first steps: the memory is forgotten and the
/// query runs as a cold one. A memory used with other trees than its last ones is forgotten
/// too, so a mix-up costs speed, never a wrong answer.
#[derive(Debug, Clone, Default)]
pub struct DistanceMemory {
    /// The last query: the trees, B's pose in A's frame, the distance it settled.
    last: Option<LastQuery>,
    /// The closest triangles the pair's queries found last, in leaf order.
    pair: Option<[u32; 2]>,
    /// The front of the last walk, when it ran to its end (`has_front`).
    front: Vec<BoundedPair>,
    has_front: bool,
    /// The length of the front of the last walk from the roots: a carried front only refines
    /// (a reopened pair is replaced by its children), so it is dropped once it has grown to
    /// [`FRONT_GROWTH`] times that, and the walk starts from the roots again.
    roots_front_len: usize,
    /// Walks from the carried front since the last walk from the roots.
    carried_walks: usize,
    /// Buffers reused across queries: the walk's queue and the front it records.
    queue: OpenQueue,
    next_front: Vec<BoundedPair>,
}

/// The last query of a pair.
#[derive(Debug, Clone, Copy)]
struct LastQuery {
    /// A's and B's tree ids.
    ids: (u64, u64),
    /// B's pose in A's frame.
    rotation: Matrix3<f64>,
    translation: Vector3<f64>,
    /// The best distance it found (the bound asked for, when nothing was closer).
    distance: f64,
}

/// How much a carried front may grow over the front of a walk from the roots: scanning it costs
/// a comparison a pair, a walk a bound test a pair, so beyond a few times the scan costs more
/// than the walk it saves.
const FRONT_GROWTH: usize = 2;

/// How many walks start from a carried front before one starts from the roots again: a front
/// only refines, and one grown fine where many node pairs were nearly as close as the closest
/// (two rings face to face) would outlive that pose, its scan costing more at every later pose
/// than the walk it saves. A walk from the roots with the last closest triangles' bound costs
/// about a carried walk's scan, so once in this many queries it adds little.
const REFRESH: usize = 32;

/// A motion of B larger than this fraction of the last distance plus B's bounding radius is a
/// jump. Along a path (a hand's motion from one frame to the next, a tumble) B moves by a small
/// fraction of its size; a quarter of it already reopens most of a front, whose bounds exceed
/// the distance by about the size of its nodes.
const JUMP: f64 = 0.25;

/// How far the points of B moved in A's frame since the last query.
struct Motion {
    turn: Matrix3<f64>,
    turn_norm: f64,
    shift: Vector3<f64>,
}

impl Motion {
    fn since(last: &LastQuery, rotation: &Matrix3<f64>, translation: &Vector3<f64>) -> Self {
        let turn = rotation - last.rotation;
        Motion {
            turn_norm: turn.norm(),
            turn,
            shift: translation - last.translation,
        }
    }

    /// How far any point of B within `sphere` moved: its centre by `turn c + shift`, and its
    /// points turned about the centre by at most |turn| r.
    fn within(&self, sphere: &NodeSphere) -> f64 {
        (self.turn * sphere.centre() + self.shift).norm()
            + self.turn_norm * f64::from(sphere.radius)
    }
}

impl DistanceMemory {
    /// Starts a query of `a` and `b` with B at (`rotation`, `translation`) in A's frame: returns
    /// the closest triangles (leaf order) of the pair's last query, to measure first. After a
    /// jump, or with other trees than the last query's, the memory is forgotten and there are
    /// none.
    pub(super) fn begin(
        &mut self,
        a: &DopTree,
        b: &DopTree,
        rotation: &Matrix3<f64>,
        translation: &Vector3<f64>,
    ) -> Option<[u32; 2]> {
        let last = self.last?;
        let root = &b.nodes[0].sphere;
        let moved = Motion::since(&last, rotation, translation).within(root);
        let near = moved < JUMP * (last.distance + f64::from(root.radius));
        if last.ids != (a.id, b.id) || !near {
            *self = DistanceMemory {
                queue: std::mem::take(&mut self.queue),
                front: std::mem::take(&mut self.front),
                next_front: std::mem::take(&mut self.next_front),
                ..DistanceMemory::default()
            };
            return None;
        }
        self.pair
    }

    /// Sets up a walk of `a` and `b` with B at (`rotation`, `translation`) in A's frame, the best
    /// distance known being `best`: the pairs of the last front that the motion since may have
    /// brought below `best` are set aside in the queue's carried pairs with their carried
    /// bounds; those still proved apart go straight to the new front. Returns the queue and the new front, and whether the walk
    /// must start from the roots instead (no front, or most of it to open again).
    pub(super) fn start_walk(
        &mut self,
        b: &DopTree,
        rotation: &Matrix3<f64>,
        translation: &Vector3<f64>,
        best: f64,
    ) -> (&mut OpenQueue, &mut Vec<BoundedPair>, bool) {
        self.queue.clear();
        self.next_front.clear();
        let last = self
            .last
            .filter(|_| self.has_front)
            .filter(|_| self.front.len() <= FRONT_GROWTH * self.roots_front_len.max(64))
            .filter(|_| self.carried_walks < REFRESH);
        let Some(last) = last else {
            return (&mut self.queue, &mut self.next_front, true);
        };
        let motion = Motion::since(&last, rotation, translation);
        for &(ia, ib, bound) in &self.front {
            let bound = bound - motion.within(&b.nodes[ib as usize].sphere);
            if bound >= best {
                self.next_front.push((ia, ib, bound));
            } else {
                self.queue.carried.push((ia, ib, bound));
            }
        }
        if 2 * self.queue.carried.len() > self.front.len() {
            // Most of the front must be opened again: the roots are a shorter way.
            self.queue.clear();
            self.next_front.clear();
            return (&mut self.queue, &mut self.next_front, true);
        }
        (&mut self.queue, &mut self.next_front, false)
    }

    /// Ends a query of `a` and `b` with B at (`rotation`, `translation`) that found `closest`:
    /// keeps the front the walk recorded when it is `complete` (the walk ran to its end), forgets
    /// the old one otherwise.
    pub(super) fn finish(
        &mut self,
        (a, b): (&DopTree, &DopTree),
        (rotation, translation): (&Matrix3<f64>, &Vector3<f64>),
        closest: &Closest,
        complete: bool,
        from_roots: bool,
    ) {
        if complete && from_roots {
            self.roots_front_len = self.next_front.len();
        }
        self.carried_walks = if from_roots {
            0
        } else {
            self.carried_walks + 1
        };
        if complete {
            std::mem::swap(&mut self.front, &mut self.next_front);
        } else {
            self.front.clear();
        }
        self.has_front = complete;
        self.last = Some(LastQuery {
            ids: (a.id, b.id),
            rotation: *rotation,
            translation: *translation,
            distance: closest.distance,
        });
        self.pair = closest.pair.or(self.pair);
    }
}
