//! The clearance watch: every watched part pair closer than the scene's threshold, frame after
//! frame, with its distance, closest points and triangles, and the moments a pair comes below the
//! threshold and is clear again.
//!
//! Which pairs: in `held` mode each grasped part against every other part, in `movable` mode each
//! movable part against every other part; only pairs the collision pipeline tests (the scene's
//! interest rules), and a pair stays watched while it is below, so that every
//! [`ClearanceKind::Below`] has its [`ClearanceKind::Restored`] even after the part is let go (a
//! peg released in its hole is still that close, and stays listed).
//!
//! Cost: a frame first culls pairs by the parts' bounding spheres in the world (a few flops a
//! part: a 1,000-part scene costs microseconds), then queries the DOP-trees of the pairs left with
//! [`DopTree::distance_below`](crate::collision::DopTree::distance_below), each pair keeping its
//! [`DistanceMemory`] from frame to frame so that a part moved a little costs a few triangle
//! tests. A pair whose two poses have not changed since its last query keeps that answer: it is
//! still exact, and parts at rest cost nothing.
//!
//! Hysteresis: a pair comes below at `d < threshold` and is restored only at `d ≥ threshold ×
//! (1 + `[`HYSTERESIS`]`)`. Tracked hands jitter by a tenth of a millimetre; without the band a
//! pair hovering at the threshold would flood the events at the loops' rate.
//!
//! Deadline: [`ClearanceStage::measure`] asks `go_on` before each pair after the first and stops
//! when it says no (the runtime says no once a newer frame waits). The pairs not measured keep
//! their last answer, reported stale, and are measured first on the next frame, so none starves.

use std::collections::HashMap;
use std::sync::Arc;

use nalgebra::{Isometry3, Point3};

use crate::collision::QueryStats;
use crate::collision::distance::{ClosestPoints, DistanceMemory};
use crate::grasping::PartId;
use crate::scene::{ClearanceParts, Scene};

/// How far beyond the threshold a pair below must get to be restored, as a fraction of the
/// threshold (see the module docs).
pub const HYSTERESIS: f64 = 0.1;

/// A pair's distance and closest points, in the world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClearanceReading {
    /// The part (the held one in `held` mode).
    pub part: PartId,
    /// The other part.
    pub other: PartId,
    /// Their distance, metres.
    pub distance: f64,
    /// The closest point on `part`.
    pub point: Point3<f64>,
    /// The closest point on `other`.
    pub other_point: Point3<f64>,
    /// The closest triangles, `[of part, of other]`, by index in each part's mesh.
    pub triangles: [u32; 2],
    /// Not measured on this frame's poses: the reading is an earlier frame's.
    pub stale: bool,
}

/// What a clearance event reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClearanceKind {
    /// The pair came closer than the threshold.
    Below,
    /// The pair is apart again by the threshold and its hysteresis.
    Restored,
}

/// A pair's change of state on a frame, with the reading that made it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClearanceEvent {
    /// Below or restored.
    pub kind: ClearanceKind,
    /// The measurement.
    pub reading: ClearanceReading,
}

/// One frame's clearance: the pairs below the threshold, closest first, and the changes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ClearanceOutcome {
    /// Every pair below, closest first (ties by ids); stale ones carry their last reading.
    pub below: Vec<ClearanceReading>,
    /// Pairs that came below or were restored on this frame, by their ids.
    pub events: Vec<ClearanceEvent>,
    /// Pairs queried on this frame (the rest of the pairs near enough to need it were reused or
    /// left stale).
    pub queried: usize,
    /// Pairs left stale by the deadline.
    pub stale: usize,
}

/// A watched pair's state.
struct PairState {
    /// The reading's orientation: `(part, other)`.
    ids: (PartId, PartId),
    memory: DistanceMemory,
    /// Below the threshold (until restored).
    below: bool,
    /// The last query: the poses it was made at, its bound, and what it found within it.
    last: Option<LastQuery>,
    /// The last query's reading, kept while below.
    reading: Option<ClearanceReading>,
    /// The last frame ([`ClearanceStage::frame`]) on which the pair was a candidate.
    seen: u64,
}

