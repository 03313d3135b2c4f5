//! Lower bounds on the distance between a node of A and a node of B: the walk opens a node pair
//! only when its bound is below the best distance found so far.

use nalgebra::{Point3, Vector3};

use super::super::realign::{AffineRealign, RealignCache, rounding_margin};
use super::super::separation::BOX_TEST_MAX_TRIANGLES;
use super::super::traverse::{TreePair, overlap_slack};
use crate::collision::QueryStats;
use crate::collision::oriented_box::OrientedBox;
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

/// A lower bound on the distance between two sets, with the unit line (A's frame) along which
/// their projections are at least that far apart: as B moves, the bound falls only by how far
/// B's points move along that line, which for a part turning beside another (its near side
/// moving across the gap, not into it) is a small part of their motion. A zero line: the bound
/// is not one line's gap, and every motion counts in full.
#[derive(Debug, Clone, Copy)]
pub(super) struct Gap {
    pub(super) bound: f64,
    pub(super) along: Vector3<f64>,
}

impl Gap {
    /// A bound that no one line carries.
    pub(super) fn anywhere(bound: f64) -> Self {
        Gap {
            bound,
            along: Vector3::zeros(),
        }
    }

    /// The gap along the unit line `along`.
    pub(super) fn along(bound: f64, along: Vector3<f64>) -> Self {
        Gap { bound, along }
    }

    /// The larger of the two bounds.
    pub(super) fn max(self, other: Gap) -> Gap {
        if other.bound > self.bound {
            other
        } else {
            self
        }
    }
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
    /// true distance (the boxes are padded for theirs). Each is a gap along one line, which a
    /// bound of at least `best` keeps (the pair stays closed, in the front).
    #[inline(always)]
    pub(super) fn lower_bound<const FUSED: bool>(
        &self,
        cache: &mut RealignCache<'_>,
        (ia, ib): (u32, u32),
        direction: Option<&Direction>,
        best: f64,
        stats: &mut QueryStats,
    ) -> Gap {
        stats.bv_tests += 1;
        let (sa, sb) = (
            self.a.nodes[ia as usize].sphere,
            self.b.nodes[ib as usize].sphere,
        );
        let between = self.rotation * sb.centre() + self.translation - sa.centre();
        let length = between.norm();
        let spheres = length - f64::from(sa.radius) - f64::from(sb.radius);
        if spheres >= best {
            return match length > 0.0 {
                true => Gap::along(spheres, between / length),
                false => Gap::anywhere(spheres),
            };
        }
        let rounding = self.dop_rounding();
        let boxed = self.a.node_triangles(ia).len() <= BOX_TEST_MAX_TRIANGLES
            && self.b.node_triangles(ib).len() <= BOX_TEST_MAX_TRIANGLES;
        let directed = if boxed {
            self.boxes_gap((ia, ib), direction, best)
        } else {
            direction.map_or(Gap::anywhere(f64::MIN), |direction| {
                Gap::along(
                    self.dops_gap_along((ia, ib), direction) - rounding,
                    direction.u,
                )
            })
        };
        if directed.bound >= best {
            return directed;
        }
        let da: &[f32; K] = self.a.node_offsets(ia as usize).try_into().unwrap();
        let e = cache.get::<K, FUSED, _>(&self.realigner, self.b, ib, stats);
        let slack = overlap_slack(da, e);
        let dops = -f64::from(slack) - rounding;
        if dops >= best {
            // Closed along one of A's normals: the one whose sum is the least found.
            let axis = (0..K).position(|i| da[i] + e[i] == slack).unwrap_or(0);
            return Gap::along(dops, self.a.set.normal(axis));
        }
        // Below the best: the pair is opened, and its line is never asked for.
        Gap::anywhere(spheres.max(directed.bound).max(dops))
    }

