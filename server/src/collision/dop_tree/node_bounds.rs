//! What a node keeps besides its DOP: a sphere, which bounds how far the node's points move when
//! its tree turns (for the certificates of a front), and an oriented box, for the box test near
//! the leaves.

use nalgebra::{Matrix3, Point3, Vector3};

use super::build::round_up;
use super::front::CERTIFICATE_ROUNDING;
use crate::collision::oriented_box::OrientedBox;
use crate::collision::triangle::Triangle;
use crate::geometry::bounding_box_of;

/// A sphere enclosing a node's triangles, in its tree's frame.
#[derive(Debug, Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(super) struct NodeSphere {
    pub(super) centre: [f32; 3],
    pub(super) radius: f32,
}

impl NodeSphere {
    /// The sphere centred on the bounding box of `points`, with the radius rounded up so that
    /// every point lies within it from the `f32` centre, widened by the certificates' rounding
    /// guard (their directions are unit only to `f32` rounding).
    pub(super) fn around<'a>(points: impl Iterator<Item = &'a Point3<f64>> + Clone) -> Self {
        let (lo, hi) = bounding_box_of(points.clone());
        let centre = nalgebra::center(&lo, &hi).coords.map(|x| x as f32);
        let radius = points
            .map(|p| (p.coords - centre.cast::<f64>()).norm_squared())
            .fold(0.0, f64::max)
            .sqrt();
        NodeSphere {
            centre: centre.into(),
            radius: round_up(radius * (1.0 + CERTIFICATE_ROUNDING)),
        }
    }

    pub(super) fn centre(&self) -> Vector3<f64> {
        Vector3::from(self.centre).cast::<f64>()
    }
}

/// An oriented box around a node's triangles, in its tree's frame and in `f32` (the box tests of
/// [`TreePair::box_separation`](super::traverse::TreePair::box_separation) read it beside the
/// DOPs, so it is kept as small as they are).
#[derive(Debug, Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(super) struct NodeBox {
    /// Axes as columns, unit and orthogonal to `f32` rounding.
    axes: [[f32; 3]; 3],
    centre: [f32; 3],
    /// Half side lengths, padded so that every triangle corner `p` is `centre + sum of u_i
    /// axes_i` with `|u_i| <= extents[i]`, in spite of the rounded axes and centre.
    pub(super) extents: [f32; 3],
}

/// Relative pad of a [`NodeBox`]'s extents, of the box's distance from the origin plus its half
/// sides: covers axes orthonormal only to `f32` rounding (a few 1e-7) and the `f32` centre.
const BOX_ROUNDING: f64 = 1e-5;

impl NodeBox {
    /// The box fitted (as the OBB-tree fits its boxes) to `triangles`, rounded to `f32`
    /// outwards.
    pub(super) fn around(triangles: &[Triangle]) -> Self {
        let axes = OrientedBox::fitted_axes(triangles)
            .map(|x| x as f32)
            .cast::<f64>();
        let (lo, hi) = OrientedBox::local_range(&axes, triangles);
        let centre = axes * ((lo + hi) * 0.5);
        let half = (hi - lo) * 0.5;
        let pad = BOX_ROUNDING * (centre.norm() + half.sum());
        NodeBox {
            axes: axes.map(|x| x as f32).into(),
            centre: centre.map(|x| x as f32).into(),
            extents: half.map(|x| round_up(x + pad)).into(),
        }
    }

    /// The box in `f64`, for the separating-axis test and projections.
    pub(super) fn oriented(&self) -> OrientedBox {
        OrientedBox {
            axes: Matrix3::from(self.axes).cast::<f64>(),
            center: Vector3::from(self.centre).cast::<f64>(),
            extents: Vector3::from(self.extents).cast::<f64>(),
        }
    }
}
