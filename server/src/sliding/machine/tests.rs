use super::*;
use crate::sliding::ContactKind;

/// A world of half-spaces that a set of part points must stay inside: an analytic stand-in
/// for collision detection that exercises the machine alone.
struct HalfSpaces {
    /// Each plane as (inward unit normal, offset): free where `normal · x >= offset`.
    planes: Vec<(Unit<Vector3<f64>>, f64)>,
    points: Vec<Point>,
    queries: usize,
}

impl HalfSpaces {
    fn unit_cube(planes: &[([f64; 3], f64)]) -> Self {
        let mut points = Vec::new();
        for i in 0..8 {
            let c = |bit: i32| if i & (1 << bit) != 0 { 0.5 } else { -0.5 };
            points.push(Point::new(c(0), c(1), c(2)));
        }
        HalfSpaces {
            planes: planes
                .iter()
                .map(|&(n, d)| (Unit::new_normalize(Vector3::from(n)), d))
                .collect(),
            points,
            queries: 0,
        }
    }

    fn penetrations(&self, pose: &Pose) -> impl Iterator<Item = (Point, Unit<Vector3<f64>>)> + '_ {
        let pose = *pose;
        self.points.iter().flat_map(move |p| {
            let x = pose * p;
            self.planes
                .iter()
                .filter(move |(n, d)| n.dot(&x.coords) < *d)
                .map(move |(n, _)| (x, *n))
        })
    }
}

impl SlideWorld for HalfSpaces {
    fn collides(&mut self, part_pose: &Pose) -> bool {
        self.queries += 1;
        self.penetrations(part_pose).next().is_some()
    }

    fn clearance(&mut self, part_pose: &Pose, d_max: f64) -> Option<f64> {
        self.queries += 1;
        let distance = self
            .points
            .iter()
            .flat_map(|p| {
                let x = part_pose * p;
                self.planes.iter().map(move |(n, d)| n.dot(&x.coords) - d)
            })
            .fold(f64::INFINITY, f64::min)
            .max(0.0);
        (distance < d_max).then_some(distance)
    }

    fn contacts(&mut self, part_pose: &Pose, _: &Motion, _: &Point, out: &mut Vec<Contact>) {
        self.queries += 1;
        let found: Vec<_> = self.penetrations(part_pose).collect();
        out.extend(found.into_iter().map(|(point, normal)| Contact {
            obstacle: 0,
            point,
            normal,
            kind: ContactKind::VertexFace,
        }));
    }
}

fn at(x: f64, y: f64, z: f64) -> Pose {
    Pose::translation(x, y, z)
}

fn params(metaphor: SlidingMetaphor) -> SlideParams {
    SlideParams {
        metaphor,
        contact_tolerance: Some(1e-4),
        ..SlideParams::default()
    }
}

/// Runs frames towards each ghost pose, checking after every single step that the visible
/// pose is free and that no step asked more than one query.
fn drive(machine: &mut SlideMachine, world: &mut HalfSpaces, ghosts: &[Pose]) -> RestReason {
    let mut reason = RestReason::Grasped;
    for ghost in ghosts {
        machine.set_ghost(ghost);
        for _ in 0..10_000 {
            let before = world.queries;
            let event = machine.step(world);
            assert!(
                world.queries - before <= 1,
                "{event:?} asked several queries"
            );
            let visible = machine.visible_pose();
            assert!(
                world.penetrations(&visible).next().is_none(),
                "visible pose collides"
            );
            if let Event::Rested(r) = event {
                reason = r;
                break;
            }
        }
    }
    reason
}

fn assert_near(pose: &Pose, expected: [f64; 3], within: f64) {
    let error = (pose.translation.vector - Vector3::from(expected)).norm();
    assert!(
        error <= within,
        "at {}, expected {expected:?}",
        pose.translation.vector
    );
}

#[test]
fn a_block_dragged_into_the_floor_ends_above_the_ghost() {
    let mut world = HalfSpaces::unit_cube(&[([0., 0., 1.], 0.0)]);
    let mut machine = SlideMachine::new(
        &at(0., 0., 1.),
        Vector3::zeros(),
        0.87,
        params(SlidingMetaphor::RubberBand),
    );
    let ghosts: Vec<Pose> = (1..=20)
        .map(|i| at(0.1 * i as f64, 0.05 * i as f64, 1.0 - 0.1 * i as f64))
        .collect();
    let reason = drive(&mut machine, &mut world, &ghosts);
    assert_eq!(reason, RestReason::Blocked);
    assert_near(&machine.visible_pose(), [2.0, 1.0, 0.5], 3e-4);
    assert!(machine.contacts().all(|c| c.normal.z > 0.999));
}

