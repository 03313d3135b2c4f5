//! Clearance frames: the part pairs closer than a scene's clearance threshold, on
//! `vas/output/clearance`.
//!
//! A frame follows each parts frame whose poses it measured, with that frame's number, so that a
//! renderer draws each pair's closest points on the poses it already shows. The server measures
//! beside its loops and never holds a frame back for a measurement: a pair it could not measure
//! again before the next frame keeps its previous measurement and is flagged
//! [`CLEARANCE_STALE`].

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};

use crate::output::InputStamp;

/// Pairs a [`ClearanceFrame`] lists at most: the closest ones; [`ClearanceFrame::more`] counts
/// the rest. 32 keeps a frame at 2.7 kB and is far more than a part comes close to at once.
pub const MAX_CLEARANCE_PAIRS: usize = 32;

/// [`ClearancePair::flags`] bit: the pair was not measured again on this frame's poses in time;
/// its distance and points are from an earlier frame.
pub const CLEARANCE_STALE: u32 = 1 << 0;

/// Two parts closer than the threshold, with their closest points.
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[type_name("vas::output::ClearancePair::v1")]
#[repr(C)]
pub struct ClearancePair {
    /// One part's id (a held part, in `held` mode).
    pub part: u32,
    /// The other part's id.
    pub other: u32,
    /// The closest triangles, by index in each part's mesh: `[of part, of other]`.
    pub triangles: [u32; 2],
    /// State bits: [`CLEARANCE_STALE`].
    pub flags: u32,
    /// Padding, 0.
    pub reserved: u32,
    /// Distance between the two parts, metres (0 when they touch).
    pub distance: f64,
    /// The closest point on `part`, in the world (metres).
    pub point: [f64; 3],
    /// The closest point on `other`, in the world (metres).
    pub other_point: [f64; 3],
}

impl ClearancePair {
    /// True when the pair carries an earlier frame's measurement.
    pub fn is_stale(&self) -> bool {
        self.flags & CLEARANCE_STALE != 0
    }
}

/// The pairs closer than the scene's clearance threshold on one parts frame, closest first.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, Serialize, Deserialize)]
#[type_name("vas::output::ClearanceFrame::v1")]
#[repr(C)]
pub struct ClearanceFrame {
    /// The parts frame (`vas/output/parts`) whose poses were measured.
    pub frame: u64,
    /// The latest tracker sample taken into account.
    pub tracker: InputStamp,
    /// The latest glove sample taken into account.
    pub glove: InputStamp,
    /// The latest hand-joints sample taken into account.
    pub joints: InputStamp,
    /// When the frame was published, in nanoseconds since the Unix epoch.
    pub timestamp_ns: u64,
    /// The scene's threshold, metres.
    pub threshold: f64,
    /// Pairs listed in [`ClearanceFrame::pairs`].
    pub pair_count: u32,
    /// Pairs closer than the threshold beyond [`MAX_CLEARANCE_PAIRS`], not listed.
    pub more: u32,
    /// The pairs, closest first; the first `pair_count` are set.
    pub pairs: [ClearancePair; MAX_CLEARANCE_PAIRS],
}

impl Default for ClearanceFrame {
    /// A frame of no pairs.
    fn default() -> Self {
        Self {
            frame: 0,
            tracker: InputStamp::default(),
            glove: InputStamp::default(),
            joints: InputStamp::default(),
            timestamp_ns: 0,
            threshold: 0.0,
            pair_count: 0,
            more: 0,
            pairs: [ClearancePair::default(); MAX_CLEARANCE_PAIRS],
        }
    }
}

impl ClearanceFrame {
    /// The pairs listed.
    pub fn listed(&self) -> &[ClearancePair] {
        &self.pairs[..(self.pair_count as usize).min(MAX_CLEARANCE_PAIRS)]
    }
}
