//! PLY (the Stanford polygon format): ASCII, and binary in either byte order.
//!
//! The reader takes the `vertex` element's `x`, `y` and `z` (of any numeric type; float or
//! double in practice) and the `face` element's `vertex_indices` (or `vertex_index`) lists,
//! triangulated as fans; every other element and property is read past. It is written for vas
//! rather than taken from a crate so that it keeps no per-element maps or lists (a face goes
//! straight into triangles) and so that every count in the header is checked against the bytes
//! that follow it before anything is allocated for it: a header that counts more elements than
//! the file holds, or fewer, is refused with the element and the figures.

use super::super::mesh::Point;
use super::{ContentError, RawMesh};

/// Parses a PLY file; a file whose header counts more faces than `max_triangles` (each face
/// gives one triangle at least), or whose faces give more, is refused.
pub(super) fn parse_ply(bytes: &[u8], max_triangles: u64) -> Result<RawMesh, ContentError> {
    let (header, body) = Header::parse(bytes)?;
    let vertex = header.element("vertex")?;
    let face = header.element("face")?;
    let coordinates = ["x", "y", "z"].map(|name| vertex.scalar(name));
    let corners = face.corner_list()?;
    header.check_counts(body.len())?;
    if face.count > max_triangles {
        return Err(ContentError::TooManyTriangles(face.count));
    }

    let mut body = Body::new(header.encoding, body);
    // The counts fit in the body (checked above), so these allocations are bounded by the file.
    let mut vertices = Vec::with_capacity(usize::try_from(vertex.count).unwrap_or(0));
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for element in &header.elements {
        for index in 0..element.count {
            let at = || format!("{} {index}", element.name);
            if std::ptr::eq(element, vertex) {
                let mut point = [0.0; 3];
                for (p, property) in element.properties.iter().enumerate() {
                    match coordinates.iter().position(|&c| c == Some(p)) {
                        Some(axis) => point[axis] = body.number(property.scalar()?, &at)?,
                        None => body.skip(property, &at)?,
                    }
                }
                vertices.push(Point::from(point));
            } else if std::ptr::eq(element, face) {
                for (p, property) in element.properties.iter().enumerate() {
                    if p == corners.property {
                        body.face(corners, vertex.count, &mut triangles, &at)?;
                        if triangles.len() as u64 > max_triangles {
                            return Err(ContentError::TooManyTriangles(triangles.len() as u64));
                        }
                    } else {
                        body.skip(property, &at)?;
                    }
                }
            } else {
                for property in &element.properties {
                    body.skip(property, &at)?;
                }
            }
        }
    }
    body.finish()?;
    Ok((vertices, triangles))
}

/// How the body after the header is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

/// The numeric types of PLY properties.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    /// The type a header names (both the old and the sized names).
    fn named(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    /// Bytes in a binary body.
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

/// A property of an element: one number, or a list of numbers preceded by its length.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Property {
    name: String,
    /// The number's type, or the list items' type.
    item: Scalar,
    /// The type of the list's length, for a list.
    list_length: Option<Scalar>,
}

impl Property {
    /// The type of a property that must be a single number.
    fn scalar(&self) -> Result<Scalar, String> {
        match self.list_length {
            None => Ok(self.item),
            Some(_) => Err(format!("property {} is a list, not a number", self.name)),
        }
    }

    /// The fewest bytes the property takes in the body: a binary number or list length, or in
    /// ASCII a digit and a separator.
    fn min_bytes(&self, encoding: Encoding) -> u64 {
        match encoding {
            Encoding::Ascii => 2,
            _ => self.list_length.unwrap_or(self.item).size() as u64,
        }
    }
}

/// An element of the header: its name, how many the body holds, and their properties.
#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
}

/// Where a face's corners are: the index of the list property and its types.
#[derive(Debug, Clone, Copy)]
struct CornerList {
    property: usize,
    length: Scalar,
    index: Scalar,
}

impl Element {
    /// The position of the single-number property `name`, if there is one.
    fn scalar(&self, name: &str) -> Option<usize> {
        self.properties
            .iter()
            .position(|p| p.name == name && p.list_length.is_none())
    }

    /// The `vertex_indices` (or `vertex_index`) list of a face element.
    fn corner_list(&self) -> Result<CornerList, String> {
        let property = self
            .properties
            .iter()
            .position(|p| p.name == "vertex_indices" || p.name == "vertex_index")
            .ok_or("the face element has no vertex_indices list")?;
        let p = &self.properties[property];
        match p.list_length {
            Some(length) if p.item.is_integer() => Ok(CornerList {
                property,
                length,
                index: p.item,
            }),
            _ => Err(format!(
                "the face property {} is not a list of integers",
                p.name
            )),
        }
    }
}

