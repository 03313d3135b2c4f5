//! Edge adjacency of a triangle mesh: which triangles share an edge, which edges are open rims or
//! non-manifold, and which triangles meet at a vertex. Contact classification in sliding counts
//! the neighbours of a touching triangle, and must cope with open sheet metal and soups.

use super::mesh::TriMesh;

/// Edges, their triangles, and the triangles around each vertex of one [`TriMesh`].
///
/// An edge is an unordered pair of vertex indices, so welding first (see
/// [`weld`](super::weld::weld)) is what makes the triangles of a soup neighbours. An edge used by
/// one triangle is open (a rim), by two manifold, by more non-manifold; all three are kept as
/// they are. Lists are stored flat (offsets into one array) to stay compact on big meshes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EdgeAdjacency {
    /// Edge `e` as (smaller vertex, larger vertex), sorted.
    edges: Vec<[u32; 2]>,
    /// Triangles of edge `e`: `edge_triangles[edge_offsets[e]..edge_offsets[e + 1]]`.
    edge_offsets: Vec<usize>,
    edge_triangles: Vec<u32>,
    /// Edge `k` of a triangle joins its corners `k` and `(k + 1) % 3`.
    triangle_edges: Vec<[u32; 3]>,
    /// Triangles at vertex `v`: `vertex_triangles[vertex_offsets[v]..vertex_offsets[v + 1]]`.
    vertex_offsets: Vec<usize>,
    vertex_triangles: Vec<u32>,
}

