//! The DOP-tree's side of B11: one turn of its distance query over a pose sequence, timed per
//! query as B1 times its collision queries, with the pair's memory carried from pose to pose
//! (what a simulation keeps per pair of objects) or fresh at every query (cold).

use std::time::{Duration, Instant};

use nalgebra::Isometry3;
use vas_server::collision::distance::{ClosestPoints, DistanceMemory};
use vas_server::collision::{DopTree, QueryStats};

use super::compare::Answer;

/// What a query starts from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Memory {
    /// One `DistanceMemory` carried along the sequence.
    Carried,
    /// A fresh `DistanceMemory` at every query.
    Cold,
}

/// One turn of `a`'s distance query against `b` over `poses`: each pose's answer, its time in
/// nanoseconds (the clock's `overhead` subtracted), and the counters summed. The turn starts
/// with one untimed query at the last pose, the pose before the first on the tumbling path, as
/// B1's turns do.
pub fn run_turn(
    a: &DopTree,
    b: &DopTree,
    poses: &[Isometry3<f64>],
    memory: Memory,
    overhead: Duration,
) -> (Vec<Answer>, Vec<f64>, QueryStats) {
    let mut stats = QueryStats::default();
    let mut carried = DistanceMemory::default();
    if let Some(last) = poses.last() {
        std::hint::black_box(a.distance(b, last, &mut carried, &mut QueryStats::default()));
    }
    let mut found = Vec::with_capacity(poses.len());
    let mut nanoseconds = Vec::with_capacity(poses.len());
    for pose in poses {
        let mut fresh = DistanceMemory::default();
        let memory = match memory {
            Memory::Carried => &mut carried,
            Memory::Cold => &mut fresh,
        };
        let start = Instant::now();
        let closest = a.distance(b, pose, memory, &mut stats);
        let took = start.elapsed().saturating_sub(overhead);
        found.push(closest);
        nanoseconds.push(took.as_secs_f64() * 1e9);
    }
    let answers = found
        .iter()
        .zip(poses)
        .map(|(closest, pose)| answer(closest, pose))
        .collect();
    (answers, nanoseconds, stats)
}

/// A DOP-tree answer with both points in A's frame.
fn answer(closest: &ClosestPoints, pose: &Isometry3<f64>) -> Answer {
    let named = |t: u32| (t != u32::MAX).then_some(t);
    Answer {
        distance: closest.distance,
        on_a: closest.on_a,
        on_b: pose * closest.on_b,
        triangles: closest.triangles.map(named),
    }
}
