//! Distance between meshes: how much room there is between two parts and where it is tightest.
//!
//! The DOP-tree answers it ([`DopTree::distance`](super::DopTree::distance), and
//! [`distance_below`](super::DopTree::distance_below) for "only if closer than"), walking both
//! trees and pruning every node pair whose lower bound is no better than the closest triangle
//! pair found so far; a [`DistanceMemory`] kept per pair of objects carries what the last query
//! found to the next one (temporal coherence). [`PairsWithin`] finds every pair of objects closer
//! than a clearance. The exact triangle distance is [`triangle_distance`]; the reference answer
//! of the tests is [`brute_force_distance`].

mod brute_force;
mod closest;
mod triangles;
mod within;

pub use super::dop_tree::DistanceMemory;
pub use brute_force::brute_force_distance;
pub use closest::ClosestPoints;
pub use triangles::{TriangleDistance, separated_triangle_distance, triangle_distance};
pub use within::{PairWithin, PairsWithin};

#[cfg(test)]
mod tests;
