//! How the traversal proves a node pair apart, and the certificate each proof leaves for the
//! front: the DOP axis that separated the pair, a face plane of a leaf, or the separating axis of
//! the two nodes' oriented boxes.
//!
//! Near contact a small patch of a smooth surface is nearly flat: its box is thin where a DOP of
//! fixed axes is not, and a leaf's face plane often clears a small subtree beside it. Both tests
//! end the walk, and its front, several levels higher than the DOPs alone.

use nalgebra::Vector3;

use super::realign::{Realign, RealignCache};
use super::traverse::{FrontPair, Slack, TreePair};
use super::tree::{DopTree, Node};
use crate::collision::QueryStats;
use crate::collision::triangle::Triangle;

/// Largest subtree, in triangles, whose pair with a leaf of the other tree is tested against the
/// leaf's face planes before it is split (a test costs a projection of the subtree's corners).
const PLANE_TEST_MAX_TRIANGLES: usize = 16;

/// Largest node, in triangles, whose pair with another such node is tested with their oriented
/// boxes when their DOPs overlap, in walks that record a front: a small patch is thin across its
/// box, not its DOP; above this size a box test rarely separates what the DOPs did not.
pub(super) const BOX_TEST_MAX_TRIANGLES: usize = 64;

/// The same bound in walks that record no front (a detached query's, the search around an old
/// witness): there a box test only prunes, and most of these walks end on a hit, where the boxes
/// on the way down overlap; small boxes still pay on the worst queries (see BENCHMARKS.md, B2).
pub(super) const PLAIN_BOX_TEST_MAX_TRIANGLES: usize = 8;

/// Relative rounding guard of [`TreePair::face_separation`]'s gaps, of the coordinates' scale:
/// covers the `f64` rounding of a projection and of posing a corner in the other frame, each a
/// few ulps.
const FACE_ROUNDING: f64 = 64.0 * f64::EPSILON;

/// How [`TreePair::face_separation`] measures the extent of an inner node along a leaf's face
/// normal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Extent {
    /// Projecting every corner of its triangles: exact, for small subtrees.
    Exact,
    /// From its bounding sphere: a bound, in constant time, for large subtrees.
    Sphere,
}

/// How a traversal ended at a node pair.
#[derive(Debug, Clone, Copy)]
pub(super) enum Ending {
    /// Proved apart: the other tree's triangles lie at least `gap` beyond this tree's along
    /// `direction` (unit to f32 rounding), in A's frame, or in B's when `along_b`.
    Separated {
        gap: f64,
        direction: [f32; 3],
        along_b: bool,
    },
    /// To be tested again: a pair of leaves that no face plane separates, or a pair left
    /// unexplored when a first hit stopped the traversal.
    Retest,
}

