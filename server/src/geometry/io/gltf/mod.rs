//! glTF 2.0, as a `.gltf` (JSON, with its buffers in files beside it or in `data:` URIs) or a
//! `.glb` (binary) file: one mesh of the whole scene ([`load_mesh`](super::load_mesh)), or its
//! mesh nodes as separate parts ([`GltfFile::parts`], a scene's `[[assemblies]]`).
//!
//! Triangles come from primitives of mode TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN; points
//! and lines are skipped with a warning. Materials, textures, skins, morph targets, animations
//! and cameras are ignored.

mod accessors;
mod buffers;
mod document;
mod glb;
mod nodes;
mod parts;
mod primitives;

use std::borrow::Cow;
use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Matrix4, Point3};

use super::{ContentError, FileLimits, GeometryError, RawMesh, checked_mesh};
use crate::geometry::mesh::TriMesh;
use document::Document;
use nodes::MeshNode;
pub use parts::GltfPart;

/// A glTF file read and checked: its document, its buffers and its mesh nodes.
#[derive(Debug)]
pub struct GltfFile<'a> {
    path: PathBuf,
    document: Document,
    buffers: Vec<Cow<'a, [u8]>>,
    nodes: Vec<MeshNode>,
}

impl<'a> GltfFile<'a> {
    /// The glTF file `path` whose contents are `bytes` (GLB if they begin with its magic or the
    /// name ends in `.glb`, else JSON): its document, the buffers it names (read within
    /// `limits.mesh_bytes`, together with `bytes`) and its scene graph.
    pub fn parse(
        path: &Path,
        bytes: &'a [u8],
        limits: &FileLimits,
    ) -> Result<GltfFile<'a>, GeometryError> {
        let error = |reason: String| GeometryError::Parse {
            path: path.to_owned(),
            reason,
        };
        let binary = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
        let (json, bin) = if binary || bytes.starts_with(glb::MAGIC) {
            let glb = glb::split(bytes).map_err(error)?;
            (glb.json, glb.bin)
        } else {
            (bytes, None)
        };
        let document = Document::parse(json).map_err(error)?;
        let buffers =
            buffers::load(&document, path, bin, limits, bytes.len() as u64).map_err(error)?;
        let nodes = nodes::mesh_nodes(&document).map_err(error)?;
        let skipped: usize = (nodes.iter())
            .flat_map(|node| &document.meshes[node.mesh].primitives)
            .filter(|primitive| !primitives::has_triangles(primitive))
            .count();
        if skipped > 0 {
            tracing::warn!(
                file = %path.display(),
                skipped,
                "skipped point and line primitives (no surface to collide with)"
            );
        }
        Ok(GltfFile {
            path: path.to_owned(),
            document,
            buffers,
            nodes,
        })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn error(&self, reason: String) -> GeometryError {
        GeometryError::Parse {
            path: self.path.clone(),
            reason,
        }
    }

    /// The mesh nodes of the scene as parts, in the order of the scene graph's walk (depth
    /// first, roots and children in order), named by `unique_names` (`<file
    /// stem>/node<index>` for a node without a name). Nodes whose mesh has no triangle
    /// primitive, and nodes scaled to nothing (a zero scale) or beyond any size, are left out
    /// with a warning.
    pub fn parts(&self) -> Vec<GltfPart> {
        let stem = self
            .path
            .file_stem()
            .map_or("gltf".into(), |s| s.to_string_lossy());
        let named: Vec<(usize, Option<&str>)> = (self.nodes.iter())
            .map(|n| (n.node, self.document.nodes[n.node].name.as_deref()))
            .collect();
        let names = parts::unique_names(&stem, &named);
        let mut parts = Vec::with_capacity(self.nodes.len());
        for (node, name) in self.nodes.iter().zip(names) {
            let mesh_primitives = &self.document.meshes[node.mesh].primitives;
            if !mesh_primitives.iter().any(primitives::has_triangles) {
                tracing::warn!(
                    file = %self.path.display(),
                    node = name,
                    "a node whose mesh has no triangles is not a part"
                );
                continue;
            }
            let Some((pose, shape)) = parts::split_world(&node.world) else {
                tracing::warn!(
                    file = %self.path.display(),
                    node = name,
                    "a node scaled to nothing (or beyond any size) is not a part"
                );
                continue;
            };
            parts.push(GltfPart {
                name,
                node: node.node,
                mesh: node.mesh,
                pose,
                shape,
            });
        }
        parts
    }

    /// How many triangles mesh `mesh` has, from the file's counts (nothing is read).
    pub fn triangle_count(&self, mesh: usize) -> Result<u64, GeometryError> {
        primitives::triangle_count(&self.document, mesh).map_err(|e| self.error(e))
    }

    /// Mesh `mesh` with `shape` applied to its vertices (the triangles turned over when `shape`
    /// mirrors, so that they keep facing out), checked as [`TriMesh::new`] checks meshes.
    pub fn mesh(&self, mesh: usize, shape: &Matrix3<f64>) -> Result<TriMesh, GeometryError> {
        let (vertices, triangles) = primitives::mesh_triangles(&self.document, &self.buffers, mesh)
            .map_err(|e| self.error(e))?;
        let mut placed = (Vec::new(), Vec::new());
        append_placed(&mut placed, &vertices, &triangles, &shape.to_homogeneous());
        checked_mesh(&self.path, placed.0, placed.1)
    }

    /// Every mesh node's triangles, placed by its world transform, in one mesh; a scene of more
    /// than `max_triangles` is refused before any is read.
    pub(super) fn whole(&self, max_triangles: u64) -> Result<RawMesh, ContentError> {
        let mut counts = HashMap::new();
        let mut total = 0u64;
        for node in &self.nodes {
            let count = match counts.entry(node.mesh) {
                Entry::Occupied(known) => *known.get(),
                Entry::Vacant(slot) => {
                    *slot.insert(primitives::triangle_count(&self.document, node.mesh)?)
                }
            };
            total = total.saturating_add(count);
        }
        if total > max_triangles {
            return Err(ContentError::TooManyTriangles(total));
        }
        let mut meshes: HashMap<usize, RawMesh> = HashMap::new();
        let mut whole = (Vec::new(), Vec::new());
        for node in &self.nodes {
            let (vertices, triangles) = match meshes.entry(node.mesh) {
                Entry::Occupied(known) => known.into_mut(),
                Entry::Vacant(slot) => slot.insert(primitives::mesh_triangles(
                    &self.document,
                    &self.buffers,
                    node.mesh,
                )?),
            };
            append_placed(&mut whole, vertices, triangles, &node.world);
        }
        Ok(whole)
    }
}

/// Appends `vertices` and `triangles` to `mesh`, the vertices mapped by the affine `transform`
/// and the triangles turned over when it mirrors.
fn append_placed(
    mesh: &mut RawMesh,
    vertices: &[Point3<f64>],
    triangles: &[[u32; 3]],
    transform: &Matrix4<f64>,
) {
    let base = u32::try_from(mesh.0.len()).unwrap_or(u32::MAX);
    let mirrors = transform.fixed_view::<3, 3>(0, 0).determinant() < 0.0;
    mesh.0
        .extend(vertices.iter().map(|v| transform.transform_point(v)));
    mesh.1.extend(triangles.iter().map(|&[a, b, c]| {
        let turned = if mirrors { [a, c, b] } else { [a, b, c] };
        turned.map(|i| base.saturating_add(i))
    }));
}
