//! Hand-joints input from the real captured hands in `tests/fixtures/hands/`.

use std::path::PathBuf;

use vas_server::grasping::Side;
use vas_server::grasping::retarget::{Capture, HandJoints};

/// The captured pinch: thumb and index tips together.
pub const PINCH: &str = "webxr_pinch.json";

/// The captured open, relaxed hand.
pub const RELAXED: &str = "webxr_relaxed.json";

/// The path of the capture `name`.
pub fn capture_path(name: &str) -> PathBuf {
    crate::fixtures_dir().join("hands").join(name)
}

/// The capture `name` as a hand of `side` (the captures are left hands; a right hand is their
/// mirror image).
pub fn captured(name: &str, side: Side) -> HandJoints {
    Capture::read(&capture_path(name))
        .unwrap_or_else(|error| panic!("{error}"))
        .joints_of(side)
}
