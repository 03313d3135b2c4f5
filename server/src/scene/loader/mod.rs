//! Loading a scene config: read, parse, validate every key, load or build each part's mesh, and
//! either return the whole scene or refuse it with the file, the key and the reason.

mod assembly;
mod meshes;
mod users;

use std::collections::{BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use vas_protocol::Readable;

use super::file::{GroupsFile, PartFile, SceneFile};
use super::groups::sorted_pair;
use super::params::Problem;
use super::{Groups, Part, PartTree, QUATERNION_NORM_TOLERANCE, Scene, SceneError};
use crate::collision::dop_tree::TreeCache;
use crate::geometry::{FileLimits, GeometryError, TriMesh, describe_toml_error, read_regular_text};

pub(super) use assembly::AssemblyFile;

/// How a scene is loaded: the largest files it may read, and where its trees are cached.
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// The largest files read.
    pub limits: FileLimits,
    /// The folder of built trees (`--tree-cache`), if any.
    pub tree_cache: Option<Arc<TreeCache>>,
}

impl From<FileLimits> for LoadOptions {
    fn from(limits: FileLimits) -> Self {
        LoadOptions {
            limits,
            tree_cache: None,
        }
    }
}

impl Scene {
    /// Loads and validates the scene config at `path`. Mesh paths (and the hand model) are
    /// relative to the config's folder. Each file may have the [default](FileLimits::default)
    /// size at most.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Scene::load_with(path, &LoadOptions::default())
    }

    /// [`Scene::load`] of files (config, meshes, hand model) within `options`' limits, with its
    /// trees in `options`' cache.
    pub fn load_with(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
        let text = read_regular_text(path, options.limits.config_bytes).map_err(|source| {
            SceneError::Read {
                file: path.to_owned(),
                source,
            }
        })?;
        Scene::from_toml(path, &text, options)
    }

    /// [`Scene::load_with`] on a config's text already read from `path`: errors name `path`,
    /// and mesh and hand paths are relative to its folder.
    pub fn from_toml(path: &Path, text: &str, options: &LoadOptions) -> Result<Scene, SceneError> {
        let file: SceneFile = toml::from_str(text).map_err(|e| SceneError::Syntax {
            file: path.to_owned(),
            message: describe_toml_error(text, &e),
        })?;
        Loader {
            path,
            folder: path.parent().unwrap_or(Path::new("")),
            limits: &options.limits,
            tree_cache: options.tree_cache.clone(),
            meshes: HashMap::new(),
            by_content: HashMap::new(),
            read_ahead: HashMap::new(),
            orientations: file.params.dop_orientations,
            triangles: 0,
        }
        .scene(file)
    }
}

/// Validation state while loading one scene.
struct Loader<'a> {
    path: &'a Path,
    folder: &'a Path,
    /// The largest files read.
    limits: &'a FileLimits,
    /// Where the parts' trees are cached.
    tree_cache: Option<Arc<TreeCache>>,
    /// Meshes already loaded or built, with their trees, by source, so that parts sharing one
    /// are loaded once and share its tree.
    meshes: HashMap<String, (Arc<TriMesh>, PartTree)>,
    /// The same meshes by [content hash](TriMesh::content_hash) (several for a collision).
    by_content: HashMap<u64, Vec<(Arc<TriMesh>, PartTree)>>,
    /// Mesh files read ahead of their parts ([`Loader::read_ahead`]), by path, until a part
    /// takes its file.
    read_ahead: HashMap<PathBuf, Result<TriMesh, GeometryError>>,
    /// The scene's DOP orientation count, for the parts' trees.
    orientations: usize,
    /// The triangles of the parts so far, against [`FileLimits::scene_triangles`].
    triangles: u64,
}