impl EdgeAdjacency {
    /// Builds the adjacency of `mesh` in time linear in its triangles (for meshes whose vertices
    /// each have a bounded number of edges, as welded surfaces do).
    pub fn new(mesh: &TriMesh) -> Self {
        let triangles = mesh.triangles();
        let vertex_count = mesh.vertices().len();
        let corner_edge = |corners: &[u32; 3], k: usize| {
            let (a, b) = (corners[k], corners[(k + 1) % 3]);
            (a.min(b), a.max(b))
        };
        // Every (edge, triangle, corner) incidence, bucketed by the edge's smaller vertex (a
        // counting sort), then each bucket (a vertex's few edges) sorted by the larger vertex,
        // triangle and corner: the incidences in the order of their edges, without a sort of
        // them all.
        let mut bucket_starts = vec![0usize; vertex_count + 1];
        for corners in triangles {
            for k in 0..3 {
                bucket_starts[corner_edge(corners, k).0 as usize + 1] += 1;
            }
        }
        for v in 0..vertex_count {
            bucket_starts[v + 1] += bucket_starts[v];
        }
        let mut bucket_fill = bucket_starts.clone();
        let mut incidences = vec![(0u32, 0u32, 0u8); 3 * triangles.len()];
        for (t, corners) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (low, high) = corner_edge(corners, k);
                let slot = &mut bucket_fill[low as usize];
                incidences[*slot] = (high, t as u32, k as u8);
                *slot += 1;
            }
        }
        drop(bucket_fill);

        let mut edges = Vec::new();
        let mut edge_offsets = vec![0];
        let mut edge_triangles = Vec::with_capacity(incidences.len());
        let mut triangle_edges = vec![[0u32; 3]; triangles.len()];
        for low in 0..vertex_count {
            let bucket = &mut incidences[bucket_starts[low]..bucket_starts[low + 1]];
            bucket.sort_unstable();
            for &(high, t, k) in bucket.iter() {
                let edge = [low as u32, high];
                if edges.last() != Some(&edge) {
                    if !edges.is_empty() {
                        edge_offsets.push(edge_triangles.len());
                    }
                    edges.push(edge);
                }
                edge_triangles.push(t);
                triangle_edges[t as usize][k as usize] = (edges.len() - 1) as u32;
            }
        }
        edge_offsets.push(edge_triangles.len());
        drop(incidences);

        let mut vertex_offsets = vec![0usize; vertex_count + 1];
        for corners in triangles {
            for &v in corners {
                vertex_offsets[v as usize + 1] += 1;
            }
        }
        for v in 0..vertex_count {
            vertex_offsets[v + 1] += vertex_offsets[v];
        }
        let mut fill = vertex_offsets.clone();
        let mut vertex_triangles = vec![0u32; vertex_offsets[vertex_count]];
        for (t, corners) in triangles.iter().enumerate() {
            for &v in corners {
                vertex_triangles[fill[v as usize]] = t as u32;
                fill[v as usize] += 1;
            }
        }

        EdgeAdjacency {
            edges,
            edge_offsets,
            edge_triangles,
            triangle_edges,
            vertex_offsets,
            vertex_triangles,
        }
    }

    /// Number of distinct edges.
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// The two vertices of edge `edge`, smaller index first.
    pub fn edge(&self, edge: usize) -> [u32; 2] {
        self.edges[edge]
    }

    /// The edge joining vertices `a` and `b` (in either order), if some triangle has it.
    pub fn find_edge(&self, a: u32, b: u32) -> Option<usize> {
        self.edges.binary_search(&[a.min(b), a.max(b)]).ok()
    }

    /// The triangles on edge `edge`: one for an open edge, two for a manifold one, more for a
    /// non-manifold one.
    pub fn edge_triangles(&self, edge: usize) -> &[u32] {
        &self.edge_triangles[self.edge_offsets[edge]..self.edge_offsets[edge + 1]]
    }

    /// The edges of triangle `triangle`; edge `k` joins its corners `k` and `(k + 1) % 3`.
    pub fn triangle_edges(&self, triangle: usize) -> [u32; 3] {
        self.triangle_edges[triangle]
    }

    /// The triangles sharing an edge with `triangle` (edge-neighbours), edge by edge; a
    /// triangle sharing two edges (a duplicate) appears twice.
    pub fn triangle_neighbours(&self, triangle: usize) -> impl Iterator<Item = u32> + '_ {
        self.triangle_edges[triangle]
            .into_iter()
            .flat_map(|e| self.edge_triangles(e as usize))
            .copied()
            .filter(move |&t| t as usize != triangle)
    }

    /// The triangles that have `vertex` as a corner.
    pub fn vertex_triangles(&self, vertex: usize) -> &[u32] {
        &self.vertex_triangles[self.vertex_offsets[vertex]..self.vertex_offsets[vertex + 1]]
    }

    /// The open edges (used by exactly one triangle): the rims of open geometry.
    pub fn open_edges(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.edge_count()).filter(|&e| self.edge_triangles(e).len() == 1)
    }

    /// The non-manifold edges (used by more than two triangles).
    pub fn non_manifold_edges(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.edge_count()).filter(|&e| self.edge_triangles(e).len() > 2)
    }

    /// True when every edge is shared by exactly two triangles: the surface has no rim.
    pub fn is_closed(&self) -> bool {
        (0..self.edge_count()).all(|e| self.edge_triangles(e).len() == 2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::mesh::Point;
    use rand::{Rng, SeedableRng};

    fn mesh(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> TriMesh {
        let vertices = vertices.iter().map(|&v| Point::from(v)).collect();
        TriMesh::new(vertices, triangles.to_vec()).unwrap().0
    }

    #[test]
    fn tetrahedron_is_closed_and_every_triangle_has_three_neighbours() {
        let tetra = mesh(
            &[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]],
            &[[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]],
        );
        let adjacency = EdgeAdjacency::new(&tetra);
        assert_eq!(adjacency.edge_count(), 6);
        assert!(adjacency.is_closed());
        for t in 0..4 {
            let mut neighbours: Vec<u32> = adjacency.triangle_neighbours(t).collect();
            neighbours.sort_unstable();
            let expected: Vec<u32> = (0..4).filter(|&o| o != t as u32).collect();
            assert_eq!(neighbours, expected);
        }
        assert_eq!(adjacency.vertex_triangles(3), &[1, 2, 3]);
    }

    #[test]
    fn open_and_non_manifold_edges_are_reported() {
        // Three triangles fanning around the edge (0, 1), like pages of a book.
        let book = mesh(
            &[
                [0., 0., 0.],
                [0., 0., 1.],
                [1., 0., 0.],
                [0., 1., 0.],
                [-1., 0., 0.],
            ],
            &[[0, 1, 2], [1, 0, 3], [0, 1, 4]],
        );
        let adjacency = EdgeAdjacency::new(&book);
        let spine = adjacency.find_edge(1, 0).unwrap();
        assert_eq!(adjacency.edge_triangles(spine), &[0, 1, 2]);
        assert_eq!(adjacency.non_manifold_edges().collect::<Vec<_>>(), [spine]);
        assert_eq!(adjacency.open_edges().count(), 6);
        assert!(!adjacency.is_closed());
        assert_eq!(adjacency.find_edge(2, 3), None);
        let edges = adjacency.triangle_edges(1);
        assert_eq!(adjacency.edge(edges[0] as usize), [0, 1]);
        assert_eq!(adjacency.edge(edges[1] as usize), [0, 3]);
    }

    #[test]
    fn matches_a_brute_force_oracle_on_random_meshes() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..20 {
            let vertex_count = rng.random_range(3..30);
            let vertices: Vec<[f64; 3]> = (0..vertex_count)
                .map(|_| [(); 3].map(|_| rng.random_range(-1.0..1.0)))
                .collect();
            let triangles: Vec<[u32; 3]> = (0..rng.random_range(1..80))
                .map(|_| [(); 3].map(|_| rng.random_range(0..vertex_count as u32)))
                .collect();
            let Ok((m, _)) = TriMesh::new(
                vertices.iter().map(|&v| Point::from(v)).collect(),
                triangles,
            ) else {
                continue;
            };
            let adjacency = EdgeAdjacency::new(&m);
            let has_edge = |t: &[u32; 3], a: u32, b: u32| t.contains(&a) && t.contains(&b);
            for e in 0..adjacency.edge_count() {
                let [a, b] = adjacency.edge(e);
                let expected: Vec<u32> = (0..m.triangles().len() as u32)
                    .filter(|&t| has_edge(&m.triangles()[t as usize], a, b))
                    .collect();
                assert_eq!(adjacency.edge_triangles(e), expected);
            }
            for (t, corners) in m.triangles().iter().enumerate() {
                for k in 0..3 {
                    let e = adjacency.triangle_edges(t)[k] as usize;
                    let mut expected = [corners[k], corners[(k + 1) % 3]];
                    expected.sort_unstable();
                    assert_eq!(adjacency.edge(e), expected);
                }
            }
            for v in 0..m.vertices().len() {
                let expected: Vec<u32> = (0..m.triangles().len() as u32)
                    .filter(|&t| m.triangles()[t as usize].contains(&(v as u32)))
                    .collect();
                assert_eq!(adjacency.vertex_triangles(v), expected);
            }
        }
    }
}
