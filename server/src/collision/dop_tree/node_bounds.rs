//! What a node keeps besides its DOP: a sphere, which bounds how far the node's points move when
//! its tree turns (for the certificates of a front), and an oriented box, for the box test near
//! the leaves.

use nalgebra::{Matrix3, Point3, Vector3};

use super::build::round_up;
use super::front::CERTIFICATE_ROUNDING;
use crate::collision::oriented_box::{OrientedBox, SurfaceMoments};
use crate::collision::triangle::Triangle;
use crate::geometry::{bounding_box_of, larger};

/// A sphere enclosing a node's triangles, in its tree's frame.
#[derive(Debug, Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(super) struct NodeSphere {
    pub(super) centre: [f32; 3],
    pub(super) radius: f32,
}

impl NodeSphere {
    /// The sphere centred on the bounding box of `points`; see [`NodeSphere::centred`].
    pub(super) fn around<'a>(points: impl Iterator<Item = &'a Point3<f64>> + Clone) -> Self {
        let (lo, hi) = bounding_box_of(points.clone());
        NodeSphere::centred(nalgebra::center(&lo, &hi).coords, points)
    }

    /// The sphere centred on `centre` rounded to `f32`, with the radius rounded up so that every
    /// one of `points` lies within it from that centre, widened by the certificates' rounding
    /// guard (their directions are unit only to `f32` rounding).
    pub(super) fn centred<'a>(
        centre: Vector3<f64>,
        points: impl Iterator<Item = &'a Point3<f64>>,
    ) -> Self {
        let centre = centre.map(|x| x as f32);
        let radius = points
            .map(|p| (p.coords - centre.cast::<f64>()).norm_squared())
            .fold(0.0, larger)
            .sqrt();
        NodeSphere {
            centre: centre.into(),
            radius: round_up(radius * (1.0 + CERTIFICATE_ROUNDING)),
        }
    }

    /// The smallest sphere around spheres `a` and `b`, with its centre rounded to `f32` and its
    /// radius rounded up so that both lie within it from that centre, widened by the same guard
    /// as [`NodeSphere::around`]: a parent's sphere from its children's, without reading their
    /// triangles.
    pub(super) fn enclosing(a: &NodeSphere, b: &NodeSphere) -> Self {
        let (ca, cb) = (a.centre(), b.centre());
        let (ra, rb) = (f64::from(a.radius), f64::from(b.radius));
        let distance = (cb - ca).norm();
        let centre = if distance + rb <= ra {
            ca
        } else if distance + ra <= rb {
            cb
        } else {
            // On the line through both centres, reaching from a's far side to b's.
            ca + (cb - ca) * ((distance + rb - ra) / (2.0 * distance))
        };
        let centre = centre.map(|x| x as f32);
        let reach = |c: Vector3<f64>, r: f64| (c - centre.cast::<f64>()).norm() + r;
        let radius = reach(ca, ra).max(reach(cb, rb));
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
    /// The box fitted (as the OBB-tree fits its boxes) to `triangles`, whose moments are
    /// `moments`, rounded to `f32` outwards.
    pub(super) fn fitted(moments: &SurfaceMoments, triangles: &[Triangle]) -> Self {
        let axes = moments.axes().map(|x| x as f32).cast::<f64>();
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

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    proptest! {
        /// The sphere around two spheres holds both, whether they overlap, nest or share their
        /// centre, and is no larger than the two side by side.
        #[test]
        fn the_enclosing_sphere_holds_both(
            a in prop::array::uniform4(-10.0..10.0f32),
            b in prop::array::uniform4(-10.0..10.0f32),
            same_centre in any::<bool>(),
        ) {
            let a = NodeSphere { centre: [a[0], a[1], a[2]], radius: a[3].abs() };
            let b = NodeSphere {
                centre: if same_centre { a.centre } else { [b[0], b[1], b[2]] },
                radius: b[3].abs(),
            };
            let s = NodeSphere::enclosing(&a, &b);
            for part in [a, b] {
                let reach = (part.centre() - s.centre()).norm() + f64::from(part.radius);
                prop_assert!(reach <= f64::from(s.radius), "{part:?} reaches {reach} of {s:?}");
            }
            let apart = (a.centre() - b.centre()).norm() + f64::from(a.radius) + f64::from(b.radius);
            let largest = f64::from(a.radius.max(b.radius));
            prop_assert!(f64::from(s.radius) <= (apart / 2.0).max(largest) * (1.0 + 1e-5) + 1e-6);
        }
    }
}
