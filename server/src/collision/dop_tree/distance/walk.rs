//! The walk of a distance query: over node pairs, nearest first (`queue`), each opened only
//! while its lower bound is below the best distance found; the leaves' triangle pairs measured
//! exactly.

use nalgebra::Point3;

use super::super::realign::{AffineRealign, RealignCache, Scratch, with_scratch};
use super::super::traverse::TreePair;
use super::super::tree::DEFAULT_LEAF_SIZE;
use super::bounds::{BoundedTriangle, Direction, Gap, ranges_gap, triangles_gap};
use super::memory::BoundedPair;
use super::queue::OpenQueue;
use crate::collision::QueryStats;
use crate::collision::distance::{
    TriangleDistance, separated_triangle_distance, triangle_distance,
};

/// How many of a leaf's triangles are bounded at once: the default leaf size.
const LEAF_CHUNK: usize = DEFAULT_LEAF_SIZE;

/// How much closer than the best (relatively) a triangle pair must possibly be to be measured.
const TIE: f64 = 1e-14;

/// The closest triangle pair found so far, in A's frame.
#[derive(Debug, Clone, Copy)]
pub(super) struct Closest {
    /// The best distance: the least measured, or the bound asked for while nothing is closer.
    pub(super) distance: f64,
    /// The two triangles' positions in leaf order; `None` while nothing closer than the bound
    /// asked for was measured.
    pub(super) pair: Option<[u32; 2]>,
    pub(super) on_a: Point3<f64>,
    /// B's closest point, in A's frame.
    pub(super) on_b: Point3<f64>,
}

impl Closest {
    /// Keeps `found` between triangles `pair` (leaf order) if it is closer than the best.
    fn offer(&mut self, found: TriangleDistance, pair: [u32; 2]) {
        if found.distance < self.distance {
            *self = Closest {
                distance: found.distance,
                pair: Some(pair),
                on_a: found.on_first,
                on_b: found.on_second,
            };
        }
    }

    /// The bound from which a triangle pair is not measured: the best distance, less a relative
    /// [`TIE`] once a pair is measured. Triangles sharing the closest corner or edge (a corner
    /// of one part nearest the other: every triangle around it) are exactly as far as the best,
    /// and their bounds fall short of it by a rounding; measuring them would change the answer
    /// by less than the measure's own rounding.
    fn tie(&self) -> f64 {
        match self.pair {
            Some(_) => self.distance * (1.0 - TIE),
            None => self.distance,
        }
    }

    /// Nothing found yet, and only distances below `d_max` wanted.
    pub(super) fn within(d_max: f64) -> Self {
        Closest {
            distance: d_max,
            pair: None,
            on_a: Point3::origin(),
            on_b: Point3::origin(),
        }
    }
}

/// One walk's state: the best pair, the pairs still to open, the pairs left closed.
struct Walk<'w> {
    closest: &'w mut Closest,
    queue: &'w mut OpenQueue,
    front: &'w mut Vec<BoundedPair>,
    from_roots: bool,
}

