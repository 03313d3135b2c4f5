//! Contact classification (the paper's §3.2 and Figure 8): from the intersecting triangle pairs at
//! the first colliding pose of a bisection, one contact point per pair with a normal found from the
//! geometry alone.
//!
//! For a touching pair `(p, q)` (`p` on the part, `q` on the obstacle), `n_p` counts the triangles
//! adjacent to `p` that touch `q`, and `n_q` those adjacent to `q` that touch `p`:
//! * `n_p = n_q = 1`: edge/edge; the normal is the cross product of the part's edge shared by `p`
//!   and its touching neighbour and the obstacle's edge shared likewise;
//! * `n_p > 1` (a fan of part triangles around a vertex pierces `q`): vertex/face, the normal is
//!   `q`'s plane normal; `n_q > 1` symmetrically face/vertex with `p`'s plane normal; both above one
//!   (faces lying on faces): face/face with `q`'s normal;
//! * a count of zero (rims of open meshes, or a shallow approximation): which edges cross which
//!   triangle decides. Edges of both triangles cross the other: edge/edge with those edges; only
//!   `p`'s edges cross `q`: vertex/face; only `q`'s: face/vertex.
//!
//! An edge between coplanar triangles is no edge, and a vertex with no sharp edge around it no
//! vertex: both are the inside of a face (the cell boundaries of a subdivided face).
//!
//! Stored normals and winding are never used: a plane normal comes from a cross product of the
//! triangle's edges, and every normal is oriented against the approach, the motion of the contact
//! point from the last free pose to the colliding one. So inconsistent winding and sheets touched
//! from either side need no special case.

use nalgebra::{Point3, Unit, Vector3};

use super::motion::{Motion, Pose};
use crate::geometry::{EdgeAdjacency, Point, TriMesh};

/// How a pair of triangles touches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum ContactKind {
    /// A vertex (or rim) of the part in a face of the obstacle: the obstacle's face normal.
    VertexFace,
    /// A vertex (or rim) of the obstacle in a face of the part: the part's face normal.
    FaceVertex,
    /// An edge of the part across an edge of the obstacle: normal across both edges.
    EdgeEdge,
    /// Faces on faces (coplanar or several triangles each way): the obstacle's face normal.
    FaceFace,
}

/// One classified contact point, in the world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Index of the obstacle touched, as the caller numbers them.
    pub obstacle: usize,
    /// The contact point: the middle of the two triangles' intersection.
    pub point: Point,
    /// Unit normal pointing from the obstacle towards the part: the part may move along it.
    pub normal: Unit<Vector3<f64>>,
    /// The classification that chose the normal.
    pub kind: ContactKind,
}

/// A triangle pair that intersects: part triangle and obstacle triangle indices.
pub type TouchingPair = [u32; 2];

/// One side of a contact: a mesh, its edge adjacency and its pose in the world.
#[derive(Clone, Copy)]
pub struct ContactSide<'a> {
    /// The mesh, in its own frame.
    pub mesh: &'a TriMesh,
    /// Its edge adjacency (built on the welded mesh, so that neighbours share vertex indices).
    pub adjacency: &'a EdgeAdjacency,
    /// The mesh frame's pose in the world.
    pub pose: &'a Pose,
}

impl ContactSide<'_> {
    /// The corners of triangle `t` in the world frame.
    fn corners(&self, t: u32) -> [Point; 3] {
        self.mesh.triangle(t as usize).map(|p| self.pose * p)
    }
}

/// Where the edges of one triangle pass through another: up to three crossings.
#[derive(Debug, Clone, Copy, Default)]
struct Crossings {
    count: usize,
    edges: [usize; 3],
    points: [Point; 3],
}

