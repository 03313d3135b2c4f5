//! The paper's comparison baselines, which the product does not use: the k-DOP tree re-aligned
//! by brute force (QuickCD) and the OBB-tree (RAPID, as in FCL). Both answer through
//! [`MeshCollider`](vas_server::collision::MeshCollider) like the DOP-tree and parry.

mod kdop_bruteforce;
mod obb_tree;

pub use kdop_bruteforce::KdopBruteForceTree;
pub use obb_tree::ObbTree;

#[cfg(test)]
mod tests {
    use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use vas_server::collision::{DopTree, MeshCollider, QueryStats};
    use vas_server::geometry::{TriMesh, shapes};

    use super::{KdopBruteForceTree, ObbTree};

    fn sorted(mut pairs: Vec<[u32; 2]>) -> Vec<[u32; 2]> {
        pairs.sort_unstable();
        pairs
    }

    /// Each baseline gives the DOP-tree's answers (the library checks the DOP-tree against
    /// exhaustive brute force) at random poses of `b` within `reach` of `a`: first hit and all
    /// pairs. Returns the number of colliding poses.
    fn agree_with_the_dop_tree(a: &TriMesh, b: &TriMesh, poses: usize, seed: u64) -> usize {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let dop = (DopTree::build(a), DopTree::build(b));
        let kdop = (KdopBruteForceTree::build(a), KdopBruteForceTree::build(b));
        let obb = (ObbTree::build(a), ObbTree::build(b));
        let mut stats = QueryStats::default();
        let mut colliding = 0;
        for _ in 0..poses {
            let axis = Vector3::new(rng.random(), rng.random(), rng.random::<f64>() + 0.1);
            let rotation = UnitQuaternion::from_axis_angle(
                &nalgebra::Unit::new_normalize(axis),
                rng.random_range(0.0..std::f64::consts::TAU),
            );
            let shift = Vector3::from_fn(|_, _| rng.random_range(-2.0..2.0));
            let pose = Isometry3::from_parts(Translation3::from(shift), rotation);
            let mut expected = Vec::new();
            dop.0
                .intersecting_pairs(&dop.1, &pose, &mut expected, &mut stats);
            let hit = !expected.is_empty();
            assert_eq!(dop.0.intersects(&dop.1, &pose, &mut stats), hit);
            colliding += usize::from(hit);
            let expected = sorted(expected);
            assert_eq!(
                kdop.0.intersects(&kdop.1, &pose, &mut stats),
                hit,
                "k-DOP at {pose}"
            );
            assert_eq!(
                obb.0.intersects(&obb.1, &pose, &mut stats),
                hit,
                "OBB at {pose}"
            );
            let mut pairs = Vec::new();
            kdop.0
                .intersecting_pairs(&kdop.1, &pose, &mut pairs, &mut stats);
            assert_eq!(sorted(pairs), expected, "k-DOP pairs at {pose}");
            let mut pairs = Vec::new();
            obb.0
                .intersecting_pairs(&obb.1, &pose, &mut pairs, &mut stats);
            assert_eq!(sorted(pairs), expected, "OBB pairs at {pose}");
        }
        colliding
    }

    #[test]
    fn the_baselines_answer_as_the_dop_tree_on_tori_and_open_sheets() {
        let torus = shapes::torus(1.0, 0.35, 24, 12);
        let small = shapes::torus(1.0, 0.2, 16, 8);
        let colliding = agree_with_the_dop_tree(&torus, &small, 400, 1);
        assert!(
            (50..350).contains(&colliding),
            "{colliding} colliding poses"
        );
        let sheet = shapes::build(shapes::ShapeKind::SheetWithHole, 800).normalized_to_unit_box();
        let hyperboloid =
            shapes::build(shapes::ShapeKind::Hyperboloid, 600).normalized_to_unit_box();
        let colliding = agree_with_the_dop_tree(&sheet, &hyperboloid, 400, 2);
        assert!(
            (20..380).contains(&colliding),
            "{colliding} colliding poses"
        );
    }

    #[test]
    fn identical_touching_copies_collide_in_every_baseline() {
        // Two copies at the identity share every triangle: each must report contact.
        let mesh = shapes::torus(1.0, 0.35, 12, 6);
        let id = Isometry3::identity();
        let mut stats = QueryStats::default();
        let obb = ObbTree::build(&mesh);
        assert!(obb.intersects(&obb, &id, &mut stats));
        let kdop = KdopBruteForceTree::build(&mesh);
        assert!(kdop.intersects(&kdop, &id, &mut stats));
        assert!(stats.tri_tests > 0 && stats.bv_tests > 0 && stats.realignments > 0);
    }
}
