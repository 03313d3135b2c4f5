//! Scripted glove and tracker trajectories against procedural parts: the grasps the hand must
//! recognise, with every frame checked for penetration by parry, independently of the DOP-trees.

use std::sync::Arc;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use parry3d::query::{PointQuery, contact, intersection_test};
use parry3d::shape::{ConvexPolyhedron, TriMesh as ParryTriMesh, TriMeshFlags};

use super::analysis::{GraspType, PrecisionKind};
use super::clasp::HandPose;
use super::collider::{Obstacle, PartGeometry, PartId};
use super::hand::{GraspEvent, GraspParams, GraspingHand, HandFrame, HandInput, HandMode};
use super::model::tests::right_hand;
use super::model::{FLEX_COUNT, FlexVector, HandModel};
use crate::geometry::TriMesh;
use crate::geometry::shapes;

/// Input samples per second of the scripted trajectories (a tracker and glove at 1 kHz).
const RATE: f64 = 1000.0;

/// A penetration deeper than this (metres) is reported: parry computes in `f32`, whose rounding
/// at these sizes is well below it.
const DEPTH_SLACK: f64 = 1e-6;

/// A part of a scripted scene, with its independent parry copy.
struct ScenePart {
    id: PartId,
    geometry: PartGeometry,
    pose: Isometry3<f64>,
    oracle: ParryTriMesh,
}

impl ScenePart {
    fn new(id: PartId, mesh: TriMesh, pose: Isometry3<f64>) -> ScenePart {
        let vertices = mesh.vertices().iter().map(|v| v.cast::<f32>()).collect();
        let oracle =
            ParryTriMesh::with_flags(vertices, mesh.triangles().to_vec(), TriMeshFlags::ORIENTED)
                .expect("a valid mesh makes a valid parry mesh");
        ScenePart {
            id,
            geometry: PartGeometry::new(mesh),
            pose,
            oracle,
        }
    }
}

/// A hand posture: flex values in degrees by index, the rest zero.
fn posture(values: &[(usize, f64)]) -> FlexVector {
    let mut flex = [0.0; FLEX_COUNT];
    for &(i, degrees) in values {
        flex[i] = degrees.to_radians();
    }
    flex
}

/// A keyframe of a scripted trajectory.
#[derive(Clone, Copy)]
struct Key {
    /// Seconds from the start.
    time: f64,
    /// The cart in the world.
    cart: Isometry3<f64>,
    /// The hand root in the cart's frame (the tracker).
    tracker: Isometry3<f64>,
    flex: FlexVector,
}

/// Samples keyframes at [`RATE`], interpolating linearly (rotations by slerp).
fn sample(keys: &[Key]) -> Vec<Key> {
    let mut out = Vec::new();
    for pair in keys.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let n = ((b.time - a.time) * RATE).round() as usize;
        for i in 0..n {
            let t = i as f64 / n as f64;
            out.push(Key {
                time: a.time + t * (b.time - a.time),
                cart: a.cart.lerp_slerp(&b.cart, t),
                tracker: a.tracker.lerp_slerp(&b.tracker, t),
                flex: std::array::from_fn(|v| a.flex[v] + t * (b.flex[v] - a.flex[v])),
            });
        }
    }
    out.push(keys[keys.len() - 1]);
    out
}

fn pose(translation: [f64; 3], rotation: UnitQuaternion<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(Vector3::from(translation)), rotation)
}

/// A scripted run: the hand, the parts, and what every frame gave.
struct Run {
    model: Arc<HandModel>,
    hand: GraspingHand,
    parts: Vec<ScenePart>,
    segments: Vec<ConvexPolyhedron>,
    frames: Vec<HandFrame>,
    events: Vec<(usize, GraspEvent)>,
    penetrations: Vec<String>,
}

