//! A headset's tracked hands, as a page in a WebXR session sends them: one binary message per
//! hand per XR frame, read here and turned into the server's [`HandJointsSample`].
//!
//! The message is binary, little-endian, [`MESSAGE_BYTES`] long (the page writes it into one
//! `ArrayBuffer` without building any string, and the viewer reads it without a JSON parser: at
//! two hands and 72 to 120 frames a second, that is what stays cheap on both ends):
//!
//! ```text
//! u32 kind  = 1 (KIND)
//! u32 user  : the scene's user the hand is (an index into the scene message's `users`)
//! u32 side  = 0 right, 1 left (HandSide codes)
//! u32 valid : bit i set when WebXR joint i has a pose this frame; bits 25 and up are 0
//! f32 joints[25][8]: position x, y, z (metres), orientation x, y, z, w, radius (metres)
//! ```
//!
//! The joints are WebXR's 25 in WebXR order (wrist first), each in vas's world frame (metres, z
//! up): the page takes them out of the session's reference space through the inverse of the
//! transform it draws the vas world with. A joint whose bit is clear is sent as zeros and read
//! as unknown; a hand with no bit set is an untracked hand. The page picks the user (its
//! `?user=NAME`, else the scene's first); the server refuses and counts a user its scene lacks.

use vas_client::protocol::{
    JOINT_ORIENTATION_TRACKED, JOINT_ORIENTATION_VALID, JOINT_POSITION_TRACKED,
    JOINT_POSITION_VALID, MAX_USERS,
};
use vas_client::{HAND_JOINT_COUNT, HandJointsSample, HandSide, JointLocation};

/// The joints WebXR's `XRHand` has: OpenXR's without the palm.
pub const WEBXR_JOINT_COUNT: usize = HAND_JOINT_COUNT - 1;

/// The message's first word.
pub const KIND: u32 = 1;

/// Values per joint: position (3), orientation (4), radius.
const JOINT_VALUES: usize = 8;

/// Bytes before the joints: kind, user, side, valid bits.
const HEADER_BYTES: usize = 16;

/// A hand-joints message's exact length in bytes.
pub const MESSAGE_BYTES: usize = HEADER_BYTES + 4 * JOINT_VALUES * WEBXR_JOINT_COUNT;

/// The bits of `valid` that name joints.
const JOINT_BITS: u32 = (1 << WEBXR_JOINT_COUNT) - 1;

/// Whether a binary message says it is a hand-joints message (its first word is [`KIND`]),
/// whatever else it holds.
pub fn is_hand_joints(bytes: &[u8]) -> bool {
    bytes.get(..4) == Some(&KIND.to_le_bytes())
}

/// Why a hand-joints message was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HandJointsError {
    /// Not [`MESSAGE_BYTES`] long: not 25 joints of 8 values.
    Length,
    /// The first word is not [`KIND`].
    Kind,
    /// The user is beyond the most users a scene has.
    User,
    /// The side is neither right (0) nor left (1).
    Side,
    /// A valid bit names no WebXR joint.
    ValidBits,
    /// A joint with a pose has a value that is NaN or infinite.
    NonFinite,
}

impl HandJointsError {
    /// The rejection in words, for the close frame and the log.
    pub fn reason(self) -> &'static str {
        match self {
            Self::Length => "hand joints: not 25 joints of 8 values",
            Self::Kind => "hand joints: not a hand-joints message",
            Self::User => "hand joints: no scene has that user",
            Self::Side => "hand joints: side is neither right nor left",
            Self::ValidBits => "hand joints: a valid bit names no joint",
            Self::NonFinite => "hand joints: a value is not finite",
        }
    }
}

/// One joint as the page sent it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Joint {
    /// Position in the vas world, metres.
    pub position: [f32; 3],
    /// Orientation in the vas world, x, y, z, w.
    pub rotation: [f32; 4],
    /// Distance from the joint to the skin, metres.
    pub radius: f32,
}

/// One hand in one XR frame, as the page sent it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandJoints {
    /// Whose hand: the scene's user index.
    pub user: u32,
    /// Which hand.
    pub side: HandSide,
    /// WebXR's 25 joints in WebXR order; `None` where the frame had no pose for the joint.
    pub joints: [Option<Joint>; WEBXR_JOINT_COUNT],
}

