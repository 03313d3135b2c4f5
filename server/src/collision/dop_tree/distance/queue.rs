//! The node pairs a distance walk has yet to open, nearest first.
//!
//! Why nearest first rather than depth first: a depth-first walk opens every pair whose bound is
//! below the best distance *when it gets there*, and the first leaves it reaches are often far
//! from the answer (long thin triangles make the first bounds loose), so it can measure tens of
//! thousands of triangle pairs a little farther than the answer before it finds the answer's
//! region. Nearest first opens only pairs whose bound is below the final distance, give or take
//! the last pairs it opens. Among overlapping pairs (bound at most 0, where the meshes may
//! touch) the last pushed comes first: a depth-first dive, which reaches a contact as soon as
//! the collision walk does, instead of opening every overlapping pair level by level.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::bounds::Gap;
use super::memory::BoundedPair;

/// A node pair to open: A's node, B's node and a lower bound on their distance.
#[derive(Debug, Clone, Copy)]
pub(super) struct Pending {
    pub(super) ia: u32,
    pub(super) ib: u32,
    pub(super) bound: f64,
    /// What the queue orders by, smallest first: the bits of the bound with every overlap
    /// counted as 0 (the bits of non-negative floats order as the floats do, and integers
    /// compare faster in the heap's sifts).
    key: u64,
    /// The pair's place in push order: later pairs first among overlapping ones.
    order: u32,
}

impl PartialEq for Pending {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Pending {}

impl PartialOrd for Pending {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Pending {
    /// Greater is opened sooner (the heap pops its greatest): the smaller key, then the later.
    fn cmp(&self, other: &Self) -> Ordering {
        other.key.cmp(&self.key).then(self.order.cmp(&other.order))
    }
}

/// The pairs waiting to be opened (see the module docs), and the pairs carried from the last
/// front whose bounds (an earlier pose's less the motion since) no longer keep them closed: each
/// is measured again at the new pose before the walk, and most, still apart, go straight back
/// to the front without passing through the heap. Kept in the pair's
/// [`DistanceMemory`](super::DistanceMemory) so that the buffers are reused from query to query.
#[derive(Debug, Clone, Default)]
pub(super) struct OpenQueue {
    heap: BinaryHeap<Pending>,
    pushed: u32,
    pub(super) carried: Vec<BoundedPair>,
}

impl OpenQueue {
    /// Empties the queue.
    pub(super) fn clear(&mut self) {
        self.heap.clear();
        self.pushed = 0;
        self.carried.clear();
    }

    /// Queues A's node `ia` and B's node `ib` at `bound`.
    pub(super) fn push(&mut self, ia: u32, ib: u32, bound: f64) {
        self.pushed = self.pushed.wrapping_add(1);
        self.heap.push(Pending {
            ia,
            ib,
            bound,
            key: if bound > 0.0 { bound.to_bits() } else { 0 },
            order: self.pushed,
        });
    }

    /// The pair to open next.
    pub(super) fn pop(&mut self) -> Option<Pending> {
        self.heap.pop()
    }

    /// Moves every pair waiting to `front`, with its bound, in no order.
    pub(super) fn drain_into(&mut self, front: &mut Vec<BoundedPair>) {
        front.extend(self.heap.drain().map(|p| BoundedPair {
            ia: p.ia,
            ib: p.ib,
            gap: Gap::anywhere(p.bound),
        }));
    }

    /// Pairs waiting in the heap.
    #[cfg(test)]
    fn len(&self) -> usize {
        self.heap.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_first_and_overlaps_last_pushed_first() {
        let mut queue = OpenQueue::default();
        for (i, bound) in [0.5, -0.2, 0.1, -0.4, 0.3, 0.0].into_iter().enumerate() {
            queue.push(i as u32, 0, bound);
        }
        assert_eq!(queue.len(), 6);
        let order: Vec<u32> = std::iter::from_fn(|| queue.pop()).map(|p| p.ia).collect();
        // The overlaps (bounds -0.2, -0.4, 0.0) last pushed first, then 0.1, 0.3, 0.5.
        assert_eq!(order, [5, 3, 1, 2, 4, 0]);
    }
}
