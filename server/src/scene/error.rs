//! Why a scene config was refused.

use std::io;
use std::path::PathBuf;

use thiserror::Error;

use crate::geometry::GeometryError;

/// Why a scene config was refused; every variant names the file.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("scene {}: cannot read it: {source}", file.display())]
    Read {
        /// The scene file.
        file: PathBuf,
        /// What the operating system said.
        #[source]
        source: io::Error,
    },
    /// The file is not valid TOML, has an unknown key, or a value of the wrong type.
    #[error("scene {}: {message}", file.display())]
    Syntax {
        /// The scene file.
        file: PathBuf,
        /// The line, the offending text and the reason.
        message: String,
    },
    /// A value is out of range or inconsistent with the rest of the scene.
    #[error("scene {}: {key}: {reason}", file.display())]
    Invalid {
        /// The scene file.
        file: PathBuf,
        /// The key, as in the config (`parts[2].rotation`).
        key: String,
        /// What is wrong.
        reason: String,
    },
    /// A part's mesh file could not be loaded or its shape not built.
    #[error("scene {}: {key}: {source}", file.display())]
    Mesh {
        /// The scene file.
        file: PathBuf,
        /// The key, as in the config (`parts[1].mesh`).
        key: String,
        /// Why the mesh failed.
        #[source]
        source: GeometryError,
    },
}
