//! The traversal split across rayon's threads, for long queries where one pair dominates: from
//! the roots, down a few levels of node pairs into tasks ([`TreePair::parallel`]), or from a
//! remembered front, in chunks of its due pairs ([`TreePair::run_walk_parallel`]).

use std::sync::atomic::{AtomicBool, Ordering};

use super::realign::Realign;
use super::traverse::{Found, FrontPair, TreePair, Walk, dops_overlap};
use super::tree::DopTree;
use crate::collision::QueryStats;

/// Depth to which the parallel traversal splits the node-pair tree into rayon tasks (up to
/// 2^depth tasks). The split pays only for long traversals (all pairs of two meshes in deep
/// contact); on a short query the tasks' hand-over costs more than the work.
pub(super) const PARALLEL_DEPTH: u32 = 6;

/// A split query walks the remembered front in parallel only from this many due pairs: below,
/// handing the work to other threads costs more than it saves.
pub(super) const PARALLEL_MIN_STARTS: usize = 256;

/// Pairs a split walk of a remembered front tests on the calling thread before it splits: the
/// pairs of leaves that no plane separated come first, a query that finds contact usually finds
/// it among them, and then it never pays for the split.
pub(super) const SEQUENTIAL_PREFIX_STARTS: usize = 64;

/// Chunks per thread of a split walk: several, so that threads that finish early steal work.
const PARALLEL_CHUNKS_PER_THREAD: usize = 4;

/// Depth of the cut through the larger tree where a split query from the roots starts: up to
/// 2^depth pairs, enough for work stealing to balance two to eight threads.
const PARALLEL_CUT_DEPTH: u32 = 5;

/// The starts of a split query from the roots: the nodes of the larger tree at
/// [`PARALLEL_CUT_DEPTH`] (or leaves above it), each paired with the other tree's root. Like the
/// root pair, they cover every pair of leaves exactly once.
pub(super) fn top_starts(a: &DopTree, b: &DopTree) -> Vec<(u32, u32)> {
    let cut_a = a.nodes.len() >= b.nodes.len();
    let tree = if cut_a { a } else { b };
    let mut cut = vec![0u32];
    for _ in 0..PARALLEL_CUT_DEPTH {
        cut = cut
            .iter()
            .flat_map(|&node| {
                let n = tree.nodes[node as usize];
                if n.is_leaf() {
                    vec![node]
                } else {
                    vec![n.first, n.first + 1]
                }
            })
            .collect();
    }
    cut.into_iter()
        .map(|node| if cut_a { (node, 0) } else { (0, node) })
        .collect()
}

impl<R> TreePair<'_, R> {
    /// A first-hit traversal from `starts` that records its front in `front`: the first
    /// `sequential` starts on this thread, the rest split into chunks across rayon's threads.
    /// Without a hit, the front comes out complete, in the order of `starts`; a hit stops the
    /// other chunks, and the front they leave is incomplete (callers drop it).
    pub(super) fn run_walk_parallel<const K: usize>(
        &self,
        starts: &[(u32, u32)],
        sequential: usize,
        front: &mut Vec<FrontPair>,
        stats: &mut QueryStats,
    ) -> Option<[u32; 2]>
    where
        R: Realign<K>,
    {
        use rayon::prelude::*;
        let (prefix, starts) = starts.split_at(sequential.min(starts.len()));
        let walk = Walk {
            starts: prefix,
            stop: None,
            front: Some(front),
        };
        if let Some(hit) = self.run_walk::<K>(walk, stats) {
            return Some(hit);
        }
        let chunk = starts
            .len()
            .div_ceil(PARALLEL_CHUNKS_PER_THREAD * rayon::current_num_threads())
            .max(1);
        let stop = AtomicBool::new(false);
        let walks: Vec<(Option<[u32; 2]>, Vec<FrontPair>, QueryStats)> = starts
            .par_chunks(chunk)
            .map(|chunk| {
                let (mut ended, mut chunk_stats) = (Vec::new(), QueryStats::default());
                let walk = Walk {
                    starts: chunk,
                    stop: Some(&stop),
                    front: Some(&mut ended),
                };
                let hit = self.run_walk::<K>(walk, &mut chunk_stats);
                (hit, ended, chunk_stats)
            })
            .collect();
        stats.split_walks += 1;
        let mut hit = None;
        for (chunk_hit, ended, chunk_stats) in walks {
            hit = hit.or(chunk_hit);
            front.extend_from_slice(&ended);
            *stats += chunk_stats;
        }
        hit
    }

    /// Splits the traversal into rayon tasks down to `depth`, then traverses sequentially.
    pub(super) fn parallel<const ALL: bool, const K: usize>(
        &self,
        ia: u32,
        ib: u32,
        depth: u32,
        stop: &AtomicBool,
    ) -> Found
    where
        R: Realign<K>,
    {
        let mut found = Found::default();
        if stop.load(Ordering::Relaxed) {
            return found;
        }
        let (na, nb) = (&self.a.nodes[ia as usize], &self.b.nodes[ib as usize]);
        if depth == 0 || (na.is_leaf() && nb.is_leaf()) {
            found.hit = self.sequential::<ALL, K>(
                Walk {
                    stop: Some(stop),
                    ..Walk::from(&[(ia, ib)])
                },
                &mut found.stats,
                &mut found.pairs,
            );
            return found;
        }
        let mut e = [0f32; K];
        self.realigner.realign::<false>(self.b, ib as usize, &mut e);
        found.stats.realignments += 1;
        found.stats.bv_tests += 1;
        let da: &[f32; K] = self.a.node_offsets(ia as usize).try_into().unwrap();
        if !dops_overlap(da, &e) {
            return found;
        }
        found.stats.nodes_visited += 1;
        let [first, second] = self.children(ia, ib);
        let (x, y) = rayon::join(
            || self.parallel::<ALL, K>(first.0, first.1, depth - 1, stop),
            || self.parallel::<ALL, K>(second.0, second.1, depth - 1, stop),
        );
        found.stats += x.stats;
        found.stats += y.stats;
        found.hit = x.hit.or(y.hit);
        found.pairs = x.pairs;
        found.pairs.extend_from_slice(&y.pairs);
        found
    }
}
