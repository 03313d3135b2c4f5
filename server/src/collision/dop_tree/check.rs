//! A tree checked against its triangles: that its nodes form one tree laid out as the traversal
//! reads it, and that every bound the traversal trusts (DOP offsets, spheres, boxes) holds every
//! triangle under its node. A tree that passes answers no query wrongly, whoever built it: a tree
//! read from a cache is checked so before it is used.

use std::sync::Arc;

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

use super::separation::BOX_TEST_MAX_TRIANGLES;
use super::shared;
use super::tree::{DopTree, Node};

/// The relative margin by which a child's sphere must lie inside its parent's for the check to
/// take it as held without reading the corners: far above the rounding of the distances.
const SPHERE_SLACK: f64 = 1e-9;

/// What is wrong with a tree, in words.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct Defect(String);

fn defect(what: impl Into<String>) -> Defect {
    Defect(what.into())
}

/// Per node of a tree, its parent and the triangles under it (`start..end` in leaf order).
type Layout = (Arc<[u32]>, Arc<[[u32; 2]]>);

/// The parent of each node and the triangles under it (`start..end` in leaf order) of `nodes`
/// over `triangle_count` triangles in leaf order, if they form one tree as the builder lays it
/// out: the root first, the two children of an inner node adjacent and after it, every node
/// reached once, leaves taking the triangles in order, each exactly once.
pub(super) fn structure(nodes: &[Node], triangle_count: usize) -> Result<Layout, Defect> {
    const UNREACHED: u32 = u32::MAX;
    if nodes.is_empty() || nodes.len() > 2 * triangle_count.max(1) {
        return Err(defect(format!(
            "{} nodes for {triangle_count} triangles",
            nodes.len()
        )));
    }
    let (mut shared_parents, mut shared_ranges) =
        (shared::zeroed(nodes.len()), shared::zeroed(nodes.len()));
    let parents = shared::unshared(&mut shared_parents);
    parents.fill(UNREACHED);
    parents[0] = 0;
    let ranges = shared::unshared(&mut shared_ranges);
    let mut next_triangle = 0usize;
    let mut stack = vec![0usize];
    while let Some(index) = stack.pop() {
        let node = &nodes[index];
        let first = node.first as usize;
        if node.is_leaf() {
            let end = first + node.count as usize;
            if first != next_triangle || end > triangle_count {
                return Err(defect(format!(
                    "leaf {index} holds triangles {first}..{end}, not the next ones from \
                     {next_triangle} of {triangle_count}"
                )));
            }
            ranges[index] = [first as u32, end as u32];
            next_triangle = end;
            continue;
        }
        if first <= index || first + 1 >= nodes.len() {
            return Err(defect(format!(
                "node {index} has children {first} and {} of {} nodes",
                first + 1,
                nodes.len()
            )));
        }
        for child in [first, first + 1] {
            if parents[child] != UNREACHED {
                return Err(defect(format!("node {child} is reached twice")));
            }
            parents[child] = index as u32;
        }
        // The left subtree's triangles come first.
        stack.extend([first + 1, first]);
    }
    if let Some(index) = parents.iter().position(|&p| p == UNREACHED) {
        return Err(defect(format!("node {index} is not in the tree")));
    }
    if next_triangle != triangle_count {
        return Err(defect(format!(
            "the leaves hold {next_triangle} of {triangle_count} triangles"
        )));
    }
    // Children come after their parent: in reverse order, a node's children are done first.
    for index in (0..nodes.len()).rev() {
        let node = &nodes[index];
        if !node.is_leaf() {
            let first = node.first as usize;
            ranges[index] = [ranges[first][0], ranges[first + 1][1]];
        }
    }
    Ok((shared_parents, shared_ranges))
}

/// Whether the triangle ids of a tree over `triangle_count` triangles name each exactly once.
pub(super) fn permutation(ids: &[u32], triangle_count: usize) -> Result<(), Defect> {
    if ids.len() != triangle_count {
        return Err(defect(format!(
            "{} triangle ids for {triangle_count} triangles",
            ids.len()
        )));
    }
    let mut seen = vec![false; triangle_count];
    for &id in ids {
        match seen.get_mut(id as usize) {
            Some(seen) if !*seen => *seen = true,
            _ => {
                return Err(defect(format!(
                    "triangle id {id} is out of range or repeated"
                )));
            }
        }
    }
    Ok(())
}

