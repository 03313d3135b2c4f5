//! The triangle mesh every other module works on.
//!
//! Real CAD meshes are polygon soups: open, with inconsistent winding, duplicated vertices and
//! non-manifold edges. `TriMesh` accepts all of that. It guarantees only what the algorithms need:
//! every coordinate is finite, every index is in range, and no triangle is degenerate (zero area);
//! [`TriMesh::new`] removes degenerate triangles and reports how many it removed.

use nalgebra::{Point3, Vector3};
use thiserror::Error;

/// A point in a mesh's own frame, in metres.
pub type Point = Point3<f64>;

/// The axis-aligned bounding box of `points` as (minimum corner, maximum corner); inverted
/// (`f64::MAX` above `f64::MIN`) when there are none.
pub fn bounding_box_of<'a>(points: impl IntoIterator<Item = &'a Point>) -> (Point, Point) {
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in points {
        for i in 0..3 {
            lo[i] = smaller(lo[i], p[i]);
            hi[i] = larger(hi[i], p[i]);
        }
    }
    (Point::from(lo), Point::from(hi))
}

/// The larger of `a` and `b`, in one instruction on finite numbers where `f64::max` takes
/// several to order NaN: for loops over every point of a mesh.
#[inline]
pub fn larger(a: f64, b: f64) -> f64 {
    if b > a { b } else { a }
}

/// The smaller of `a` and `b`; see [`larger`].
#[inline]
pub fn smaller(a: f64, b: f64) -> f64 {
    if b < a { b } else { a }
}

/// The centre of the bounding box of `points` and the radius of the sphere around it that holds
/// every one of them.
pub fn bounding_sphere_of<'a>(points: impl IntoIterator<Item = &'a Point> + Clone) -> (Point, f64) {
    let (lo, hi) = bounding_box_of(points.clone());
    let centre = nalgebra::center(&lo, &hi);
    let radius = points
        .into_iter()
        .map(|p| (p - centre).norm())
        .fold(0.0, larger);
    (centre, radius)
}

/// Why a mesh was refused.
#[derive(Debug, Error, PartialEq)]
pub enum MeshError {
    /// The mesh has no triangle left (none given, or all degenerate).
    #[error("the mesh has no (non-degenerate) triangles")]
    Empty,
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {index} has a non-finite coordinate")]
    NonFiniteVertex {
        /// Index of the offending vertex.
        index: usize,
    },
    /// A vertex coordinate is finite but beyond [`MAX_COORDINATE`].
    #[error("vertex {index} has a coordinate of {value}, beyond {MAX_COORDINATE}")]
    CoordinateTooLarge {
        /// Index of the offending vertex.
        index: usize,
        /// The coordinate.
        value: f64,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "triangle {triangle} refers to vertex {vertex}, but there are only {vertex_count} vertices"
    )]
    IndexOutOfRange {
        /// Index of the offending triangle.
        triangle: usize,
        /// The vertex index it names.
        vertex: u32,
        /// How many vertices the mesh has.
        vertex_count: usize,
    },
    /// More vertices than a `u32` index can address.
    #[error("the mesh has {0} vertices, more than a u32 index can address")]
    TooManyVertices(usize),
}

/// The largest magnitude of a mesh coordinate. What is derived from coordinates (extents,
/// squared lengths and their squares, single-precision bounds of the collision structures)
/// stays finite below it; a kilometre-sized part in micrometres still fits.
pub const MAX_COORDINATE: f64 = 1e9;

/// An indexed triangle mesh with finite coordinates within [`MAX_COORDINATE`] and no degenerate
/// triangles.
#[derive(Debug, Clone, PartialEq)]
pub struct TriMesh {
    vertices: Vec<Point>,
    triangles: Vec<[u32; 3]>,
}

/// What [`TriMesh::new`] had to clean up, so that callers can log it with the file name.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CleanupReport {
    /// Triangles dropped because two corners coincide or all three are collinear.
    pub degenerate_triangles_removed: usize,
}

impl TriMesh {
    /// Builds a mesh, checking coordinates and indices and dropping degenerate triangles.
    ///
    /// Fails if a coordinate is not finite or beyond [`MAX_COORDINATE`], an index is out of
    /// range, or no triangle is left.
    pub fn new(
        vertices: Vec<Point>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<(Self, CleanupReport), MeshError> {
        if u32::try_from(vertices.len()).is_err() {
            return Err(MeshError::TooManyVertices(vertices.len()));
        }
        if let Some(index) = vertices
            .iter()
            .position(|v| !v.coords.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFiniteVertex { index });
        }
        if let Some((index, value)) = vertices.iter().enumerate().find_map(|(index, v)| {
            v.coords
                .iter()
                .find(|c| c.abs() > MAX_COORDINATE)
                .map(|&value| (index, value))
        }) {
            return Err(MeshError::CoordinateTooLarge { index, value });
        }
        for (triangle, t) in triangles.iter().enumerate() {
            if let Some(&vertex) = t.iter().find(|&&i| i as usize >= vertices.len()) {
                return Err(MeshError::IndexOutOfRange {
                    triangle,
                    vertex,
                    vertex_count: vertices.len(),
                });
            }
        }
        let before = triangles.len();
        let triangles: Vec<[u32; 3]> = triangles
            .into_iter()
            .filter(|t| !is_degenerate(&vertices, t))
            .collect();
        if triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        let report = CleanupReport {
            degenerate_triangles_removed: before - triangles.len(),
        };
        Ok((
            TriMesh {
                vertices,
                triangles,
            },
            report,
        ))
    }

