//! What a frame reports: the colliding pairs of the whole scene and the counters of each stage.

use super::back_end::Tally;
use super::box_stage::BoxUpdate;
use super::objects::ObjectId;
use crate::collision::QueryStats;
use std::time::Duration;

/// How much a frame should report about colliding pairs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Detail {
    /// Only which pairs collide (the exact test stops at the first intersecting triangle pair).
    Pairs,
    /// Also every intersecting triangle pair of each colliding pair.
    TrianglePairs,
}

/// Pairs taken in and let through by one stage in one frame, and the stage's wall time.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StageCounters {
    /// Pairs that reached the stage.
    pub pairs_in: u64,
    /// Pairs the stage passed on (for the exact test: the colliding ones).
    pub pairs_out: u64,
    /// Time spent in the stage: wall time for the broad phase and the interest matrix; for the
    /// separating-plane and exact stages, which share one parallel pass over the pairs, the sum
    /// of their per-pair times over all threads (their work, not their share of the frame).
    pub time: Duration,
}

/// The counters of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FrameStats {
    /// Objects in the front-end queue.
    pub moved: u64,
    /// Pairs involving a moved object → pairs whose boxes overlap.
    pub broad_phase: StageCounters,
    /// → pairs of interest.
    pub interest: StageCounters,
    /// → pairs no separating plane was found for.
    pub separating_plane: StageCounters,
    /// → colliding pairs.
    pub exact: StageCounters,
    /// Perceptron loops run by the pre-check.
    pub plane_loops: u64,
    /// Exact tests whose traversal was split across threads.
    pub split_tests: u64,
    /// Work counters of the exact tests.
    pub exact_work: QueryStats,
    /// Wall time of the whole frame.
    pub total: Duration,
}

/// A pair of objects whose meshes intersect.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CollidingPair {
    /// The object with the smaller id.
    pub a: ObjectId,
    /// The other object.
    pub b: ObjectId,
    /// `[triangle of a, triangle of b]` for each intersecting triangle pair; empty unless the
    /// frame asked for [`Detail::TrianglePairs`].
    pub triangles: Vec<[u32; 2]>,
}

/// What a frame found: every colliding pair of the scene, sorted, and the stage counters.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FrameReport {
    /// All pairs colliding after this frame, sorted by `(a, b)`.
    pub colliding: Vec<CollidingPair>,
    /// This frame's counters.
    pub stats: FrameStats,
}

impl FrameStats {
    /// The counters of a frame over `objects` objects of which `moved` were queued, from what its
    /// box stage changed and what its back end's tests add up to (the total time left at zero).
    pub(super) fn counted(moved: u64, objects: u64, update: &BoxUpdate, tally: &Tally) -> Self {
        let broad_phase = StageCounters {
            pairs_in: moved * (objects - moved) + moved * moved.saturating_sub(1) / 2,
            pairs_out: update.overlapping as u64,
            time: update.time,
        };
        FrameStats {
            moved,
            broad_phase,
            interest: StageCounters {
                pairs_in: broad_phase.pairs_out,
                pairs_out: tally.pairs,
                time: update.interest_time,
            },
            separating_plane: StageCounters {
                pairs_in: tally.pairs,
                pairs_out: tally.unseparated,
                time: tally.plane_time,
            },
            exact: StageCounters {
                pairs_in: tally.unseparated,
                pairs_out: tally.colliding,
                time: tally.exact_time,
            },
            plane_loops: tally.plane_loops,
            split_tests: tally.split_tests,
            exact_work: tally.exact_work,
            total: Duration::ZERO,
        }
    }
}
