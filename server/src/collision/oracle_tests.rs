//! Every collider against independent oracles: brute force over all triangle pairs, and parry.
//!
//! Near-touching poses, where rounding (parry works in `f32`) may decide, are recognised by
//! re-running brute force at slightly moved poses; only those may disagree with parry.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3, Vector4};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::brute_force::posed_triangles;
use super::triangle::triangles_intersect;
use super::*;
use crate::geometry::{TriMesh, shapes};
use vas_testkit::tumble::tumble_pose;

/// A soup of `n` random triangles of about `size` inside the box [-1, 1]^3.
pub(crate) fn random_soup(rng: &mut ChaCha8Rng, n: usize, size: f64) -> TriMesh {
    let mut vertices = Vec::new();
    for _ in 0..n {
        let centre = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        for _ in 0..3 {
            let offset = Vector3::new(
                rng.random_range(-size..size),
                rng.random_range(-size..size),
                rng.random_range(-size..size),
            );
            vertices.push(Point3::from(centre + offset));
        }
    }
    let triangles = (0..n as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    TriMesh::new(vertices, triangles).unwrap().0
}

/// A closed torus (major radius 1, minor `r`) of `2 nu nv` triangles.
pub(crate) fn torus(r: f64, nu: u32, nv: u32) -> TriMesh {
    let mut vertices = Vec::new();
    for i in 0..nu {
        let u = std::f64::consts::TAU * i as f64 / nu as f64;
        for j in 0..nv {
            let v = std::f64::consts::TAU * j as f64 / nv as f64;
            let ring = 1.0 + r * v.cos();
            vertices.push(Point3::new(ring * u.cos(), ring * u.sin(), r * v.sin()));
        }
    }
    let index = |i: u32, j: u32| (i % nu) * nv + (j % nv);
    let mut triangles = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            );
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    TriMesh::new(vertices, triangles).unwrap().0
}

/// A uniformly random rotation and a translation uniform in [-reach, reach]^3.
pub(crate) fn random_pose(rng: &mut ChaCha8Rng, reach: f64) -> Isometry3<f64> {
    let q = loop {
        let v = Vector4::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let n = v.norm();
        if n > 0.1 && n <= 1.0 {
            break UnitQuaternion::from_quaternion(nalgebra::Quaternion::from(v / n));
        }
    };
    let t = Vector3::new(
        rng.random_range(-reach..reach),
        rng.random_range(-reach..reach),
        rng.random_range(-reach..reach),
    );
    Isometry3::from_parts(Translation3::from(t), q)
}

/// Whether any triangle pair intersects, by testing every pair whose boxes overlap: exhaustive
/// like [`brute_force_pairs`] and sharing nothing with the trees but the triangle test and the
/// placing of B ([`posed_triangles`]), fast enough for meshes of thousands of triangles (B's boxes are sorted along x, so each triangle
/// of A meets only the boxes of its own x-range).
pub(crate) fn brute_force_hit(a: &TriMesh, b: &TriMesh, b_to_a: &Isometry3<f64>) -> bool {
    let bounds = |t: &[Point3<f64>; 3]| {
        let lo = t[0].coords.inf(&t[1].coords).inf(&t[2].coords);
        let hi = t[0].coords.sup(&t[1].coords).sup(&t[2].coords);
        (lo, hi)
    };
    let mut moved: Vec<_> = posed_triangles(b, b_to_a)
        .into_iter()
        .map(|t| (bounds(&t), t))
        .collect();
    moved.sort_unstable_by(|x, y| x.0.0.x.total_cmp(&y.0.0.x));
    (0..a.triangles().len()).any(|i| {
        let ta = a.triangle(i);
        let (lo, hi) = bounds(&ta);
        let end = moved.partition_point(|((b_lo, _), _)| b_lo.x <= hi.x);
        moved[..end].iter().any(|((b_lo, b_hi), tb)| {
            (0..3).all(|axis| b_hi[axis] >= lo[axis] && b_lo[axis] <= hi[axis])
                && triangles_intersect(&ta, tb)
        })
    })
}

