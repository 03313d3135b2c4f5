//! Mesh specifications as command lines and benchmarks take them: `shape:KIND:TRIANGLES` or a
//! file path.

use std::path::Path;

use super::super::mesh::TriMesh;
use super::super::shapes::{self, ShapeKind};
use super::{GeometryError, load_mesh};

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
