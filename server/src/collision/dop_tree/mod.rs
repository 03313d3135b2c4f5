//! The DOP-tree: a bounding-volume tree of k-DOPs over a triangle mesh, and the simultaneous
//! traversal of two such trees with lazy O(k) re-alignment (the paper's §2.1).
//!
//! A newcomer can read the files in the order a query uses them:
//! - `tree`: the tree's layout and its public API ([`DopTree`]); `build` makes it, and
//!   `node_bounds` holds the sphere and the box each node keeps besides its DOP, `shared` how its
//!   arrays are allocated once and filled in place;
//! - `query`: a query's entry and the stages it goes through;
//! - `pair_memory`: what the last queries of the same two trees left (temporal coherence), with
//!   the `front` where the last walk ended and the `certificates` that keep its pairs apart;
//! - `root_separation`: the cheap proof that the two roots are apart;
//! - `realign`: B's nodes mapped into A's orientations in O(k), cached per query;
//! - `traverse`: the depth-first walk over node pairs; `separation`: the tests beyond the DOPs
//!   and the certificates they leave; `parallel`: the walk split across threads;
//! - `distance`: the distance query's own walk, with its bounds and its memory;
//! - `cache`: built trees kept in a folder, as `persist` writes and reads them, and `check`
//!   accepts them.

mod build;
mod cache;
mod certificates;
mod check;
mod distance;
mod front;
mod node_bounds;
mod pair_memory;
mod parallel;
mod persist;
mod query;
mod realign;
mod root_separation;
mod separation;
mod shared;
mod traverse;
mod tree;

pub use cache::{Provenance, TreeCache};
pub use distance::DistanceMemory;
pub use persist::reseal;
pub use tree::{DEFAULT_LEAF_SIZE, DopTree};

// The traversal is generic over how B's nodes are re-aligned, so that another method (the
// benchmarks' k-DOP tree re-aligned by brute force) runs the very same walk.
pub use realign::{Realign, rounding_margin};
pub use traverse::TreePair;

#[cfg(test)]
mod tests;
