//! An oriented box fitted to a set of triangles (RAPID's fit, as FCL implements it), and the
//! 15-axis separating-axis test between two such boxes.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use super::triangle::Triangle;

/// Added to the absolute rotation entries so that nearly parallel edges (whose cross product is
/// almost zero) do not produce false separations, as RAPID does.
const PARALLEL_SLACK: f64 = 1e-6;

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
        let axes = Self::fitted_axes(triangles, subset);
        let (lo, hi) = Self::local_range(&axes, triangles, subset);
        let scale = hi.abs().max().max(lo.abs().max());
        OrientedBox {
            axes,
            center: axes * ((lo + hi) * 0.5),
            // A relative pad covers the rounding of the projections.
            extents: (hi - lo) * 0.5 + Vector3::repeat(scale * 1e-12),
        }
    }

    /// The axes of the box fitted to the triangles `subset`, as columns: the eigenvectors of
    /// their area-weighted covariance, by decreasing variance.
    pub fn fitted_axes(triangles: &[Triangle], subset: &[u32]) -> Matrix3<f64> {
        // Area-weighted second moments of the triangles as surfaces.
        let mut area_sum = 0.0;
        let mut mean = Vector3::zeros();
        let mut moment = Matrix3::zeros();
        for &t in subset {
            let [p, q, r] = &triangles[t as usize];
            let area = 0.5 * (q - p).cross(&(r - p)).norm();
            let m = (p.coords + q.coords + r.coords) / 3.0;
            area_sum += area;
            mean += area * m;
            moment += (area / 12.0)
                * (9.0 * m * m.transpose()
                    + p.coords * p.coords.transpose()
                    + q.coords * q.coords.transpose()
                    + r.coords * r.coords.transpose());
        }
        mean /= area_sum;
        let covariance = moment / area_sum - mean * mean.transpose();
        let eigen = SymmetricEigen::new(covariance);
        // Columns sorted by decreasing variance: the first axis is the one to split along.
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
        Matrix3::from_columns(&order.map(|i| eigen.eigenvectors.column(i).into_owned()))
    }

    /// The lowest and highest projections of the corners of the triangles `subset` on each of
    /// `axes` (columns).
    pub fn local_range(
        axes: &Matrix3<f64>,
        triangles: &[Triangle],
        subset: &[u32],
    ) -> (Vector3<f64>, Vector3<f64>) {
        let mut lo = Vector3::repeat(f64::MAX);
        let mut hi = Vector3::repeat(f64::MIN);
        for p in subset.iter().flat_map(|&t| &triangles[t as usize]) {
            let local = axes.tr_mul(&p.coords);
            lo = lo.inf(&local);
            hi = hi.sup(&local);
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
