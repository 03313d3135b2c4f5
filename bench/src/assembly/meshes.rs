//! The meshes of the generated assembly that the procedural shapes do not offer: open sheets of
//! an exact triangle count (the body panels), parts made of several shapes (bolts, brackets),
//! and the small fittings in their variety.

use nalgebra::{Isometry3, Point3, Quaternion, UnitQuaternion, Vector3};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use vas_server::geometry::{TriMesh, shapes};

/// An open sheet (one surface, no thickness) of exactly `triangles` triangles (at least 2): a
/// grid over the unit square, mapped into space by `surface(u, v)`. Its cells are near-square
/// when `aspect` is the sheet's length along u over its length along v. Where `triangles` does
/// not fill whole rows, the last row is partly filled (a ragged edge, as a trimmed panel has).
/// Triangles wind counter-clockwise seen from the side `du x dv` points to.
pub fn open_sheet(
    triangles: usize,
    aspect: f64,
    surface: impl Fn(f64, f64) -> Point3<f64>,
) -> TriMesh {
    assert!(triangles >= 2, "a sheet needs at least two triangles");
    let half = triangles / 2;
    let columns = ((half as f64 * aspect).sqrt().round() as usize).clamp(1, half);
    let full_rows = triangles / (2 * columns);
    let rest = triangles - 2 * columns * full_rows;
    let rows = full_rows + usize::from(rest > 0);
    let point = |i: usize, j: usize| surface(i as f64 / columns as f64, j as f64 / rows as f64);
    let mut vertices: Vec<Point3<f64>> = (0..=full_rows)
        .flat_map(|j| (0..=columns).map(move |i| (i, j)))
        .map(|(i, j)| point(i, j))
        .collect();
    let index = |i: usize, j: usize| (j * (columns + 1) + i) as u32;
    let mut faces = Vec::with_capacity(triangles);
    for j in 0..full_rows {
        for i in 0..columns {
            let (a, b, c, d) = (
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            );
            faces.extend([[a, b, c], [a, c, d]]);
        }
    }
    // The partial row: `rest` triangles over its first cells, the last cell maybe half filled.
    let top = vertices.len() as u32;
    vertices.extend((0..=rest.div_ceil(2)).map(|i| point(i, rows)));
    for t in 0..rest {
        let i = t / 2;
        let (a, b) = (index(i, full_rows), index(i + 1, full_rows));
        let (c, d) = (top + i as u32 + 1, top + i as u32);
        faces.push(if t % 2 == 0 { [a, b, c] } else { [a, c, d] });
    }
    mesh(vertices, faces)
}

/// One mesh of several pieces, each placed in the part's frame by its pose: a soup of closed
/// shells that may overlap, as CAD exports a part made of features.
pub fn combined(pieces: &[(TriMesh, Isometry3<f64>)]) -> TriMesh {
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    for (piece, pose) in pieces {
        let offset = vertices.len() as u32;
        vertices.extend(piece.vertices().iter().map(|v| pose * v));
        faces.extend(piece.triangles().iter().map(|t| t.map(|i| i + offset)));
    }
    mesh(vertices, faces)
}

/// The mesh of vertices and faces built valid by construction.
fn mesh(vertices: Vec<Point3<f64>>, faces: Vec<[u32; 3]>) -> TriMesh {
    let (mesh, cleanup) = TriMesh::new(vertices, faces).expect("a generated mesh is valid");
    assert_eq!(
        cleanup.degenerate_triangles_removed, 0,
        "a generated mesh has no degenerate triangle"
    );
    mesh
}

/// The kinds of small part that fill the assembly around its panels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fitting {
    /// An L of two plates.
    Bracket,
    /// A shaft with a head.
    Bolt,
    /// A box.
    Block,
    /// A capped cylinder.
    Cylinder,
    /// A tube.
    Pipe,
}

impl Fitting {
    /// Every kind, in the order a fitting's index picks them.
    pub const ALL: [Fitting; 5] = [
        Fitting::Bracket,
        Fitting::Bolt,
        Fitting::Block,
        Fitting::Cylinder,
        Fitting::Pipe,
    ];

