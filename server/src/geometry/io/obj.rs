//! Wavefront OBJ: reading with tobj, and writing.

use std::fmt::Write as _;
use std::io::Cursor;
use std::path::Path;

use super::super::mesh::{Point, TriMesh};
use super::{ContentError, GeometryError, RawMesh};

/// Parses OBJ text with tobj.
///
/// Only `v` and `f` records reach tobj: positions are all vas uses, and dropping the other
/// records keeps every group in one vertex index space (so vertices shared between groups stay
/// shared) and keeps tobj away from texture and normal indices, which it does not range-check
/// before doing arithmetic on them.
pub(super) fn parse_obj(bytes: &[u8]) -> Result<RawMesh, ContentError> {
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
