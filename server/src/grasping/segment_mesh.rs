//! Collision meshes of the hand's segments: closed convex polytopes of a few hundred triangles.
//!
//! A segment's shape is the convex hull of spheres around a few centres ([`SweptHull`]); its mesh
//! is the convex hull of points on those spheres. Every vertex lies on a sphere, so the mesh lies
//! inside the ideal shape and is exactly what collision detection and the tests' oracle both see.

use std::collections::HashMap;

use nalgebra::Point3;
use parry3d::shape::Ball;
use parry3d::transformation::try_convex_hull;
use thiserror::Error;

use super::model::SweptHull;
use crate::collision::orientation::OrientationError;
use crate::geometry::{MeshError, TriMesh};

/// Subdivisions around each sphere (longitude).
const SPHERE_LONGITUDES: u32 = 14;
/// Subdivisions from pole to pole (latitude).
const SPHERE_LATITUDES: u32 = 8;

/// Why a segment mesh could not be built.
#[derive(Debug, Error)]
pub enum SegmentMeshError {
    /// The hull computation failed (degenerate input).
    #[error("convex hull of the segment's spheres failed: {0:?}")]
    Hull(parry3d::transformation::ConvexHullError),
    /// The hull is not a valid mesh.
    #[error("segment mesh: {0}")]
    Mesh(#[from] MeshError),
    /// The segments' DOP-trees cannot have the orientation count asked for.
    #[error("segment DOP-trees: {0}")]
    Orientations(#[from] OrientationError),
}

/// The closed mesh of `shape` with every sphere's radius grown by `inflate` metres (0 for the
/// collision mesh; a little for the contact probe that finds what a touching segment touches).
pub fn swept_hull_mesh(shape: &SweptHull, inflate: f64) -> Result<TriMesh, SegmentMeshError> {
    // parry3d computes in f32: fine for centimetre-sized hulls, whose vertices we keep in f64.
    let (sphere, _) =
        Ball::new((shape.radius + inflate) as f32).to_trimesh(SPHERE_LONGITUDES, SPHERE_LATITUDES);
    let points: Vec<parry3d::math::Point<f32>> = shape
        .centres
        .iter()
        .flat_map(|c| {
            let c = c.cast::<f32>();
            sphere.iter().map(move |p| p + c.coords)
        })
        .collect();
    let (vertices, triangles) = try_convex_hull(&points).map_err(SegmentMeshError::Hull)?;
    let vertices = vertices
        .iter()
        .map(|p| p.cast::<f64>())
        .collect::<Vec<Point3<f64>>>();
    let (vertices, triangles) = refine(vertices, triangles, MAX_EDGE);
    Ok(TriMesh::new(vertices, triangles)?.0)
}

/// Longest edge of a segment mesh (metres). A convex hull has a few large flat faces and long
/// thin triangles along its rounded edges; their bounding volumes are loose, and a segment
/// resting a fraction of a millimetre from a finely tessellated part then costs thousands of
/// triangle tests. Small triangles keep the leaves of the segment's DOP-tree tight.
const MAX_EDGE: f64 = 0.008;

/// Splits every edge longer than `max_edge` at its midpoint, re-triangulating the triangles
/// around it, until no edge is longer. New vertices lie on the old edges, so the surface is
/// unchanged, and shared edges are split once for both triangles, so a closed mesh stays closed.
fn refine(
    mut vertices: Vec<Point3<f64>>,
    mut triangles: Vec<[u32; 3]>,
    max_edge: f64,
) -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
    loop {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                if !midpoints.contains_key(&key)
                    && (vertices[a as usize] - vertices[b as usize]).norm() > max_edge
                {
                    let middle = nalgebra::center(&vertices[a as usize], &vertices[b as usize]);
                    midpoints.insert(key, vertices.len() as u32);
                    vertices.push(middle);
                }
            }
        }
        if midpoints.is_empty() {
            return (vertices, triangles);
        }
        let mut refined = Vec::with_capacity(triangles.len() * 4);
        for t in triangles {
            split_triangle(
                t,
                |a, b| midpoints.get(&(a.min(b), a.max(b))).copied(),
                &mut refined,
            );
        }
        triangles = refined;
    }
}

