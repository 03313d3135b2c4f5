//! Reading meshes from OBJ, STL, PLY and glTF files, writing OBJ, and mesh specifications
//! (`shape:KIND:TRIANGLES` or a file path) as command lines and benchmarks take them.
//!
//! Loading never panics, whatever the bytes: a file that cannot be used gives a
//! [`GeometryError`] naming the file and the reason, and degenerate triangles are dropped with a
//! warning that names the file and the count. Counts that a file announces (a binary STL's, a
//! PLY header's, a glTF accessor's) are checked against the bytes present and the triangle limit
//! before anything is allocated for them.

mod files;
mod gltf;
mod obj;
mod ply;
mod spec;
mod stl;
mod toml_error;

use std::io;
use std::path::{Path, PathBuf};

use thiserror::Error;

use super::mesh::{MeshError, Point, TriMesh};
pub use files::{
    ConfigFileError, FileLimits, read_config_text, read_regular_file, read_regular_text,
};
pub use gltf::{GltfFile, GltfPart};
pub use obj::write_obj;
pub use spec::parse_mesh_spec;
pub use toml_error::describe_toml_error;

/// Why a mesh could not be read, written or built; every variant names the file (or the
/// specification) and the reason.
#[derive(Debug, Error)]
pub enum GeometryError {
    /// The file could not be read (missing, unreadable).
    #[error("cannot read mesh file {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: io::Error,
    },
    /// The file name ends in none of the extensions of the formats vas reads.
    #[error(
        "mesh file {}: unsupported format (expected a .obj, .stl, .ply, .gltf or .glb file)",
        path.display()
    )]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
    /// The file is not valid in its format.
    #[error("mesh file {}: {reason}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong with its contents.
        reason: String,
    },
    /// The file has more triangles than the limit allows.
    #[error(
        "mesh file {}: at least {count} triangles, more than the {allowed} allowed",
        path.display()
    )]
    TooManyTriangles {
        /// The file.
        path: PathBuf,
        /// How many triangles it announces or holds (a lower bound where its faces are
        /// polygons).
        count: u64,
        /// How many it may have.
        allowed: u64,
    },
    /// The file parsed, but its mesh is unusable (no triangles, non-finite coordinates,
    /// indices out of range).
    #[error("mesh file {}: {source}", path.display())]
    InvalidMesh {
        /// The file.
        path: PathBuf,
        /// What is wrong with the mesh.
        #[source]
        source: MeshError,
    },
    /// The file could not be written.
    #[error("cannot write mesh file {}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: io::Error,
    },
    /// A `shape:` specification that does not name a shape and a triangle count.
    #[error("mesh specification {spec:?}: {reason}")]
    BadSpec {
        /// The specification as given.
        spec: String,
        /// What is wrong with it.
        reason: String,
    },
}

/// Why a file's contents are refused, before the file's name is attached.
#[derive(Debug)]
enum ContentError {
    /// Not valid in the file's format: the reason.
    Malformed(String),
    /// More triangles than allowed: how many the file announces or holds.
    TooManyTriangles(u64),
}

impl From<String> for ContentError {
    fn from(reason: String) -> Self {
        ContentError::Malformed(reason)
    }
}

impl ContentError {
    /// The error of `path`, read under `limits`.
    fn of_file(self, path: &Path, limits: &FileLimits) -> GeometryError {
        match self {
            ContentError::Malformed(reason) => GeometryError::Parse {
                path: path.to_owned(),
                reason,
            },
            ContentError::TooManyTriangles(count) => GeometryError::TooManyTriangles {
                path: path.to_owned(),
                count,
                allowed: limits.scene_triangles,
            },
        }
    }
}

/// Vertices and triangles as a file gives them, before [`TriMesh::new`] checks them.
type RawMesh = (Vec<Point>, Vec<[u32; 3]>);

/// The formats vas reads, by file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Obj,
    Stl,
    Ply,
    /// `.gltf` (JSON, or binary whatever the extension) or `.glb` (binary).
    Gltf,
}