impl<R> TreePair<'_, R> {
    /// The certificate of node pair `(ia, ib)`, whose DOPs overlap, from their oriented boxes:
    /// the separating axis the 15-axis test finds, in A's frame, rounded to `f32`, with the gap
    /// between the boxes' projections on it; `None` when the boxes overlap too, or when either
    /// node has more than `max_triangles` (untested).
    pub(super) fn box_separation(
        &self,
        (ia, ib): (u32, u32),
        max_triangles: usize,
        stats: &mut QueryStats,
    ) -> Option<Ending> {
        if self.a.node_triangles(ia).len() > max_triangles
            || self.b.node_triangles(ib).len() > max_triangles
        {
            return None;
        }
        stats.bv_tests += 1;
        let box_a = self.a.boxes[ia as usize].oriented();
        let box_b = self.b.boxes[ib as usize].oriented();
        let axis = box_a.separating_axis(&box_b, &self.rotation, &self.translation)?;
        let direction = axis.try_normalize(f64::MIN_POSITIVE)?.cast::<f32>();
        let exact = direction.cast::<f64>();
        // B's box projected in B's frame: n . (R q + t) = (Rᵀ n) . q + n . t.
        let (low_a, high_a) = box_a.projection(&exact, 0.0);
        let (low_b, high_b) = box_b.projection(
            &(self.rotation.transpose() * exact),
            exact.dot(&self.translation),
        );
        let (gap, sign) = if low_b > high_a {
            (low_b - high_a, 1.0)
        } else if low_a > high_b {
            (low_a - high_b, -1.0)
        } else {
            return None;
        };
        Some(Ending::Separated {
            gap,
            direction: (direction * sign).into(),
            along_b: false,
        })
    }

    /// Adds to `front`, when the traversal records one, the node pair that `slack` (negative)
    /// separates with its certificate: the axis the slack came from (found again among the
    /// cached offsets) and the gap along it.
    pub(super) fn record_separation<const K: usize, const FUSED: bool>(
        &self,
        front: Option<&mut Vec<FrontPair>>,
        cache: &mut RealignCache<'_>,
        reverse_cache: &mut RealignCache<'_>,
        (ia, ib): (u32, u32),
        slack: Slack,
    ) where
        R: Realign<K>,
    {
        let Some(front) = front else {
            return;
        };
        let mut unused = QueryStats::default();
        let (own, moved, set) = if slack.along_b {
            // A slack along B's axes comes from a reverse test, so there is a reverse method.
            let Some(reverse) = self.realigner.reverse(self.a, self.b) else {
                front.push(FrontPair {
                    pair: (ia, ib),
                    ending: Ending::Retest,
                });
                return;
            };
            (
                self.b.node_offsets(ib as usize),
                reverse_cache.get::<K, FUSED, R>(reverse, self.a, ia, &mut unused),
                &self.b.set,
            )
        } else {
            (
                self.a.node_offsets(ia as usize),
                cache.get::<K, FUSED, R>(&self.realigner, self.b, ib, &mut unused),
                &self.a.set,
            )
        };
        // The first axis whose sum is the slack (the overlap test's own sums over the same
        // offsets), compared all at once (a bit mask) rather than one branch per axis.
        let mut mask = 0u32;
        for i in 0..K {
            mask |= u32::from(own[i] + moved[i] <= slack.value) << i;
        }
        let axis = (mask.trailing_zeros() as usize).min(K - 1);
        front.push(FrontPair {
            pair: (ia, ib),
            ending: Ending::Separated {
                gap: -slack.value as f64,
                direction: set.normal(axis).cast::<f32>().into(),
                along_b: slack.along_b,
            },
        });
    }

    /// How the leaf's face planes are tried against the other node of a pair of a leaf and an
    /// inner node, one in each tree: against the inner node's triangles when it has at most
    /// [`PLANE_TEST_MAX_TRIANGLES`]; against its bounding sphere when it is smaller than the
    /// leaf (the traversal would otherwise descend the inner node alone under a large
    /// triangle); not at all for other pairs (a small triangle's plane rarely clears a larger
    /// subtree, and the descent splits that subtree anyway).
    pub(super) fn plane_test_extent(
        &self,
        na: &Node,
        nb: &Node,
        ia: u32,
        ib: u32,
    ) -> Option<Extent> {
        let extent = |tree: &DopTree, index: u32, inner: &Node, leaf: &Node| {
            if tree.node_triangles(index).len() <= PLANE_TEST_MAX_TRIANGLES {
                Some(Extent::Exact)
            } else {
                (inner.size < leaf.size).then_some(Extent::Sphere)
            }
        };
        match (na.is_leaf(), nb.is_leaf()) {
            (true, false) => extent(self.b, ib, nb, na),
            (false, true) => extent(self.a, ia, na, nb),
            _ => None,
        }
    }

    /// The certificate of node pair `(ia, ib)` where at least one is a leaf: the plane of one
    /// of the leaves' triangles with all of the other node's corners (or, by `extent`, its
    /// bounding sphere) strictly beyond it, the widest gap of them; [`Ending::Retest`] when no
    /// such plane separates them.
    pub(super) fn face_separation(&self, ia: u32, ib: u32, extent: Extent) -> Ending {
        let (node_a, node_b) = (&self.a.nodes[ia as usize], &self.b.nodes[ib as usize]);
        let triangles_a = self.a.node_triangles(ia);
        let triangles_b = self.b.node_triangles(ib);
        let planes = |node: &Node, triangles| if node.is_leaf() { triangles } else { &[][..] };
        let planes_a = planes(node_a, triangles_a);
        let planes_b = planes(node_b, triangles_b);
        // A node's projections on `direction` (in its tree's frame) plus `offset`, or `None` as
        // soon as the corners projected so far give `hopeless` (see below).
        let range = |node: &Node,
                     triangles,
                     direction: &Vector3<f64>,
                     offset: f64,
                     hopeless: &dyn Fn((f64, f64)) -> bool| {
            if node.is_leaf() || extent == Extent::Exact {
                projection_range_until(triangles, direction, offset, hopeless)
            } else {
                let centre = direction.dot(&node.sphere.centre()) + offset;
                let radius = f64::from(node.sphere.radius);
                Some((centre - radius, centre + radius))
            }
        };
        // Both sides are projected here in each tree's own frame, while the triangle test poses
        // B's corners in A's frame (R q + t): the two round differently, so a gap within that
        // rounding proves nothing (a corner 4e-16 inside a face was once cleared by it).
        let rounding = FACE_ROUNDING
            * (f64::from(self.a.max_abs_offset())
                + f64::from(self.b.max_abs_offset())
                + self.translation.abs().sum());
        let mut best = Ending::Retest;
        let mut widest = 0.0;
        // A's normals in A's frame, B's in B's own; each rounded to f32 (as stored) before the
        // gap along it is measured. B's corners are projected in B's frame: n . (R q + t) =
        // (Rᵀ n) . q + n . t.
        let candidates = planes_a
            .iter()
            .map(|t| (t, false))
            .chain(planes_b.iter().map(|t| (t, true)));
        for (triangle, along_b) in candidates {
            let Some(normal) = face_normal(triangle) else {
                continue;
            };
            let direction = normal.cast::<f32>();
            let exact = direction.cast::<f64>();
            let (in_a, in_b) = if along_b {
                (self.rotation * exact, exact)
            } else {
                (exact, self.rotation.transpose() * exact)
            };
            let offset_b = in_a.dot(&self.translation);
            // The plane's own node is a leaf, projected whole. The gaps below beat `widest` only
            // while the other node's corners stay beyond it: the other node's projection stops
            // at the first triangle that rules both out. A partial range only widens as corners
            // come in, so the planes skipped are exactly those the complete ranges would reject.
            let beats = widest;
            let hopeless = |(low_a, high_a): (f64, f64), (low_b, high_b): (f64, f64)| {
                !(low_b - high_a - rounding > beats || low_a - high_b - rounding > beats)
            };
            let ranges = if along_b {
                let b = projection_range(triangles_b, &in_b, offset_b);
                range(node_a, triangles_a, &in_a, 0.0, &|a| hopeless(a, b)).map(|a| (a, b))
            } else {
                let a = projection_range(triangles_a, &in_a, 0.0);
                range(node_b, triangles_b, &in_b, offset_b, &|b| hopeless(a, b)).map(|b| (a, b))
            };
            let Some(((low_a, high_a), (low_b, high_b))) = ranges else {
                continue;
            };
            // In A's frame the other tree is B (beyond along +normal when B is above); in B's
            // frame it is A.
            let (above, below) = (low_b - high_a - rounding, low_a - high_b - rounding);
            let (gap, sign) = if above > widest {
                (above, if along_b { -1.0 } else { 1.0 })
            } else if below > widest {
                (below, if along_b { 1.0 } else { -1.0 })
            } else {
                continue;
            };
            widest = gap;
            best = Ending::Separated {
                gap,
                direction: (direction * sign).into(),
                along_b,
            };
        }
        best
    }
}

/// The unit normal of a triangle, if it is not degenerate.
fn face_normal(t: &Triangle) -> Option<Vector3<f64>> {
    let normal = (t[1] - t[0]).cross(&(t[2] - t[0]));
    let length = normal.norm();
    (length > 0.0 && length.is_finite()).then(|| normal / length)
}

/// The least and greatest of `direction . p + offset` over the triangles' corners `p`.
fn projection_range(triangles: &[Triangle], direction: &Vector3<f64>, offset: f64) -> (f64, f64) {
    projection_range_until(triangles, direction, offset, &|_| false)
        .expect("a projection that never gives up is complete")
}

/// [`projection_range`], or `None` as soon as the range of the triangles projected so far is
/// `hopeless`.
fn projection_range_until(
    triangles: &[Triangle],
    direction: &Vector3<f64>,
    offset: f64,
    hopeless: &dyn Fn((f64, f64)) -> bool,
) -> Option<(f64, f64)> {
    let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
    for triangle in triangles {
        for p in triangle {
            let x = direction.x * p.x + direction.y * p.y + direction.z * p.z + offset;
            low = low.min(x);
            high = high.max(x);
        }
        if hopeless((low, high)) {
            return None;
        }
    }
    Some((low, high))
}
