//! Lower bounds on the distance between a node of A and a node of B: the walk opens a node pair
//! only when its bound is below the best distance found so far.

use nalgebra::{Point3, Vector3};

use super::super::realign::{AffineRealign, RealignCache, rounding_margin};
use super::super::separation::BOX_TEST_MAX_TRIANGLES;
use super::super::traverse::{TreePair, overlap_slack};
use crate::collision::QueryStats;
use crate::collision::triangle::Triangle;

/// A direction along which node pairs are measured apart: where the best pair found so far
/// points (from A's closest point to B's), so that near the answer the bound is nearly the
/// distance itself, which the DOPs' fixed directions are not (they miss it by the cosine of
/// the angle to the nearest of them, a few per cent of a large distance).
///
/// The support of a node's DOP along a direction is at most the same combination of the offsets
/// of the three normals of the set whose cone holds the direction (the coefficients are
/// non-negative): three multiply-adds a node.
#[derive(Debug, Clone, Copy)]
pub(super) struct Direction {
    /// The unit direction, A's frame.
    pub(super) u: Vector3<f64>,
    /// A's cone of `u`, and B's cone of `-u` taken into B's frame.
    a_cone: ([u8; 3], [f64; 3]),
    b_cone: ([u8; 3], [f64; 3]),
    /// `u · t`: where B's origin lies along `u`.
    along_translation: f64,
}

impl<const K: usize> TreePair<'_, AffineRealign<K>> {
    /// The direction from `from` to `to` (A's frame), or `None` when they coincide.
    pub(super) fn direction(&self, from: &Point3<f64>, to: &Point3<f64>) -> Option<Direction> {
        let u = (to - from).try_normalize(0.0)?;
        let a_cone = self.a.set.support_cone(&u);
        let b_cone = self.b.set.support_cone(&-(self.rotation.transpose() * u));
        Some(Direction {
            u,
            a_cone: (a_cone.planes, a_cone.lambda),
            b_cone: (b_cone.planes, b_cone.lambda),
            along_translation: u.dot(&self.translation),
        })
    }

    /// A lower bound on the distance between A's node `ia` and B's node `ib`; the tests stop at
    /// the first bound of at least `best` (the pair cannot hold a closer triangle pair).
    ///
    /// The cheap bounds first: the nodes' spheres (one subtraction from their centres'
    /// distance); then, for small nodes, their oriented boxes' gaps along the line through their
    /// centres and along `direction`, for larger ones their DOPs' gap along `direction`; only
    /// when none prunes, the DOPs re-aligned to A's unit directions, the widest gap along one of
    /// them. The DOP bounds lose the bound of their `f32` rounding, so that no bound exceeds the
    /// true distance (the boxes are padded for theirs).
    #[inline(always)]
    pub(super) fn lower_bound<const FUSED: bool>(
        &self,
        cache: &mut RealignCache<'_>,
        (ia, ib): (u32, u32),
        direction: Option<&Direction>,
        best: f64,
        stats: &mut QueryStats,
    ) -> f64 {
        stats.bv_tests += 1;
        let (sa, sb) = (
            self.a.nodes[ia as usize].sphere,
            self.b.nodes[ib as usize].sphere,
        );
        let centre_b = self.rotation * sb.centre() + self.translation;
        let spheres = (sa.centre() - centre_b).norm() - f64::from(sa.radius) - f64::from(sb.radius);
        if spheres >= best {
            return spheres;
        }
        let rounding = self.dop_rounding();
        let boxed = self.a.node_triangles(ia).len() <= BOX_TEST_MAX_TRIANGLES
            && self.b.node_triangles(ib).len() <= BOX_TEST_MAX_TRIANGLES;
        let directed = if boxed {
            self.boxes_gap((ia, ib), direction)
        } else {
            direction.map_or(f64::MIN, |direction| {
                self.dops_gap_along((ia, ib), direction) - rounding
            })
        };
        if directed >= best {
            return directed;
        }
        let da: &[f32; K] = self.a.node_offsets(ia as usize).try_into().unwrap();
        let e = cache.get::<K, FUSED, _>(&self.realigner, self.b, ib, stats);
        let dops = -f64::from(overlap_slack(da, e)) - rounding;
        spheres.max(directed).max(dops)
    }

    /// How much the `f32` offsets and their re-alignment may be off: the margin of offsets as
    /// large as the two trees' plus the translation between them.
    #[inline(always)]
    fn dop_rounding(&self) -> f64 {
        let scale = f64::from(self.a.max_abs_offset)
            + f64::from(self.b.max_abs_offset)
            + self.translation.norm();
        2.0 * f64::from(rounding_margin(scale))
    }

    /// The gap between the two nodes' DOPs along `direction`, from the offsets of its cones.
    #[inline(always)]
    fn dops_gap_along(&self, (ia, ib): (u32, u32), direction: &Direction) -> f64 {
        let support = |offsets: &[f32], (planes, lambda): ([u8; 3], [f64; 3])| {
            (0..3).fold(0.0, |sum, l| {
                sum + lambda[l] * f64::from(offsets[planes[l] as usize])
            })
        };
        let a_reach = support(self.a.node_offsets(ia as usize), direction.a_cone);
        let b_start = direction.along_translation
            - support(self.b.node_offsets(ib as usize), direction.b_cone);
        b_start - a_reach
    }

    /// The gap between the two nodes' oriented boxes along the better of the line through their
    /// centres (which bounds pairs side by side, where a long thin node's sphere is loose) and
    /// `direction` (pairs one above the other). The boxes' extents are padded for their own
    /// rounding, so the gaps are true bounds.
    #[inline(always)]
    fn boxes_gap(&self, (ia, ib): (u32, u32), direction: Option<&Direction>) -> f64 {
        let box_a = self.a.boxes[ia as usize].oriented();
        let box_b = self.b.boxes[ib as usize].oriented();
        let gap_along = |w: &Vector3<f64>| {
            let (low_a, high_a) = box_a.projection(w, 0.0);
            let (low_b, high_b) =
                box_b.projection(&(self.rotation.transpose() * w), w.dot(&self.translation));
            (low_b - high_a).max(low_a - high_b)
        };
        let across = (self.rotation * box_b.center + self.translation - box_a.center)
            .try_normalize(0.0)
            .map_or(f64::MIN, |w| gap_along(&w));
        direction.map_or(across, |direction| across.max(gap_along(&direction.u)))
    }
}

/// A lower bound on the distance between two triangles (A's frame), cheaper than measuring it:
/// the gap between their corners' projections on the line through their centroids and on `u`
/// (the direction of the best pair so far).
pub(super) fn triangles_gap(t1: &Triangle, t2: &Triangle, u: Option<&Vector3<f64>>) -> f64 {
    let centroid = |t: &Triangle| (t[0].coords + t[1].coords + t[2].coords) / 3.0;
    let gap_along = |w: &Vector3<f64>| {
        let range = |t: &Triangle| {
            t.iter().fold((f64::MAX, f64::MIN), |(low, high), corner| {
                let x = corner.coords.dot(w);
                (low.min(x), high.max(x))
            })
        };
        let ((low_1, high_1), (low_2, high_2)) = (range(t1), range(t2));
        (low_2 - high_1).max(low_1 - high_2)
    };
    let across = (centroid(t2) - centroid(t1))
        .try_normalize(0.0)
        .map_or(f64::MIN, |w| gap_along(&w));
    u.map_or(across, |u| across.max(gap_along(u)))
}
