//! Orientation sets of k-DOPs and the "generic DOP" that makes O(k) re-alignment possible.
//!
//! A k-DOP is the intersection of k half-spaces `n_i . x <= d_i` with fixed unit normals `n_i`.
//! Normals come in opposite pairs: `n_{i + k/2} = -n_i`, so a DOP is also k/2 intervals (slabs).
//!
//! Re-alignment (the paper's §2.1): a DOP of the second object, rotated by R, is enclosed by a DOP
//! of the first object's orientations. For a direction `u` (a first-object normal expressed in
//! the second object's frame), pick three of the set's normals whose cone contains `u`:
//! `u = λ1 n_j1 + λ2 n_j2 + λ3 n_j3` with `λ >= 0`. Then for every `x` of the DOP,
//! `u . x = Σ λ_l (n_jl . x) <= Σ λ_l d_jl`: the new offset is an affine combination of three old
//! ones, whatever the offsets are, so it is always conservative. It is exact when the DOP has the
//! combinatorial structure of the cone chosen; the cones are taken from the vertices of a
//! *generic* DOP (every vertex on exactly three planes), whose normal cones tile the sphere.

use std::sync::OnceLock;

use nalgebra::{Matrix3, Vector3};
use thiserror::Error;

/// The orientation-set sizes supported: 6 (box), 14, 18, 24 and 26.
pub const SUPPORTED_K: [usize; 5] = [6, 14, 18, 24, 26];

/// The default number of orientations: the fastest over the meshes of the tumbling benchmark
/// (see BENCHMARKS.md, B1). Fewer slots make re-alignment and set-up cheaper; too few leave the
/// re-aligned DOPs loose where a long part lies at a slant.
pub const DEFAULT_K: usize = 18;

/// Why an orientation set could not be made.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum OrientationError {
    /// `k` is not one of [`SUPPORTED_K`].
    #[error("unsupported number of DOP orientations {0}: choose one of 6, 14, 18, 24, 26")]
    Unsupported(usize),
}

/// One vertex of the generic DOP: the three planes through it and the matrix that turns a
/// direction into the coefficients of those planes' normals.
#[derive(Debug, Clone)]
struct GenericVertex {
    /// Indices (into the k normals) of the three planes through the vertex.
    planes: [u8; 3],
    /// The vertex's position on the generic DOP, used to find the vertex supporting a direction.
    position: Vector3<f64>,
    /// `(N^T)^-1` where the rows of N are the three normals: `λ = coefficients * u`.
    coefficients: Matrix3<f64>,
}

/// Cells per cube-map face edge of the support-cone lookup table.
const CUBE_CELLS: usize = 16;

/// Samples per cell edge when the lookup table is built.
const CELL_SAMPLES: usize = 6;

/// A fixed set of k DOP normals with its generic DOP, shared by every tree built with it.
#[derive(Debug, Clone)]
pub struct OrientationSet {
    /// The k/2 unit axes; normal `i < k/2` is `axes[i]`, normal `i + k/2` is `-axes[i]`.
    axes: Vec<Vector3<f64>>,
    /// Vertices of the generic DOP; their normal cones cover the sphere.
    vertices: Vec<GenericVertex>,
    /// Cube map over directions: cell `c` lists, in `cell_vertices[cell_start[c]..cell_start[c +
    /// 1]]`, the generic vertices whose normal cone meets the cell (found by dense sampling; a
    /// query that finds none of them containing its direction falls back to a full search).
    cell_start: Vec<u16>,
    cell_vertices: Vec<u8>,
}

/// The support cone of a direction: three plane indices and their non-negative coefficients.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SupportCone {
    /// Indices of the three normals spanning the cone.
    pub planes: [u8; 3],
    /// Non-negative coefficients with `u = Σ lambda_l n_planes[l]`.
    pub lambda: [f64; 3],
}

