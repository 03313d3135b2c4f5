//! What a segment is in the hand: its finger and its joint's level.

use serde::Deserialize;

/// Which part of the hand a segment belongs to (the analysis' semantics).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Finger {
    /// The palm.
    Palm,
    /// The thumb.
    Thumb,
    /// The index finger.
    Index,
    /// The middle finger.
    Middle,
    /// The ring finger.
    Ring,
    /// The little finger.
    Pinky,
}

impl Finger {
    /// The five digits, thumb first, then the fingers from the thumb side outward.
    pub const DIGITS: [Finger; 5] = [
        Finger::Thumb,
        Finger::Index,
        Finger::Middle,
        Finger::Ring,
        Finger::Pinky,
    ];

    /// Position across the hand: 0 for the thumb, 1 for the index ... 4 for the pinky; `None`
    /// for the palm. Two fingers are neighbours when their positions differ by one.
    pub fn position(self) -> Option<usize> {
        Finger::DIGITS.iter().position(|&f| f == self)
    }
}

/// Where along its digit a segment sits (the analysis' semantics).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JointLevel {
    /// The palm itself.
    Palm,
    /// The segment nearest the palm (moved by the MCP joint; the thumb's metacarpal).
    Inner,
    /// The middle segment.
    Middle,
    /// The tip segment.
    Outer,
}
