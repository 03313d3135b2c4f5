//! Tests of the DOP-tree's parts: node bounds, certificates and the front, the vector scan, the
//! pair memory and the re-alignment. Answers against oracles are in `collision::oracle_tests`.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::certificates::{Certificates, DueCertificates, NodeBound};
use super::node_bounds::NodeSphere;
use super::pair_memory::{Carry, MEMORY_SLOTS, PairMemory};
use super::query::LazyPair;
use super::realign::{AffineRealign, MAX_K, Realign};
use super::separation::{BOX_TEST_MAX_TRIANGLES, Ending};
use super::traverse::TreePair;
use super::tree::{DopTree, Node};
use crate::collision::oracle_tests::brute_force_hit;
use crate::collision::oracle_tests::{random_pose, random_soup, torus};
use crate::collision::orientation::OrientationSet;
use crate::collision::{MeshCollider, QueryStats};
use vas_testkit::tumble::tumble_pose;

/// Every corner of every node's triangles, with the node.
fn node_corners(tree: &DopTree) -> impl Iterator<Item = (usize, Point3<f64>)> + '_ {
    (0..tree.node_count()).flat_map(move |node| {
        tree.node_triangles(node as u32)
            .iter()
            .flatten()
            .map(move |&corner| (node, corner))
    })
}

/// Every corner of node `node`'s triangles, placed by `pose`.
fn corners_at(tree: &DopTree, node: u32, pose: &Isometry3<f64>) -> Vec<Vector3<f64>> {
    tree.node_triangles(node)
        .iter()
        .flatten()
        .map(|corner| (pose * corner).coords)
        .collect()
}

/// How far every point of `far` lies beyond every point of `near` along `direction`
/// (negative where their projections overlap).
fn separation_along(near: &[Vector3<f64>], far: &[Vector3<f64>], direction: &Vector3<f64>) -> f64 {
    let top = near
        .iter()
        .map(|p| p.dot(direction))
        .fold(f64::MIN, f64::max);
    let bottom = far
        .iter()
        .map(|q| q.dot(direction))
        .fold(f64::MAX, f64::min);
    bottom - top
}

#[test]
fn a_remembered_proof_answers_only_for_its_own_pair() {
    // Thin rings, long along y: their bounding spheres overlap 1 apart along x, so the
    // query proves their roots apart and remembers the proof.
    let ring = torus(0.3, 24, 8)
        .map_vertices(|v| Point3::new(0.1 * v.x, 2.0 * v.y, 0.1 * v.z))
        .unwrap();
    let (a, b) = (DopTree::build(&ring), DopTree::build(&ring));
    // Whole tori, which intersect at the same pose, in a pair whose memory takes the same
    // slot of this thread's table.
    let whole = torus(0.3, 24, 8);
    let c = DopTree::build(&whole);
    let slot = PairMemory::slot((a.id, b.id));
    let d = std::iter::repeat_with(|| DopTree::build(&whole))
        .take(100 * MEMORY_SLOTS)
        .find(|d| PairMemory::slot((c.id, d.id)) == slot)
        .expect("some tree's pair with c shares the slot");
    let pose = Isometry3::translation(1.0, 0.0, 0.0);
    let mut stats = QueryStats::default();
    assert!(!a.intersects(&b, &pose, &mut stats), "the rings are apart");
    assert!(
        brute_force_hit(&whole, &whole, &pose),
        "the oracle: the tori intersect"
    );
    assert!(
        c.intersects(&d, &pose, &mut stats),
        "the rings' proof must not answer for the tori"
    );
}

#[test]
fn node_spheres_hold_their_triangles() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for mesh in [torus(0.3, 20, 10), random_soup(&mut rng, 300, 0.2)] {
        let tree = DopTree::build(&mesh);
        for (node, corner) in node_corners(&tree) {
            let sphere = &tree.nodes[node].sphere;
            let distance = (corner.coords - sphere.centre()).norm();
            assert!(
                distance <= f64::from(sphere.radius),
                "node {node}: corner at {distance} from a sphere of radius {}",
                sphere.radius
            );
        }
        // Not the tree's sphere everywhere: a leaf's is about its triangle's size.
        let leaf = tree.nodes.iter().position(Node::is_leaf).unwrap();
        assert!(f64::from(tree.nodes[leaf].sphere.radius) < 0.5 * tree.bounding_radius);
    }
}

