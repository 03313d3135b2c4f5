//! What the loaders accept, reading a file within it, and why a config file was refused.

use std::fmt;
use std::io;
use std::path::{Path, PathBuf};

use thiserror::Error;

/// What the loaders accept: the largest files by kind and the most triangles of a scene. A
/// setting of the deployment (`vas-server --max-mesh-file`, `--max-config-file`,
/// `--max-scene-triangles`), so that input larger than any the site uses is refused before it
/// fills the memory.
///
/// Passed down to every read rather than kept in a global, so that each load (and each test)
/// says which limits it reads under.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileLimits {
    /// The largest mesh file, in bytes; a `.gltf` file and the buffer files it names count
    /// together.
    pub mesh_bytes: u64,
    /// The largest config file (scene, hand model), in bytes.
    pub config_bytes: u64,
    /// The most triangles of a scene's parts together (a part that shares another's mesh counts
    /// too); a mesh file loaded on its own may have as many. Checked against the counts a file
    /// or a shape announces, before their triangles are read or built.
    pub scene_triangles: u64,
}

impl Default for FileLimits {
    /// 4 GiB for a mesh (more than a 20-million-triangle binary STL), 16 MiB for a config and
    /// 50 million triangles for a scene (some 5 GB of meshes and trees).
    fn default() -> Self {
        Self {
            mesh_bytes: 4 << 30,
            config_bytes: 16 << 20,
            scene_triangles: 50_000_000,
        }
    }
}

/// Reads a whole file of at most `limit` bytes, refusing anything but a regular file: a FIFO
/// would block the reader until a writer comes (forever, for a server's I/O thread), and a
/// device such as `/dev/zero` never ends. Symbolic links are followed to what they name.
pub fn read_regular_file(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    use std::io::Read;
    let kind = std::fs::metadata(path)?.file_type();
    if !kind.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "not a regular file (a directory, FIFO, socket or device)",
        ));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(limit + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(io::Error::new(
            io::ErrorKind::FileTooLarge,
            format!("larger than the {limit} bytes a file may have"),
        ));
    }
    Ok(bytes)
}

/// `read_regular_file` for UTF-8 text.
pub fn read_regular_text(path: &Path, limit: u64) -> io::Result<String> {
    String::from_utf8(read_regular_file(path, limit)?)
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidData, "not UTF-8 text"))
}

/// Why a config file (a hand model, a hand capture) was refused: the file, and what is wrong.
#[derive(Debug, Error)]
pub enum ConfigFileError {
    /// The file could not be read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// The file.
        file: PathBuf,
        /// The underlying error.
        source: io::Error,
    },
    /// The file is not valid in its format or does not have the expected keys and types.
    #[error("{file}: {message}")]
    Syntax {
        /// The file.
        file: PathBuf,
        /// The line, the offending text and the reason.
        message: String,
    },
    /// A value is present but not acceptable.
    #[error("{file}: {key}: {reason}")]
    Invalid {
        /// The file.
        file: PathBuf,
        /// The offending key, as a path such as `segment[3].dofs[0].axis`.
        key: String,
        /// What is wrong with it.
        reason: String,
    },
}

impl ConfigFileError {
    /// A [`ConfigFileError::Syntax`] of `file`.
    pub fn syntax(file: &Path, message: String) -> Self {
        ConfigFileError::Syntax {
            file: file.to_path_buf(),
            message,
        }
    }

    /// A [`ConfigFileError::Invalid`] of `file`.
    pub fn invalid(file: &Path, key: impl fmt::Display, reason: impl fmt::Display) -> Self {
        ConfigFileError::Invalid {
            file: file.to_path_buf(),
            key: key.to_string(),
            reason: reason.to_string(),
        }
    }
}

/// [`read_regular_text`] for a config file, its errors naming the file.
pub fn read_config_text(path: &Path, limit: u64) -> Result<String, ConfigFileError> {
    read_regular_text(path, limit).map_err(|source| ConfigFileError::Io {
        file: path.to_path_buf(),
        source,
    })
}