impl HandJoints {
    /// Reads a hand-joints message (see the module's documentation).
    pub fn parse(bytes: &[u8]) -> Result<Self, HandJointsError> {
        if bytes.len() != MESSAGE_BYTES {
            return Err(HandJointsError::Length);
        }
        let word = |index: usize| {
            let at = 4 * index;
            u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
        };
        if word(0) != KIND {
            return Err(HandJointsError::Kind);
        }
        let user = word(1);
        if user as usize >= MAX_USERS {
            return Err(HandJointsError::User);
        }
        let side = HandSide::try_from(word(2)).map_err(|_| HandJointsError::Side)?;
        let valid = word(3);
        if valid & !JOINT_BITS != 0 {
            return Err(HandJointsError::ValidBits);
        }
        let mut joints = [None; WEBXR_JOINT_COUNT];
        for (index, joint) in joints.iter_mut().enumerate() {
            if valid & (1 << index) == 0 {
                continue;
            }
            let first = HEADER_BYTES / 4 + JOINT_VALUES * index;
            let values: [f32; JOINT_VALUES] =
                std::array::from_fn(|value| f32::from_bits(word(first + value)));
            if !values.iter().all(|value| value.is_finite()) {
                return Err(HandJointsError::NonFinite);
            }
            *joint = Some(Joint {
                position: [values[0], values[1], values[2]],
                rotation: [values[3], values[4], values[5], values[6]],
                radius: values[7],
            });
        }
        Ok(Self { user, side, joints })
    }

    /// Whether the frame had a pose for any joint (a hand with none is not tracked).
    pub fn any_valid(&self) -> bool {
        self.joints.iter().any(Option::is_some)
    }

    /// The server's sample of this hand, numbered `seq` and stamped `timestamp_ns`: OpenXR's 26
    /// joints with the palm, which WebXR lacks, unknown (flags 0), and every joint the page had
    /// a pose for valid and tracked in position and orientation. An unknown joint is the
    /// origin, unturned, with flags 0.
    pub fn sample(&self, seq: u64, timestamp_ns: u64) -> HandJointsSample {
        const KNOWN: u32 = JOINT_POSITION_VALID
            | JOINT_POSITION_TRACKED
            | JOINT_ORIENTATION_VALID
            | JOINT_ORIENTATION_TRACKED;
        let unknown = JointLocation {
            position: [0.0; 3],
            rotation: [0.0, 0.0, 0.0, 1.0],
            radius: 0.0,
            flags: 0,
        };
        let mut locations = [unknown; HAND_JOINT_COUNT];
        for (location, joint) in locations[1..].iter_mut().zip(&self.joints) {
            if let Some(joint) = joint {
                *location = JointLocation {
                    position: joint.position.map(f64::from),
                    rotation: joint.rotation.map(f64::from),
                    radius: joint.radius,
                    flags: KNOWN,
                };
            }
        }
        HandJointsSample {
            seq,
            timestamp_ns,
            joints: locations,
            side: self.side as u32,
            user: self.user,
        }
    }
}

/// A message of `joints` for `user`'s hand of `side` (`None`: no pose), as the page writes it;
/// for tests and tools.
pub fn encode(user: u32, side: u32, joints: &[Option<Joint>; WEBXR_JOINT_COUNT]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(MESSAGE_BYTES);
    let valid = (joints.iter().enumerate())
        .filter(|(_, joint)| joint.is_some())
        .fold(0u32, |bits, (index, _)| bits | 1 << index);
    for word in [KIND, user, side, valid] {
        bytes.extend_from_slice(&word.to_le_bytes());
    }
    for joint in joints {
        let values = joint.map_or([0.0; JOINT_VALUES], |joint| {
            let [x, y, z] = joint.position;
            let [qx, qy, qz, qw] = joint.rotation;
            [x, y, z, qx, qy, qz, qw, joint.radius]
        });
        for value in values {
            bytes.extend_from_slice(&value.to_le_bytes());
        }
    }
    bytes
}

/// Numbers each hand's samples (by user and side) from 1, as the server expects of one sender.
#[derive(Debug, Default)]
pub struct Sequence {
    last: [[u64; 2]; MAX_USERS],
}

