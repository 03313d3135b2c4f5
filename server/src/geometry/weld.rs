//! Vertex welding: turning a polygon soup into a mesh whose triangles share vertices, so that
//! edge adjacency (and with it contact classification) sees which triangles are neighbours.

use std::collections::{HashMap, HashSet};

use super::mesh::{Point, TriMesh};

/// Merges vertices that lie within `tolerance` (Euclidean distance) of a kept vertex.
///
/// Vertices are visited in order; each one joins the nearest already kept vertex within the
/// tolerance, or is kept itself. Triangles that collapse (two corners merged) or become
/// degenerate are removed, and so are duplicates (the same three vertices in any order), which
/// welding a soup with doubled faces produces. Unused vertices are dropped. A tolerance of zero
/// (or a negative or non-finite one) merges only identical positions.
///
/// If the tolerance is so large that every triangle would collapse, the mesh is returned
/// unchanged and a warning is logged: a mesh always keeps at least one triangle.
pub fn weld(mesh: &TriMesh, tolerance: f64) -> TriMesh {
    let tolerance = if tolerance.is_finite() && tolerance > 0.0 {
        tolerance
    } else {
        0.0
    };
    let (kept, representative) = if tolerance > 0.0 {
        cluster_within(mesh.vertices(), tolerance)
    } else {
        cluster_identical(mesh.vertices())
    };

    let mut seen = HashSet::with_capacity(mesh.triangles().len());
    let triangles: Vec<[u32; 3]> = mesh
        .triangles()
        .iter()
        .map(|t| t.map(|i| representative[i as usize]))
        .filter(|&[a, b, c]| a != b && b != c && a != c)
        .filter(|t| {
            let mut key = *t;
            key.sort_unstable();
            seen.insert(key)
        })
        .collect();

    // Keep only the vertices some triangle still uses, in their order of first use.
    let mut compact = vec![u32::MAX; kept.len()];
    let mut vertices = Vec::new();
    let triangles = triangles
        .into_iter()
        .map(|t| {
            t.map(|i| {
                let slot = &mut compact[i as usize];
                if *slot == u32::MAX {
                    *slot = vertices.len() as u32;
                    vertices.push(kept[i as usize]);
                }
                *slot
            })
        })
        .collect();

    match TriMesh::new(vertices, triangles) {
        Ok((welded, _)) => welded,
        Err(_) => {
            tracing::warn!(
                tolerance,
                "welding would collapse every triangle; the mesh is left unwelded"
            );
            mesh.clone()
        }
    }
}

/// Kept vertices and, for every input vertex, the index of the kept vertex it merges into.
type Clusters = (Vec<Point>, Vec<u32>);

/// Merges bit-identical positions (with -0.0 and 0.0 treated as equal).
fn cluster_identical(vertices: &[Point]) -> Clusters {
    let mut index_of = HashMap::with_capacity(vertices.len());
    let mut kept = Vec::new();
    let representative = vertices
        .iter()
        .map(|v| {
            let key = v.coords.map(|c| (c + 0.0).to_bits());
            *index_of.entry((key.x, key.y, key.z)).or_insert_with(|| {
                kept.push(*v);
                (kept.len() - 1) as u32
            })
        })
        .collect();
    (kept, representative)
}

