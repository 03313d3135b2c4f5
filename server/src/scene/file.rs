//! The scene config as written in TOML, before validation.

use std::path::PathBuf;

use serde::Deserialize;

use super::loader::AssemblyFile;
use super::params::AlgorithmParams;
use super::params::Rates;
use super::unheld::ReleaseMode;
use crate::geometry::shapes::ShapeSpec;

/// The config as written, before validation.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub(super) name: String,
    pub(super) hand: Option<PathBuf>,
    pub(super) hands: Option<Vec<PathBuf>>,
    #[serde(default)]
    pub(super) users: Vec<UserFile>,
    #[serde(default)]
    pub(super) params: AlgorithmParams,
    #[serde(default)]
    pub(super) rates: Rates,
    #[serde(default)]
    pub(super) groups: GroupsFile,
    #[serde(default)]
    pub(super) parts: Vec<PartFile>,
    #[serde(default)]
    pub(super) assemblies: Vec<AssemblyFile>,
}

/// One `[[users]]` entry: a person's name and their hand models.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct UserFile {
    pub(super) name: String,
    pub(super) hand: Option<PathBuf>,
    pub(super) hands: Option<Vec<PathBuf>>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct GroupsFile {
    #[serde(default)]
    pub(super) not_of_interest: Vec<[String; 2]>,
    #[serde(default)]
    pub(super) parts_not_of_interest: Vec<[String; 2]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PartFile {
    pub(super) name: String,
    pub(super) mesh: Option<PathBuf>,
    pub(super) scale: Option<f64>,
    pub(super) shape: Option<ShapeSpec>,
    #[serde(default)]
    pub(super) position: [f64; 3],
    pub(super) rotation: Option<[f64; 4]>,
    #[serde(default)]
    pub(super) movable: bool,
    #[serde(default = "default_group")]
    pub(super) group: String,
    pub(super) push: Option<bool>,
    pub(super) release: Option<ReleaseMode>,
}

pub(super) fn default_group() -> String {
    "default".to_owned()
}
