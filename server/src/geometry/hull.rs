//! Convex hulls with vertex adjacency, for the separating-plane pre-check (the paper's §2.2).
//!
//! The pre-check needs only a hull's vertices and which vertices share an edge: the extremal vertex
//! along a direction is then found by hill-climbing from a good start, in time that grows with the
//! path length rather than the vertex count. The hull itself is computed by parry (in `f32`, around
//! the mesh's centre); its vertices are mapped back to the mesh's own `f64` points, so they are
//! exact mesh vertices.
//!
//! A "separated" answer must be proven, so the hull also knows how far any mesh vertex may stick
//! out of it ([`ConvexHull::tolerance`]): parry drops points within its epsilon of a face and
//! flattens almost-planar input, and its `f32` decisions leave rounding-level non-convexity. When
//! parry fails, the mesh's bounding box serves as the (looser, still enclosing) polytope.

use super::mesh::{Point, TriMesh};
use nalgebra::{Point3, Vector3};
use parry3d::query::PointQuery;
use parry3d::shape::Triangle;
use std::collections::HashMap;

/// Slack, relative to the hull's radius, added to the measured tolerance: it covers the rounding
/// of the `f32` hull computation (near-coplanar faces that are a hair non-convex) and of the `f32`
/// point-triangle distances used to measure the tolerance.
const ROUNDING_SLACK: f64 = 1e-6;

/// The fixed directions whose extremal vertices are kept as starting points for cold searches:
/// the six axes and the eight cube diagonals.
const HINT_DIRECTIONS: [[f64; 3]; 14] = [
    [1.0, 0.0, 0.0],
    [-1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.0, 0.0, -1.0],
    [1.0, 1.0, 1.0],
    [1.0, 1.0, -1.0],
    [1.0, -1.0, 1.0],
    [1.0, -1.0, -1.0],
    [-1.0, 1.0, 1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [-1.0, -1.0, -1.0],
];

/// Where a [`ConvexHull`]'s polytope came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HullSource {
    /// The convex hull of the mesh's vertices.
    ConvexHull,
    /// The mesh's bounding box, used because the hull computation failed or gave an unusable hull.
    BoundingBox,
}

/// A convex polytope enclosing a mesh, as vertices plus vertex adjacency, with hill-climbing
/// support queries.
#[derive(Debug, Clone)]
pub struct ConvexHull {
    vertices: Vec<Point>,
    /// `neighbours[neighbour_offsets[v]..neighbour_offsets[v + 1]]` are the neighbours of `v`.
    neighbour_offsets: Vec<u32>,
    neighbours: Vec<u32>,
    /// Extremal vertex along each of [`HINT_DIRECTIONS`].
    hints: [u32; 14],
    centre: Point,
    radius: f64,
    tolerance: f64,
    source: HullSource,
}

impl ConvexHull {
    /// The convex hull of `mesh` (its referenced vertices), or its bounding box if parry cannot
    /// compute a usable hull. Never fails: a valid [`TriMesh`] always has an enclosing polytope.
    ///
    /// Cost: the hull computation plus, for mesh vertices that are not hull vertices and lie on or
    /// outside a face plane, a scan of the faces to measure the tolerance.
    pub fn of(mesh: &TriMesh) -> ConvexHull {
        let used = referenced_vertices(mesh);
        let (lo, hi) = bounds(&used);
        let centre = nalgebra::center(&lo, &hi);
        parry_hull(&used, centre)
            .and_then(|(vertices, faces)| Self::from_faces(&used, vertices, &faces, centre))
            .unwrap_or_else(|| Self::bounding_box(lo, hi))
    }

