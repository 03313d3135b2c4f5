//! How the pipeline runs an exact test: serially, or split across threads when the pair's last
//! test was expensive.

use crate::collision::{DopTree, MeshCollider, ParryMesh, QueryStats};
use nalgebra::Isometry3;

/// An exact test the pipeline can run on its thread pool: serially for a cheap pair, or split
/// across threads for a pair whose last test was long (see
/// [`PipelineConfig::split_min_bv_tests`](super::PipelineConfig::split_min_bv_tests)).
pub trait ExactTest: MeshCollider {
    /// Like [`MeshCollider::intersects`], but free to split a long traversal across the current
    /// rayon pool. Tests without a parallel traversal run serially.
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