impl Run {
    fn new(parts: Vec<ScenePart>, start: Isometry3<f64>) -> Run {
        let model = Arc::new(right_hand());
        let hand = GraspingHand::new(
            model.clone(),
            GraspParams::default(),
            HandPose {
                root: start,
                flex: [0.0; FLEX_COUNT],
            },
        )
        .unwrap();
        let segments = (0..model.segments().len())
            .map(|s| {
                let points: Vec<_> = hand
                    .geometry()
                    .mesh(s)
                    .vertices()
                    .iter()
                    .map(|v| v.cast::<f32>())
                    .collect();
                ConvexPolyhedron::from_convex_hull(&points).expect("segment meshes are convex")
            })
            .collect();
        Run {
            model,
            hand,
            parts,
            segments,
            frames: Vec::new(),
            events: Vec::new(),
            penetrations: Vec::new(),
        }
    }

    /// Feeds the samples, moving held parts with the hand and checking every frame for
    /// penetration.
    fn play(&mut self, samples: &[Key]) {
        for sample in samples {
            let input = HandInput {
                cart: sample.cart,
                tracker: sample.tracker,
                flex: sample.flex.map(|v| v as f32),
            };
            let obstacles: Vec<Obstacle> = self
                .parts
                .iter()
                .map(|p| Obstacle {
                    part: p.id,
                    geometry: &p.geometry,
                    pose: p.pose,
                })
                .collect();
            let frame = self.hand.step(&input, &obstacles);
            for event in &frame.events {
                self.events.push((self.frames.len(), *event));
                if let GraspEvent::Release { part, pose } = event {
                    self.part_mut(*part).pose = *pose;
                }
            }
            if let Some((part, pose)) = frame.held {
                self.part_mut(part).pose = pose;
            }
            self.check(&frame.pose);
            self.frames.push(frame);
        }
    }

    fn part_mut(&mut self, id: PartId) -> &mut ScenePart {
        self.parts
            .iter_mut()
            .find(|p| p.id == id)
            .expect("known part")
    }

    /// Records every segment of the visible hand that penetrates a part, by parry.
    fn check(&mut self, hand: &HandPose) {
        let poses = self.model.segment_poses(&hand.flex);
        for (s, local) in poses.iter().enumerate() {
            let world = (hand.root * local).cast::<f32>();
            for part in &self.parts {
                let part_pose = part.pose.cast::<f32>();
                let relative = part_pose.inv_mul(&world);
                let overlaps =
                    intersection_test(&part_pose, &part.oracle, &world, &self.segments[s]).unwrap();
                let depth = if overlaps {
                    contact(&part_pose, &part.oracle, &world, &self.segments[s], 0.0)
                        .unwrap()
                        .map_or(0.0, |c| -f64::from(c.dist))
                } else {
                    0.0
                };
                let centre = relative * self.model.segments()[s].shape.centres[0].cast::<f32>();
                let inside = part.oracle.contains_local_point(&centre);
                if depth > DEPTH_SLACK || inside {
                    self.penetrations.push(format!(
                        "frame {}: {} enters part {} by {depth:.2e} m{}",
                        self.frames.len(),
                        self.model.segments()[s].name,
                        part.id,
                        if inside { " (inside)" } else { "" }
                    ));
                }
            }
        }
    }

    fn assert_no_penetration(&self) {
        assert!(
            self.penetrations.is_empty(),
            "{} penetrations, first: {:?}",
            self.penetrations.len(),
            &self.penetrations[..self.penetrations.len().min(5)]
        );
    }

    /// Names of the segments touching anything in frame `i`.
    fn touching(&self, i: usize) -> Vec<&str> {
        self.frames[i]
            .touching
            .iter()
            .enumerate()
            .filter(|(_, parts)| !parts.is_empty())
            .map(|(s, _)| self.model.segments()[s].name.as_str())
            .collect()
    }

    /// A line per `every` frames, for failure messages.
    fn summary(&self, every: usize) -> String {
        let mut out = String::new();
        for (i, f) in self.frames.iter().enumerate().step_by(every) {
            out += &format!(
                "\n{i:5} {:?} steps {:2} grasp {:?} held {:?} root {:?} touching {:?}",
                f.mode,
                f.clasp_steps,
                f.grasp,
                f.held.map(|h| h.0),
                f.pose.root.translation.vector.as_slice(),
                self.touching(i)
            );
        }
        out + &format!("\nevents {:?}", self.events)
    }

