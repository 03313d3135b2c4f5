//! The clasp minimisation (PAPER §4) against balls and a floor, and its parameters.

use std::f64::consts::FRAC_PI_2;

use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use vas_server::grasping::clasp::{
    ClaspOutcome, ClaspParams, ClaspPlan, HandPose, ObjectSet, SEGMENT_COUNT, clasp,
};
use vas_server::grasping::model::{FLEX_COUNT, FlexVector, HandModel, SegmentId};
use vas_testkit::balls::BallWorld;
use vas_testkit::hand_models::right_hand;

const INDEX_MCP: usize = 4;
const MCPS: [usize; 4] = [4, 7, 11, 15];

#[test]
fn a_table_with_some_keys_fills_the_rest_with_defaults() {
    let params: ClaspParams = toml::from_str("flex_tolerance = 0.01\nmax_steps = 12").unwrap();
    params.validate().unwrap();
    assert_eq!((params.flex_tolerance, params.max_steps), (0.01, 12));
    let defaults = ClaspParams::default();
    defaults.validate().unwrap();
    assert_eq!(params.root_tolerance, defaults.root_tolerance);
    assert_eq!(params.max_motion, defaults.max_motion);
}

#[test]
fn bad_clasp_values_are_refused_with_their_key() {
    let unknown = toml::from_str::<ClaspParams>("max_iterations = 16").unwrap_err();
    assert!(unknown.to_string().contains("max_iterations"), "{unknown}");
    for (text, key) in [
        ("flex_tolerance = inf", "flex_tolerance"),
        ("flex_tolerance = 0.6", "flex_tolerance"),
        ("root_tolerance = -1e-3", "root_tolerance"),
        ("max_motion = 0.0", "max_motion"),
        ("max_steps = 0", "max_steps"),
        ("max_steps = 10001", "max_steps"),
    ] {
        let params: ClaspParams = toml::from_str(text).unwrap();
        assert_eq!(params.validate().unwrap_err().key, key, "{text}");
    }
}

fn at_height(z: f64, flex: FlexVector) -> HandPose {
    HandPose {
        root: Isometry3::translation(0.0, 0.0, z),
        flex,
    }
}

fn unlimited() -> ClaspParams {
    ClaspParams {
        max_motion: f64::INFINITY,
        ..ClaspParams::default()
    }
}

fn segment(model: &HandModel, name: &str) -> SegmentId {
    model
        .segments()
        .iter()
        .position(|s| s.name == name)
        .unwrap()
}

fn floor() -> BallWorld {
    BallWorld {
        floor: Some(0.0),
        ..BallWorld::default()
    }
}

#[test]
fn a_free_target_is_reached_in_one_step_per_stage() {
    let model = right_hand();
    let plan = ClaspPlan::new(&model);
    let world = BallWorld {
        floor: Some(-1.0),
        ..BallWorld::default()
    };
    let mut target = at_height(0.1, [0.3; FLEX_COUNT]);
    target.root.rotation = UnitQuaternion::from_euler_angles(0.2, -0.1, 0.4);
    let start = at_height(0.0, [0.0; FLEX_COUNT]);
    let out = clasp(
        &model,
        &plan,
        &start,
        &target,
        &unlimited(),
        world.collider(&model),
    );
    assert!(out.reached_target);
    // One step for the root, one for the flex values.
    assert_eq!((out.steps, out.checks), (2, 2 * SEGMENT_COUNT as u32));
    assert!(out.touching.iter().all(|t| t.is_empty()));
    assert!((out.pose.root.translation.vector - target.root.translation.vector).norm() < 1e-12);
    assert!(out.pose.root.rotation.angle_to(&target.root.rotation) < 1e-12);
    assert_eq!(out.pose.flex, target.flex);
    // A hand that does not move needs no check at all.
    let still = clasp(
        &model,
        &plan,
        &start,
        &start,
        &unlimited(),
        world.collider(&model),
    );
    assert_eq!((still.steps, still.checks), (0, 0));
    assert!(still.reached_target);
}