impl OrientationSet {
    /// The set of `k` orientations: 6 = the coordinate axes; 14 = axes and the 4 cube diagonals;
    /// 18 = axes and the 6 edge diagonals `(1, ±1, 0)`; 26 = all of those; 24 = the 12 directions
    /// `(0, ±1, ±2)` and their permutations (face normals of the tetrakis hexahedron, an evenly
    /// spread set of 12 directions).
    ///
    /// Each set is built once per process (its lookup table takes milliseconds) and cloned
    /// after: an assembly of a thousand parts asks for it a thousand times.
    pub fn new(k: usize) -> Result<Self, OrientationError> {
        static BUILT: [OnceLock<OrientationSet>; SUPPORTED_K.len()] =
            [const { OnceLock::new() }; SUPPORTED_K.len()];
        let index = (SUPPORTED_K.iter().position(|&supported| supported == k))
            .ok_or(OrientationError::Unsupported(k))?;
        Ok(BUILT[index].get_or_init(|| Self::build(k)).clone())
    }

    /// Builds the set of `k` orientations, one of [`SUPPORTED_K`].
    fn build(k: usize) -> Self {
        let coordinate = [[1., 0., 0.], [0., 1., 0.], [0., 0., 1.]];
        let corner = [[1., 1., 1.], [1., 1., -1.], [1., -1., 1.], [-1., 1., 1.]];
        let edge = [
            [1., 1., 0.],
            [1., 0., 1.],
            [0., 1., 1.],
            [1., -1., 0.],
            [1., 0., -1.],
            [0., 1., -1.],
        ];
        let tetrakis = [
            [0., 1., 2.],
            [0., -1., 2.],
            [0., 2., 1.],
            [0., -2., 1.],
            [1., 0., 2.],
            [-1., 0., 2.],
            [2., 0., 1.],
            [-2., 0., 1.],
            [1., 2., 0.],
            [-1., 2., 0.],
            [2., 1., 0.],
            [-2., 1., 0.],
        ];
        let raw: Vec<[f64; 3]> = match k {
            6 => coordinate.to_vec(),
            14 => [&coordinate[..], &corner[..]].concat(),
            18 => [&coordinate[..], &edge[..]].concat(),
            24 => tetrakis.to_vec(),
            26 => [&coordinate[..], &corner[..], &edge[..]].concat(),
            _ => unreachable!("k = {k} is not one of SUPPORTED_K"),
        };
        let axes: Vec<Vector3<f64>> = raw.iter().map(|a| Vector3::from(*a).normalize()).collect();
        let vertices = generic_vertices(&axes);
        let mut set = OrientationSet {
            axes,
            vertices,
            cell_start: vec![0],
            cell_vertices: Vec::new(),
        };
        set.build_cube_map();
        set
    }

    /// Number of orientations (half-spaces) k.
    pub fn k(&self) -> usize {
        2 * self.axes.len()
    }

    /// The k/2 unit axes; normal `i` is `axes[i]` and normal `i + k/2` is `-axes[i]`.
    pub fn axes(&self) -> &[Vector3<f64>] {
        &self.axes
    }

    /// Normal `i` in `0..k`.
    pub fn normal(&self, i: usize) -> Vector3<f64> {
        let h = self.axes.len();
        if i < h {
            self.axes[i]
        } else {
            -self.axes[i - h]
        }
    }

    /// Number of vertices of the generic DOP (`2k - 4` for a simple polytope).
    pub fn generic_vertex_count(&self) -> usize {
        self.vertices.len()
    }

    /// Plane triples and matrices to compute, from a DOP's offsets, the vertex positions of a DOP
    /// with the generic structure: `x = inverse * (d_j1, d_j2, d_j3)`. Used by the brute-force
    /// re-alignment baseline.
    pub fn vertex_solvers(&self) -> Vec<([u8; 3], Matrix3<f64>)> {
        self.vertices
            .iter()
            .map(|v| (v.planes, v.coefficients.transpose()))
            .collect()
    }

    /// The generic vertex supporting direction `u` (non-zero, any length) and the coefficients
    /// expressing `u` in its three normals; the coefficients are non-negative (rounding clamped).
    pub fn support_cone(&self, u: &Vector3<f64>) -> SupportCone {
        let mut no_hint = u8::MAX;
        self.support_cone_hinted(u, &mut no_hint)
    }

