//! A glTF file as separate parts: each mesh node's name, and its world transform split into a
//! rigid pose and the shape (scale, mirroring, shear) that is baked into its mesh.

use std::collections::HashSet;

use nalgebra::{Isometry3, Matrix3, Matrix4, Rotation3, Translation3, UnitQuaternion, Vector3};

/// A mesh node of a glTF file as a part: where it is and what its mesh becomes.
#[derive(Debug, Clone, PartialEq)]
pub struct GltfPart {
    /// The node's name, unique within the file: see `unique_names`.
    pub name: String,
    /// The node's index in the file.
    pub node: usize,
    /// The index of the node's mesh in the file.
    pub mesh: usize,
    /// The rotation and translation of the node's world transform: the part's pose in the
    /// file's frame.
    pub pose: Isometry3<f64>,
    /// The rest of the world transform, `pose⁻¹ × world`: the scale (non-uniform, negative),
    /// mirroring and shear that [`GltfFile::mesh`](super::GltfFile::mesh) bakes into the mesh's
    /// vertices. Rounded to nine significant digits, so that instances of one mesh at the same
    /// scale get the same shape whatever their rotation.
    pub shape: Matrix3<f64>,
}

impl GltfPart {
    /// What identifies the part's baked mesh within its file: parts with the same key have the
    /// same mesh (instances of one mesh at one scale).
    pub fn mesh_key(&self) -> String {
        format!("mesh {} shaped {:?}", self.mesh, self.shape.as_slice())
    }
}

/// Splits an affine world transform into a rotation and translation, and the linear map left
/// (`world = pose × shape`); `None` when the transform collapses a direction (a zero scale) or
/// is too large to decompose.
///
/// The rotation is that of the polar decomposition of the linear part. A mirroring transform
/// (negative determinant) has no rotation of its own: it is taken as the mirror in the part's
/// own x followed by a rotation, so that a node mirrored in x keeps its rotation.
pub(super) fn split_world(world: &Matrix4<f64>) -> Option<(Isometry3<f64>, Matrix3<f64>)> {
    let linear: Matrix3<f64> = world.fixed_view::<3, 3>(0, 0).into();
    let svd = linear.svd(true, true);
    let (largest, smallest) = (svd.singular_values.max(), svd.singular_values.min());
    // Not finite: a transform so large that its squares overflow (no mesh fits under it).
    if !largest.is_finite() || smallest <= largest * 1e-12 {
        return None;
    }
    let mut orthogonal = svd.u? * svd.v_t?;
    if orthogonal.determinant() < 0.0 {
        orthogonal.set_column(0, &-orthogonal.column(0));
    }
    // Orthogonal to rounding: the direct conversion, renormalised (no iteration).
    let rotation =
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(orthogonal));
    let rotation = UnitQuaternion::new_normalize(rotation.into_inner());
    if !rotation.coords.iter().all(|c| c.is_finite()) {
        return None;
    }
    let shape = rounded(&(rotation.to_rotation_matrix().matrix().transpose() * linear));
    let translation = Translation3::from(Vector3::new(world[(0, 3)], world[(1, 3)], world[(2, 3)]));
    Some((Isometry3::from_parts(translation, rotation), shape))
}

/// `m` with every entry rounded to nine significant digits of its largest entry (and no
/// negative zeros), so that shapes equal to that precision are equal.
fn rounded(m: &Matrix3<f64>) -> Matrix3<f64> {
    let largest = m.amax();
    let unit = 10f64.powi(largest.log10().floor() as i32 - 8);
    m.map(|x| (x / unit).round() * unit + 0.0)
}

/// Names for mesh nodes: each node's own name, or `<file stem>/node<index>` for a node without
/// one. Where names repeat, the first (in the order given) keeps it and each later one gets
/// `<name>#2`, `<name>#3`, ..., the smallest number that no other node's name already takes.
pub(super) fn unique_names(stem: &str, nodes: &[(usize, Option<&str>)]) -> Vec<String> {
    let base: Vec<String> = nodes
        .iter()
        .map(|&(index, name)| match name {
            Some(name) if !name.trim().is_empty() => name.to_owned(),
            _ => format!("{stem}/node{index}"),
        })
        .collect();
    let taken: HashSet<&str> = base.iter().map(String::as_str).collect();
    let mut given: HashSet<String> = HashSet::with_capacity(base.len());
    base.iter()
        .map(|name| {
            let mut unique = name.clone();
            let mut number = 2;
            while given.contains(&unique) || (unique != *name && taken.contains(unique.as_str())) {
                unique = format!("{name}#{number}");
                number += 1;
            }
            given.insert(unique.clone());
            unique
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn names_are_defaulted_and_made_unique_in_order() {
        let nodes = [
            (0, Some("wheel")),
            (1, None),
            (2, Some("wheel")),
            (3, Some("wheel#2")),
            (4, Some("")),
            (5, Some("wheel")),
        ];
        assert_eq!(
            unique_names("car", &nodes),
            [
                "wheel",
                "car/node1",
                "wheel#3",
                "wheel#2",
                "car/node4",
                "wheel#4"
            ]
        );
    }

    #[test]
    fn a_world_transform_splits_into_a_pose_and_a_baked_shape() {
        let rotation = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), FRAC_PI_2);
        let translation = Vector3::new(1.0, 2.0, 3.0);
        for scale in [[2.0, 0.5, 1.0], [-1.0, 1.0, 1.0], [1.0, 1.0, 1.0]] {
            let world = Matrix4::new_translation(&translation)
                * rotation.to_homogeneous()
                * Matrix4::new_nonuniform_scaling(&Vector3::from(scale));
            let (pose, shape) = split_world(&world).unwrap();
            assert!((pose.translation.vector - translation).norm() < 1e-15);
            // The node's own rotation is kept, mirrored in x or not; the scale is the shape.
            assert!(pose.rotation.angle_to(&rotation) < 1e-12, "{scale:?}");
            assert_eq!(
                shape,
                Matrix3::from_diagonal(&Vector3::from(scale)),
                "{scale:?}"
            );
            let again = pose.to_homogeneous().fixed_view::<3, 3>(0, 0) * shape;
            assert!((again - world.fixed_view::<3, 3>(0, 0)).amax() < 1e-12);
        }
        let flat = Matrix4::new_nonuniform_scaling(&Vector3::new(1.0, 0.0, 1.0));
        assert!(split_world(&flat).is_none());
    }
}
