//! Reading accessors: vertex positions and triangle indices, each element checked to lie in the
//! bytes of its buffer view and buffer before any is read or anything allocated for them.

use std::borrow::Cow;

use super::document::{Accessor, Document};
use crate::geometry::mesh::Point;

/// Component types (glTF 2.0, 3.6.2.2).
const UNSIGNED_BYTE: u32 = 5121;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;
const FLOAT: u32 = 5126;

/// An accessor's elements in its buffer: `count` elements of `size` bytes, `stride` apart, from
/// the start of `bytes`.
struct Elements<'a> {
    bytes: &'a [u8],
    count: usize,
    stride: usize,
}

impl<'a> Elements<'a> {
    fn iter(&self, size: usize) -> impl Iterator<Item = &'a [u8]> + '_ {
        (0..self.count).map(move |i| &self.bytes[i * self.stride..i * self.stride + size])
    }
}

/// Accessor `index` of `document`, as a reader names it in errors.
fn accessor(document: &Document, index: usize) -> Result<&Accessor, String> {
    document.accessors.get(index).ok_or_else(|| {
        format!(
            "accessor {index} does not exist (the file has {})",
            document.accessors.len()
        )
    })
}

/// Where accessor `index`'s elements lie in its buffer view, checked against the document
/// alone: `count` elements of `size` bytes, `stride` apart, from `start` bytes into view `view`,
/// the last one ending within the view's length.
struct Extent {
    view: usize,
    start: u64,
    count: u64,
    stride: u64,
}

/// The extent of accessor `index`, whose elements must be of `kind` (`VEC3`, `SCALAR`) and of
/// `size` bytes: its count is checked against the bytes of its buffer view, so that a count
/// that the file does not hold is refused before anything is counted or read by it.
fn extent(document: &Document, index: usize, kind: &str, size: usize) -> Result<Extent, String> {
    let accessor = accessor(document, index)?;
    let name = || format!("accessor {index}");
    if accessor.kind != kind {
        return Err(format!("{} is a {}, not a {kind}", name(), accessor.kind));
    }
    if accessor.sparse.is_some() {
        return Err(format!("{} is sparse, which vas does not read", name()));
    }
    let view_index = accessor
        .buffer_view
        .ok_or_else(|| format!("{} has no buffer view", name()))?;
    let view = document
        .buffer_views
        .get(view_index)
        .ok_or_else(|| format!("{}'s buffer view {view_index} does not exist", name()))?;
    let stride = view.byte_stride.unwrap_or(size as u64);
    if stride < size as u64 {
        return Err(format!(
            "buffer view {view_index} has a stride of {stride} bytes, less than {}'s elements \
             of {size}",
            name()
        ));
    }
    // The last element's end, relative to the view.
    let end = accessor
        .count
        .checked_sub(1)
        .map_or(Some(accessor.byte_offset), |last| {
            last.checked_mul(stride)
                .and_then(|start| start.checked_add(size as u64))
                .and_then(|length| length.checked_add(accessor.byte_offset))
        });
    if end.is_none_or(|end| end > view.byte_length) {
        return Err(format!(
            "{} counts {} elements, more than the {} bytes of its buffer view {view_index} hold",
            name(),
            accessor.count,
            view.byte_length
        ));
    }
    Ok(Extent {
        view: view_index,
        start: accessor.byte_offset,
        count: accessor.count,
        stride,
    })
}

/// The bytes of accessor `index` ([`extent`]), its buffer view checked to lie within its
/// buffer.
fn elements<'a>(
    document: &Document,
    buffers: &'a [Cow<'_, [u8]>],
    index: usize,
    kind: &str,
    size: usize,
) -> Result<Elements<'a>, String> {
    let extent = extent(document, index, kind, size)?;
    let view = &document.buffer_views[extent.view];
    let buffer = buffers.get(view.buffer).ok_or_else(|| {
        format!(
            "buffer view {}'s buffer {} does not exist",
            extent.view, view.buffer
        )
    })?;
    let view_end = view.byte_offset.checked_add(view.byte_length);
    if view_end.is_none_or(|end| end > buffer.len() as u64) {
        return Err(format!(
            "buffer view {} ends beyond the {} bytes of its buffer {}",
            extent.view,
            buffer.len(),
            view.buffer
        ));
    }
    // Every figure is now within the buffer's length, so within usize.
    let start = (view.byte_offset + extent.start) as usize;
    let length = (view.byte_length - extent.start) as usize;
    Ok(Elements {
        bytes: &buffer[start..start + length],
        count: extent.count as usize,
        stride: extent.stride as usize,
    })
}

/// The bytes of a position (three floats), once the accessor is checked to hold floats.
fn position_size(document: &Document, index: usize) -> Result<usize, String> {
    let component_type = accessor(document, index)?.component_type;
    if component_type != FLOAT {
        return Err(format!(
            "accessor {index} of positions has component type {component_type}, not FLOAT \
             ({FLOAT})"
        ));
    }
    Ok(12)
}

/// The bytes of an index (an unsigned byte, short or int), by the accessor's component type.
fn index_size(document: &Document, index: usize) -> Result<usize, String> {
    match accessor(document, index)?.component_type {
        UNSIGNED_BYTE => Ok(1),
        UNSIGNED_SHORT => Ok(2),
        UNSIGNED_INT => Ok(4),
        component_type => Err(format!(
            "accessor {index} of indices has component type {component_type}, not an \
             unsigned integer"
        )),
    }
}

/// How many vertices a `POSITION` accessor holds, checked against its buffer view.
pub(super) fn position_count(document: &Document, index: usize) -> Result<u64, String> {
    Ok(extent(document, index, "VEC3", position_size(document, index)?)?.count)
}

/// How many indices an index accessor holds, checked against its buffer view.
pub(super) fn index_count(document: &Document, index: usize) -> Result<u64, String> {
    Ok(extent(document, index, "SCALAR", index_size(document, index)?)?.count)
}

/// The vertices of a `POSITION` accessor (three floats each); a non-finite coordinate is
/// refused.
pub(super) fn positions(
    document: &Document,
    buffers: &[Cow<'_, [u8]>],
    index: usize,
) -> Result<Vec<Point>, String> {
    let size = position_size(document, index)?;
    let elements = elements(document, buffers, index, "VEC3", size)?;
    let mut points = Vec::with_capacity(elements.count);
    for (vertex, bytes) in elements.iter(size).enumerate() {
        let coordinate =
            |i: usize| f64::from(f32::from_le_bytes(bytes[i..i + 4].try_into().expect("4")));
        let point = Point::new(coordinate(0), coordinate(4), coordinate(8));
        if !point.iter().all(|c| c.is_finite()) {
            return Err(format!(
                "accessor {index}: vertex {vertex} has a non-finite coordinate"
            ));
        }
        points.push(point);
    }
    Ok(points)
}

/// The values of an index accessor (unsigned bytes, shorts or ints).
pub(super) fn indices(
    document: &Document,
    buffers: &[Cow<'_, [u8]>],
    index: usize,
) -> Result<Vec<u32>, String> {
    let size = index_size(document, index)?;
    let elements = elements(document, buffers, index, "SCALAR", size)?;
    Ok(elements
        .iter(size)
        .map(|bytes| match *bytes {
            [a] => u32::from(a),
            [a, b] => u32::from(u16::from_le_bytes([a, b])),
            [a, b, c, d] => u32::from_le_bytes([a, b, c, d]),
            _ => unreachable!("elements of 1, 2 or 4 bytes"),
        })
        .collect())
}