/// Whether every bound of `tree` (laid out as [`structure`] accepts) holds its node's triangles:
/// each leaf's offsets bound its triangles along every normal and each inner node's its
/// children's; each sphere holds its node's corners; each box the traversal reads (nodes of at
/// most [`BOX_TEST_MAX_TRIANGLES`] triangles) holds them. Also that node sizes are what the
/// offsets give, for the traversal's choice of which node to descend.
pub(super) fn bounds(tree: &DopTree) -> Result<(), Defect> {
    let k = tree.k;
    (0..tree.nodes.len()).into_par_iter().try_for_each(|index| {
        let node = &tree.nodes[index];
        let offsets = tree.node_offsets(index);
        if offsets.iter().any(|d| !d.is_finite()) {
            return Err(defect(format!(
                "node {index} has an offset that is not finite"
            )));
        }
        let triangles = tree.node_triangles(index as u32);
        if node.is_leaf() {
            let h = k / 2;
            for (i, axis) in tree.set.axes().iter().enumerate() {
                let (low, high) = (triangles.iter().flatten())
                    .map(|p| axis.dot(&p.coords))
                    .fold((f64::MAX, f64::MIN), |(low, high), x| {
                        (low.min(x), high.max(x))
                    });
                // Normal `i + h` is axis `i` negated, and a negated dot product rounds to the
                // negated value: its reach is `-low`.
                if f64::from(offsets[i]) < high || f64::from(offsets[i + h]) < -low {
                    return Err(defect(format!("leaf {index} does not bound its triangles")));
                }
            }
        } else {
            let first = node.first as usize;
            let children = [tree.node_offsets(first), tree.node_offsets(first + 1)];
            if (0..k).any(|i| offsets[i] < children[0][i].max(children[1][i])) {
                return Err(defect(format!("node {index} does not bound its children")));
            }
        }
        let sphere = &node.sphere;
        let radius = f64::from(sphere.radius);
        if !radius.is_finite() || !sphere_holds(tree, index, sphere.centre(), radius) {
            return Err(defect(format!(
                "the sphere of node {index} misses a corner"
            )));
        }
        if triangles.len() <= BOX_TEST_MAX_TRIANGLES {
            let oriented = tree.boxes[index].oriented();
            let to_box: Option<Matrix3<f64>> = oriented.axes.try_inverse();
            let holds = to_box.is_some_and(|to_box| {
                (triangles.iter().flatten()).all(|p| {
                    let u = to_box * (p.coords - oriented.center);
                    (0..3).all(|i| u[i].abs() <= oriented.extents[i])
                })
            });
            if !holds {
                return Err(defect(format!("the box of node {index} misses a corner")));
            }
        }
        let h = k / 2;
        let size = (0..h)
            .map(|i| offsets[i] + offsets[i + h])
            .fold(0.0, f32::max);
        if node.size != size {
            return Err(defect(format!(
                "node {index} has size {} where its offsets give {size}",
                node.size
            )));
        }
        Ok(())
    })
}

