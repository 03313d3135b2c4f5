//! The bounding-box stage: incremental sweep and prune over world-space axis-aligned boxes.
//!
//! Each axis keeps the boxes' interval endpoints sorted. When a box moves, only its endpoints are
//! sifted to their new places (insertion sort, which costs next to nothing under coherent motion),
//! and every time a lower endpoint passes an upper endpoint of another box the pair's overlap is
//! re-tested; the set of overlapping pairs is kept per box. So a frame costs in proportion to the
//! moved boxes and the endpoint swaps they cause, not to the scene size, and the pairs to check for
//! a moved object are simply its overlap list.

use nalgebra::{Isometry3, Point3, Vector3};
use rayon::prelude::*;

/// An axis-aligned box in the scene's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// The minimum corner.
    pub min: Point3<f64>,
    /// The maximum corner.
    pub max: Point3<f64>,
}

impl Aabb {
    /// The box of `local` (a box in an object's frame) placed at `pose`: the tight axis-aligned box
    /// of the rotated box, from its centre and the absolute rotation matrix (no corner loop).
    pub fn transformed(local: &Aabb, pose: &Isometry3<f64>) -> Aabb {
        let centre = pose * nalgebra::center(&local.min, &local.max);
        let half: Vector3<f64> = (local.max - local.min) * 0.5;
        let half = pose.rotation.to_rotation_matrix().matrix().abs() * half;
        Aabb {
            min: centre - half,
            max: centre + half,
        }
    }

    /// True when the closed boxes share a point.
    pub fn overlaps(&self, other: &Aabb) -> bool {
        (0..3).all(|k| self.min[k] <= other.max[k] && other.min[k] <= self.max[k])
    }

    /// This box grown by `margin` on every side.
    pub fn expanded(&self, margin: f64) -> Aabb {
        let grow = Vector3::repeat(margin);
        Aabb {
            min: self.min - grow,
            max: self.max + grow,
        }
    }
}

/// One end of a box's interval on one axis.
#[derive(Debug, Clone, Copy)]
struct Endpoint {
    value: f64,
    /// `box id << 1 | 1` for an upper end, `box id << 1` for a lower end.
    tag: u32,
}

impl Endpoint {
    fn owner(self) -> u32 {
        self.tag >> 1
    }

    fn is_upper(self) -> bool {
        self.tag & 1 == 1
    }

    /// Sort order: by value, and a lower end before an upper end at equal values, so that boxes
    /// that merely touch count as overlapping, like [`Aabb::overlaps`].
    fn goes_before(self, other: Endpoint) -> bool {
        self.value < other.value
            || (self.value == other.value && !self.is_upper() && other.is_upper())
    }
}

/// Refreshes the endpoint values of one axis from `boxes`, re-sorts them by insertion sort (every
/// pair of endpoints whose order changed is swapped once, recorded in `crossings`), updates
/// `positions`, and returns the number of swaps.
fn resort_axis(
    axis: usize,
    boxes: &[Option<Aabb>],
    endpoints: &mut [Endpoint],
    positions: &mut [[u32; 2]],
    crossings: &mut Vec<(Endpoint, Endpoint)>,
) -> u64 {
    crossings.clear();
    for endpoint in endpoints.iter_mut() {
        let bounds = boxes[endpoint.owner() as usize]
            .as_ref()
            .expect("endpoints of live boxes");
        endpoint.value = if endpoint.is_upper() {
            bounds.max[axis]
        } else {
            bounds.min[axis]
        };
    }
    let mut swaps = 0;
    for at in 1..endpoints.len() {
        let moving = endpoints[at];
        let mut to = at;
        while to > 0 && moving.goes_before(endpoints[to - 1]) {
            let other = endpoints[to - 1];
            endpoints[to] = other;
            if moving.owner() != other.owner() && moving.is_upper() != other.is_upper() {
                crossings.push((moving, other));
            }
            to -= 1;
        }
        endpoints[to] = moving;
        swaps += (at - to) as u64;
    }
    for (at, endpoint) in endpoints.iter().enumerate() {
        positions[endpoint.owner() as usize][usize::from(endpoint.is_upper())] = at as u32;
    }
    swaps
}

