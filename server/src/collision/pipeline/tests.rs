//! The pipeline against brute force: every pair of the scene tested exactly, each frame.

use super::back_end::PAIRS_PER_TASK;
use super::interest::GroupId;
use super::*;
use crate::collision::{DopTree, ParryMesh};
use crate::geometry::{ConvexHull, Point, TriMesh};
use nalgebra::{Translation3, UnitQuaternion, Vector3};
use parry3d::shape::Ball;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;
use std::sync::Arc;

/// An ellipsoid with half-axes `axes`, bent into a banana when `bend` is non-zero (so that its
/// hull is looser than the mesh).
fn shape(axes: Vector3<f64>, bend: f64) -> TriMesh {
    let (points, triangles) = Ball::new(1.0).to_trimesh(12, 8);
    let points = points
        .iter()
        .map(|p| {
            let p: Point = nalgebra::convert(*p);
            let p = Point::from(p.coords.component_mul(&axes));
            Point::new(p.x + bend * p.y * p.y, p.y, p.z)
        })
        .collect();
    TriMesh::new(points, triangles).unwrap().0
}

fn model<C: ExactTest>(mesh: &TriMesh) -> Arc<CollisionModel<C>> {
    Arc::new(CollisionModel::new(C::build(mesh), ConvexHull::of(mesh)))
}

/// The test's own copy of each object, to check the pipeline against.
struct Body<C> {
    mesh: TriMesh,
    model: Arc<CollisionModel<C>>,
    pose: Isometry3<f64>,
    velocity: Vector3<f64>,
    spin: Vector3<f64>,
    group: u16,
    is_static: bool,
}

struct Scene<C> {
    rng: ChaCha8Rng,
    bodies: BTreeMap<ObjectId, Body<C>>,
    shapes: Vec<(TriMesh, Arc<CollisionModel<C>>)>,
    size: f64,
    /// The rules the oracle applies: group 1 never meets group 2, and one object pair is off.
    disallowed_object_pair: Option<(ObjectId, ObjectId)>,
}

impl<C: ExactTest> Scene<C> {
    fn new(seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let shapes = (0..6)
            .map(|i| {
                let axes = Vector3::new(
                    rng.random_range(0.2..0.8),
                    rng.random_range(0.2..0.8),
                    rng.random_range(0.2..0.8),
                );
                let mesh = shape(axes, if i % 2 == 0 { 0.0 } else { 1.5 });
                let model = model(&mesh);
                (mesh, model)
            })
            .collect();
        Scene {
            rng,
            bodies: BTreeMap::new(),
            shapes,
            size: 5.0,
            disallowed_object_pair: None,
        }
    }

    fn random_pose(&mut self) -> Isometry3<f64> {
        let size = self.size;
        Isometry3::from_parts(
            Translation3::new(
                self.rng.random_range(0.0..size),
                self.rng.random_range(0.0..size),
                self.rng.random_range(0.0..size),
            ),
            UnitQuaternion::from_euler_angles(
                self.rng.random_range(-3.0..3.0),
                self.rng.random_range(-3.0..3.0),
                self.rng.random_range(-3.0..3.0),
            ),
        )
    }

    fn add(&mut self, pipeline: &mut CollisionPipeline<C>) -> ObjectId {
        let (mesh, model) = self.shapes[self.rng.random_range(0..self.shapes.len())].clone();
        let pose = self.random_pose();
        let is_static = self.rng.random_bool(0.2);
        let group = self.rng.random_range(0..3);
        let id = pipeline
            .add(ObjectDesc {
                model: Arc::clone(&model),
                pose,
                group: GroupId(group),
                is_static,
            })
            .unwrap();
        let velocity = Vector3::new(
            self.rng.random_range(-0.05..0.05),
            self.rng.random_range(-0.05..0.05),
            self.rng.random_range(-0.05..0.05),
        );
        let spin = velocity * 2.0;
        self.bodies.insert(
            id,
            Body {
                mesh,
                model,
                pose,
                velocity,
                spin,
                group,
                is_static,
            },
        );
        id
    }