    /// The grasp and release events, with their frame numbers.
    fn grasps(&self) -> Vec<(usize, PartId, GraspType)> {
        self.events
            .iter()
            .filter_map(|&(i, e)| match e {
                GraspEvent::Grasp { part, grasp, .. } => Some((i, part, grasp)),
                GraspEvent::Release { .. } => None,
            })
            .collect()
    }

    fn releases(&self) -> Vec<(usize, PartId)> {
        self.events
            .iter()
            .filter_map(|&(i, e)| match e {
                GraspEvent::Release { part, .. } => Some((i, part)),
                GraspEvent::Grasp { .. } => None,
            })
            .collect()
    }

    /// The frame index at `time` seconds.
    fn frame_at(time: f64) -> usize {
        (time * RATE).round() as usize
    }
}

/// A handle: a cylinder of radius 1.6 cm and length 12 cm along x.
fn handle(id: PartId, centre: [f64; 3]) -> ScenePart {
    let mesh = shapes::cylinder(0.016, 0.12, 2_000);
    let along_x = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
    ScenePart::new(id, mesh, pose(centre, along_x))
}

/// A screw: a shaft of radius 3 mm and length 16 mm along x with a head of radius 5 mm, 3 mm
/// long, at its +x end.
fn screw(id: PartId, centre: [f64; 3]) -> ScenePart {
    let along_x = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
    let shaft = shapes::cylinder(0.003, 0.016, 400)
        .map_vertices(|p| along_x * p)
        .unwrap();
    let head = shapes::cylinder(0.005, 0.003, 300)
        .map_vertices(|p| along_x * p + Vector3::new(0.0095, 0.0, 0.0))
        .unwrap();
    let offset = shaft.vertices().len() as u32;
    let vertices = shaft
        .vertices()
        .iter()
        .chain(head.vertices())
        .copied()
        .collect();
    let triangles = shaft
        .triangles()
        .iter()
        .copied()
        .chain(head.triangles().iter().map(|t| t.map(|i| i + offset)))
        .collect();
    let (mesh, _) = TriMesh::new(vertices, triangles).unwrap();
    ScenePart::new(id, mesh, pose(centre, UnitQuaternion::identity()))
}

/// A box of the given edge lengths.
fn block(id: PartId, size: [f64; 3], centre: [f64; 3]) -> ScenePart {
    let mesh = shapes::cuboid(Vector3::from(size), 1_200);
    ScenePart::new(id, mesh, pose(centre, UnitQuaternion::identity()))
}

/// The open hand: fingers straight, the thumb spread in the plane of the palm.
fn open_hand() -> FlexVector {
    posture(&[(0, -30.0), (3, 45.0)])
}

/// A keyframe with the cart at the origin.
fn key(time: f64, tracker: Isometry3<f64>, flex: FlexVector) -> Key {
    Key {
        time,
        cart: Isometry3::identity(),
        tracker,
        flex,
    }
}

fn at(translation: [f64; 3]) -> Isometry3<f64> {
    pose(translation, UnitQuaternion::identity())
}

/// Distance between the translations of two poses.
fn distance(a: &Isometry3<f64>, b: &Isometry3<f64>) -> f64 {
    (a.translation.vector - b.translation.vector).norm()
}

/// A fist closing on whatever it holds, the thumb across.
fn fist() -> FlexVector {
    posture(&[
        (0, 60.0),
        (1, 40.0),
        (2, 40.0),
        (3, 10.0),
        (4, 85.0),
        (5, 90.0),
        (6, 70.0),
        (7, 85.0),
        (8, 90.0),
        (9, 70.0),
        (11, 85.0),
        (12, 90.0),
        (13, 70.0),
        (15, 85.0),
        (16, 90.0),
        (17, 70.0),
    ])
}

/// The hand comes down on a handle lying across the palm 3 cm below it, presses 5 mm into it
/// and closes the fist around it (0.55 s).
fn grasp_handle_keys() -> Vec<Key> {
    vec![
        key(0.0, at([0.0, 0.0, 0.02]), open_hand()),
        key(0.2, at([0.0, 0.0, -0.035]), open_hand()),
        key(0.5, at([0.0, 0.0, -0.035]), fist()),
        key(0.55, at([0.0, 0.0, -0.035]), fist()),
    ]
}

