//! The DOP-tree's distance against the brute force over all triangle pairs: random soups with
//! slivers, closed tori, touching and intersecting poses, the bound asked for, and
//! memories carried along coherent motion or misused.

use nalgebra::Isometry3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::DistanceMemory;
use crate::collision::distance::{
    ClosestPoints, PairsWithin, brute_force_distance, triangle_distance,
};
use crate::collision::oracle_tests::{random_pose, random_soup, torus};
use crate::collision::{DopTree, MeshCollider, QueryStats};
use crate::geometry::TriMesh;
use vas_testkit::tumble::tumble_pose;

/// A soup whose every fifth triangle is a sliver (a corner 1e-9 off the opposite edge's middle, or
/// two corners 1e-9 apart), as CAD exports have; exactly degenerate ones a mesh drops.
fn soup_with_slivers(rng: &mut ChaCha8Rng, n: usize) -> TriMesh {
    let soup = random_soup(rng, n, 0.3);
    let mut vertices = soup.vertices().to_vec();
    let nudge = nalgebra::Vector3::new(1e-9, -1e-9, 1e-9);
    for (i, [a, b, c]) in soup.triangles().iter().enumerate() {
        let (a, b, c) = (*a as usize, *b as usize, *c as usize);
        match i % 10 {
            0 => vertices[b] = vertices[a] + nudge,
            5 => vertices[c] = nalgebra::center(&vertices[a], &vertices[b]) + nudge,
            _ => {}
        }
    }
    TriMesh::new(vertices, soup.triangles().to_vec()).unwrap().0
}

/// Checks `found` against the brute force at `b_to_a`: the same distance (relative 1e-12, exactly
/// 0 when touching), on triangles of that distance, with points as far apart as that.
fn assert_matches(a: &TriMesh, b: &TriMesh, b_to_a: &Isometry3<f64>, found: &ClosestPoints) {
    let expected = brute_force_distance(a, b, b_to_a).expect("meshes have triangles");
    assert!(
        (found.distance - expected.distance).abs() <= 1e-12 * expected.distance,
        "tree {} against brute force {} at {b_to_a}",
        found.distance,
        expected.distance
    );
    let [ta, tb] = found.triangles;
    let moved = b.triangle(tb as usize).map(|corner| b_to_a * corner);
    let own = triangle_distance(&a.triangle(ta as usize), &moved).distance;
    assert!(
        (own - found.distance).abs() <= 1e-12 * (1.0 + own),
        "{own} against {found:?}"
    );
    let gap = (found.on_a - b_to_a * found.on_b).norm();
    assert!(
        (gap - found.distance).abs() <= 1e-9,
        "{gap} against {found:?}"
    );
}

/// A cold query of `tb` posed at `b_to_a` against `ta` (the trees of `a` and `b`), checked by
/// [`assert_matches`]; whether the two touch.
fn cold_query_matches(
    a: &TriMesh,
    b: &TriMesh,
    ta: &DopTree,
    tb: &DopTree,
    b_to_a: &Isometry3<f64>,
) -> bool {
    let found = ta.distance(
        tb,
        b_to_a,
        &mut DistanceMemory::default(),
        &mut QueryStats::default(),
    );
    assert_matches(a, b, b_to_a, &found);
    found.distance == 0.0
}

#[test]
fn random_soups_with_slivers_agree_with_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut touching = 0;
    for case in 0..800 {
        let (n, m) = (rng.random_range(1..60), rng.random_range(1..60));
        let (a, b) = (
            soup_with_slivers(&mut rng, n),
            soup_with_slivers(&mut rng, m),
        );
        let (ta, tb) = (DopTree::build(&a), DopTree::build(&b));
        let pose = random_pose(&mut rng, [0.5, 2.0, 4.0][case % 3]);
        touching += cold_query_matches(&a, &b, &ta, &tb, &pose) as usize;
    }
    assert!(touching > 80 && touching < 720, "{touching} touching poses");
}

#[test]
fn tori_agree_with_brute_force_at_every_distance() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let (a, b) = (torus(0.3, 24, 12), torus(0.2, 16, 8));
    let (ta, tb) = (DopTree::build(&a), DopTree::build(&b));
    let mut touching = 0;
    for case in 0..600 {
        let pose = random_pose(&mut rng, [1.0, 2.5, 5.0][case % 3]);
        touching += cold_query_matches(&a, &b, &ta, &tb, &pose) as usize;
    }
    assert!(touching > 30 && touching < 570, "{touching} touching poses");
}

#[test]
fn identical_copies_touch() {
    let a = torus(0.3, 12, 6);
    let tree = DopTree::build(&a);
    let found = tree.distance(
        &tree,
        &Isometry3::identity(),
        &mut DistanceMemory::default(),
        &mut QueryStats::default(),
    );
    assert_eq!(found.distance, 0.0);
}

#[test]
fn a_bound_answers_exactly_below_it_and_nothing_above() {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let (a, b) = (torus(0.3, 20, 10), random_soup(&mut rng, 40, 0.3));
    let (ta, tb) = (DopTree::build(&a), DopTree::build(&b));
    let (mut below, mut above) = (0, 0);
    for _ in 0..800 {
        let pose = random_pose(&mut rng, 3.0);
        let d_max = rng.random_range(0.0..1.0);
        let expected = brute_force_distance(&a, &b, &pose).unwrap().distance;
        let found = ta.distance_below(
            &tb,
            &pose,
            d_max,
            &mut DistanceMemory::default(),
            &mut QueryStats::default(),
        );
        match found {
            Some(found) => {
                below += 1;
                assert!(expected < d_max, "{expected} reported below {d_max}");
                assert_matches(&a, &b, &pose, &found);
            }
            None => {
                above += 1;
                assert!(expected >= d_max, "{expected} missed below {d_max}");
            }
        }
    }
    assert!(below > 80 && above > 80, "{below} below, {above} above");
}

