//! An oriented box fitted to a set of triangles (RAPID's fit, as FCL implements it), and the
//! 15-axis separating-axis test between two such boxes.

use nalgebra::{Matrix3, Vector3};

use super::triangle::Triangle;
use crate::geometry::{larger, smaller};

/// Added to the absolute rotation entries so that nearly parallel edges (whose cross product is
/// almost zero) do not produce false separations, as RAPID does.
const PARALLEL_SLACK: f64 = 1e-6;

/// Most sweeps of [`symmetric_eigen`]; three or four reach [`JACOBI_TOLERANCE`].
const JACOBI_SWEEPS: usize = 8;

/// Where [`symmetric_eigen`] stops: the off-diagonal entries at most this much of the diagonal.
/// Far below what a box's axes need (the DOP-tree keeps them in `f32`; any orthonormal axes
/// give a valid box), and a sweep sooner than rounding level.
const JACOBI_TOLERANCE: f64 = 1e-9;

/// The eigenvectors (as columns) and eigenvalues of the symmetric `m`, by cyclic Jacobi
/// rotations, as FCL fits its boxes: on a 3x3 matrix a few sweeps bring the off-diagonal entries
/// to [`JACOBI_TOLERANCE`], several times faster than a general solver. The vectors are orthonormal
/// whatever the accuracy (products of rotations), which is what a box needs.
fn symmetric_eigen(m: Matrix3<f64>) -> (Matrix3<f64>, Vector3<f64>) {
    let mut a = m;
    let mut vectors = Matrix3::identity();
    for _ in 0..JACOBI_SWEEPS {
        let off = a[(0, 1)].powi(2) + a[(0, 2)].powi(2) + a[(1, 2)].powi(2);
        if off <= (JACOBI_TOLERANCE * a.diagonal().norm()).powi(2) {
            break;
        }
        for (p, q, r) in [(0, 1, 2), (0, 2, 1), (1, 2, 0)] {
            let apq = a[(p, q)];
            if apq == 0.0 {
                continue;
            }
            // The rotation in the (p, q) plane that zeroes a[(p, q)] (the smaller of the two
            // angles), applied entry by entry.
            let theta = (a[(q, q)] - a[(p, p)]) / (2.0 * apq);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            a[(p, p)] -= t * apq;
            a[(q, q)] += t * apq;
            a[(p, q)] = 0.0;
            a[(q, p)] = 0.0;
            let (arp, arq) = (a[(r, p)], a[(r, q)]);
            a[(r, p)] = c * arp - s * arq;
            a[(r, q)] = s * arp + c * arq;
            a[(p, r)] = a[(r, p)];
            a[(q, r)] = a[(r, q)];
            for i in 0..3 {
                let (vp, vq) = (vectors[(i, p)], vectors[(i, q)]);
                vectors[(i, p)] = c * vp - s * vq;
                vectors[(i, q)] = s * vp + c * vq;
            }
        }
    }
    (vectors, a.diagonal())
}

/// The area-weighted moments of a set of triangles as surfaces, to which a box's axes are
/// fitted. They add: a node's are the sum of its children's.
#[derive(Debug, Clone, Copy)]
pub struct SurfaceMoments {
    area: f64,
    /// Sum of each triangle's area times its centroid.
    first: Vector3<f64>,
    /// Sum of each triangle's second moment about the origin.
    second: Matrix3<f64>,
}

impl SurfaceMoments {
    pub fn of<'t>(triangles: impl IntoIterator<Item = &'t Triangle>) -> Self {
        let mut moments = SurfaceMoments {
            area: 0.0,
            first: Vector3::zeros(),
            second: Matrix3::zeros(),
        };
        for [p, q, r] in triangles {
            let area = 0.5 * (q - p).cross(&(r - p)).norm();
            let m = (p.coords + q.coords + r.coords) / 3.0;
            moments.area += area;
            moments.first += area * m;
            moments.second += (area / 12.0)
                * (9.0 * m * m.transpose()
                    + p.coords * p.coords.transpose()
                    + q.coords * q.coords.transpose()
                    + r.coords * r.coords.transpose());
        }
        moments
    }

    /// The axes of the fitted box, as columns: the eigenvectors of the covariance, by
    /// decreasing variance.
    pub fn axes(&self) -> Matrix3<f64> {
        let mean = self.first / self.area;
        let covariance = self.second / self.area - mean * mean.transpose();
        let (vectors, values) = symmetric_eigen(covariance);
        // Columns sorted by decreasing variance: the first axis is the one to split along.
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| values[b].total_cmp(&values[a]));
        Matrix3::from_columns(&order.map(|i| vectors.column(i).into_owned()))
    }
}

impl std::ops::Add for SurfaceMoments {
    type Output = SurfaceMoments;

    fn add(self, other: SurfaceMoments) -> SurfaceMoments {
        SurfaceMoments {
            area: self.area + other.area,
            first: self.first + other.first,
            second: self.second + other.second,
        }
    }
}

/// A box fitted to a set of triangles: the OBB-tree's bounding volume, and the DOP-tree's second
/// test near the leaves (`dop_tree::NodeBox`).
#[derive(Debug, Clone, Copy)]
pub struct OrientedBox {
    /// Box axes as columns, in the mesh frame, by decreasing variance of the triangles.
    pub axes: Matrix3<f64>,
    pub center: Vector3<f64>,
    /// Half side lengths along the axes.
    pub extents: Vector3<f64>,
}

