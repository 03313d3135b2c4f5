//! Violent shoves of a held peg against its block: a power grasp on the peg, carried over the
//! block and lowered into its hole, then shoved again and again by random jumps of the hand (up
//! to [`MAX_SHIFT`] and [`MAX_TURN_DEGREES`], downwards or sideways, so into the block), each
//! followed by a return to the rest pose. Seeded: the same seed gives the same shoves.
//!
//! The sliding machine is stressed where it is slowest: every shove puts the ghost centimetres
//! deep into the block, and the visible peg must find its contacts from far away.

use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
use vas_server::scene::Part;

use super::{Keyframe, fist, power_grasp_at};

/// The largest jump of a shove, metres.
pub const MAX_SHIFT: f64 = 0.15;
/// The largest turn of a shove, degrees.
pub const MAX_TURN_DEGREES: f64 = 25.0;
/// How deep the peg's lower end rests in the hole between shoves (metres).
const REST_DEPTH: f64 = 0.02;
/// How far above the block's top the peg's lower end is carried (metres).
const CARRY_GAP: f64 = 0.02;
/// Seconds the hand takes to jump to a shove and back.
const JUMP: f64 = 0.02;
/// Seconds the hand holds a shove, and then the rest pose.
const HOLD: f64 = 0.03;
/// Seconds from one shove to the next.
pub const PERIOD: f64 = 2.0 * (JUMP + HOLD);

/// The seeded shoves of a held peg against its block.
#[derive(Debug, Clone, PartialEq)]
pub struct Shoves {
    /// The trajectory, to be sampled with [`sample`](super::sample).
    pub keys: Vec<Keyframe>,
    /// When the first shove starts (seconds): before it the peg is grasped and put in place.
    pub first_shove: f64,
    /// The peg's middle at rest, in the world: shoves turn the hand about it.
    pub centre: Vector3<f64>,
}

/// `count` shoves drawn from `seed` of `peg` (an upright cylinder along its z axis, as in the
/// peg insert scenes) in the hole of `block`.
pub fn shoves(peg: &Part, block: &Part, seed: u64, count: usize) -> Shoves {
    let up = Vector3::z();
    let (left, right) = extent(peg, &Vector3::x());
    let (peg_bottom, _) = extent(peg, &up);
    let (_, block_top) = extent(block, &up);
    let mut over = block.pose.translation.vector - peg.pose.translation.vector;
    over.z = 0.0;
    let lift = (block_top + CARRY_GAP - peg_bottom) * up;
    let lower = -(CARRY_GAP + REST_DEPTH) * up;

    let mut keys = power_grasp_at(&peg.pose, (right - left) / 2.0);
    for (duration, offset) in [(0.2, lift), (0.5, over), (0.3, lower)] {
        let mut key = hold(&keys, 0.05);
        key.time += duration;
        key.tracker = Translation3::from(offset) * key.tracker;
        keys.push(key);
    }
    keys.push(hold(&keys, 0.1));
    let rest = *keys.last().expect("the grasp has keyframes");
    let first_shove = rest.time;
    let centre = Translation3::from(peg.pose.translation.vector + lift + over + lower);

    let mut random = SplitMix64(seed);
    for _ in 0..count {
        let shove = centre * random.turn() * centre.inverse() * Translation3::from(random.shift());
        let start = keys.last().expect("keyframes so far").time;
        let at = |time: f64, tracker: Isometry3<f64>| Keyframe {
            time: start + time,
            cart: rest.cart,
            tracker,
            flex: fist(),
        };
        keys.push(at(JUMP, Isometry3::from(shove) * rest.tracker));
        keys.push(at(JUMP + HOLD, Isometry3::from(shove) * rest.tracker));
        keys.push(at(2.0 * JUMP + HOLD, rest.tracker));
        keys.push(at(PERIOD, rest.tracker));
    }
    Shoves {
        keys,
        first_shove,
        centre: centre.vector,
    }
}

/// The last keyframe held for `duration` more seconds, the fist closed.
fn hold(keys: &[Keyframe], duration: f64) -> Keyframe {
    let mut key = *keys.last().expect("a trajectory starts with a keyframe");
    key.time += duration;
    key.flex = fist();
    key
}