    /// Builds the hull from parry's faces over `vertices` (exact mesh points), measures how far the
    /// `mesh_points` stick out, and checks hill-climbing along the hint directions; `None` if the
    /// result is unusable.
    fn from_faces(
        mesh_points: &[Point],
        vertices: Vec<Point>,
        faces: &[[u32; 3]],
        centre: Point,
    ) -> Option<ConvexHull> {
        let mut edges: Vec<[u32; 2]> = faces
            .iter()
            .flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]])
            .filter(|[a, b]| a != b)
            .flat_map(|[a, b]| [[a, b], [b, a]])
            .collect();
        let hull = Self::with_edges(vertices, &mut edges, centre, HullSource::ConvexHull);
        let tolerance = containment_tolerance(mesh_points, &hull.vertices, faces, centre);
        let hull = ConvexHull {
            tolerance: tolerance + ROUNDING_SLACK * hull.radius,
            ..hull
        };
        hull.climbs_to_the_true_extremes().then_some(hull)
    }

    /// The box `[lo, hi]` as an eight-vertex polytope.
    fn bounding_box(lo: Point, hi: Point) -> ConvexHull {
        let vertices = (0..8)
            .map(|corner| {
                let pick = |bit: u32, axis: usize| {
                    if corner & bit == 0 {
                        lo[axis]
                    } else {
                        hi[axis]
                    }
                };
                Point::new(pick(1, 0), pick(2, 1), pick(4, 2))
            })
            .collect();
        // Corners differing in one coordinate bit share a box edge.
        let mut edges: Vec<[u32; 2]> = (0..8u32)
            .flat_map(|v| [1, 2, 4].map(|bit| [v, v ^ bit]))
            .collect();
        let hull = Self::with_edges(
            vertices,
            &mut edges,
            nalgebra::center(&lo, &hi),
            HullSource::BoundingBox,
        );
        ConvexHull {
            tolerance: ROUNDING_SLACK * hull.radius,
            ..hull
        }
    }

    /// Assembles the adjacency from directed `edges` (each edge in both directions, duplicates
    /// allowed), the bounding sphere and the start hints; the tolerance is left at zero.
    fn with_edges(
        vertices: Vec<Point>,
        edges: &mut Vec<[u32; 2]>,
        centre: Point,
        source: HullSource,
    ) -> ConvexHull {
        edges.sort_unstable();
        edges.dedup();
        let mut neighbour_offsets = vec![0u32; vertices.len() + 1];
        for &[from, _] in edges.iter() {
            neighbour_offsets[from as usize + 1] += 1;
        }
        for v in 0..vertices.len() {
            neighbour_offsets[v + 1] += neighbour_offsets[v];
        }
        let neighbours = edges.iter().map(|&[_, to]| to).collect();
        let radius = vertices
            .iter()
            .map(|v| (v - centre).norm())
            .fold(0.0, f64::max);
        let mut hull = ConvexHull {
            vertices,
            neighbour_offsets,
            neighbours,
            hints: [0; 14],
            centre,
            radius,
            tolerance: 0.0,
            source,
        };
        hull.hints = HINT_DIRECTIONS.map(|d| hull.brute_force_extremal(&Vector3::from(d)).0);
        hull
    }

    /// True when hill-climbing from the opposite side reaches the brute-force extremes along the
    /// hint directions (within the tolerance): a cheap guard against a broken hull.
    fn climbs_to_the_true_extremes(&self) -> bool {
        HINT_DIRECTIONS.iter().enumerate().all(|(i, d)| {
            let direction = Vector3::from(*d);
            // Start from the opposite extreme: the longest climb there is.
            let opposite = if i < 6 { i ^ 1 } else { 19 - i };
            let (_, climbed) = self.extremal_vertex(&direction, self.hints[opposite]);
            let (_, best) = self.brute_force_extremal(&direction);
            climbed >= best - self.tolerance
        })
    }

    /// The hull's vertices: exact vertices of the mesh (or the box corners).
    pub fn vertices(&self) -> &[Point] {
        &self.vertices
    }

    /// The vertices sharing a hull edge with vertex `v`.
    pub fn neighbours(&self, v: u32) -> &[u32] {
        let range = self.neighbour_offsets[v as usize] as usize
            ..self.neighbour_offsets[v as usize + 1] as usize;
        &self.neighbours[range]
    }

    /// The centre of the hull's bounding box.
    pub fn centre(&self) -> Point {
        self.centre
    }

    /// The largest distance from [`ConvexHull::centre`] to a hull vertex.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// How far beyond the polytope any mesh vertex may lie: a support value found on the hull must
    /// be widened by this much before it bounds the mesh.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// Whether this is the true convex hull or the bounding-box fallback.
    pub fn source(&self) -> HullSource {
        self.source
    }

    /// A good vertex to start a cold search along `direction`: the stored extremal vertex of the
    /// closest of fourteen fixed directions.
    pub fn start_vertex(&self, direction: &Vector3<f64>) -> u32 {
        let closest = HINT_DIRECTIONS
            .iter()
            .map(|d| Vector3::from(*d).normalize().dot(direction))
            .enumerate()
            .fold((0, f64::NEG_INFINITY), |best, (i, dot)| {
                if dot > best.1 { (i, dot) } else { best }
            })
            .0;
        self.hints[closest]
    }

    /// The vertex maximising `direction · v`, by steepest-ascent hill-climbing from `start`, and
    /// that maximum. On a convex polytope a vertex no neighbour improves on is the global maximum.
    pub fn extremal_vertex(&self, direction: &Vector3<f64>, start: u32) -> (u32, f64) {
        let mut best = start;
        let mut best_value = self.vertices[start as usize].coords.dot(direction);
        loop {
            let mut next = best;
            let mut next_value = best_value;
            for &n in self.neighbours(best) {
                let value = self.vertices[n as usize].coords.dot(direction);
                if value > next_value {
                    next = n;
                    next_value = value;
                }
            }
            if next == best {
                return (best, best_value);
            }
            best = next;
            best_value = next_value;
        }
    }

    /// The extremal vertex along `direction` by scanning every vertex: the reference the
    /// hill-climbing is checked against.
    pub fn brute_force_extremal(&self, direction: &Vector3<f64>) -> (u32, f64) {
        self.vertices
            .iter()
            .map(|v| v.coords.dot(direction))
            .enumerate()
            .fold((0, f64::NEG_INFINITY), |best, (i, value)| {
                if value > best.1 {
                    (i as u32, value)
                } else {
                    best
                }
            })
    }
}