/// The header of a PLY file.
#[derive(Debug)]
struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
}

impl Header {
    /// The header at the start of `bytes`, and the body after it.
    fn parse(bytes: &[u8]) -> Result<(Header, &[u8]), String> {
        const END: &[u8] = b"end_header";
        if !(bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n")) {
            return Err("not a PLY file: it does not begin with the line \"ply\"".to_owned());
        }
        let mut encoding = None;
        let mut elements: Vec<Element> = Vec::new();
        let mut rest = bytes;
        let mut line_number = 0;
        loop {
            let Some(end) = rest.iter().position(|&b| b == b'\n') else {
                return Err("not a valid PLY file: the header has no end_header line".to_owned());
            };
            let line = String::from_utf8_lossy(&rest[..end]);
            let line = line.trim();
            rest = &rest[end + 1..];
            line_number += 1;
            let bad =
                |reason: &str| format!("not a valid PLY file: header line {line_number}: {reason}");
            let words: Vec<&str> = line.split_ascii_whitespace().collect();
            match words.as_slice() {
                ["ply"] if line_number == 1 => {}
                [] | ["comment" | "obj_info", ..] => {}
                ["format", format, "1.0"] => {
                    encoding = Some(match *format {
                        "ascii" => Encoding::Ascii,
                        "binary_little_endian" => Encoding::LittleEndian,
                        "binary_big_endian" => Encoding::BigEndian,
                        _ => return Err(bad("unknown format")),
                    });
                }
                ["element", name, count] => elements.push(Element {
                    name: (*name).to_owned(),
                    count: count
                        .parse()
                        .map_err(|_| bad("the count is not a number"))?,
                    properties: Vec::new(),
                }),
                ["property", rest @ ..] => {
                    let element = elements
                        .last_mut()
                        .ok_or_else(|| bad("a property before any element"))?;
                    let scalar =
                        |name: &str| Scalar::named(name).ok_or_else(|| bad("unknown type"));
                    let property = match rest {
                        ["list", length, item, name] => {
                            let length = scalar(length)?;
                            if !length.is_integer() {
                                return Err(bad("a list's length must be an integer"));
                            }
                            Property {
                                name: (*name).to_owned(),
                                item: scalar(item)?,
                                list_length: Some(length),
                            }
                        }
                        [kind, name] => Property {
                            name: (*name).to_owned(),
                            item: scalar(kind)?,
                            list_length: None,
                        },
                        _ => {
                            return Err(bad(
                                "expected property TYPE NAME or property list TYPE TYPE NAME",
                            ));
                        }
                    };
                    element.properties.push(property);
                }
                [word] if word.as_bytes() == END => break,
                _ => return Err(bad("not a header line")),
            }
        }
        let encoding = encoding.ok_or("not a valid PLY file: the header has no format line")?;
        Ok((Header { encoding, elements }, rest))
    }

    /// The element `name`, which a mesh needs.
    fn element(&self, name: &str) -> Result<&Element, String> {
        let element = self
            .elements
            .iter()
            .find(|e| e.name == name)
            .ok_or_else(|| format!("the file has no {name} element"))?;
        if name == "vertex" {
            for axis in ["x", "y", "z"] {
                if element.scalar(axis).is_none() {
                    return Err(format!("the vertex element has no {axis} property"));
                }
            }
        }
        Ok(element)
    }

    /// Refuses counts that the `body_length` bytes after the header cannot hold, before they
    /// are read, so that a lying header allocates nothing.
    fn check_counts(&self, body_length: usize) -> Result<(), String> {
        let mut left = body_length as u64;
        for element in &self.elements {
            let each: u64 = (element.properties.iter())
                .map(|p| p.min_bytes(self.encoding))
                .sum();
            if each == 0 && element.count > 0 {
                return Err(format!(
                    "the header counts {} {} elements, which have no properties",
                    element.count, element.name
                ));
            }
            let needed = element.count.checked_mul(each).filter(|&n| n <= left);
            let Some(needed) = needed else {
                return Err(format!(
                    "the header counts {} {} elements, more than the {} bytes after the header \
                     can hold",
                    element.count, element.name, body_length
                ));
            };
            left -= needed;
        }
        Ok(())
    }
}

/// The body after the header, read in order.
struct Body<'a> {
    encoding: Encoding,
    bytes: &'a [u8],
    /// The bytes read so far.
    position: usize,
}

impl<'a> Body<'a> {
    fn new(encoding: Encoding, bytes: &'a [u8]) -> Self {
        Body {
            encoding,
            bytes,
            position: 0,
        }
    }