#[test]
fn node_boxes_hold_their_triangles() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for mesh in [torus(0.3, 20, 10), random_soup(&mut rng, 300, 0.2)] {
        let tree = DopTree::build(&mesh);
        let directions: Vec<Vector3<f64>> = (0..16)
            .map(|_| Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)).normalize())
            .collect();
        // Only small nodes have boxes: the traversal tests no others.
        let boxed = node_corners(&tree)
            .filter(|&(node, _)| tree.node_triangles(node as u32).len() <= BOX_TEST_MAX_TRIANGLES);
        for (node, corner) in boxed {
            for direction in &directions {
                let (low, high) = tree.boxes[node].oriented().projection(direction, 0.0);
                let along = corner.coords.dot(direction);
                assert!(
                    (low..=high).contains(&along),
                    "node {node}: corner at {along} outside [{low}, {high}]"
                );
            }
        }
        // Fitted, not merely enclosing: a leaf's box is flat across its one triangle.
        let tree = DopTree::with_options(&mesh, &OrientationSet::default(), 1);
        let leaf = tree.nodes.iter().position(Node::is_leaf).unwrap();
        let extents = tree.boxes[leaf].extents;
        assert!(extents[2] < 0.01 * extents[0], "leaf box {extents:?}");
    }
}

#[test]
fn box_certificates_hold_at_their_pose() {
    // Wherever the boxes of a node pair give a certificate, every corner of B's node lies at
    // least the gap beyond every corner of A's node along its direction.
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let a = DopTree::build(&torus(0.3, 12, 6));
    let b = DopTree::build(&random_soup(&mut rng, 120, 0.3));
    let mut certified = 0;
    for _ in 0..20 {
        let pose = random_pose(&mut rng, 1.0);
        let pair = TreePair::new(&a, &b, &pose, |_, _| ());
        for ia in 0..a.node_count() as u32 {
            for ib in 0..b.node_count() as u32 {
                let mut stats = QueryStats::default();
                let Some(Ending::Separated { gap, direction, .. }) =
                    pair.box_separation((ia, ib), BOX_TEST_MAX_TRIANGLES, &mut stats)
                else {
                    continue;
                };
                certified += 1;
                let direction = Vector3::from(direction).cast::<f64>();
                let apart = separation_along(
                    &corners_at(&a, ia, &Isometry3::identity()),
                    &corners_at(&b, ib, &pose),
                    &direction,
                );
                assert!(
                    apart >= gap - 1e-12,
                    "pair ({ia}, {ib}): corners {apart} apart, certificate {gap}"
                );
            }
        }
    }
    assert!(certified > 1000, "only {certified} certificates");
}

#[test]
fn front_certificates_not_due_still_separate() {
    // Along a tumble, every certificate of the remembered front that the next pose does not
    // put due (its tree bound, its node bound, or the renewal of one by the other) must
    // still separate its pair there: B's corners beyond A's along its direction.
    let a = DopTree::build(&torus(0.35, 20, 10));
    let b = DopTree::build(&torus(0.35, 20, 10));
    let (mut checked, mut renewed) = (0, 0);
    for d in [2.8, 2.5, 2.3] {
        for s in 0..240 {
            let pose = tumble_pose(d, s, 1200);
            let mut memory = PairMemory::take(&a, &b);
            let pair = LazyPair::<18>::new(&a, &b, &pose);
            if let (Carry::Advanced { .. }, _) = memory.carry_front(&pair) {
                let inverse = pose.inverse();
                for (frame, certificates) in memory.front.separated.iter().enumerate() {
                    let due = &memory.due[frame];
                    renewed += due.renewed.len();
                    for (i, &(ia, ib)) in certificates.pairs.iter().enumerate() {
                        if due.indices.contains(&(i as u32)) {
                            continue;
                        }
                        let direction =
                            Vector3::from_fn(|c, _| f64::from(certificates.directions[c][i]));
                        // In A's frame B lies beyond; in B's frame A does.
                        let (near, far) = if frame == 0 {
                            (
                                corners_at(&a, ia, &Isometry3::identity()),
                                corners_at(&b, ib, &pose),
                            )
                        } else {
                            (
                                corners_at(&b, ib, &Isometry3::identity()),
                                corners_at(&a, ia, &inverse),
                            )
                        };
                        let apart = separation_along(&near, &far, &direction);
                        assert!(
                            apart > 0.0,
                            "d {d} step {s}: pair ({ia}, {ib}) overlaps by {} along its certificate",
                            -apart
                        );
                        checked += 1;
                    }
                }
            }
            PairMemory::put_back(memory);
            a.intersects(&b, &pose, &mut QueryStats::default());
        }
    }
    assert!(checked > 5_000, "only {checked} certificates checked");
    assert!(renewed > 500, "only {renewed} certificates renewed");
}