/// Whether the sphere (`centre`, `radius`) holds every corner under node `index` (whose own
/// sphere is not trusted). A descendant whose sphere lies inside it holds its corners, which that
/// descendant's own check holds them to, so only the subtrees reaching past the sphere are
/// descended, down to the corners of their leaves.
fn sphere_holds(tree: &DopTree, index: usize, centre: Vector3<f64>, radius: f64) -> bool {
    let inside = |node: &Node| {
        let reach = (node.sphere.centre() - centre).norm() + f64::from(node.sphere.radius);
        reach * (1.0 + SPHERE_SLACK) <= radius
    };
    let mut pending = vec![index];
    while let Some(index) = pending.pop() {
        let node = &tree.nodes[index];
        if node.is_leaf() {
            let mut corners = tree.node_triangles(index as u32).iter().flatten();
            if corners.any(|p| (p.coords - centre).norm() > radius) {
                return false;
            }
        } else {
            let first = node.first as usize;
            for child in [first, first + 1] {
                if !inside(&tree.nodes[child]) {
                    pending.push(child);
                }
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::collision::MeshCollider;
    use crate::collision::oracle_tests::{random_soup, torus};

    #[test]
    fn built_trees_pass() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for mesh in [torus(0.3, 20, 10), random_soup(&mut rng, 500, 0.2)] {
            for leaf_size in [1, 4] {
                let set = crate::collision::orientation::OrientationSet::default();
                let tree = DopTree::with_options(&mesh, &set, leaf_size);
                let (parents, ranges) =
                    structure(&tree.nodes, tree.triangle_count()).expect("a tree");
                assert_eq!(&parents[..], &tree.parents[..]);
                assert_eq!(&ranges[..], &tree.triangle_ranges[..]);
                permutation(&tree.triangle_ids, mesh.triangles().len()).expect("ids");
                bounds(&tree).expect("bounds");
            }
        }
    }

    #[test]
    fn the_sphere_check_agrees_with_reading_every_corner() {
        use rand::Rng;
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let tree = DopTree::build(&torus(0.3, 24, 12));
        let every_corner_held = |t: &DopTree| {
            (0..t.node_count()).all(|i| {
                let sphere = &t.nodes[i].sphere;
                (t.node_triangles(i as u32).iter().flatten())
                    .all(|p| (p.coords - sphere.centre()).norm() <= f64::from(sphere.radius))
            })
        };
        let mut refused = 0;
        for _ in 0..300 {
            let mut copy = tree.clone();
            let mut nodes = copy.nodes.to_vec();
            for _ in 0..rng.random_range(1..4) {
                let node = rng.random_range(0..nodes.len());
                nodes[node].sphere.radius *= rng.random_range(0.9..1.0f32);
            }
            copy.nodes = nodes.into();
            let held = every_corner_held(&copy);
            assert_eq!(bounds(&copy).is_ok(), held);
            refused += usize::from(!held);
        }
        assert!(refused > 30, "only {refused} damaged trees were refused");
    }

    #[test]
    fn every_kind_of_damage_is_found() {
        let tree = DopTree::build(&torus(0.3, 12, 6));
        let n = tree.triangle_count();
        let inner = (0..tree.node_count())
            .find(|&i| !tree.nodes[i].is_leaf() && i > 0)
            .unwrap();
        let leaf = (0..tree.node_count())
            .find(|&i| tree.nodes[i].is_leaf())
            .unwrap();

        let mut nodes = tree.nodes.to_vec();
        nodes[inner].first = inner as u32;
        assert!(structure(&nodes, n).is_err(), "a child before its parent");
        let mut nodes = tree.nodes.to_vec();
        nodes[leaf].count += 1;
        assert!(
            structure(&nodes, n).is_err(),
            "a leaf taking another's triangle"
        );
        assert!(
            structure(&tree.nodes, n + 1).is_err(),
            "a triangle in no leaf"
        );

        let mut ids = tree.triangle_ids.to_vec();
        ids[1] = ids[0];
        assert!(permutation(&ids, n).is_err(), "a repeated id");

        let damaged = |change: &dyn Fn(&mut DopTree)| {
            let mut copy = tree.clone();
            change(&mut copy);
            bounds(&copy).map_err(|defect| defect.to_string())
        };
        let k = tree.k;
        let shrink_offset = |node: usize, offset: usize| {
            move |t: &mut DopTree| {
                let mut offsets = t.offsets.to_vec();
                offsets[node * k + offset] -= 1e-3;
                t.offsets = offsets.into();
            }
        };
        for offset in [0, k / 2 + 1, k - 1] {
            assert!(
                damaged(&shrink_offset(leaf, offset))
                    .unwrap_err()
                    .contains("does not bound"),
                "offset {offset} of a leaf"
            );
        }
        assert!(
            damaged(&shrink_offset(inner, 0))
                .unwrap_err()
                .contains("does not bound")
        );
        assert!(
            damaged(&|t| {
                let mut nodes = t.nodes.to_vec();
                nodes[inner].sphere.radius *= 0.5;
                t.nodes = nodes.into();
            })
            .unwrap_err()
            .contains("sphere")
        );
        assert!(
            damaged(&|t| {
                let mut boxes = t.boxes.to_vec();
                boxes[leaf].extents[0] *= 0.5;
                t.boxes = boxes.into();
            })
            .unwrap_err()
            .contains("box")
        );
        assert!(
            damaged(&|t| {
                let mut nodes = t.nodes.to_vec();
                nodes[0].size *= 2.0;
                t.nodes = nodes.into();
            })
            .unwrap_err()
            .contains("size")
        );
    }
}