/// True when moving B by `epsilon` in some direction changes the brute-force answer.
fn near_touching(a: &TriMesh, b: &TriMesh, pose: &Isometry3<f64>, epsilon: f64) -> bool {
    let answer = !brute_force_pairs(a, b, pose).is_empty();
    [Vector3::x(), Vector3::y(), Vector3::z()]
        .iter()
        .flat_map(|axis| [axis * epsilon, -axis * epsilon])
        .any(|shift| {
            let moved = Translation3::from(shift) * pose;
            brute_force_pairs(a, b, &moved).is_empty() == answer
        })
}

fn sorted(mut pairs: Vec<[u32; 2]>) -> Vec<[u32; 2]> {
    pairs.sort_unstable();
    pairs
}

/// Checks every collider on `poses` random poses of `b` against `a`: first hit and all pairs
/// against brute force, first hit against parry (up to near-touching poses). Returns the number
/// of colliding poses.
fn check_all(a: &TriMesh, b: &TriMesh, poses: usize, reach: f64, seed: u64) -> usize {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let sets: Vec<OrientationSet> = orientation::SUPPORTED_K
        .iter()
        .map(|&k| OrientationSet::new(k).unwrap())
        .collect();
    let dops: Vec<(DopTree, DopTree)> = sets
        .iter()
        .map(|s| {
            (
                DopTree::with_options(a, s, 1 + s.k() % 4),
                DopTree::with_options(b, s, 1 + s.k() % 3),
            )
        })
        .collect();
    let parry = (ParryMesh::build(a), ParryMesh::build(b));
    let mut colliding = 0;
    let mut parry_disagreements = 0;
    for _ in 0..poses {
        let pose = random_pose(&mut rng, reach);
        let expected = sorted(brute_force_pairs(a, b, &pose));
        let hit = !expected.is_empty();
        colliding += hit as usize;
        let mut stats = QueryStats::default();
        for (k, (da, db)) in orientation::SUPPORTED_K.iter().zip(&dops) {
            assert_eq!(da.intersects(db, &pose, &mut stats), hit, "doptree k {k}");
            let mut pairs = Vec::new();
            da.intersecting_pairs(db, &pose, &mut pairs, &mut stats);
            assert_eq!(sorted(pairs), expected, "doptree k {k} pairs");
        }
        let (da, db) = &dops[3];
        assert_eq!(da.intersects_parallel(db, &pose, &mut stats), hit);
        let mut pairs = Vec::new();
        da.intersecting_pairs_parallel(db, &pose, &mut pairs, &mut stats);
        assert_eq!(sorted(pairs), expected, "parallel pairs");
        assert_eq!(
            brute_force_hit(a, b, &pose),
            hit,
            "the filtered brute force"
        );
        if parry.0.intersects(&parry.1, &pose, &mut stats) != hit {
            assert!(
                near_touching(a, b, &pose, 1e-4),
                "parry disagrees at a pose that is not near touching: {pose}"
            );
            parry_disagreements += 1;
        }
    }
    assert!(
        parry_disagreements * 100 <= poses,
        "{parry_disagreements} near-touching disagreements with parry in {poses} poses"
    );
    colliding
}

#[test]
fn random_soups_agree_with_brute_force_and_parry() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for round in 0..4 {
        let a = random_soup(&mut rng, 40, 0.3);
        let b = random_soup(&mut rng, 25 + 10 * round, 0.4);
        let colliding = check_all(&a, &b, 500, 2.0, round as u64);
        assert!(
            colliding > 100 && colliding < 450,
            "{colliding} colliding poses"
        );
    }
}

#[test]
fn tori_agree_with_brute_force_and_parry() {
    let a = torus(0.35, 24, 12);
    let b = torus(0.2, 16, 8);
    let colliding = check_all(&a, &b, 600, 2.0, 9);
    assert!(
        colliding > 100 && colliding < 550,
        "{colliding} colliding poses"
    );
}

