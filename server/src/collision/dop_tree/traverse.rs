//! The simultaneous depth-first traversal of two trees ([`TreePair`]).
//!
//! B's nodes are re-aligned lazily, once per query (a small direct-mapped cache), leaves exactly
//! from their corners; children pairs are tested when generated and the deeper overlap is visited
//! first; pairs that A's axes barely fail to separate are also tested along B's axes (A's node
//! re-aligned into B's frame). Near the leaves, the face-plane and box tests of `separation` end
//! the walk higher up than the DOPs alone would.
//!
//! The traversal is compiled twice, portable and with AVX2/FMA, chosen at run time.

use std::sync::atomic::{AtomicBool, Ordering};

use nalgebra::{Isometry3, Matrix3, Point3, Vector3};

use super::parallel::PARALLEL_DEPTH;
use super::realign::{Realign, RealignCache, Scratch, with_scratch};
use super::separation::{BOX_TEST_MAX_TRIANGLES, Ending, Extent, PLAIN_BOX_TEST_MAX_TRIANGLES};
use super::tree::{DopTree, Node};
use crate::collision::QueryStats;
use crate::collision::triangle::{Triangle, triangles_intersect};

/// One query between two DOP-trees: B's pose in A's frame and the re-alignment method.
pub struct TreePair<'a, R> {
    pub(super) a: &'a DopTree,
    pub(super) b: &'a DopTree,
    pub(super) rotation: Matrix3<f64>,
    pub(super) translation: Vector3<f64>,
    pub(super) realigner: R,
}

/// Where a sequential traversal starts and what it records besides its answer.
pub(super) struct Walk<'w> {
    /// Node pairs to test first (the root pair for a whole query).
    pub(super) starts: &'w [(u32, u32)],
    /// Set by the first task of a parallel query that finds a hit; stops the others.
    pub(super) stop: Option<&'w AtomicBool>,
    /// Receives every node pair at which the traversal ended without a hit, with its slack: a
    /// complete traversal's front covers every pair of leaves exactly once.
    pub(super) front: Option<&'w mut Vec<FrontPair>>,
}

impl<'w> Walk<'w> {
    /// A traversal from `starts` that records nothing.
    pub(super) fn from(starts: &'w [(u32, u32)]) -> Self {
        Walk {
            starts,
            stop: None,
            front: None,
        }
    }
}

/// A node pair at which a traversal ended, and how.
#[derive(Debug, Clone, Copy)]
pub(super) struct FrontPair {
    pub(super) pair: (u32, u32),
    pub(super) ending: Ending,
}

/// The axis-aligned box of a triangle's corners.
struct CornerBox {
    lo: [f64; 3],
    hi: [f64; 3],
}

impl CornerBox {
    fn of(triangle: &Triangle) -> Self {
        let [p, q, r] = triangle;
        CornerBox {
            lo: std::array::from_fn(|i| p[i].min(q[i]).min(r[i])),
            hi: std::array::from_fn(|i| p[i].max(q[i]).max(r[i])),
        }
    }

    /// Whether the box of `triangle`'s corners is disjoint from this one (touching is not).
    fn misses(&self, triangle: &Triangle) -> bool {
        let [p, q, r] = triangle;
        (0..3)
            .any(|i| p[i].max(q[i]).max(r[i]) < self.lo[i] || p[i].min(q[i]).min(r[i]) > self.hi[i])
    }
}

/// How deeply two nodes' DOPs overlap along their tightest axis: negative when they are
/// disjoint, and then the subtrees' triangles are at least `-value` apart along that axis.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Slack {
    pub(super) value: f32,
    /// The axis is one of B's (A's node re-aligned into B's frame), not one of A's.
    pub(super) along_b: bool,
}

/// What a traversal found.
#[derive(Default)]
pub(super) struct Found {
    pub(super) stats: QueryStats,
    pub(super) pairs: Vec<[u32; 2]>,
    /// The first pair of leaves found with intersecting triangles (node indices of A and B).
    pub(super) hit: Option<[u32; 2]>,
}

