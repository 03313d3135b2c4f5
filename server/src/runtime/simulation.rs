//! The simulation state the runtime drives: a plain struct, no threads and no IPC.
//!
//! Validated inputs go in ([`Simulation::apply_tracker`], [`Simulation::apply_glove`]); frames
//! come out ([`Simulation::hand_frame`], [`Simulation::parts_frame`]). The grasping, sliding and
//! collision loops will own the parts of this state they advance; the I/O thread keeps handing
//! them the latest validated targets and publishing the frames they verify.

use nalgebra::Isometry3;
use vas_protocol::{
    FLEX_COUNT, GloveSample, GloveTarget, GraspType, HandFrame, InputRejection, InputStamp,
    InputStats, PartState, PartsFrameHeader, TrackerSample, TrackerTarget, WirePose,
};

use crate::scene::Scene;
use crate::sliding::Metaphor;

/// The scene, the valid part poses, the latest validated hand target and the input counters.
pub struct Simulation {
    scene: Scene,
    part_poses: Vec<Isometry3<f64>>,
    tracker: Option<TrackerTarget>,
    glove: Option<GloveTarget>,
    stats: InputStats,
    hand_frames: u64,
    parts_frames: u64,
}

impl Simulation {
    /// Starts with every part at its scene pose and no hand target.
    pub fn new(scene: Scene) -> Self {
        let part_poses = scene.parts.iter().map(|part| part.pose).collect();
        Self {
            scene,
            part_poses,
            tracker: None,
            glove: None,
            stats: InputStats::default(),
            hand_frames: 0,
            parts_frames: 0,
        }
    }

    /// The scene being simulated.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Input counters since the server started.
    pub fn stats(&self) -> InputStats {
        self.stats
    }

    /// Validates a tracker sample and, if valid, makes it the hand root target; counts it
    /// either way.
    pub fn apply_tracker(&mut self, sample: &TrackerSample) -> Result<(), InputRejection> {
        match sample.validate() {
            Ok(target) => {
                self.stats.tracker_accepted += 1;
                self.tracker = Some(target);
                Ok(())
            }
            Err(rejection) => {
                match rejection {
                    InputRejection::NonFinite { .. } => self.stats.tracker_rejected_non_finite += 1,
                    InputRejection::NotUnitQuaternion { .. } => {
                        self.stats.tracker_rejected_quaternion += 1;
                    }
                }
                Err(rejection)
            }
        }
    }

    /// Validates a glove sample and, if finite, makes its clamped flex values the finger target;
    /// counts it, and the values clamped, either way. Returns the bits of the clamped values.
    pub fn apply_glove(&mut self, sample: &GloveSample) -> Result<u32, InputRejection> {
        match sample.validate() {
            Ok(target) => {
                self.stats.glove_accepted += 1;
                if target.clamped != 0 {
                    self.stats.glove_samples_clamped += 1;
                    self.stats.glove_values_clamped += u64::from(target.clamped_count());
                }
                self.glove = Some(target);
                Ok(target.clamped)
            }
            Err(rejection) => {
                self.stats.glove_rejected_non_finite += 1;
                Err(rejection)
            }
        }
    }

    /// The next hand frame: the latest validated targets (the identity root and a flat hand
    /// before the first sample of a stream), stamped with the inputs it answers.
    pub fn hand_frame(&mut self, timestamp_ns: u64) -> HandFrame {
        self.hand_frames += 1;
        HandFrame {
            frame: self.hand_frames,
            tracker: self.tracker_stamp(),
            glove: self.glove_stamp(),
            timestamp_ns,
            root: self
                .tracker
                .map_or(WirePose::IDENTITY, |target| target.hand_in_world().into()),
            flex: self.glove.map_or([0.0; FLEX_COUNT], |target| target.flex),
            touching: 0,
            grasp_type: GraspType::None as u32,
        }
    }