    /// Moves about `share` of the dynamic bodies coherently (bouncing off the walls), and now and
    /// then makes one jump.
    fn step(&mut self, share: f64) -> Vec<(ObjectId, Isometry3<f64>)> {
        let mut moves = Vec::new();
        let size = self.size;
        let ids: Vec<ObjectId> = self.bodies.keys().copied().collect();
        for id in ids {
            if self.bodies[&id].is_static || !self.rng.random_bool(share) {
                continue;
            }
            let jump = self.rng.random_bool(0.01);
            let random = self.random_pose();
            let body = self.bodies.get_mut(&id).unwrap();
            if jump {
                body.pose = random;
            } else {
                let mut position = body.pose.translation.vector + body.velocity;
                for k in 0..3 {
                    if !(0.0..size).contains(&position[k]) {
                        body.velocity[k] = -body.velocity[k];
                        position[k] = position[k].clamp(0.0, size);
                    }
                }
                body.pose = Isometry3::from_parts(
                    Translation3::from(position),
                    UnitQuaternion::from_scaled_axis(body.spin) * body.pose.rotation,
                );
            }
            moves.push((id, body.pose));
        }
        moves
    }

    fn is_interesting(&self, (a, b): (ObjectId, ObjectId)) -> bool {
        let (ba, bb) = (&self.bodies[&a], &self.bodies[&b]);
        let groups = (ba.group.min(bb.group), ba.group.max(bb.group));
        !(ba.is_static && bb.is_static)
            && groups != (1, 2)
            && self.disallowed_object_pair != Some((a, b))
    }

