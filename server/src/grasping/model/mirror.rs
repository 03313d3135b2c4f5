//! The mirror image of a hand, and a hand reshaped by a calibration.

use nalgebra::{Point3, Unit, UnitQuaternion, Vector3};

use super::validate::variable_levers;
use super::{Dof, HandModel, Segment, SweptHull};

impl HandModel {
    /// The mirror image of this hand in the `x = 0` plane (a right hand becomes a left hand).
    ///
    /// A reflection `S = diag(-1, 1, 1)` maps a rotation about axis `a` by `θ` to a rotation about
    /// `-S a` by `θ`, so points get `x` negated and rotation axes get `y` and `z` negated; flex
    /// values keep their meaning.
    pub fn mirrored(&self) -> HandModel {
        let point = |p: &Point3<f64>| Point3::new(-p.x, p.y, p.z);
        let axis = |a: &Unit<Vector3<f64>>| Unit::new_unchecked(Vector3::new(a.x, -a.y, -a.z));
        let rotation = |q: &UnitQuaternion<f64>| match q.axis_angle() {
            Some((a, angle)) => UnitQuaternion::from_axis_angle(&axis(&a), angle),
            None => UnitQuaternion::identity(),
        };
        let segments = self
            .segments
            .iter()
            .map(|s| Segment {
                origin: Vector3::new(-s.origin.x, s.origin.y, s.origin.z),
                base_rotation: rotation(&s.base_rotation),
                dofs: s
                    .dofs
                    .iter()
                    .map(|d| Dof {
                        axis: axis(&d.axis),
                        pivot: point(&d.pivot),
                        terms: d.terms.clone(),
                    })
                    .collect(),
                shape: SweptHull {
                    centres: s.shape.centres.iter().map(point).collect(),
                    radius: s.shape.radius,
                },
                ..s.clone()
            })
            .collect();
        HandModel {
            name: format!("{} (mirrored)", self.name),
            side: self.side.mirrored(),
            limits: self.limits.clone(),
            segments,
            levers: self.levers,
        }
    }

    /// This hand with its segments' geometry (joint origins, pivots, shapes) changed by `edit`,
    /// as a per-user calibration does; the tree, the degrees of freedom' axes and flex terms and
    /// the limits stay as they are.
    pub fn reshaped(&self, edit: impl FnOnce(&mut [Segment])) -> HandModel {
        let mut segments = self.segments.clone();
        edit(&mut segments);
        debug_assert!(
            segments
                .iter()
                .zip(&self.segments)
                .all(|(new, old)| { new.parent == old.parent && new.dofs.len() == old.dofs.len() })
        );
        let levers = variable_levers(&segments);
        HandModel {
            name: self.name.clone(),
            side: self.side,
            limits: self.limits.clone(),
            segments,
            levers,
        }
    }
}
