//! Render geometry on `vas/scene/geometry`: every part's mesh and every hand segment's mesh, so
//! that a renderer draws from the wire alone and never reads the server's files.
//!
//! One sample carries a whole scene generation: a [`GeometryHeader`] user header over a byte
//! slice in the layout below. The service keeps it as history, so a renderer that joins late, or
//! after a load or reset (each makes a new generation), gets the current geometry at once.
//!
//! The payload is a sequence of little-endian fields, each 4 bytes or a multiple (so a browser
//! can view positions as a `Float32Array` in place):
//!
//! ```text
//! payload  := mesh{part_count} hand{hand_count}          parts in id order
//! hand     := user:u32 side:u32 segment_count:u32 name mesh{segment_count}
//!             segments in HandSegment order; hands grouped by user, in the users' order
//! mesh     := name vertex_count:u32 triangle_count:u32 normals:u32 (0 or 1) 0:u32
//!             position:[f32;3]{vertex_count} normal:[f32;3]{vertex_count if normals}
//!             triangle:[u32;3]{triangle_count}
//! name     := byte_len:u32 utf8 bytes, zero-padded to a multiple of 4
//! ```
//!
//! A part's mesh is in the part's own frame with its scale applied (place it at the part's pose);
//! a segment's mesh is in the segment's frame (place it at the segment's pose in the hand frame).

use iceoryx2::prelude::ZeroCopySend;

use crate::HandSide;

/// The user header of a geometry sample.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, ZeroCopySend)]
#[type_name("vas::scene::GeometryHeader::v2")]
#[repr(C)]
pub struct GeometryHeader {
    /// Changes with every scene load and reset; frames of the same scene carry no generation,
    /// the geometry stays until the next one.
    pub generation: u64,
    /// Bytes of the payload.
    pub byte_len: u64,
    /// Part meshes, one per part id.
    pub part_count: u32,
    /// Hands, each with its segment meshes.
    pub hand_count: u32,
}

/// Longest name written; longer ones are cut at a character boundary.
pub const MAX_MESH_NAME_BYTES: usize = 256;

/// A triangle mesh for drawing.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshData {
    /// The part's or segment's name.
    pub name: String,
    /// Vertex positions in metres, in the mesh's own frame.
    pub positions: Vec<[f32; 3]>,
    /// Unit normals, one per position, or empty (the renderer computes them).
    pub normals: Vec<[f32; 3]>,
    /// Vertex indices of each triangle. CAD meshes may be polygon soups whose winding means
    /// nothing: draw both sides.
    pub triangles: Vec<[u32; 3]>,
}

impl MeshData {
    /// The smallest and largest coordinates of the positions, or `None` without positions.
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let first = *self.positions.first()?;
        Some(self.positions.iter().fold((first, first), |(lo, hi), p| {
            (
                std::array::from_fn(|i| lo[i].min(p[i])),
                std::array::from_fn(|i| hi[i].max(p[i])),
            )
        }))
    }
}

/// One hand's segment meshes.
#[derive(Debug, Clone, PartialEq)]
pub struct HandGeometry {
    /// Whose hand: an index into the scene's users
    /// ([`ControlResponse::users`](crate::ControlResponse::users)).
    pub user: u32,
    /// Which hand.
    pub side: HandSide,
    /// The hand model's name.
    pub model: String,
    /// Each segment's mesh in its own frame, in [`crate::HandSegment`] order.
    pub segments: Vec<MeshData>,
}

/// Everything a renderer draws of a scene generation.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneGeometry {
    /// See [`GeometryHeader::generation`].
    pub generation: u64,
    /// Each part's mesh, by part id.
    pub parts: Vec<MeshData>,
    /// Each hand's segment meshes.
    pub hands: Vec<HandGeometry>,
}

/// Why a geometry payload could not be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum GeometryDecodeError {
    /// The payload ends before the field.
    #[error("the geometry payload ends at byte {at} inside {field}")]
    Truncated {
        /// Byte offset where the field starts.
        at: usize,
        /// The field.
        field: &'static str,
    },
    /// Bytes are left after the last mesh.
    #[error("the geometry payload has {0} bytes after its last mesh")]
    TrailingBytes(usize),
    /// A field holds a value no writer produces.
    #[error("invalid geometry field {field} = {value} at byte {at}")]
    Invalid {
        /// Byte offset of the field.
        at: usize,
        /// The field.
        field: &'static str,
        /// Its value.
        value: u64,
    },
}

