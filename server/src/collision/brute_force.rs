//! The reference answer of the colliders: every triangle pair put to the exact test. Slow
//! (quadratic), so only for the oracle tests and the fuzz targets.

use nalgebra::{Isometry3, Point3};

use super::triangle::{Triangle, triangles_intersect};
use crate::geometry::TriMesh;

/// `b`'s triangles in A's frame, moved as the DOP-tree moves them (the rotation as a matrix,
/// then the translation), so that answers at touching contact compare exactly.
pub fn posed_triangles(b: &TriMesh, b_to_a: &Isometry3<f64>) -> Vec<Triangle> {
    let rotation = b_to_a.rotation.to_rotation_matrix();
    let translation = b_to_a.translation.vector;
    (0..b.triangles().len())
        .map(|j| {
            b.triangle(j)
                .map(|p| Point3::from(rotation.matrix() * p.coords + translation))
        })
        .collect()
}

/// Every intersecting pair `[triangle of A, triangle of B]`, with B posed at `b_to_a` in A's
/// frame, by testing all of them; sorted.
pub fn brute_force_pairs(a: &TriMesh, b: &TriMesh, b_to_a: &Isometry3<f64>) -> Vec<[u32; 2]> {
    let moved = posed_triangles(b, b_to_a);
    let mut pairs = Vec::new();
    for i in 0..a.triangles().len() {
        let ta = a.triangle(i);
        for (j, tb) in moved.iter().enumerate() {
            if triangles_intersect(&ta, tb) {
                pairs.push([i as u32, j as u32]);
            }
        }
    }
    pairs
}