    /// Every interesting pair whose meshes intersect, by exact tests on all pairs whose exact
    /// world boxes (from all transformed vertices) overlap; with triangle pairs if asked.
    fn brute_force(&self, triangles: bool) -> Vec<CollidingPair> {
        let boxes: BTreeMap<ObjectId, Aabb> = self
            .bodies
            .iter()
            .map(|(&id, body)| {
                let points: Vec<_> = body.mesh.vertices().iter().map(|v| body.pose * v).collect();
                let (min, max) = points
                    .iter()
                    .fold((points[0], points[0]), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
                (id, Aabb { min, max })
            })
            .collect();
        let mut colliding = Vec::new();
        for (&a, body_a) in &self.bodies {
            for (&b, body_b) in self.bodies.range(a..).skip(1) {
                if !self.is_interesting((a, b)) || !boxes[&a].overlaps(&boxes[&b]) {
                    continue;
                }
                let b_to_a = body_a.pose.inv_mul(&body_b.pose);
                let (ea, eb) = (body_a.model.exact(), body_b.model.exact());
                let mut found = Vec::new();
                let hit = if triangles {
                    ea.intersecting_pairs(eb, &b_to_a, &mut found, &mut QueryStats::default());
                    !found.is_empty()
                } else {
                    ea.intersects(eb, &b_to_a, &mut QueryStats::default())
                };
                if hit {
                    found.sort_unstable();
                    colliding.push(CollidingPair {
                        a,
                        b,
                        triangles: found,
                    });
                }
            }
        }
        colliding
    }
}

/// A rayon pool of `threads` threads.
fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

fn interest_rules(disallowed: (ObjectId, ObjectId)) -> InterestMatrix {
    let mut interest = InterestMatrix::new();
    interest.disallow_groups(GroupId(2), GroupId(1));
    interest.disallow_objects(disallowed.1, disallowed.0);
    interest
}

fn sorted_triangles(mut report: FrameReport) -> Vec<CollidingPair> {
    for pair in &mut report.colliding {
        pair.triangles.sort_unstable();
    }
    report.colliding
}

#[test]
fn pairs_equal_brute_force_over_thousands_of_random_frames_with_parry() {
    pairs_equal_brute_force::<ParryMesh>(21);
}

#[test]
fn pairs_equal_brute_force_over_thousands_of_random_frames_with_dop_trees() {
    let (split, exact) = pairs_equal_brute_force::<DopTree>(24);
    assert!(
        split * 10 > exact && split * 10 < exact * 9,
        "{split} of {exact} exact tests on several threads were split"
    );
}

/// Runs a random scene of 30 objects for 2,500 frames, alternately on one thread and on two or
/// three (so that a frame's pairs are shared by their owner and one or two helpers), and compares
/// every frame's colliding pairs (and every tenth frame's triangle pairs) with brute force, using
/// the same exact test `C`. The split threshold is low enough for this scene's small meshes that
/// frames on several threads run both split and unsplit first-hit tests; returns how many were
/// split and how many ran in all.
fn pairs_equal_brute_force<C: ExactTest + 'static>(seed: u64) -> (u64, u64) {
    let mut scene = Scene::<C>::new(seed);
    let mut pipeline = CollisionPipeline::new(PipelineConfig {
        split_min_bv_tests: 40,
        ..PipelineConfig::default()
    });
    for _ in 0..30 {
        scene.add(&mut pipeline);
    }
    let ids: Vec<ObjectId> = scene.bodies.keys().copied().collect();
    scene.disallowed_object_pair = Some((ids[3], ids[7]));
    pipeline.set_interest(interest_rules((ids[3], ids[7])));
    let (one_thread, two_threads, three_threads) = (pool(1), pool(2), pool(3));
    let (mut colliding_frames, mut separated_by_plane) = (0, 0);
    let (mut split_tests, mut parallel_exact_tests, mut shared_frames) = (0, 0, 0);
    let mut last_colliding = Vec::new();
    for frame in 0..2500 {
        // Most frames move half the scene (the broad phase re-sorts whole axes); every third
        // moves a body or two (it sifts them one at a time).
        let share = if frame % 3 == 2 { 0.05 } else { 0.5 };
        for (id, pose) in scene.step(share) {
            pipeline.queue_move(id, pose).unwrap();
        }
        if frame % 100 == 50 {
            // Replace an object: its pairs and cached planes must go with it.
            let victim = *scene
                .bodies
                .keys()
                .nth(scene.rng.random_range(8..30))
                .unwrap();
            pipeline.remove(victim).unwrap();
            scene.bodies.remove(&victim);
            assert_eq!(
                pipeline.remove(victim),
                Err(PipelineError::UnknownObject(victim))
            );
            scene.add(&mut pipeline);
        }
        if frame % 250 == 125
            && let Some(pair) = last_colliding.first()
        {
            // Forbid a pair in contact, which allows the one forbidden before again: the pair
            // table must drop the one and take in the other if its boxes overlap.
            scene.disallowed_object_pair = Some(*pair);
            pipeline.set_interest(interest_rules(*pair));
        }
        let detail = if frame % 10 == 0 {
            Detail::TrianglePairs
        } else {
            Detail::Pairs
        };
        let threads = match frame % 4 {
            1 => &two_threads,
            3 => &three_threads,
            _ => &one_thread,
        };
        let report = threads.install(|| pipeline.run_frame(detail));
        let stats = report.stats;
        if frame % 2 == 0 {
            assert_eq!(stats.split_tests, 0, "one thread never splits");
        } else {
            // Frames of more pairs than one chunk share them out among the threads.
            shared_frames += usize::from(stats.separating_plane.pairs_in > PAIRS_PER_TASK as u64);
            if detail == Detail::Pairs {
                split_tests += stats.split_tests;
                parallel_exact_tests += stats.exact.pairs_in;
            }
        }
        assert!(stats.broad_phase.pairs_out <= stats.broad_phase.pairs_in);
        assert_eq!(stats.interest.pairs_in, stats.broad_phase.pairs_out);
        assert_eq!(stats.separating_plane.pairs_in, stats.interest.pairs_out);
        assert_eq!(stats.exact.pairs_in, stats.separating_plane.pairs_out);
        separated_by_plane += stats.separating_plane.pairs_in - stats.separating_plane.pairs_out;
        let expected = scene.brute_force(detail == Detail::TrianglePairs);
        let found = sorted_triangles(report);
        assert_eq!(found, expected, "frame {frame}");
        last_colliding = found.iter().map(|pair| (pair.a, pair.b)).collect();
        colliding_frames += usize::from(!expected.is_empty());
    }
    assert!(
        colliding_frames > 1000,
        "only {colliding_frames} frames had collisions"
    );
    assert!(
        separated_by_plane > 10_000,
        "the plane stage separated only {separated_by_plane} pairs"
    );
    assert!(
        shared_frames > 500,
        "only {shared_frames} frames on several threads shared out their pairs"
    );
    (split_tests, parallel_exact_tests)
}