impl SceneGeometry {
    /// The header of this geometry's sample.
    pub fn header(&self) -> GeometryHeader {
        GeometryHeader {
            generation: self.generation,
            byte_len: self.encoded_len() as u64,
            part_count: count(self.parts.len()),
            hand_count: count(self.hands.len()),
        }
    }

    /// Bytes of this geometry's payload: what [`SceneGeometry::encode_into`] writes.
    pub fn encoded_len(&self) -> usize {
        let parts: usize = self.parts.iter().map(MeshData::encoded_len).sum();
        let hands: usize = (self.hands.iter())
            .map(|hand| {
                12 + name_len(&hand.model)
                    + hand
                        .segments
                        .iter()
                        .map(MeshData::encoded_len)
                        .sum::<usize>()
            })
            .sum();
        parts + hands
    }

    /// Writes the payload into `out`, which must be [`SceneGeometry::encoded_len`] bytes long:
    /// a publisher writes it straight into a loaned sample, with no copy between.
    ///
    /// # Panics
    /// If `out` has another length.
    pub fn encode_into(&self, out: &mut [u8]) {
        assert_eq!(out.len(), self.encoded_len(), "geometry payload length");
        let mut out = Writer { bytes: out, at: 0 };
        for part in &self.parts {
            out.mesh(part);
        }
        for hand in &self.hands {
            out.u32(hand.user);
            out.u32(hand.side as u32);
            out.u32(count(hand.segments.len()));
            out.name(&hand.model);
            for segment in &hand.segments {
                out.mesh(segment);
            }
        }
    }

    /// The header and payload of this geometry's sample.
    pub fn encode(&self) -> (GeometryHeader, Vec<u8>) {
        let header = self.header();
        let mut bytes = vec![0; header.byte_len as usize];
        self.encode_into(&mut bytes);
        (header, bytes)
    }

    /// Reads a sample's payload, checking every count against the bytes there are (a corrupt
    /// sample cannot make it allocate more than the payload holds), every index against its
    /// mesh's vertices and every coordinate for being finite.
    pub fn decode(header: &GeometryHeader, bytes: &[u8]) -> Result<Self, GeometryDecodeError> {
        let mut input = Reader { bytes, at: 0 };
        let parts = (0..header.part_count)
            .map(|_| input.mesh())
            .collect::<Result<_, _>>()?;
        let hands = (0..header.hand_count)
            .map(|_| {
                let at = input.at;
                let user = input.u32("hand user")?;
                if user as usize >= crate::MAX_USERS {
                    return Err(GeometryDecodeError::Invalid {
                        at,
                        field: "hand user",
                        value: user.into(),
                    });
                }
                let at = input.at;
                let side = input.u32("hand side")?;
                let side = HandSide::try_from(side).map_err(|_| GeometryDecodeError::Invalid {
                    at,
                    field: "hand side",
                    value: side.into(),
                })?;
                let segments = input.u32("segment count")?;
                let model = input.name()?;
                let segments = (0..segments)
                    .map(|_| input.mesh())
                    .collect::<Result<_, _>>()?;
                Ok(HandGeometry {
                    user,
                    side,
                    model,
                    segments,
                })
            })
            .collect::<Result<_, GeometryDecodeError>>()?;
        match bytes.len() - input.at {
            0 => Ok(Self {
                generation: header.generation,
                parts,
                hands,
            }),
            left => Err(GeometryDecodeError::TrailingBytes(left)),
        }
    }
}

fn count(len: usize) -> u32 {
    u32::try_from(len).expect("meshes hold fewer than 2^32 elements")
}

impl MeshData {
    /// Whether the normals are written: one per position.
    fn has_normals(&self) -> bool {
        self.normals.len() == self.positions.len() && !self.normals.is_empty()
    }