    /// The name of a part of this kind.
    pub fn name(self) -> &'static str {
        match self {
            Fitting::Bracket => "bracket",
            Fitting::Bolt => "bolt",
            Fitting::Block => "block",
            Fitting::Cylinder => "cylinder",
            Fitting::Pipe => "pipe",
        }
    }

    /// A fitting of this kind with about `triangles` triangles, its dimensions drawn from `rng`
    /// (a few centimetres to a few decimetres), centred near its frame's origin.
    pub fn mesh(self, triangles: usize, rng: &mut ChaCha8Rng) -> TriMesh {
        let mut size = |lo: f64, hi: f64| rng.random_range(lo..hi);
        match self {
            Fitting::Bracket => {
                let (width, thickness) = (size(0.02, 0.06), size(0.002, 0.005));
                let (foot, leg) = (size(0.03, 0.1), size(0.03, 0.1));
                let plate = |x, z| shapes::cuboid(Vector3::new(x, width, z), triangles / 2);
                combined(&[
                    (
                        plate(foot, thickness),
                        Isometry3::translation(foot / 2.0, 0.0, thickness / 2.0),
                    ),
                    (
                        plate(thickness, leg),
                        Isometry3::translation(thickness / 2.0, 0.0, leg / 2.0),
                    ),
                ])
            }
            Fitting::Bolt => {
                let (radius, length) = (size(0.003, 0.008), size(0.02, 0.08));
                let head = shapes::cylinder(1.7 * radius, 0.7 * radius, triangles * 3 / 7);
                combined(&[
                    (
                        shapes::cylinder(radius, length, triangles * 4 / 7),
                        Isometry3::identity(),
                    ),
                    (
                        head,
                        Isometry3::translation(0.0, 0.0, (length + 0.7 * radius) / 2.0),
                    ),
                ])
            }
            Fitting::Block => shapes::cuboid(
                Vector3::new(size(0.02, 0.15), size(0.02, 0.15), size(0.02, 0.15)),
                triangles,
            ),
            Fitting::Cylinder => shapes::cylinder(size(0.005, 0.04), size(0.02, 0.2), triangles),
            Fitting::Pipe => {
                let outer = size(0.008, 0.03);
                shapes::pipe(0.8 * outer, outer, size(0.05, 0.3), triangles)
            }
        }
    }
}

/// A rotation drawn uniformly from `rng` (Shoemake's method).
pub fn random_rotation(rng: &mut ChaCha8Rng) -> UnitQuaternion<f64> {
    let (u1, u2, u3): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let (t2, t3) = (std::f64::consts::TAU * u2, std::f64::consts::TAU * u3);
    UnitQuaternion::from_quaternion(Quaternion::new(
        b * t3.cos(),
        a * t2.sin(),
        a * t2.cos(),
        b * t3.sin(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn flat(u: f64, v: f64) -> Point3<f64> {
        Point3::new(3.0 * u, v, 0.0)
    }

    #[test]
    fn a_sheet_has_exactly_the_triangles_asked_for() {
        for triangles in [2, 3, 7, 100, 101, 999, 12_345] {
            let sheet = open_sheet(triangles, 3.0, flat);
            assert_eq!(sheet.triangles().len(), triangles);
            let (lo, hi) = sheet.bounding_box();
            assert!(lo.x >= 0.0 && hi.x <= 3.0 && lo.y >= 0.0 && hi.y <= 1.0);
        }
    }

    #[test]
    fn a_sheet_faces_the_side_du_cross_dv_points_to() {
        let sheet = open_sheet(1001, 3.0, flat);
        for t in 0..sheet.triangles().len() {
            let [a, b, c] = sheet.triangle(t);
            assert!((b - a).cross(&(c - a)).z > 0.0, "triangle {t} faces down");
        }
    }

    #[test]
    fn fittings_have_about_the_triangles_asked_for() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for fitting in Fitting::ALL {
            let n = fitting.mesh(1000, &mut rng).triangles().len();
            assert!((700..1400).contains(&n), "{fitting:?}: {n}");
        }
    }

    #[test]
    fn random_rotations_are_unit_and_seeded() {
        let draw = || random_rotation(&mut ChaCha8Rng::seed_from_u64(3));
        assert_eq!(draw(), draw());
        assert!((draw().norm() - 1.0).abs() < 1e-12);
    }
}