impl Sequence {
    /// The next number for the hand of `joints`.
    pub fn next(&mut self, joints: &HandJoints) -> u64 {
        let last = &mut self.last[joints.user as usize][joints.side as usize];
        *last += 1;
        *last
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hand whose joint `i` is at `(i, 2i, 3i)` cm, turned a quarter about z.
    fn hand() -> [Option<Joint>; WEBXR_JOINT_COUNT] {
        let half = std::f32::consts::FRAC_1_SQRT_2;
        std::array::from_fn(|index| {
            let at = index as f32 / 100.0;
            Some(Joint {
                position: [at, 2.0 * at, 3.0 * at],
                rotation: [0.0, 0.0, half, half],
                radius: 0.01,
            })
        })
    }

    #[test]
    fn a_hand_reads_back_and_maps_to_openxr_joints_with_the_palm_unknown() {
        let bytes = encode(2, HandSide::Left as u32, &hand());
        assert_eq!(bytes.len(), MESSAGE_BYTES);
        assert!(is_hand_joints(&bytes));
        let read = HandJoints::parse(&bytes).expect("a well-formed message");
        assert_eq!((read.user, read.side), (2, HandSide::Left));
        assert_eq!(read.joints, hand());
        assert!(read.any_valid());

        let sample = read.sample(7, 123);
        assert_eq!((sample.seq, sample.timestamp_ns), (7, 123));
        assert_eq!((sample.user, sample.side), (2, HandSide::Left as u32));
        assert_eq!(sample.joints[0].flags, 0, "WebXR has no palm");
        assert_eq!(sample.joints[0].rotation, [0.0, 0.0, 0.0, 1.0]);
        // OpenXR joint i + 1 is WebXR joint i.
        let tip = sample.joints[HAND_JOINT_COUNT - 1];
        let sent = hand()[WEBXR_JOINT_COUNT - 1].unwrap();
        assert_eq!(tip.position, sent.position.map(f64::from));
        assert_eq!(tip.rotation, sent.rotation.map(f64::from));
        assert_eq!(
            tip.flags, 0b1111,
            "valid and tracked in position and orientation"
        );
        assert_eq!(tip.radius, 0.01);
        assert!(sample.is_finite());
    }

    #[test]
    fn a_hand_without_poses_is_sent_untracked_and_a_missing_joint_unknown() {
        let untracked = HandJoints::parse(&encode(0, 0, &[None; WEBXR_JOINT_COUNT])).unwrap();
        assert_eq!(untracked.side, HandSide::Right);
        assert!(!untracked.any_valid());
        let sample = untracked.sample(1, 1);
        assert!(sample.joints.iter().all(|joint| joint.flags == 0));
        assert!(sample.is_finite());

        let mut joints = hand();
        joints[3] = None;
        let sample = HandJoints::parse(&encode(0, 0, &joints))
            .unwrap()
            .sample(2, 2);
        assert_eq!(sample.joints[4].flags, 0);
        assert_eq!(sample.joints[5].flags, 0b1111);
    }

    #[test]
    fn malformed_messages_are_rejected_with_their_reason() {
        let good = encode(0, 1, &hand());
        // Wrong joint counts: one joint short, one too many, a huge array, nothing.
        let mut short = good.clone();
        short.truncate(MESSAGE_BYTES - 4 * JOINT_VALUES);
        let mut long = good.clone();
        long.extend_from_slice(&[0; 4 * JOINT_VALUES]);
        let huge = [good.clone(), vec![0; 1 << 20]].concat();
        for bytes in [&short, &long, &huge, &good[..0], &good[..4]] {
            assert_eq!(
                HandJoints::parse(bytes),
                Err(HandJointsError::Length),
                "{} bytes",
                bytes.len()
            );
        }
        // A user beyond any scene's, a bad side, a bad kind, a bit for a 26th joint.
        let mut bad_user = good.clone();
        bad_user[4..8].copy_from_slice(&(MAX_USERS as u32).to_le_bytes());
        assert_eq!(HandJoints::parse(&bad_user), Err(HandJointsError::User));
        let mut bad_side = good.clone();
        bad_side[8..12].copy_from_slice(&2u32.to_le_bytes());
        assert_eq!(HandJoints::parse(&bad_side), Err(HandJointsError::Side));
        bad_side[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
        assert_eq!(HandJoints::parse(&bad_side), Err(HandJointsError::Side));
        let mut bad_kind = good.clone();
        bad_kind[0..4].copy_from_slice(&2u32.to_le_bytes());
        assert_eq!(HandJoints::parse(&bad_kind), Err(HandJointsError::Kind));
        assert!(!is_hand_joints(&bad_kind));
        let mut extra_bit = good.clone();
        extra_bit[12..16].copy_from_slice(&(JOINT_BITS | 1 << 25).to_le_bytes());
        assert_eq!(
            HandJoints::parse(&extra_bit),
            Err(HandJointsError::ValidBits)
        );
        // NaN or infinity in any value of a joint with a pose.
        for (index, bad) in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY]
            .into_iter()
            .enumerate()
        {
            let mut joints = hand();
            let joint = joints[10 + index].as_mut().unwrap();
            match index {
                0 => joint.position[1] = bad,
                1 => joint.rotation[3] = bad,
                _ => joint.radius = bad,
            }
            assert_eq!(
                HandJoints::parse(&encode(0, 1, &joints)),
                Err(HandJointsError::NonFinite)
            );
        }
        // A joint without a pose may hold anything: it is not read.
        let mut unknown_nan = encode(0, 1, &hand());
        unknown_nan[12..16].copy_from_slice(&(JOINT_BITS & !1).to_le_bytes());
        unknown_nan[HEADER_BYTES..HEADER_BYTES + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        let read = HandJoints::parse(&unknown_nan).expect("the NaN is in no joint with a pose");
        assert_eq!(read.joints[0], None);
    }

    #[test]
    fn each_hand_is_numbered_from_one() {
        let hand = |user, side| HandJoints {
            user,
            side,
            joints: [None; WEBXR_JOINT_COUNT],
        };
        let mut sequence = Sequence::default();
        assert_eq!(sequence.next(&hand(0, HandSide::Right)), 1);
        assert_eq!(sequence.next(&hand(0, HandSide::Right)), 2);
        assert_eq!(sequence.next(&hand(0, HandSide::Left)), 1);
        assert_eq!(sequence.next(&hand(1, HandSide::Right)), 1);
        assert_eq!(sequence.next(&hand(0, HandSide::Right)), 3);
    }
}