/// The vertices that some triangle uses (a mesh may carry unused ones).
fn referenced_vertices(mesh: &TriMesh) -> Vec<Point> {
    let mut used = vec![false; mesh.vertices().len()];
    for &i in mesh.triangles().iter().flatten() {
        used[i as usize] = true;
    }
    mesh.vertices()
        .iter()
        .zip(used)
        .filter_map(|(v, used)| used.then_some(*v))
        .collect()
}

/// Minimum and maximum corner of the points' bounding box.
fn bounds(points: &[Point]) -> (Point, Point) {
    points
        .iter()
        .fold((points[0], points[0]), |(lo, hi), p| (lo.inf(p), hi.sup(p)))
}

/// Runs parry's hull on the distinct points (shifted to `centre` and rounded to `f32`) and maps
/// the hull's vertices back to the exact `f64` points; `None` if parry fails.
fn parry_hull(points: &[Point], centre: Point) -> Option<(Vec<Point>, Vec<[u32; 3]>)> {
    // Adding 0.0 turns -0.0 into 0.0 so that equal points have equal bits.
    let key = |p: &Point3<f32>| p.coords.map(|c| (c + 0.0).to_bits());
    let mut exact_of: HashMap<_, Point> = HashMap::with_capacity(points.len());
    let mut distinct = Vec::with_capacity(points.len());
    for p in points {
        let rounded: Point3<f32> = nalgebra::convert(Point::from(p - centre));
        exact_of.entry(key(&rounded)).or_insert_with(|| {
            distinct.push(rounded);
            *p
        });
    }
    // parry documents `try_convex_hull` as the non-panicking entry point, yet some degenerate
    // inputs still trip internal assertions; a failed hull only costs the pre-check its tightness.
    let hull = std::panic::catch_unwind(|| parry3d::transformation::try_convex_hull(&distinct));
    let (hull_points, faces) = hull.ok()?.ok()?;
    if hull_points.len() < 3 || faces.is_empty() {
        return None;
    }
    let vertices = hull_points
        .iter()
        .map(|p| exact_of.get(&key(p)).copied())
        .collect::<Option<Vec<_>>>()?;
    Some((vertices, faces))
}