    /// Bytes of this mesh in a payload.
    fn encoded_len(&self) -> usize {
        let floats = self.positions.len() * if self.has_normals() { 2 } else { 1 };
        name_len(&self.name) + 16 + 12 * (floats + self.triangles.len())
    }
}

/// The bytes of `name` that are written: at most [`MAX_MESH_NAME_BYTES`], cut at a character
/// boundary.
fn written_name(name: &str) -> &[u8] {
    let mut end = name.len().min(MAX_MESH_NAME_BYTES);
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    &name.as_bytes()[..end]
}

/// Bytes of a name field.
fn name_len(name: &str) -> usize {
    4 + written_name(name).len().next_multiple_of(4)
}

/// Writes a payload front to back into a buffer of its exact length.
struct Writer<'a> {
    bytes: &'a mut [u8],
    at: usize,
}

impl Writer<'_> {
    fn put(&mut self, bytes: &[u8]) {
        self.bytes[self.at..self.at + bytes.len()].copy_from_slice(bytes);
        self.at += bytes.len();
    }

    fn u32(&mut self, value: u32) {
        self.put(&value.to_le_bytes());
    }

    fn name(&mut self, name: &str) {
        let bytes = written_name(name);
        self.u32(count(bytes.len()));
        self.put(bytes);
        let padded = bytes.len().next_multiple_of(4);
        self.put(&[0; 3][..padded - bytes.len()]);
    }

    /// Writes `values` as little-endian 4-byte words.
    fn words<T: Copy>(&mut self, values: impl Iterator<Item = T>, to_le: fn(T) -> [u8; 4]) {
        for (chunk, value) in self.bytes[self.at..].chunks_exact_mut(4).zip(values) {
            chunk.copy_from_slice(&to_le(value));
            self.at += 4;
        }
    }

    fn mesh(&mut self, mesh: &MeshData) {
        let normals = mesh.has_normals();
        self.name(&mesh.name);
        self.u32(count(mesh.positions.len()));
        self.u32(count(mesh.triangles.len()));
        self.u32(u32::from(normals));
        self.u32(0);
        let floats = (mesh.positions.iter())
            .chain(mesh.normals.iter().filter(|_| normals))
            .flatten()
            .copied();
        self.words(floats, f32::to_le_bytes);
        self.words(mesh.triangles.iter().flatten().copied(), u32::to_le_bytes);
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, len: usize, field: &'static str) -> Result<&[u8], GeometryDecodeError> {
        let truncated = GeometryDecodeError::Truncated { at: self.at, field };
        let end = self.at.checked_add(len).ok_or(truncated.clone())?;
        let taken = self.bytes.get(self.at..end).ok_or(truncated)?;
        self.at = end;
        Ok(taken)
    }

    fn u32(&mut self, field: &'static str) -> Result<u32, GeometryDecodeError> {
        let bytes = self.take(4, field)?;
        Ok(u32::from_le_bytes(bytes.try_into().expect("4 bytes")))
    }

    fn name(&mut self) -> Result<String, GeometryDecodeError> {
        let at = self.at;
        let len = self.u32("name length")? as usize;
        if len > MAX_MESH_NAME_BYTES {
            return Err(GeometryDecodeError::Invalid {
                at,
                field: "name length",
                value: len as u64,
            });
        }
        let bytes = self.take(len.next_multiple_of(4), "name")?;
        String::from_utf8(bytes[..len].to_vec()).map_err(|_| GeometryDecodeError::Invalid {
            at: at + 4,
            field: "name (not UTF-8)",
            value: len as u64,
        })
    }

    /// `count` triples of 4-byte values, checked to fit before anything is allocated.
    fn triples<T>(
        &mut self,
        count: u32,
        field: &'static str,
        read: impl Fn([u8; 4]) -> T,
    ) -> Result<Vec<[T; 3]>, GeometryDecodeError> {
        let bytes = self.take(count as usize * 12, field)?;
        Ok(bytes
            .chunks_exact(12)
            .map(|triple| {
                std::array::from_fn(|i| read(triple[4 * i..4 * i + 4].try_into().expect("4")))
            })
            .collect())
    }

    fn mesh(&mut self) -> Result<MeshData, GeometryDecodeError> {
        let name = self.name()?;
        let vertices = self.u32("vertex count")?;
        let triangles = self.u32("triangle count")?;
        let at = self.at;
        let normals = self.u32("normals flag")?;
        if normals > 1 {
            return Err(GeometryDecodeError::Invalid {
                at,
                field: "normals flag",
                value: normals.into(),
            });
        }
        self.u32("reserved")?;
        let floats_at = self.at;
        let positions = self.triples(vertices, "positions", f32::from_le_bytes)?;
        let normals = self.triples(vertices * normals, "normals", f32::from_le_bytes)?;
        if let Some(bad) = positions
            .iter()
            .chain(&normals)
            .flatten()
            .position(|v| !v.is_finite())
        {
            return Err(GeometryDecodeError::Invalid {
                at: floats_at + 4 * bad,
                field: "coordinate (not finite)",
                value: 0,
            });
        }
        let indices_at = self.at;
        let triangles = self.triples(triangles, "triangles", u32::from_le_bytes)?;
        if let Some(bad) = triangles.iter().flatten().position(|&i| i >= vertices) {
            return Err(GeometryDecodeError::Invalid {
                at: indices_at + 4 * bad,
                field: "vertex index",
                value: triangles.as_flattened()[bad].into(),
            });
        }
        Ok(MeshData {
            name,
            positions,
            normals,
            triangles,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(name: &str, normals: bool) -> MeshData {
        let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.5, -2.0]];
        MeshData {
            name: name.to_owned(),
            normals: if normals {
                vec![[0.0, 0.0, 1.0]; 3]
            } else {
                Vec::new()
            },
            positions,
            triangles: vec![[0, 1, 2]],
        }
    }

    fn geometry() -> SceneGeometry {
        SceneGeometry {
            generation: 7,
            parts: vec![mesh("peg", false), mesh("bloc\u{e9}", true)],
            hands: vec![HandGeometry {
                user: 2,
                side: HandSide::Left,
                model: "left hand".into(),
                segments: vec![mesh("palm", false), mesh("thumb", true)],
            }],
        }
    }

    #[test]
    fn geometry_decodes_to_what_was_encoded() {
        let geometry = geometry();
        let (header, bytes) = geometry.encode();
        assert_eq!(header.byte_len as usize, bytes.len());
        assert_eq!(bytes.len() % 4, 0);
        assert_eq!(SceneGeometry::decode(&header, &bytes), Ok(geometry));
    }

    #[test]
    fn every_cut_of_the_payload_is_refused() {
        let (header, bytes) = geometry().encode();
        for len in 0..bytes.len() {
            assert!(
                SceneGeometry::decode(&header, &bytes[..len]).is_err(),
                "cut at {len}"
            );
        }
        let mut longer = bytes.clone();
        longer.extend_from_slice(&[0; 4]);
        assert_eq!(
            SceneGeometry::decode(&header, &longer),
            Err(GeometryDecodeError::TrailingBytes(4))
        );
    }

    #[test]
    fn bad_indices_coordinates_and_counts_are_refused() {
        let mut bad_index = geometry();
        bad_index.parts[0].triangles[0][2] = 3;
        let mut not_finite = geometry();
        not_finite.hands[0].segments[1].positions[1][0] = f32::NAN;
        for geometry in [bad_index, not_finite] {
            let (header, bytes) = geometry.encode();
            assert!(matches!(
                SceneGeometry::decode(&header, &bytes),
                Err(GeometryDecodeError::Invalid { .. })
            ));
        }
        // A vertex count far beyond the payload is refused before anything is allocated.
        let (header, mut bytes) = geometry().encode();
        let count_at = 4 + "peg".len().next_multiple_of(4);
        bytes[count_at..count_at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(
            SceneGeometry::decode(&header, &bytes),
            Err(GeometryDecodeError::Truncated { .. })
        ));
    }

    #[test]
    fn bounds_span_the_positions() {
        assert_eq!(
            mesh("m", false).bounds(),
            Some(([0.0, 0.0, -2.0], [1.0, 1.5, 0.0]))
        );
        assert_eq!(MeshData::default().bounds(), None);
    }
}
