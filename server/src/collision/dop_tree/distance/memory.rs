//! What a pair's distance queries carry from one to the next: the last closest triangles, and
//! the front where the last walk ended.

use nalgebra::{Matrix3, Vector3};

use super::super::tree::DopTree;

/// A node pair with a lower bound on its distance.
pub(super) type BoundedPair = (u32, u32, f64);

/// The trees' ids and B's pose in A's frame (rotation, translation) a front holds for.
type FrontPose = ((u64, u64), Matrix3<f64>, Vector3<f64>);

/// What the last distance queries between two objects found: keep one per pair of objects (it is
/// `Send`, and cheap when empty) and pass it to every query of that pair.
///
/// At a nearby pose, the last closest triangles are still (nearly) the closest, so their distance
/// is an upper bound that prunes most of the walk; and the front where the last walk ended (every
/// node pair it did not open, with its lower bound) still holds, less how far the motion since
/// can have brought each pair closer: the next walk opens only the pairs whose bound no longer
/// exceeds the best distance, instead of walking down from the roots. After a jump most of the
/// front no longer holds and the walk starts from the roots: a jump costs little more than a cold
/// query. A memory used with other trees than its last ones is ignored, so a mix-up costs speed,
/// never a wrong answer.
#[derive(Debug, Clone, Default)]
pub struct DistanceMemory {
    /// The two trees' ids and the closest triangles' positions in leaf order.
    last: Option<((u64, u64), [u32; 2])>,
    /// The front of the last complete walk, and the trees' ids and B's pose in A's frame it
    /// holds for.
    front: Vec<BoundedPair>,
    front_of: Option<FrontPose>,
    /// The length of the front of the last walk from the roots: a carried front only refines
    /// (a reopened pair is replaced by its children), so it is dropped once it has grown to
    /// [`FRONT_GROWTH`] times that, and the walk starts from the roots again.
    roots_front_len: usize,
    /// Buffers reused across queries: the walk's stack and the front it records.
    stack: Vec<BoundedPair>,
    next_front: Vec<BoundedPair>,
}

/// How much a carried front may grow over the front of a walk from the roots: scanning it costs
/// a comparison a pair, a walk a bound test a pair, so beyond a few times the scan costs more
/// than the walk it saves.
const FRONT_GROWTH: usize = 2;

impl DistanceMemory {
    /// The closest triangles (leaf order) the last query of `a` and `b` found.
    pub(super) fn last_pair(&self, a: &DopTree, b: &DopTree) -> Option<[u32; 2]> {
        self.last
            .filter(|(ids, _)| *ids == (a.id, b.id))
            .map(|(_, pair)| pair)
    }

    /// Remembers the closest triangles of `a` and `b` (leaf order).
    pub(super) fn remember(&mut self, a: &DopTree, b: &DopTree, pair: [u32; 2]) {
        self.last = Some(((a.id, b.id), pair));
    }

    /// Sets up a walk of `a` and `b` with B at (`rotation`, `translation`) in A's frame, the best
    /// distance known being `best`: the pairs of the last front that the motion since may have
    /// brought below `best` go on the walk's stack (nearest on top); those still proved apart go
    /// straight to the new front. Returns the stack and the new front, and whether the walk
    /// must start from the roots instead (no front, another pair of trees, or a jump).
    pub(super) fn start_walk(
        &mut self,
        a: &DopTree,
        b: &DopTree,
        rotation: &Matrix3<f64>,
        translation: &Vector3<f64>,
        best: f64,
    ) -> (&mut Vec<BoundedPair>, &mut Vec<BoundedPair>, bool) {
        self.stack.clear();
        self.next_front.clear();
        let usable = self.front.len() <= FRONT_GROWTH * self.roots_front_len.max(64)
            && self.front_of.is_some_and(|(ids, ..)| ids == (a.id, b.id));
        if !usable {
            return (&mut self.stack, &mut self.next_front, true);
        }
        let (_, old_rotation, old_translation) = self.front_of.expect("checked usable");
        let turn = rotation - old_rotation;
        let (turn_norm, shift) = (turn.norm(), translation - old_translation);
        // How far any point of B's node `ib` moved in A's frame: its sphere's centre moved by
        // `turn c + shift`, and its points turned about the centre by at most |turn| r.
        let motion = |ib: u32| {
            let sphere = b.nodes[ib as usize].sphere;
            (turn * sphere.centre() + shift).norm() + turn_norm * f64::from(sphere.radius)
        };
        for &(ia, ib, bound) in &self.front {
            let bound = bound - motion(ib);
            if bound >= best {
                self.next_front.push((ia, ib, bound));
            } else {
                self.stack.push((ia, ib, bound));
            }
        }
        if 2 * self.stack.len() > self.front.len() {
            // A jump: most of the front must be opened again, the roots are a shorter way.
            self.stack.clear();
            self.next_front.clear();
            return (&mut self.stack, &mut self.next_front, true);
        }
        self.stack.sort_unstable_by(|x, y| y.2.total_cmp(&x.2));
        (&mut self.stack, &mut self.next_front, false)
    }

    /// Keeps the front the walk recorded, when it is `complete` (the walk ran to its end), as
    /// the front of `a` and `b` at this pose; forgets the old one otherwise.
    pub(super) fn finish_walk(
        &mut self,
        a: &DopTree,
        b: &DopTree,
        rotation: &Matrix3<f64>,
        translation: &Vector3<f64>,
        complete: bool,
        from_roots: bool,
    ) {
        if complete && from_roots {
            self.roots_front_len = self.next_front.len();
        }
        if complete {
            std::mem::swap(&mut self.front, &mut self.next_front);
            self.front_of = Some(((a.id, b.id), *rotation, *translation));
        } else {
            self.front.clear();
            self.front_of = None;
        }
    }
}