/// Merges each vertex into the nearest kept vertex within `tolerance`, found through a uniform
/// grid of cell size `tolerance` (so only the 27 cells around a vertex can hold a match).
fn cluster_within(vertices: &[Point], tolerance: f64) -> Clusters {
    // Float-to-int casts saturate, so huge coordinates share edge cells instead of overflowing;
    // the distance test below keeps the result correct either way.
    let cell_of = |p: &Point| p.coords.map(|c| (c / tolerance).floor() as i64);
    let mut grid: HashMap<(i64, i64, i64), Vec<u32>> = HashMap::new();
    let mut kept: Vec<Point> = Vec::new();
    let tolerance_squared = tolerance * tolerance;
    let representative = vertices
        .iter()
        .map(|v| {
            let cell = cell_of(v);
            let mut best: Option<(f64, u32)> = None;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let neighbour = (
                            cell.x.saturating_add(dx),
                            cell.y.saturating_add(dy),
                            cell.z.saturating_add(dz),
                        );
                        for &k in grid.get(&neighbour).into_iter().flatten() {
                            let d = (kept[k as usize] - v).norm_squared();
                            if d <= tolerance_squared && best.is_none_or(|(bd, _)| d < bd) {
                                best = Some((d, k));
                            }
                        }
                    }
                }
            }
            best.map(|(_, k)| k).unwrap_or_else(|| {
                let k = kept.len() as u32;
                kept.push(*v);
                grid.entry((cell.x, cell.y, cell.z)).or_default().push(k);
                k
            })
        })
        .collect();
    (kept, representative)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64, z: f64) -> Point {
        Point::new(x, y, z)
    }

    /// Two triangles of a unit square as a soup (6 vertices), one corner slightly off.
    fn square_soup(offset: f64) -> TriMesh {
        let vertices = vec![
            p(0., 0., 0.),
            p(1., 0., 0.),
            p(1., 1., 0.),
            p(0., 0., offset),
            p(1., 1., 0.),
            p(0., 1., 0.),
        ];
        TriMesh::new(vertices, vec![[0, 1, 2], [3, 4, 5]])
            .unwrap()
            .0
    }

    #[test]
    fn soup_corners_within_tolerance_merge() {
        let welded = weld(&square_soup(1e-7), 1e-6);
        assert_eq!(welded.vertices().len(), 4);
        assert_eq!(welded.triangles().len(), 2);
        let [a, b] = [welded.triangles()[0], welded.triangles()[1]];
        let shared = a.iter().filter(|i| b.contains(i)).count();
        assert_eq!(shared, 2, "the diagonal is shared after welding");
    }

    #[test]
    fn corners_beyond_tolerance_stay_apart() {
        assert_eq!(weld(&square_soup(1e-5), 1e-6).vertices().len(), 5);
        // Zero tolerance merges only exact duplicates.
        assert_eq!(weld(&square_soup(1e-7), 0.0).vertices().len(), 5);
        assert_eq!(weld(&square_soup(0.0), 0.0).vertices().len(), 4);
    }

    #[test]
    fn collapsed_and_duplicate_triangles_are_removed() {
        let vertices = vec![
            p(0., 0., 0.),
            p(1., 0., 0.),
            p(0., 1., 0.),
            p(1e-9, 0., 0.),
            p(0., 1e-3, 0.),
        ];
        // Triangle 1 duplicates triangle 0 (other order); triangle 2 collapses.
        let mesh = TriMesh::new(vertices, vec![[0, 1, 2], [2, 1, 3], [0, 3, 4]])
            .unwrap()
            .0;
        let welded = weld(&mesh, 1e-6);
        assert_eq!(welded.triangles().len(), 1);
        assert_eq!(welded.vertices().len(), 3);
    }

    #[test]
    fn a_tolerance_that_collapses_everything_leaves_the_mesh_unchanged() {
        let mesh = square_soup(0.0);
        assert_eq!(weld(&mesh, 10.0), mesh);
        assert_eq!(weld(&mesh, f64::NAN).vertices().len(), 4);
    }

    #[test]
    fn welding_matches_a_brute_force_oracle_on_random_soups() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..50 {
            // Points on a coarse lattice, jittered well below the tolerance, so that the right
            // clustering is unambiguous: same lattice point <=> within tolerance.
            let tolerance = 1e-3;
            let vertices: Vec<Point> = (0..300)
                .map(|_| {
                    let lattice = p(
                        rng.random_range(0..6) as f64,
                        rng.random_range(0..6) as f64,
                        rng.random_range(0..3) as f64,
                    ) * 0.1;
                    let jitter = p(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    ) * (tolerance * 0.2);
                    lattice + jitter.coords
                })
                .collect();
            let (kept, representative) = cluster_within(&vertices, tolerance);
            for (i, a) in vertices.iter().enumerate() {
                for (j, b) in vertices.iter().enumerate() {
                    let same = representative[i] == representative[j];
                    assert_eq!(same, (a - b).norm() <= tolerance, "vertices {i} and {j}");
                }
                assert!((kept[representative[i] as usize] - a).norm() <= tolerance);
            }
        }
    }
}