#[test]
fn into_a_crease_the_block_slides_along_it_and_into_a_corner_it_stops() {
    let floor = ([0., 0., 1.], 0.0);
    let wall = ([-1., 0., 0.], -1.0); // free where x <= 1
    let back = ([0., -1., 0.], -1.0); // free where y <= 1
    let ghost = [at(3.0, 2.0, -1.0)];

    let mut world = HalfSpaces::unit_cube(&[floor, wall]);
    let mut machine = SlideMachine::new(
        &at(0., 0., 1.),
        Vector3::zeros(),
        0.87,
        params(SlidingMetaphor::RubberBand),
    );
    assert_eq!(drive(&mut machine, &mut world, &ghost), RestReason::Blocked);
    assert_near(&machine.visible_pose(), [0.5, 2.0, 0.5], 3e-4);

    let mut world = HalfSpaces::unit_cube(&[floor, wall, back]);
    let mut machine = SlideMachine::new(
        &at(0., 0., 1.),
        Vector3::zeros(),
        0.87,
        params(SlidingMetaphor::RubberBand),
    );
    assert_eq!(drive(&mut machine, &mut world, &ghost), RestReason::Blocked);
    assert_near(&machine.visible_pose(), [0.5, 0.5, 0.5], 3e-4);
}

#[test]
fn without_contact_every_metaphor_follows_the_ghost() {
    let ghost = Pose::new(Vector3::new(0.3, -0.2, 0.5), Vector3::new(0.0, 0.4, 0.1));
    for metaphor in [
        SlidingMetaphor::RubberBand,
        SlidingMetaphor::SpiralSpring,
        SlidingMetaphor::Incremental,
    ] {
        let mut world = HalfSpaces::unit_cube(&[]);
        let mut machine =
            SlideMachine::new(&Pose::identity(), Vector3::zeros(), 0.87, params(metaphor));
        assert_eq!(
            drive(&mut machine, &mut world, &[ghost]),
            RestReason::Reached
        );
        let rotation_error = machine.visible_pose().rotation.angle_to(&ghost.rotation);
        if metaphor.rotates() {
            assert!(rotation_error < 1e-9, "{metaphor:?}");
        } else {
            assert!((machine.visible_pose().rotation.angle() - 0.0).abs() < 1e-12);
        }
        assert_near(&machine.visible_pose(), [0.3, -0.2, 0.5], 1e-9);
    }
}

#[test]
fn the_spiral_spring_tilts_the_block_only_as_far_as_the_floor_allows() {
    let mut world = HalfSpaces::unit_cube(&[([0., 0., 1.], 0.0)]);
    let mut machine = SlideMachine::new(
        &at(0., 0., 0.5005),
        Vector3::zeros(),
        0.87,
        params(SlidingMetaphor::SpiralSpring),
    );
    // The ghost tilts about x while staying at the same height: a corner would dig in.
    let ghost = Pose::new(Vector3::new(0.0, 0.0, 0.5005), Vector3::new(0.3, 0.0, 0.0));
    drive(&mut machine, &mut world, &[ghost]);
    let visible = machine.visible_pose();
    // It turns most of the way towards the ghost's tilt, pivoting on its lower edge, which
    // ends on the floor (within the tolerance and the lift), never through it.
    let (roll, _, _) = visible.rotation.euler_angles();
    assert!((0.2..=0.3 + 1e-9).contains(&roll), "roll {roll}");
    let lowest = world
        .points
        .iter()
        .map(|p| (visible * p).z)
        .fold(f64::MAX, f64::min);
    assert!((0.0..=3e-4).contains(&lowest), "lowest corner at {lowest}");
}

