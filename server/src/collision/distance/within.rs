//! Every pair of objects closer than a clearance: the distance query with an upper bound over a
//! set of candidate pairs, each pair's memory kept from one call to the next.

use std::collections::HashMap;

use nalgebra::Isometry3;

use super::{ClosestPoints, DistanceMemory};
use crate::collision::{DopTree, QueryStats};

/// A pair of objects closer than the clearance asked for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairWithin {
    /// The two objects' indices.
    pub a: usize,
    pub b: usize,
    /// Their distance and closest points (each in its own object's frame).
    pub closest: ClosestPoints,
}

/// Finds the pairs of objects closer than a clearance, frame after frame: each candidate pair
/// keeps its [`DistanceMemory`], so a pair that moves a little costs little. A far pair costs
/// one sphere test.
#[derive(Debug, Default)]
pub struct PairsWithin {
    memories: HashMap<(usize, usize), DistanceMemory>,
}

impl PairsWithin {
    /// Appends to `out` every pair `(a, b)` of `candidates` whose objects (tree and world pose,
    /// indexed as in `objects`) are closer than `clearance`, in the candidates' order.
    pub fn find(
        &mut self,
        objects: &[(&DopTree, Isometry3<f64>)],
        candidates: impl IntoIterator<Item = (usize, usize)>,
        clearance: f64,
        stats: &mut QueryStats,
        out: &mut Vec<PairWithin>,
    ) {
        for (a, b) in candidates {
            let ((tree_a, pose_a), (tree_b, pose_b)) = (&objects[a], &objects[b]);
            let memory = self.memories.entry((a, b)).or_default();
            let b_to_a = pose_a.inv_mul(pose_b);
            if let Some(closest) = tree_a.distance_below(tree_b, &b_to_a, clearance, memory, stats)
            {
                out.push(PairWithin { a, b, closest });
            }
        }
    }

    /// Forgets every pair's memory (the objects changed).
    pub fn clear(&mut self) {
        self.memories.clear();
    }
}
