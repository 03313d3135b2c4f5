//! The bounding-box stage of a frame: the moved objects' boxes in the sweep and prune, the pairs
//! whose overlap ended, and the pairs of interest whose overlap started, tested by the back end.

use super::back_end::{BackEnd, Tally};
use super::interest::InterestMatrix;
use super::objects::Slot;
use super::{ExactTest, PairEntry, PairKey, is_interesting, ordered};
use crate::collision::broad_phase::{Aabb, SweepAndPrune};
use std::time::{Duration, Instant};

/// The bounding-box stage of a frame, with what it reads: the half of
/// [`CollisionPipeline::run_frame`](super::CollisionPipeline::run_frame) that runs beside the
/// back end's carried pairs.
pub(super) struct BoxStage<'a, C> {
    pub(super) broad_phase: &'a mut SweepAndPrune,
    pub(super) slots: &'a [Slot<C>],
    pub(super) queue: &'a [u32],
    pub(super) queued: &'a [bool],
    pub(super) interest: &'a InterestMatrix,
}

/// What the bounding-box stage changed, and the back end's results for the started pairs.
pub(super) struct BoxUpdate {
    /// Wall time of moving the boxes.
    pub(super) time: Duration,
    /// Pairs whose boxes overlap after the update and that involve a queued object.
    pub(super) overlapping: usize,
    /// Pairs whose overlap ended, sorted.
    pub(super) ended: Vec<PairKey>,
    /// The pairs of interest whose overlap started, tested.
    pub(super) started: Vec<PairEntry>,
    /// Time of the interest matrix on the started pairs.
    pub(super) interest_time: Duration,
    /// What the tests of the started pairs add up to.
    pub(super) started_tally: Tally,
}

impl<C: ExactTest> BoxStage<'_, C> {
    /// Moves the boxes of the queued objects to their objects' poses, then gathers the pairs
    /// whose overlap ended and tests those of interest whose overlap started: here rather than
    /// after the join, so that this work too runs beside the carried pairs instead of after them.
    pub(super) fn update(self, back_end: &BackEnd<'_, C>) -> BoxUpdate {
        let start = Instant::now();
        let updates: Vec<(u32, Aabb)> = self
            .queue
            .iter()
            .filter_map(|&index| {
                let object = self.slots[index as usize].object.as_ref()?;
                Some((
                    index,
                    Aabb::transformed(object.model.local_bounds(), &object.pose),
                ))
            })
            .collect();
        self.broad_phase.update_many(&updates);
        let time = start.elapsed();

        let overlapping = self
            .queue
            .iter()
            .map(|&index| {
                let overlaps = self.broad_phase.overlaps(index);
                overlaps
                    .iter()
                    .filter(|&&other| !self.queued[other as usize] || index < other)
                    .count()
            })
            .sum();
        let mut ended: Vec<PairKey> = self
            .broad_phase
            .drain_ended()
            .map(|[a, b]| ordered(a, b))
            .collect();
        ended.sort_unstable();
        let mut started: Vec<PairKey> = self
            .broad_phase
            .drain_started()
            .map(|[a, b]| ordered(a, b))
            .collect();
        // An overlap can start and end again within one update of several boxes.
        started.retain(|&(a, b)| self.broad_phase.overlaps(a).contains(&b));

        let interest_start = Instant::now();
        let mut started: Vec<PairEntry> = started
            .into_iter()
            .filter(|&pair| is_interesting(self.slots, self.interest, pair))
            .map(PairEntry::new)
            .collect();
        let interest_time = interest_start.elapsed();
        let started_tally = back_end.run(&mut started.iter_mut().collect::<Vec<_>>());
        BoxUpdate {
            time,
            overlapping,
            ended,
            started,
            interest_time,
            started_tally,
        }
    }
}
