//! `[[assemblies]]`: every mesh node of a glTF file as a part of the scene, with one table of
//! config.
//!
//! ```toml
//! [[assemblies]]
//! file = "cad/gearbox.glb"          # .gltf or .glb, relative to the scene file
//! up = "y"                          # "y": the file is y-up (glTF's own convention) and is
//!                                   # turned a quarter about x to the scene's z-up (its +y
//!                                   # becomes +z, its +z becomes -y); default "z": as it is
//! position = [0.0, 0.0, 0.75]       # the assembly's origin in the scene; default the origin
//! rotation = [0.0, 0.0, 0.0, 1.0]   # the assembly's rotation (x, y, z, w); default identity
//! movable = ["shaft", "gear#2"]     # these parts movable, the rest static; or true / false
//!                                   # for every part; default false
//! group = "gearbox"                 # every part's collision group; default "default"
//! ```
//!
//! A part is made of each node that carries a mesh with triangles, reached from the file's
//! default scene (or from every root node), in the order of a depth-first walk. Its name is the
//! node's name; a node without one is named `<file stem>/node<index>`, and where names repeat the
//! first keeps it and later ones get `<name>#2`, `<name>#3`, ... (the smallest number no other
//! node's name takes). The node's world transform is split: its rotation and translation are the
//! part's pose (after the `up` turn and the assembly's placement); what is left, its scale
//! (non-uniform or negative too, a mirror turning the triangles over) and any shear, is baked
//! into the part's mesh. Nodes that instance one mesh at one scale share one mesh and one
//! DOP-tree. The parts count towards the scene's triangle limit with the triangles the file's
//! accessors announce, before any mesh is built.

use std::collections::HashSet;
use std::f64::consts::FRAC_PI_2;
use std::path::PathBuf;

use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use serde::Deserialize;

use super::Loader;
use crate::geometry::{GltfFile, GltfPart, read_mesh_file};
use crate::scene::file::default_group;
use crate::scene::{Part, SceneError};

/// An `[[assemblies]]` table as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(in crate::scene) struct AssemblyFile {
    file: PathBuf,
    #[serde(default)]
    up: UpAxis,
    #[serde(default)]
    position: [f64; 3],
    rotation: Option<[f64; 4]>,
    #[serde(default)]
    movable: Movable,
    #[serde(default = "default_group")]
    group: String,
}

/// The axis that points up in the file.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
enum UpAxis {
    /// Turned to the scene's z.
    Y,
    /// The scene's own.
    #[default]
    Z,
}

impl UpAxis {
    /// The turn from the file's frame to the scene's z-up frame.
    fn turn(self) -> UnitQuaternion<f64> {
        match self {
            UpAxis::Y => UnitQuaternion::from_axis_angle(&Vector3::x_axis(), FRAC_PI_2),
            UpAxis::Z => UnitQuaternion::identity(),
        }
    }
}

/// Which parts of an assembly are movable.
#[derive(Debug, Deserialize)]
#[serde(untagged, expecting = "true, false, or a list of part names")]
enum Movable {
    /// Every part, or none.
    All(bool),
    /// The parts named.
    Named(Vec<String>),
}

impl Default for Movable {
    fn default() -> Self {
        Movable::All(false)
    }
}

impl Loader<'_> {
    /// The parts of assembly `index`.
    pub(super) fn assembly(
        &mut self,
        index: usize,
        assembly: AssemblyFile,
    ) -> Result<Vec<Part>, SceneError> {
        let key = |field: &str| format!("assemblies[{index}].{field}");
        self.name(&key("group"), &assembly.group)?;
        self.one_line(&key("file"), &assembly.file)?;
        let position = self.position(&key("position"), assembly.position)?;
        let rotation = match assembly.rotation {
            None => UnitQuaternion::identity(),
            Some(q) => self.rotation(&key("rotation"), q)?,
        };
        let placement = Isometry3::from_parts(position, rotation * assembly.up.turn());

        let path = self.folder.join(&assembly.file);
        let is_gltf = (path.extension().and_then(|e| e.to_str()))
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"));
        if !is_gltf {
            return Err(self.invalid(
                key("file"),
                format!("{} is not a .gltf or .glb file", path.display()),
            ));
        }
        let scene_file = self.path.to_owned();
        let mesh_error = |key: String| {
            let file = scene_file.clone();
            move |source| SceneError::Mesh { file, key, source }
        };
        let bytes = read_mesh_file(&path, self.limits).map_err(mesh_error(key("file")))?;
        let file = GltfFile::parse(&path, &bytes, self.limits).map_err(mesh_error(key("file")))?;
        let gltf_parts = file.parts();
        if gltf_parts.is_empty() {
            return Err(self.invalid(
                key("file"),
                format!("{} has no node with a triangle mesh", path.display()),
            ));
        }

        let movable: HashSet<&str> = match &assembly.movable {
            Movable::All(false) => HashSet::new(),
            Movable::All(true) => gltf_parts.iter().map(|p| p.name.as_str()).collect(),
            Movable::Named(names) => {
                if let Some((i, _)) = (names.iter().enumerate())
                    .find(|(_, name)| !gltf_parts.iter().any(|p| &p.name == *name))
                {
                    return Err(self.invalid(
                        key(&format!("movable[{i}]")),
                        format!("names no part of {}", path.display()),
                    ));
                }
                names.iter().map(String::as_str).collect()
            }
        };

        // A part is named by its node: a node's name may be one of the config's values.
        let part_key = |part: &GltfPart| format!("assemblies[{index}].file node {}", part.node);
        // The limit is checked with the counts the file announces, before any mesh is built.
        for part in &gltf_parts {
            let count = (file.triangle_count(part.mesh)).map_err(mesh_error(key("file")))?;
            self.count_triangles(&part_key(part), count)?;
        }

        let source = path.display().to_string();
        let mut parts = Vec::with_capacity(gltf_parts.len());
        for part in &gltf_parts {
            let part_key = part_key(part);
            let pose = placement * part.pose;
            self.position(&part_key, pose.translation.vector.into())?;
            let cache_key = format!("{source}#{}", part.mesh_key());
            let (mesh, tree) = match self.cached(&cache_key) {
                Some(shared) => shared,
                None => {
                    let mesh = (file.mesh(part.mesh, &part.shape))
                        .map_err(mesh_error(part_key.clone()))?;
                    self.remember(cache_key, mesh)
                }
            };
            parts.push(Part {
                name: part.name.clone(),
                mesh,
                mesh_source: format!("{source}#/nodes/{}", part.node),
                scale: 1.0,
                pose,
                movable: movable.contains(part.name.as_str()),
                group: assembly.group.clone(),
                push: None,
                release: None,
                tree,
            });
        }
        Ok(parts)
    }
}