    /// The cone of generic vertex `v` if it contains the unit direction `u` (the fast path of a
    /// query whose rotation changed little since the previous one).
    #[inline]
    pub fn cone_if_contains(&self, v: u8, u: &Vector3<f64>) -> Option<SupportCone> {
        let vertex = self.vertices.get(v as usize)?;
        let c = &vertex.coefficients;
        let lambda = [0, 1, 2].map(|r| c[(r, 0)] * u.x + c[(r, 1)] * u.y + c[(r, 2)] * u.z);
        (lambda[0] >= -1e-12 && lambda[1] >= -1e-12 && lambda[2] >= -1e-12).then(|| SupportCone {
            planes: vertex.planes,
            lambda: lambda.map(|l| l.max(0.0)),
        })
    }

    /// [`Self::support_cone`], trying first the generic vertex `hint` (the answer for a nearby
    /// direction, e.g. the same axis at the previous query: temporal coherence), then the few
    /// candidates of `u`'s cube-map cell, then all vertices. `hint` is set to the vertex found.
    pub fn support_cone_hinted(&self, u: &Vector3<f64>, hint: &mut u8) -> SupportCone {
        let tolerance = -1e-12 * u.abs().max();
        let contains = |v: u8| {
            let lambda = self.vertices.get(v as usize)?.coefficients * u;
            (lambda.min() >= tolerance).then_some((v, lambda))
        };
        let (v, lambda) = contains(*hint)
            .or_else(|| {
                let cell = cube_cell(u);
                self.cell_vertices
                    [self.cell_start[cell] as usize..self.cell_start[cell + 1] as usize]
                    .iter()
                    .find_map(|&v| contains(v))
            })
            .unwrap_or_else(|| {
                let best = (0..self.vertices.len())
                    .max_by(|&a, &b| {
                        u.dot(&self.vertices[a].position)
                            .total_cmp(&u.dot(&self.vertices[b].position))
                    })
                    .expect("a generic DOP has vertices");
                (best as u8, self.vertices[best].coefficients * u)
            });
        *hint = v;
        SupportCone {
            planes: self.vertices[v as usize].planes,
            lambda: [lambda.x.max(0.0), lambda.y.max(0.0), lambda.z.max(0.0)],
        }
    }

    /// Fills the cube-map lookup table by sampling every cell densely.
    fn build_cube_map(&mut self) {
        let mut lists: Vec<Vec<u8>> = vec![Vec::new(); 6 * CUBE_CELLS * CUBE_CELLS];
        let samples_per_face = CUBE_CELLS * CELL_SAMPLES;
        for face in 0..6 {
            for i in 0..=samples_per_face {
                for j in 0..=samples_per_face {
                    let s = 2.0 * i as f64 / samples_per_face as f64 - 1.0;
                    let t = 2.0 * j as f64 / samples_per_face as f64 - 1.0;
                    let major = if face % 2 == 0 { 1.0 } else { -1.0 };
                    let mut u = Vector3::zeros();
                    u[face / 2] = major;
                    u[(face / 2 + 1) % 3] = s;
                    u[(face / 2 + 2) % 3] = t;
                    let best = (0..self.vertices.len())
                        .max_by(|&a, &b| {
                            u.dot(&self.vertices[a].position)
                                .total_cmp(&u.dot(&self.vertices[b].position))
                        })
                        .expect("a generic DOP has vertices") as u8;
                    // A sample on a cell border belongs to every cell it touches.
                    for di in [0, 1] {
                        for dj in [0, 1] {
                            let probe = Vector3::from_fn(|c, _| {
                                let nudge = 1e-9 * (di as f64 - 0.5);
                                let nudge_t = 1e-9 * (dj as f64 - 0.5);
                                if c == (face / 2 + 1) % 3 {
                                    u[c] + nudge
                                } else if c == (face / 2 + 2) % 3 {
                                    u[c] + nudge_t
                                } else {
                                    u[c]
                                }
                            });
                            let list = &mut lists[cube_cell(&probe)];
                            if !list.contains(&best) {
                                list.push(best);
                            }
                        }
                    }
                }
            }
        }
        for list in lists {
            self.cell_vertices.extend(list);
            self.cell_start.push(self.cell_vertices.len() as u16);
        }
    }
}

/// The cube-map cell of direction `u`: the face of its largest component, then a grid cell.
fn cube_cell(u: &Vector3<f64>) -> usize {
    let axis = u.iamax();
    let major = u[axis];
    let face = 2 * axis + (major < 0.0) as usize;
    let inverse = 1.0 / major.abs();
    let grid = |c: f64| {
        let x = (c * inverse + 1.0) * 0.5 * CUBE_CELLS as f64;
        (x as usize).min(CUBE_CELLS - 1)
    };
    let (s, t) = (grid(u[(axis + 1) % 3]), grid(u[(axis + 2) % 3]));
    (face * CUBE_CELLS + s) * CUBE_CELLS + t
}