impl Format {
    /// The format of `path`, by its extension.
    fn of(path: &Path) -> Result<Format, GeometryError> {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("obj") => Ok(Format::Obj),
            Some("stl") => Ok(Format::Stl),
            Some("ply") => Ok(Format::Ply),
            Some("gltf" | "glb") => Ok(Format::Gltf),
            _ => Err(GeometryError::UnsupportedFormat {
                path: path.to_owned(),
            }),
        }
    }
}

/// Loads a triangle mesh from an `.obj`, `.stl` (binary or ASCII), `.ply` (ASCII or binary) or
/// `.gltf`/`.glb` file, chosen by extension.
///
/// All objects and groups of an OBJ file become one mesh that keeps the file's vertex sharing;
/// polygons (OBJ and PLY) are triangulated as fans. A glTF file becomes one mesh of every
/// triangle primitive of every node of its default scene, each placed by its node's world
/// transform. Normals, texture coordinates and materials are ignored. Degenerate triangles are
/// removed with a warning naming the file and the count. The file may have the
/// [default](FileLimits::default) size and triangle count at most.
pub fn load_mesh(path: &Path) -> Result<TriMesh, GeometryError> {
    load_mesh_within(path, &FileLimits::default())
}

/// [`load_mesh`] of a file of at most `limits.mesh_bytes` (a `.gltf` with its buffer files)
/// and `limits.scene_triangles` triangles.
pub fn load_mesh_within(path: &Path, limits: &FileLimits) -> Result<TriMesh, GeometryError> {
    let bytes = read_mesh_file(path, limits)?;
    mesh_from_bytes_within(path, &bytes, limits)
}

/// The bytes of the mesh file `path` (of a supported format, at most `limits.mesh_bytes`).
pub fn read_mesh_file(path: &Path, limits: &FileLimits) -> Result<Vec<u8>, GeometryError> {
    // An unsupported name is refused before the file is read.
    Format::of(path)?;
    read_regular_file(path, limits.mesh_bytes).map_err(|source| GeometryError::Read {
        path: path.to_owned(),
        source,
    })
}

/// [`load_mesh`] on a file's contents already read: `path` chooses the format by its extension
/// and names the file in errors and warnings (a `.gltf` file's buffer files are read relative
/// to it).
pub fn mesh_from_bytes(path: &Path, bytes: &[u8]) -> Result<TriMesh, GeometryError> {
    mesh_from_bytes_within(path, bytes, &FileLimits::default())
}

/// [`mesh_from_bytes`] under `limits`.
fn mesh_from_bytes_within(
    path: &Path,
    bytes: &[u8],
    limits: &FileLimits,
) -> Result<TriMesh, GeometryError> {
    let max_triangles = limits.scene_triangles;
    let raw = match Format::of(path)? {
        Format::Obj => obj::parse_obj(bytes),
        Format::Stl => stl::parse_stl(bytes, max_triangles),
        Format::Ply => ply::parse_ply(bytes, max_triangles),
        Format::Gltf => GltfFile::parse(path, bytes, limits)?.whole(max_triangles),
    };
    let (vertices, triangles) = raw.map_err(|error| error.of_file(path, limits))?;
    if triangles.len() as u64 > max_triangles {
        return Err(ContentError::TooManyTriangles(triangles.len() as u64).of_file(path, limits));
    }
    checked_mesh(path, vertices, triangles)
}

/// The mesh of `path`'s vertices and triangles, checked by [`TriMesh::new`]; degenerate
/// triangles are removed with a warning naming the file and the count.
fn checked_mesh(
    path: &Path,
    vertices: Vec<Point>,
    triangles: Vec<[u32; 3]>,
) -> Result<TriMesh, GeometryError> {
    let (mesh, report) =
        TriMesh::new(vertices, triangles).map_err(|source| GeometryError::InvalidMesh {
            path: path.to_owned(),
            source,
        })?;
    if report.degenerate_triangles_removed > 0 {
        tracing::warn!(
            file = %path.display(),
            removed = report.degenerate_triangles_removed,
            "removed degenerate triangles from the mesh"
        );
    }
    Ok(mesh)
}