    /// A hash of the mesh's exact content (every coordinate's bits and every index): equal
    /// meshes hash alike, so a scene recognises one mesh whatever file or shape it came from.
    pub fn content_hash(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut hasher = rustc_hash::FxHasher::default();
        self.vertices.len().hash(&mut hasher);
        for v in &self.vertices {
            v.coords.map(f64::to_bits).as_slice().hash(&mut hasher);
        }
        self.triangles.hash(&mut hasher);
        hasher.finish()
    }

    /// The vertices, in the mesh's own frame.
    pub fn vertices(&self) -> &[Point] {
        &self.vertices
    }

    /// The triangles as indices into [`TriMesh::vertices`]; winding is not meaningful.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The three corners of triangle `index`.
    pub fn triangle(&self, index: usize) -> [Point; 3] {
        let [a, b, c] = self.triangles[index];
        [
            self.vertices[a as usize],
            self.vertices[b as usize],
            self.vertices[c as usize],
        ]
    }

    /// The axis-aligned bounding box as (minimum corner, maximum corner).
    pub fn bounding_box(&self) -> (Point, Point) {
        bounding_box_of(&self.vertices)
    }

    /// The centre of the bounding box and the radius of the sphere around it that holds every
    /// vertex: a cheap bound for culling, and the pivot and reach of a grasped part.
    pub fn bounding_sphere(&self) -> (Point, f64) {
        bounding_sphere_of(&self.vertices)
    }

    /// A copy with every vertex mapped by `f` (translation, rotation, scaling); triangles whose
    /// image is degenerate are dropped as in [`TriMesh::new`].
    pub fn map_vertices(&self, f: impl Fn(&Point) -> Point) -> Result<TriMesh, MeshError> {
        let vertices = self.vertices.iter().map(f).collect();
        TriMesh::new(vertices, self.triangles.clone()).map(|(mesh, _)| mesh)
    }

    /// A copy centred on its bounding-box centre and scaled uniformly to fit in [-1, 1]^3: the
    /// normalisation of the tumbling-pair benchmark (B1).
    pub fn normalized_to_unit_box(&self) -> TriMesh {
        let (lo, hi) = self.bounding_box();
        let centre = nalgebra::center(&lo, &hi);
        let half_extent = ((hi - lo) * 0.5).max();
        let scale = if half_extent > 0.0 {
            1.0 / half_extent
        } else {
            1.0
        };
        // Uniform scaling of a valid mesh keeps every triangle non-degenerate.
        self.map_vertices(|v| Point::from((v - centre) * scale))
            .expect("uniform scaling keeps a valid mesh valid")
    }
}

/// True when the triangle has (numerically) zero area.
fn is_degenerate(vertices: &[Point], t: &[u32; 3]) -> bool {
    let [a, b, c] = t.map(|i| vertices[i as usize]);
    let (ab, ac): (Vector3<f64>, Vector3<f64>) = (b - a, c - a);
    let scale = ab.norm_squared().max(ac.norm_squared());
    ab.cross(&ac).norm_squared() <= scale * scale * 1e-24
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64, z: f64) -> Point {
        Point::new(x, y, z)
    }

    #[test]
    fn degenerate_triangles_are_removed_and_counted() {
        let vertices = vec![p(0., 0., 0.), p(1., 0., 0.), p(0., 1., 0.), p(2., 0., 0.)];
        let (mesh, report) = TriMesh::new(vertices, vec![[0, 1, 2], [0, 1, 3], [1, 1, 2]]).unwrap();
        assert_eq!(mesh.triangles(), &[[0, 1, 2]]);
        assert_eq!(report.degenerate_triangles_removed, 2);
    }

    #[test]
    fn bad_input_is_refused_with_a_reason() {
        let nan = vec![p(0., 0., 0.), p(f64::NAN, 0., 0.), p(0., 1., 0.)];
        assert_eq!(
            TriMesh::new(nan, vec![[0, 1, 2]]).unwrap_err(),
            MeshError::NonFiniteVertex { index: 1 }
        );
        let ok = vec![p(0., 0., 0.), p(1., 0., 0.), p(0., 1., 0.)];
        assert_eq!(
            TriMesh::new(ok.clone(), vec![[0, 1, 7]]).unwrap_err(),
            MeshError::IndexOutOfRange {
                triangle: 0,
                vertex: 7,
                vertex_count: 3
            }
        );
        assert_eq!(TriMesh::new(ok, vec![]).unwrap_err(), MeshError::Empty);
    }

    #[test]
    fn normalisation_fits_the_unit_box() {
        let vertices = vec![p(10., 20., 30.), p(14., 20., 30.), p(10., 22., 31.)];
        let (mesh, _) = TriMesh::new(vertices, vec![[0, 1, 2]]).unwrap();
        let (lo, hi) = mesh.normalized_to_unit_box().bounding_box();
        assert!((lo - p(-1., -0.5, -0.25)).norm() < 1e-12, "{lo}");
        assert!((hi - p(1., 0.5, 0.25)).norm() < 1e-12, "{hi}");
    }
}
