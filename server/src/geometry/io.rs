//! Reading meshes from OBJ and STL files, writing OBJ, and mesh specifications
//! (`shape:KIND:TRIANGLES` or a file path) as command lines and benchmarks take them.
//!
//! Loading never panics, whatever the bytes: a file that cannot be used gives a
//! [`GeometryError`] naming the file and the reason, and degenerate triangles are dropped with a
//! warning that names the file and the count.

use std::fmt::Write as _;
use std::io::{self, Cursor};
use std::path::{Path, PathBuf};

use thiserror::Error;

use super::mesh::{MeshError, Point, TriMesh};
use super::shapes::{self, ShapeKind};

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
    /// The file name ends in neither `.obj` nor `.stl`.
    #[error("mesh file {}: unsupported format (expected a .obj or .stl file)", path.display())]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
    /// The file is not valid OBJ or STL.
    #[error("mesh file {}: {reason}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong with its contents.
        reason: String,
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

/// The largest files the loaders read, by kind: a setting of the deployment (`vas-server
/// --max-mesh-file`, `--max-config-file`), so that a file that is larger than any the site
/// uses is refused before it fills the memory.
///
/// Passed down to every read rather than kept in a global, so that each load (and each test)
/// says which limits it reads under.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileLimits {
    /// The largest mesh file, in bytes.
    pub mesh_bytes: u64,
    /// The largest config file (scene, hand model), in bytes.
    pub config_bytes: u64,
}

impl Default for FileLimits {
    /// 4 GiB for a mesh (more than a 20-million-triangle binary STL) and 16 MiB for a config.
    fn default() -> Self {
        Self {
            mesh_bytes: 4 << 30,
            config_bytes: 16 << 20,
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

/// [`read_regular_file`] for UTF-8 text.
pub fn read_regular_text(path: &Path, limit: u64) -> io::Result<String> {
    String::from_utf8(read_regular_file(path, limit)?)
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidData, "not UTF-8 text"))
}

/// The longest excerpt of a file that an error message quotes, in characters.
const MAX_EXCERPT_CHARS: usize = 120;

/// A config's TOML error in one line: the line number, the offending line (cut to
/// [`MAX_EXCERPT_CHARS`], so that a file of one 50 MB line does not come back as a 50 MB
/// message) and the parser's reason.
pub fn describe_toml_error(text: &str, error: &toml::de::Error) -> String {
    let reason = error.message().trim();
    match error.span() {
        Some(span) => {
            let start = span.start.min(text.len());
            let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
            let line_number = text[..start].matches('\n').count() + 1;
            let line = text[line_start..].lines().next().unwrap_or("").trim();
            let mut excerpt: String = line.chars().take(MAX_EXCERPT_CHARS).collect();
            if excerpt.len() < line.len() {
                excerpt.push('…');
            }
            format!("line {line_number} (`{excerpt}`): {reason}")
        }
        None => reason.to_owned(),
    }
}

/// Loads a triangle mesh from an `.obj` or `.stl` (binary or ASCII) file, chosen by extension.
///
/// All objects and groups of an OBJ file become one mesh that keeps the file's vertex sharing;
/// polygons are triangulated as fans. Normals, texture coordinates and materials are ignored.
/// Degenerate triangles are removed with a warning naming the file and the count. The file may
/// have the [default](FileLimits::default) size at most.
pub fn load_mesh(path: &Path) -> Result<TriMesh, GeometryError> {
    load_mesh_within(path, &FileLimits::default())
}

/// [`load_mesh`] of a file of at most `limits.mesh_bytes`.
pub fn load_mesh_within(path: &Path, limits: &FileLimits) -> Result<TriMesh, GeometryError> {
    // An unsupported name is refused before the file is read.
    mesh_parser(path)?;
    let bytes =
        read_regular_file(path, limits.mesh_bytes).map_err(|source| GeometryError::Read {
            path: path.to_owned(),
            source,
        })?;
    mesh_from_bytes(path, &bytes)
}

/// [`load_mesh`] on a file's contents already read: `path` chooses the format by its extension
/// and names the file in errors and warnings.
pub fn mesh_from_bytes(path: &Path, bytes: &[u8]) -> Result<TriMesh, GeometryError> {
    let (vertices, triangles) =
        mesh_parser(path)?(bytes).map_err(|reason| GeometryError::Parse {
            path: path.to_owned(),
            reason,
        })?;
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

/// Parses a file's bytes into vertices and triangles as the file gives them.
type Parser = fn(&[u8]) -> Result<RawMesh, String>;

/// The parser of `path`'s format, by its extension.
fn mesh_parser(path: &Path) -> Result<Parser, GeometryError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("obj") => Ok(parse_obj),
        Some("stl") => Ok(parse_stl),
        _ => Err(GeometryError::UnsupportedFormat {
            path: path.to_owned(),
        }),
    }
}