#[test]
fn fingers_closing_onto_a_floor_stop_tight_against_it_and_touch_it() {
    let model = right_hand();
    let plan = ClaspPlan::new(&model);
    let world = floor();
    let start = at_height(0.05, [0.0; FLEX_COUNT]);
    let mut target = start;
    for v in MCPS {
        target.flex[v] = FRAC_PI_2;
    }
    let params = unlimited();
    let out = clasp(
        &model,
        &plan,
        &start,
        &target,
        &params,
        world.collider(&model),
    );
    assert!(
        world.hand_hits(&model, &out.pose).is_empty(),
        "the result collides"
    );
    for v in MCPS {
        let angle = out.pose.flex[v];
        assert!(angle > 0.3 && angle < FRAC_PI_2, "MCP {v}: {angle}");
        // Tight: closing further by a few tolerances collides.
        let mut deeper = out.pose;
        deeper.flex[v] += 3.0 * params.flex_tolerance;
        assert!(
            !world.hand_hits(&model, &deeper).is_empty(),
            "MCP {v} stopped short"
        );
    }
    for name in ["index outer", "middle outer", "ring outer", "pinky outer"] {
        assert_eq!(
            out.touching[segment(&model, name)],
            ObjectSet::single(0),
            "{name}"
        );
    }
    // The thumb does not move and does not reach the floor.
    for name in ["thumb inner", "thumb middle", "thumb outer"] {
        assert!(out.touching[segment(&model, name)].is_empty(), "{name}");
    }
    assert!(!out.reached_target);
}

#[test]
fn a_blocked_root_stops_at_the_floor_with_the_palm_touching() {
    let model = right_hand();
    let plan = ClaspPlan::new(&model);
    let world = floor();
    // An open flat hand: the thumb rolled back into the plane of the palm and spread. The
    // palm is the lowest part, 1.25 cm below the root; the thumb's metacarpal reaches
    // 0.2 cm + 0.95 cm.
    let mut open = [0.0; FLEX_COUNT];
    open[0] = -30f64.to_radians();
    open[3] = 45f64.to_radians();
    let params = unlimited();
    let (start, target) = (at_height(0.05, open), at_height(0.0, open));
    let out = clasp(
        &model,
        &plan,
        &start,
        &target,
        &params,
        world.collider(&model),
    );
    let z = out.pose.root.translation.z;
    assert!(z > 0.0125 && z < 0.0125 + params.root_tolerance, "{z}");
    assert!(out.touching[model.palm()].contains(0));
    assert!(out.touching[segment(&model, "thumb inner")].is_empty());
    // One step to the target, one just short of the tolerance, then bisection.
    assert!(out.steps <= 10, "{}", out.steps);
}

#[test]
fn random_minimisations_never_end_in_collision() {
    let model = right_hand();
    let plan = ClaspPlan::new(&model);
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let random_flex = |rng: &mut ChaCha8Rng| -> FlexVector {
        std::array::from_fn(|v| {
            let limit = &model.limits()[v];
            rng.random_range(limit.min..limit.max)
        })
    };
    let mut cases = 0;
    let mut reached = 0;
    let mut touched = 0;
    while cases < 300 {
        let world = BallWorld {
            floor: None,
            balls: (0..rng.random_range(2..6))
                .map(|_| {
                    let x = rng.random_range(-0.1..0.1);
                    let y = rng.random_range(-0.05..0.2);
                    let z = rng.random_range(-0.1..0.1);
                    (Point3::new(x, y, z), rng.random_range(0.005..0.03))
                })
                .collect(),
        };
        let start = HandPose {
            root: Isometry3::identity(),
            flex: random_flex(&mut rng),
        };
        if !world.hand_hits(&model, &start).is_empty() {
            continue;
        }
        let offset = Vector3::from_fn(|_, _| rng.random_range(-0.03..0.03));
        let turn = Vector3::from_fn(|_, _| rng.random_range(-0.4..0.4));
        let target = HandPose {
            root: Isometry3::new(offset, turn),
            flex: random_flex(&mut rng),
        };
        let out = clasp(
            &model,
            &plan,
            &start,
            &target,
            &unlimited(),
            world.collider(&model),
        );
        cases += 1;
        assert!(
            world.hand_hits(&model, &out.pose).is_empty(),
            "case {cases} ends in collision"
        );
        for v in 0..FLEX_COUNT {
            let (a, b) = (
                start.flex[v].min(target.flex[v]),
                start.flex[v].max(target.flex[v]),
            );
            assert!(out.pose.flex[v] >= a - 1e-12 && out.pose.flex[v] <= b + 1e-12);
        }
        // The root moves first with the flex values where they were: when that and the
        // target are free, the target is reached.
        let root_first = HandPose {
            root: target.root,
            flex: start.flex,
        };
        let path_free = world.hand_hits(&model, &target).is_empty()
            && world.hand_hits(&model, &root_first).is_empty();
        assert_eq!(out.reached_target, path_free, "case {cases}");
        assert!(out.steps <= 2 * ClaspParams::default().max_steps);
        reached += usize::from(path_free);
        touched += usize::from(out.touching.iter().any(|t| !t.is_empty()));
    }
    // The cases exercise both outcomes.
    assert!(
        reached > 20 && cases - reached > 20,
        "{reached} of {cases} free"
    );
    assert!(touched > 20, "{touched}");
}