#[test]
fn far_pairs_end_at_the_bounding_spheres() {
    let a = torus(0.3, 20, 10);
    let tree = DopTree::build(&a);
    let far = Isometry3::translation(10.0, 0.0, 0.0);
    let mut stats = QueryStats::default();
    let found = tree.distance_below(&tree, &far, 1.0, &mut DistanceMemory::default(), &mut stats);
    assert_eq!(found, None);
    assert_eq!(
        (stats.bv_tests, stats.tri_tests, stats.realignments),
        (1, 0, 0)
    );
}

#[test]
fn a_memory_carried_along_a_tumble_gives_the_same_answers_for_less_work() {
    let (a, b) = (torus(0.3, 32, 12), torus(0.3, 32, 12));
    let (ta, tb) = (DopTree::build(&a), DopTree::build(&b));
    let (mut coherent, mut cold) = (QueryStats::default(), QueryStats::default());
    let mut memory = DistanceMemory::default();
    for step in 0..200 {
        let pose = tumble_pose(3.0 - 0.01 * step as f64, step, 400);
        let carried = ta.distance(&tb, &pose, &mut memory, &mut coherent);
        let fresh = ta.distance(&tb, &pose, &mut DistanceMemory::default(), &mut cold);
        // Equal up to the rounding of a tie between neighbouring triangles.
        assert!(
            (carried.distance - fresh.distance).abs() <= 1e-12 * fresh.distance,
            "step {step}: {} against {}",
            carried.distance,
            fresh.distance
        );
        if step % 25 == 0 {
            assert_matches(&a, &b, &pose, &carried);
        }
    }
    assert!(
        coherent.tri_tests < cold.tri_tests && coherent.bv_tests < cold.bv_tests,
        "coherent {coherent:?} against cold {cold:?}"
    );
}

#[test]
fn a_memory_of_other_trees_or_a_jump_changes_no_answer() {
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    let meshes = [
        torus(0.3, 16, 8),
        random_soup(&mut rng, 50, 0.3),
        torus(0.1, 10, 6),
    ];
    let trees = meshes.each_ref().map(DopTree::build);
    let mut memory = DistanceMemory::default();
    for _ in 0..300 {
        let (i, j) = (rng.random_range(0..3), rng.random_range(0..3));
        let pose = random_pose(&mut rng, 3.0);
        let found = trees[i].distance(&trees[j], &pose, &mut memory, &mut QueryStats::default());
        assert_matches(&meshes[i], &meshes[j], &pose, &found);
    }
}

#[test]
fn after_a_jump_a_carried_memory_does_a_cold_querys_work() {
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    let (a, b) = (torus(0.3, 24, 12), torus(0.2, 16, 8));
    let (ta, tb) = (DopTree::build(&a), DopTree::build(&b));
    let mut memory = DistanceMemory::default();
    for _ in 0..100 {
        let pose = random_pose(&mut rng, 2.0);
        let (mut carried, mut cold) = (QueryStats::default(), QueryStats::default());
        let found = ta.distance(&tb, &pose, &mut memory, &mut carried);
        let fresh = ta.distance(&tb, &pose, &mut DistanceMemory::default(), &mut cold);
        assert_eq!(found, fresh);
        assert_eq!(
            (carried.bv_tests, carried.tri_tests),
            (cold.bv_tests, cold.tri_tests)
        );
    }
}

#[test]
fn pairs_within_a_clearance_are_those_the_brute_force_finds() {
    let mut rng = ChaCha8Rng::seed_from_u64(16);
    let meshes: Vec<TriMesh> = (0..6)
        .map(|i| match i % 2 {
            0 => torus(0.3, 12, 6),
            _ => random_soup(&mut rng, 20, 0.3),
        })
        .collect();
    let trees: Vec<DopTree> = meshes.iter().map(DopTree::build).collect();
    let mut within = PairsWithin::default();
    let mut found_any = 0;
    for _ in 0..40 {
        let poses: Vec<Isometry3<f64>> = (0..6).map(|_| random_pose(&mut rng, 3.0)).collect();
        let objects: Vec<(&DopTree, Isometry3<f64>)> =
            trees.iter().zip(poses.iter().copied()).collect();
        let candidates: Vec<(usize, usize)> = (0..6)
            .flat_map(|i| (i + 1..6).map(move |j| (i, j)))
            .collect();
        let mut out = Vec::new();
        within.find(
            &objects,
            candidates.iter().copied(),
            0.4,
            &mut QueryStats::default(),
            &mut out,
        );
        let expected: Vec<(usize, usize)> = candidates
            .into_iter()
            .filter(|&(i, j)| {
                let b_to_a = poses[i].inv_mul(&poses[j]);
                brute_force_distance(&meshes[i], &meshes[j], &b_to_a)
                    .unwrap()
                    .distance
                    < 0.4
            })
            .collect();
        let reported: Vec<(usize, usize)> = out.iter().map(|pair| (pair.a, pair.b)).collect();
        assert_eq!(reported, expected);
        for pair in &out {
            let b_to_a = poses[pair.a].inv_mul(&poses[pair.b]);
            assert_matches(&meshes[pair.a], &meshes[pair.b], &b_to_a, &pair.closest);
        }
        found_any += out.len();
    }
    assert!(found_any > 20, "{found_any} pairs within the clearance");
}
