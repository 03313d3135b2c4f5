//! Triangle meshes: the mesh type, loading (OBJ, STL, PLY, glTF), welding, adjacency, convex
//! hulls and procedural shapes.

pub(crate) mod adjacency;
pub mod hull;
pub(crate) mod io;
pub mod mesh;
pub mod shapes;
pub(crate) mod weld;

pub use adjacency::EdgeAdjacency;
pub use hull::{ConvexHull, HullSource};
pub use io::{
    ConfigFileError, FileLimits, GeometryError, GltfFile, GltfPart, describe_toml_error, load_mesh,
    load_mesh_within, mesh_from_bytes, parse_mesh_spec, read_config_text, read_mesh_file,
    read_regular_text, write_obj,
};
pub use mesh::{
    CleanupReport, MeshError, Point, TriMesh, bounding_box_of, bounding_sphere_of, larger, smaller,
};
pub use weld::weld;