/// The lowest and highest value of the part's vertices along `axis` in the world.
fn extent(part: &Part, axis: &Vector3<f64>) -> (f64, f64) {
    part.mesh
        .vertices()
        .iter()
        .map(|v| (part.pose * v).coords.dot(axis))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        })
}

/// A small seeded generator (SplitMix64): the shoves need no more than uniform numbers.
struct SplitMix64(u64);

impl SplitMix64 {
    /// Uniform in [0, 1).
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A direction uniform on the unit sphere.
    fn direction(&mut self) -> Unit<Vector3<f64>> {
        let z = 2.0 * self.uniform() - 1.0;
        let phi = std::f64::consts::TAU * self.uniform();
        let r = (1.0 - z * z).max(0.0).sqrt();
        Unit::new_unchecked(Vector3::new(r * phi.cos(), r * phi.sin(), z))
    }

    /// A jump of up to [`MAX_SHIFT`], downwards or level: into the block.
    fn shift(&mut self) -> Vector3<f64> {
        let mut direction = self.direction().into_inner();
        direction.z = -direction.z.abs();
        direction * MAX_SHIFT * self.uniform()
    }

    /// A turn of up to [`MAX_TURN_DEGREES`] about a random axis.
    fn turn(&mut self) -> UnitQuaternion<f64> {
        let angle = MAX_TURN_DEGREES.to_radians() * self.uniform();
        UnitQuaternion::from_axis_angle(&self.direction(), angle)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::input_samples;
    use crate::offline;
    use nalgebra::Point3;
    use vas_client::recording::{RecordedSample, Recording, RecordingHeader};
    use vas_server::scene::Scene;

    fn scene() -> Scene {
        Scene::load(&crate::configs_dir().join("peg_insert.toml")).expect("the scene loads")
    }

    fn shoves_in(scene: &Scene, seed: u64, count: usize) -> Shoves {
        let part = |name| scene.parts.iter().find(|p| p.name == name).unwrap();
        shoves(part("peg"), part("block"), seed, count)
    }

    #[test]
    fn shoves_are_seeded_and_within_their_bounds() {
        let scene = scene();
        let a = shoves_in(&scene, 7, 40);
        assert_eq!(a, shoves_in(&scene, 7, 40));
        assert_ne!(a.keys, shoves_in(&scene, 8, 40).keys);
        let rest = *a.keys.iter().rfind(|k| k.time <= a.first_shove).unwrap();
        let centre = Point3::from(a.centre);
        let (mut shift, mut turn) = (0.0f64, 0.0f64);
        for key in a.keys.iter().filter(|k| k.time > a.first_shove) {
            let shove = key.tracker * rest.tracker.inverse();
            shift = shift.max((shove * centre - centre).norm());
            turn = turn.max(shove.rotation.angle().to_degrees());
        }
        assert!((0.8 * MAX_SHIFT..=MAX_SHIFT).contains(&shift), "{shift}");
        assert!(
            (0.8 * MAX_TURN_DEGREES..=MAX_TURN_DEGREES).contains(&turn),
            "{turn}"
        );
    }

    #[test]
    fn a_shoved_peg_is_held_and_never_penetrates_its_block() {
        let mut scene = scene();
        let shoves = shoves_in(&scene, 1, 6);
        let recording = Recording {
            header: RecordingHeader::new(scene.name.clone(), "shoves"),
            samples: input_samples(&shoves.keys)
                .into_iter()
                .map(|input| RecordedSample {
                    time: input.timestamp_ns() as f64 * 1e-9,
                    input,
                })
                .collect(),
        };
        // With contact approximation by bisection alone, and with conservative advancement.
        for advance in [false, true] {
            scene.params.sliding.conservative_advancement = advance;
            let run = offline::replay(&scene, &recording).expect("the recording replays");
            assert!(!run.events.is_empty(), "the peg was never grasped");
            assert!(run.penetrations.is_empty(), "{:?}", run.penetrations);
            // The block held the shoved peg back by centimetres.
            assert!(run.max_held_back > 0.01, "{}", run.max_held_back);
        }
    }
}
