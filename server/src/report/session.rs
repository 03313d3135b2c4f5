//! The per-pair accumulation of a session: each frame's distance, closest points, contact and
//! clash, folded into what the report says about the pair.

use nalgebra::Isometry3;

use super::clash::ClashJudge;
use super::{Interval, Moment, PairReport, Report, Status};
use crate::collision::QueryStats;
use crate::collision::distance::{ClosestPoints, DistanceMemory};
use crate::scene::Scene;

/// How far beyond the threshold a pair's distance is still measured (a multiple of the
/// threshold): the timeline figure shows the clearance up to there.
pub const CEILING: f64 = 2.0;

/// One measured pair and what it has shown so far.
struct PairState {
    a: usize,
    b: usize,
    contact_tolerance: f64,
    memory: DistanceMemory,
    /// The last relative pose measured (B in A's frame), its answer and whether it clashed.
    last: Option<(Isometry3<f64>, Option<ClosestPoints>, bool)>,
    minimum: Option<Moment>,
    frames_below: usize,
    seconds_below: f64,
    below: bool,
    contacts: Vec<Interval>,
    clash_frames: usize,
    first_clash: Option<usize>,
    timeline: Vec<(usize, Option<f64>)>,
}

impl PairState {
    /// The pair's distance at `poses` (A's and B's), if below `ceiling`: a bounding-sphere gap
    /// first, then the DOP-trees' distance query with the pair's memory.
    fn measure(
        &mut self,
        scene: &Scene,
        (pose_a, pose_b): (&Isometry3<f64>, &Isometry3<f64>),
        ceiling: f64,
        stats: &mut QueryStats,
    ) -> Option<ClosestPoints> {
        let (part_a, part_b) = (&scene.parts[self.a], &scene.parts[self.b]);
        let (centre_a, radius_a) = part_a.mesh.bounding_sphere();
        let (centre_b, radius_b) = part_b.mesh.bounding_sphere();
        let gap = (pose_a * centre_a - pose_b * centre_b).norm() - radius_a - radius_b;
        if gap >= ceiling {
            return None;
        }
        let b_to_a = pose_a.inverse() * pose_b;
        (part_a.tree()).distance_below(part_b.tree(), &b_to_a, ceiling, &mut self.memory, stats)
    }

    /// Keeps `closest` (at `poses`, the frame of `sample` at `time`) as the minimum if it is
    /// closer than the minimum so far.
    fn keep_if_closest(
        &mut self,
        closest: &ClosestPoints,
        (pose_a, pose_b): (&Isometry3<f64>, &Isometry3<f64>),
        sample: usize,
        time: f64,
    ) {
        if (self.minimum.as_ref()).is_some_and(|minimum| closest.distance >= minimum.clearance_m) {
            return;
        }
        let (on_a, on_b) = closest.in_world(pose_a, pose_b);
        self.minimum = Some(Moment {
            clearance_m: closest.distance,
            sample,
            time_s: time,
            point_a: on_a.coords.into(),
            point_b: on_b.coords.into(),
            triangles: closest.triangles,
        });
    }

    /// Opens a contact interval at `sample` when the pair touches (its `distance` within the
    /// contact tolerance) and closes the open one when it no longer does.
    fn track_contact(&mut self, distance: Option<f64>, sample: usize) {
        let touching = distance.is_some_and(|d| d <= self.contact_tolerance);
        match self.contacts.last_mut() {
            Some(open) if open.end.is_none() && !touching => open.end = Some(sample),
            Some(open) if open.end.is_none() => {}
            _ if touching => self.contacts.push(Interval {
                begin: sample,
                end: None,
            }),
            _ => {}
        }
    }
}

/// A session being measured, frame by frame.
pub struct Session<'s> {
    scene: &'s Scene,
    threshold: f64,
    judge: ClashJudge,
    pairs: Vec<PairState>,
    frames: usize,
    last_time: f64,
    stats: QueryStats,
}

