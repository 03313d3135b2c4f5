//! The grasping half of a frame: each grasping hand stepped against the parts at their visible
//! poses, on the hand's collision copy.

use nalgebra::{Isometry3, Vector3};

use super::frames::HandTarget;
use crate::grasping::collider::MAX_OBJECTS;
use crate::grasping::{
    GraspEvent, GraspingHand, HandInput, HandStep, Obstacle as HandObstacle, PartGeometry, PartId,
};
use crate::scene::Part;

/// One hand's outcome of a grasping step.
#[derive(Debug, Clone, PartialEq)]
pub struct SteppedHand {
    /// The hand's frame: visible hand, grasp, grasp and release events.
    pub frame: HandStep,
    /// The parts it let go of because the other hand grasped them (their release events are
    /// in the frame's).
    pub handed_over: Vec<PartId>,
}

/// The grasping half of a frame: the hands among the parts' collision copies.
pub struct GraspStage {
    hands: Vec<GraspingHand>,
    parts: Vec<PartGeometry>,
    poses: Vec<Isometry3<f64>>,
}

impl GraspStage {
    /// The `hands` among `parts` (a part's id is its index), which start at their configured
    /// poses.
    pub fn new(hands: Vec<GraspingHand>, parts: &[Part]) -> GraspStage {
        GraspStage {
            hands,
            parts: parts.iter().map(Part::grasp_geometry).collect(),
            poses: parts.iter().map(|part| part.pose).collect(),
        }
    }

    /// The grasping hands.
    pub fn hands(&self) -> &[GraspingHand] {
        &self.hands
    }

    /// Takes the visible part poses the hands are stepped against from now on (the sliding
    /// stage's, once verified); a list of the wrong length is ignored.
    pub fn set_part_poses(&mut self, poses: &[Isometry3<f64>]) {
        if poses.len() == self.poses.len() {
            self.poses.copy_from_slice(poses);
        }
    }

    /// Steps each hand towards its target (`targets` in the hands' order) against the parts
    /// within its reach, at their visible poses: a hand whose target says to let go (its tracking lost beyond the grace
    /// period) first releases what it holds, and a hand that grasps the part another holds takes
    /// it over.
    pub fn step(&mut self, targets: &[HandTarget]) -> Vec<SteppedHand> {
        let mut stepped: Vec<SteppedHand> = self
            .hands
            .iter_mut()
            .zip(targets)
            .map(|(hand, target)| {
                let released = target.let_go.then(|| hand.let_go()).flatten();
                let obstacles =
                    obstacles_within_reach(hand, &self.parts, &self.poses, &target.input);
                let mut frame = hand.step(&target.input, &obstacles);
                frame.events.splice(0..0, released);
                SteppedHand {
                    frame,
                    handed_over: Vec::new(),
                }
            })
            .collect();
        for taker in 0..stepped.len() {
            let grasped: Vec<PartId> = (stepped[taker].frame.events.iter())
                .filter_map(|event| match *event {
                    GraspEvent::Grasp { part, .. } => Some(part),
                    GraspEvent::Release { .. } => None,
                })
                .collect();
            for part in grasped {
                for giver in (0..self.hands.len()).filter(|&giver| giver != taker) {
                    if self.hands[giver]
                        .held()
                        .is_some_and(|held| held.part == part)
                        && let Some(release) = self.hands[giver].let_go()
                    {
                        let given = &mut stepped[giver];
                        given.frame.events.push(release);
                        given.frame.held = None;
                        given.handed_over.push(part);
                    }
                }
            }
        }
        stepped
    }
}

