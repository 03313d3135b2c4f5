//! What a pair's distance queries carry from one to the next.

use super::super::tree::DopTree;

/// What the last distance query between two objects found: keep one per pair of objects (it is
/// `Send`, and cheap when empty) and pass it to every query of that pair. At a nearby pose, the
/// last closest triangles are still (nearly) the closest, so their distance is an upper bound
/// that prunes almost the whole walk; after a jump they cost one triangle test more than a cold
/// query. A memory used with other trees than its last ones is ignored, so a mix-up costs speed,
/// never a wrong answer.
#[derive(Debug, Clone, Default)]
pub struct DistanceMemory {
    /// The two trees' ids and the closest triangles' positions in leaf order.
    last: Option<((u64, u64), [u32; 2])>,
    /// The walk's stack, reused: node pairs with their lower bounds.
    stack: Vec<(u32, u32, f64)>,
}

impl DistanceMemory {
    /// The closest triangles (leaf order) the last query of `a` and `b` found.
    pub(super) fn last_pair(&self, a: &DopTree, b: &DopTree) -> Option<[u32; 2]> {
        self.last
            .filter(|(ids, _)| *ids == (a.id, b.id))
            .map(|(_, pair)| pair)
    }

    /// Remembers the closest triangles of `a` and `b` (leaf order).
    pub(super) fn remember(&mut self, a: &DopTree, b: &DopTree, pair: [u32; 2]) {
        self.last = Some(((a.id, b.id), pair));
    }

    /// The walk's stack, emptied.
    pub(super) fn stack(&mut self) -> &mut Vec<(u32, u32, f64)> {
        self.stack.clear();
        &mut self.stack
    }
}