impl OrientedBox {
    /// The box fitted to the triangles `subset` of `triangles`.
    pub fn fit(triangles: &[Triangle], subset: &[u32]) -> Self {
        let chosen = || subset.iter().map(|&t| &triangles[t as usize]);
        let axes = SurfaceMoments::of(chosen()).axes();
        let (lo, hi) = Self::local_range(&axes, chosen());
        let scale = hi.abs().max().max(lo.abs().max());
        OrientedBox {
            axes,
            center: axes * ((lo + hi) * 0.5),
            // A relative pad covers the rounding of the projections.
            extents: (hi - lo) * 0.5 + Vector3::repeat(scale * 1e-12),
        }
    }

    /// The lowest and highest projections of the corners of `triangles` on each of `axes`
    /// (columns).
    pub fn local_range<'t>(
        axes: &Matrix3<f64>,
        triangles: impl IntoIterator<Item = &'t Triangle>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let mut lo = Vector3::repeat(f64::MAX);
        let mut hi = Vector3::repeat(f64::MIN);
        for p in triangles.into_iter().flatten() {
            let local = axes.tr_mul(&p.coords);
            for i in 0..3 {
                lo[i] = smaller(lo[i], local[i]);
                hi[i] = larger(hi[i], local[i]);
            }
        }
        (lo, hi)
    }

    /// The box's projection on `direction` (in its own frame) plus `offset`.
    pub fn projection(&self, direction: &Vector3<f64>, offset: f64) -> (f64, f64) {
        let centre = self.center.dot(direction) + offset;
        let radius = (0..3)
            .map(|i| self.extents[i] * self.axes.column(i).dot(direction).abs())
            .sum::<f64>();
        (centre - radius, centre + radius)
    }

    /// The 15-axis separating-axis test of this box against `other` posed by (rotation,
    /// translation) in this box's mesh frame: an axis, in that frame and not normalised, along
    /// which the boxes' projections are disjoint, or `None` when none of the 15 is.
    pub fn separating_axis(
        &self,
        other: &OrientedBox,
        rotation: &Matrix3<f64>,
        translation: &Vector3<f64>,
    ) -> Option<Vector3<f64>> {
        // The other box in this box's frame: r[i][j] = A_i . B_j, t = centre offset in A's axes.
        let b_axes = rotation * other.axes;
        let r = self.axes.tr_mul(&b_axes);
        let t = self
            .axes
            .tr_mul(&(rotation * other.center + translation - self.center));
        let abs_r = r.abs().add_scalar(PARALLEL_SLACK);
        let (ea, eb) = (&self.extents, &other.extents);
        for i in 0..3 {
            let rb = eb.dot(&abs_r.row(i).transpose());
            if t[i].abs() > ea[i] + rb {
                return Some(self.axes.column(i).into_owned());
            }
        }
        for j in 0..3 {
            let ra = ea.dot(&abs_r.column(j));
            if t.dot(&r.column(j)).abs() > ra + eb[j] {
                return Some(b_axes.column(j).into_owned());
            }
        }
        for i in 0..3 {
            let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
            for j in 0..3 {
                let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
                let ra = ea[i1] * abs_r[(i2, j)] + ea[i2] * abs_r[(i1, j)];
                let rb = eb[j1] * abs_r[(i, j2)] + eb[j2] * abs_r[(i, j1)];
                let distance = (t[i2] * r[(i1, j)] - t[i1] * r[(i2, j)]).abs();
                if distance > ra + rb {
                    return Some(self.axes.column(i).cross(&b_axes.column(j)));
                }
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::SymmetricEigen;
    use proptest::prelude::*;

    use super::*;

    proptest! {
        /// The Jacobi eigenvectors are orthonormal and diagonalise the matrix, and the
        /// eigenvalues are nalgebra's.
        #[test]
        fn jacobi_eigen_matches_nalgebra(
            entries in prop::array::uniform6(-1.0e3..1.0e3f64),
            scale in prop::sample::select(vec![1e-9, 1e-3, 1.0, 1e6]),
        ) {
            let [a, b, c, d, e, f] = entries.map(|x| x * scale);
            let m = Matrix3::new(a, d, e, d, b, f, e, f, c);
            let (vectors, values) = symmetric_eigen(m);
            let tolerance = 10.0 * JACOBI_TOLERANCE * m.norm().max(f64::MIN_POSITIVE);
            prop_assert!((vectors.transpose() * vectors - Matrix3::identity()).norm() < 1e-12);
            let diagonal = vectors.transpose() * m * vectors;
            prop_assert!((diagonal - Matrix3::from_diagonal(&values)).norm() < tolerance);
            let mut ours: Vec<f64> = values.iter().copied().collect();
            let mut theirs: Vec<f64> = SymmetricEigen::new(m).eigenvalues.iter().copied().collect();
            ours.sort_by(f64::total_cmp);
            theirs.sort_by(f64::total_cmp);
            for (x, y) in ours.iter().zip(&theirs) {
                prop_assert!((x - y).abs() < tolerance, "{x} against {y}");
            }
        }

        /// The moments of two sets of triangles added are those of their union, as a node's box
        /// is fitted to the sum of its children's.
        #[test]
        fn moments_add_up(
            corners in prop::collection::vec(prop::array::uniform9(-10.0..10.0f64), 2..12),
            cut in 1usize..11,
        ) {
            let triangles: Vec<Triangle> = corners
                .iter()
                .map(|c| [0, 3, 6].map(|i| nalgebra::Point3::new(c[i], c[i + 1], c[i + 2])))
                .collect();
            let (left, right) = triangles.split_at(cut.min(triangles.len() - 1));
            let whole = SurfaceMoments::of(&triangles);
            let sum = SurfaceMoments::of(left) + SurfaceMoments::of(right);
            let scale = 1e-12 * (1.0 + whole.second.norm());
            prop_assert!((whole.area - sum.area).abs() <= scale);
            prop_assert!((whole.first - sum.first).norm() <= scale);
            prop_assert!((whole.second - sum.second).norm() <= scale);
        }
    }
}
