//! A glTF mesh's triangles: its primitives of mode TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN,
//! indexed or not, in one vertex list. Points and lines are no surface and are left out.

use std::borrow::Cow;

use super::accessors;
use super::document::{Document, Primitive, TRIANGLE_FAN, TRIANGLE_STRIP, TRIANGLES};
use crate::geometry::io::RawMesh;

/// Whether `primitive` gives triangles (the other modes are points and lines).
pub(super) fn has_triangles(primitive: &Primitive) -> bool {
    matches!(primitive.mode, TRIANGLES | TRIANGLE_STRIP | TRIANGLE_FAN)
}

/// The triangles mesh `mesh` has, from its accessors' counts alone (nothing is read), each count
/// checked against the bytes of its buffer view.
pub(super) fn triangle_count(document: &Document, mesh: usize) -> Result<u64, String> {
    let mut total = 0u64;
    for (p, primitive) in mesh_of(document, mesh)?.primitives.iter().enumerate() {
        if !has_triangles(primitive) {
            continue;
        }
        let corners = match primitive.indices {
            Some(indices) => accessors::index_count(document, indices)?,
            None => accessors::position_count(document, position_accessor(primitive, mesh, p)?)?,
        };
        total = total.saturating_add(match primitive.mode {
            TRIANGLES => corners / 3,
            _ => corners.saturating_sub(2),
        });
    }
    Ok(total)
}

/// The vertices and triangles of mesh `mesh`, in the mesh's own frame.
pub(super) fn mesh_triangles(
    document: &Document,
    buffers: &[Cow<'_, [u8]>],
    mesh: usize,
) -> Result<RawMesh, String> {
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for (p, primitive) in mesh_of(document, mesh)?.primitives.iter().enumerate() {
        if !has_triangles(primitive) {
            continue;
        }
        let at = |reason: String| format!("mesh {mesh} primitive {p}: {reason}");
        let positions =
            accessors::positions(document, buffers, position_accessor(primitive, mesh, p)?)
                .map_err(at)?;
        let count = positions.len();
        let corners = match primitive.indices {
            Some(indices) => accessors::indices(document, buffers, indices).map_err(at)?,
            None => {
                (0..u32::try_from(count).map_err(|_| at("too many vertices".into()))?).collect()
            }
        };
        if let Some((i, corner)) = corners
            .iter()
            .enumerate()
            .find(|&(_, &c)| c as usize >= count)
        {
            return Err(at(format!(
                "index {i} is {corner}, beyond its {count} vertices"
            )));
        }
        if primitive.mode == TRIANGLES && corners.len() % 3 != 0 {
            return Err(at(format!(
                "{} indices of triangles, not a multiple of 3",
                corners.len()
            )));
        }
        let base = u32::try_from(vertices.len())
            .map_err(|_| at("more vertices than a u32 index can address".into()))?;
        let offset = |t: [u32; 3]| t.map(|c| base.saturating_add(c));
        match primitive.mode {
            TRIANGLES => {
                triangles.extend(corners.chunks_exact(3).map(|t| offset([t[0], t[1], t[2]])))
            }
            // Every other triangle of a strip turns the other way (glTF 2.0, 3.7.2.1).
            TRIANGLE_STRIP => triangles.extend(corners.windows(3).enumerate().map(|(i, w)| {
                offset(if i % 2 == 0 {
                    [w[0], w[1], w[2]]
                } else {
                    [w[1], w[0], w[2]]
                })
            })),
            _ => triangles.extend(
                corners
                    .windows(2)
                    .skip(1)
                    .map(|w| offset([w[0], w[1], corners[0]])),
            ),
        }
        vertices.extend(positions);
    }
    Ok((vertices, triangles))
}

/// Mesh `mesh` of `document`.
fn mesh_of(document: &Document, mesh: usize) -> Result<&super::document::Mesh, String> {
    document.meshes.get(mesh).ok_or_else(|| {
        format!(
            "mesh {mesh} does not exist (the file has {})",
            document.meshes.len()
        )
    })
}

/// The accessor of a triangle primitive's positions.
fn position_accessor(primitive: &Primitive, mesh: usize, p: usize) -> Result<usize, String> {
    primitive
        .attributes
        .get("POSITION")
        .copied()
        .ok_or_else(|| format!("mesh {mesh} primitive {p} has no POSITION attribute"))
}
