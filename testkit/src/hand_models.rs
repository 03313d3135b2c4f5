//! The project's hand models (`configs/hands/`), loaded for tests.

use std::path::{Path, PathBuf};

use vas_server::grasping::HandModel;

/// The folder of the shipped hand models.
pub fn hands_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/hands")
}

/// The shipped right hand.
pub fn right_hand() -> HandModel {
    HandModel::load(&hands_dir().join("right.toml")).expect("the right hand loads")
}
