//! Grasping handed over to sliding, offline: scripted hands take, carry, press and hand over
//! parts, and every frame is checked against parry.

use std::sync::Arc;

use nalgebra::{Isometry3, Translation3, Vector3};
use parry3d::query::intersection_test;
use parry3d::shape::TriMesh as ParryTriMesh;

use vas_server::collision::DopTree;
use vas_server::collision::orientation::DEFAULT_K;
use vas_server::collision::parry_mesh::{millimetre_pose, millimetre_trimesh};
use vas_server::geometry::{TriMesh, shapes};
use vas_server::grasping::{
    FLEX_COUNT, GraspClass, GraspEvent, GraspParams, GraspingHand, HandPose, PartId,
};
use vas_server::scene::{Part, PartTree, UnheldParams};
use vas_server::simulation::frames::HandTarget;
use vas_server::simulation::interaction::{Interaction, InteractionFrame};
use vas_server::sliding::motion::pose_distance;
use vas_server::sliding::world::SlideBody;
use vas_server::sliding::{RestReason, SlideParams, SlidingMetaphor};
use vas_testkit::hand_models::right_hand;
use vas_testkit::script::{Keyframe, ScriptedGrasp, open_hand, sample};

/// Input samples per second (a tracker and glove at 1 kHz).
const RATE: f64 = 1000.0;

/// The handle's id, and the table's in the scenes with one.
const HANDLE: PartId = 0;
const TABLE: PartId = 1;

/// Top of the table, 5.5 mm below the scripted handle's lowest point.
const TABLE_TOP: f64 = -0.08;

/// The table's edge towards the hand, beyond the hand's reach in x.
const TABLE_EDGE: f64 = 0.08;

fn part(name: &str, mesh: TriMesh, pose: Isometry3<f64>, movable: bool) -> Part {
    Part {
        name: name.into(),
        mesh: Arc::new(mesh),
        mesh_source: format!("shape:{name}"),
        scale: 1.0,
        pose,
        movable,
        group: "default".into(),
        push: None,
        release: None,
        tree: PartTree::new(DEFAULT_K, None),
    }
}

/// parry's copy of each part, in millimetres: an oracle independent of the DOP-trees.
struct Oracle {
    meshes: Vec<ParryTriMesh>,
}

impl Oracle {
    fn new(parts: &[Part]) -> Oracle {
        let meshes = parts.iter().map(|p| millimetre_trimesh(&p.mesh)).collect();
        Oracle { meshes }
    }

    /// Whether parts `a` and `b` intersect at the given poses.
    fn intersects(
        &self,
        a: PartId,
        pose_a: &Isometry3<f64>,
        b: PartId,
        pose_b: &Isometry3<f64>,
    ) -> bool {
        intersection_test(
            &millimetre_pose(pose_a),
            &self.meshes[a as usize],
            &millimetre_pose(pose_b),
            &self.meshes[b as usize],
        )
        .expect("parry supports mesh pairs")
    }
}

/// A scripted interaction: the parts, the interaction and every frame it gave, with the
/// handle's visible pose after each.
struct Run {
    parts: Vec<Part>,
    interaction: Interaction,
    frames: Vec<InteractionFrame>,
    handle_poses: Vec<Isometry3<f64>>,
}

impl Run {
    /// The right hand parked at `start` among `parts`, sliding by spiral spring (so that the
    /// carried handle turns with the hand).
    fn new(parts: Vec<Part>, start: Isometry3<f64>) -> Run {
        let hand = GraspingHand::new(
            Arc::new(right_hand()),
            GraspParams::default(),
            HandPose {
                root: start,
                flex: [0.0; FLEX_COUNT],
            },
        )
        .expect("the right hand's segment meshes build");
        let params = SlideParams {
            metaphor: SlidingMetaphor::SpiralSpring,
            ..SlideParams::default()
        };
        let interaction = Interaction::new(
            vec![hand],
            &parts,
            params,
            UnheldParams::held_only(),
            1.0 / RATE,
        );
        Run {
            parts,
            interaction,
            frames: Vec::new(),
            handle_poses: Vec::new(),
        }
    }

