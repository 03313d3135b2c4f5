//! Scripted glove and tracker trajectories against procedural parts: the grasps the hand must
//! recognise, with every frame checked for penetration by parry, independently of the DOP-trees.

use std::sync::Arc;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use parry3d::query::{PointQuery, contact, intersection_test};
use parry3d::shape::{ConvexPolyhedron, TriMesh as ParryTriMesh, TriMeshFlags};

use vas_server::geometry::TriMesh;
use vas_server::geometry::shapes;
use vas_server::grasping::analysis::GraspClass;
use vas_server::grasping::clasp::HandPose;
use vas_server::grasping::collider::{Obstacle, PartGeometry, PartId};
use vas_server::grasping::hand::{GraspEvent, GraspParams, GraspingHand, HandMode, HandStep};
use vas_server::grasping::model::{FLEX_COUNT, HandModel};
use vas_testkit::hand_models::{hands_dir, right_hand};
use vas_testkit::script::{Keyframe, ScriptedGrasp, fist, open_hand, posture, sample};

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

    /// The part of a scripted grasp, with about 2,000 triangles.
    fn scripted(id: PartId, script: ScriptedGrasp) -> ScenePart {
        ScenePart::new(id, script.part_mesh(2_000), script.part_pose())
    }
}

fn pose(translation: [f64; 3], rotation: UnitQuaternion<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(Translation3::from(Vector3::from(translation)), rotation)
}

fn at(translation: [f64; 3]) -> Isometry3<f64> {
    pose(translation, UnitQuaternion::identity())
}

/// Distance between the translations of two poses.
fn distance(a: &Isometry3<f64>, b: &Isometry3<f64>) -> f64 {
    (a.translation.vector - b.translation.vector).norm()
}

/// A scripted run: the hand, the parts, and what every frame gave.
struct Run {
    model: Arc<HandModel>,
    hand: GraspingHand,
    parts: Vec<ScenePart>,
    segments: Vec<ConvexPolyhedron>,
    frames: Vec<HandStep>,
    events: Vec<(usize, GraspEvent)>,
    penetrations: Vec<String>,
}

impl Run {
    fn new(parts: Vec<ScenePart>, start: Isometry3<f64>) -> Run {
        Run::with_hand(right_hand(), parts, start)
    }

    fn with_hand(model: HandModel, parts: Vec<ScenePart>, start: Isometry3<f64>) -> Run {
        let model = Arc::new(model);
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
    fn play(&mut self, keys: &[Keyframe]) {
        for sample in sample(keys, RATE) {
            let input = sample.input();
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
            .filter(|(_, contacts)| !contacts.is_empty())
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
                f.clasp.map_or(0, |c| c.steps),
                f.grasp,
                f.held.map(|h| h.0),
                f.pose.root.translation.vector.as_slice(),
                self.touching(i)
            );
        }
        out + &format!("\nevents {:?}", self.events)
    }