/// The largest distance from a mesh point to the hull surface, over the points that are not
/// strictly inside every face plane. Faces are triangles over `vertices`; distances are taken in
/// `f32` around `centre` (the caller adds slack for that rounding).
fn containment_tolerance(
    mesh_points: &[Point],
    vertices: &[Point],
    faces: &[[u32; 3]],
    centre: Point,
) -> f64 {
    let centroid = Point::from(
        vertices.iter().map(|v| v.coords).sum::<Vector3<f64>>() / vertices.len() as f64,
    );
    // Face planes oriented away from the centroid, whatever parry's winding.
    let planes: Vec<(Vector3<f64>, f64)> = faces
        .iter()
        .filter_map(|&[a, b, c]| {
            let [a, b, c] = [a, b, c].map(|i| vertices[i as usize]);
            let mut normal = (b - a).cross(&(c - a)).try_normalize(0.0)?;
            if normal.dot(&(centroid - a)) > 0.0 {
                normal = -normal;
            }
            Some((normal, normal.dot(&a.coords)))
        })
        .collect();
    let triangles: Vec<Triangle> = faces
        .iter()
        .map(|face| {
            let [a, b, c] =
                face.map(|i| nalgebra::convert(Point::from(vertices[i as usize] - centre)));
            Triangle::new(a, b, c)
        })
        .collect();
    let is_hull_vertex: std::collections::HashSet<[u64; 3]> = vertices
        .iter()
        .map(|v| v.coords.map(f64::to_bits).into())
        .collect();
    mesh_points
        .iter()
        .filter(|p| !is_hull_vertex.contains(&<[u64; 3]>::from(p.coords.map(f64::to_bits))))
        .filter(|p| planes.iter().any(|(n, d)| n.dot(&p.coords) >= *d))
        .map(|p| {
            let local: Point3<f32> = nalgebra::convert(Point::from(p - centre));
            triangles
                .iter()
                .map(|t| t.distance_to_local_point(&local, true))
                .fold(f32::INFINITY, f32::min) as f64
        })
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn mesh_of(points: Vec<Point>, triangles: Vec<[u32; 3]>) -> TriMesh {
        TriMesh::new(points, triangles).unwrap().0
    }

    /// A random point cloud turned into a mesh by a fan of triangles (the hull ignores topology).
    fn random_cloud(rng: &mut ChaCha8Rng, n: usize, flat: bool) -> TriMesh {
        let points: Vec<Point> = (0..n)
            .map(|_| {
                let z = if flat {
                    0.0
                } else {
                    rng.random_range(-1.0..1.0)
                };
                Point::new(rng.random_range(-1.0..1.0), rng.random_range(-2.0..2.0), z)
            })
            .collect();
        let triangles = (1..n as u32 - 1).map(|i| [0, i, i + 1]).collect();
        mesh_of(points, triangles)
    }

    fn random_direction(rng: &mut ChaCha8Rng) -> Vector3<f64> {
        Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize()
    }

    /// The hull's support (hill-climbed from a random vertex, widened by the tolerance) bounds the
    /// support of every mesh vertex, in many random directions.
    fn assert_encloses(hull: &ConvexHull, mesh: &TriMesh, rng: &mut ChaCha8Rng) {
        for _ in 0..500 {
            let d = random_direction(rng);
            let start = rng.random_range(0..hull.vertices().len() as u32);
            let (_, climbed) = hull.extremal_vertex(&d, start);
            let mesh_max = mesh
                .vertices()
                .iter()
                .map(|v| v.coords.dot(&d))
                .fold(f64::NEG_INFINITY, f64::max);
            assert!(
                climbed + hull.tolerance() >= mesh_max,
                "climbed {climbed} + {} < mesh support {mesh_max}",
                hull.tolerance()
            );
            let (_, brute) = hull.brute_force_extremal(&d);
            assert!(
                climbed >= brute - hull.tolerance(),
                "local maximum {climbed} < {brute}"
            );
        }
    }

    #[test]
    fn hull_of_random_clouds_encloses_them_and_climbs_to_the_maximum() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for n in [4, 10, 100, 2000] {
            let mesh = random_cloud(&mut rng, n, false);
            let hull = ConvexHull::of(&mesh);
            assert_eq!(hull.source(), HullSource::ConvexHull);
            assert!(hull.vertices().len() <= n);
            for v in hull.vertices() {
                assert!(
                    mesh.vertices().contains(v),
                    "hull vertex {v} is not a mesh vertex"
                );
            }
            assert_encloses(&hull, &mesh, &mut rng);
        }
    }

    #[test]
    fn flat_meshes_get_a_flat_hull_that_still_encloses_them() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let mesh = random_cloud(&mut rng, 500, true);
        let hull = ConvexHull::of(&mesh);
        assert!(hull.vertices().iter().all(|v| v.z == 0.0));
        assert_encloses(&hull, &mesh, &mut rng);
    }

    #[test]
    fn cube_hull_has_its_corners_and_edge_neighbours() {
        let corners: Vec<Point> = (0..8)
            .map(|c| Point::new((c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64))
            .collect();
        // Two triangles per face of the unit cube.
        let triangles = vec![
            [0, 1, 3],
            [0, 3, 2],
            [4, 5, 7],
            [4, 7, 6],
            [0, 1, 5],
            [0, 5, 4],
            [2, 3, 7],
            [2, 7, 6],
            [0, 2, 6],
            [0, 6, 4],
            [1, 3, 7],
            [1, 7, 5],
        ];
        let hull = ConvexHull::of(&mesh_of(corners, triangles));
        assert_eq!(hull.vertices().len(), 8);
        for v in 0..8u32 {
            let n = hull.neighbours(v);
            // Three cube edges, plus at most the face diagonals of the hull's triangulation.
            assert!(
                (3..=6).contains(&n.len()),
                "vertex {v} has {} neighbours",
                n.len()
            );
        }
        assert!(hull.tolerance() < 1e-5);
        let (v, value) = hull.extremal_vertex(
            &Vector3::new(1.0, 1.0, 1.0),
            hull.start_vertex(&-Vector3::new(1.0, 1.0, 1.0)),
        );
        assert_eq!(hull.vertices()[v as usize], Point::new(1.0, 1.0, 1.0));
        assert_eq!(value, 3.0);
    }

    #[test]
    fn interior_points_left_out_of_the_hull_need_no_tolerance_but_near_face_ones_do() {
        // A tetrahedron with one point deep inside and one just outside a face (closer than
        // parry's epsilon, so it is dropped from the hull).
        let points = vec![
            Point::new(0.0, 0.0, 0.0),
            Point::new(1.0, 0.0, 0.0),
            Point::new(0.0, 1.0, 0.0),
            Point::new(0.0, 0.0, 1.0),
            Point::new(0.1, 0.1, 0.1),
            Point::new(0.3, 0.3, -1e-7),
        ];
        let triangles = vec![
            [0, 1, 2],
            [0, 1, 3],
            [0, 2, 3],
            [1, 2, 3],
            [4, 0, 1],
            [5, 1, 2],
        ];
        let hull = ConvexHull::of(&mesh_of(points, triangles));
        assert_eq!(hull.vertices().len(), 4);
        assert!(hull.tolerance() >= 1e-7, "tolerance {}", hull.tolerance());
        assert!(hull.tolerance() < 1e-5, "tolerance {}", hull.tolerance());
    }

    #[test]
    fn hulls_of_procedural_shapes_and_real_meshes_enclose_them() {
        use crate::geometry::shapes::{self, ShapeKind};
        let mut rng = ChaCha8Rng::seed_from_u64(10);
        for kind in &ShapeKind::ALL {
            for triangles in [100, 3000] {
                let mesh = shapes::build(*kind, triangles);
                let hull = ConvexHull::of(&mesh);
                assert_eq!(hull.source(), HullSource::ConvexHull, "{kind}");
                assert!(
                    hull.tolerance() < 1e-4 * hull.radius(),
                    "{kind}: {}",
                    hull.tolerance()
                );
                assert_encloses(&hull, &mesh, &mut rng);
            }
        }
        let meshes = concat!(env!("CARGO_MANIFEST_DIR"), "/../configs/meshes");
        for name in [
            "fcl_env",
            "fcl_rob",
            "low_poly_bunny",
            "ur5e_wrist3",
            "ur5e_base",
        ] {
            let path = std::path::Path::new(meshes).join(format!("{name}.obj"));
            let mesh = crate::geometry::load_mesh(&path).unwrap();
            let hull = ConvexHull::of(&mesh);
            assert_eq!(hull.source(), HullSource::ConvexHull, "{name}");
            assert_encloses(&hull, &mesh, &mut rng);
        }
    }

    #[test]
    fn failed_hull_falls_back_to_the_bounding_box() {
        let boxed =
            ConvexHull::bounding_box(Point::new(-1.0, -2.0, 0.0), Point::new(1.0, 2.0, 0.0));
        assert_eq!(boxed.source(), HullSource::BoundingBox);
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for _ in 0..200 {
            let d = random_direction(&mut rng);
            let (_, climbed) = boxed.extremal_vertex(&d, rng.random_range(0..8));
            assert!((climbed - (d.x.abs() + 2.0 * d.y.abs())).abs() < 1e-12);
        }
    }
}
