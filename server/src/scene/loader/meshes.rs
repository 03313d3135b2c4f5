//! The loader's meshes: files read ahead in parallel, procedural shapes, the scene's triangle
//! budget, and meshes shared between parts with their trees.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use vas_protocol::Readable;

use super::Loader;
use crate::geometry::shapes::ShapeSpec;
use crate::geometry::{FileLimits, GeometryError, Point, TriMesh, load_mesh_within};
use crate::scene::file::PartFile;
use crate::scene::{PartTree, SceneError};

impl Loader<'_> {
    pub(super) fn mesh_file(
        &mut self,
        index: usize,
        relative: &Path,
        scale: Option<f64>,
    ) -> Result<(Arc<TriMesh>, String, PartTree), SceneError> {
        let scale = scale.unwrap_or(1.0);
        if !(scale.is_finite() && scale > 0.0) {
            return Err(self.invalid(
                format!("parts[{index}].scale"),
                format!("must be a positive number, not {}", Readable(scale)),
            ));
        }
        let key = format!("parts[{index}].mesh");
        self.one_line(&key, relative)?;
        let path = self.folder.join(relative);
        let source = path.display().to_string();
        let cache_key = format!("{source} x {scale}");
        if let Some((mesh, tree)) = self.cached(&cache_key) {
            self.count_triangles(&key, mesh.triangles().len() as u64)?;
            return Ok((mesh, source, tree));
        }
        let mesh_error = |source| SceneError::Mesh {
            file: self.path.to_owned(),
            key: key.clone(),
            source,
        };
        let within = FileLimits {
            scene_triangles: self.triangles_left(),
            ..*self.limits
        };
        let loaded = match self.read_ahead.remove(&path) {
            // Refused for its share of the limit only: read again with all the parts before
            // it leave.
            Some(Err(GeometryError::TooManyTriangles { .. })) | None => {
                load_mesh_within(&path, &within)
            }
            Some(read) => read,
        };
        let mut mesh = match loaded {
            Err(GeometryError::TooManyTriangles { count, .. }) => {
                return Err(self.too_many_triangles(&key, count));
            }
            loaded => loaded.map_err(mesh_error)?,
        };
        if scale != 1.0 {
            // Uniform scaling keeps the triangles' shapes; only extreme scales can make some
            // degenerate, and a mesh with none left is refused.
            mesh = mesh
                .map_vertices(|v| Point::from(v.coords * scale))
                .map_err(|source| {
                    mesh_error(GeometryError::InvalidMesh {
                        path: path.clone(),
                        source,
                    })
                })?;
        }
        self.count_triangles(&key, mesh.triangles().len() as u64)?;
        let (mesh, tree) = self.remember(cache_key, mesh);
        Ok((mesh, source, tree))
    }

    pub(super) fn shape(
        &mut self,
        index: usize,
        shape: ShapeSpec,
    ) -> Result<(Arc<TriMesh>, String, PartTree), SceneError> {
        let key = format!("parts[{index}].shape");
        let source = shape.to_string();
        if let Some((mesh, tree)) = self.cached(&source) {
            self.count_triangles(&key, mesh.triangles().len() as u64)?;
            return Ok((mesh, source, tree));
        }
        // The requested count, before the shape is built (which meets it within a few percent).
        let requested = shape.triangles() as u64;
        if requested > self.triangles_left() {
            return Err(self.too_many_triangles(&key, requested));
        }
        let mesh = shape
            .build()
            .map_err(|e| self.invalid(format!("{key}.{}", e.field), e.reason))?;
        self.count_triangles(&key, mesh.triangles().len() as u64)?;
        let (mesh, tree) = self.remember(source.clone(), mesh);
        Ok((mesh, source, tree))
    }

    /// Reads the mesh files `parts` name, each once, on all of rayon's threads, ahead of the
    /// parts, which are then made in order: their triangles are counted against the scene's
    /// limit, and the first bad part is reported, as if each file were read in its turn.
    ///
    /// The files read at once share what the limit leaves: each claims, before it is read, its
    /// share (one per thread) of the triangles not claimed yet, and is refused beyond it, so
    /// that all read ahead stay within the limit together; a file refused for its share is read
    /// again in its turn, with all the parts before it leave.
    pub(super) fn read_ahead(&mut self, parts: &[PartFile]) {
        use rayon::prelude::*;
        let mut paths: Vec<PathBuf> = (parts.iter())
            .filter(|part| part.shape.is_none())
            .filter_map(|part| part.mesh.as_ref().map(|mesh| self.folder.join(mesh)))
            .collect();
        paths.sort_unstable();
        paths.dedup();
        let threads = rayon::current_num_threads().max(1) as u64;
        let limits = *self.limits;
        let claimed = std::sync::Mutex::new(0u64);
        let claims = || {
            claimed
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
        };
        self.read_ahead = (paths.into_par_iter().with_max_len(1))
            .map(|path| {
                let share = {
                    let mut claimed = claims();
                    let share = limits.scene_triangles.saturating_sub(*claimed) / threads;
                    *claimed += share;
                    share
                };
                let within = FileLimits {
                    scene_triangles: share,
                    ..limits
                };
                let read = load_mesh_within(&path, &within);
                let used = read
                    .as_ref()
                    .map_or(0, |mesh| mesh.triangles().len() as u64);
                *claims() -= share - used.min(share);
                (path, read)
            })
            .collect();
    }

    /// How many triangles the next part may have within the scene's limit.
    pub(super) fn triangles_left(&self) -> u64 {
        self.limits.scene_triangles.saturating_sub(self.triangles)
    }

    /// Adds the `count` triangles of the part at `key` to the scene's, refusing the part if the
    /// scene would have more than its limit.
    pub(super) fn count_triangles(&mut self, key: &str, count: u64) -> Result<(), SceneError> {
        if count > self.triangles_left() {
            return Err(self.too_many_triangles(key, count));
        }
        self.triangles += count;
        Ok(())
    }

    /// The refusal of the part at `key`, whose `count` triangles the scene's limit has no room for.
    pub(super) fn too_many_triangles(&self, key: &str, count: u64) -> SceneError {
        self.invalid(
            key,
            format!(
                "the part needs at least {count} triangles, but the scene's limit of {} \
                 triangles (--max-scene-triangles) leaves {} after the parts before it",
                self.limits.scene_triangles,
                self.triangles_left()
            ),
        )
    }

    /// The mesh loaded or built for `key` before, with its tree.
    pub(super) fn cached(&self, key: &str) -> Option<(Arc<TriMesh>, PartTree)> {
        self.meshes.get(key).cloned()
    }

    /// Keeps `mesh` for `key`, with a tree for it that every part using it shares. A mesh
    /// equal to one kept before (from another file, shape or node) is that one: its tree is
    /// built once.
    pub(super) fn remember(&mut self, key: String, mesh: TriMesh) -> (Arc<TriMesh>, PartTree) {
        let same_content = self.by_content.entry(mesh.content_hash()).or_default();
        let entry = match same_content.iter().find(|(kept, _)| **kept == mesh) {
            Some(kept) => kept.clone(),
            None => {
                let entry = (
                    Arc::new(mesh),
                    PartTree::new(self.orientations, self.tree_cache.clone()),
                );
                same_content.push(entry.clone());
                entry
            }
        };
        self.meshes.insert(key, entry.clone());
        entry
    }
}
