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
    /// A mesh of many vertices gets the hull of a bounded sample of them (`hull_candidates`):
    /// the pre-check needs a hull that is tight, not exact, and parry's hull grows faster than
    /// linearly in its input. The vertices the sample misses are covered by the tolerance.
    ///
    /// Cost: linear in the mesh's vertices (the sample, the tolerance's face climb per vertex)
    /// plus the hull of at most `SAMPLE_CELLS` points.
    pub fn of(mesh: &TriMesh) -> ConvexHull {
        let used = referenced_vertices(mesh);
        let (lo, hi) = bounds(&used);
        let centre = nalgebra::center(&lo, &hi);
        let cube = CubeFrame::new(lo, hi);
        parry_hull(&hull_candidates(&used, &cube), &cube)
            .and_then(|(vertices, faces)| Self::from_faces(&used, vertices, &faces, centre))
            .unwrap_or_else(|| Self::bounding_box(lo, hi))
    }

    /// Builds the hull from parry's faces over `vertices` (exact mesh points), measures how far the
    /// `mesh_points` stick out, and checks hill-climbing along the hint directions; `None` if the
    /// result is unusable or its tolerance would take more than linear time to measure.
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
        let tolerance = containment_tolerance(mesh_points, &hull.vertices, faces, centre)?;
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

/// The number of direction cells `hull_candidates` keeps a point of: a cube map of
/// `SAMPLE_CELLS_PER_EDGE²` cells on each of its six faces.
const SAMPLE_CELLS: usize = 6 * SAMPLE_CELLS_PER_EDGE * SAMPLE_CELLS_PER_EDGE;

/// Cells along an edge of a cube-map face: the sample's angular resolution is about 90° / this.
const SAMPLE_CELLS_PER_EDGE: usize = 32;

/// The frame in which the mesh's bounding box is the cube `[-1, 1]³` (an axis of no extent is
/// scaled as the longest): hulls are computed there, so that parry's `f32` arithmetic and
/// epsilons see a long or flat part as well-conditioned as a round one, and the sample is as
/// fine along a part's short axes as along its long one. An affine map keeps the hull's
/// vertices and faces, so the hull found there is the hull here.
struct CubeFrame {
    centre: Point,
    scale: Vector3<f64>,
}

impl CubeFrame {
    fn new(lo: Point, hi: Point) -> CubeFrame {
        let half = (hi - lo) / 2.0;
        let longest = half.max();
        CubeFrame {
            centre: nalgebra::center(&lo, &hi),
            scale: half.map(|h| if h > 0.0 { 1.0 / h } else { 1.0 / longest }),
        }
    }

    fn map(&self, p: &Point) -> Vector3<f64> {
        (p - self.centre).component_mul(&self.scale)
    }
}

/// The points whose hull is computed: all of them when there are at most `SAMPLE_CELLS`,
/// else, for each cell of a cube map of directions in the [`CubeFrame`], the point of that cell
/// farthest along the cell's central direction. Every hull vertex is then near a sampled one, so
/// the sampled hull is tight; what it misses, the tolerance covers.
fn hull_candidates(points: &[Point], cube: &CubeFrame) -> Vec<Point> {
    if points.len() <= SAMPLE_CELLS {
        return points.to_vec();
    }
    let mut best: Vec<Option<(f64, Point)>> = vec![None; SAMPLE_CELLS];
    for p in points {
        let d = cube.map(p);
        let Some((cell, axis)) = direction_cell(&d) else {
            continue;
        };
        let along = d.dot(&axis);
        if best[cell].is_none_or(|(value, _)| along > value) {
            best[cell] = Some((along, *p));
        }
    }
    best.into_iter().flatten().map(|(_, p)| p).collect()
}

