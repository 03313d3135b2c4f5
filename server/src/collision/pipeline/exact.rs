//! How the pipeline runs an exact test: serially, or split across threads when few pairs reach
//! the exact stage.

use crate::collision::{DopTree, MeshCollider, ParryMesh, QueryStats};
use nalgebra::Isometry3;

/// An exact test the pipeline can run on its thread pool: serially for a frame with many pairs,
/// or split across threads when a few pairs dominate the frame.
pub trait ExactTest: MeshCollider {
    /// Like [`MeshCollider::intersects`], but free to split the work across the current rayon
    /// pool. Tests without a parallel traversal run serially.
    fn intersects_split(
        &self,
        other: &Self,
        b_to_a: &Isometry3<f64>,
        stats: &mut QueryStats,
    ) -> bool {
        self.intersects(other, b_to_a, stats)
    }
}

impl ExactTest for DopTree {
    fn intersects_split(
        &self,
        other: &Self,
        b_to_a: &Isometry3<f64>,
        stats: &mut QueryStats,
    ) -> bool {
        self.intersects_parallel(other, b_to_a, stats)
    }
}

/// parry's mesh test has no parallel traversal; it is the tests' oracle.
impl ExactTest for ParryMesh {}