    /// The next number, of type `scalar`, as a float; `at` names the element for errors.
    fn number(&mut self, scalar: Scalar, at: &dyn Fn() -> String) -> Result<f64, String> {
        if self.encoding == Encoding::Ascii {
            let token = self.token(at)?;
            return token
                .parse::<f64>()
                .map_err(|_| format!("{}: a word that is not a number", at()));
        }
        let size = scalar.size();
        let bytes = self
            .bytes
            .get(self.position..self.position + size)
            .ok_or_else(|| format!("the file ends in {}", at()))?;
        self.position += size;
        let mut word = [0u8; 8];
        word[..size].copy_from_slice(bytes);
        if self.encoding == Encoding::BigEndian {
            word[..size].reverse();
        }
        let [a, b, c, d, ..] = word;
        Ok(match scalar {
            Scalar::I8 => f64::from(a as i8),
            Scalar::U8 => f64::from(a),
            Scalar::I16 => f64::from(i16::from_le_bytes([a, b])),
            Scalar::U16 => f64::from(u16::from_le_bytes([a, b])),
            Scalar::I32 => f64::from(i32::from_le_bytes([a, b, c, d])),
            Scalar::U32 => f64::from(u32::from_le_bytes([a, b, c, d])),
            Scalar::F32 => f64::from(f32::from_le_bytes([a, b, c, d])),
            Scalar::F64 => f64::from_le_bytes(word),
        })
    }

    /// The next number, which must be a whole number (a list length or an index).
    fn integer(&mut self, scalar: Scalar, at: &dyn Fn() -> String) -> Result<i64, String> {
        let value = self.number(scalar, at)?;
        if value.fract() != 0.0 || !value.is_finite() || value.abs() > 2f64.powi(53) {
            return Err(format!(
                "{}: {} is not a whole number",
                at(),
                vas_protocol::Readable(value)
            ));
        }
        Ok(value as i64)
    }