/// A binary STL (one that does not begin as ASCII STL does) must hold exactly the triangles its
/// header counts: the reader stops at the count, so a count smaller than the data would drop
/// triangles silently.
fn check_binary_stl_length(bytes: &[u8]) -> Result<(), String> {
    /// The header's 80 bytes and the triangle count's 4; then 50 bytes a triangle.
    const HEADER: usize = 84;
    const TRIANGLE: usize = 50;
    if bytes.starts_with(b"solid") || bytes.len() < HEADER {
        return Ok(());
    }
    let count = u32::from_le_bytes(bytes[80..HEADER].try_into().expect("four bytes"));
    let expected = (count as usize)
        .checked_mul(TRIANGLE)
        .and_then(|data| data.checked_add(HEADER));
    if expected.is_some_and(|expected| bytes.len() > expected) {
        return Err(format!(
            "not a valid STL file: its header counts {count} triangles, but it holds {} bytes, \
             room for {} triangles",
            bytes.len(),
            (bytes.len() - HEADER) / TRIANGLE
        ));
    }
    Ok(())
}

/// Vertices and triangles as a file gives them, before [`TriMesh::new`] checks them.
type RawMesh = (Vec<Point>, Vec<[u32; 3]>);

/// Parses OBJ text with tobj.
///
/// Only `v` and `f` records reach tobj: positions are all vas uses, and dropping the other
/// records keeps every group in one vertex index space (so vertices shared between groups stay
/// shared) and keeps tobj away from texture and normal indices, which it does not range-check
/// before doing arithmetic on them.
fn parse_obj(bytes: &[u8]) -> Result<RawMesh, String> {
    let text = String::from_utf8_lossy(bytes);
    let mut geometry = String::with_capacity(text.len());
    for line in text.lines() {
        if matches!(line.split_whitespace().next(), Some("v" | "f")) {
            geometry.push_str(line);
            geometry.push('\n');
        }
    }
    let options = tobj::LoadOptions {
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj_buf(&mut Cursor::new(geometry), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| format!("not a valid OBJ file: {e}"))?;
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for model in models {
        let base = u32::try_from(vertices.len())
            .map_err(|_| "more vertices than a u32 index can address".to_owned())?;
        let positions = &model.mesh.positions;
        vertices.extend(
            positions
                .chunks_exact(3)
                .map(|c| Point::new(c[0], c[1], c[2])),
        );
        triangles.extend(
            model
                .mesh
                .indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]].map(|i| base.saturating_add(i))),
        );
    }
    Ok((vertices, triangles))
}

/// Parses binary or ASCII STL with stl_io (which merges bit-identical vertices).
fn parse_stl(bytes: &[u8]) -> Result<RawMesh, String> {
    check_binary_stl_length(bytes)?;
    let stl = stl_io::read_stl(&mut Cursor::new(bytes))
        .map_err(|e| format!("not a valid STL file: {e}"))?;
    let vertices = stl
        .vertices
        .iter()
        .map(|v| Point::from(v.0.map(f64::from)))
        .collect();
    let triangles = stl
        .faces
        .iter()
        .map(|f| f.vertices.map(|i| u32::try_from(i).unwrap_or(u32::MAX)))
        .collect();
    Ok((vertices, triangles))
}

/// Writes `mesh` as a Wavefront OBJ file (`v` and `f` records, coordinates in shortest
/// round-trip form, so that loading the file gives back exactly the same mesh).
pub fn write_obj(mesh: &TriMesh, path: &Path) -> Result<(), GeometryError> {
    let mut text = String::new();
    let _ = writeln!(
        text,
        "# {} vertices, {} triangles",
        mesh.vertices().len(),
        mesh.triangles().len()
    );
    for v in mesh.vertices() {
        let _ = writeln!(text, "v {} {} {}", v.x, v.y, v.z);
    }
    for [a, b, c] in mesh.triangles() {
        let _ = writeln!(text, "f {} {} {}", a + 1, b + 1, c + 1);
    }
    std::fs::write(path, text).map_err(|source| GeometryError::Write {
        path: path.to_owned(),
        source,
    })
}

/// Resolves a mesh specification: `shape:KIND:TRIANGLES` builds a procedural shape of unit size
/// (see [`shapes::build`]), anything else is a file path for [`load_mesh`].
pub fn parse_mesh_spec(spec: &str) -> Result<TriMesh, GeometryError> {
    let Some(rest) = spec.strip_prefix("shape:") else {
        return load_mesh(Path::new(spec));
    };
    let bad = |reason: String| GeometryError::BadSpec {
        spec: spec.to_owned(),
        reason,
    };
    let (kind, count) = rest
        .split_once(':')
        .ok_or_else(|| bad("expected shape:KIND:TRIANGLES".to_owned()))?;
    let kind: ShapeKind = kind.parse().map_err(|e| bad(format!("{e}")))?;
    let triangles: usize = count
        .parse()
        .map_err(|_| bad(format!("{count:?} is not a triangle count")))?;
    if !(1..=shapes::MAX_TRIANGLES).contains(&triangles) {
        return Err(bad(format!(
            "the triangle count must be between 1 and {}",
            shapes::MAX_TRIANGLES
        )));
    }
    Ok(shapes::build(kind, triangles))
}