impl<'a, R> TreePair<'a, R> {
    /// Prepares a query of `b` posed at `b_to_a` in `a`'s frame; `realigner` is made from the
    /// rotation and translation.
    pub fn new(
        a: &'a DopTree,
        b: &'a DopTree,
        b_to_a: &Isometry3<f64>,
        realigner: impl FnOnce(&Matrix3<f64>, &Vector3<f64>) -> R,
    ) -> Self {
        let rotation = *b_to_a.rotation.to_rotation_matrix().matrix();
        let translation = b_to_a.translation.vector;
        let realigner = realigner(&rotation, &translation);
        TreePair {
            a,
            b,
            rotation,
            translation,
            realigner,
        }
    }

    /// B's leaf triangle `index` (leaf order) moved into A's frame.
    pub(super) fn b_triangle_in_a(&self, index: usize) -> Triangle {
        self.b.triangles[index].map(|p| Point3::from(self.rotation * p.coords + self.translation))
    }

    /// Tests every triangle pair of two leaves whose corners' boxes overlap; records pairs when
    /// `ALL`, else stops at a hit.
    fn leaf_pair<const ALL: bool>(
        &self,
        leaf_a: &Node,
        leaf_b: &Node,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
    ) -> bool {
        let mut hit = false;
        let range_a = leaf_a.first as usize..(leaf_a.first + leaf_a.count) as usize;
        for ib in leaf_b.first as usize..(leaf_b.first + leaf_b.count) as usize {
            let tb = self.b_triangle_in_a(ib);
            let box_b = CornerBox::of(&tb);
            for ia in range_a.clone() {
                // The boxes of the two triangles' corners first: as exact as the triangle test
                // (the same corners), and a fraction of its cost.
                if box_b.misses(&self.a.triangles[ia]) {
                    continue;
                }
                stats.tri_tests += 1;
                if triangles_intersect(&self.a.triangles[ia], &tb) {
                    hit = true;
                    if !ALL {
                        return true;
                    }
                    out.push([self.a.triangle_ids[ia], self.b.triangle_ids[ib]]);
                }
            }
        }
        hit
    }

    /// The two node pairs to visit after `(ia, ib)` overlapped: the larger node is split.
    pub(super) fn children(&self, ia: u32, ib: u32) -> [(u32, u32); 2] {
        let (na, nb) = (self.a.nodes[ia as usize], self.b.nodes[ib as usize]);
        let split_a = !na.is_leaf() && (nb.is_leaf() || na.size >= nb.size);
        if split_a {
            [(na.first, ib), (na.first + 1, ib)]
        } else {
            [(ia, nb.first), (ia, nb.first + 1)]
        }
    }
}

