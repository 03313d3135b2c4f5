//! Collision meshes of the hand's segments: closed convex polytopes of a few hundred triangles.
//!
//! A segment's shape is the convex hull of spheres around a few centres ([`SweptHull`]); its mesh
//! is the convex hull of points on those spheres. Every vertex lies on a sphere, so the mesh lies
//! inside the ideal shape and is exactly what collision detection and the tests' oracle both see.

use nalgebra::Point3;
use parry3d::shape::Ball;
use parry3d::transformation::try_convex_hull;
use thiserror::Error;

use super::model::SweptHull;
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
    Ok(TriMesh::new(vertices, triangles)?.0)
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
    fn every_segment_mesh_is_closed_fits_its_shape_and_has_a_few_hundred_triangles() {
        let model = right_hand();
        for segment in model.segments() {
            let mesh = swept_hull_mesh(&segment.shape, 0.0).unwrap();
            let n = mesh.triangles().len();
            assert!((100..=600).contains(&n), "{}: {n} triangles", segment.name);
            assert!(is_closed(&mesh), "{} is not closed", segment.name);
            // Every vertex is on one of the spheres (within f32 rounding), none outside all.
            for v in mesh.vertices() {
                let nearest = segment
                    .shape
                    .centres
                    .iter()
                    .map(|c| (v - c).norm())
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    (nearest - segment.shape.radius).abs() < 1e-6,
                    "{}: {nearest}",
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
}