    /// The next ASCII word.
    fn token(&mut self, at: &dyn Fn() -> String) -> Result<&'a str, String> {
        let rest = &self.bytes[self.position..];
        let start = rest
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .ok_or_else(|| format!("the file ends in {}", at()))?;
        let length = rest[start..]
            .iter()
            .position(u8::is_ascii_whitespace)
            .unwrap_or(rest.len() - start);
        self.position += start + length;
        std::str::from_utf8(&rest[start..start + length])
            .map_err(|_| format!("{}: a word that is not text", at()))
    }

    /// Reads past a property.
    fn skip(&mut self, property: &Property, at: &dyn Fn() -> String) -> Result<(), String> {
        let items = match property.list_length {
            Some(length) => self.list_length(length, property.item, at)?,
            None => 1,
        };
        for _ in 0..items {
            self.number(property.item, at)?;
        }
        Ok(())
    }

    /// A list's length, checked against the bytes left for its items.
    fn list_length(
        &mut self,
        length: Scalar,
        item: Scalar,
        at: &dyn Fn() -> String,
    ) -> Result<u64, String> {
        let count = self.integer(length, at)?;
        let each = match self.encoding {
            Encoding::Ascii => 2,
            _ => item.size() as i64,
        };
        let left = (self.bytes.len() - self.position) as i64;
        if count < 0 || count.saturating_mul(each) > left {
            return Err(format!(
                "{}: a list of {count} items, more than the file holds",
                at()
            ));
        }
        Ok(count as u64)
    }

    /// A face's corners, as a fan of triangles appended to `triangles`; every corner must be one
    /// of the `vertex_count` vertices.
    fn face(
        &mut self,
        corners: CornerList,
        vertex_count: u64,
        triangles: &mut Vec<[u32; 3]>,
        at: &dyn Fn() -> String,
    ) -> Result<(), String> {
        let count = self.list_length(corners.length, corners.index, at)?;
        if count < 3 {
            return Err(format!(
                "{}: {count} corners; a face needs 3 at least",
                at()
            ));
        }
        let mut corner = || -> Result<u32, String> {
            let index = self.integer(corners.index, at)?;
            u32::try_from(index)
                .ok()
                .filter(|&i| u64::from(i) < vertex_count)
                .ok_or_else(|| {
                    format!(
                        "{}: corner {index} is not one of the {vertex_count} vertices",
                        at()
                    )
                })
        };
        let first = corner()?;
        let mut previous = corner()?;
        for _ in 2..count {
            let next = corner()?;
            triangles.push([first, previous, next]);
            previous = next;
        }
        Ok(())
    }

    /// Refuses data after the last element the header counts.
    fn finish(self) -> Result<(), String> {
        let rest = &self.bytes[self.position..];
        let trailing = match self.encoding {
            Encoding::Ascii => rest.iter().any(|b| !b.is_ascii_whitespace()),
            _ => !rest.is_empty(),
        };
        if trailing {
            return Err(format!(
                "{} bytes follow the last element the header counts (a count too small?)",
                rest.len()
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangles_of(text: &str) -> Vec<[u32; 3]> {
        parse_ply(text.as_bytes(), 100).unwrap().1
    }

    #[test]
    fn polygons_become_fans_and_other_elements_are_read_past() {
        let text = "ply\nformat ascii 1.0\ncomment a quad and a pentagon\n\
                    element vertex 6\nproperty float x\nproperty uchar red\nproperty float y\n\
                    property float z\nelement face 2\nproperty uchar flags\n\
                    property list uchar int vertex_indices\nelement edge 1\n\
                    property list uchar int vertex_index\nend_header\n\
                    0 1 0 0\n1 1 0 0\n1 1 1 0\n0 1 1 0\n2 1 0 0\n2 1 1 0\n\
                    7 4 0 1 2 3\n7 5 1 4 5 2 3\n2 0 1\n";
        let (vertices, triangles) = parse_ply(text.as_bytes(), 100).unwrap();
        assert_eq!(vertices[5], Point::new(2.0, 1.0, 0.0));
        assert_eq!(
            triangles,
            [[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2], [1, 2, 3]]
        );
    }

    #[test]
    fn binary_bodies_of_either_byte_order_read_alike() {
        let header = |order: &str| {
            format!(
                "ply\r\nformat binary_{order}_endian 1.0\r\nelement vertex 3\r\n\
                 property double x\r\nproperty double y\r\nproperty float z\r\n\
                 element face 1\r\nproperty list uchar uint vertex_indices\r\nend_header\r\n"
            )
        };
        let corners: [[f64; 3]; 3] = [[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [0.0, 2.0, -1.0]];
        let mut expected = Vec::new();
        for big in [false, true] {
            let mut file = header(if big { "big" } else { "little" }).into_bytes();
            for [x, y, z] in corners {
                let (x, y, z) = if big {
                    (x.to_be_bytes(), y.to_be_bytes(), (z as f32).to_be_bytes())
                } else {
                    (x.to_le_bytes(), y.to_le_bytes(), (z as f32).to_le_bytes())
                };
                file.extend(x.into_iter().chain(y).chain(z));
            }
            file.push(3);
            for i in [0u32, 1, 2] {
                file.extend(if big {
                    i.to_be_bytes()
                } else {
                    i.to_le_bytes()
                });
            }
            let (vertices, triangles) = parse_ply(&file, 10).unwrap();
            assert_eq!(triangles, [[0, 1, 2]]);
            expected.push(vertices);
        }
        assert_eq!(expected[0], expected[1]);
        assert_eq!(expected[0][2], Point::new(0.0, 2.0, -1.0));
    }

    #[test]
    fn lying_counts_and_bad_corners_are_refused() {
        let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\nelement face";
        let body = "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        let list = "property list uchar int vertex_indices\n";
        let refusal = |text: String| match parse_ply(text.as_bytes(), 100) {
            Err(ContentError::Malformed(reason)) => reason,
            other => panic!("{other:?}"),
        };
        assert_eq!(
            triangles_of(&format!("{head} 1\n{list}{body}")),
            [[0, 1, 2]]
        );
        let many = refusal(format!("{head} 1000000000000\n{list}{body}"));
        assert!(
            many.contains("1000000000000 face elements, more than"),
            "{many}"
        );
        let few = refusal(format!("{head} 0\n{list}{body}"));
        assert!(few.contains("follow the last element"), "{few}");
        let out = refusal(format!(
            "{head} 1\n{list}{}",
            body.replace("3 0 1 2", "3 0 1 3")
        ));
        assert!(
            out.contains("face 0: corner 3 is not one of the 3 vertices"),
            "{out}"
        );
        let short = refusal(format!(
            "{head} 1\n{list}{}",
            body.replace("3 0 1 2", "2 0 1")
        ));
        assert!(short.contains("face 0: 2 corners"), "{short}");
        let long = refusal(format!(
            "{head} 1\n{list}{}",
            body.replace("3 0 1 2", "9 0 1 2")
        ));
        assert!(long.contains("face 0: a list of 9 items"), "{long}");
        assert!(matches!(
            parse_ply(format!("{head} 2\n{list}{body}3 2 1 0\n").as_bytes(), 1),
            Err(ContentError::TooManyTriangles(2))
        ));
    }
}