/// Appends the triangles that replace `t` once some of its edges have midpoints (`midpoint(a, b)`),
/// keeping its winding.
fn split_triangle(
    t: [u32; 3],
    midpoint: impl Fn(u32, u32) -> Option<u32>,
    out: &mut Vec<[u32; 3]>,
) {
    // Rotate the corners so that the split edges come first: (0,1), then (1,2), then (2,0).
    for r in 0..3 {
        let [a, b, c] = [t[r], t[(r + 1) % 3], t[(r + 2) % 3]];
        match (midpoint(a, b), midpoint(b, c), midpoint(c, a)) {
            (None, None, None) => {
                out.push([a, b, c]);
                return;
            }
            (Some(ab), None, None) => {
                out.extend([[a, ab, c], [ab, b, c]]);
                return;
            }
            (Some(ab), Some(bc), None) => {
                out.extend([[a, ab, c], [ab, b, bc], [ab, bc, c]]);
                return;
            }
            (Some(ab), Some(bc), Some(ca)) => {
                out.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
                return;
            }
            // Another rotation puts the split edges first.
            _ => {}
        }
    }
    unreachable!("every pattern of split edges is a rotation of one handled above")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasping::model::tests::right_hand;
    use std::collections::HashMap;

    /// Every edge of a closed triangle mesh is shared by exactly two triangles.
    fn is_closed(mesh: &TriMesh) -> bool {
        let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
        for t in mesh.triangles() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        edges.values().all(|&n| n == 2)
    }

    #[test]
    fn every_segment_mesh_is_closed_fits_its_shape_and_has_only_small_triangles() {
        let model = right_hand();
        for segment in model.segments() {
            let mesh = swept_hull_mesh(&segment.shape, 0.0).unwrap();
            assert!(is_closed(&mesh), "{} is not closed", segment.name);
            for i in 0..mesh.triangles().len() {
                let [a, b, c] = mesh.triangle(i);
                let longest = (a - b).norm().max((b - c).norm()).max((c - a).norm());
                assert!(
                    longest <= MAX_EDGE + 1e-12,
                    "{}: edge of {longest} m",
                    segment.name
                );
            }
            // Every vertex is on the swept surface (within f32 rounding), or a little inside it
            // between the spheres' sample points. The centres of our shapes span an
            // axis-aligned segment or rectangle, which is their own hull: distances to it clamp.
            let (lo, hi) = segment.shape.centres.iter().fold(
                (segment.shape.centres[0], segment.shape.centres[0]),
                |(lo, hi), c| (lo.inf(c), hi.sup(c)),
            );
            for v in mesh.vertices() {
                let nearest = Point3::from(v.coords.zip_zip_map(
                    &lo.coords,
                    &hi.coords,
                    |x, l, h| x.clamp(l, h),
                ));
                let depth = segment.shape.radius - (v - nearest).norm();
                assert!(
                    (-1e-6..0.05 * segment.shape.radius).contains(&depth),
                    "{}: {depth}",
                    segment.name
                );
            }
            // The mesh spans its shape: along +y it reaches the last centre plus the radius.
            let (_, hi) = mesh.bounding_box();
            let top = segment
                .shape
                .centres
                .iter()
                .map(|c| c.y)
                .fold(f64::MIN, f64::max);
            assert!(
                (hi.y - top - segment.shape.radius).abs() < 1e-6,
                "{}",
                segment.name
            );
            let probe = swept_hull_mesh(&segment.shape, 0.001).unwrap();
            assert!((probe.bounding_box().1.y - hi.y - 0.001).abs() < 1e-6);
        }
    }

    #[test]
    fn refining_keeps_the_surface_and_closes_shared_edges() {
        // A tetrahedron with 10 cm edges, refined to 3 cm: every new vertex lies on an old edge.
        let corners = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.1, 0.0, 0.0),
            Point3::new(0.0, 0.1, 0.0),
            Point3::new(0.0, 0.0, 0.1),
        ];
        let faces = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let (vertices, triangles) = refine(corners.clone(), faces.clone(), 0.03);
        let mesh = TriMesh::new(vertices, triangles).unwrap().0;
        assert!(is_closed(&mesh));
        assert!(mesh.triangles().len() > 4 * 16);
        let area = |m: &TriMesh| {
            (0..m.triangles().len())
                .map(|i| {
                    let [a, b, c] = m.triangle(i);
                    (b - a).cross(&(c - a)).norm() / 2.0
                })
                .sum::<f64>()
        };
        let original = TriMesh::new(corners, faces).unwrap().0;
        assert!((area(&mesh) - area(&original)).abs() < 1e-12);
        for v in mesh.vertices() {
            // On the tetrahedron's surface: one coordinate zero, or on the slanted face.
            let on_face = v.x.abs() < 1e-15
                || v.y.abs() < 1e-15
                || v.z.abs() < 1e-15
                || (v.x + v.y + v.z - 0.1).abs() < 1e-15;
            assert!(on_face, "{v}");
        }
    }
}
