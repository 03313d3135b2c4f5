//! Loading real files: meshes (OBJ, STL, soups, broken ones) and scene configs, in one test
//! binary.

mod mesh_files;
mod scenes;
