//! The `vas/control` request-response service: scene information, scene loading, reset, sliding
//! metaphor, and the input counters.
//!
//! Both types have a fixed size so that they travel zero-copy. A scene's part list is therefore
//! read one part per request ([`ControlRequestKind::PartInfo`]) rather than in one response:
//! scenes have any number of parts, and a renderer reads them once at start.
//! Strings are bounded ([`MAX_NAME_BYTES`], [`MAX_PATH_BYTES`]); the server cuts longer names at
//! a character boundary and says so in [`PartDescription::truncated`].

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};

use crate::pose::WirePose;
use crate::text::WireText;

/// Capacity of names (scene, part, group) in bytes.
pub const MAX_NAME_BYTES: usize = 64;
/// Capacity of paths and mesh sources in bytes.
pub const MAX_PATH_BYTES: usize = 512;
/// Capacity of the human-readable status message in bytes.
pub const MAX_STATUS_MESSAGE_BYTES: usize = 256;

wire_code_enum! {
    /// What a [`ControlRequest`] asks for.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum ControlRequestKind {
        /// Scene name, source file and part count.
        SceneInfo = 1,
        /// One part's description; [`ControlRequest::argument`] is the part id.
        PartInfo = 2,
        /// Replace the scene by the file in [`ControlRequest::path`], as the server's file system
        /// sees it (for local tools; a page of the viewer uses [`Self::LoadNamedScene`]).
        LoadScene = 3,
        /// Put every part back to its initial pose and forget the hand state.
        Reset = 4,
        /// Select the sliding metaphor; [`ControlRequest::argument`] is a [`SlidingMetaphor`] code.
        SetMetaphor = 5,
        /// The name of the scene number [`ControlRequest::argument`] among those the server may
        /// load by name ([`ControlResponse::listed`]), and how many there are
        /// ([`ControlResponse::listed_count`]).
        ListScene = 6,
        /// Replace the scene by the one the server lists under the name in
        /// [`ControlRequest::path`]: a name, never a path, so that a remote page can only choose
        /// among the scenes the server offers.
        LoadNamedScene = 7,
    }
}

wire_code_enum! {
    /// How a grasped part follows the ghost that the hand holds (the paper's three metaphors).
    ///
    /// One spelling everywhere a person reads it: `rubber-band`, `spiral-spring`, `incremental`
    /// (scene configs, the command line, the viewer's messages and page, logs).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
    #[serde(rename_all = "kebab-case")]
    pub enum SlidingMetaphor {
        /// The position is pulled towards the ghost; the orientation comes from the simulation.
        #[default]
        RubberBand = 1,
        /// Rubber band and spiral spring: position and orientation are both pulled towards the
        /// ghost.
        SpiralSpring = 2,
        /// The part repeats the ghost's motion increment.
        Incremental = 3,
    }
}

impl SlidingMetaphor {
    /// Every metaphor, in code order.
    pub const ALL: [SlidingMetaphor; 3] = [
        SlidingMetaphor::RubberBand,
        SlidingMetaphor::SpiralSpring,
        SlidingMetaphor::Incremental,
    ];

    /// The metaphor's name: `rubber-band`, `spiral-spring` or `incremental`.
    pub fn name(self) -> &'static str {
        match self {
            SlidingMetaphor::RubberBand => "rubber-band",
            SlidingMetaphor::SpiralSpring => "spiral-spring",
            SlidingMetaphor::Incremental => "incremental",
        }
    }

    /// Whether sliding under this metaphor may turn the part.
    pub fn rotates(self) -> bool {
        self != SlidingMetaphor::RubberBand
    }
}

impl std::fmt::Display for SlidingMetaphor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A name that is no sliding metaphor.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("no sliding metaphor is called {0:?}: rubber-band, spiral-spring or incremental")]
pub struct UnknownMetaphor(pub String);

impl std::str::FromStr for SlidingMetaphor {
    type Err = UnknownMetaphor;