    /// The grasp and release events, with their frame numbers.
    fn grasps(&self) -> Vec<(usize, PartId, GraspClass)> {
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

/// Plays a scripted grasp and checks what every scripted grasp must do: no penetration, one
/// grasp of the expected type in time, the part carried with the hand at the grasp's offset,
/// one release after the carrying.
fn check_scripted_grasp(script: ScriptedGrasp) -> Run {
    let keys = script.keyframes();
    let run = Run::new(vec![ScenePart::scripted(1, script)], keys[0].tracker);
    check_run(run, script, &keys)
}

/// Plays `keys` (a scripted grasp's, perhaps mirrored) and checks the run as
/// [`check_scripted_grasp`] describes.
fn check_run(mut run: Run, script: ScriptedGrasp, keys: &[Keyframe]) -> Run {
    let start_pose = run.parts[0].pose;
    run.play(keys);
    let summary = run.summary(50);
    run.assert_no_penetration();
    let milestones = script.milestones();

    let grasps = run.grasps();
    assert_eq!(grasps.len(), 1, "{summary}");
    let (grasped_at, part, grasp) = grasps[0];
    assert_eq!((part, grasp), (1, script.expected()), "{summary}");
    assert!(
        grasped_at < Run::frame_at(milestones.grasped_by),
        "{summary}"
    );

    let frame = &run.frames[Run::frame_at(milestones.carried)];
    assert_eq!(frame.grasp, Some(script.expected()), "{summary}");
    let (held, part_pose) = frame.held.expect("held while carried");
    assert_eq!(held, 1);
    let GraspEvent::Grasp { hand_to_part, .. } = run.events[0].1 else {
        unreachable!("the first event is the grasp")
    };
    assert!(distance(&frame.pose.root.inv_mul(&part_pose), &hand_to_part) < 1e-9);
    assert!(
        distance(&part_pose, &start_pose) > 0.04,
        "the part stayed behind: {summary}"
    );

    let releases = run.releases();
    assert_eq!(releases.len(), 1, "{summary}");
    assert!(
        releases[0].0 > Run::frame_at(milestones.release_after),
        "{summary}"
    );
    assert!(run.frames.last().unwrap().held.is_none());
    run
}

#[test]
fn a_power_grasp_of_a_cylinder_handle_holds_it_and_it_follows_the_hand() {
    let run = check_scripted_grasp(ScriptedGrasp::PowerOnHandle);
    // Opening the hand leaves the handle where it was carried.
    let GraspEvent::Release { pose, .. } = run.events[1].1 else {
        unreachable!("the second event is the release")
    };
    assert_eq!(run.parts[0].pose, pose);
}

#[test]
fn the_left_hand_grasps_a_mirrored_handle() {
    // Everything mirrored in x = 0: poses become S·P·S with S = diag(-1, 1, 1).
    let mirror = |p: &Isometry3<f64>| {
        let s = nalgebra::Matrix3::from_diagonal(&Vector3::new(-1.0, 1.0, 1.0));
        let matrix = s * p.rotation.to_rotation_matrix().matrix() * s;
        let rotation = nalgebra::Rotation3::from_matrix_unchecked(matrix);
        let t = p.translation.vector;
        Isometry3::from_parts(
            Translation3::new(-t.x, t.y, t.z),
            UnitQuaternion::from_rotation_matrix(&rotation),
        )
    };
    let script = ScriptedGrasp::PowerOnHandle;
    let keys: Vec<Keyframe> = script
        .keyframes()
        .iter()
        .map(|k| Keyframe {
            tracker: mirror(&k.tracker),
            ..*k
        })
        .collect();
    let left = HandModel::load(&hands_dir().join("left.toml")).unwrap();
    // The handle is symmetric under the mirror: the same mesh at the mirrored pose.
    let handle = ScenePart::new(1, script.part_mesh(2_000), mirror(&script.part_pose()));
    let run = Run::with_hand(left, vec![handle], keys[0].tracker);
    check_run(run, script, &keys);
}

#[test]
fn a_tip_pinch_of_a_small_screw_is_a_precision_grasp() {
    check_scripted_grasp(ScriptedGrasp::TipPinchOfScrew);
}

#[test]
fn an_open_hand_under_a_part_carries_it_by_gravity_until_tipped() {
    check_scripted_grasp(ScriptedGrasp::GravityUnderBlock);
}

#[test]
fn the_back_of_the_hand_pushes_a_box_and_grasps_nothing() {
    // A box 2 cm above the back of the palm; the hand rises 3 cm into it, then makes a fist.
    let box_centre = [0.0, 0.06, 0.0125 + 0.02 + 0.04];
    let cube = shapes::cuboid(Vector3::new(0.08, 0.08, 0.08), 1_200);
    let mut run = Run::new(
        vec![ScenePart::new(5, cube, at(box_centre))],
        Isometry3::identity(),
    );
    let curled = posture(&[
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
    let k = Keyframe::new;
    let keys = [
        k(0.0, Isometry3::identity(), open_hand()),
        k(0.15, at([0.0, 0.0, 0.03]), open_hand()),
        k(0.2, at([0.0, 0.0, 0.03]), open_hand()),
        k(0.4, at([0.0, 0.0, 0.03]), curled),
        k(0.45, at([0.0, 0.0, 0.03]), curled),
    ];
    run.play(&keys);
    let summary = run.summary(50);
    run.assert_no_penetration();
    assert!(run.events.is_empty(), "{summary}");
    // The back of the palm rests against the box: a push.
    let pressed = Run::frame_at(0.2);
    assert_eq!(
        run.frames[pressed].grasp,
        Some(GraspClass::Push),
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
        Some(GraspClass::Push),
        "{summary}"
    );
    assert_eq!(run.parts[0].pose, at(box_centre));
}

#[test]
fn the_cart_carries_a_held_part_without_clasping() {
    let script = ScriptedGrasp::PowerOnHandle;
    let mut run = Run::new(vec![ScenePart::scripted(7, script)], at([0.0, 0.0, 0.02]));
    // The grasp of the handle, up to the closed fist.
    let mut keys: Vec<Keyframe> = script
        .keyframes()
        .into_iter()
        .filter(|k| k.time <= 0.55)
        .collect();
    let hold = keys[keys.len() - 1].tracker;
    let walked = pose(
        [0.3, -0.2, 0.0],
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.5),
    );
    for time in [0.85, 0.95] {
        keys.push(Keyframe {
            cart: walked,
            ..Keyframe::new(time, hold, fist())
        });
    }
    run.play(&keys);
    let summary = run.summary(50);
    run.assert_no_penetration();
    assert_eq!(run.grasps().len(), 1, "{summary}");
    assert!(run.releases().is_empty(), "{summary}");
    let walking = &run.frames[Run::frame_at(0.7)];
    assert_eq!(
        (walking.mode, walking.clasp),
        (HandMode::Navigating, None),
        "{summary}"
    );
    // After the walk the hand clasps again, still holding the handle where the cart took it.
    let after = run.frames.last().unwrap();
    assert_eq!(after.mode, HandMode::Clasping, "{summary}");
    let (_, handle_pose) = after.held.expect("still held");
    let GraspEvent::Grasp { hand_to_part, .. } = run.events[0].1 else {
        unreachable!("the first event is the grasp")
    };
    assert!(
        distance(&handle_pose, &(walked * hold * hand_to_part)) < 1e-9,
        "{summary}"
    );
}

#[test]
fn a_hand_carried_into_a_part_by_the_cart_waits_until_moved_free() {
    // A wall ahead of the hand; the cart walks the hand 10 cm into it.
    let wall = shapes::cuboid(Vector3::new(0.2, 0.05, 0.2), 1_200);
    let mut run = Run::new(
        vec![ScenePart::new(4, wall, at([0.0, 0.25, 0.0]))],
        Isometry3::identity(),
    );
    let walked = at([0.0, 0.1, 0.0]);
    let walking = |time: f64, tracker: Isometry3<f64>| Keyframe {
        cart: walked,
        ..Keyframe::new(time, tracker, open_hand())
    };
    let keys = [
        Keyframe::new(0.0, Isometry3::identity(), open_hand()),
        Keyframe::new(0.05, Isometry3::identity(), open_hand()),
        walking(0.25, Isometry3::identity()),
        walking(0.3, Isometry3::identity()),
        // The user lifts the hand out of the wall; it is free above 10 cm.
        walking(0.5, at([0.0, 0.0, 0.15])),
    ];
    run.play(&keys);
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
        assert_eq!(f.clasp, None);
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

#[test]
fn the_grasping_scene_names_a_hand_that_grasps_its_handle() {
    use vas_server::scene::Scene;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/grasp_table.toml");
    let scene = Scene::load(&path).unwrap();
    let model = Arc::clone(&scene.hands.first().expect("the scene names a hand").model);
    assert_eq!(model.name(), "right hand, 22 DOF");
    // The scripted power grasp, moved to where the scene's handle lies.
    let handle = scene.parts.iter().position(|p| p.name == "handle").unwrap();
    let script = ScriptedGrasp::PowerOnHandle;
    let shift = scene.parts[handle].pose * script.part_pose().inverse();
    // The scene's own trees, with the scene's orientation set, as the server uses them.
    let handle_geometry = scene.parts[handle].grasp_geometry();
    let others: Vec<(PartId, PartGeometry, Isometry3<f64>)> = scene
        .parts
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != handle)
        .map(|(i, p)| (i as PartId, p.grasp_geometry(), p.pose))
        .collect();
    let keys = script.keyframes();
    let mut hand = GraspingHand::new(
        model,
        scene.params.grasp(),
        HandPose {
            root: shift * keys[0].tracker,
            flex: [0.0; FLEX_COUNT],
        },
    )
    .unwrap();
    let mut handle_pose = scene.parts[handle].pose;
    let mut grasps = Vec::new();
    for key in sample(&keys, RATE)
        .iter()
        .filter(|k| k.time <= script.milestones().carried)
    {
        let mut obstacles = vec![Obstacle {
            part: handle as PartId,
            geometry: &handle_geometry,
            pose: handle_pose,
        }];
        obstacles.extend(others.iter().map(|(id, g, pose)| Obstacle {
            part: *id,
            geometry: g,
            pose: *pose,
        }));
        let input = Keyframe {
            tracker: shift * key.tracker,
            ..*key
        }
        .input();
        let frame = hand.step(&input, &obstacles);
        grasps.extend(frame.events.iter().filter_map(|e| match e {
            GraspEvent::Grasp { part, grasp, .. } => Some((*part, *grasp)),
            GraspEvent::Release { .. } => None,
        }));
        if let Some((_, pose)) = frame.held {
            handle_pose = pose;
        }
    }
    assert_eq!(grasps, vec![(handle as PartId, GraspClass::Power)]);
    assert!(distance(&handle_pose, &scene.parts[handle].pose) > 0.05);
}