#[test]
fn a_jump_is_approached_by_at_most_the_largest_motion() {
    let model = right_hand();
    let plan = ClaspPlan::new(&model);
    let world = BallWorld::default();
    let params = ClaspParams::default();
    let mut target = at_height(0.1, [0.0; FLEX_COUNT]);
    target.flex[INDEX_MCP] = 1.0;
    let start = at_height(0.0, [0.0; FLEX_COUNT]);
    let out = clasp(
        &model,
        &plan,
        &start,
        &target,
        &params,
        world.collider(&model),
    );
    assert!(!out.reached_target);
    assert!((out.pose.root.translation.z - params.max_motion).abs() < 1e-12);
    let index_motion = out.pose.flex[INDEX_MCP] * model.lever(INDEX_MCP);
    assert!((index_motion - params.max_motion).abs() < 1e-12);
}

#[test]
fn the_step_cap_leaves_unfixed_values_at_their_valid_end() {
    let model = right_hand();
    let plan = ClaspPlan::new(&model);
    let world = floor();
    let start = at_height(0.05, [0.0; FLEX_COUNT]);
    let mut target = at_height(-0.02, [0.0; FLEX_COUNT]);
    target.flex[INDEX_MCP] = 1.2;
    let params = ClaspParams {
        max_steps: 1,
        ..unlimited()
    };
    let out = clasp(
        &model,
        &plan,
        &start,
        &target,
        &params,
        world.collider(&model),
    );
    // One step per stage: the root and the finger both collide at their targets.
    assert_eq!(out.steps, 2);
    assert_eq!(out.pose.root, start.root);
    assert_eq!(out.pose.flex[INDEX_MCP], 0.0);
    assert!(out.touching[model.palm()].contains(0));
}

/// One minimisation from `start` toward a target where the index MCP closes a little and
/// the DIP a long way; the tip collides only while the MCP is past `mcp_limit` or the DIP
/// past `dip_limit`.
fn tip_run(start: &HandPose, mcp_limit: f64, dip_limit: f64) -> ClaspOutcome {
    let model = right_hand();
    let plan = ClaspPlan::new(&model);
    let tip = segment(&model, "index outer");
    let mut target = at_height(0.0, [0.0; FLEX_COUNT]);
    target.flex[4] = 0.1;
    target.flex[6] = 1.4;
    clasp(
        &model,
        &plan,
        start,
        &target,
        &unlimited(),
        |s, placement| {
            // Recover the joint angles from the tip's pose: its origin swings about the MCP (at
            // y = 0.095 on the palm), its rotation about -x is MCP + DIP (the PIP stays at 0).
            let origin = placement.local.translation.vector;
            let mcp = (-origin.z).atan2(origin.y - 0.095);
            let dip = placement.local.rotation.scaled_axis().x.abs() - mcp;
            let collides = s == tip && (mcp > mcp_limit || dip > dip_limit);
            if collides {
                ObjectSet::single(0)
            } else {
                ObjectSet::EMPTY
            }
        },
    )
}

#[test]
fn fixing_a_joint_clears_the_flags_of_the_segments_it_carries() {
    let model = right_hand();
    let tip = segment(&model, "index outer");
    let rest = at_height(0.0, [0.0; FLEX_COUNT]);
    // The tip's collisions come from the MCP: once the MCP is fixed they are forgotten and
    // the tip is not touching. (The DIP, blamed for the tip's collisions too, stops short of
    // its target in this minimisation.)
    let out = tip_run(&rest, 0.05, f64::INFINITY);
    assert!(out.touching[tip].is_empty());
    assert!(out.pose.flex[6] > 0.0 && out.pose.flex[6] < 1.4);
    let mcp = out.pose.flex[4];
    assert!(mcp < 0.05 && mcp > 0.05 - 0.001, "{mcp}");

    // The tip's collisions come from its own joint. The MCP, blamed too and fixed first,
    // clears the tip's flag, and the DIP gets fixed just short of the contact without
    // colliding again: not touching yet.
    let first = tip_run(&rest, f64::INFINITY, 0.7);
    let tolerance = ClaspParams::default().flex_tolerance;
    let dip = first.pose.flex[6];
    assert!(dip < 0.7 && dip > 0.7 - tolerance, "{dip}");
    assert!(first.touching[tip].is_empty());
    // In the next frame the hand starts at the contact: the step just past it collides, both
    // values are fixed in the same step, the DIP first, and the tip is touching.
    let second = tip_run(&first.pose, f64::INFINITY, 0.7);
    assert_eq!(second.touching[tip], ObjectSet::single(0));
    assert_eq!(second.steps, 2);
    assert_eq!(second.pose.flex, first.pose.flex);
}