#[derive(Clone, Copy)]
struct LastQuery {
    poses: [Isometry3<f64>; 2],
    bound: f64,
    found: Option<ClosestPoints>,
}

impl LastQuery {
    /// This query's answer at `poses` under `bound`, if it gives it: the poses are the same and
    /// the answer is exact (a distance found is the distance, whatever the bound) or proves the
    /// pair at least `bound` apart.
    fn reuse(&self, poses: &[Isometry3<f64>; 2], bound: f64) -> Option<Option<ClosestPoints>> {
        if self.poses != *poses {
            return None;
        }
        match self.found {
            Some(found) => Some(Some(found).filter(|found| found.distance < bound)),
            None => (bound <= self.bound).then_some(None),
        }
    }
}

/// The clearance watch over one scene (see the module docs).
pub struct ClearanceStage {
    scene: Arc<Scene>,
    threshold: f64,
    parts: ClearanceParts,
    /// Each part's bounding sphere in its own frame (centre, radius), for the cull.
    spheres: Vec<(Point3<f64>, f64)>,
    /// Pairs being watched, keyed by their ids in order.
    pairs: HashMap<(PartId, PartId), PairState>,
    /// Pairs the last frame left unmeasured: measured first on the next.
    overdue: Vec<(PartId, PartId)>,
    /// Frames measured.
    frame: u64,
}

impl ClearanceStage {
    /// The watch of `scene`'s `[params.clearance]`; `None` when it has no threshold (off).
    pub fn new(scene: Arc<Scene>) -> Option<ClearanceStage> {
        let params = scene.params.clearance;
        let threshold = params.threshold?;
        let spheres = scene
            .parts
            .iter()
            .map(|part| part.mesh.bounding_sphere())
            .collect();
        Some(ClearanceStage {
            scene,
            threshold,
            parts: params.parts,
            spheres,
            pairs: HashMap::new(),
            overdue: Vec::new(),
            frame: 0,
        })
    }

    /// The threshold, metres.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// Measures the watched pairs at `poses` (every part's, by id) with `held` the grasped parts,
    /// asking `go_on` before each query after the first whether there is time for it.
    pub fn measure(
        &mut self,
        poses: &[Isometry3<f64>],
        held: &[PartId],
        mut go_on: impl FnMut() -> bool,
    ) -> ClearanceOutcome {
        let candidates = self.candidates(poses, held);
        let mut outcome = ClearanceOutcome::default();
        let mut stats = QueryStats::default();
        let mut overdue = Vec::new();
        for key in candidates {
            let state = self.pairs.get_mut(&key).expect("candidates are watched");
            let (a, b) = state.ids;
            let at = [poses[a as usize], poses[b as usize]];
            let bound = if state.below {
                f64::INFINITY
            } else {
                self.threshold
            };
            let found = match state.last.and_then(|last| last.reuse(&at, bound)) {
                Some(found) => found,
                _ if outcome.queried > 0 && !go_on() => {
                    overdue.push(key);
                    continue;
                }
                _ => {
                    outcome.queried += 1;
                    let tree_a = self.scene.parts[a as usize].tree();
                    let tree_b = self.scene.parts[b as usize].tree();
                    let b_to_a = at[0].inv_mul(&at[1]);
                    let found = (tree_a.distance_below(
                        tree_b,
                        &b_to_a,
                        bound,
                        &mut state.memory,
                        &mut stats,
                    ))
                    .filter(|closest| closest.distance.is_finite());
                    state.last = Some(LastQuery {
                        poses: at,
                        bound,
                        found,
                    });
                    found
                }
            };
            let reading = found.map(|closest| ClearanceReading {
                part: a,
                other: b,
                distance: closest.distance,
                point: at[0] * closest.on_a,
                other_point: at[1] * closest.on_b,
                triangles: closest.triangles,
                stale: false,
            });
            let restore_at = self.threshold * (1.0 + HYSTERESIS);
            let event = match (state.below, reading) {
                (false, Some(reading)) if reading.distance < self.threshold => {
                    Some((ClearanceKind::Below, reading))
                }
                (true, Some(reading)) if reading.distance >= restore_at => {
                    Some((ClearanceKind::Restored, reading))
                }
                _ => None,
            };
            if let Some((kind, reading)) = event {
                state.below = kind == ClearanceKind::Below;
                outcome.events.push(ClearanceEvent { kind, reading });
            }
            state.reading = reading.filter(|_| state.below);
        }
        outcome.stale = overdue.len();
        for key in &overdue {
            if let Some(reading) = self.pairs.get_mut(key).and_then(|s| s.reading.as_mut()) {
                reading.stale = true;
            }
        }
        self.overdue = overdue;
        // Pairs that are neither near nor below are forgotten, their memories with them.
        let frame = self.frame;
        self.pairs
            .retain(|_, state| state.below || state.seen == frame);
        outcome.below = (self.pairs.values())
            .filter(|state| state.below)
            .filter_map(|state| state.reading)
            .collect();
        outcome.below.sort_by(|x, y| {
            (x.distance.total_cmp(&y.distance)).then((x.part, x.other).cmp(&(y.part, y.other)))
        });
        outcome
            .events
            .sort_by_key(|event| (event.reading.part, event.reading.other));
        outcome
    }