const HANDLE_CENTRE: [f64; 3] = [-0.005, 0.075, -0.0585];

#[test]
fn a_power_grasp_of_a_cylinder_handle_holds_it_and_it_follows_the_hand() {
    let start_pose = handle(7, HANDLE_CENTRE).pose;
    let mut run = Run::new(vec![handle(7, HANDLE_CENTRE)], at([0.0, 0.0, 0.02]));
    let tilted = pose(
        [0.05, 0.1, 0.04],
        UnitQuaternion::from_euler_angles(0.4, 0.2, 0.3),
    );
    let mut keys = grasp_handle_keys();
    keys.extend([
        // Carry it away, turning the hand.
        key(0.85, tilted, fist()),
        key(0.9, tilted, fist()),
        // Open the hand.
        key(1.1, tilted, open_hand()),
        key(1.2, tilted, open_hand()),
    ]);
    run.play(&sample(&keys));
    let summary = run.summary(50);
    run.assert_no_penetration();

    let grasps = run.grasps();
    assert_eq!(grasps.len(), 1, "{summary}");
    let (grasped_at, part, grasp) = grasps[0];
    assert_eq!((part, grasp), (7, GraspType::Power), "{summary}");
    assert!(grasped_at < Run::frame_at(0.55), "{summary}");
    // While carried the handle keeps its place in the hand, and is still held in a power grasp.
    let carried = Run::frame_at(0.9);
    let frame = &run.frames[carried];
    assert_eq!(frame.grasp, Some(GraspType::Power), "{summary}");
    let (held, part_pose) = frame.held.expect("held while carried");
    assert_eq!(held, 7);
    let offset = frame.pose.root.inv_mul(&part_pose);
    let GraspEvent::Grasp { hand_to_part, .. } = run.events[0].1 else {
        unreachable!()
    };
    assert!(distance(&offset, &hand_to_part) < 1e-9);
    assert!(
        distance(&part_pose, &start_pose) > 0.1,
        "the handle stayed behind: {summary}"
    );
    // Opening the hand releases it, once, where it was carried.
    let releases = run.releases();
    assert_eq!(releases.len(), 1, "{summary}");
    assert!(
        releases[0].0 > Run::frame_at(0.9) && releases[0].0 < Run::frame_at(1.2),
        "{summary}"
    );
    assert!(distance(&run.parts[0].pose, &part_pose) < 1e-9);
    assert!(run.frames.last().unwrap().held.is_none());
}

#[test]
fn a_tip_pinch_of_a_small_screw_is_a_precision_grasp() {
    let mut run = Run::new(
        vec![screw(3, [-0.0295, 0.121, -0.0717])],
        Isometry3::identity(),
    );
    let preshape = posture(&[(0, 30.0), (3, 40.0), (4, 20.0), (5, 15.0), (6, 5.0)]);
    let pinch = posture(&[
        (0, 70.0),
        (3, 25.0),
        (1, 30.0),
        (2, 15.0),
        (4, 60.0),
        (5, 45.0),
        (6, 20.0),
    ]);
    let lifted = at([0.0, 0.02, 0.05]);
    let keys = [
        key(0.0, Isometry3::identity(), preshape),
        key(0.3, Isometry3::identity(), pinch),
        key(0.35, Isometry3::identity(), pinch),
        key(0.6, lifted, pinch),
        key(0.65, lifted, pinch),
        key(0.85, lifted, preshape),
        key(0.9, lifted, preshape),
    ];
    run.play(&sample(&keys));
    let summary = run.summary(50);
    run.assert_no_penetration();
    let grasps = run.grasps();
    assert_eq!(grasps.len(), 1, "{summary}");
    assert_eq!(
        (grasps[0].1, grasps[0].2),
        (3, GraspType::Precision(PrecisionKind::TipPinch)),
        "{summary}"
    );
    let lifted_frame = &run.frames[Run::frame_at(0.65)];
    let (_, screw_pose) = lifted_frame.held.expect("held while lifted");
    assert!(
        (screw_pose.translation.z - (-0.0717 + 0.05)).abs() < 0.005,
        "{summary}"
    );
    assert_eq!(run.releases().len(), 1, "{summary}");
    assert!(run.frames.last().unwrap().held.is_none());
}