impl Crossings {
    /// The crossings of the edges of `t` (edge `i` runs from corner `i` to corner `i + 1`) with
    /// triangle `through`. Coplanar edges never count as crossings.
    fn of(t: &[Point; 3], through: &[Point; 3]) -> Crossings {
        let mut crossings = Crossings::default();
        let normal = plane_normal(through);
        let distance = t.map(|v| normal.dot(&(v - through[0])));
        for edge in 0..3 {
            let (i, j) = (edge, (edge + 1) % 3);
            let (di, dj) = (distance[i], distance[j]);
            if (di > 0.0 && dj > 0.0) || (di < 0.0 && dj < 0.0) || di == dj {
                continue;
            }
            let point = t[i] + (t[j] - t[i]) * (di / (di - dj));
            if contains_coplanar_point(through, &normal, &point) {
                crossings.edges[crossings.count] = edge;
                crossings.points[crossings.count] = point;
                crossings.count += 1;
            }
        }
        crossings
    }
}

/// A (non-unit) normal of the triangle's plane, with arbitrary sign.
fn plane_normal(t: &[Point; 3]) -> Vector3<f64> {
    (t[1] - t[0]).cross(&(t[2] - t[0]))
}

/// Whether `point`, in the plane of `t`, lies in `t` (boundary included, with rounding slack).
fn contains_coplanar_point(t: &[Point; 3], normal: &Vector3<f64>, point: &Point) -> bool {
    let slack = -1e-12 * normal.norm_squared();
    (0..3).all(|i| {
        let edge = t[(i + 1) % 3] - t[i];
        edge.cross(&(point - t[i])).dot(normal) >= slack
    })
}

/// What one side of a touching pair presents to the other.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Feature {
    /// A vertex: a fan of triangles around it pierces the other triangle.
    Vertex,
    /// A sharp edge (world vector); edges between coplanar triangles count as face.
    Edge(Vector3<f64>),
    /// The inside of a flat region.
    Face,
}

/// Sine of the angle between two triangles' planes below which the edge they share is not a
/// feature but a fold line of a flat region (cell boundaries of a subdivided face).
const FLAT_EDGE_SINE: f64 = 0.01;

impl ContactSide<'_> {
    /// The feature of triangle `t` touching the other triangle: from the count of its neighbours
    /// that `touch` it too, or, when none does (rims, shallow touches), from which of its edges
    /// cross the other triangle. A vertex inside a flat region (a cell corner of a subdivided
    /// face) is a face, as an edge between coplanar triangles is: a block's side dipping through
    /// a table at one of the table's grid corners is stopped by the table's face, not by a
    /// "vertex" pushing it back sideways.
    fn feature(&self, t: u32, touch: impl Fn(u32) -> bool, crossings: &Crossings) -> Feature {
        let edges = self.adjacency.triangle_edges(t as usize);
        // Per edge of `t`, how many triangles across it touch the other triangle.
        let across = edges.map(|edge| {
            (self.adjacency.edge_triangles(edge as usize).iter())
                .filter(|&&n| n != t && touch(n))
                .count()
        });
        let edge = match across.iter().sum::<usize>() {
            0 => match crossings.count {
                0 => return Feature::Face,
                1 => crossings.edges[0],
                _ => {
                    let crossing = |k: usize| crossings.edges[..crossings.count].contains(&k);
                    return self.vertex_unless_flat(t, [0, 1, 2].map(crossing));
                }
            },
            1 => (0..3)
                .find(|&k| across[k] > 0)
                .expect("one edge has a touching triangle"),
            _ => return self.vertex_unless_flat(t, across.map(|n| n > 0)),
        };
        let edge = edges[edge] as usize;
        if self.is_sharp(edge) {
            let [u, v] = self.adjacency.edge(edge);
            let vertices = self.mesh.vertices();
            Feature::Edge(self.pose * (vertices[v as usize] - vertices[u as usize]))
        } else {
            Feature::Face
        }
    }

    /// A vertex of triangle `t`, where its edges marked `involved` (edge `k` joins corners `k`
    /// and `k + 1`) meet the other triangle: the corner two of them share, or the ends of the
    /// only one; a face when every such corner lies inside a flat region.
    fn vertex_unless_flat(&self, t: u32, involved: [bool; 3]) -> Feature {
        let several = involved.iter().filter(|&&i| i).count() >= 2;
        // Corner `c` ends edges `c` and `c + 2`.
        let mut corners = (0..3).filter(|&c| {
            let (a, b) = (involved[c], involved[(c + 2) % 3]);
            if several { a && b } else { a || b }
        });
        if corners.all(|c| self.is_flat_vertex(self.mesh.triangles()[t as usize][c])) {
            Feature::Face
        } else {
            Feature::Vertex
        }
    }

    /// Whether no edge at `vertex` is sharp: it lies inside a flat region.
    fn is_flat_vertex(&self, vertex: u32) -> bool {
        let triangles = self.mesh.triangles();
        (self.adjacency.vertex_triangles(vertex as usize).iter()).all(|&n| {
            let corners = triangles[n as usize];
            let edges = self.adjacency.triangle_edges(n as usize);
            (0..3)
                .filter(|&k| corners[k] == vertex || corners[(k + 1) % 3] == vertex)
                .all(|k| !self.is_sharp(edges[k] as usize))
        })
    }

    /// Whether an edge is a geometric feature: a rim, non-manifold, or folded.
    fn is_sharp(&self, edge: usize) -> bool {
        let &[a, b] = self.adjacency.edge_triangles(edge) else {
            return true;
        };
        let na = plane_normal(&self.mesh.triangle(a as usize)).normalize();
        let nb = plane_normal(&self.mesh.triangle(b as usize)).normalize();
        na.cross(&nb).norm() > FLAT_EDGE_SINE
    }
}