/// Incremental sweep and prune. Boxes are named by small integer ids chosen by the caller (dense
/// ids keep the per-box tables small).
#[derive(Debug, Clone, Default)]
pub struct SweepAndPrune {
    boxes: Vec<Option<Aabb>>,
    axes: [Vec<Endpoint>; 3],
    /// Per axis, where each box's lower and upper endpoints sit.
    positions: [Vec<[u32; 2]>; 3],
    overlaps: Vec<Vec<u32>>,
    /// Overlaps that ended since the last [`SweepAndPrune::drain_ended`].
    ended: Vec<[u32; 2]>,
    /// Overlaps that started since the last [`SweepAndPrune::drain_started`].
    started: Vec<[u32; 2]>,
    /// Per axis, the endpoint crossings of a batched update, (now first, now second); kept to
    /// reuse the memory.
    crossings: [Vec<(Endpoint, Endpoint)>; 3],
    swaps: u64,
}

impl SweepAndPrune {
    /// An empty broad phase.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds box `id` (which must not be present) with bounds `aabb`.
    ///
    /// # Panics
    /// If `id` is already present or a bound is not finite (callers validate poses).
    pub fn insert(&mut self, id: u32, aabb: Aabb) {
        let index = id as usize;
        if index >= self.boxes.len() {
            self.boxes.resize(index + 1, None);
            for positions in &mut self.positions {
                positions.resize(index + 1, [0; 2]);
            }
            self.overlaps.resize_with(index + 1, Vec::new);
        }
        assert!(self.boxes[index].is_none(), "box {id} is already present");
        // Enter at +infinity, beyond every other box, then move into place like any update.
        let far = Point3::from(Vector3::repeat(f64::INFINITY));
        self.boxes[index] = Some(Aabb { min: far, max: far });
        for (axis, endpoints) in self.axes.iter_mut().enumerate() {
            let at = endpoints.len() as u32;
            self.positions[axis][index] = [at, at + 1];
            endpoints.push(Endpoint {
                value: f64::INFINITY,
                tag: id << 1,
            });
            endpoints.push(Endpoint {
                value: f64::INFINITY,
                tag: id << 1 | 1,
            });
        }
        self.update(id, aabb);
    }

    /// Removes box `id` and all its overlaps.
    ///
    /// # Panics
    /// If `id` is not present.
    pub fn remove(&mut self, id: u32) {
        let far = Point3::from(Vector3::repeat(f64::INFINITY));
        // Moving to +infinity ends every overlap and leaves the endpoints last on each axis.
        self.update(id, Aabb { min: far, max: far });
        for endpoints in &mut self.axes {
            endpoints.truncate(endpoints.len() - 2);
        }
        self.boxes[id as usize] = None;
    }

    /// Moves box `id` to `aabb`, updating the overlaps it gains and loses.
    ///
    /// # Panics
    /// If `id` is not present or a bound is NaN.
    pub fn update(&mut self, id: u32, aabb: Aabb) {
        let index = id as usize;
        let old = self.boxes[index].expect("updating a box that is not present");
        assert!(
            aabb.min.iter().chain(aabb.max.iter()).all(|v| !v.is_nan()),
            "box {id} has a NaN bound"
        );
        self.boxes[index] = Some(aabb);
        for axis in 0..3 {
            let [lower, upper] = self.positions[axis][index];
            self.axes[axis][lower as usize].value = aabb.min[axis];
            self.axes[axis][upper as usize].value = aabb.max[axis];
            // Sift the leading end first, or the trailing one would stop at it too early.
            if aabb.min[axis] > old.min[axis] {
                self.sift(axis, upper);
                self.sift(axis, self.positions[axis][index][0]);
            } else {
                self.sift(axis, lower);
                self.sift(axis, self.positions[axis][index][1]);
            }
        }
    }