impl<R> TreePair<'_, R> {
    /// Runs the query from the root pair, sequentially or split across threads. Returns the
    /// first pair of leaves found with intersecting triangles (node indices of A and B), if any.
    pub fn run<const ALL: bool, const K: usize>(
        &self,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
        parallel: bool,
    ) -> Option<[u32; 2]>
    where
        R: Realign<K>,
    {
        let found = if parallel {
            let stop = AtomicBool::new(false);
            self.parallel::<ALL, K>(0, 0, PARALLEL_DEPTH, &stop)
        } else {
            let mut found = Found::default();
            found.hit = self.sequential::<ALL, K>(
                Walk::from(&[(0, 0)]),
                &mut found.stats,
                &mut found.pairs,
            );
            found
        };
        *stats += found.stats;
        out.extend_from_slice(&found.pairs);
        found.hit
    }

    /// A first-hit traversal as `walk` says; returns the pair of leaves found with intersecting
    /// triangles, if any.
    pub(super) fn run_walk<const K: usize>(
        &self,
        walk: Walk<'_>,
        stats: &mut QueryStats,
    ) -> Option<[u32; 2]>
    where
        R: Realign<K>,
    {
        self.sequential::<false, K>(walk, stats, &mut Vec::new())
    }

    /// Depth-first traversal from one node pair with this thread's re-alignment cache, compiled
    /// for AVX2 and FMA where the CPU has them (the interval tests and re-alignments are vector
    /// code).
    pub(super) fn sequential<const ALL: bool, const K: usize>(
        &self,
        walk: Walk<'_>,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
    ) -> Option<[u32; 2]>
    where
        R: Realign<K>,
    {
        with_scratch(|scratch| {
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                // SAFETY: the CPU supports AVX2 and FMA, checked just above.
                return unsafe { self.traverse_avx2::<ALL, K>(scratch, walk, stats, out) };
            }
            self.traverse::<ALL, K, false>(scratch, walk, stats, out)
        })
    }

    /// [`Self::traverse`] compiled with AVX2 and FMA enabled.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn traverse_avx2<const ALL: bool, const K: usize>(
        &self,
        scratch: &mut Scratch,
        walk: Walk<'_>,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
    ) -> Option<[u32; 2]>
    where
        R: Realign<K>,
    {
        self.traverse::<ALL, K, true>(scratch, walk, stats, out)
    }

    /// The traversal itself: a stack of node pairs, B's nodes re-aligned once per query.
    #[inline(always)]
    fn traverse<const ALL: bool, const K: usize, const FUSED: bool>(
        &self,
        scratch: &mut Scratch,
        walk: Walk<'_>,
        stats: &mut QueryStats,
        out: &mut Vec<[u32; 2]>,
    ) -> Option<[u32; 2]>
    where
        R: Realign<K>,
    {
        scratch.begin();
        let stamp = scratch.stamp;
        let Scratch {
            tags,
            realigned,
            reverse_tags,
            reverse_realigned,
            stack,
            ..
        } = scratch;
        let mut cache = RealignCache {
            stamp,
            tags,
            realigned,
        };
        let mut reverse_cache = RealignCache {
            stamp,
            tags: reverse_tags,
            realigned: reverse_realigned,
        };
        let Walk {
            starts,
            stop,
            mut front,
        } = walk;
        let box_max_triangles = if front.is_some() {
            BOX_TEST_MAX_TRIANGLES
        } else {
            PLAIN_BOX_TEST_MAX_TRIANGLES
        };
        let mut hit = None;
        // Each start is explored to the end before the next one, so a first hit leaves the
        // later starts untested. The stack holds node pairs already known to overlap. Children
        // pairs are tested when generated and the one overlapping more deeply is visited first:
        // a first hit is found sooner.
        'starts: for (index, &start) in starts.iter().enumerate() {
            let slack = self.slack::<K, FUSED>(&mut cache, &mut reverse_cache, start, stats);
            if slack.value < 0.0 {
                let front = front.as_deref_mut();
                self.record_separation::<K, FUSED>(
                    front,
                    &mut cache,
                    &mut reverse_cache,
                    start,
                    slack,
                );
                continue;
            }
            stack.push(start);
            while let Some((ia, ib)) = stack.pop() {
                if let Some(stop) = stop
                    && stop.load(Ordering::Relaxed)
                {
                    break 'starts;
                }
                stats.nodes_visited += 1;
                let (na, nb) = (&self.a.nodes[ia as usize], &self.b.nodes[ib as usize]);
                if na.is_leaf() && nb.is_leaf() {
                    let found = self.leaf_pair::<ALL>(na, nb, stats, out);
                    if let Some(front) = front.as_deref_mut() {
                        let ending = if found {
                            Ending::Retest
                        } else {
                            self.face_separation(ia, ib, Extent::Exact)
                        };
                        front.push(FrontPair {
                            pair: (ia, ib),
                            ending,
                        });
                        if found && !ALL {
                            // Every pair left unexplored is tested again next time: the front
                            // then still covers every pair of leaves.
                            let unexplored = stack.iter().chain(&starts[index + 1..]);
                            front.extend(unexplored.map(|&pair| FrontPair {
                                pair,
                                ending: Ending::Retest,
                            }));
                        }
                    }
                    if found {
                        hit = hit.or(Some([ia, ib]));
                        if !ALL {
                            if let Some(stop) = stop {
                                stop.store(true, Ordering::Relaxed);
                            }
                            break 'starts;
                        }
                    }
                    continue;
                }
                // A subtree against one triangle: the triangle's plane often separates them
                // where their DOPs overlap, and it stays a valid certificate along motion in
                // that plane (a peg sliding down its hole's wall), where the DOP axis that would
                // separate their descendants is often the direction of motion. Against a large
                // triangle at a slant it is what ends the descent at all: the triangle's
                // re-aligned DOP is as wide as the triangle along every axis, and would overlap
                // most of the other tree's nodes (a table top under a fine part).
                if let Some(extent) = self.plane_test_extent(na, nb, ia, ib) {
                    stats.bv_tests += 1;
                    let ending = self.face_separation(ia, ib, extent);
                    if let Ending::Separated { .. } = ending {
                        if let Some(front) = front.as_deref_mut() {
                            front.push(FrontPair {
                                pair: (ia, ib),
                                ending,
                            });
                        }
                        continue;
                    }
                }
                let [first, second] = self.children(ia, ib);
                let first_slack =
                    self.slack::<K, FUSED>(&mut cache, &mut reverse_cache, first, stats);
                let second_slack =
                    self.slack::<K, FUSED>(&mut cache, &mut reverse_cache, second, stats);
                // Relative depth: overlap over the size of the pair's smaller node.
                let relative = |(ia, ib): (u32, u32), slack: f32| {
                    let size = self.a.nodes[ia as usize]
                        .size
                        .min(self.b.nodes[ib as usize].size);
                    slack / size.max(f32::MIN_POSITIVE)
                };
                let (deeper, shallower) =
                    if relative(first, first_slack.value) >= relative(second, second_slack.value) {
                        ((first, first_slack), (second, second_slack))
                    } else {
                        ((second, second_slack), (first, first_slack))
                    };
                for (pair, slack) in [shallower, deeper] {
                    if slack.value >= 0.0 {
                        if let Some(ending) = self.box_separation(pair, box_max_triangles, stats) {
                            if let Some(front) = front.as_deref_mut() {
                                front.push(FrontPair { pair, ending });
                            }
                        } else {
                            stack.push(pair);
                        }
                    } else {
                        let front = front.as_deref_mut();
                        self.record_separation::<K, FUSED>(
                            front,
                            &mut cache,
                            &mut reverse_cache,
                            pair,
                            slack,
                        );
                    }
                }
            }
        }
        stack.clear();
        hit
    }

    /// The overlap slack of a node pair: the least `a_i + e_i` over the axes, negative exactly
    /// when some axis separates them (and then minus a lower bound on their distance). B's node
    /// is re-aligned unless cached for this query; when the method tests both ways and A's axes
    /// do not separate, A's node re-aligned into B's frame is tested against B's axes too.
    #[inline(always)]
    fn slack<const K: usize, const FUSED: bool>(
        &self,
        cache: &mut RealignCache<'_>,
        reverse_cache: &mut RealignCache<'_>,
        (ia, ib): (u32, u32),
        stats: &mut QueryStats,
    ) -> Slack
    where
        R: Realign<K>,
    {
        let forward = |value| Slack {
            value,
            along_b: false,
        };
        let da: &[f32; K] = self.a.node_offsets(ia as usize).try_into().unwrap();
        let e = cache.get::<K, FUSED, R>(&self.realigner, self.b, ib, stats);
        stats.bv_tests += 1;
        let along_a = overlap_slack(da, e);
        // Only pairs that A's axes barely fail to separate are worth B's axes: deep overlaps
        // are rarely separated by them.
        let (na, nb) = (&self.a.nodes[ia as usize], &self.b.nodes[ib as usize]);
        if along_a < 0.0 || along_a > REVERSE_TEST_SLACK * (na.size + nb.size) {
            return forward(along_a);
        }
        let Some(reverse) = self.realigner.reverse(self.a, self.b) else {
            return forward(along_a);
        };
        let db: &[f32; K] = self.b.node_offsets(ib as usize).try_into().unwrap();
        let e = reverse_cache.get::<K, FUSED, R>(reverse, self.a, ia, stats);
        stats.bv_tests += 1;
        let along_b = overlap_slack(db, e);
        if along_b < along_a {
            Slack {
                value: along_b,
                along_b: true,
            }
        } else {
            forward(along_a)
        }
    }
}

/// True when A's node offsets `a` and B's re-aligned opposite offsets `e` overlap on every axis.
#[inline(always)]
pub(super) fn dops_overlap<const K: usize>(a: &[f32; K], e: &[f32; K]) -> bool {
    overlap_slack(a, e) >= 0.0
}

/// The least `a_i + e_i`: how deeply the DOPs overlap along their tightest axis (negative when
/// they are disjoint).
#[inline(always)]
pub(super) fn overlap_slack<const K: usize>(a: &[f32; K], e: &[f32; K]) -> f32 {
    let mut least = f32::INFINITY;
    for i in 0..K {
        let s = a[i] + e[i];
        least = if s < least { s } else { least };
    }
    least
}

/// Fraction of the two nodes' sizes below which an overlap along A's axes is checked along B's.
const REVERSE_TEST_SLACK: f32 = 0.05;