/// Classifies every touching pair of one obstacle and appends one contact per pair to `out`.
///
/// `pairs` must be sorted (they are looked up by binary search); `approach` is the motion of the
/// part's pivot from the last free pose to the colliding one, and `pivot` the pivot's world
/// position at the colliding pose.
pub fn classify_pairs(
    obstacle: usize,
    part: &ContactSide<'_>,
    other: &ContactSide<'_>,
    pairs: &[TouchingPair],
    approach: &Motion,
    pivot: &Point,
    out: &mut Vec<Contact>,
) {
    debug_assert!(pairs.is_sorted());
    let touching = |p: u32, q: u32| pairs.binary_search(&[p, q]).is_ok();
    for &[p, q] in pairs {
        let tp = part.corners(p);
        let tq = other.corners(q);
        let crossings_p = Crossings::of(&tp, &tq);
        let crossings_q = Crossings::of(&tq, &tp);
        let point = contact_point(&crossings_p, &crossings_q, &tp, &tq);
        let approach_at_point = approach.point_displacement(&(point - pivot));
        let feature_p = part.feature(p, |n| touching(n, q), &crossings_p);
        let feature_q = other.feature(q, |n| touching(p, n), &crossings_q);
        let (kind, normal) = match (feature_p, feature_q) {
            (Feature::Vertex, Feature::Vertex) | (Feature::Face, Feature::Face) => {
                (ContactKind::FaceFace, plane_normal(&tq))
            }
            (Feature::Vertex | Feature::Edge(_), Feature::Face) | (Feature::Vertex, _) => {
                (ContactKind::VertexFace, plane_normal(&tq))
            }
            (Feature::Face, Feature::Edge(_)) | (_, Feature::Vertex) => {
                (ContactKind::FaceVertex, plane_normal(&tp))
            }
            (Feature::Edge(ep), Feature::Edge(eq)) => (
                ContactKind::EdgeEdge,
                edge_edge_normal(&ep, &eq, &approach_at_point),
            ),
        };
        if let Some(normal) = orient(normal, &approach_at_point, &tp, &tq) {
            out.push(Contact {
                obstacle,
                point,
                normal,
                kind,
            });
        }
    }
}