#[test]
fn the_back_of_the_hand_pushes_a_box_and_grasps_nothing() {
    // A box 2 cm above the back of the palm; the hand rises 3 cm into it, then makes a fist.
    let box_centre = [0.0, 0.06, 0.0125 + 0.02 + 0.04];
    let mut run = Run::new(
        vec![block(5, [0.08, 0.08, 0.08], box_centre)],
        Isometry3::identity(),
    );
    let fist = posture(&[
        (4, 80.0),
        (5, 80.0),
        (6, 60.0),
        (7, 80.0),
        (8, 80.0),
        (9, 60.0),
        (11, 80.0),
        (12, 80.0),
        (15, 80.0),
        (16, 80.0),
    ]);
    let keys = [
        key(0.0, Isometry3::identity(), open_hand()),
        key(0.15, at([0.0, 0.0, 0.03]), open_hand()),
        key(0.2, at([0.0, 0.0, 0.03]), open_hand()),
        key(0.4, at([0.0, 0.0, 0.03]), fist),
        key(0.45, at([0.0, 0.0, 0.03]), fist),
    ];
    run.play(&sample(&keys));
    let summary = run.summary(50);
    run.assert_no_penetration();
    assert!(run.events.is_empty(), "{summary}");
    // The back of the palm rests against the box: a push.
    let pressed = Run::frame_at(0.2);
    assert_eq!(
        run.frames[pressed].grasp,
        Some(GraspType::Push),
        "{summary}"
    );
    assert!(run.touching(pressed).contains(&"palm"), "{summary}");
    // It stops with the back of its palm mesh at the box's bottom (within the tolerance).
    let palm_top = run.hand.geometry().mesh(0).bounding_box().1.z;
    let contact = 0.0125 + 0.02 - palm_top;
    let reached = run.frames[pressed].pose.root.translation.z;
    let tolerance = GraspParams::default().clasp.root_tolerance;
    assert!(
        reached <= contact && reached > contact - tolerance,
        "stopped at {reached}, not {contact}: {summary}"
    );
    assert_eq!(
        run.frames.last().unwrap().grasp,
        Some(GraspType::Push),
        "{summary}"
    );
    assert_eq!(run.parts[0].pose, at(box_centre));
}

#[test]
fn an_open_hand_under_a_part_carries_it_by_gravity_until_tipped() {
    // Palm up: the hand turned half a turn about y. A block 4 x 5 x 3 cm above the palm.
    let palm_up = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI);
    let centre = [-0.005, 0.055, 0.0125 + 0.02 + 0.015];
    let mut run = Run::new(
        vec![block(9, [0.04, 0.05, 0.03], centre)],
        pose([0.0, 0.0, 0.0], palm_up),
    );
    let tipped = palm_up * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 80f64.to_radians());
    let keys = [
        key(0.0, pose([0.0, 0.0, 0.0], palm_up), open_hand()),
        // Up under the block, pressing 5 mm into it.
        key(0.2, pose([0.0, 0.0, 0.025], palm_up), open_hand()),
        key(0.25, pose([0.0, 0.0, 0.025], palm_up), open_hand()),
        // Carry it sideways and up.
        key(0.5, pose([0.1, 0.05, 0.08], palm_up), open_hand()),
        key(0.55, pose([0.1, 0.05, 0.08], palm_up), open_hand()),
        // Tip the hand over: the block would slide off.
        key(0.75, pose([0.1, 0.05, 0.08], tipped), open_hand()),
        key(0.8, pose([0.1, 0.05, 0.08], tipped), open_hand()),
    ];
    run.play(&sample(&keys));
    let summary = run.summary(50);
    run.assert_no_penetration();
    let grasps = run.grasps();
    assert_eq!(grasps.len(), 1, "{summary}");
    assert_eq!(
        (grasps[0].1, grasps[0].2),
        (9, GraspType::Gravity),
        "{summary}"
    );
    let carried = &run.frames[Run::frame_at(0.55)];
    let (_, block_pose) = carried.held.expect("carried");
    assert!(distance(&block_pose, &at(centre)) > 0.1, "{summary}");
    assert_eq!(run.releases().len(), 1, "{summary}");
    assert!(run.releases()[0].0 > Run::frame_at(0.55), "{summary}");
}

