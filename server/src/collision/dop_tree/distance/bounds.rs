//! Lower bounds on the distance between a node of A and a node of B: the walk opens a node pair
//! only when its bound is below the best distance found so far.

use nalgebra::{Point3, Vector3};

use super::super::realign::{AffineRealign, RealignCache, rounding_margin};
use super::super::traverse::{TreePair, overlap_slack};
use crate::collision::QueryStats;
use crate::collision::triangle::Triangle;

impl<const K: usize> TreePair<'_, AffineRealign<K>> {
    /// A lower bound on the distance between A's node `ia` and B's node `ib`, or `None` when it
    /// is at least `best` (the pair cannot hold a closer triangle pair).
    ///
    /// First the nodes' spheres (one subtraction from their centres' distance); only when they
    /// do not prune, the DOPs: B's node re-aligned to A's unit directions, the widest gap along
    /// one of them, less the bound of the re-alignment's `f32` rounding so that the bound never
    /// exceeds the true distance.
    #[inline(always)]
    pub(super) fn lower_bound<const FUSED: bool>(
        &self,
        cache: &mut RealignCache<'_>,
        (ia, ib): (u32, u32),
        best: f64,
        stats: &mut QueryStats,
    ) -> Option<f64> {
        stats.bv_tests += 1;
        let (sa, sb) = (
            self.a.nodes[ia as usize].sphere,
            self.b.nodes[ib as usize].sphere,
        );
        let centre_b = self.rotation * sb.centre() + self.translation;
        let spheres = (sa.centre() - centre_b).norm() - f64::from(sa.radius) - f64::from(sb.radius);
        if spheres >= best {
            return None;
        }
        let da: &[f32; K] = self.a.node_offsets(ia as usize).try_into().unwrap();
        let e = cache.get::<K, FUSED, _>(&self.realigner, self.b, ib, stats);
        let dops = -f64::from(overlap_slack(da, e)) - self.dop_rounding();
        let bound = spheres.max(dops);
        (bound < best).then_some(bound)
    }

    /// How much the `f32` re-aligned offsets may be off: the margin of offsets as large as the
    /// two trees' plus the translation between them.
    #[inline(always)]
    fn dop_rounding(&self) -> f64 {
        let scale = f64::from(self.a.max_abs_offset)
            + f64::from(self.b.max_abs_offset)
            + self.translation.norm();
        2.0 * f64::from(rounding_margin(scale))
    }
}

/// A sphere around a triangle: centred on its corners' mean, reaching its farthest corner.
pub(super) fn triangle_sphere(triangle: &Triangle) -> (Point3<f64>, f64) {
    let centre = Point3::from((triangle[0].coords + triangle[1].coords + triangle[2].coords) / 3.0);
    let radius = triangle
        .iter()
        .map(|corner| (corner - centre).norm())
        .fold(0.0, f64::max);
    (centre, radius)
}

/// The lower bound of two triangles' spheres on their distance.
pub(super) fn spheres_gap(a: &(Point3<f64>, f64), b: &(Point3<f64>, f64)) -> f64 {
    let between: Vector3<f64> = a.0 - b.0;
    between.norm() - a.1 - b.1
}
