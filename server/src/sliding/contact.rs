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
//! Stored normals and winding are never used: a plane normal comes from a cross product of the
//! triangle's edges, and every normal is oriented against the approach, the motion of the contact
//! point from the last free pose to the colliding one. So inconsistent winding and sheets touched
//! from either side need no special case.

use nalgebra::{Point3, Unit, Vector3};

use super::motion::Motion;
use crate::geometry::Point;

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

/// Triangles sharing an edge with a given triangle: what the classification counts.
pub trait TriangleNeighbours {
    /// The triangles that share an edge with `triangle`.
    fn neighbours(&self, triangle: u32) -> impl Iterator<Item = u32> + '_;
}

/// One side of a contact: its triangles in the world frame and their adjacency.
pub struct ContactSide<'a, N> {
    /// The three corners, in world coordinates, of triangle `t`.
    pub corners: &'a dyn Fn(u32) -> [Point; 3],
    /// The vertex indices of triangle `t` (to find the edge two triangles share).
    pub indices: &'a dyn Fn(u32) -> [u32; 3],
    /// Edge adjacency of the side's mesh.
    pub neighbours: &'a N,
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

    fn edge_vector(&self, t: &[Point; 3]) -> Option<Vector3<f64>> {
        (self.count > 0).then(|| t[(self.edges[0] + 1) % 3] - t[self.edges[0]])
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

/// The edge two triangles share, as a vector; None if they share no two vertex indices.
fn shared_edge(a: [u32; 3], b: [u32; 3], corners_a: &[Point; 3]) -> Option<Vector3<f64>> {
    let mut shared = (0..3).filter(|&i| b.contains(&a[i]));
    let (i, j) = (shared.next()?, shared.next()?);
    Some(corners_a[j] - corners_a[i])
}

/// Classifies every touching pair of one obstacle and appends one contact per pair to `out`.
///
/// `pairs` must be sorted (they are looked up by binary search); `approach` is the motion of the
/// part's pivot from the last free pose to the colliding one, and `pivot` the pivot's world
/// position at the colliding pose.
pub fn classify_pairs<P: TriangleNeighbours, Q: TriangleNeighbours>(
    obstacle: usize,
    part: &ContactSide<'_, P>,
    other: &ContactSide<'_, Q>,
    pairs: &[TouchingPair],
    approach: &Motion,
    pivot: &Point,
    out: &mut Vec<Contact>,
) {
    debug_assert!(pairs.is_sorted());
    let touching = |p: u32, q: u32| pairs.binary_search(&[p, q]).is_ok();
    for &[p, q] in pairs {
        let tp = (part.corners)(p);
        let tq = (other.corners)(q);
        let p_neighbour =
            first_and_count(part.neighbours.neighbours(p).filter(|&n| touching(n, q)));
        let q_neighbour =
            first_and_count(other.neighbours.neighbours(q).filter(|&n| touching(p, n)));
        let crossings_p = Crossings::of(&tp, &tq);
        let crossings_q = Crossings::of(&tq, &tp);
        let point = contact_point(&crossings_p, &crossings_q, &tp, &tq);
        let approach_at_point = approach.point_displacement(&(point - pivot));

        let (kind, normal) = match (p_neighbour, q_neighbour) {
            (Some((np, 1)), Some((nq, 1))) => {
                let edges = shared_edge((part.indices)(p), (part.indices)(np), &tp)
                    .zip(shared_edge((other.indices)(q), (other.indices)(nq), &tq));
                match edges {
                    Some((ep, eq)) => (
                        ContactKind::EdgeEdge,
                        edge_edge_normal(&ep, &eq, &approach_at_point),
                    ),
                    None => by_crossings(&crossings_p, &crossings_q, &tp, &tq, &approach_at_point),
                }
            }
            (Some((_, a)), Some((_, b))) if a > 1 && b > 1 => {
                (ContactKind::FaceFace, plane_normal(&tq))
            }
            (Some((_, a)), _) if a > 1 => (ContactKind::VertexFace, plane_normal(&tq)),
            (_, Some((_, b))) if b > 1 => (ContactKind::FaceVertex, plane_normal(&tp)),
            _ => by_crossings(&crossings_p, &crossings_q, &tp, &tq, &approach_at_point),
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

/// The first item of an iterator and how many there are; None when empty.
fn first_and_count(mut items: impl Iterator<Item = u32>) -> Option<(u32, usize)> {
    let first = items.next()?;
    Some((first, 1 + items.count()))
}

/// The rim rule: which triangle's edges cross the other decides the kind and the normal.
fn by_crossings(
    crossings_p: &Crossings,
    crossings_q: &Crossings,
    tp: &[Point; 3],
    tq: &[Point; 3],
    approach: &Vector3<f64>,
) -> (ContactKind, Vector3<f64>) {
    match (crossings_p.edge_vector(tp), crossings_q.edge_vector(tq)) {
        (Some(ep), Some(eq)) => (ContactKind::EdgeEdge, edge_edge_normal(&ep, &eq, approach)),
        (Some(_), None) => (ContactKind::VertexFace, plane_normal(tq)),
        (None, Some(_)) => (ContactKind::FaceVertex, plane_normal(tp)),
        (None, None) => (ContactKind::FaceFace, plane_normal(tq)),
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