impl Default for OrientationSet {
    /// The set of [`DEFAULT_K`] orientations.
    fn default() -> Self {
        OrientationSet::new(DEFAULT_K).expect("the default k is supported")
    }
}

/// A fixed sequence of small offsets in [-0.05, 0.05) (SplitMix64): a generic DOP needs offsets
/// that are distinct and the same on every run, not statistical quality.
struct Perturbation(u64);

impl Perturbation {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        let unit = (z >> 11) as f64 / (1u64 << 53) as f64;
        0.1 * unit - 0.05
    }
}

/// Vertices of a generic DOP: offsets `1 + small perturbation` (a fixed pseudo-random sequence),
/// perturbed again until every vertex lies on exactly three planes.
fn generic_vertices(axes: &[Vector3<f64>]) -> Vec<GenericVertex> {
    let h = axes.len();
    let k = 2 * h;
    let normal = |i: usize| if i < h { axes[i] } else { -axes[i - h] };
    let mut perturbation = Perturbation(0x0d0b);
    for _attempt in 0..1000 {
        let offsets: Vec<f64> = (0..k).map(|_| 1.0 + perturbation.next()).collect();
        let mut vertices = Vec::new();
        let mut degenerate = false;
        'triples: for i in 0..k {
            for j in i + 1..k {
                for l in j + 1..k {
                    let rows = Matrix3::from_rows(&[
                        normal(i).transpose(),
                        normal(j).transpose(),
                        normal(l).transpose(),
                    ]);
                    let Some(inverse) = rows.try_inverse() else {
                        continue;
                    };
                    if rows.determinant().abs() < 1e-6 {
                        continue;
                    }
                    let x = inverse * Vector3::new(offsets[i], offsets[j], offsets[l]);
                    let slack: Vec<f64> = (0..k).map(|m| offsets[m] - normal(m).dot(&x)).collect();
                    if slack.iter().any(|&s| s < -1e-9) {
                        continue;
                    }
                    if slack.iter().filter(|&&s| s < 1e-7).count() > 3 {
                        degenerate = true;
                        break 'triples;
                    }
                    vertices.push(GenericVertex {
                        planes: [i as u8, j as u8, l as u8],
                        position: x,
                        coefficients: rows
                            .transpose()
                            .try_inverse()
                            .expect("the transpose of an invertible matrix is invertible"),
                    });
                }
            }
        }
        if !degenerate && vertices.len() == 2 * k - 4 {
            return vertices;
        }
    }
    unreachable!("random perturbation of the unit DOP gives a simple polytope almost surely")
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn every_supported_set_has_a_simple_generic_dop() {
        for k in SUPPORTED_K {
            let set = OrientationSet::new(k).unwrap();
            assert_eq!(set.k(), k);
            assert_eq!(set.generic_vertex_count(), 2 * k - 4, "k = {k}");
            for i in 0..set.axes().len() {
                assert!((set.normal(i) + set.normal(i + k / 2)).norm() < 1e-15);
            }
        }
        assert_eq!(
            OrientationSet::new(10).unwrap_err(),
            OrientationError::Unsupported(10)
        );
    }

    #[test]
    fn support_cone_reconstructs_the_direction_with_non_negative_coefficients() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for k in SUPPORTED_K {
            let set = OrientationSet::new(k).unwrap();
            for _ in 0..2000 {
                let u = Vector3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                );
                let cone = set.support_cone(&u);
                let mut hint = rng.random_range(0..set.generic_vertex_count() as u8);
                assert_eq!(set.support_cone_hinted(&u, &mut hint), cone);
                let rebuilt: Vector3<f64> = (0..3)
                    .map(|l| set.normal(cone.planes[l] as usize) * cone.lambda[l])
                    .sum();
                assert!(
                    (rebuilt - u).norm() < 1e-9 * (1.0 + u.norm()),
                    "k {k} u {u}"
                );
                assert!(cone.lambda.iter().all(|&l| l >= 0.0));
            }
        }
    }
}