    fn play(&mut self, keys: &[Keyframe]) {
        for key in sample(keys, RATE) {
            let frame = (self.interaction)
                .step(&[HandTarget::tracking(key.input())])
                .remove(0);
            self.handle_poses
                .push(self.interaction.part_pose(HANDLE).expect("the handle"));
            self.frames.push(frame);
        }
    }

    /// The handle's grasp and release events, with their frame numbers.
    fn handle_events(&self) -> impl Iterator<Item = (usize, GraspEvent)> + '_ {
        self.frames.iter().enumerate().flat_map(|(i, frame)| {
            frame
                .hand
                .events
                .iter()
                .filter_map(move |&event| match event {
                    GraspEvent::Grasp { part, .. } | GraspEvent::Release { part, .. }
                        if part == HANDLE =>
                    {
                        Some((i, event))
                    }
                    _ => None,
                })
        })
    }

    /// The handle's grasps: frame and grasp type.
    fn grasps(&self) -> Vec<(usize, GraspClass)> {
        self.handle_events()
            .filter_map(|(i, event)| match event {
                GraspEvent::Grasp { grasp, .. } => Some((i, grasp)),
                GraspEvent::Release { .. } => None,
            })
            .collect()
    }

    /// The handle's releases: frame and the pose the event carries (the ghost's).
    fn releases(&self) -> Vec<(usize, Isometry3<f64>)> {
        self.handle_events()
            .filter_map(|(i, event)| match event {
                GraspEvent::Release { pose, .. } => Some((i, pose)),
                GraspEvent::Grasp { .. } => None,
            })
            .collect()
    }
}

/// The scripted handle, 24 cm long instead of 12 (the hand closes on the same cross-section),
/// so that one end reaches past the hand over a table that the hand itself never touches.
fn handle_and_table() -> Vec<Part> {
    let script = ScriptedGrasp::PowerOnHandle;
    let handle = shapes::cylinder(0.016, 0.24, 2_000);
    let table = shapes::cuboid(Vector3::new(0.2, 0.3, 0.05), 400);
    let table_pose = Isometry3::from(Translation3::new(
        TABLE_EDGE + 0.1,
        0.075,
        TABLE_TOP - 0.025,
    ));
    vec![
        part("handle", handle, script.part_pose(), true),
        part("table", table, table_pose, false),
    ]
}

/// The scripted power grasp up to the closed fist, then the hand pressing 3 cm down.
fn grasp_and_press_down() -> Vec<Keyframe> {
    let mut keys = ScriptedGrasp::PowerOnHandle.keyframes();
    let grasped_by = ScriptedGrasp::PowerOnHandle.milestones().grasped_by;
    keys.retain(|k| k.time <= grasped_by);
    let last = *keys.last().expect("keyframes");
    let mut pressed = last;
    pressed.tracker = Translation3::new(0.0, 0.0, -0.03) * last.tracker;
    for (dt, key) in [(0.3, pressed), (0.35, pressed)] {
        keys.push(Keyframe {
            time: last.time + dt,
            ..key
        });
    }
    keys
}

/// The lowest point of the handle at `pose` over the table (which starts at x = 0.08).
fn lowest(parts: &[Part], pose: &Isometry3<f64>) -> f64 {
    parts[HANDLE as usize]
        .mesh
        .vertices()
        .iter()
        .map(|v| pose * v)
        .filter(|v| v.x >= TABLE_EDGE)
        .map(|v| v.z)
        .fold(f64::INFINITY, f64::min)
}

/// Checks every frame of a run among the handle and the table: the visible handle never
/// intersects the table (by parry) nor goes below its top. Returns how deep the ghost went.
fn assert_visible_handle_never_enters_the_table(run: &Run) -> f64 {
    let oracle = Oracle::new(&run.parts);
    let table_pose = run.parts[TABLE as usize].pose;
    let mut ghost_depth = 0.0_f64;
    for (i, pose) in run.handle_poses.iter().enumerate() {
        assert!(
            !oracle.intersects(HANDLE, pose, TABLE, &table_pose),
            "frame {i}: the visible handle intersects the table"
        );
        assert!(
            lowest(&run.parts, pose) > TABLE_TOP,
            "frame {i}: the visible handle is below the table top"
        );
        if let Some(held) = &run.frames[i].held {
            ghost_depth = ghost_depth.max(TABLE_TOP - lowest(&run.parts, &held.ghost));
        }
    }
    ghost_depth
}