/// The certificates that [`Certificates::flagged`] puts due or renews, by a brute force written
/// from the two bounds' definitions (the expected answer, in ascending order).
fn flagged_by_brute_force(
    certificates: &[((f64, f64), Vector3<f64>, NodeSphere)],
    centre: &Vector3<f64>,
    threshold: f64,
    nodes: &NodeBound,
) -> DueCertificates {
    let mut expected = DueCertificates::default();
    for (j, ((expiry, anchor), direction, sphere)) in certificates.iter().enumerate() {
        let tree = expiry + direction.dot(centre);
        if tree > threshold {
            continue;
        }
        let moved = nodes.rotation * sphere.centre() + nodes.translation;
        let node = anchor + direction.dot(&moved) - f64::from(sphere.radius) * nodes.turn;
        if node <= nodes.guard {
            expected.indices.push(j as u32);
        } else {
            // The tree bound's gap now is `tree - (threshold - guard)`, the node bound's `node`.
            let renewed = expiry + node - (tree - (threshold - nodes.guard));
            expected.renewed.push((j as u32, renewed));
        }
    }
    expected
}

/// Whether two scans flagged the same certificates, with renewed expiries equal to `1e-12`
/// (fused and unfused arithmetic, or another order of the terms, round differently).
fn assert_same_flags(found: &DueCertificates, expected: &DueCertificates, context: &str) {
    assert_eq!(found.indices, expected.indices, "{context}: due");
    assert_eq!(
        found.renewed.len(),
        expected.renewed.len(),
        "{context}: renewed"
    );
    for ((i, x), (j, y)) in found.renewed.iter().zip(&expected.renewed) {
        assert_eq!(i, j, "{context}: renewed");
        assert!((x - y).abs() < 1e-12, "{context}: expiry {x} against {y}");
    }
}

/// Whether this CPU has AVX2 and FMA, which [`Certificates::flagged`]'s vector scan needs.
fn vector_scan_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// What the vector scan flags, where the CPU can run it.
fn vector_scan_flags(
    certificates: &Certificates,
    centre: &Vector3<f64>,
    threshold: f64,
    nodes: &NodeBound,
) -> Option<DueCertificates> {
    if !vector_scan_available() {
        return None;
    }
    #[cfg(target_arch = "x86_64")]
    {
        let mut due = DueCertificates::default();
        // SAFETY: the CPU supports AVX2 and FMA, checked just above.
        unsafe { certificates.flagged_avx2(centre, threshold, nodes, &mut due) };
        Some(due)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (certificates, centre, threshold, nodes);
        None
    }
}

/// The expiry scans of a front's certificates against a brute force over random fronts of every
/// length up to 40 (whole groups of four and tails), with bounds spread around the thresholds so
/// that every outcome occurs: not flagged, due, renewed. The portable scan is always tested; the
/// AVX2 scan only where the CPU has AVX2 and FMA, against the portable one. On a CPU without
/// them the vector scan is not exercised, and the test says so on its error output.
#[test]
fn the_scalar_and_vector_scans_flag_what_the_bounds_say() {
    let vector_scan = vector_scan_available();
    if !vector_scan {
        eprintln!("no AVX2 and FMA on this CPU: the vector scan of the certificates is not tested");
    }
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let (mut due_seen, mut renewed_seen, mut vector_rounds) = (0, 0, 0);
    for round in 0..2000u32 {
        let mut certificates = Certificates::default();
        let mut drawn = Vec::new();
        for j in 0..round % 41 {
            let d = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)).normalize();
            let sphere = NodeSphere {
                centre: std::array::from_fn(|_| rng.random_range(-1.0..1.0)),
                radius: rng.random_range(0.0..0.5),
            };
            let bounds = (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            let direction = [d.x as f32, d.y as f32, d.z as f32];
            certificates.push(bounds, direction, &sphere, (j, j));
            drawn.push((bounds, Vector3::from(direction).cast::<f64>(), sphere));
        }
        let centre = Vector3::from_fn(|_, _| rng.random_range(-0.5..0.5));
        let rotation =
            UnitQuaternion::from_scaled_axis(Vector3::from_fn(|_, _| rng.random_range(-0.3..0.3)));
        let nodes = NodeBound {
            rotation: *rotation.to_rotation_matrix().matrix(),
            translation: Vector3::from_fn(|_, _| rng.random_range(-0.5..0.5)),
            turn: rng.random_range(0.0..0.3),
            guard: 1e-6,
        };
        let threshold = rng.random_range(0.0..0.2);
        // Compare only away from a tie at either bound's limit, where rounding decides.
        let near_tie = drawn.iter().any(|((expiry, anchor), direction, sphere)| {
            let tree = expiry + direction.dot(&centre);
            let moved = nodes.rotation * sphere.centre() + nodes.translation;
            let node = anchor + direction.dot(&moved) - f64::from(sphere.radius) * nodes.turn;
            (tree - threshold).abs() < 1e-12 || (node - nodes.guard).abs() < 1e-12
        });
        if near_tie {
            continue;
        }
        let expected = flagged_by_brute_force(&drawn, &centre, threshold, &nodes);
        let mut scalar = DueCertificates::default();
        certificates.flagged_scalar(&centre, threshold, &nodes, &mut scalar, 0);
        assert_same_flags(&scalar, &expected, &format!("round {round}, portable scan"));
        if let Some(vector) = vector_scan_flags(&certificates, &centre, threshold, &nodes) {
            assert_same_flags(&vector, &scalar, &format!("round {round}, vector scan"));
            vector_rounds += 1;
        }
        due_seen += expected.indices.len();
        renewed_seen += expected.renewed.len();
    }
    assert!(
        due_seen > 1000 && renewed_seen > 1000,
        "{due_seen} due, {renewed_seen} renewed"
    );
    assert_eq!(
        vector_rounds > 0,
        vector_scan,
        "{vector_rounds} rounds of the vector scan"
    );
}