/// The cube-map cell of direction `d` (its largest coordinate picks the face, the other two
/// divided by it the cell) and the cell's central direction (not normalised: the same scale for
/// every point of the cell), or `None` for the zero vector.
fn direction_cell(d: &Vector3<f64>) -> Option<(usize, Vector3<f64>)> {
    let axis = d.iamax();
    let major = d[axis];
    if major == 0.0 {
        return None;
    }
    let face = 2 * axis + usize::from(major < 0.0);
    let cells = SAMPLE_CELLS_PER_EDGE as f64;
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let cell_of =
        |c: f64| (((c / major.abs() + 1.0) * 0.5 * cells) as usize).min(SAMPLE_CELLS_PER_EDGE - 1);
    let (i, j) = (cell_of(d[u]), cell_of(d[v]));
    let middle = |k: usize| (k as f64 + 0.5) / cells * 2.0 - 1.0;
    let mut central = Vector3::zeros();
    central[axis] = major.signum();
    central[u] = middle(i);
    central[v] = middle(j);
    Some((
        (face * SAMPLE_CELLS_PER_EDGE + i) * SAMPLE_CELLS_PER_EDGE + j,
        central,
    ))
}

/// Runs parry's hull on the distinct points (in the [`CubeFrame`], rounded to `f32`) and maps
/// the hull's vertices back to the exact `f64` points; `None` if parry fails.
fn parry_hull(points: &[Point], cube: &CubeFrame) -> Option<(Vec<Point>, Vec<[u32; 3]>)> {
    // Adding 0.0 turns -0.0 into 0.0 so that equal points have equal bits.
    let key = |p: &Point3<f32>| p.coords.map(|c| (c + 0.0).to_bits());
    let mut exact_of: HashMap<_, Point> = HashMap::with_capacity(points.len());
    let mut distinct = Vec::with_capacity(points.len());
    for p in points {
        let rounded: Point3<f32> = nalgebra::convert(Point::from(cube.map(p)));
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

/// How far any mesh point lies outside the hull: over the points that are not strictly inside
/// every face plane, an upper bound of the distance to the hull surface. Faces are triangles over
/// `vertices`; distances are taken in `f32` around `centre` (the caller adds slack for that
/// rounding).
///
/// Each point is tested against the one plane its ray from the hull's centroid leaves through,
/// found by hill-climbing over the planes ([`FaceClimb`]), so the cost grows with the points times
/// a short climb (mesh points come in spatially coherent order, and each climb starts where the
/// last ended). A point on or outside that plane gets an upper bound of its distance to the hull.
/// A hull whose centroid is not well inside every face (flat or degenerate) falls back to testing
/// every point against every face, if that takes at most [`EXHAUSTIVE_BUDGET`] tests; else the
/// answer is `None` and the caller uses the bounding box.
fn containment_tolerance(
    mesh_points: &[Point],
    vertices: &[Point],
    faces: &[[u32; 3]],
    centre: Point,
) -> Option<f64> {
    let centroid = centroid_of(vertices);
    let planes = face_planes(vertices, faces, centroid);
    let Some(climb) = FaceClimb::new(&planes, faces, centroid, vertices) else {
        return (mesh_points.len().saturating_mul(faces.len()) <= EXHAUSTIVE_BUDGET)
            .then(|| exhaustive_tolerance(mesh_points, vertices, faces, centre));
    };
    let triangles = local_triangles(vertices, faces, centre);
    let hull_vertices = is_hull_vertex(vertices);
    let mut start = 0;
    let mut tolerance = 0.0f64;
    for p in mesh_points
        .iter()
        .filter(|p| !hull_vertices.contains(&bits(p)))
    {
        let q = p - centroid;
        let (plane, ratio) = climb.exit_plane(&q, start);
        start = plane;
        if ratio >= 1.0 {
            // Two bounds of the distance to the hull, each valid alone: to the point where the
            // ray leaves the hull (`centroid + q / ratio`), and to a face on the exit plane.
            let radial = q.norm() * (1.0 - 1.0 / ratio);
            let face = triangles[climb.faces[plane as usize] as usize]
                .distance_to_local_point(&local_point(p, centre), true)
                as f64;
            tolerance = tolerance.max(radial.min(face));
        }
    }
    Some(tolerance)
}

/// The most point-face tests [`exhaustive_tolerance`] may take (a few tenths of a second): a flat
/// hull of a large mesh gets the bounding box instead.
const EXHAUSTIVE_BUDGET: usize = 50_000_000;

/// The exact distance version of [`containment_tolerance`]: every point on or outside some face
/// plane, against every face. Quadratic; for hulls the face climb cannot serve.
fn exhaustive_tolerance(
    mesh_points: &[Point],
    vertices: &[Point],
    faces: &[[u32; 3]],
    centre: Point,
) -> f64 {
    let planes: Vec<(Vector3<f64>, f64)> = face_planes(vertices, faces, centroid_of(vertices))
        .into_iter()
        .flatten()
        .collect();
    let triangles = local_triangles(vertices, faces, centre);
    let hull_vertices = is_hull_vertex(vertices);
    mesh_points
        .iter()
        .filter(|p| !hull_vertices.contains(&bits(p)))
        .filter(|p| planes.iter().any(|(n, d)| n.dot(&p.coords) >= *d))
        .map(|p| {
            let local = local_point(p, centre);
            triangles
                .iter()
                .map(|t| t.distance_to_local_point(&local, true))
                .fold(f32::INFINITY, f32::min) as f64
        })
        .fold(0.0, f64::max)
}

/// Each face's plane (unit normal pointing away from `centroid`, offset along it), or `None` for
/// a face of no area.
fn face_planes(
    vertices: &[Point],
    faces: &[[u32; 3]],
    centroid: Point,
) -> Vec<Option<(Vector3<f64>, f64)>> {
    faces
        .iter()
        .map(|&[a, b, c]| {
            let [a, b, c] = [a, b, c].map(|i| vertices[i as usize]);
            let mut normal = (b - a).cross(&(c - a)).try_normalize(0.0)?;
            if normal.dot(&(centroid - a)) > 0.0 {
                normal = -normal;
            }
            Some((normal, normal.dot(&a.coords)))
        })
        .collect()
}

/// The mean of the hull's vertices: a point well inside a hull that is not flat.
fn centroid_of(vertices: &[Point]) -> Point {
    Point::from(vertices.iter().map(|v| v.coords).sum::<Vector3<f64>>() / vertices.len() as f64)
}

/// `p` around `centre` in `f32`, as the faces of [`local_triangles`] are.
fn local_point(p: &Point, centre: Point) -> Point3<f32> {
    nalgebra::convert(Point::from(p - centre))
}

/// The faces as `f32` triangles around `centre`, for parry's point-triangle distance.
fn local_triangles(vertices: &[Point], faces: &[[u32; 3]], centre: Point) -> Vec<Triangle> {
    faces
        .iter()
        .map(|face| {
            let [a, b, c] = face.map(|i| local_point(&vertices[i as usize], centre));
            Triangle::new(a, b, c)
        })
        .collect()
}

/// A point's exact bits, to recognise hull vertices among mesh points.
fn bits(p: &Point) -> [u64; 3] {
    p.coords.map(f64::to_bits).into()
}

/// The hull's vertices by their exact bits.
fn is_hull_vertex(vertices: &[Point]) -> std::collections::HashSet<[u64; 3]> {
    vertices.iter().map(bits).collect()
}

/// Finds the plane a ray from the hull's centroid leaves through, by hill-climbing over the
/// hull's planes. With `q` the ray's direction, that plane maximises `n · q / h` (`n` its outward
/// normal, `h` its distance from the centroid): a support query on the hull's polar dual, whose
/// vertices are `n / h` and whose edges join planes that meet in a hull edge, so a local maximum
/// is the global one. Coplanar faces are one plane here (else a face inside a flat region, all
/// of whose neighbours lie in that region, would stop the climb). The ray's point
/// `centroid + q` is outside the hull exactly when the maximum is 1 or more.
struct FaceClimb {
    /// `n / h` per plane.
    scaled_normals: Vec<Vector3<f64>>,
    /// A face of each plane.
    faces: Vec<u32>,
    /// `neighbours[offsets[i]..offsets[i + 1]]` are the planes meeting plane `i` in an edge.
    offsets: Vec<u32>,
    neighbours: Vec<u32>,
}

impl FaceClimb {
    /// `None` when some face has no area or a plane that passes within a hair of the centroid
    /// (a flat or degenerate hull): the polar dual is then unbounded or ill-conditioned.
    fn new(
        planes: &[Option<(Vector3<f64>, f64)>],
        faces: &[[u32; 3]],
        centroid: Point,
        vertices: &[Point],
    ) -> Option<FaceClimb> {
        let radius = vertices
            .iter()
            .map(|v| (v - centroid).norm())
            .fold(0.0, f64::max);
        let scaled = planes
            .iter()
            .map(|plane| {
                let (normal, offset) = (*plane)?;
                let height = offset - normal.dot(&centroid.coords);
                (height > 1e-6 * radius).then(|| normal / height)
            })
            .collect::<Option<Vec<_>>>()?;
        let face_pairs = faces_sharing_an_edge(faces);
        // Neighbouring faces on one plane (to rounding) become one plane.
        let mut group: Vec<u32> = (0..faces.len() as u32).collect();
        for &[f, g] in &face_pairs {
            let (a, b) = (scaled[f as usize], scaled[g as usize]);
            if (a - b).norm() <= 1e-9 * a.norm() {
                let (rf, rg) = (root(&mut group, f), root(&mut group, g));
                group[rf.max(rg) as usize] = rf.min(rg);
            }
        }
        let mut plane_of = vec![u32::MAX; faces.len()];
        let mut plane_faces = Vec::new();
        for f in 0..faces.len() as u32 {
            let r = root(&mut group, f) as usize;
            if plane_of[r] == u32::MAX {
                plane_of[r] = plane_faces.len() as u32;
                plane_faces.push(f);
            }
            plane_of[f as usize] = plane_of[r];
        }
        let mut pairs: Vec<[u32; 2]> = face_pairs
            .iter()
            .map(|&[f, g]| [plane_of[f as usize], plane_of[g as usize]])
            .filter(|[i, j]| i != j)
            .collect();
        pairs.sort_unstable();
        pairs.dedup();
        let mut offsets = vec![0u32; plane_faces.len() + 1];
        for &[from, _] in &pairs {
            offsets[from as usize + 1] += 1;
        }
        for i in 0..plane_faces.len() {
            offsets[i + 1] += offsets[i];
        }
        Some(FaceClimb {
            scaled_normals: plane_faces.iter().map(|&f| scaled[f as usize]).collect(),
            faces: plane_faces,
            offsets,
            neighbours: pairs.iter().map(|&[_, to]| to).collect(),
        })
    }

    /// The plane maximising `n · q / h`, climbing from plane `start`, and that maximum.
    fn exit_plane(&self, q: &Vector3<f64>, start: u32) -> (u32, f64) {
        let mut best = start;
        let mut best_value = self.scaled_normals[start as usize].dot(q);
        loop {
            let range =
                self.offsets[best as usize] as usize..self.offsets[best as usize + 1] as usize;
            let (next, next_value) = self.neighbours[range]
                .iter()
                .map(|&j| (j, self.scaled_normals[j as usize].dot(q)))
                .fold((best, best_value), |a, b| if b.1 > a.1 { b } else { a });
            if next == best {
                return (best, best_value);
            }
            best = next;
            best_value = next_value;
        }
    }
}

/// Every ordered pair of distinct faces that share an edge.
fn faces_sharing_an_edge(faces: &[[u32; 3]]) -> Vec<[u32; 2]> {
    // Sorted, an edge's faces are adjacent.
    let mut edge_faces: Vec<([u32; 2], u32)> = faces
        .iter()
        .enumerate()
        .flat_map(|(f, &[a, b, c])| {
            [[a, b], [b, c], [c, a]].map(|[u, v]| ([u.min(v), u.max(v)], f as u32))
        })
        .collect();
    edge_faces.sort_unstable();
    edge_faces
        .chunk_by(|x, y| x.0 == y.0)
        .flat_map(|group| {
            group.iter().flat_map(move |&(_, f)| {
                group
                    .iter()
                    .filter(move |&&(_, g)| g != f)
                    .map(move |&(_, g)| [f, g])
            })
        })
        .collect()
}

/// The representative of `f`'s group in a union-find forest, halving the path on the way.
fn root(group: &mut [u32], mut f: u32) -> u32 {
    while group[f as usize] != f {
        group[f as usize] = group[group[f as usize] as usize];
        f = group[f as usize];
    }
    f
}

#[cfg(test)]
mod tests;
