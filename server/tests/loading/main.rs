//! Loading real files: meshes (OBJ, STL, PLY, glTF, soups, broken ones), scene configs and
//! glTF assemblies, in one test binary.

mod assemblies;
mod counts;
mod formats;
mod mesh_files;
mod overlaps;
mod scene_refusals;
mod scenes;
mod users;