/// The normal across two edges; for (nearly) parallel edges, the part of the reversed approach
/// that is perpendicular to the obstacle's edge (the part is stopped against the edge only).
fn edge_edge_normal(ep: &Vector3<f64>, eq: &Vector3<f64>, approach: &Vector3<f64>) -> Vector3<f64> {
    let cross = ep.cross(eq);
    // sin of 1 degree: below it the cross product's direction is mostly rounding.
    if cross.norm_squared() > 3.0e-4 * ep.norm_squared() * eq.norm_squared() {
        return cross;
    }
    let along = eq.normalize();
    -(approach - along * along.dot(approach))
}

/// Orients a contact normal so that it points against the approach; when the approach is
/// tangential (a graze), from the obstacle triangle's centroid towards the part triangle's.
/// None for a degenerate normal.
fn orient(
    normal: Vector3<f64>,
    approach: &Vector3<f64>,
    tp: &[Point; 3],
    tq: &[Point; 3],
) -> Option<Unit<Vector3<f64>>> {
    let normal = Unit::try_new(normal, 1e-300)?;
    let along_approach = normal.dot(approach);
    let sign = if along_approach.abs() > 1e-6 * approach.norm() {
        -along_approach
    } else {
        normal.dot(&(centroid(tp) - centroid(tq)))
    };
    Some(if sign < 0.0 { -normal } else { normal })
}

fn centroid(t: &[Point; 3]) -> Point {
    Point3::from((t[0].coords + t[1].coords + t[2].coords) / 3.0)
}

/// The middle of the pair's intersection: the mean of the edge crossings (or of the two
/// centroids when the triangles are coplanar and no edge crosses).
fn contact_point(cp: &Crossings, cq: &Crossings, tp: &[Point; 3], tq: &[Point; 3]) -> Point {
    let count = cp.count + cq.count;
    if count == 0 {
        return Point3::from((centroid(tp).coords + centroid(tq).coords) / 2.0);
    }
    let sum: Vector3<f64> = cp.points[..cp.count]
        .iter()
        .chain(&cq.points[..cq.count])
        .map(|p| p.coords)
        .sum();
    Point3::from(sum / count as f64)
}

/// A cluster of contacts with similar normals: its first normal, a basis of its tangent plane, and
/// per tangent direction the farthest reach seen and the index of the contact with it.
type Cluster<const D: usize> = (
    Unit<Vector3<f64>>,
    [Vector3<f64>; 2],
    [Option<(f64, usize)>; D],
);