impl<'s> Session<'s> {
    /// Measures the pairs of `scene`'s parts of interest to each other with at least one movable
    /// part, reporting those closer than `threshold` metres (finite and positive).
    pub fn new(scene: &'s Scene, threshold: f64) -> Session<'s> {
        let size = |id: usize| {
            let (min, max) = scene.parts[id].mesh.bounding_box();
            (max - min).norm()
        };
        let mut used = vec![false; scene.parts.len()];
        let mut pairs = Vec::new();
        for a in 0..scene.parts.len() {
            for b in a + 1..scene.parts.len() {
                let (part_a, part_b) = (&scene.parts[a], &scene.parts[b]);
                if !(part_a.movable || part_b.movable) || !scene.pair_of_interest(a, b) {
                    continue;
                }
                // The tolerance the simulation calls a contact by, for the part that moves.
                let moving_size = match (part_a.movable, part_b.movable) {
                    (true, true) => size(a).max(size(b)),
                    (true, false) => size(a),
                    _ => size(b),
                };
                used[a] = true;
                used[b] = true;
                pairs.push(PairState {
                    a,
                    b,
                    contact_tolerance: scene.params.sliding.tolerance_for(moving_size),
                    memory: DistanceMemory::default(),
                    last: None,
                    minimum: None,
                    frames_below: 0,
                    seconds_below: 0.0,
                    below: false,
                    contacts: Vec::new(),
                    clash_frames: 0,
                    first_clash: None,
                    timeline: Vec::new(),
                });
            }
        }
        Session {
            scene,
            threshold,
            judge: ClashJudge::new(scene, &used),
            pairs,
            frames: 0,
            last_time: 0.0,
            stats: QueryStats::default(),
        }
    }

    /// Pairs measured.
    pub fn pairs_measured(&self) -> usize {
        self.pairs.len()
    }

    /// Takes the frame of the recording's `sample` (at `time` seconds): every part's pose, by id.
    pub fn observe(&mut self, sample: usize, time: f64, poses: &[Isometry3<f64>]) {
        let ceiling = CEILING * self.threshold;
        let elapsed = time - self.last_time;
        for pair in &mut self.pairs {
            let (pose_a, pose_b) = (&poses[pair.a], &poses[pair.b]);
            let b_to_a = pose_a.inverse() * pose_b;
            let (closest, clash) = match pair.last {
                Some((last, closest, clash)) if last == b_to_a => (closest, clash),
                _ => {
                    let closest =
                        pair.measure(self.scene, (pose_a, pose_b), ceiling, &mut self.stats);
                    let clash = self.judge.clashes((pair.a, pose_a), (pair.b, pose_b));
                    pair.last = Some((b_to_a, closest, clash));
                    (closest, clash)
                }
            };
            if pair.below {
                pair.seconds_below += elapsed;
            }
            let distance = closest.map(|closest| closest.distance);
            pair.below = distance.is_some_and(|d| d < self.threshold);
            pair.frames_below += usize::from(pair.below);
            if let Some(closest) = closest {
                pair.keep_if_closest(&closest, (pose_a, pose_b), sample, time);
            }
            pair.track_contact(distance, sample);
            if clash {
                pair.clash_frames += 1;
                pair.first_clash.get_or_insert(sample);
            }
            if distance.is_some() || !pair.timeline.is_empty() {
                pair.timeline.push((sample, distance));
            }
        }
        self.frames += 1;
        self.last_time = time;
    }

    /// The report: `recording` names the recording, which had `samples` samples of which
    /// `rejected` were invalid.
    pub fn finish(self, recording: String, samples: usize, rejected: usize) -> Report {
        let scene = self.scene;
        let pairs_measured = self.pairs.len();
        let mut reported: Vec<PairReport> = (self.pairs.into_iter())
            .filter(|pair| pair.frames_below > 0 || pair.clash_frames > 0)
            .map(|pair| PairReport {
                a: scene.parts[pair.a].name.clone(),
                b: scene.parts[pair.b].name.clone(),
                status: if pair.clash_frames > 0 {
                    Status::Clash
                } else if !pair.contacts.is_empty() {
                    Status::Contact
                } else {
                    Status::Clearance
                },
                minimum: pair.minimum,
                frames_below: pair.frames_below,
                seconds_below: pair.seconds_below,
                contact_tolerance_m: pair.contact_tolerance,
                contacts: pair.contacts,
                clash_frames: pair.clash_frames,
                first_clash: pair.first_clash,
                timeline: pair.timeline,
            })
            .collect();
        let clearance = |pair: &PairReport| pair.minimum.as_ref().map_or(0.0, |m| m.clearance_m);
        reported
            .sort_by(|x, y| (x.status.cmp(&y.status)).then(clearance(x).total_cmp(&clearance(y))));
        Report {
            scene: scene.name.clone(),
            recording,
            samples,
            frames: self.frames,
            rejected,
            threshold_m: self.threshold,
            pairs_measured,
            pairs: reported,
        }
    }
}

#[cfg(test)]
mod tests;