    /// Moves many boxes at once, like [`SweepAndPrune::update`] for each. When a good part of the
    /// scene moves, one insertion-sort pass per axis over all endpoints (in memory order, the three
    /// axes in parallel on the current rayon pool) beats sifting each box's endpoints through
    /// scattered memory; for a few boxes, each is sifted alone.
    ///
    /// # Panics
    /// If an id is not present or a bound is NaN.
    pub fn update_many(&mut self, updates: &[(u32, Aabb)]) {
        let live = self.axes[0].len() / 2;
        if updates.len() * 8 < live {
            for &(id, aabb) in updates {
                self.update(id, aabb);
            }
            return;
        }
        for &(id, aabb) in updates {
            assert!(
                self.boxes[id as usize].is_some(),
                "updating a box that is not present"
            );
            assert!(
                aabb.min.iter().chain(aabb.max.iter()).all(|v| !v.is_nan()),
                "box {id} has a NaN bound"
            );
            self.boxes[id as usize] = Some(aabb);
        }
        // The axes are independent: sort them in parallel, recording the crossings, and apply the
        // crossings afterwards. Every box already has its final bounds, so each crossing is
        // judged on them and the order of application does not matter.
        let boxes = &self.boxes;
        self.swaps += self
            .axes
            .par_iter_mut()
            .zip(self.positions.par_iter_mut())
            .zip(self.crossings.par_iter_mut())
            .enumerate()
            .map(|(axis, ((endpoints, positions), crossings))| {
                resort_axis(axis, boxes, endpoints, positions, crossings)
            })
            .sum::<u64>();
        let crossings = std::mem::take(&mut self.crossings);
        for &(first, second) in crossings.iter().flatten() {
            self.crossed(first, second);
        }
        self.crossings = crossings;
    }

    /// Moves the endpoint at `at` on `axis` to its sorted place.
    fn sift(&mut self, axis: usize, at: u32) {
        let mut at = at as usize;
        let moving = self.axes[axis][at];
        while at > 0 && moving.goes_before(self.axes[axis][at - 1]) {
            self.swap(axis, at - 1, moving);
            at -= 1;
        }
        while at + 1 < self.axes[axis].len() && self.axes[axis][at + 1].goes_before(moving) {
            self.swap(axis, at + 1, moving);
            at += 1;
        }
    }

    /// Swaps `moving` with its neighbour at `other_at`, updating positions and the overlap of the
    /// two boxes.
    fn swap(&mut self, axis: usize, other_at: usize, moving: Endpoint) {
        let endpoints = &mut self.axes[axis];
        let other = endpoints[other_at];
        let moving_at =
            self.positions[axis][moving.owner() as usize][usize::from(moving.is_upper())] as usize;
        endpoints.swap(moving_at, other_at);
        self.positions[axis][moving.owner() as usize][usize::from(moving.is_upper())] =
            other_at as u32;
        self.positions[axis][other.owner() as usize][usize::from(other.is_upper())] =
            moving_at as u32;
        self.swaps += 1;
        if other_at < moving_at {
            self.crossed(moving, other);
        } else {
            self.crossed(other, moving);
        }
    }

    /// Records that endpoint `first` now comes before endpoint `second` on some axis. A lower end
    /// before another box's upper end may start an overlap (tested on all axes); an upper end
    /// before another box's lower end ends any overlap of the two boxes.
    fn crossed(&mut self, first: Endpoint, second: Endpoint) {
        let (a, b) = (first.owner(), second.owner());
        if a == b || first.is_upper() == second.is_upper() {
            return;
        }
        let listed = self.overlaps[a as usize].contains(&b);
        if first.is_upper() {
            if listed {
                self.ended.push([a, b]);
                for (from, to) in [(a, b), (b, a)] {
                    let list = &mut self.overlaps[from as usize];
                    let at = list
                        .iter()
                        .position(|&x| x == to)
                        .expect("overlaps are symmetric");
                    list.swap_remove(at);
                }
            }
        } else if !listed
            && let (Some(box_a), Some(box_b)) = (self.boxes[a as usize], self.boxes[b as usize])
            && box_a.overlaps(&box_b)
        {
            self.overlaps[a as usize].push(b);
            self.overlaps[b as usize].push(a);
            self.started.push([a, b]);
        }
    }