    /// How much the `f32` offsets and their re-alignment may be off: the margin of offsets as
    /// large as the two trees' plus the translation between them. Far above the `f64` rounding
    /// of any corner in A's frame, it is also the gap that proves two triangles apart.
    #[inline(always)]
    pub(super) fn dop_rounding(&self) -> f64 {
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

    /// The gap between the two nodes' oriented boxes along the best of the line through their
    /// centres (which bounds pairs side by side, where a long thin node's sphere is loose),
    /// `direction` (pairs one above the other) and each box's thinnest axis (a small node of a
    /// smooth surface is nearly flat across it: pairs of patches face to face), stopping at the
    /// first of at least `best`. The boxes' extents are padded for their own rounding, so the
    /// gaps are true bounds.
    #[inline(always)]
    fn boxes_gap(&self, (ia, ib): (u32, u32), direction: Option<&Direction>, best: f64) -> Gap {
        let box_a = self.a.boxes[ia as usize].oriented();
        let box_b = self.b.boxes[ib as usize].oriented();
        // Along `w` in A's frame, `w_b` being the same direction in B's.
        let gap_along = |w: Vector3<f64>, w_b: &Vector3<f64>| {
            let a = box_a.projection(&w, 0.0);
            let b = box_b.projection(w_b, w.dot(&self.translation));
            Gap::along(ranges_gap(a, b), w)
        };
        let in_b = |w: &Vector3<f64>| self.rotation.tr_mul(w);
        let thinnest = |b: &OrientedBox| b.axes.column(b.extents.imin()).into_owned();
        let mut gap = Gap::anywhere(f64::MIN);
        if let Some(w) =
            (self.rotation * box_b.center + self.translation - box_a.center).try_normalize(0.0)
        {
            gap = gap_along(w, &in_b(&w));
        }
        if gap.bound < best
            && let Some(direction) = direction
        {
            gap = gap.max(gap_along(direction.u, &in_b(&direction.u)));
        }
        if gap.bound < best {
            let w = thinnest(&box_a);
            gap = gap.max(gap_along(w, &in_b(&w)));
        }
        if gap.bound < best {
            let w_b = thinnest(&box_b);
            gap = gap.max(gap_along(self.rotation * w_b, &w_b));
        }
        gap
    }
}

/// A triangle (A's frame) with what its lower bounds reuse: the range of its corners along the
/// direction of the best pair (when there is one), and once a bound needs more than that
/// ([`BoundedTriangle::complete`]), its unit normal (none when it is degenerate) with their range
/// along it, and its centroid. Near the answer the direction's ranges settle most pairs, so the
/// rest is worked out only for the triangles that need it.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct BoundedTriangle {
    pub(super) corners: Triangle,
    along_u: Option<(f64, f64)>,
    /// Whether `normal` and `centroid` are worked out.
    completed: bool,
    normal: Option<(Vector3<f64>, (f64, f64))>,
    centroid: Vector3<f64>,
}

impl BoundedTriangle {
    /// `corners` bounded along `u` (unit), the direction of the best pair so far.
    pub(super) fn new(corners: Triangle, u: Option<&Vector3<f64>>) -> Self {
        let mut bounded = BoundedTriangle {
            corners,
            ..BoundedTriangle::default()
        };
        bounded.along_u = u.map(|u| bounded.range(u));
        bounded
    }

    /// Works out its normal, the range along it and its centroid, once.
    fn complete(&mut self) {
        if self.completed {
            return;
        }
        let [p, q, r] = &self.corners;
        self.centroid = (p.coords + q.coords + r.coords) / 3.0;
        self.normal = (q - p)
            .cross(&(r - p))
            .try_normalize(0.0)
            .map(|n| (n, self.range(&n)));
        self.completed = true;
    }

    /// Its corners' span along the direction it was bounded along, if any.
    pub(super) fn along_u(&self) -> Option<(f64, f64)> {
        self.along_u
    }

    /// The least and the greatest of its corners' projections on `w`.
    fn range(&self, w: &Vector3<f64>) -> (f64, f64) {
        self.corners
            .iter()
            .fold((f64::MAX, f64::MIN), |(low, high), corner| {
                let x = corner.coords.dot(w);
                (low.min(x), high.max(x))
            })
    }
}