impl Loader<'_> {
    fn invalid(&self, key: impl Into<String>, reason: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            file: self.path.to_owned(),
            key: key.into(),
            reason: reason.into(),
        }
    }

    /// `value` checked as a name: not blank, and one line without control characters, so that
    /// no message naming it could carry a line of the file (refusals name keys, never values).
    fn name(&self, key: &str, value: &str) -> Result<(), SceneError> {
        if value.trim().is_empty() {
            return Err(self.invalid(key, "must not be empty"));
        }
        self.one_line(key, Path::new(value))
    }

    /// `path` checked to be one line without control characters: messages quote the paths of
    /// files that could not be read, and a path must not carry a line of the file with it.
    fn one_line(&self, key: &str, path: &Path) -> Result<(), SceneError> {
        if path.to_string_lossy().chars().any(char::is_control) {
            return Err(self.invalid(key, "must be one line, without control characters"));
        }
        Ok(())
    }

    fn problem(&self, problem: Problem) -> SceneError {
        self.invalid(problem.key, problem.reason)
    }

    /// The whole scene of `file`, or the first thing wrong with it.
    fn scene(mut self, file: SceneFile) -> Result<Scene, SceneError> {
        self.name("name", &file.name)?;
        file.params.validate().map_err(|p| self.problem(p))?;
        file.rates.validate().map_err(|p| self.problem(p))?;
        let parts = self.parts(file.parts, file.assemblies)?;
        let groups = self.groups(&parts, &file.groups)?;
        // Loaded here, so that whatever loads a scene (check-scene, run, a load-scene request)
        // refuses a broken hand model the same way.
        let (users, hands) = self.users(file.hand, file.hands, file.users)?;
        Ok(Scene {
            name: file.name,
            source: self.path.to_owned(),
            parts,
            users,
            hands,
            params: file.params,
            rates: file.rates,
            groups,
        })
    }

    /// The `[[parts]]`, then each assembly's parts, in order; every name used once (checked
    /// against a map of the names so far, so that a 100,000-node assembly loads in linear time).
    fn parts(
        &mut self,
        listed: Vec<PartFile>,
        assemblies: Vec<AssemblyFile>,
    ) -> Result<Vec<Part>, SceneError> {
        self.read_ahead(&listed);
        let mut parts: Vec<Part> = Vec::with_capacity(listed.len());
        let mut names: HashMap<String, usize> = HashMap::with_capacity(listed.len());
        for (index, part) in listed.into_iter().enumerate() {
            let part = self.part(index, part)?;
            if let Some(&first) = names.get(&part.name) {
                return Err(self.invalid(
                    format!("parts[{index}].name"),
                    format!("is the name of parts[{first}] too"),
                ));
            }
            names.insert(part.name.clone(), parts.len());
            parts.push(part);
        }
        for (index, assembly) in assemblies.into_iter().enumerate() {
            for part in self.assembly(index, assembly)? {
                if let Some(&first) = names.get(&part.name) {
                    return Err(self.invalid(
                        format!("assemblies[{index}]"),
                        format!("{} has the name of part {first}", part.mesh_source),
                    ));
                }
                names.insert(part.name.clone(), parts.len());
                parts.push(part);
            }
        }
        Ok(parts)
    }

    /// The groups the parts name, and the `[groups]` rules, each naming known groups and parts.
    fn groups(&self, parts: &[Part], rules: &GroupsFile) -> Result<Groups, SceneError> {
        let names: Vec<String> = parts
            .iter()
            .map(|p| p.group.clone())
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        if names.len() >= usize::from(u16::MAX) {
            return Err(self.invalid(
                "parts",
                format!(
                    "name {} collision groups; at most {} fit",
                    names.len(),
                    u16::MAX - 1
                ),
            ));
        }
        let mut not_of_interest = Vec::with_capacity(rules.not_of_interest.len());
        for (index, [a, b]) in rules.not_of_interest.iter().enumerate() {
            let find_group = |group: &String| names.contains(group);
            if !(find_group(a) && find_group(b)) {
                return Err(self.invalid(
                    format!("groups.not_of_interest[{index}]"),
                    format!(
                        "its {} group is the group of no part",
                        if find_group(a) { "second" } else { "first" }
                    ),
                ));
            }
            not_of_interest.push(sorted_pair(a, b));
        }
        let by_name: HashMap<&str, usize> = (parts.iter().enumerate())
            .map(|(id, part)| (part.name.as_str(), id))
            .collect();
        let mut parts_not_of_interest = Vec::with_capacity(rules.parts_not_of_interest.len());
        for (index, [a, b]) in rules.parts_not_of_interest.iter().enumerate() {
            let key = format!("groups.parts_not_of_interest[{index}]");
            let find = |name: &String| by_name.get(name.as_str()).copied();
            match (find(a), find(b)) {
                (Some(i), Some(j)) if i != j => parts_not_of_interest.push([i.min(j), i.max(j)]),
                (Some(_), Some(_)) => {
                    return Err(self.invalid(key, "names one part twice"));
                }
                _ => {
                    let which = if find(a).is_none() { "first" } else { "second" };
                    return Err(
                        self.invalid(key, format!("its {which} name is the name of no part"))
                    );
                }
            }
        }
        Ok(Groups {
            names,
            not_of_interest,
            parts_not_of_interest,
        })
    }

    fn part(&mut self, index: usize, part: PartFile) -> Result<Part, SceneError> {
        let key = |field: &str| format!("parts[{index}].{field}");
        self.name(&key("name"), &part.name)?;
        self.name(&key("group"), &part.group)?;
        let position = self.position(&key("position"), part.position)?;
        let rotation = match part.rotation {
            None => UnitQuaternion::identity(),
            Some(q) => self.rotation(&key("rotation"), q)?,
        };
        let pose = Isometry3::from_parts(position, rotation);
        let (mesh, mesh_source, tree) = match (part.mesh, part.shape) {
            (Some(mesh), None) => self.mesh_file(index, &mesh, part.scale)?,
            (None, Some(shape)) if part.scale.is_none() => self.shape(index, shape)?,
            (None, Some(_)) => {
                return Err(self.invalid(
                    key("scale"),
                    "applies to mesh files only; give a shape's dimensions instead",
                ));
            }
            (Some(_), Some(_)) => {
                return Err(self.invalid(key("shape"), "give either mesh or shape, not both"));
            }
            (None, None) => {
                return Err(self.invalid(
                    format!("parts[{index}]"),
                    "needs a mesh (a file) or a shape",
                ));
            }
        };
        Ok(Part {
            name: part.name,
            mesh,
            mesh_source,
            scale: part.scale.unwrap_or(1.0),
            pose,
            movable: part.movable,
            group: part.group,
            push: part.push,
            release: part.release,
            tree,
        })
    }

    /// A position from a config, refused unless finite and within the bound of tracker input
    /// ([`vas_protocol::MAX_POSITION_M`]), so that every pose derived from a part's stays
    /// finite.
    fn position(&self, key: &str, position: [f64; 3]) -> Result<Translation3<f64>, SceneError> {
        let limit = vas_protocol::MAX_POSITION_M;
        if let Some(c) = position.iter().find(|c| !c.is_finite() || c.abs() > limit) {
            return Err(self.invalid(
                key,
                format!(
                    "coordinates must be finite and within {limit} m, not {}",
                    Readable(*c)
                ),
            ));
        }
        Ok(Translation3::from(position))
    }

    /// A unit quaternion from (x, y, z, w), refused unless its norm is 1 within
    /// [`QUATERNION_NORM_TOLERANCE`]; accepted ones are renormalised to full precision.
    fn rotation(
        &self,
        key: &str,
        [x, y, z, w]: [f64; 4],
    ) -> Result<UnitQuaternion<f64>, SceneError> {
        if ![x, y, z, w].iter().all(|c| c.is_finite()) {
            return Err(self.invalid(key, "components must be finite"));
        }
        let quaternion = Quaternion::new(w, x, y, z);
        let norm = quaternion.norm();
        if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
            let [x, y, z, w, norm] = [x, y, z, w, norm].map(Readable);
            return Err(self.invalid(
                key,
                format!(
                    "[{x}, {y}, {z}, {w}] has norm {norm}; a unit quaternion [x, y, z, w] is \
                     required (norm 1 within {QUATERNION_NORM_TOLERANCE})"
                ),
            ));
        }
        Ok(UnitQuaternion::from_quaternion(quaternion))
    }
}
