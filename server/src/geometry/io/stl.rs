//! STL, binary or ASCII, read with stl_io.

use std::io::Cursor;

use super::super::mesh::Point;
use super::{ContentError, RawMesh};

/// The header's 80 bytes and the triangle count's 4; then 50 bytes a triangle.
const HEADER: usize = 84;
/// The bytes of one triangle of a binary STL.
const TRIANGLE: usize = 50;

/// Parses binary or ASCII STL with stl_io (which merges bit-identical vertices); a binary file
/// whose header counts more than `max_triangles` is refused before it is read.
pub(super) fn parse_stl(bytes: &[u8], max_triangles: u64) -> Result<RawMesh, ContentError> {
    if let Some(count) = binary_stl_count(bytes)?
        && count > max_triangles
    {
        return Err(ContentError::TooManyTriangles(count));
    }
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

/// The triangle count of a binary STL's header (`None` for a file that begins as ASCII STL does,
/// or is too short for a header). The file must hold no more than the triangles it counts: the
/// reader stops at the count, so a count smaller than the data would drop triangles silently.
fn binary_stl_count(bytes: &[u8]) -> Result<Option<u64>, ContentError> {
    if bytes.starts_with(b"solid") || bytes.len() < HEADER {
        return Ok(None);
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
        )
        .into());
    }
    Ok(Some(u64::from(count)))
}
