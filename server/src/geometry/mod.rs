//! Triangle meshes: the mesh type, loading, welding, adjacency, convex hulls and procedural shapes.

pub mod hull;
pub mod mesh;

pub use hull::{ConvexHull, HullSource};
pub use mesh::{CleanupReport, MeshError, Point, TriMesh};
