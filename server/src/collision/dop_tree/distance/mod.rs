//! The distance query on two DOP-trees: the least distance between their triangles, the closest
//! points and the triangles they lie on.
//!
//! A query goes through these stages, B posed in A's frame:
//! 1. the bounding spheres give a lower bound: a pair provably farther than the bound asked for
//!    ([`DopTree::distance_below`]) ends here;
//! 2. the closest triangles of the pair's last query ([`DistanceMemory`]), measured at the new
//!    pose, give an upper bound: at a nearby pose it is already (nearly) the answer; after a
//!    jump (B moved far against the last distance and its size) the memory is forgotten and the
//!    query runs cold;
//! 3. the front where the pair's last walk ended ([`DistanceMemory`]) is carried to the new pose:
//!    its node pairs whose lower bounds, less how far the motion since moved B's node along the
//!    line each bound was measured along, still exceed the best distance stay closed; the
//!    others are where the walk starts, each measured again at the new pose before it is opened
//!    (from the roots without a front, or when measuring them again would cost about what the
//!    last walk from the roots did);
//! 4. the walk (`walk`) opens only the node pairs whose lower bound (`bounds`: the nodes'
//!    spheres, their boxes or DOPs along the best pair's direction, their DOPs re-aligned in
//!    O(k)) is below the best distance found so far, nearest first (`queue`), measures the
//!    triangle pairs of the leaves it reaches exactly (but not those that can only tie the best,
//!    within a rounding), and records the pairs it leaves closed, with their bounds' lines, as
//!    the new front.

mod bounds;
mod memory;
mod queue;
mod walk;

use nalgebra::{Isometry3, Point3};

pub use memory::DistanceMemory;
use walk::Closest;

use super::realign::{AffineRealign, CONE_HINTS, with_cone_hints};
use super::traverse::TreePair;
use super::tree::DopTree;
use crate::collision::QueryStats;
use crate::collision::distance::ClosestPoints;

impl DopTree {
    /// The least distance between this tree's triangles and `other`'s posed at `b_to_a` in this
    /// tree's frame, with the closest points and their triangles; 0 with a point of contact when
    /// they touch or intersect, infinite when either tree has no triangle. `memory` is the
    /// pair's: what this query finds makes the next one at a nearby pose fast.
    pub fn distance(
        &self,
        other: &DopTree,
        b_to_a: &Isometry3<f64>,
        memory: &mut DistanceMemory,
        stats: &mut QueryStats,
    ) -> ClosestPoints {
        self.distance_below(other, b_to_a, f64::INFINITY, memory, stats)
            .unwrap_or(ClosestPoints {
                distance: f64::INFINITY,
                on_a: Point3::origin(),
                on_b: Point3::origin(),
                triangles: [u32::MAX; 2],
            })
    }

    /// Like [`DopTree::distance`], but only when the distance is below `d_max`: `None` as soon as
    /// the trees are proved at least `d_max` apart (at once when their bounding spheres are).
    pub fn distance_below(
        &self,
        other: &DopTree,
        b_to_a: &Isometry3<f64>,
        d_max: f64,
        memory: &mut DistanceMemory,
        stats: &mut QueryStats,
    ) -> Option<ClosestPoints> {
        assert_eq!(
            self.k, other.k,
            "the two trees of a query must have the same orientation set"
        );
        if self.triangles.is_empty() || other.triangles.is_empty() || d_max.is_nan() {
            return None;
        }
        let centre_b = b_to_a * other.bounding_centre;
        stats.bv_tests += 1;
        let gap =
            (centre_b - self.bounding_centre).norm() - self.bounding_radius - other.bounding_radius;
        if gap >= d_max {
            return None;
        }
        let closest = match self.k {
            6 => closest::<6>(self, other, b_to_a, d_max, memory, stats),
            14 => closest::<14>(self, other, b_to_a, d_max, memory, stats),
            18 => closest::<18>(self, other, b_to_a, d_max, memory, stats),
            24 => closest::<24>(self, other, b_to_a, d_max, memory, stats),
            26 => closest::<26>(self, other, b_to_a, d_max, memory, stats),
            k => unreachable!("orientation sets have a supported k, not {k}"),
        };
        let [ia, ib] = closest.pair?;
        let inverse = b_to_a.inverse();
        Some(ClosestPoints {
            distance: closest.distance,
            on_a: closest.on_a,
            on_b: inverse * closest.on_b,
            triangles: [
                self.triangle_ids[ia as usize],
                other.triangle_ids[ib as usize],
            ],
        })
    }
}

/// Stages 2 to 4 with A's orientation count `K`.
fn closest<const K: usize>(
    a: &DopTree,
    b: &DopTree,
    b_to_a: &Isometry3<f64>,
    d_max: f64,
    memory: &mut DistanceMemory,
    stats: &mut QueryStats,
) -> Closest {
    let pair = TreePair::new(a, b, b_to_a, |rotation, translation| {
        with_cone_hints(&CONE_HINTS, |hints| {
            AffineRealign::<K>::new(a, b, rotation, translation, hints)
        })
    });
    let mut closest = Closest::within(d_max);
    let pose = (&pair.rotation, &pair.translation);
    if let Some(last) = memory.begin(a, b, pose.0, pose.1) {
        pair.measure_triangles(last, &mut closest, stats);
    }
    let tests_before = stats.bv_tests;
    let (queue, front, from_roots) = memory.start_walk(b, pose.0, pose.1, closest.distance);
    let complete = pair.walk_closest(&mut closest, queue, front, from_roots, stats);
    let walk = stats.bv_tests - tests_before;
    memory.finish((a, b), pose, &closest, (complete, from_roots, walk));
    closest
}

#[cfg(test)]
mod tests;
