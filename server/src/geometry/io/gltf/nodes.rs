//! The scene graph: the nodes that carry meshes, reached from the default scene's roots (or from
//! every root, when the file names no default scene), each with its world transform.

use nalgebra::{Matrix4, Quaternion, Translation3, UnitQuaternion, Vector3};
use vas_protocol::Readable;

use super::document::{Document, Node};

/// A node that carries a mesh, where the scene graph puts it.
#[derive(Debug, Clone)]
pub(super) struct MeshNode {
    /// The node's index in the file.
    pub node: usize,
    /// The mesh's index in the file.
    pub mesh: usize,
    /// The node's transform from the mesh's frame to the file's world: its ancestors' transforms
    /// times its own (affine).
    pub world: Matrix4<f64>,
}

/// Every node with a mesh, in the order of a depth-first walk (roots in order, children in
/// order). The nodes must form trees: a node reached twice (with two parents, or in a cycle) is
/// refused.
pub(super) fn mesh_nodes(document: &Document) -> Result<Vec<MeshNode>, String> {
    let count = document.nodes.len();
    let node_exists = |index: usize, whose: &dyn Fn() -> String| {
        if index < count {
            Ok(index)
        } else {
            Err(format!(
                "{} names node {index}, which does not exist (the file has {count})",
                whose()
            ))
        }
    };
    let roots: Vec<usize> = match document.scene {
        Some(scene) => {
            let scene_nodes = &document
                .scenes
                .get(scene)
                .ok_or_else(|| format!("the default scene {scene} does not exist"))?
                .nodes;
            for &root in scene_nodes {
                node_exists(root, &|| format!("scene {scene}"))?;
            }
            scene_nodes.clone()
        }
        None => {
            let mut is_child = vec![false; count];
            for (parent, node) in document.nodes.iter().enumerate() {
                for &child in &node.children {
                    is_child[node_exists(child, &|| format!("node {parent}"))?] = true;
                }
            }
            (0..count).filter(|&i| !is_child[i]).collect()
        }
    };

    let mut reached = vec![false; count];
    let mut found = Vec::new();
    // Depth first without recursion (a chain of nodes may be as deep as the file is long);
    // children are pushed in reverse so that they are visited in order.
    let mut stack: Vec<(usize, Matrix4<f64>)> = roots
        .iter()
        .rev()
        .map(|&root| (root, Matrix4::identity()))
        .collect();
    while let Some((index, parent)) = stack.pop() {
        if std::mem::replace(&mut reached[index], true) {
            return Err(format!(
                "node {index} is reached twice: glTF nodes must form trees"
            ));
        }
        let node = &document.nodes[index];
        let world = parent * local_transform(node).map_err(|e| format!("node {index}: {e}"))?;
        if !world.iter().all(|c| c.is_finite()) {
            return Err(format!("node {index}: its world transform is not finite"));
        }
        if let Some(mesh) = node.mesh {
            if mesh >= document.meshes.len() {
                return Err(format!(
                    "node {index} names mesh {mesh}, which does not exist (the file has {})",
                    document.meshes.len()
                ));
            }
            found.push(MeshNode {
                node: index,
                mesh,
                world,
            });
        }
        for &child in node.children.iter().rev() {
            stack.push((node_exists(child, &|| format!("node {index}"))?, world));
        }
    }
    Ok(found)
}

/// A node's transform from its own frame to its parent's: its matrix, or its translation,
/// rotation and scale (T R S).
fn local_transform(node: &Node) -> Result<Matrix4<f64>, String> {
    if let Some(matrix) = node.matrix {
        let matrix = Matrix4::from_column_slice(&matrix);
        let bottom = [
            matrix[(3, 0)],
            matrix[(3, 1)],
            matrix[(3, 2)],
            matrix[(3, 3)],
        ];
        if bottom != [0.0, 0.0, 0.0, 1.0] {
            return Err(format!(
                "its matrix's last row is {bottom:?}, not [0, 0, 0, 1] (a projection, not a \
                 placement)"
            ));
        }
        return Ok(matrix);
    }
    let translation = Translation3::from(Vector3::from(node.translation.unwrap_or([0.0; 3])));
    let [x, y, z, w] = node.rotation.unwrap_or([0.0, 0.0, 0.0, 1.0]);
    let quaternion = Quaternion::new(w, x, y, z);
    let norm = quaternion.norm();
    if !(norm.is_finite() && norm > 0.5) {
        let [x, y, z, w] = [x, y, z, w].map(Readable);
        return Err(format!(
            "its rotation [{x}, {y}, {z}, {w}] is not a unit quaternion"
        ));
    }
    let rotation = UnitQuaternion::new_normalize(quaternion);
    let scale = Vector3::from(node.scale.unwrap_or([1.0; 3]));
    Ok(translation.to_homogeneous()
        * rotation.to_homogeneous()
        * Matrix4::new_nonuniform_scaling(&scale))
}