#[test]
fn identical_touching_copies_collide() {
    // Two copies at the identity share every triangle: the tree must report contact.
    let mesh = torus(0.35, 12, 6);
    let mut stats = QueryStats::default();
    let id = Isometry3::identity();
    let dop = DopTree::build(&mesh);
    assert!(dop.intersects(&dop, &id, &mut stats));
    assert!(stats.tri_tests > 0 && stats.bv_tests > 0 && stats.realignments > 0);
}

#[test]
fn procedural_open_and_closed_shapes_agree_with_brute_force_and_parry() {
    use crate::geometry::shapes::{ShapeKind, build};
    let pairs = [
        (ShapeKind::Hyperboloid, 300, ShapeKind::SheetWithHole, 200),
        (ShapeKind::Sphere, 250, ShapeKind::Pipe, 300),
        (ShapeKind::BoxWithHole, 300, ShapeKind::Cylinder, 120),
    ];
    for (seed, (kind_a, n_a, kind_b, n_b)) in pairs.into_iter().enumerate() {
        let a = build(kind_a, n_a).normalized_to_unit_box();
        let b = build(kind_b, n_b).normalized_to_unit_box();
        let colliding = check_all(&a, &b, 250, 2.0, 20 + seed as u64);
        assert!(
            colliding > 25 && colliding < 240,
            "{kind_a} vs {kind_b}: {colliding} colliding poses"
        );
    }
}

#[test]
fn real_mesh_agrees_with_brute_force_and_parry() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../configs/meshes/low_poly_bunny.obj");
    let bunny = crate::geometry::load_mesh(&path)
        .unwrap()
        .normalized_to_unit_box();
    let probe = torus(0.3, 12, 8).normalized_to_unit_box();
    let colliding = check_all(&bunny, &probe, 250, 1.8, 33);
    assert!(
        colliding > 25 && colliding < 240,
        "{colliding} colliding poses"
    );
}

#[test]
fn large_triangles_against_a_fine_mesh_agree_with_brute_force_and_parry() {
    // A handful of triangles larger than the whole torus: each is a leaf of B that outgrows
    // every inner node of A, where the traversal tries a leaf's plane against A's node spheres.
    let mut rng = ChaCha8Rng::seed_from_u64(41);
    let a = torus(0.35, 40, 20);
    let b = random_soup(&mut rng, 6, 1.6);
    let colliding = check_all(&a, &b, 300, 1.5, 42);
    assert!(
        colliding > 30 && colliding < 290,
        "{colliding} colliding poses"
    );
}

#[test]
fn a_large_slanted_triangle_clear_of_a_fine_mesh_is_proved_apart_near_the_roots() {
    // One triangle much larger than the torus, in a slanted plane just clear of it: its DOP
    // overlaps nearly every node of the torus's tree, but its plane clears their spheres.
    let a = torus(0.35, 80, 40);
    let normal = Vector3::new(0.3, -0.2, 1.0).normalize();
    let clearance = a
        .vertices()
        .iter()
        .map(|v| normal.dot(&v.coords))
        .fold(f64::MIN, f64::max)
        + 0.02;
    let across = normal.cross(&Vector3::x()).normalize();
    let along = normal.cross(&across);
    let centre = normal * clearance;
    let corners = [0.0, 2.1, 4.2].map(|angle: f64| {
        Point3::from(centre + (across * angle.cos() + along * angle.sin()) * 6.0)
    });
    let b = TriMesh::new(corners.to_vec(), vec![[0, 1, 2]]).unwrap().0;
    let pose = Isometry3::identity();
    assert!(
        brute_force_pairs(&a, &b, &pose).is_empty(),
        "the triangle clears the torus"
    );
    let (tree_a, tree_b) = (DopTree::build(&a), DopTree::build(&b));
    for (first, second, b_to_a) in [(&tree_a, &tree_b, pose), (&tree_b, &tree_a, pose.inverse())] {
        let mut stats = QueryStats::default();
        assert!(!first.intersects(second, &b_to_a, &mut stats));
        assert!(
            stats.nodes_visited * 50 < tree_a.node_count() as u64,
            "{} of the torus tree's {} nodes visited",
            stats.nodes_visited,
            tree_a.node_count()
        );
    }
}

