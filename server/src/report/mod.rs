//! A session's report: how close the parts came to each other along a replayed recording, per
//! part pair, in the words of CATIA's clash analysis.
//!
//! [`Session`] takes the part poses of every frame (`vas-server report` feeds it a lockstep
//! replay, [`crate::replay`]) and measures every pair of parts of interest to each other of which
//! at least one is movable (two static parts never move, so their clearance is the scene's, not
//! the session's). A pair is reported when it came within the clearance threshold at least once:
//!
//! * **clearance**: the pair was closer than the threshold; the minimum distance, the sample and
//!   the closest points where it occurred, and how long it stayed below the threshold.
//! * **contact**: the distance was within the contact tolerance (the scene's sliding contact
//!   tolerance, the one the simulation calls a contact by): the intervals of samples it lasted.
//! * **clash**: the parts interpenetrate, judged independently of the DOP-trees by parry on the
//!   same poses; none for the poses vas publishes.
//!
//! Distances come from the DOP-tree's distance query, with one [`DistanceMemory`] per pair across
//! frames (temporal coherence); a pair whose relative pose did not change keeps its last answer.
//! [`Report`] is what the JSON holds; [`html`] renders it as one self-contained page with a
//! [`timeline`] figure per pair.
//!
//! [`DistanceMemory`]: crate::collision::distance::DistanceMemory

mod clash;
pub mod html;
mod session;
pub mod timeline;

use serde::Serialize;

pub use session::Session;

/// A pair's worst state along the session, as CATIA names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// The parts interpenetrated in at least one frame.
    Clash,
    /// They touched (within the contact tolerance) but never interpenetrated.
    Contact,
    /// They came within the threshold, never touching.
    Clearance,
}

impl Status {
    /// The status in a word.
    pub fn name(self) -> &'static str {
        match self {
            Status::Clash => "clash",
            Status::Contact => "contact",
            Status::Clearance => "clearance",
        }
    }
}

/// Where and when a pair was closest.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Moment {
    /// The distance, metres (0 when touching or interpenetrating).
    pub clearance_m: f64,
    /// The recording's sample (from 0) whose frame it was.
    pub sample: usize,
    /// The sample's time in the recording, seconds.
    pub time_s: f64,
    /// The closest point on the first part, in the world, metres.
    pub point_a: [f64; 3],
    /// The closest point on the second part, in the world, metres.
    pub point_b: [f64; 3],
    /// The triangles of the first and second part's meshes they lie on.
    pub triangles: [u32; 2],
}

/// A stretch of frames in contact: from `begin` to `end` (samples, `end` the first no longer in
/// contact; `None` while still in contact at the end of the recording).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Interval {
    /// The first sample in contact.
    pub begin: usize,
    /// The first sample after it no longer in contact.
    pub end: Option<usize>,
}

/// One part pair that came within the threshold.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PairReport {
    /// The first part's name (the lower id).
    pub a: String,
    /// The second part's name.
    pub b: String,
    /// Its worst state.
    pub status: Status,
    /// The minimum clearance and where it occurred (`None` only for a pair parry finds clashing
    /// that the distance query never saw within twice the threshold).
    pub minimum: Option<Moment>,
    /// Frames below the threshold.
    pub frames_below: usize,
    /// Seconds below the threshold: each such frame counts until the next frame's sample.
    pub seconds_below: f64,
    /// The contact tolerance of this pair, metres.
    pub contact_tolerance_m: f64,
    /// The contact intervals, in order.
    pub contacts: Vec<Interval>,
    /// Frames in which parry finds the parts interpenetrating.
    pub clash_frames: usize,
    /// The first of them, as a sample.
    pub first_clash: Option<usize>,
    /// Per frame, the sample and the clearance (metres) if below twice the threshold, for the
    /// timeline figure; not in the JSON.
    #[serde(skip)]
    pub timeline: Vec<(usize, Option<f64>)>,
}

/// The whole report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// The scene's name.
    pub scene: String,
    /// The recording's file name, as given.
    pub recording: String,
    /// Samples in the recording.
    pub samples: usize,
    /// Frames stepped (one per valid sample from the first that places a hand).
    pub frames: usize,
    /// Samples refused as invalid.
    pub rejected: usize,
    /// The clearance threshold, metres.
    pub threshold_m: f64,
    /// Pairs measured (of interest to each other, at least one movable).
    pub pairs_measured: usize,
    /// The pairs that came within the threshold, the closest first.
    pub pairs: Vec<PairReport>,
}

impl Report {
    /// The report as pretty-printed JSON.
    pub fn json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report is plain data")
    }
}