    /// A frame with no time to measure at all (a newer one already waits): every pair below
    /// keeps its last reading, stale; no events.
    pub fn unmeasured(&mut self) -> ClearanceOutcome {
        let mut below: Vec<ClearanceReading> = (self.pairs.values_mut())
            .filter(|state| state.below)
            .filter_map(|state| state.reading.as_mut())
            .map(|reading| {
                reading.stale = true;
                *reading
            })
            .collect();
        below.sort_by(|x, y| {
            (x.distance.total_cmp(&y.distance)).then((x.part, x.other).cmp(&(y.part, y.other)))
        });
        ClearanceOutcome {
            stale: below.len(),
            below,
            ..ClearanceOutcome::default()
        }
    }

    /// The pairs to measure on this frame, overdue ones first, then by ids: the selected pairs
    /// whose bounding spheres are closer than their bound, and every pair below. Each gets a
    /// state.
    fn candidates(&mut self, poses: &[Isometry3<f64>], held: &[PartId]) -> Vec<(PartId, PartId)> {
        self.frame += 1;
        let frame = self.frame;
        let scene = &self.scene;
        let count = scene.parts.len().min(poses.len());
        let watched: Vec<usize> = match self.parts {
            ClearanceParts::Held => (held.iter().map(|&part| part as usize))
                .filter(|&part| part < count)
                .collect(),
            ClearanceParts::Movable => (0..count).filter(|&i| scene.parts[i].movable).collect(),
        };
        let centres: Vec<Point3<f64>> = (poses.iter().zip(&self.spheres))
            .map(|(pose, (centre, _))| pose * centre)
            .collect();
        let reach = self.threshold * (1.0 + HYSTERESIS);
        let mut keys: Vec<(PartId, PartId)> = Vec::new();
        for &part in &watched {
            for other in 0..count {
                let gap = (centres[part] - centres[other]).norm()
                    - self.spheres[part].1
                    - self.spheres[other].1;
                // The spheres first: the interest rules compare group names.
                if gap >= reach || !scene.pair_of_interest(part, other) {
                    continue;
                }
                let key = ordered(part as PartId, other as PartId);
                let state = (self.pairs.entry(key)).or_insert_with(|| PairState {
                    ids: (part as PartId, other as PartId),
                    memory: DistanceMemory::default(),
                    below: false,
                    last: None,
                    reading: None,
                    seen: frame,
                });
                state.seen = frame;
                keys.push(key);
            }
        }
        keys.extend(
            (self.pairs.iter())
                .filter(|(_, state)| state.below)
                .map(|(key, _)| *key),
        );
        keys.sort_unstable();
        keys.dedup();
        // Pairs whose parts are gone (poses of another scene) cannot be measured.
        keys.retain(|&(a, b)| (a.max(b) as usize) < count);
        let overdue = &self.overdue;
        keys.sort_by_key(|key| !overdue.contains(key));
        keys
    }
}

/// A pair's key: its ids in order.
fn ordered(a: PartId, b: PartId) -> (PartId, PartId) {
    (a.min(b), a.max(b))
}

#[cfg(test)]
mod tests;