    fn from_str(name: &str) -> Result<Self, Self::Err> {
        (SlidingMetaphor::ALL.into_iter())
            .find(|metaphor| metaphor.name() == name)
            .ok_or_else(|| UnknownMetaphor(name.to_owned()))
    }
}

/// A request on `vas/control`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ZeroCopySend)]
#[type_name("vas::control::ControlRequest::v1")]
#[repr(C)]
pub struct ControlRequest {
    /// A [`ControlRequestKind`] code.
    pub kind: u32,
    /// Part id for `PartInfo`, metaphor code for `SetMetaphor`, 0 otherwise.
    pub argument: u32,
    /// Scene file for `LoadScene`, as the server sees the file system; scene name for
    /// `LoadNamedScene`; empty otherwise.
    pub path: WireText<MAX_PATH_BYTES>,
}

impl ControlRequest {
    /// Ask for the scene summary.
    pub fn scene_info() -> Self {
        Self::with_argument(ControlRequestKind::SceneInfo, 0)
    }

    /// Ask for the description of part `id`.
    pub fn part_info(id: u32) -> Self {
        Self::with_argument(ControlRequestKind::PartInfo, id)
    }

    /// Ask the server to replace its scene by the file at `path`.
    pub fn load_scene(path: WireText<MAX_PATH_BYTES>) -> Self {
        Self {
            path,
            ..Self::with_argument(ControlRequestKind::LoadScene, 0)
        }
    }

    /// Ask for the name of the `index`th scene the server may load by name.
    pub fn list_scene(index: u32) -> Self {
        Self::with_argument(ControlRequestKind::ListScene, index)
    }

    /// Ask the server to replace its scene by the one it lists as `name`.
    pub fn load_named_scene(name: WireText<MAX_PATH_BYTES>) -> Self {
        Self {
            path: name,
            ..Self::with_argument(ControlRequestKind::LoadNamedScene, 0)
        }
    }

    /// Ask the server to put the scene back to its initial state.
    pub fn reset() -> Self {
        Self::with_argument(ControlRequestKind::Reset, 0)
    }

    /// Ask the server to use `metaphor` for sliding.
    pub fn set_metaphor(metaphor: SlidingMetaphor) -> Self {
        Self::with_argument(ControlRequestKind::SetMetaphor, metaphor as u32)
    }

    fn with_argument(kind: ControlRequestKind, argument: u32) -> Self {
        Self {
            kind: kind as u32,
            argument,
            path: WireText::EMPTY,
        }
    }
}

wire_code_enum! {
    /// Outcome of a control request.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum ControlStatus {
        /// Done; the response fields for the request kind are filled.
        Ok = 0,
        /// The request kind or an argument code is unknown.
        InvalidRequest = 1,
        /// `PartInfo` named a part id the scene does not have.
        NoSuchPart = 2,
        /// `LoadScene` or `LoadNamedScene` failed (or `ListScene` asked past the list); the scene
        /// is unchanged and the message says why.
        SceneLoadFailed = 3,
        /// The server understands the request but cannot carry it out in this version.
        Unsupported = 4,
        /// `LoadScene` while another scene is loading; ask again once that request is answered.
        Busy = 5,
    }
}