/// The gap between two ranges of projections on one line (`low`, `high`), whichever lies
/// beyond the other; negative when they overlap.
pub(super) fn ranges_gap((low_1, high_1): (f64, f64), (low_2, high_2): (f64, f64)) -> f64 {
    (low_2 - high_1).max(low_1 - high_2)
}

/// A lower bound on the distance between two triangles bounded along the same direction,
/// cheaper than measuring it: the gap between their corners' projections on a few lines,
/// stopping at the first of at least `best`. The lines, cheapest first: the direction of the
/// best pair (both ranges already known: near the answer, where most pairs are bounded, it is
/// nearly the surfaces' normal), each triangle's normal (triangles face to face), the line
/// through their centroids (side by side); the triangles are completed only when the first
/// falls short. Each gap is of both triangles' projections, so a normal that rounding has
/// tilted still gives a true bound.
pub(super) fn triangles_gap(t1: &mut BoundedTriangle, t2: &mut BoundedTriangle, best: f64) -> f64 {
    let mut gap = match (t1.along_u, t2.along_u) {
        (Some(range_1), Some(range_2)) => ranges_gap(range_1, range_2),
        _ => f64::MIN,
    };
    if gap >= best {
        return gap;
    }
    t1.complete();
    t2.complete();
    if let Some((n, own)) = t2.normal {
        gap = gap.max(ranges_gap(t1.range(&n), own));
    }
    if gap < best
        && let Some((n, own)) = t1.normal
    {
        gap = gap.max(ranges_gap(own, t2.range(&n)));
    }
    if gap < best
        && let Some(w) = (t2.centroid - t1.centroid).try_normalize(0.0)
    {
        gap = gap.max(ranges_gap(t1.range(&w), t2.range(&w)));
    }
    gap
}

#[cfg(test)]
mod tests {
    use nalgebra::{Point3, Vector3};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::{BoundedTriangle, triangles_gap};
    use crate::collision::distance::triangle_distance;
    use crate::collision::triangle::Triangle;

    /// A random triangle near `centre`: one in four a sliver, a segment or a point.
    fn random_triangle(rng: &mut ChaCha8Rng, centre: Vector3<f64>) -> Triangle {
        let mut corner =
            || Point3::from(centre + Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)));
        let mut t = [corner(), corner(), corner()];
        match rng.random_range(0..8) {
            0 => t[1] = t[0],
            1 => t[2] = t[0] + (t[1] - t[0]) * 0.5,
            2 => t[2] = t[0] + (t[1] - t[0]) * 0.5 + Vector3::new(1e-9, 0.0, -1e-9),
            3 => t = [t[0]; 3],
            _ => {}
        }
        t
    }

    /// The triangles' gap never exceeds their exact distance, along any `u`, whether it stops
    /// early or not; and facing triangles far apart are bounded close to their distance.
    #[test]
    fn the_triangles_gap_is_a_lower_bound() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut tight = 0;
        for case in 0..20_000 {
            let reach = [0.5, 2.0, 6.0][case % 3];
            let centre = Vector3::from_fn(|_, _| rng.random_range(-reach..reach));
            let (t1, t2) = (
                random_triangle(&mut rng, Vector3::zeros()),
                random_triangle(&mut rng, centre),
            );
            let exact = triangle_distance(&t1, &t2).distance;
            let u = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)).try_normalize(0.0);
            for best in [f64::INFINITY, exact, 0.5 * exact] {
                let (mut b1, mut b2) = (
                    BoundedTriangle::new(t1, u.as_ref()),
                    BoundedTriangle::new(t2, u.as_ref()),
                );
                let gap = triangles_gap(&mut b1, &mut b2, best);
                assert!(
                    gap <= exact + 1e-12 * (1.0 + reach),
                    "case {case}: gap {gap} over the distance {exact}: {t1:?} {t2:?}"
                );
                tight += (best.is_infinite() && exact > 0.0 && gap >= 0.9 * exact) as usize;
            }
        }
        assert!(tight > 4_000, "{tight} bounds within 10% of the distance");
    }
}