#[test]
fn a_grasped_handle_follows_the_hand_where_nothing_is_in_the_way() {
    let script = ScriptedGrasp::PowerOnHandle;
    let milestones = script.milestones();
    let start = script.part_pose();
    let parts = vec![part("handle", script.part_mesh(2_000), start, true)];
    let mut keys = script.keyframes();
    keys.retain(|k| k.time <= milestones.carried);
    let mut run = Run::new(parts, keys[0].tracker);
    run.play(&keys);

    let (grasps, releases) = (run.grasps(), run.releases());
    assert_eq!(grasps.len(), 1, "one grasp: {grasps:?}");
    let (grasped_at, grasp) = grasps[0];
    assert_eq!(grasp, GraspClass::Power);
    assert!(grasped_at as f64 <= milestones.grasped_by * RATE);
    assert!(releases.is_empty(), "released while carried: {releases:?}");

    let machine = run
        .interaction
        .slide_machine(0)
        .expect("the handle is held");
    let (_, radius) = SlideBody::<DopTree>::new(run.parts[0].mesh.clone()).pivot_and_radius();
    for (i, frame) in run.frames.iter().enumerate().skip(grasped_at) {
        let held = frame.held.as_ref().expect("held from the grasp on");
        assert_eq!(held.rest, RestReason::Reached, "frame {i}");
        assert_eq!(held.visible, run.handle_poses[i]);
        let lag = pose_distance(&held.visible, &held.ghost, radius);
        assert!(
            lag <= 2.0 * machine.tolerance(),
            "frame {i}: visible {lag:.2e} m from the ghost"
        );
    }
    // It was carried away and turned with the hand.
    let end = run.handle_poses.last().expect("frames");
    assert!((end.translation.vector - start.translation.vector).norm() > 0.08);
    assert!(end.rotation.angle_to(&start.rotation) > 0.3);
}

#[test]
fn a_handle_pressed_into_a_table_slides_on_it_and_never_enters_it() {
    let parts = handle_and_table();
    let keys = grasp_and_press_down();
    let mut run = Run::new(parts, keys[0].tracker);
    run.play(&keys);

    let (grasps, releases) = (run.grasps(), run.releases());
    assert_eq!(grasps.len(), 1, "one grasp: {grasps:?}");
    assert!(releases.is_empty(), "released while pressed: {releases:?}");
    let ghost_depth = assert_visible_handle_never_enters_the_table(&run);
    assert!(
        ghost_depth > 0.015,
        "the ghost went only {ghost_depth} m into the table"
    );
    // The handle rests on the table, not where it was grasped.
    let end = run.handle_poses.last().expect("frames");
    let gap = lowest(&run.parts, end) - TABLE_TOP;
    assert!(gap < 0.001, "the handle stays {gap} m above the table");
    let held = run
        .frames
        .last()
        .and_then(|f| f.held.clone())
        .expect("held");
    assert!(
        run.interaction
            .slide_machine(0)
            .expect("held")
            .contacts()
            .next()
            .is_some()
    );
    assert!(held.visible != held.ghost);
}

#[test]
fn opening_the_hand_leaves_the_handle_at_its_last_valid_pose() {
    let parts = handle_and_table();
    let mut keys = grasp_and_press_down();
    let pressed = *keys.last().expect("keyframes");
    for (dt, flex) in [(0.2, open_hand()), (0.3, open_hand())] {
        keys.push(Keyframe {
            time: pressed.time + dt,
            flex,
            ..pressed
        });
    }
    let mut run = Run::new(parts, keys[0].tracker);
    run.play(&keys);

    let (grasps, releases) = (run.grasps(), run.releases());
    assert_eq!(grasps[0].1, GraspClass::Power);
    let (released_at, ghost) = *releases.first().expect("the open hand releases the handle");
    assert!(released_at as f64 > pressed.time * RATE);
    assert!(run.frames[released_at].held.is_none());
    // The handle stays where sliding last left it, above the table, not at the ghost's pose
    // under its top, and the opening fingers, still brushing it, do not take hold of it
    // again.
    let last_valid = run.handle_poses[released_at - 1];
    assert!(lowest(&run.parts, &ghost) < TABLE_TOP - 0.015);
    assert_eq!(grasps.len(), 1, "grasped once: {grasps:?}");
    for (i, pose) in run.handle_poses.iter().enumerate().skip(released_at) {
        assert_eq!(*pose, last_valid, "frame {i}");
    }
    assert_visible_handle_never_enters_the_table(&run);
}

