//! The I/O thread's input state: validation and counters of tracker and glove samples, and the
//! latest accepted target of each, as the hand input of the next frame.

use nalgebra::Isometry3;
use vas_protocol::{
    FLEX_COUNT, GloveSample, GloveTarget, InputRejection, InputStamp, InputStats, TrackerSample,
    TrackerTarget,
};

use super::frames::{InputFrame, Stamps};
use crate::grasping::HandInput;

/// The latest validated targets and the input counters.
#[derive(Debug, Default)]
pub struct Inputs {
    tracker: Option<TrackerTarget>,
    glove: Option<GloveTarget>,
    stats: InputStats,
}

impl Inputs {
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
                    InputRejection::OutOfRange { .. } => {
                        self.stats.tracker_rejected_out_of_range += 1;
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

    /// The next frame's input: the latest targets (the identity cart and root and a flat hand
    /// before the first sample of a stream), stamped with the samples they come from.
    pub fn frame(&self) -> InputFrame {
        let (cart, tracker) = self
            .tracker
            .map_or((Isometry3::identity(), Isometry3::identity()), |target| {
                (target.cart, target.hand)
            });
        InputFrame {
            stamps: Stamps {
                tracker: self.tracker.map_or_else(InputStamp::default, |t| t.stamp),
                glove: self.glove.map_or_else(InputStamp::default, |g| g.stamp),
            },
            input: HandInput {
                cart,
                tracker,
                flex: self.glove.map_or([0.0; FLEX_COUNT], |target| target.flex),
            },
        }
    }

    /// Forgets the targets (a reset); the counters go on.
    pub fn forget_targets(&mut self) {
        self.tracker = None;
        self.glove = None;
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Translation3, UnitQuaternion, Vector3};
    use vas_protocol::{FLEX_LIMITS_RAD, WirePose};

    use super::*;

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
    fn accepted_tracker_samples_set_the_hand_root_in_the_world() {
        let mut inputs = Inputs::default();
        let before = inputs.frame();
        assert_eq!(before.stamps, Stamps::default());
        assert_eq!(
            before.input.cart * before.input.tracker,
            Isometry3::identity()
        );
        inputs
            .apply_tracker(&tracker(3, at(0.1, 0.0, 0.0), at(0.0, 0.0, 1.0)))
            .expect("valid");
        let frame = inputs.frame();
        assert_eq!(
            frame.stamps.tracker,
            InputStamp {
                seq: 3,
                timestamp_ns: 1_003
            }
        );
        assert_eq!(frame.stamps.glove, InputStamp::default());
        let root = frame.input.cart * frame.input.tracker;
        assert!((root.translation.vector - Vector3::new(0.1, 0.0, 1.0)).norm() < 1e-12);
        assert_eq!(frame.input.flex, [0.0; FLEX_COUNT]);
    }

    #[test]
    fn rejected_tracker_samples_are_counted_and_keep_the_previous_target() {
        let mut inputs = Inputs::default();
        let turned = Translation3::new(0.0, 0.2, 0.0)
            * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.5);
        inputs
            .apply_tracker(&tracker(1, turned.into(), WirePose::IDENTITY))
            .expect("valid");
        let mut nan = tracker(2, at(0.0, 0.0, 0.0), WirePose::IDENTITY);
        nan.cart.position[2] = f64::NAN;
        assert!(inputs.apply_tracker(&nan).is_err());
        let mut stretched = tracker(3, at(0.0, 0.0, 0.0), WirePose::IDENTITY);
        stretched.hand.rotation = [0.0, 0.0, 0.0, 1.5];
        assert!(inputs.apply_tracker(&stretched).is_err());

        let stats = inputs.stats();
        assert_eq!(
            (
                stats.tracker_accepted,
                stats.tracker_rejected_non_finite,
                stats.tracker_rejected_quaternion
            ),
            (1, 1, 1)
        );
        let frame = inputs.frame();
        assert_eq!(frame.stamps.tracker.seq, 1);
        let root = frame.input.cart * frame.input.tracker;
        assert!((root.translation.vector - turned.translation.vector).norm() < 1e-12);
        assert!(root.rotation.angle_to(&turned.rotation) < 1e-9);
    }

    #[test]
    fn positions_whose_combination_would_overflow_are_rejected_and_counted() {
        // Each coordinate finite, their sum infinite: the combined root was once published as
        // [null, null, null].
        let mut inputs = Inputs::default();
        inputs
            .apply_tracker(&tracker(1, at(0.1, 0.0, 1.0), WirePose::IDENTITY))
            .expect("valid");
        let far = tracker(2, at(1e308, 1e308, 1e308), at(1e308, 1e308, 1e308));
        assert!(matches!(
            inputs.apply_tracker(&far),
            Err(InputRejection::OutOfRange { value, .. }) if value == 1e308
        ));
        let stats = inputs.stats();
        assert_eq!(
            (stats.tracker_accepted, stats.tracker_rejected_out_of_range),
            (1, 1)
        );
        assert_eq!(stats.rejected(), 1);
        let root = inputs.frame().input.cart * inputs.frame().input.tracker;
        assert!(root.translation.vector.iter().all(|c| c.is_finite()));
        assert!((root.translation.vector - Vector3::new(0.1, 0.0, 1.0)).norm() < 1e-12);
    }

    #[test]
    fn glove_samples_are_clamped_and_counted() {
        let mut inputs = Inputs::default();
        let mut flex = [0.1f32; FLEX_COUNT];
        flex[6] = 2.0;
        flex[20] = -3.0;
        let sample = GloveSample {
            seq: 4,
            timestamp_ns: 40,
            flex,
        };
        assert_eq!(inputs.apply_glove(&sample), Ok((1 << 6) | (1 << 20)));
        let mut broken = sample;
        broken.flex[0] = f32::NAN;
        assert!(inputs.apply_glove(&broken).is_err());
        let stats = inputs.stats();
        assert_eq!(stats.glove_accepted, 1);
        assert_eq!(stats.glove_rejected_non_finite, 1);
        assert_eq!(stats.glove_samples_clamped, 1);
        assert_eq!(stats.glove_values_clamped, 2);
        assert_eq!(stats.rejected(), 1);
        let frame = inputs.frame();
        assert_eq!(
            frame.stamps.glove,
            InputStamp {
                seq: 4,
                timestamp_ns: 40
            }
        );
        assert_eq!(frame.input.flex[6], FLEX_LIMITS_RAD[6].1);
        assert_eq!(frame.input.flex[20], FLEX_LIMITS_RAD[20].0);
        assert_eq!(frame.input.flex[1], 0.1);
    }

    #[test]
    fn forgetting_the_targets_keeps_the_counters() {
        let mut inputs = Inputs::default();
        inputs
            .apply_tracker(&tracker(8, at(1.0, 2.0, 3.0), WirePose::IDENTITY))
            .expect("valid");
        inputs.forget_targets();
        let frame = inputs.frame();
        assert_eq!(frame.stamps, Stamps::default());
        assert_eq!(frame.input.tracker, Isometry3::identity());
        assert_eq!(inputs.stats().tracker_accepted, 1);
    }
}