    /// The next parts frame: header and the valid pose of every part, indexed by part id.
    pub fn parts_frame(&mut self, timestamp_ns: u64) -> (PartsFrameHeader, Vec<PartState>) {
        self.parts_frames += 1;
        let states: Vec<PartState> = self
            .part_poses
            .iter()
            .zip(0u32..)
            .map(|(pose, id)| {
                let pose = WirePose::from_isometry(pose);
                PartState {
                    id,
                    flags: 0,
                    position: pose.position,
                    rotation: pose.rotation,
                }
            })
            .collect();
        let header = PartsFrameHeader {
            frame: self.parts_frames,
            tracker: self.tracker_stamp(),
            glove: self.glove_stamp(),
            timestamp_ns,
            part_count: u32::try_from(states.len()).unwrap_or(u32::MAX),
        };
        (header, states)
    }

    /// Puts every part back to its scene pose and forgets the hand targets; counters and frame
    /// numbers go on.
    pub fn reset(&mut self) {
        self.part_poses = self.scene.parts.iter().map(|part| part.pose).collect();
        self.tracker = None;
        self.glove = None;
    }

    /// Selects how grasped parts follow the hand from now on.
    pub fn set_sliding_metaphor(&mut self, metaphor: Metaphor) {
        self.scene.params.sliding.metaphor = metaphor;
    }

    /// Replaces the scene and resets the state to it.
    pub fn replace_scene(&mut self, scene: Scene) {
        self.scene = scene;
        self.reset();
    }

    fn tracker_stamp(&self) -> InputStamp {
        self.tracker
            .map_or_else(InputStamp::default, |target| target.stamp)
    }

    fn glove_stamp(&self) -> InputStamp {
        self.glove
            .map_or_else(InputStamp::default, |target| target.stamp)
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use nalgebra::{Translation3, UnitQuaternion, Vector3};
    use vas_protocol::{FLEX_LIMITS_RAD, InputStamp};

    use super::*;

    fn scene(file: &str) -> Scene {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../configs")
            .join(file);
        Scene::load(&path).expect("the shipped scenes load")
    }

    fn tracker(seq: u64, hand: WirePose, cart: WirePose) -> TrackerSample {
        TrackerSample {
            seq,
            timestamp_ns: 1_000 + seq,
            hand,
            cart,
            sensor_id: 0,
        }
    }

    fn at(x: f64, y: f64, z: f64) -> WirePose {
        WirePose {
            position: [x, y, z],
            rotation: [0.0, 0.0, 0.0, 1.0],
        }
    }

    #[test]
    fn parts_frames_hold_the_scene_poses_in_id_order() {
        let scene = scene("default.toml");
        let expected: Vec<_> = scene.parts.iter().map(|part| part.pose).collect();
        let mut simulation = Simulation::new(scene);
        let (header, states) = simulation.parts_frame(77);
        assert_eq!(header.frame, 1);
        assert_eq!(header.timestamp_ns, 77);
        assert_eq!(header.part_count as usize, expected.len());
        assert_eq!(header.tracker, InputStamp::default());
        for ((state, pose), id) in states.iter().zip(&expected).zip(0u32..) {
            assert_eq!(state.id, id);
            assert_eq!(state.flags, 0);
            let back = state.pose().to_isometry();
            assert!((back.translation.vector - pose.translation.vector).norm() < 1e-12);
            assert!(back.rotation.angle_to(&pose.rotation) < 1e-9);
        }
        assert_eq!(simulation.parts_frame(78).0.frame, 2);
    }

    #[test]
    fn accepted_tracker_samples_set_the_hand_root_in_the_world() {
        let mut simulation = Simulation::new(scene("default.toml"));
        simulation
            .apply_tracker(&tracker(3, at(0.1, 0.0, 0.0), at(0.0, 0.0, 1.0)))
            .expect("valid");
        let frame = simulation.hand_frame(5);
        assert_eq!(frame.frame, 1);
        assert_eq!(
            frame.tracker,
            InputStamp {
                seq: 3,
                timestamp_ns: 1_003
            }
        );
        assert_eq!(frame.glove, InputStamp::default());
        assert_eq!(frame.root.position, [0.1, 0.0, 1.0]);
        assert_eq!(frame.flex, [0.0; FLEX_COUNT]);
        assert_eq!(simulation.parts_frame(6).0.tracker.seq, 3);
    }

    #[test]
    fn rejected_tracker_samples_are_counted_and_keep_the_previous_target() {
        let mut simulation = Simulation::new(scene("default.toml"));
        let turned = Translation3::new(0.0, 0.2, 0.0)
            * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.5);
        simulation
            .apply_tracker(&tracker(1, turned.into(), WirePose::IDENTITY))
            .expect("valid");
        let mut nan = tracker(2, at(0.0, 0.0, 0.0), WirePose::IDENTITY);
        nan.cart.position[2] = f64::NAN;
        assert!(simulation.apply_tracker(&nan).is_err());
        let mut stretched = tracker(3, at(0.0, 0.0, 0.0), WirePose::IDENTITY);
        stretched.hand.rotation = [0.0, 0.0, 0.0, 1.5];
        assert!(simulation.apply_tracker(&stretched).is_err());

        let stats = simulation.stats();
        assert_eq!(
            (
                stats.tracker_accepted,
                stats.tracker_rejected_non_finite,
                stats.tracker_rejected_quaternion
            ),
            (1, 1, 1)
        );
        let frame = simulation.hand_frame(9);
        assert_eq!(frame.tracker.seq, 1);
        let root = frame.root.to_isometry();
        assert!((root.translation.vector - turned.translation.vector).norm() < 1e-12);
        assert!(root.rotation.angle_to(&turned.rotation) < 1e-9);
    }