/// B's pose after a small random step from `pose`: a turn of up to `turn` radians about a random
/// axis and a shift of up to `shift` per coordinate, pulled towards `centre` so the walk keeps
/// crossing in and out of contact.
fn small_step(
    rng: &mut ChaCha8Rng,
    pose: &Isometry3<f64>,
    turn: f64,
    shift: f64,
    centre: &Vector3<f64>,
) -> Isometry3<f64> {
    let axis = nalgebra::Unit::new_normalize(Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(0.1..1.0),
    ));
    let rotation = UnitQuaternion::from_axis_angle(&axis, rng.random_range(-turn..turn));
    let jitter = Vector3::from_fn(|_, _| rng.random_range(-shift..shift));
    let pull = (centre - pose.translation.vector) * 0.2;
    Isometry3::from_parts(
        Translation3::from(pose.translation.vector + jitter + pull),
        rotation * pose.rotation,
    )
}

#[test]
fn coherent_pose_sequences_agree_with_brute_force() {
    // First-hit queries carry a witness and a front of separated node pairs from one query to
    // the next; walks of small steps, back-and-forth jumps (as bisection makes) and a second
    // pair of trees queried in between exercise every way that memory is used or dropped.
    let a = torus(0.35, 16, 8);
    let b = torus(0.2, 12, 6);
    let mut rng = ChaCha8Rng::seed_from_u64(77);
    // B's centre is pulled along x in and out of A's reach (the tori touch near x = 2.55).
    let centre_at = |step: usize| Vector3::new(2.45 + 0.4 * (step as f64 / 25.0).sin(), 0.1, 0.0);
    for (k, leaf_size) in [(18, 1), (24, 2), (6, 1), (14, 3), (26, 1)] {
        let [da, db, other] = dop_trees([&a, &b, &b], k, leaf_size);
        let mut pose =
            Isometry3::from_parts(Translation3::from(centre_at(0)), UnitQuaternion::identity());
        let (mut hits, mut misses, mut switches, mut last) = (0, 0, 0, None);
        for step in 0..400 {
            let centre = centre_at(step);
            pose = small_step(&mut rng, &pose, 0.03, 0.01, &centre);
            let mut queried = vec![pose];
            if step % 7 == 0 {
                // A jump away and back, as bisection's trial poses go.
                queried.push(small_step(&mut rng, &pose, 0.3, 0.2, &centre));
                queried.push(pose);
            }
            for q in &queried {
                let expected = !brute_force_pairs(&a, &b, q).is_empty();
                let mut stats = QueryStats::default();
                assert_eq!(
                    da.intersects(&db, q, &mut stats),
                    expected,
                    "k {k} leaf {leaf_size} step {step}"
                );
                if step % 5 == 0 {
                    assert_eq!(other.intersects(&da, &q.inverse(), &mut stats), expected);
                }
                hits += expected as usize;
                misses += !expected as usize;
                switches += (last.is_some_and(|l| l != expected)) as usize;
                last = Some(expected);
            }
        }
        assert!(
            hits > 50 && misses > 50 && switches > 5,
            "k {k}: {hits} hits, {misses} misses, {switches} switches"
        );
    }
}

#[test]
fn sliding_translations_agree_with_brute_force() {
    // A peg slid down a hole with a few percent of radial clearance (between the polygons)
    // while pushed sideways in and out of the wall: the front's certificates across the gap
    // survive motion along the wall and must expire on motion towards it; trial poses deep in
    // the wall and back (as bisection makes) and a slight turn now and then exercise the rest.
    let (peg, block) = small_peg_and_block();
    let poses = peg_sliding_down_a_hole(240, 5);
    for (k, leaf_size) in [(26, 1), (18, 2), (14, 1)] {
        let [dp, db] = dop_trees([&peg, &block], k, leaf_size);
        let (mut hits, mut misses) = (0, 0);
        for (step, q) in &poses {
            // B (the peg) in A's (the block's) frame, and the other way round.
            let expected = !brute_force_pairs(&block, &peg, q).is_empty();
            assert_both_ways(
                <DopTree as MeshCollider>::intersects,
                (&db, &dp),
                q,
                expected,
                &mut QueryStats::default(),
                &format!("k {k} leaf {leaf_size} step {step}"),
            );
            hits += expected as usize;
            misses += !expected as usize;
        }
        assert!(
            hits > 40 && misses > 40,
            "k {k}: {hits} hits, {misses} misses"
        );
    }
}