#[test]
fn bad_poses_and_stale_ids_are_refused() {
    let mut scene = Scene::<ParryMesh>::new(23);
    let mut pipeline = CollisionPipeline::new(PipelineConfig::default());
    let id = scene.add(&mut pipeline);
    let mut nan = Isometry3::identity();
    nan.translation.vector.x = f64::NAN;
    assert!(matches!(
        pipeline.queue_move(id, nan),
        Err(PipelineError::InvalidPose(..))
    ));
    let model = Arc::clone(&scene.shapes[0].1);
    let desc = ObjectDesc {
        model,
        pose: nan,
        group: GroupId(0),
        is_static: false,
    };
    assert!(matches!(
        pipeline.add(desc),
        Err(PipelineError::InvalidPose(..))
    ));
    pipeline.remove(id).unwrap();
    let reused = scene.add(&mut pipeline);
    assert_eq!(reused.index(), id.index());
    assert_eq!(
        pipeline.queue_move(id, Isometry3::identity()),
        Err(PipelineError::UnknownObject(id))
    );
    assert!(pipeline.queue_move(reused, Isometry3::identity()).is_ok());
}

#[test]
fn pairs_known_apart_skip_the_exact_test_only_at_their_poses() {
    // Two unit balls whose boxes overlap at a corner: without the pre-check, every frame that
    // moves one of them tests the pair exactly.
    let config = PipelineConfig {
        separating_plane: false,
        ..PipelineConfig::default()
    };
    let mut pipeline = CollisionPipeline::<DopTree>::new(config);
    let ball = model::<DopTree>(&shape(Vector3::new(1.0, 1.0, 1.0), 0.0));
    let desc = |pose: Isometry3<f64>| ObjectDesc {
        model: Arc::clone(&ball),
        pose,
        group: GroupId(0),
        is_static: false,
    };
    let at = |x: f64, y: f64| Isometry3::translation(x, y, 0.0);
    let fixed = pipeline.add(desc(at(0.0, 0.0))).unwrap();
    let moving = pipeline.add(desc(at(1.6, 1.6))).unwrap();
    let first = pipeline.run_frame(Detail::Pairs);
    assert_eq!((first.stats.exact.pairs_in, first.colliding.len()), (1, 0));

    // Known apart where both are: no exact test, and still apart.
    let apart = at(1.6, 1.5);
    pipeline.queue_move(moving, apart).unwrap();
    pipeline.set_known_apart([KnownApart {
        a: (moving, apart),
        b: (fixed, at(0.0, 0.0)),
    }]);
    let skipped = pipeline.run_frame(Detail::Pairs);
    assert_eq!(
        (skipped.stats.exact.pairs_in, skipped.colliding.len()),
        (0, 0)
    );

    // Moved into the other ball, the fact (for the old pose) no longer holds: tested, colliding.
    pipeline.queue_move(moving, at(0.5, 0.0)).unwrap();
    let tested = pipeline.run_frame(Detail::Pairs);
    assert_eq!(tested.stats.exact.pairs_in, 1);
    let pair = tested
        .colliding
        .iter()
        .map(|p| (p.a, p.b))
        .collect::<Vec<_>>();
    assert_eq!(pair, vec![(fixed, moving)]);

    // A fact never hides a pair that collided when last tested.
    pipeline.queue_move(moving, at(0.4, 0.0)).unwrap();
    pipeline.set_known_apart([KnownApart {
        a: (fixed, at(0.0, 0.0)),
        b: (moving, at(0.4, 0.0)),
    }]);
    let still = pipeline.run_frame(Detail::Pairs);
    assert_eq!((still.stats.exact.pairs_in, still.colliding.len()), (1, 1));
}

#[test]
fn answers_do_not_depend_on_the_separating_plane_stage() {
    let mut scene = Scene::<DopTree>::new(25);
    let mut with_plane = CollisionPipeline::new(PipelineConfig::default());
    for _ in 0..25 {
        scene.add(&mut with_plane);
    }
    let mut without_plane = CollisionPipeline::new(PipelineConfig {
        separating_plane: false,
        ..PipelineConfig::default()
    });
    for body in scene.bodies.values() {
        without_plane
            .add(ObjectDesc {
                model: Arc::clone(&body.model),
                pose: body.pose,
                group: GroupId(body.group),
                is_static: body.is_static,
            })
            .unwrap();
    }
    let (mut plane_tests, mut direct_tests) = (0, 0);
    for frame in 0..300 {
        for (id, pose) in scene.step(0.5) {
            with_plane.queue_move(id, pose).unwrap();
            without_plane.queue_move(id, pose).unwrap();
        }
        let expected = with_plane.run_frame(Detail::Pairs);
        let report = without_plane.run_frame(Detail::Pairs);
        assert_eq!(report.colliding, expected.colliding, "frame {frame}");
        assert_eq!(
            report.stats.separating_plane.pairs_out,
            report.stats.separating_plane.pairs_in
        );
        plane_tests += expected.stats.exact.pairs_in;
        direct_tests += report.stats.exact.pairs_in;
    }
    assert!(
        plane_tests * 2 < direct_tests,
        "{plane_tests} exact tests with the plane stage, {direct_tests} without"
    );
}

