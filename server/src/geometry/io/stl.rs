//! STL, binary or ASCII: stl_io reads the triangles, and vertices with bit-identical
//! coordinates are merged here.

use std::io::Cursor;

use rustc_hash::FxHashMap;

use super::super::mesh::Point;
use super::{ContentError, RawMesh};

/// The header's 80 bytes and the triangle count's 4; then 50 bytes a triangle.
const HEADER: usize = 84;
/// The bytes of one triangle of a binary STL.
const TRIANGLE: usize = 50;

/// Parses binary or ASCII STL, merging vertices whose coordinates are bit-identical (an STL
/// file repeats every corner in each triangle that has it); a binary file whose header counts
/// more than `max_triangles` is refused before it is read, an ASCII one when it gets there.
///
/// The merge is a hash map keyed by the coordinates' bits with a fast hash, sized from a
/// binary file's count: what stl_io's own indexing does, with a hash several times cheaper,
/// which matters on an assembly's millions of triangles.
pub(super) fn parse_stl(bytes: &[u8], max_triangles: u64) -> Result<RawMesh, ContentError> {
    let announced = binary_stl_count(bytes)?;
    if let Some(count) = announced
        && count > max_triangles
    {
        return Err(ContentError::TooManyTriangles(count));
    }
    // The kind of error only: stl_io's own messages quote the offending line of the file.
    let invalid = |e: std::io::Error| format!("not a valid STL file: {}", e.kind());
    let mut cursor = Cursor::new(bytes);
    let reader = stl_io::create_stl_reader(&mut cursor).map_err(invalid)?;
    // A closed mesh has about half as many vertices as triangles.
    let expected = announced.unwrap_or(0) as usize;
    let mut index_of: FxHashMap<[u32; 3], u32> =
        FxHashMap::with_capacity_and_hasher(expected / 2, Default::default());
    let mut vertices: Vec<Point> = Vec::with_capacity(expected / 2);
    let mut triangles: Vec<[u32; 3]> = Vec::with_capacity(expected);
    for triangle in reader {
        let triangle = triangle.map_err(invalid)?;
        if triangles.len() as u64 == max_triangles {
            return Err(ContentError::TooManyTriangles(max_triangles + 1));
        }
        triangles.push(triangle.vertices.map(|vertex| {
            *index_of
                .entry(vertex.0.map(f32::to_bits))
                .or_insert_with(|| {
                    vertices.push(Point::from(vertex.0.map(f64::from)));
                    // Three vertices a triangle at most: within u32 under any triangle limit a
                    // file's size allows.
                    (vertices.len() - 1) as u32
                })
        }));
    }
    Ok((vertices, triangles))
}

/// The triangle count of a binary STL's header (`None` for a file that begins as ASCII STL does,
/// or is too short for a header). The file must hold exactly the triangles it counts: a count
/// larger than the data would have memory reserved for triangles that are not there, and a
/// count smaller than the data would drop triangles silently (the reader stops at the count).
fn binary_stl_count(bytes: &[u8]) -> Result<Option<u64>, ContentError> {
    if bytes.starts_with(b"solid") || bytes.len() < HEADER {
        return Ok(None);
    }
    let count = u32::from_le_bytes(bytes[80..HEADER].try_into().expect("four bytes"));
    let data = bytes.len() - HEADER;
    if u64::from(count) * TRIANGLE as u64 != data as u64 {
        return Err(format!(
            "not a valid STL file: the triangle count in its binary header does not match its \
             {} bytes (an {HEADER}-byte header and {TRIANGLE} bytes a triangle: room for {})",
            bytes.len(),
            data / TRIANGLE
        )
        .into());
    }
    Ok(Some(u64::from(count)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The header's 80 bytes, `count`, and `triangles` zeroed triangles.
    fn binary(count: u32, triangles: usize) -> Vec<u8> {
        let mut bytes = vec![0; 80];
        bytes.extend(count.to_le_bytes());
        bytes.resize(bytes.len() + triangles * TRIANGLE, 0);
        bytes
    }

    #[test]
    fn a_count_beyond_the_bytes_present_is_refused_before_anything_is_reserved() {
        // 84 bytes announcing 49,999,999 triangles: about 1.8 GB reserved before the fix.
        for (count, present) in [(49_999_999, 0), (u32::MAX, 1), (3, 2), (1, 2)] {
            match parse_stl(&binary(count, present), u64::MAX) {
                Err(ContentError::Malformed(reason)) => assert!(
                    reason.contains(&format!("room for {present})")),
                    "{count}: {reason}"
                ),
                other => panic!("{count} announced, {present} present: {other:?}"),
            }
        }
        assert_eq!(parse_stl(&binary(2, 2), 10).unwrap().1.len(), 2);
    }
}