#[test]
fn coherent_all_pairs_queries_agree_with_brute_force() {
    // All-pairs queries carry the front as first-hit queries do, and share it with them: along
    // a peg sliding down its hole (in and out of the wall, with trial poses deep in it and
    // back), each must give exactly brute force's triangle pairs, both ways, with a first-hit
    // query of the same trees every third step. Carrying the front must also save work: the
    // same queries from the roots (the memoryless split query) test more bounding volumes.
    let (peg, block) = small_peg_and_block();
    let poses = peg_sliding_down_a_hole(240, 9);
    for (k, leaf_size) in [(18, 1), (24, 2), (6, 1)] {
        let [dp, db] = dop_trees([&peg, &block], k, leaf_size);
        let (mut coherent, mut from_roots) = (QueryStats::default(), QueryStats::default());
        let (mut hits, mut misses) = (0, 0);
        for (step, q) in &poses {
            let context = format!("k {k} leaf {leaf_size} step {step}");
            let expected = brute_force_pairs(&block, &peg, q);
            let mut pairs = Vec::new();
            db.intersecting_pairs(&dp, q, &mut pairs, &mut coherent);
            assert_eq!(sorted(pairs), expected, "{context}");
            let mut reversed = Vec::new();
            dp.intersecting_pairs(&db, &q.inverse(), &mut reversed, &mut QueryStats::default());
            let reversed = reversed.into_iter().map(|[p, b]| [b, p]).collect();
            assert_eq!(sorted(reversed), expected, "{context}, reversed");
            if step % 3 == 0 {
                let hit = db.intersects(&dp, q, &mut QueryStats::default());
                assert_eq!(hit, !expected.is_empty(), "{context}, first hit");
            }
            db.intersecting_pairs_parallel(&dp, q, &mut Vec::new(), &mut from_roots);
            hits += !expected.is_empty() as usize;
            misses += expected.is_empty() as usize;
        }
        assert!(
            hits > 40 && misses > 40,
            "k {k}: {hits} hits, {misses} misses"
        );
        assert!(
            coherent.bv_tests < from_roots.bv_tests,
            "k {k}: {} bounding-volume tests carried, {} from the roots",
            coherent.bv_tests,
            from_roots.bv_tests
        );
    }
}

#[test]
fn tumbling_queries_agree_with_brute_force() {
    // Two tori turning about two axes at every step (the tumbling benchmark's motion, in larger
    // steps), from apart to near-touching: a certificate whose tree-wide bound expires at every
    // turn lives on while its node's own sphere keeps the gap, and the roots' separation proof
    // while the gap outlasts the turn; both must expire in time. First-hit and all-pairs queries
    // must give brute force's answers, and carrying the memory must at least halve the work of
    // the same all-pairs queries from the roots.
    let a = torus(0.35, 20, 10);
    let b = torus(0.35, 20, 10);
    // A fifth of a revolution at each distance, in steps of 0.3 degrees about each axis.
    let (steps, taken) = (1200, 240);
    for (k, leaf_size) in [(18, 1), (24, 1), (14, 2)] {
        let [da, db] = dop_trees([&a, &b], k, leaf_size);
        let (mut coherent, mut from_roots) = (QueryStats::default(), QueryStats::default());
        let (mut hits, mut misses) = (0, 0);
        for d in [2.8, 2.5, 2.3, 2.1] {
            for s in 0..taken {
                let pose = tumble_pose(d, s, steps);
                let context = format!("k {k} leaf {leaf_size} d {d} step {s}");
                let expected = brute_force_pairs(&a, &b, &pose);
                let hit = da.intersects(&db, &pose, &mut QueryStats::default());
                assert_eq!(hit, !expected.is_empty(), "{context}, first hit");
                if s % 2 == 0 {
                    let mut pairs = Vec::new();
                    da.intersecting_pairs(&db, &pose, &mut pairs, &mut coherent);
                    assert_eq!(sorted(pairs), expected, "{context}, all pairs");
                    let mut unused = Vec::new();
                    da.intersecting_pairs_parallel(&db, &pose, &mut unused, &mut from_roots);
                }
                hits += hit as usize;
                misses += !hit as usize;
            }
        }
        assert!(
            hits > 200 && misses > 200,
            "k {k}: {hits} hits, {misses} misses"
        );
        assert!(
            2 * coherent.bv_tests < from_roots.bv_tests,
            "k {k}: {} bounding-volume tests carried, {} from the roots",
            coherent.bv_tests,
            from_roots.bv_tests
        );
    }
}

