//! The walk of a distance query: depth first over node pairs, nearer pairs first, each opened
//! only while its lower bound is below the best distance found; the leaves' triangle pairs
//! measured exactly.

use nalgebra::Point3;

use super::super::realign::{AffineRealign, RealignCache, Scratch, with_scratch};
use super::super::traverse::TreePair;
use super::bounds::{spheres_gap, triangle_sphere};
use crate::collision::QueryStats;
use crate::collision::distance::{TriangleDistance, triangle_distance};

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

    /// Walks from the root pair, improving `closest`; `stack` is scratch space.
    pub(super) fn walk_closest(
        &self,
        closest: &mut Closest,
        stack: &mut Vec<(u32, u32, f64)>,
        stats: &mut QueryStats,
    ) {
        with_scratch(|scratch| {
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                // SAFETY: the CPU supports AVX2 and FMA, checked just above.
                return unsafe { self.walk_avx2(scratch, closest, stack, stats) };
            }
            self.walk::<false>(scratch, closest, stack, stats)
        })
    }

    /// [`Self::walk`] compiled with AVX2 and FMA enabled (the re-alignment is vector code).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn walk_avx2(
        &self,
        scratch: &mut Scratch,
        closest: &mut Closest,
        stack: &mut Vec<(u32, u32, f64)>,
        stats: &mut QueryStats,
    ) {
        self.walk::<true>(scratch, closest, stack, stats)
    }

    #[inline(always)]
    fn walk<const FUSED: bool>(
        &self,
        scratch: &mut Scratch,
        closest: &mut Closest,
        stack: &mut Vec<(u32, u32, f64)>,
        stats: &mut QueryStats,
    ) {
        scratch.begin();
        let mut cache = RealignCache {
            stamp: scratch.stamp,
            tags: &mut scratch.tags,
            realigned: &mut scratch.realigned,
        };
        if let Some(bound) = self.lower_bound::<FUSED>(&mut cache, (0, 0), closest.distance, stats)
        {
            stack.push((0, 0, bound));
        }
        while let Some((ia, ib, bound)) = stack.pop() {
            // The best distance may have improved since the pair was pushed.
            if bound >= closest.distance {
                continue;
            }
            stats.nodes_visited += 1;
            let (na, nb) = (&self.a.nodes[ia as usize], &self.b.nodes[ib as usize]);
            if na.is_leaf() && nb.is_leaf() {
                self.closest_in_leaves(ia, ib, closest, stats);
                if closest.distance == 0.0 {
                    return;
                }
                continue;
            }
            let [first, second] = self.children(ia, ib);
            let bounds = [first, second]
                .map(|pair| self.lower_bound::<FUSED>(&mut cache, pair, closest.distance, stats));
            // Nearer pair on top of the stack: it is walked first and tightens the best soonest.
            let (near, far) = match bounds {
                [Some(x), Some(y)] if y < x => ((second, y), Some((first, x))),
                [Some(x), y] => ((first, x), y.map(|y| (second, y))),
                [None, Some(y)] => ((second, y), None),
                [None, None] => continue,
            };
            if let Some(((fa, fb), bound)) = far {
                stack.push((fa, fb, bound));
            }
            stack.push((near.0.0, near.0.1, near.1));
        }
    }

    /// Measures the triangle pairs of two leaves whose triangles' spheres do not already prove
    /// them no closer than the best.
    fn closest_in_leaves(&self, ia: u32, ib: u32, closest: &mut Closest, stats: &mut QueryStats) {
        let (la, lb) = (&self.a.nodes[ia as usize], &self.b.nodes[ib as usize]);
        for tb in lb.first..lb.first + lb.count {
            let moved = self.b_triangle_in_a(tb as usize);
            let sphere_b = triangle_sphere(&moved);
            for ta in la.first..la.first + la.count {
                let triangle = &self.a.triangles[ta as usize];
                if spheres_gap(&triangle_sphere(triangle), &sphere_b) >= closest.distance {
                    continue;
                }
                stats.tri_tests += 1;
                closest.offer(triangle_distance(triangle, &moved), [ta, tb]);
                if closest.distance == 0.0 {
                    return;
                }
            }
        }
    }
}