/// The scripted hand-over (`scene::hand_over`): the right hand grasps the handle, the left
/// takes it over in the frame it grasps it, the right opens and withdraws without another
/// event, and the left pushes the handle into the block's hole and lets go.
#[test]
fn the_left_hand_takes_the_handle_over_from_the_right_and_inserts_it() {
    use vas_protocol::EventKind;
    use vas_testkit::script::HANDLE_RADIUS;
    use vas_testkit::script::hand_over::{self, MILESTONES};
    const RATE: f64 = 200.0;
    let start = hand_over::handle_pose();
    let parts = vec![
        part("handle", hand_over::handle_mesh(3_000), start, true),
        part(
            "block",
            hand_over::block_mesh(3_000),
            hand_over::block_pose(),
            false,
        ),
    ];
    let [right, left] = hand_over::keyframes().map(|keys| sample(&keys, RATE));
    assert_eq!(right.len(), left.len(), "one time line");
    let right_model = Arc::new(right_hand());
    let left_model = Arc::new(right_model.mirrored());
    let hands = [(right_model, &right[0]), (left_model, &left[0])]
        .map(|(model, first)| {
            let parked = HandPose {
                root: first.tracker,
                flex: [0.0; FLEX_COUNT],
            };
            GraspingHand::new(model, GraspParams::default(), parked).expect("segments build")
        })
        .into();
    let mut interaction = Interaction::new(
        hands,
        &parts,
        SlideParams::default(),
        UnheldParams::held_only(),
        1.0 / RATE,
    );
    let mut events = Vec::new();
    for (frame, (right, left)) in right.iter().zip(&left).enumerate() {
        let stepped = interaction.step(&[
            HandTarget::tracking(right.input()),
            HandTarget::tracking(left.input()),
        ]);
        for (hand, stepped) in stepped.iter().enumerate() {
            events.extend(stepped.hand.events.iter().map(|event| {
                let kind = match *event {
                    GraspEvent::Grasp { .. } => EventKind::Grasp,
                    GraspEvent::Release { part, .. } if stepped.handed_over.contains(&part) => {
                        EventKind::HandOver
                    }
                    GraspEvent::Release { .. } => EventKind::Release,
                };
                (frame, hand, kind)
            }));
        }
    }
    // As the server publishes them: a hand-over after the grasp of its frame.
    events.sort_by_key(|&(frame, _, kind)| (frame, kind == EventKind::HandOver));
    let kinds: Vec<(usize, EventKind)> =
        events.iter().map(|&(_, hand, kind)| (hand, kind)).collect();
    assert_eq!(
        kinds,
        [
            (0, EventKind::Grasp),
            (1, EventKind::Grasp),
            (0, EventKind::HandOver),
            (1, EventKind::Release)
        ],
        "{events:?}"
    );
    let at = |index: usize| events[index].0 as f64 / RATE;
    assert!(at(0) <= MILESTONES.right_grasped_by, "{events:?}");
    assert!(at(1) <= MILESTONES.left_grasped_by, "{events:?}");
    assert_eq!(
        events[1].0, events[2].0,
        "the hand-over comes with the grasp"
    );
    assert!(at(3) > MILESTONES.inserted, "{events:?}");
    // Pushed along its axis into the hole, sunk the few millimetres the hands' scripts press.
    let end = interaction.part_pose(HANDLE).expect("the handle");
    let moved = end.translation.vector - start.translation.vector;
    assert!(
        (hand_over::INSERT - 0.002..=hand_over::INSERT + 0.001).contains(&-moved.x)
            && moved.yz().norm() < hand_over::HOLE_RADIUS - HANDLE_RADIUS,
        "the handle moved by {moved:?}"
    );
    assert!(end.rotation.angle_to(&start.rotation) < 0.05);
}