    #[test]
    fn glove_samples_are_clamped_and_counted() {
        let mut simulation = Simulation::new(scene("default.toml"));
        let mut flex = [0.1f32; FLEX_COUNT];
        flex[6] = 2.0;
        flex[20] = -3.0;
        let sample = GloveSample {
            seq: 4,
            timestamp_ns: 40,
            flex,
        };
        assert_eq!(simulation.apply_glove(&sample), Ok((1 << 6) | (1 << 20)));
        let mut broken = sample;
        broken.flex[0] = f32::NAN;
        assert!(simulation.apply_glove(&broken).is_err());
        let stats = simulation.stats();
        assert_eq!(stats.glove_accepted, 1);
        assert_eq!(stats.glove_rejected_non_finite, 1);
        assert_eq!(stats.glove_samples_clamped, 1);
        assert_eq!(stats.glove_values_clamped, 2);
        assert_eq!(stats.rejected(), 1);
        let frame = simulation.hand_frame(50);
        assert_eq!(
            frame.glove,
            InputStamp {
                seq: 4,
                timestamp_ns: 40
            }
        );
        assert_eq!(frame.flex[6], FLEX_LIMITS_RAD[6].1);
        assert_eq!(frame.flex[20], FLEX_LIMITS_RAD[20].0);
        assert_eq!(frame.flex[1], 0.1);
    }

    #[test]
    fn reset_forgets_the_hand_but_keeps_the_counters() {
        let mut simulation = Simulation::new(scene("default.toml"));
        simulation
            .apply_tracker(&tracker(8, at(1.0, 2.0, 3.0), WirePose::IDENTITY))
            .expect("valid");
        simulation.reset();
        let frame = simulation.hand_frame(1);
        assert_eq!(frame.tracker, InputStamp::default());
        assert_eq!(frame.root, WirePose::IDENTITY);
        assert_eq!(simulation.stats().tracker_accepted, 1);
    }

    #[test]
    fn replacing_the_scene_publishes_its_parts() {
        let mut simulation = Simulation::new(scene("default.toml"));
        let other = scene("peg_in_hole.toml");
        let count = other.parts.len();
        simulation.replace_scene(other);
        assert_eq!(simulation.parts_frame(1).1.len(), count);
        assert_eq!(simulation.scene().name, scene("peg_in_hole.toml").name);
    }
}
