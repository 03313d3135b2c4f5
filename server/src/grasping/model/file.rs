//! A hand config as written in TOML, before validation.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use vas_protocol::HandSide;

use super::{Finger, HandConfigError, JointLevel};
use crate::geometry::{ConfigFileError, FileLimits, describe_toml_error, read_config_text};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct HandFile {
    pub(super) name: String,
    pub(super) side: HandSide,
    pub(super) mirror_of: Option<PathBuf>,
    #[serde(default)]
    pub(super) flex: Vec<FlexEntry>,
    #[serde(default)]
    pub(super) segment: Vec<SegmentEntry>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FlexEntry {
    pub(super) name: String,
    pub(super) min_deg: f64,
    pub(super) max_deg: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SegmentEntry {
    pub(super) name: String,
    pub(super) parent: String,
    pub(super) finger: Finger,
    pub(super) joint: JointLevel,
    pub(super) origin: [f64; 3],
    #[serde(default)]
    pub(super) base_rotations: Vec<AxisAngleEntry>,
    #[serde(default)]
    pub(super) dofs: Vec<DofEntry>,
    pub(super) shape: ShapeEntry,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct AxisAngleEntry {
    pub(super) axis: [f64; 3],
    pub(super) angle_deg: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DofEntry {
    pub(super) axis: [f64; 3],
    pub(super) pivot: Option<[f64; 3]>,
    pub(super) flex: Vec<usize>,
    pub(super) gains: Option<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ShapeEntry {
    pub(super) radius: f64,
    pub(super) centres: Vec<[f64; 3]>,
}

/// The name a segment config gives as parent when the segment hangs from the hand root.
pub(super) const ROOT_PARENT: &str = "root";

pub(super) fn read_hand_file(
    path: &Path,
    limits: &FileLimits,
) -> Result<HandFile, HandConfigError> {
    parse_hand_file(path, &read_config_text(path, limits.config_bytes)?)
}

pub(super) fn parse_hand_file(path: &Path, text: &str) -> Result<HandFile, HandConfigError> {
    toml::from_str(text)
        .map_err(|error| ConfigFileError::syntax(path, describe_toml_error(text, &error)))
}
