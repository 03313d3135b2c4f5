//! The reference answer of the distance queries: every triangle pair measured. Quadratic, so
//! only for the tests and the benchmarks' checks.

use nalgebra::Isometry3;

use super::{ClosestPoints, triangle_distance};
use crate::collision::brute_force::posed_triangles;
use crate::geometry::TriMesh;

/// The least distance between `a` and `b` posed at `b_to_a` in A's frame, over all triangle
/// pairs (B moved as the DOP-tree moves it, so that the answers compare exactly); the first
/// least pair in index order. `None` when either mesh has no triangle.
pub fn brute_force_distance(
    a: &TriMesh,
    b: &TriMesh,
    b_to_a: &Isometry3<f64>,
) -> Option<ClosestPoints> {
    let moved = posed_triangles(b, b_to_a);
    let inverse = b_to_a.inverse();
    let mut best: Option<ClosestPoints> = None;
    for i in 0..a.triangles().len() {
        let ta = a.triangle(i);
        for (j, tb) in moved.iter().enumerate() {
            let found = triangle_distance(&ta, tb);
            if best.is_none_or(|b| found.distance < b.distance) {
                best = Some(ClosestPoints {
                    distance: found.distance,
                    on_a: found.on_first,
                    on_b: inverse * found.on_second,
                    triangles: [i as u32, j as u32],
                });
            }
        }
    }
    best
}