#[test]
fn a_detached_query_leaves_the_front_to_the_coherent_ones() {
    let mesh = torus(0.35, 20, 10);
    let (a, b) = (DopTree::build(&mesh), DopTree::build(&mesh));
    // The front's pose and size, and whether a query at `next` would start from it.
    let front_at = |next: &Isometry3<f64>| {
        let mut memory = PairMemory::take(&a, &b);
        let carry = memory.carry_front(&LazyPair::<18>::new(&a, &b, next)).0;
        let state = (
            memory.front_pose,
            memory.front.len(),
            matches!(carry, Carry::Advanced { .. }),
        );
        PairMemory::put_back(memory);
        state
    };
    let check = |pose: &Isometry3<f64>| {
        let hit = a.intersects(&b, pose, &mut QueryStats::default());
        let expected = brute_force_hit(&mesh, &mesh, pose);
        assert_eq!(hit, expected, "at {pose:?}");
    };
    let d = 2.0;
    // A tumble near contact leaves a front.
    for s in 0..20 {
        check(&tumble_pose(d, s, 1200));
    }
    let next = tumble_pose(d, 20, 1200);
    let kept = front_at(&next);
    assert!(kept.0.is_some() && kept.1 > 0, "the tumble left no front");
    // Poses far from it and from each other (random ones, in contact or not) leave it as
    // it is, and the tumble can go on from it as before.
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..20 {
        check(&random_pose(&mut rng, 1.5));
    }
    assert_eq!(front_at(&next), kept, "a detached query changed the front");
    check(&next);
    // Queries that follow one another far from the front make a front of their own: B
    // linked through A like two links of a chain (the tubes 0.3 apart), sliding along.
    let linked = |s: usize| {
        Isometry3::from_parts(
            Translation3::new(1.0, 0.001 * s as f64, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2),
        )
    };
    for s in 0..3 {
        check(&linked(s));
    }
    let (pose, len, _) = front_at(&linked(3));
    assert_ne!(
        pose, kept.0,
        "coherent queries far from the front kept the old one"
    );
    assert!(len > 0, "the linked pair left no front");
}

#[test]
fn affine_realignment_encloses_every_moved_node() {
    // Support cones are searched for half of A's directions and mirrored for the other
    // half: each re-aligned node must still bound its corners moved into A's frame.
    const K: usize = 18;
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let a = DopTree::build(&torus(0.3, 12, 6));
    let b = DopTree::build(&random_soup(&mut rng, 200, 0.3));
    for _ in 0..50 {
        let axis =
            nalgebra::Unit::new_normalize(Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0)));
        let pose = Isometry3::from_parts(
            Translation3::from(Vector3::from_fn(|_, _| rng.random_range(-2.0..2.0))),
            UnitQuaternion::from_axis_angle(&axis, rng.random_range(-3.0..3.0)),
        );
        let rotation = *pose.rotation.to_rotation_matrix().matrix();
        let translation = pose.translation.vector;
        let mut hints = [u8::MAX; MAX_K];
        let realigner = AffineRealign::<K>::new(&a, &b, &rotation, &translation, &mut hints);
        let mut realigned = vec![[0f32; K]; b.node_count()];
        for (node, out) in realigned.iter_mut().enumerate() {
            realigner.realign::<false>(&b, node, out);
        }
        for (node, corner) in node_corners(&b) {
            let moved = pose * corner;
            for (i, &offset) in realigned[node].iter().enumerate() {
                // Stored opposite: slot i bounds B along -n_i.
                let support = -a.set.normal(i).dot(&moved.coords);
                assert!(
                    support <= f64::from(offset) + 1e-9,
                    "node {node} slot {i}: {support} beyond {offset}"
                );
            }
        }
    }
}