/// Fine grain goes by cost: of a peg in a hole with little clearance (a long traversal that finds
/// no hit) and two overlapping spheres (a first hit within a few dozen bounding-volume tests),
/// with the split bound between their costs, only the peg's exact test is split, once the
/// pipeline has seen its cost, and only on more than one thread; the answers stay those of
/// parry.
#[test]
fn only_pairs_expensive_last_time_are_split() {
    use crate::collision::MeshCollider;
    use crate::geometry::shapes::{ShapeKind, ShapeSpec};
    let block = ShapeSpec::unit(ShapeKind::BoxWithHole, 3000)
        .build()
        .unwrap();
    let peg = ShapeSpec::Cylinder {
        radius: 0.49,
        height: 2.0,
        triangles: 3000,
    }
    .build()
    .unwrap();
    let ball = ShapeSpec::unit(ShapeKind::Sphere, 1000).build().unwrap();
    let placed = |x: f64, z: f64| Isometry3::translation(x, 0.0, z);
    let objects = [
        (&block, placed(0.0, 0.0)),
        (&peg, placed(0.005, 0.2)),
        (&ball, placed(10.0, 0.0)),
        (&ball, placed(11.5, 0.0)),
    ];

    // The oracle, and the premise: one pair costs far more than the threshold, the other far less.
    let first_hit = |i: usize, j: usize| {
        let (a, b) = (DopTree::build(objects[i].0), DopTree::build(objects[j].0));
        let mut stats = QueryStats::default();
        let b_to_a = objects[i].1.inv_mul(&objects[j].1);
        let hit = a.intersects(&b, &b_to_a, &mut stats);
        let parry = ParryMesh::build(objects[i].0).intersects(
            &ParryMesh::build(objects[j].0),
            &b_to_a,
            &mut QueryStats::default(),
        );
        assert_eq!(hit, parry);
        (hit, stats.bv_tests)
    };
    let (peg_hit, peg_work) = first_hit(0, 1);
    let (balls_hit, balls_work) = first_hit(2, 3);
    assert!(!peg_hit && balls_hit);
    // The bound sits between the two costs, each well apart from it.
    let split_min_bv_tests = peg_work / 2;
    assert!(
        balls_work * 10 < split_min_bv_tests,
        "{balls_work} against {peg_work}"
    );

    let mut pipeline = CollisionPipeline::<DopTree>::new(PipelineConfig {
        split_min_bv_tests,
        ..PipelineConfig::default()
    });
    let ids: Vec<ObjectId> = objects
        .iter()
        .map(|(mesh, pose)| {
            pipeline
                .add(ObjectDesc {
                    model: model(mesh),
                    pose: *pose,
                    group: GroupId(0),
                    is_static: false,
                })
                .unwrap()
        })
        .collect();
    let (one_thread, two_threads) = (pool(1), pool(2));
    let mut frame = |threads: &rayon::ThreadPool, nudge: f64| {
        for (&id, (_, pose)) in ids.iter().zip(&objects) {
            pipeline
                .queue_move(id, Translation3::new(0.0, nudge, 0.0) * pose)
                .unwrap();
        }
        let report = threads.install(|| pipeline.run_frame(Detail::Pairs));
        let found: Vec<_> = report.colliding.iter().map(|p| (p.a, p.b)).collect();
        assert_eq!(found, [(ids[2], ids[3])]);
        assert_eq!(report.stats.exact.pairs_in, 2);
        report.stats.split_tests
    };
    assert_eq!(frame(&two_threads, 0.0), 0, "no cost is known yet");
    assert_eq!(frame(&two_threads, 1e-4), 1);
    assert_eq!(frame(&one_thread, 2e-4), 0, "one thread never splits");
    assert_eq!(frame(&two_threads, 3e-4), 1);
}