/// Counters of the server's input validation, since it started.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend, Serialize, Deserialize)]
#[repr(C)]
pub struct InputStats {
    /// Tracker samples accepted.
    pub tracker_accepted: u64,
    /// Tracker samples rejected for a NaN or infinite value.
    pub tracker_rejected_non_finite: u64,
    /// Tracker samples rejected for a rotation that is not a unit quaternion.
    pub tracker_rejected_quaternion: u64,
    /// Glove samples accepted (clamped or not).
    pub glove_accepted: u64,
    /// Glove samples rejected for a NaN or infinite value.
    pub glove_rejected_non_finite: u64,
    /// Accepted glove samples with at least one value clamped into the joint limits.
    pub glove_samples_clamped: u64,
    /// Flex values clamped into the joint limits, over all glove samples.
    pub glove_values_clamped: u64,
    /// Tracker samples rejected for a position beyond [`MAX_POSITION_M`](crate::MAX_POSITION_M).
    pub tracker_rejected_out_of_range: u64,
    /// Hand-joints samples accepted and retargeted onto their hand.
    pub joints_accepted: u64,
    /// Hand-joints samples that say their hand is not tracked (a joint the retargeting needs is
    /// not valid): not rejected, the hand stays where it was and its frames say it is untracked.
    pub joints_untracked: u64,
    /// Hand-joints samples rejected for a NaN or infinite position or radius.
    pub joints_rejected_non_finite: u64,
    /// Hand-joints samples rejected for an orientation that is not a unit quaternion.
    pub joints_rejected_quaternion: u64,
    /// Hand-joints samples rejected for a position beyond
    /// [`MAX_POSITION_M`](crate::MAX_POSITION_M).
    pub joints_rejected_out_of_range: u64,
    /// Hand-joints samples rejected as no hand: joints out of anatomical order, or bones of
    /// impossible length.
    pub joints_rejected_anatomy: u64,
    /// Hand-joints samples rejected for naming a side the scene has no hand for (or no side).
    pub joints_rejected_no_such_hand: u64,
    /// Samples of any stream rejected for a timestamp more than
    /// [`MAX_TIMESTAMP_AHEAD_NS`](crate::MAX_TIMESTAMP_AHEAD_NS) beyond the server's clock.
    pub rejected_ahead: u64,
    /// Samples of any stream rejected for naming a user the scene does not have.
    pub rejected_no_such_user: u64,
    /// Tracker and glove samples rejected for naming a side their user has no hand for (or no
    /// side).
    pub rejected_no_such_hand: u64,
}

impl InputStats {
    /// All rejected samples, of every input stream.
    pub fn rejected(&self) -> u64 {
        self.tracker_rejected_non_finite
            + self.tracker_rejected_quaternion
            + self.tracker_rejected_out_of_range
            + self.glove_rejected_non_finite
            + self.joints_rejected()
            + self.rejected_ahead
            + self.rejected_no_such_user
            + self.rejected_no_such_hand
    }

    /// Rejected hand-joints samples.
    pub fn joints_rejected(&self) -> u64 {
        self.joints_rejected_non_finite
            + self.joints_rejected_quaternion
            + self.joints_rejected_out_of_range
            + self.joints_rejected_anatomy
            + self.joints_rejected_no_such_hand
    }
}

/// [`PartDescription::flags`] bit: the part can be grasped and moved.
pub const PART_MOVABLE: u32 = 1 << 0;

/// One part of the scene, as `PartInfo` describes it.
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[repr(C)]
pub struct PartDescription {
    /// The id used in parts frames.
    pub id: u32,
    /// [`PART_MOVABLE`] when the part can be grasped.
    pub flags: u32,
    /// The part's initial pose in the scene.
    pub initial_pose: WirePose,
    /// The part's name in the scene.
    pub name: WireText<MAX_NAME_BYTES>,
    /// The collision group the part belongs to.
    pub group: WireText<MAX_NAME_BYTES>,
    /// Where the geometry comes from: a mesh path as the server resolved it, or the procedural
    /// shape's description.
    pub mesh_source: WireText<MAX_PATH_BYTES>,
    /// Non-zero when a string above was cut to fit its capacity.
    pub truncated: u32,
    /// The scale the scene applies to the part's mesh (already applied to the mesh on
    /// `vas/scene/geometry`).
    pub scale: f64,
}

/// A hand of the scene, as every [`ControlResponse`] describes it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend)]
#[repr(C)]
pub struct HandDescription {
    /// A [`crate::HandSide`] code.
    pub side: u32,
    /// Whose hand it is: an index into [`ControlResponse::users`].
    pub user: u32,
    /// The hand model's name.
    pub model: WireText<MAX_NAME_BYTES>,
}