/// Reduces contacts in place to those that shape the free space: contacts are clustered by normal
/// (within `cluster_angle` radians of a cluster's first normal), and each cluster keeps only its
/// points extreme in eight directions of its tangent plane. A face lying on a face thus costs at
/// most eight constraints, whatever the triangle count, and still blocks tilting both ways.
/// `contact` reads the contact out of an item, so that callers can reduce their own records.
pub fn reduce_contacts<T>(
    items: &mut Vec<T>,
    contact: impl Fn(&T) -> &Contact,
    cluster_angle: f64,
) {
    const DIRECTIONS: usize = 8;
    let cos_limit = cluster_angle.cos();
    // Each cluster: its first normal, a tangent basis, and the best contact per direction.
    let mut clusters: Vec<Cluster<DIRECTIONS>> = Vec::new();
    for (index, contact) in items.iter().map(&contact).enumerate() {
        let cluster = match clusters
            .iter_mut()
            .position(|(normal, _, _)| normal.dot(&contact.normal) >= cos_limit)
        {
            Some(i) => &mut clusters[i],
            None => {
                let n = contact.normal;
                let helper = if n.x.abs() < 0.6 {
                    Vector3::x()
                } else {
                    Vector3::y()
                };
                let t1 = n.cross(&helper).normalize();
                let t2 = n.cross(&t1);
                clusters.push((n, [t1, t2], [None; DIRECTIONS]));
                clusters.last_mut().expect("just pushed")
            }
        };
        let (_, [t1, t2], best) = cluster;
        for (k, slot) in best.iter_mut().enumerate() {
            let angle = k as f64 * std::f64::consts::TAU / DIRECTIONS as f64;
            let direction = *t1 * angle.cos() + *t2 * angle.sin();
            let reach = direction.dot(&contact.point.coords);
            if slot.is_none_or(|(r, _)| reach > r) {
                *slot = Some((reach, index));
            }
        }
    }
    let mut keep: Vec<usize> = clusters
        .iter()
        .flat_map(|(_, _, best)| best.iter().flatten().map(|&(_, i)| i))
        .collect();
    keep.sort_unstable();
    keep.dedup();
    let mut index = 0;
    let mut next_kept = keep.iter().peekable();
    items.retain(|_| {
        let kept = next_kept.next_if_eq(&&index).is_some();
        index += 1;
        kept
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn p(x: f64, y: f64, z: f64) -> Point {
        Point::new(x, y, z)
    }

    fn mesh(vertices: Vec<Point>, triangles: Vec<[u32; 3]>) -> (TriMesh, EdgeAdjacency) {
        let mesh = TriMesh::new(vertices, triangles).unwrap().0;
        let adjacency = EdgeAdjacency::new(&mesh);
        (mesh, adjacency)
    }

    /// A square sheet in z = 0, two triangles, with either winding.
    fn sheet(flip: bool) -> (TriMesh, EdgeAdjacency) {
        let t = if flip {
            [[0, 2, 1], [0, 2, 3]]
        } else {
            [[0, 1, 2], [0, 3, 2]]
        };
        let v = vec![
            p(-1., -1., 0.),
            p(1., -1., 0.),
            p(1., 1., 0.),
            p(-1., 1., 0.),
        ];
        mesh(v, t.to_vec())
    }

    /// A pyramid whose apex, at `depth` below z = 0, points down; four side triangles, open top.
    fn pyramid(depth: f64) -> (TriMesh, EdgeAdjacency) {
        let h = 0.3 - depth;
        let v = vec![
            p(0., 0., -depth),
            p(-0.3, -0.3, h),
            p(0.3, -0.3, h),
            p(0.3, 0.3, h),
            p(-0.3, 0.3, h),
        ];
        mesh(v, vec![[0, 1, 2], [0, 3, 2], [0, 3, 4], [0, 1, 4]])
    }

    /// A roof of two triangles along `axis` (x or y) with its ridge at height `ridge`, sloping
    /// away from it by `slope` (negative: a trough pointing down).
    fn roof(along_x: bool, ridge: f64, slope: f64) -> (TriMesh, EdgeAdjacency) {
        let put = |a: f64, b: f64, z: f64| if along_x { p(a, b, z) } else { p(b, a, z) };
        let v = vec![
            put(-1., 0., ridge),
            put(1., 0., ridge),
            put(-1., -1., ridge - slope),
            put(1., -1., ridge - slope),
            put(-1., 1., ridge - slope),
            put(1., 1., ridge - slope),
        ];
        mesh(v, vec![[0, 1, 2], [1, 3, 2], [0, 1, 4], [1, 5, 4]])
    }

    /// Brute-force touching pairs of two posed meshes, by the classification's own edge test
    /// (enough here: the test meshes cross generically).
    fn touching(a: &ContactSide<'_>, b: &ContactSide<'_>) -> Vec<TouchingPair> {
        let mut pairs = Vec::new();
        for i in 0..a.mesh.triangles().len() as u32 {
            for j in 0..b.mesh.triangles().len() as u32 {
                let (ta, tb) = (a.corners(i), b.corners(j));
                if Crossings::of(&ta, &tb).count + Crossings::of(&tb, &ta).count > 0 {
                    pairs.push([i, j]);
                }
            }
        }
        pairs
    }

    fn classify(
        part: &(TriMesh, EdgeAdjacency),
        obstacle: &(TriMesh, EdgeAdjacency),
        approach: Vector3<f64>,
    ) -> Vec<Contact> {
        let identity = Pose::identity();
        let a = ContactSide {
            mesh: &part.0,
            adjacency: &part.1,
            pose: &identity,
        };
        let b = ContactSide {
            mesh: &obstacle.0,
            adjacency: &obstacle.1,
            pose: &identity,
        };
        let pairs = touching(&a, &b);
        assert!(!pairs.is_empty(), "the test meshes do not touch");
        let motion = Motion {
            translation: approach,
            rotation: Vector3::zeros(),
        };
        let mut out = Vec::new();
        classify_pairs(3, &a, &b, &pairs, &motion, &Point::origin(), &mut out);
        assert_eq!(out.len(), pairs.len());
        out
    }

    #[test]
    fn a_vertex_in_a_face_gets_the_face_normal_whatever_the_winding_and_side() {
        for flip in [false, true] {
            let down = classify(&pyramid(0.01), &sheet(flip), Vector3::new(0.0, 0.0, -1.0));
            for c in &down {
                assert_eq!(c.kind, ContactKind::VertexFace);
                assert!(
                    (c.normal.into_inner() - Vector3::z()).norm() < 1e-12,
                    "{:?}",
                    c.normal
                );
                assert_eq!(c.obstacle, 3);
                assert!(c.point.coords.norm() < 0.02, "point {:?}", c.point);
            }
            // The same touch reached from below (a sheet has no inside): the normal flips.
            let up = classify(&pyramid(0.01), &sheet(flip), Vector3::new(0.2, 0.0, 1.0));
            assert!(
                up.iter()
                    .all(|c| (c.normal.into_inner() + Vector3::z()).norm() < 1e-12)
            );
        }
    }

    #[test]
    fn a_vertex_of_the_obstacle_in_a_face_of_the_part_gets_the_part_face_normal() {
        // The pyramid is the obstacle, pointing up into the part's sheet at z = 0.
        let (m, _) = pyramid(0.01);
        let flipped = m.map_vertices(|v| p(v.x, v.y, -v.z)).unwrap();
        let obstacle = (flipped.clone(), EdgeAdjacency::new(&flipped));
        let contacts = classify(&sheet(false), &obstacle, Vector3::new(0.0, 0.0, -1.0));
        for c in &contacts {
            assert_eq!(c.kind, ContactKind::FaceVertex);
            assert!((c.normal.into_inner() - Vector3::z()).norm() < 1e-12);
        }
    }

    /// A 2 x 2 square sheet in z = 0 of four cells, each cut along its x = y diagonal: its
    /// middle vertex is inside the flat sheet, the middles of its sides on its rim.
    fn subdivided_sheet() -> (TriMesh, EdgeAdjacency) {
        let vertex = |i: u32, j: u32| i * 3 + j;
        let vertices = (0..3)
            .flat_map(|i| (0..3).map(move |j| p(f64::from(i) - 1.0, f64::from(j) - 1.0, 0.0)))
            .collect();
        let triangles = (0..2)
            .flat_map(|i| (0..2).map(move |j| (i, j)))
            .flat_map(|(i, j)| {
                let [a, b, c, d] =
                    [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)].map(|(x, y)| vertex(x, y));
                [[a, b, c], [a, c, d]]
            })
            .collect();
        mesh(vertices, triangles)
    }

    /// A wall in the plane x = `x`, its lower rim 1 mm below z = 0.
    fn wall(x: f64) -> (TriMesh, EdgeAdjacency) {
        let v = vec![p(x, -0.5, -0.001), p(x, 0.5, -0.001), p(x, 0.0, 0.5)];
        mesh(v, vec![[0, 1, 2]])
    }

    #[test]
    fn a_wall_dipping_into_a_face_at_a_cell_corner_gets_the_face_normal_and_at_a_rim_the_wall_normal()
     {
        // Sliding along +x and a little down, the wall's foot dips into the sheet beside the
        // sheet's middle vertex: a corner of its cells, inside its face, which holds the wall up
        // and never pushes it back.
        let approach = Vector3::new(1.0, 0.0, -0.1);
        let inside = classify(&wall(-0.001), &subdivided_sheet(), approach);
        for c in &inside {
            assert!(
                (c.normal.into_inner() - Vector3::z()).norm() < 1e-12,
                "{c:?}"
            );
        }
        // Beside the middle of the sheet's rim, a vertex of the sheet's rim meets the wall.
        let rim = classify(&wall(0.999), &subdivided_sheet(), approach);
        assert!(
            rim.iter().any(|c| c.kind == ContactKind::FaceVertex
                && (c.normal.into_inner() + Vector3::x()).norm() < 1e-12),
            "{rim:?}"
        );
    }

    #[test]
    fn crossing_ridges_are_edge_edge_with_the_normal_across_both_edges() {
        // The part: a trough along x pointing down; the obstacle: a ridge along y pointing up,
        // crossed by 0.01. Edge cross product: x × y = z, oriented against the approach (-z).
        let part = roof(true, -0.005, -0.5);
        let obstacle = roof(false, 0.005, 0.5);
        let contacts = classify(&part, &obstacle, Vector3::new(0.1, 0.0, -1.0));
        assert!(contacts.iter().any(|c| c.kind == ContactKind::EdgeEdge));
        for c in contacts.iter().filter(|c| c.kind == ContactKind::EdgeEdge) {
            assert!(
                (c.normal.into_inner() - Vector3::z()).norm() < 1e-9,
                "{:?}",
                c.normal
            );
            assert!(c.point.coords.norm() < 0.05);
        }
    }

    #[test]
    fn a_lone_triangle_rim_through_a_face_is_classified_by_its_crossing_edges() {
        // One triangle (no neighbours at all) dipping a corner through the sheet: n_p = 0, so the
        // rim rule decides from the edges that cross.
        let part = mesh(
            vec![p(0.3, -0.2, -0.01), p(0.8, -0.1, 0.3), p(-0.1, 0.0, 0.3)],
            vec![[0, 1, 2]],
        );
        let contacts = classify(&part, &sheet(true), Vector3::new(0.0, 0.0, -1.0));
        assert_eq!(contacts.len(), 1);
        assert_eq!(contacts[0].kind, ContactKind::VertexFace);
        assert!((contacts[0].normal.into_inner() - Vector3::z()).norm() < 1e-12);
        // A sheet's rim edge through a part face: face/vertex, the part face's normal.
        let blade = mesh(
            vec![p(-0.8, 0.4, -0.3), p(0.2, 0.4, -0.3), p(-0.3, 0.4, 0.01)],
            vec![[0, 1, 2]],
        );
        let contacts = classify(&sheet(false), &blade, Vector3::new(0.0, 0.0, -1.0));
        assert_eq!(contacts.len(), 1);
        assert!(contacts.iter().all(|c| c.kind == ContactKind::FaceVertex));
        assert!(
            contacts
                .iter()
                .all(|c| (c.normal.into_inner() - Vector3::z()).norm() < 1e-12)
        );
    }

    #[test]
    fn reduction_keeps_the_extremes_of_each_normal_cluster() {
        let contact = |x: f64, y: f64, n: Vector3<f64>| Contact {
            obstacle: 0,
            point: p(x, y, 0.0),
            normal: Unit::new_normalize(n),
            kind: ContactKind::FaceFace,
        };
        let mut contacts = Vec::new();
        for i in 0..10 {
            for j in 0..10 {
                contacts.push(contact(i as f64, j as f64, Vector3::z()));
            }
        }
        contacts.push(contact(5.0, 5.0, Vector3::x()));
        reduce_contacts(&mut contacts, |c| c, 0.02);
        let floor: Vec<_> = contacts.iter().filter(|c| c.normal.z > 0.5).collect();
        assert!(floor.len() <= 8 && floor.len() >= 4, "{} kept", floor.len());
        for corner in [(0.0, 0.0), (9.0, 0.0), (0.0, 9.0), (9.0, 9.0)] {
            assert!(
                floor.iter().any(|c| (c.point.x, c.point.y) == corner),
                "{corner:?} dropped"
            );
        }
        assert_eq!(contacts.iter().filter(|c| c.normal.x > 0.5).count(), 1);
    }
}