#[test]
fn a_spinning_rod_agrees_with_brute_force() {
    // A rod whose centre stays put beside a torus, turning a degree a step: upright, the roots
    // are apart by a wide gap and the proof of it is carried from step to step; as the rod
    // swings down, its tip reaches into the ring although its centre never moved, so the proof
    // must expire with the turn alone.
    let torus = torus(0.35, 16, 8);
    let rod = shapes::cylinder(0.1, 4.0, 200);
    for (k, leaf_size) in [(18, 1), (24, 2), (6, 1)] {
        let [dt, dr] = dop_trees([&torus, &rod], k, leaf_size);
        let (mut hits, mut misses) = (0, 0);
        for degree in 0..360 {
            let pose = Isometry3::from_parts(
                Translation3::new(2.9, 0.0, 0.0),
                UnitQuaternion::from_axis_angle(&Vector3::y_axis(), (degree as f64).to_radians()),
            );
            let expected = brute_force_pairs(&torus, &rod, &pose);
            let context = format!("k {k} leaf {leaf_size} at {degree} degrees");
            let hit = dt.intersects(&dr, &pose, &mut QueryStats::default());
            assert_eq!(hit, !expected.is_empty(), "{context}, first hit");
            if degree % 3 == 0 {
                let mut pairs = Vec::new();
                dt.intersecting_pairs(&dr, &pose, &mut pairs, &mut QueryStats::default());
                assert_eq!(sorted(pairs), expected, "{context}, all pairs");
            }
            hits += hit as usize;
            misses += !hit as usize;
        }
        assert!(
            hits > 20 && misses > 200,
            "k {k}: {hits} hits, {misses} misses"
        );
    }
}

/// Asserts that `query` gives `expected` for the peg posed at `peg_in_block` in the block's
/// frame, and for the block in the peg's frame.
fn assert_both_ways(
    query: impl Fn(&DopTree, &DopTree, &Isometry3<f64>, &mut QueryStats) -> bool,
    (block, peg): (&DopTree, &DopTree),
    peg_in_block: &Isometry3<f64>,
    expected: bool,
    stats: &mut QueryStats,
    context: &str,
) {
    assert_eq!(
        query(block, peg, peg_in_block, stats),
        expected,
        "{context}"
    );
    let block_in_peg = peg_in_block.inverse();
    assert_eq!(
        query(peg, block, &block_in_peg, stats),
        expected,
        "{context}, reversed"
    );
}

/// A peg of 300 triangles and a block of 400 with a hole a few percent wider than it, for the
/// poses of [`peg_sliding_down_a_hole`].
fn small_peg_and_block() -> (TriMesh, TriMesh) {
    (
        shapes::cylinder(0.44, 1.5, 300),
        shapes::box_with_hole(2.0, 1.0, 0.5, 400),
    )
}

