//! Rows of vertices joined by strips: what every shape is built from.

use std::f64::consts::TAU;

use crate::geometry::mesh::{Point, TriMesh};
use crate::geometry::weld::weld;

/// Accumulates vertices and triangles; shapes are made of rows of vertices joined by strips.
#[derive(Default)]
pub(super) struct MeshBuilder {
    vertices: Vec<Point>,
    triangles: Vec<[u32; 3]>,
}

impl MeshBuilder {
    /// Adds the points as new vertices and returns their indices.
    pub(super) fn row(&mut self, points: impl IntoIterator<Item = Point>) -> Vec<u32> {
        points
            .into_iter()
            .map(|p| {
                self.vertices.push(p);
                (self.vertices.len() - 1) as u32
            })
            .collect()
    }

    /// Joins two rows of equal length with quads (a[j], a[j+1], b[j+1], b[j]), each split into
    /// two triangles; `closed` also joins the last column to the first. The normal is
    /// (a[j+1] - a[j]) x (b[j] - a[j]). Triangles with a repeated vertex (where a row collapses to
    /// a pole) are skipped.
    pub(super) fn strip(&mut self, a: &[u32], b: &[u32], closed: bool) {
        let n = a.len();
        let columns = if closed { n } else { n - 1 };
        for j in 0..columns {
            let k = (j + 1) % n;
            for t in [[a[j], a[k], b[k]], [a[j], b[k], b[j]]] {
                if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                    self.triangles.push(t);
                }
            }
        }
    }

    /// Revolves a profile of (r, z) points around z with `segments` segments (vertex j at angle
    /// 360° j / segments). Points with r = 0 become single pole vertices; `closed` joins the last
    /// profile point back to the first. Normals point to the right of the profile's direction
    /// in the (r, z) plane, i.e. outwards for a counter-clockwise profile.
    pub(super) fn revolve(&mut self, profile: &[[f64; 2]], closed: bool, segments: usize) {
        let rows: Vec<Vec<u32>> = profile
            .iter()
            .map(|&[r, z]| {
                if r == 0.0 {
                    let pole = self.row([Point::new(0.0, 0.0, z)])[0];
                    vec![pole; segments]
                } else {
                    self.row((0..segments).map(|j| {
                        let angle = TAU * j as f64 / segments as f64;
                        Point::new(r * angle.cos(), r * angle.sin(), z)
                    }))
                }
            })
            .collect();
        for pair in rows.windows(2) {
            self.strip(&pair[0], &pair[1], true);
        }
        if closed {
            self.strip(&rows[rows.len() - 1], &rows[0], true);
        }
    }

    pub(super) fn finish(self) -> TriMesh {
        TriMesh::new(self.vertices, self.triangles)
            .expect("procedural shapes with validated dimensions are valid meshes")
            .0
    }

    /// Finishes and merges vertices closer than `tolerance`, for shapes built from separate
    /// pieces.
    pub(super) fn finish_welded(self, tolerance: f64) -> TriMesh {
        weld(&self.finish(), tolerance)
    }
}
