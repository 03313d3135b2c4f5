//! What a pair's distance queries carry from one to the next: the pose and the closest triangles
//! of the last query, and the front where the last walk ended.

use nalgebra::{Matrix3, Vector3};

use super::super::node_bounds::NodeSphere;
use super::super::tree::DopTree;
use super::bounds::Gap;
use super::queue::OpenQueue;
use super::walk::Closest;

/// A node pair with a lower bound on its distance.
#[derive(Debug, Clone, Copy)]
pub(super) struct BoundedPair {
    pub(super) ia: u32,
    pub(super) ib: u32,
    pub(super) gap: Gap,
}

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
    /// The bounding-volume tests of the last walk from the roots.
    roots_work: u64,
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
            // The difference of two rotations has the spectral norm 2 sin(a/2) (a the angle
            // between them), its Frobenius norm over sqrt 2; the small term covers matrices
            // rounded off exact rotations.
            turn_norm: turn.norm() * std::f64::consts::FRAC_1_SQRT_2 * (1.0 + 1e-9) + 1e-12,
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

    /// How far `gap`'s bound on a pair with B's node in `sphere` may have fallen: how far the
    /// node's points moved along the gap's line (`w · (turn c + shift)` for its centre, at most
    /// `|turnᵀ w| r` more for the others), or anywhere when it has none.
    fn across(&self, gap: &Gap, sphere: &NodeSphere) -> f64 {
        if gap.along == Vector3::zeros() {
            return self.within(sphere);
        }
        let turned = self.turn.tr_mul(&gap.along);
        (turned.dot(&sphere.centre()) + gap.along.dot(&self.shift)).abs()
            + turned.norm() * f64::from(sphere.radius)
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
    /// bounds; those still proved apart go straight to the new front. Returns the queue and the
    /// new front, and whether the walk must start from the roots instead (no front, or so much
    /// of it to measure again that the roots cost no more).
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
        // Every point of B is in the root's sphere: one bound for the pairs far enough apart.
        let anywhere = motion.within(&b.nodes[0].sphere);
        for &pair in &self.front {
            let moved = if pair.gap.bound - anywhere >= best {
                anywhere
            } else {
                motion.across(&pair.gap, &b.nodes[pair.ib as usize].sphere)
            };
            let carried = BoundedPair {
                gap: Gap {
                    bound: pair.gap.bound - moved,
                    ..pair.gap
                },
                ..pair
            };
            if carried.gap.bound >= best {
                self.next_front.push(carried);
            } else {
                self.queue.carried.push(carried);
            }
        }
        if 2 * self.queue.carried.len() as u64 > self.roots_work.max(64) {
            // Measuring the carried pairs again would cost about what the last walk from the
            // roots did (a pair measured again costs a test, and many open a few more): the
            // roots are as short a way, and leave a fresh front.
            self.queue.clear();
            self.next_front.clear();
            return (&mut self.queue, &mut self.next_front, true);
        }
        (&mut self.queue, &mut self.next_front, false)
    }

    /// Ends a query of `a` and `b` with B at (`rotation`, `translation`) that found `closest`:
    /// keeps the front the walk recorded when it is `complete` (the walk ran to its end), forgets
    /// the old one otherwise; a walk `from_roots` leaves its `work` (bounding-volume tests) as
    /// the measure of what a carried walk must save.
    pub(super) fn finish(
        &mut self,
        (a, b): (&DopTree, &DopTree),
        (rotation, translation): (&Matrix3<f64>, &Vector3<f64>),
        closest: &Closest,
        (complete, from_roots, work): (bool, bool, u64),
    ) {
        if complete && from_roots {
            self.roots_front_len = self.next_front.len();
            self.roots_work = work;
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

#[cfg(test)]
mod tests {
    use nalgebra::{Point3, UnitQuaternion, Vector3};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::super::super::node_bounds::NodeSphere;
    use super::{Gap, LastQuery, Motion};

    /// Neither motion bound is ever beaten by a point of the sphere: its displacement (anywhere)
    /// and its displacement along a gap's line stay within them, for turns from tiny to large;
    /// and along a line the bound is the smaller.
    #[test]
    fn no_point_of_a_sphere_moves_farther_than_its_bounds() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let unit =
            |rng: &mut ChaCha8Rng| Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)).normalize();
        for case in 0..5_000 {
            let angle = [1e-4, 1e-2, 0.5, 3.0][case % 4];
            let before =
                UnitQuaternion::from_scaled_axis(unit(&mut rng) * rng.random_range(0.0..3.0));
            let after = UnitQuaternion::from_scaled_axis(unit(&mut rng) * angle) * before;
            let shift = unit(&mut rng) * rng.random_range(0.0..angle);
            let last = LastQuery {
                ids: (0, 0),
                rotation: *before.to_rotation_matrix().matrix(),
                translation: Vector3::zeros(),
                distance: 1.0,
            };
            let motion = Motion::since(&last, after.to_rotation_matrix().matrix(), &shift);
            let centre = Vector3::from_fn(|_, _| rng.random_range(-5.0..5.0));
            let points: Vec<Point3<f64>> = (0..8)
                .map(|_| Point3::from(centre + unit(&mut rng) * rng.random_range(0.0..2.0)))
                .collect();
            let sphere = NodeSphere::around(points.iter());
            let gap = Gap {
                bound: 0.0,
                along: unit(&mut rng),
            };
            let (anywhere, across) = (motion.within(&sphere), motion.across(&gap, &sphere));
            assert!(
                across <= anywhere + 1e-12,
                "case {case}: {across} > {anywhere}"
            );
            for p in &points {
                let moved = (after * p.coords + shift) - before * p.coords;
                assert!(
                    moved.norm() <= anywhere * (1.0 + 1e-9) + 1e-12,
                    "case {case}"
                );
                let along = moved.dot(&gap.along).abs();
                assert!(along <= across * (1.0 + 1e-9) + 1e-12, "case {case}");
            }
            assert_eq!(motion.across(&Gap::anywhere(0.0), &sphere), anywhere);
        }
    }
}
