//! Triangle meshes: the mesh type, loading, welding, adjacency, convex hulls and procedural shapes.

pub mod mesh;

pub use mesh::{CleanupReport, MeshError, Point, TriMesh};