#[test]
fn incremental_motion_repeats_the_ghost_delta_from_where_the_part_is() {
    let mut world = HalfSpaces::unit_cube(&[([0., 0., 1.], 0.0)]);
    let mut machine = SlideMachine::new(
        &at(0., 0., 1.),
        Vector3::zeros(),
        0.87,
        params(SlidingMetaphor::Incremental),
    );
    // Down into the floor: the part stops on it while the ghost goes 1 deeper.
    drive(&mut machine, &mut world, &[at(0.5, 0.0, -0.5)]);
    assert_near(&machine.visible_pose(), [0.5, 0.0, 0.5], 3e-4);
    // Up by 0.3: the part rises by 0.3 from where it is, not to the ghost.
    assert_eq!(
        drive(&mut machine, &mut world, &[at(0.5, 0.0, -0.2)]),
        RestReason::Reached
    );
    assert_near(&machine.visible_pose(), [0.5, 0.0, 0.8], 3e-4);
    // Switching to the rubber band pulls it back down to the ghost's projection.
    machine.set_metaphor(SlidingMetaphor::RubberBand);
    drive(&mut machine, &mut world, &[at(0.5, 0.0, -0.2)]);
    assert_near(&machine.visible_pose(), [0.5, 0.0, 0.5], 3e-4);
}

#[test]
fn a_ghost_pushed_into_the_floor_gives_the_hand_an_upward_force() {
    let mut world = HalfSpaces::unit_cube(&[([0., 0., 1.], 0.0)]);
    let mut machine = SlideMachine::new(
        &at(0., 0., 1.),
        Vector3::zeros(),
        0.87,
        params(SlidingMetaphor::RubberBand),
    );
    let mut force = crate::sliding::ForceModel::new(crate::sliding::ForceParams::default());
    machine.set_ghost(&at(0.0, 0.0, 0.49));
    assert_eq!(machine.run_frame(&mut world), RestReason::Blocked);
    let wrench = force.update(
        machine.visible_pivot_pose(),
        machine.ghost_pivot_pose(),
        0.001,
    );
    // The hand is 1 cm below the resting part (plus its gap of at most the tolerance and the
    // lift): 500 N/m pulls it up by 5 N and a little more.
    assert!(
        (5.0..=5.0 + 500.0 * 1.5e-4).contains(&wrench.force.z),
        "{}",
        wrench.force
    );
    assert!(wrench.force.xy().norm() < 1e-9);
    // A second frame with the ghost where it is changes nothing.
    assert_eq!(machine.run_frame(&mut world), RestReason::Blocked);
    machine.set_ghost(&at(0.0, 0.0, 0.49));
    assert_eq!(machine.run_frame(&mut world), RestReason::Blocked);
    assert_near(&machine.visible_pose(), [0.0, 0.0, 0.5], 3e-4);
}

#[test]
fn a_contact_left_behind_is_forgotten_at_the_next_frame() {
    // A table top (z >= 0) that ends at x = 1: beyond it the floor is at z >= -5.
    let mut world = HalfSpaces::unit_cube(&[([0., 0., 1.], 0.0)]);
    let mut machine = SlideMachine::new(
        &at(0., 0., 1.),
        Vector3::zeros(),
        0.87,
        params(SlidingMetaphor::RubberBand),
    );
    drive(&mut machine, &mut world, &[at(0.5, 0.0, -1.0)]);
    assert!(machine.contacts().count() > 0);
    world.planes = vec![(Vector3::z_axis(), -5.0)];
    assert_eq!(
        drive(&mut machine, &mut world, &[at(0.5, 0.0, -1.0)]),
        RestReason::Reached
    );
    assert_near(&machine.visible_pose(), [0.5, 0.0, -1.0], 1e-9);
}

#[test]
fn a_block_dropped_from_afar_finds_the_floor_by_distance_in_a_few_queries() {
    let mut world = HalfSpaces::unit_cube(&[([0., 0., 1.], 0.0)]);
    let mut machine = SlideMachine::new(
        &at(0., 0., 10.),
        Vector3::zeros(),
        0.87,
        SlideParams {
            conservative_advancement: true,
            ..params(SlidingMetaphor::RubberBand)
        },
    );
    assert_eq!(
        drive(&mut machine, &mut world, &[at(0.3, 0.0, -10.0)]),
        RestReason::Blocked
    );
    assert_near(&machine.visible_pose(), [0.3, 0.0, 0.5], 3e-4);
    // Bisection alone would halve 20 m down to 0.1 mm: 18 tests. Advancement gets within the
    // tolerance of the floor in two distance queries; one cut just ahead finds it.
    let stats = machine.stats();
    assert!(stats.distance_queries <= 3, "{stats:?}");
    assert!(stats.collision_checks <= 4, "{stats:?}");
}