/// DOP-trees over `meshes` with `k` orientations and leaves of `leaf_size` triangles.
fn dop_trees<const N: usize>(meshes: [&TriMesh; N], k: usize, leaf_size: usize) -> [DopTree; N] {
    let set = OrientationSet::new(k).unwrap();
    meshes.map(|mesh| DopTree::with_options(mesh, &set, leaf_size))
}

/// The poses of `steps` steps of a peg (B) sliding down a hole in a block (A), with the step each
/// belongs to: pushed sideways in and out of the wall while the push turns around the axis,
/// with a trial pose 0.2 into the wall and back every 7 steps and a slight turn every 10.
fn peg_sliding_down_a_hole(steps: usize, seed: u64) -> Vec<(usize, Isometry3<f64>)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut rotation = UnitQuaternion::identity();
    let mut poses = Vec::new();
    for step in 0..steps {
        // Sideways target: up to 0.08 off the axis, turning around it.
        let angle = step as f64 * 0.3;
        let off = 0.08 * (0.5 + 0.5 * (step as f64 / 9.0).sin());
        let depth = 0.6 - 0.004 * step as f64 + rng.random_range(-0.003..0.003);
        let centre = Vector3::new(off * angle.cos(), off * angle.sin(), depth);
        if step % 10 == 0 {
            let axis = Vector3::new(rng.random_range(-1.0..1.0), 1.0, 0.0);
            let turn = UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(axis), 0.002);
            rotation = turn * rotation;
        }
        let pose = Isometry3::from_parts(Translation3::from(centre), rotation);
        poses.push((step, pose));
        if step % 7 == 0 {
            let into_wall = Vector3::new(angle.cos(), angle.sin(), 0.0) * 0.2;
            poses.push((step, Translation3::from(into_wall) * pose));
            poses.push((step, pose));
        }
    }
    poses
}

#[test]
fn split_sliding_queries_agree_with_brute_force() {
    // A peg rocked slowly from one side of its hole to the other while it goes down: each step
    // is small enough for the query to carry the front, and the contact switches sides, far
    // from the last witness, so only a complete front finds it. The meshes are large enough for
    // hundreds of the front's pairs to be due, so that the queries split their walks across
    // two threads (from the front and from the roots); leaves of one triangle give the front
    // the most pairs. The filtered brute force, which shares nothing with them but the triangle
    // test, is the oracle.
    let peg = shapes::cylinder(0.44, 1.5, 6_000);
    let block = shapes::box_with_hole(2.0, 1.0, 0.5, 3_000);
    let set = OrientationSet::default();
    let (dp, db) = (
        DopTree::with_options(&peg, &set, 1),
        DopTree::with_options(&block, &set, 1),
    );
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let mut stats = QueryStats::default();
    let (mut hits, mut misses) = (0, 0);
    pool.install(|| {
        let mut rotation = UnitQuaternion::identity();
        for step in 0..300 {
            if step % 10 == 0 {
                let axis = nalgebra::Unit::new_normalize(Vector3::new(1.0, step as f64, 0.0));
                rotation = UnitQuaternion::from_axis_angle(&axis, 0.002) * rotation;
            }
            let off = 0.07 * (step as f64 * 0.15).sin();
            let centre = Vector3::new(off, 0.3 * off, 0.6 - 0.002 * step as f64);
            let q = Isometry3::from_parts(Translation3::from(centre), rotation);
            let expected = brute_force_hit(&block, &peg, &q);
            assert_both_ways(
                DopTree::intersects_parallel,
                (&db, &dp),
                &q,
                expected,
                &mut stats,
                &format!("step {step}"),
            );
            hits += expected as usize;
            misses += !expected as usize;
        }
    });
    assert!(hits > 20 && misses > 20, "{hits} hits, {misses} misses");
    // Which queries split depends on the threads' timing: a hit found by one chunk stops the
    // others and drops the front, so the next query starts from the roots. 14 to 19 of the 300
    // split on two cores; the floor only guards that the split path is exercised.
    assert!(
        stats.split_walks >= 5,
        "only {} split walks",
        stats.split_walks
    );
}