/// The parts the hand can touch in this step: those whose bounding sphere comes within the
/// hand's reach of the path of its root, from where it is seen to where the input puts it,
/// and the held part. A scene of a thousand parts gives the clasp the few near the hand;
/// should more than [`MAX_OBJECTS`] be near, the nearest are kept (the held part first).
fn obstacles_within_reach<'p>(
    hand: &GraspingHand,
    parts: &'p [PartGeometry],
    poses: &[Isometry3<f64>],
    input: &HandInput,
) -> Vec<HandObstacle<'p>> {
    let from = hand.visible().root.translation.vector;
    let to = (input.cart * input.tracker).translation.vector;
    let reach = hand.model().reach() + REACH_MARGIN;
    let held = hand.held().map(|held| held.part);
    let mut near: Vec<(f64, HandObstacle)> = (parts.iter().zip(poses).enumerate())
        .filter_map(|(id, (geometry, pose))| {
            let (centre, radius) = geometry.bound();
            let distance = distance_to_segment(&(pose * centre).coords, &from, &to);
            let id = id as PartId;
            let key = if held == Some(id) { -1.0 } else { distance };
            (held == Some(id) || distance <= reach + radius).then_some((
                key,
                HandObstacle {
                    part: id,
                    geometry,
                    pose: *pose,
                },
            ))
        })
        .collect();
    if near.len() > MAX_OBJECTS {
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        near.truncate(MAX_OBJECTS);
        near.sort_by_key(|(_, obstacle)| obstacle.part);
    }
    near.into_iter().map(|(_, obstacle)| obstacle).collect()
}

/// Added to the hand's reach when choosing the parts it may touch: covers the clasp's contact
/// probes, which reach a little beyond the segments.
const REACH_MARGIN: f64 = 0.05;

/// The distance from `point` to the segment from `a` to `b` (NaN when a coordinate is not
/// finite).
fn distance_to_segment(point: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let along = b - a;
    let length_squared = along.norm_squared();
    let t = if length_squared > 0.0 {
        ((point - a).dot(&along) / length_squared).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (point - (a + t * along)).norm()
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::collision::orientation::DEFAULT_K;
    use crate::geometry::shapes;
    use crate::grasping::model::tests::right_hand;
    use crate::grasping::{FLEX_COUNT, GraspParams, HandPose};
    use crate::scene::PartTree;

    fn part(name: &str, mesh: crate::geometry::TriMesh, pose: Isometry3<f64>) -> Part {
        Part {
            name: name.into(),
            mesh: Arc::new(mesh),
            mesh_source: format!("shape:{name}"),
            scale: 1.0,
            pose,
            movable: false,
            group: "default".into(),
            push: None,
            release: None,
            tree: PartTree::new(DEFAULT_K, None),
        }
    }

    #[test]
    fn the_hand_is_stepped_against_the_parts_within_its_reach_however_many_there_are() {
        let hand = GraspingHand::new(
            Arc::new(right_hand()),
            GraspParams::default(),
            HandPose {
                root: Isometry3::identity(),
                flex: [0.0; FLEX_COUNT],
            },
        )
        .expect("the right hand's segment meshes build");
        let reach = hand.model().reach();
        assert!((0.1..0.5).contains(&reach), "reach {reach} m");
        let cube = || shapes::cuboid(Vector3::repeat(0.01), 12);
        let at = |x: f64| Isometry3::translation(x, 0.0, 0.0);
        // A hundred cubes: every fourth within reach of the hand's path, the rest far off.
        let parts: Vec<Part> = (0..100)
            .map(|i| {
                let x = if i % 4 == 3 {
                    0.001 * i as f64
                } else {
                    10.0 + i as f64
                };
                part(&format!("cube {i}"), cube(), at(x))
            })
            .collect();
        let mut stage = GraspStage::new(vec![hand], &parts);
        let moving_to = |x: f64| HandInput {
            cart: Isometry3::identity(),
            tracker: at(x),
            flex: [0.0; FLEX_COUNT],
        };
        let ids = |stage: &GraspStage, input| -> Vec<PartId> {
            (obstacles_within_reach(&stage.hands[0], &stage.parts, &stage.poses, &input).iter())
                .map(|o| o.part)
                .collect()
        };
        let near: Vec<PartId> = (3..100).step_by(4).collect();
        assert_eq!(ids(&stage, moving_to(0.0)), near);
        // Every cube far off: none; every cube in reach, 2 mm apart: the nearest ones.
        stage.set_part_poses(&vec![at(100.0); 100]);
        assert!(ids(&stage, moving_to(0.0)).is_empty());
        let poses: Vec<_> = (0..100).map(|i| at(0.002 * i as f64)).collect();
        stage.set_part_poses(&poses);
        let nearest: Vec<PartId> = (0..MAX_OBJECTS as PartId).collect();
        assert_eq!(ids(&stage, moving_to(0.0)), nearest);
    }
}