    /// The overlaps that ended (box pairs that stopped overlapping, or one of them was removed)
    /// since the last call: a caller keeping per-pair state drops it here. A caller that keeps
    /// none should still drain it now and then.
    pub fn drain_ended(&mut self) -> std::vec::Drain<'_, [u32; 2]> {
        self.ended.drain(..)
    }

    /// The overlaps that started (box pairs that came to overlap) since the last call, each once:
    /// a caller that already looked at the overlaps of the boxes before moving them finds here
    /// the pairs it has not seen. An overlap that starts and then ends between two calls is
    /// listed by both drains.
    pub fn drain_started(&mut self) -> std::vec::Drain<'_, [u32; 2]> {
        self.started.drain(..)
    }

    /// The boxes overlapping box `id` (empty for an absent id).
    pub fn overlaps(&self, id: u32) -> &[u32] {
        self.overlaps.get(id as usize).map_or(&[], Vec::as_slice)
    }

    /// The current bounds of box `id`, if present.
    pub fn bounds(&self, id: u32) -> Option<Aabb> {
        self.boxes.get(id as usize).copied().flatten()
    }

    /// Endpoint swaps performed so far: the work the coherence saved is what is not counted here.
    pub fn swaps(&self) -> u64 {
        self.swaps
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::collections::BTreeSet;

    fn random_box(rng: &mut ChaCha8Rng, world: f64) -> Aabb {
        let min = Point3::new(
            rng.random_range(0.0..world),
            rng.random_range(0.0..world),
            rng.random_range(0.0..world),
        );
        // Some boxes on a coarse grid, so that equal endpoints (touching boxes) occur.
        let min = if rng.random_bool(0.2) {
            min.map(f64::round)
        } else {
            min
        };
        let size = Vector3::new(
            rng.random_range(0.0..3.0),
            rng.random_range(0.0..3.0),
            rng.random_range(0.0..3.0),
        );
        let size = if rng.random_bool(0.2) {
            size.map(f64::round)
        } else {
            size
        };
        Aabb {
            min,
            max: min + size,
        }
    }

    fn brute_force(boxes: &[Option<Aabb>]) -> BTreeSet<(u32, u32)> {
        let mut pairs = BTreeSet::new();
        for (i, a) in boxes.iter().enumerate() {
            for (j, b) in boxes.iter().enumerate().skip(i + 1) {
                if let (Some(a), Some(b)) = (a, b)
                    && a.overlaps(b)
                {
                    pairs.insert((i as u32, j as u32));
                }
            }
        }
        pairs
    }

    fn listed(sap: &SweepAndPrune, count: usize) -> BTreeSet<(u32, u32)> {
        let mut pairs = BTreeSet::new();
        for i in 0..count as u32 {
            for &j in sap.overlaps(i) {
                assert!(sap.overlaps(j).contains(&i), "overlap {i}-{j} is one-sided");
                pairs.insert((i.min(j), i.max(j)));
            }
        }
        pairs
    }

    /// Every axis in sort order, and every box's recorded positions where its endpoints are.
    fn assert_sorted_and_placed(sap: &SweepAndPrune) {
        for (endpoints, positions) in sap.axes.iter().zip(&sap.positions) {
            for (at, pair) in endpoints.windows(2).enumerate() {
                assert!(
                    !pair[1].goes_before(pair[0]),
                    "endpoints {at} and {} out of order",
                    at + 1
                );
            }
            for (at, endpoint) in endpoints.iter().enumerate() {
                let recorded =
                    positions[endpoint.owner() as usize][usize::from(endpoint.is_upper())];
                assert_eq!(recorded as usize, at, "position of {endpoint:?}");
            }
        }
    }

    #[test]
    fn overlaps_match_brute_force_through_moves_inserts_and_removals() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let count = 120;
        let world = 20.0;
        let mut sap = SweepAndPrune::new();
        let mut boxes: Vec<Option<Aabb>> = vec![None; count];
        let mut previous = BTreeSet::new();
        for frame in 0..400 {
            // Odd frames move their boxes in one batch (often most of the scene).
            let mut batch = Vec::new();
            let moves = if frame % 2 == 1 {
                rng.random_range(1..200)
            } else {
                rng.random_range(1..30)
            };
            for _ in 0..moves {
                let id = rng.random_range(0..count);
                match boxes[id] {
                    None => {
                        batch.retain(|&(other, _)| other != id as u32);
                        let b = random_box(&mut rng, world);
                        sap.insert(id as u32, b);
                        boxes[id] = Some(b);
                    }
                    Some(_) if rng.random_bool(0.1) => {
                        sap.remove(id as u32);
                        boxes[id] = None;
                    }
                    Some(old) => {
                        // Mostly small coherent moves, sometimes a jump.
                        let b = if rng.random_bool(0.9) {
                            let shift = Vector3::new(
                                rng.random_range(-0.5..0.5),
                                rng.random_range(-0.5..0.5),
                                rng.random_range(-0.5..0.5),
                            );
                            let grow = rng.random_range(0.0..0.1);
                            Aabb {
                                min: old.min + shift,
                                max: old.max + shift,
                            }
                            .expanded(grow)
                        } else {
                            random_box(&mut rng, world)
                        };
                        if frame % 2 == 1 {
                            batch.retain(|&(other, _)| other != id as u32);
                            batch.push((id as u32, b));
                        } else {
                            sap.update(id as u32, b);
                        }
                        boxes[id] = Some(b);
                    }
                }
            }
            // A box removed after its move was batched must not be updated.
            batch.retain(|&(id, _)| boxes[id as usize].is_some());
            sap.update_many(&batch);
            let now = brute_force(&boxes);
            let ended: BTreeSet<(u32, u32)> = sap
                .drain_ended()
                .map(|[a, b]| (a.min(b), a.max(b)))
                .collect();
            let started: BTreeSet<(u32, u32)> = sap
                .drain_started()
                .map(|[a, b]| (a.min(b), a.max(b)))
                .collect();
            for pair in previous.difference(&now) {
                assert!(ended.contains(pair), "the end of {pair:?} was not reported");
            }
            for pair in now.difference(&previous) {
                assert!(
                    started.contains(pair),
                    "the start of {pair:?} was not reported"
                );
            }
            for pair in &started {
                assert!(
                    now.contains(pair) || ended.contains(pair),
                    "{pair:?} was reported started but neither overlaps nor ended"
                );
            }
            assert_eq!(listed(&sap, count), now, "frame {frame}");
            assert_sorted_and_placed(&sap);
            previous = now;
            for (id, b) in boxes.iter().enumerate() {
                assert_eq!(sap.bounds(id as u32), *b);
            }
        }
    }

    #[test]
    fn transformed_box_encloses_the_rotated_corners_tightly() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        for _ in 0..200 {
            let local = random_box(&mut rng, 2.0);
            let pose = Isometry3::from_parts(
                Translation3::new(rng.random_range(-5.0..5.0), 1.0, -2.0),
                UnitQuaternion::from_euler_angles(
                    rng.random_range(-3.0..3.0),
                    rng.random_range(-3.0..3.0),
                    rng.random_range(-3.0..3.0),
                ),
            );
            let corners: Vec<Point3<f64>> = (0..8)
                .map(|c: u32| {
                    let pick = |bit: u32, k: usize| {
                        if c & bit == 0 {
                            local.min[k]
                        } else {
                            local.max[k]
                        }
                    };
                    pose * Point3::new(pick(1, 0), pick(2, 1), pick(4, 2))
                })
                .collect();
            let world = Aabb::transformed(&local, &pose);
            for k in 0..3 {
                let lo = corners.iter().map(|c| c[k]).fold(f64::INFINITY, f64::min);
                let hi = corners
                    .iter()
                    .map(|c| c[k])
                    .fold(f64::NEG_INFINITY, f64::max);
                assert!((world.min[k] - lo).abs() < 1e-9 && (world.max[k] - hi).abs() < 1e-9);
            }
        }
    }
}