impl<const K: usize> TreePair<'_, AffineRealign<K>> {
    /// Measures A's triangle `ia` against B's `ib` (leaf order), keeping them if closer.
    pub(super) fn measure_triangles(
        &self,
        [ia, ib]: [u32; 2],
        closest: &mut Closest,
        stats: &mut QueryStats,
    ) {
        let (ia, ib) = (ia as usize, ib as usize);
        if ia >= self.a.triangles.len() || ib >= self.b.triangles.len() {
            return;
        }
        stats.tri_tests += 1;
        let found = triangle_distance(&self.a.triangles[ia], &self.b_triangle_in_a(ib));
        closest.offer(found, [ia as u32, ib as u32]);
    }

    /// Walks the node pairs in `queue` (or from the root pair, with `from_roots`), improving
    /// `closest` and recording in `front` every pair it leaves closed with its bound. Returns
    /// whether the walk ran to its end (it stops at a distance of 0), so that the front is whole.
    pub(super) fn walk_closest(
        &self,
        closest: &mut Closest,
        queue: &mut OpenQueue,
        front: &mut Vec<BoundedPair>,
        from_roots: bool,
        stats: &mut QueryStats,
    ) -> bool {
        let mut walk = Walk {
            closest,
            queue,
            front,
            from_roots,
        };
        with_scratch(|scratch| {
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                // SAFETY: the CPU supports AVX2 and FMA, checked just above.
                return unsafe { self.walk_avx2(scratch, &mut walk, stats) };
            }
            self.walk::<false>(scratch, &mut walk, stats)
        })
    }

    /// [`Self::walk`] compiled with AVX2 and FMA enabled (the re-alignment is vector code).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn walk_avx2(
        &self,
        scratch: &mut Scratch,
        walk: &mut Walk<'_>,
        stats: &mut QueryStats,
    ) -> bool {
        self.walk::<true>(scratch, walk, stats)
    }

    #[inline(always)]
    fn walk<const FUSED: bool>(
        &self,
        scratch: &mut Scratch,
        walk: &mut Walk<'_>,
        stats: &mut QueryStats,
    ) -> bool {
        scratch.begin();
        let mut cache = RealignCache {
            stamp: scratch.stamp,
            tags: &mut scratch.tags,
            realigned: &mut scratch.realigned,
        };
        let Walk {
            closest,
            queue,
            front,
            from_roots,
        } = walk;
        let mut direction = self.best_direction(closest);
        if *from_roots {
            let roots = self.lower_bound::<FUSED>(
                &mut cache,
                (0, 0),
                direction.as_ref(),
                closest.distance,
                stats,
            );
            queue.push(0, 0, roots.bound);
        }
        // The carried pairs, measured again at this pose: most are still apart and stay whole in
        // the front.
        let carried = std::mem::take(&mut queue.carried);
        for &pair in &carried {
            let gap = self
                .lower_bound::<FUSED>(
                    &mut cache,
                    (pair.ia, pair.ib),
                    direction.as_ref(),
                    closest.distance,
                    stats,
                )
                .max(pair.gap);
            if gap.bound >= closest.distance {
                front.push(BoundedPair { gap, ..pair });
            } else {
                queue.push(pair.ia, pair.ib, gap.bound);
            }
        }
        queue.carried = carried;
        queue.carried.clear();
        while let Some(pending) = queue.pop() {
            let (ia, ib) = (pending.ia, pending.ib);
            // The best distance may have improved since the pair was queued.
            if pending.bound >= closest.distance {
                // Nearest first: every pair still queued is at least as far.
                front.push(BoundedPair {
                    ia,
                    ib,
                    gap: Gap::anywhere(pending.bound),
                });
                queue.drain_into(front);
                break;
            }
            stats.nodes_visited += 1;
            let (na, nb) = (&self.a.nodes[ia as usize], &self.b.nodes[ib as usize]);
            if na.is_leaf() && nb.is_leaf() {
                let before = closest.distance;
                let gap = self.closest_in_leaves(ia, ib, direction.as_ref(), closest, stats);
                if closest.distance == 0.0 {
                    return false;
                }
                front.push(BoundedPair { ia, ib, gap });
                if closest.distance < before {
                    direction = self.best_direction(closest);
                }
                continue;
            }
            let [first, second] = self.children(ia, ib);
            let [x, y] = [first, second].map(|pair| {
                self.lower_bound::<FUSED>(
                    &mut cache,
                    pair,
                    direction.as_ref(),
                    closest.distance,
                    stats,
                )
            });
            // The nearer pair queued last: among overlapping pairs it is opened first.
            let (near, far) = if y.bound < x.bound {
                ((second, y), (first, x))
            } else {
                ((first, x), (second, y))
            };
            for ((pa, pb), gap) in [far, near] {
                if gap.bound >= closest.distance {
                    front.push(BoundedPair {
                        ia: pa,
                        ib: pb,
                        gap,
                    });
                } else {
                    queue.push(pa, pb, gap.bound);
                }
            }
        }
        true
    }

    /// The direction of the best pair found, or before any, from A's centre to B's.
    fn best_direction(&self, closest: &Closest) -> Option<Direction> {
        match closest.pair {
            Some(_) => self.direction(&closest.on_a, &closest.on_b),
            None => self.direction(
                &self.a.bounding_centre,
                &(self.rotation * self.b.bounding_centre.coords + self.translation).into(),
            ),
        }
    }

    /// Measures the triangle pairs of two leaves that their projections (`triangles_gap`) do not
    /// already prove no closer than the best; returns a lower bound on the leaves' distance: the
    /// gap of all their triangles along the best pair's direction when it keeps them apart (a
    /// gap along one line, which a motion across it barely narrows), else the least of the
    /// measures and of the bounds that spared a measure.
    fn closest_in_leaves(
        &self,
        ia: u32,
        ib: u32,
        direction: Option<&Direction>,
        closest: &mut Closest,
        stats: &mut QueryStats,
    ) -> Gap {
        let (la, lb) = (&self.a.nodes[ia as usize], &self.b.nodes[ib as usize]);
        let mut least = f64::INFINITY;
        let u = direction.map(|d| &d.u);
        // The leaves' spans along `u`.
        let (mut span_a, mut span_b) = ((f64::MAX, f64::MIN), (f64::MAX, f64::MIN));
        let widen = |span: &mut (f64, f64), triangle: &BoundedTriangle| {
            if let Some((low, high)) = triangle.along_u() {
                *span = (span.0.min(low), span.1.max(high));
            }
        };
        // A gap beyond the coordinates' rounding proves two triangles apart.
        let apart = self.dop_rounding();
        let end_a = la.first + la.count;
        // A's triangles a chunk at a time, each bounded once for all of B's.
        for start in (la.first..end_a).step_by(LEAF_CHUNK) {
            let count = (end_a - start).min(LEAF_CHUNK as u32) as usize;
            let mut on_a = [BoundedTriangle::default(); LEAF_CHUNK];
            for (i, bounded) in on_a[..count].iter_mut().enumerate() {
                *bounded = BoundedTriangle::new(self.a.triangles[start as usize + i], u);
                widen(&mut span_a, bounded);
            }
            for tb in lb.first..lb.first + lb.count {
                let mut moved = BoundedTriangle::new(self.b_triangle_in_a(tb as usize), u);
                widen(&mut span_b, &moved);
                for (ta, triangle) in (start..).zip(&mut on_a[..count]) {
                    if closest.pair == Some([ta, tb]) {
                        // Measured already (the last query's closest pair, measured first): it
                        // is the best.
                        least = least.min(closest.distance);
                        continue;
                    }
                    let tie = closest.tie();
                    let gap = triangles_gap(triangle, &mut moved, tie);
                    if gap >= tie {
                        least = least.min(gap);
                        continue;
                    }
                    stats.tri_tests += 1;
                    let found = if gap > apart {
                        separated_triangle_distance(&triangle.corners, &moved.corners)
                    } else {
                        triangle_distance(&triangle.corners, &moved.corners)
                    };
                    least = least.min(found.distance);
                    closest.offer(found, [ta, tb]);
                    if closest.distance == 0.0 {
                        return Gap::anywhere(0.0);
                    }
                }
            }
        }
        let along_u = ranges_gap(span_a, span_b);
        match u {
            Some(u) if along_u >= closest.distance => Gap::along(along_u, *u),
            _ => Gap::anywhere(least),
        }
    }
}