#[test]
fn the_cart_carries_a_held_part_without_clasping() {
    let mut run = Run::new(vec![handle(7, HANDLE_CENTRE)], at([0.0, 0.0, 0.02]));
    let hold = at([0.0, 0.0, -0.035]);
    let walked = pose(
        [0.3, -0.2, 0.0],
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.5),
    );
    let mut keys = grasp_handle_keys();
    keys.extend([
        Key {
            time: 0.85,
            cart: walked,
            tracker: hold,
            flex: fist(),
        },
        Key {
            time: 0.95,
            cart: walked,
            tracker: hold,
            flex: fist(),
        },
    ]);
    run.play(&sample(&keys));
    let summary = run.summary(50);
    run.assert_no_penetration();
    assert_eq!(run.grasps().len(), 1, "{summary}");
    assert!(run.releases().is_empty(), "{summary}");
    let walking = &run.frames[Run::frame_at(0.7)];
    assert_eq!(
        (walking.mode, walking.clasp_steps),
        (HandMode::Navigating, 0),
        "{summary}"
    );
    // After the walk the hand clasps again, still holding the handle where the cart took it.
    let after = run.frames.last().unwrap();
    assert_eq!(after.mode, HandMode::Clasping, "{summary}");
    let (_, handle_pose) = after.held.expect("still held");
    let GraspEvent::Grasp { hand_to_part, .. } = run.events[0].1 else {
        unreachable!()
    };
    assert!(
        distance(&handle_pose, &(walked * hold * hand_to_part)) < 1e-9,
        "{summary}"
    );
}

#[test]
fn a_hand_carried_into_a_part_by_the_cart_waits_until_moved_free() {
    // A wall of a box ahead of the hand; the cart walks the hand 10 cm into it.
    let mut run = Run::new(
        vec![block(4, [0.2, 0.05, 0.2], [0.0, 0.25, 0.0])],
        Isometry3::identity(),
    );
    let walked = at([0.0, 0.1, 0.0]);
    let raised = at([0.0, 0.0, 0.15]);
    let keys = [
        key(0.0, Isometry3::identity(), open_hand()),
        key(0.05, Isometry3::identity(), open_hand()),
        Key {
            time: 0.25,
            cart: walked,
            tracker: Isometry3::identity(),
            flex: open_hand(),
        },
        Key {
            time: 0.3,
            cart: walked,
            tracker: Isometry3::identity(),
            flex: open_hand(),
        },
        // The user lifts the hand out of the wall; it is free above 10 cm.
        Key {
            time: 0.5,
            cart: walked,
            tracker: raised,
            flex: open_hand(),
        },
    ];
    run.play(&sample(&keys));
    let summary = run.summary(20);
    run.assert_no_penetration();
    let modes: Vec<HandMode> = run.frames.iter().map(|f| f.mode).collect();
    let first_wait = modes
        .iter()
        .position(|&m| m == HandMode::AwaitingFreeHand)
        .expect("left behind");
    let resumed = first_wait
        + modes[first_wait..]
            .iter()
            .position(|&m| m == HandMode::Clasping)
            .expect("resumed");
    // Free while walking at first, then left behind at the wall until the hand is raised.
    assert!(
        modes[60..first_wait]
            .iter()
            .all(|&m| m == HandMode::Navigating),
        "{summary}"
    );
    let left = run.frames[first_wait].pose;
    for f in &run.frames[first_wait..resumed] {
        assert_eq!(f.pose, left, "the hand moved while waiting: {summary}");
        assert_eq!(f.clasp_steps, 0);
    }
    assert!(resumed > Run::frame_at(0.3), "{summary}");
    assert!(
        run.frames[resumed].pose.root.translation.z > 0.05,
        "{summary}"
    );
    assert!(
        modes[resumed..].iter().all(|&m| m == HandMode::Clasping),
        "{summary}"
    );
}