/// Most users a scene has, each with one or two hands.
pub const MAX_USERS: usize = 4;

/// Most hands a scene has: a left and a right one for each of [`MAX_USERS`] users.
pub const MAX_HANDS: usize = 2 * MAX_USERS;

/// The answer to a [`ControlRequest`].
///
/// One flat type for every request kind: the fields a kind does not use are zero. Every response
/// carries the scene summary and the input counters, so any request doubles as a status query.
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("vas::control::ControlResponse::v8")]
#[repr(C)]
pub struct ControlResponse {
    /// A [`ControlStatus`] code.
    pub status: u32,
    /// The [`ControlRequestKind`] code this answers.
    pub kind: u32,
    /// Number of parts in the current scene (ids are `0..part_count`).
    pub part_count: u32,
    /// Non-zero when the scene name or source was cut to fit.
    pub scene_truncated: u32,
    /// Name of the current scene.
    pub scene_name: WireText<MAX_NAME_BYTES>,
    /// File the current scene was loaded from.
    pub scene_source: WireText<MAX_PATH_BYTES>,
    /// The part asked for by `PartInfo`; zero otherwise.
    pub part: PartDescription,
    /// Input validation counters at the time of the answer.
    pub stats: InputStats,
    /// Human-readable detail, mainly for errors.
    pub message: WireText<MAX_STATUS_MESSAGE_BYTES>,
    /// The world's up direction: `[0, 0, 1]` (z up).
    pub up: [f64; 3],
    /// Metres per unit of every length on the wire: 1 (lengths are in metres).
    pub metres_per_unit: f64,
    /// Hands the scene has (`hands[..hand_count]`), every user's, grouped by user in the
    /// users' order.
    pub hand_count: u32,
    /// How many scenes the server may load by name.
    pub listed_count: u32,
    /// The scene's hands.
    pub hands: [HandDescription; MAX_HANDS],
    /// `ListScene`: the name asked for; empty otherwise.
    pub listed: WireText<MAX_NAME_BYTES>,
    /// The served scene's generation, as the answer leaves: 1 for the scene the server started
    /// with, one more after each load or reset; the same number as
    /// [`GeometryHeader::generation`](crate::GeometryHeader::generation). Answers of different
    /// generations describe different scenes.
    pub generation: u64,
    /// The [`SlidingMetaphor`] code in use, as the answer leaves: the scene's own after a start,
    /// load or reset, the one asked for after a `SetMetaphor`.
    pub metaphor: u32,
    /// Users the scene has (`users[..user_count]`): 1 for a scene that declares hands without
    /// users, and for a scene without hands.
    pub user_count: u32,
    /// Each user's name, by the index that samples and frames name the user with. A scene
    /// refuses names that do not fit, so none is cut.
    pub users: [WireText<MAX_NAME_BYTES>; MAX_USERS],
}

impl ControlResponse {
    /// The names of the scene's users, by index.
    pub fn user_names(&self) -> impl Iterator<Item = &str> {
        let count = (self.user_count as usize).min(MAX_USERS);
        (self.users[..count].iter()).map(|name| name.as_str().unwrap_or_default())
    }

    /// The name of user `user`, if the scene has it.
    pub fn user_name(&self, user: u32) -> Option<&str> {
        self.user_names().nth(user as usize)
    }

    /// The index of the user called `name`, if the scene has one.
    pub fn user_index(&self, name: &str) -> Option<u32> {
        (0u32..)
            .zip(self.user_names())
            .find(|(_, user)| *user == name)
            .map(|(index, _)| index)
    }

    /// The scene's hands (`hands[..hand_count]`).
    pub fn scene_hands(&self) -> &[HandDescription] {
        &self.hands[..(self.hand_count as usize).min(MAX_HANDS)]
    }
}
