//! Pushed and settling parts among static ones, checked after every frame by parry (in
//! millimetres), an oracle independent of the DOP-trees the sliding machinery uses.

use std::sync::Arc;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use parry3d::query::{distance, intersection_test};

use super::*;
use crate::collision::orientation::DEFAULT_K;
use crate::collision::parry_mesh::{millimetre_pose, millimetre_trimesh};
use crate::geometry::{TriMesh, shapes};
use crate::scene::{Part, PartTree, ReleaseMode, ReleaseParams};

/// Sliding frames per second, as the scenes' default sliding rate.
const RATE: f64 = 500.0;

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

fn cube(size: f64) -> TriMesh {
    shapes::cuboid(Vector3::repeat(size), 200)
}

fn at(x: f64, y: f64, z: f64) -> Isometry3<f64> {
    Isometry3::translation(x, y, z)
}

/// A static wall whose face is at x = 0.05, the height of a cube at the origin and more.
fn wall_at_five_centimetres() -> Part {
    part(
        "wall",
        shapes::cuboid(Vector3::new(0.02, 0.2, 0.2), 200),
        at(0.06, 0.0, 0.0),
        false,
    )
}

/// A scene of parts, part 0 the one that moves, with pushing on and settling parts.
struct Bench {
    parts: Vec<Part>,
    slide: Vec<SlidePart>,
    poses: Vec<Isometry3<f64>>,
    unheld: Unheld,
}

impl Bench {
    fn new(parts: Vec<Part>, release: ReleaseParams) -> Bench {
        let params = UnheldParams {
            push: crate::scene::PushParams { enabled: true },
            release,
        };
        Bench {
            slide: parts.iter().map(SlidePart::of).collect(),
            poses: parts.iter().map(|p| p.pose).collect(),
            unheld: Unheld::new(params, &SlideParams::default(), 1.0 / RATE, 1),
            parts,
        }
    }

    /// One frame with part 0 pushed by `displacement` (none: no hand touches it), then parry's
    /// verdict: no part overlaps another.
    fn frame(&mut self, displacement: Option<Vector3<f64>>) {
        let pushes: Vec<Push> = (displacement.into_iter())
            .map(|displacement| Push {
                part: 0,
                displacement,
            })
            .collect();
        (self.unheld).frame(&self.slide, &mut self.poses, &[], &[&pushes]);
        for other in 1..self.parts.len() {
            assert!(
                !self.overlap(0, other),
                "{} enters {} at {:?}",
                self.parts[0].name,
                self.parts[other].name,
                self.poses[0].translation
            );
        }
    }

    fn overlap(&self, a: usize, b: usize) -> bool {
        let mesh = |i: usize| millimetre_trimesh(&self.parts[i].mesh);
        let pose = |i: usize| millimetre_pose(&self.poses[i]);
        intersection_test(&pose(a), &mesh(a), &pose(b), &mesh(b)).expect("meshes are supported")
    }

    /// Asserts that parts `a` and `b` are apart by at most a millimetre: resting contact.
    fn assert_within_a_millimetre(&self, a: usize, b: usize, other: &str) {
        let gap = self.gap(a, b);
        assert!((0.0..=0.001).contains(&gap), "{gap} m from {other}");
    }

    /// The distance between parts `a` and `b` by parry (metres).
    fn gap(&self, a: usize, b: usize) -> f64 {
        let mesh = |i: usize| millimetre_trimesh(&self.parts[i].mesh);
        let pose = |i: usize| millimetre_pose(&self.poses[i]);
        let mm = distance(&pose(a), &mesh(a), &pose(b), &mesh(b)).expect("meshes are supported");
        f64::from(mm) / 1000.0
    }

    /// Releases part 0 and runs frames until it rests; how many it took.
    fn settle(&mut self) -> usize {
        self.unheld.released(0, &self.slide);
        let mut frames = 0;
        while self.unheld.has_motion_left() {
            self.frame(None);
            frames += 1;
            assert!(frames < 10_000, "still settling");
        }
        frames
    }

    fn lowest(&self, part: usize) -> f64 {
        (self.parts[part].mesh.vertices().iter())
            .map(|v| (self.poses[part] * v).z)
            .fold(f64::INFINITY, f64::min)
    }
}

fn settling() -> ReleaseParams {
    ReleaseParams {
        floor: -1.0,
        ..ReleaseParams::default()
    }
}

#[test]
fn a_part_released_above_a_table_lands_on_it_within_half_a_second() {
    // The table's top at z = 0; the cube's lowest point 5 cm above it.
    let table = part(
        "table",
        shapes::cuboid(Vector3::new(0.4, 0.4, 0.02), 200),
        at(0.0, 0.0, -0.01),
        false,
    );
    let block = part("block", cube(0.04), at(0.01, 0.02, 0.07), true);
    let mut bench = Bench::new(vec![block, table], settling());
    let frames = bench.settle();
    assert!(frames as f64 / RATE <= 0.5, "{frames} frames");
    bench.assert_within_a_millimetre(0, 1, "the table");
    let moved = bench.poses[0].translation.vector - Vector3::new(0.01, 0.02, 0.07);
    assert!(moved.xy().norm() < 1e-6, "drifted sideways by {moved:?}");
}

#[test]
fn a_part_released_above_a_gentle_slope_stays_where_it_lands() {
    let slope = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 10f64.to_radians());
    let plane = Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.0), slope);
    let table = part(
        "slope",
        shapes::cuboid(Vector3::new(0.4, 0.4, 0.02), 200),
        plane,
        false,
    );
    let block = part("block", cube(0.04), at(0.0, 0.0, 0.1), true);
    let mut bench = Bench::new(vec![block, table], settling());
    bench.settle();
    bench.assert_within_a_millimetre(0, 1, "the slope");
    let moved = bench.poses[0].translation.vector.xy();
    assert!(moved.norm() < 0.005, "slid {moved:?} along the slope");
}

#[test]
fn a_part_with_nothing_below_stops_at_the_floor() {
    let block = part("block", cube(0.04), at(0.0, 0.0, 0.3), true);
    let far = part("far", cube(0.04), at(1.0, 0.0, 0.0), false);
    let release = ReleaseParams {
        floor: 0.05,
        ..ReleaseParams::default()
    };
    let mut bench = Bench::new(vec![block, far], release);
    bench.settle();
    assert!((bench.lowest(0) - 0.05).abs() < 1e-9, "{}", bench.lowest(0));
}

#[test]
fn a_part_pushed_into_a_wall_stops_at_it() {
    // The wall's face at x = 0.05; the block's at x = 0.02 before the push.
    let wall = wall_at_five_centimetres();
    let block = part("block", cube(0.04), at(0.0, 0.0, 0.0), true);
    let mut bench = Bench::new(vec![block, wall], settling());
    // Not quite square to the wall, as a palm pushes: friction holds the block there.
    let push = Vector3::new(0.005, 0.0003, 0.0005);
    for _ in 0..20 {
        bench.frame(Some(push));
    }
    bench.assert_within_a_millimetre(0, 1, "the wall");
    let along = bench.poses[0].translation.vector.yz();
    let before_the_wall = push.yz() * (0.03 / push.x);
    assert!(
        (along - before_the_wall).norm() < 0.0005,
        "slid {along:?} along the wall"
    );
    assert!(!bench.unheld.has_motion_left());
}

#[test]
fn a_slider_pushed_along_its_slot_stops_at_the_slot_end() {
    // A slot along x between two rails 1 mm wider apart than the slider and taller than it,
    // closed at x = 0.1.
    let rail = |y: f64| {
        part(
            "rail",
            shapes::cuboid(Vector3::new(0.3, 0.02, 0.06), 200),
            at(0.0, y, 0.0),
            false,
        )
    };
    let end = part(
        "end",
        shapes::cuboid(Vector3::new(0.02, 0.1, 0.06), 200),
        at(0.11, 0.0, 0.0),
        false,
    );
    let slider = part("slider", cube(0.04), at(0.0, 0.0, 0.0), true);
    let mut bench = Bench::new(vec![slider, rail(0.0305), rail(-0.0305), end], settling());
    // Pushed along the slot and a little into one rail: it slides along the rail.
    for _ in 0..40 {
        bench.frame(Some(Vector3::new(0.004, 0.001, 0.0)));
    }
    bench.assert_within_a_millimetre(0, 3, "the slot's end");
    assert!(bench.poses[0].translation.y.abs() <= 0.0005 + 1e-9);
}

#[test]
fn a_push_begins_when_the_hand_moves_the_part_and_lasts_while_it_touches() {
    let block = part("block", cube(0.04), at(0.0, 0.0, 0.0), true);
    let mut bench = Bench::new(vec![block], settling());
    // A hand resting on the part moves nothing and pushes nothing.
    bench.frame(Some(Vector3::zeros()));
    assert!(bench.unheld.pushed_by(0).is_empty());
    assert_eq!(bench.poses[0], at(0.0, 0.0, 0.0));
    // Its motion into the part moves it: a push, named by its part.
    bench.frame(Some(Vector3::new(0.001, 0.0, 0.0)));
    assert_eq!(bench.unheld.pushed_by(0), [0]);
    assert!((bench.poses[0].translation.x - 0.001).abs() < 1e-9);
    // Resting on it again, the hand still pushes it; it moves no farther.
    bench.frame(Some(Vector3::zeros()));
    assert_eq!(bench.unheld.pushed_by(0), [0]);
    assert!((bench.poses[0].translation.x - 0.001).abs() < 1e-9);
    bench.frame(None);
    assert!(bench.unheld.pushed_by(0).is_empty());
}

#[test]
fn a_touch_that_cannot_move_the_part_is_no_push() {
    // The wall's face at x = 0.05; the block, left where it is let go, first pushed to it.
    let wall = wall_at_five_centimetres();
    let block = Part {
        release: Some(ReleaseMode::Stay),
        ..part("block", cube(0.04), at(0.0, 0.0, 0.0), true)
    };
    let mut bench = Bench::new(vec![block, wall], settling());
    let push = Vector3::new(0.005, 0.0, 0.0);
    for _ in 0..10 {
        bench.frame(Some(push));
    }
    bench.assert_within_a_millimetre(0, 1, "the wall");
    bench.frame(None);
    let against_the_wall = bench.poses[0];
    bench.frame(Some(push));
    assert!(bench.unheld.pushed_by(0).is_empty());
    let moved = bench.poses[0].translation.vector - against_the_wall.translation.vector;
    assert!(moved.norm() < 1e-5, "moved {moved:?}");
}

/// The table of the turning tests: its top at z = 0.
fn table() -> Part {
    part(
        "table",
        shapes::cuboid(Vector3::new(0.4, 0.4, 0.02), 200),
        at(0.0, 0.0, -0.01),
        false,
    )
}

/// A slab tilted `degrees` about x, its top face through the origin, and its tilt.
fn slope(degrees: f64) -> (Part, UnitQuaternion<f64>) {
    let tilt = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), degrees.to_radians());
    let centre = tilt * Vector3::new(0.0, 0.0, -0.01);
    let pose = Isometry3::from_parts(Translation3::from(centre), tilt);
    let slab = part(
        "slope",
        shapes::cuboid(Vector3::new(0.4, 0.4, 0.02), 200),
        pose,
        false,
    );
    (slab, tilt)
}

/// The fixtures' peg: 8 cm long, 9 mm in radius, along its z axis.
fn peg(pose: Isometry3<f64>) -> Part {
    part("peg", shapes::cylinder(0.009, 0.08, 2000), pose, true)
}

/// The angle (degrees) between `up` and the nearest of the block's face normals at `pose`.
fn tilt_degrees(pose: &Isometry3<f64>, up: &Vector3<f64>) -> f64 {
    let axes = [Vector3::x(), Vector3::y(), Vector3::z()];
    (axes.iter())
        .map(|axis| {
            (pose.rotation * axis)
                .dot(up)
                .abs()
                .min(1.0)
                .acos()
                .to_degrees()
        })
        .fold(f64::INFINITY, f64::min)
}

impl Bench {
    /// Runs `frames` more frames without input: nothing moves a part at rest.
    fn stays(&mut self, frames: usize) {
        let rested = self.poses.clone();
        for _ in 0..frames {
            self.frame(None);
        }
        assert!(!self.unheld.has_motion_left());
        assert_eq!(self.poses, rested, "moved again at rest");
    }
}

#[test]
fn a_block_released_tilted_lands_on_its_edge_and_tips_flat() {
    let tilted = Isometry3::from_parts(
        Translation3::new(0.0, 0.0, 0.06),
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 20f64.to_radians()),
    );
    let block = part("block", cube(0.04), tilted, true);
    let mut bench = Bench::new(vec![block, table()], settling());
    let frames = bench.settle();
    assert!(frames as f64 / RATE <= 0.5, "{frames} frames");
    let tilt = tilt_degrees(&bench.poses[0], &Vector3::z());
    assert!(tilt < 1.0, "rests tilted {tilt} degrees");
    bench.assert_within_a_millimetre(0, 1, "the table");
    // It turned about its lower edge, towards the side its centre of mass overhung.
    let turned = (bench.poses[0].rotation)
        .angle_to(&tilted.rotation)
        .to_degrees();
    assert!((turned - 20.0).abs() < 1.0, "turned {turned} degrees");
    let sideways = bench.poses[0].translation.x;
    assert!(
        sideways.abs() < 0.001,
        "drifted {sideways} m along its edge"
    );
    bench.stays(50);
}

#[test]
fn a_block_resting_on_its_edge_tips_onto_the_face_below_its_centre() {
    // Turned 35 degrees about x, its lowest edge 0.2 mm above the table: it falls back onto the
    // face 35 degrees off, not forwards onto the one 55 degrees off.
    let lowest = 0.02 * (35f64.to_radians().cos() + 35f64.to_radians().sin());
    let start = Isometry3::from_parts(
        Translation3::new(0.0, 0.0, lowest + 0.0002),
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 35f64.to_radians()),
    );
    let block = part("block", cube(0.04), start, true);
    let mut bench = Bench::new(vec![block, table()], settling());
    let frames = bench.settle();
    assert!(frames as f64 / RATE <= 0.5, "{frames} frames");
    assert!(
        bench.poses[0].rotation.angle() < 1f64.to_radians(),
        "{:?}",
        bench.poses[0]
    );
    bench.assert_within_a_millimetre(0, 1, "the table");
    bench.stays(50);
}

#[test]
fn a_block_resting_flat_stays_still() {
    let start = at(0.01, -0.02, 0.0201);
    let block = part("block", cube(0.04), start, true);
    let mut bench = Bench::new(vec![block, table()], settling());
    bench.settle();
    let moved = bench.poses[0].translation.vector - start.translation.vector;
    assert!(moved.norm() < 2e-4, "moved {moved:?}");
    assert!(bench.poses[0].rotation.angle() < 1e-9, "turned");
}

#[test]
fn a_block_resting_on_a_gentle_slope_neither_slides_nor_tips() {
    let (slab, tilt) = slope(10.0);
    // The block sits on the slope, 0.1 mm off its top face.
    let centre = tilt * Vector3::z() * 0.0201;
    let start = Isometry3::from_parts(Translation3::from(centre), tilt);
    let block = part("block", cube(0.04), start, true);
    let mut bench = Bench::new(vec![block, slab], settling());
    bench.settle();
    let moved = bench.poses[0].translation.vector - start.translation.vector;
    assert!(moved.norm() < 2e-4, "moved {moved:?}");
    let turned = bench.poses[0].rotation.angle_to(&tilt).to_degrees();
    assert!(turned < 1e-6, "turned {turned} degrees");
}

#[test]
fn a_block_landing_on_a_gentle_slope_tips_onto_its_face_there() {
    let (slab, tilt) = slope(10.0);
    let block = part("block", cube(0.04), at(0.0, 0.0, 0.1), true);
    let mut bench = Bench::new(vec![block, slab], settling());
    bench.settle();
    let tilt = tilt_degrees(&bench.poses[0], &(tilt * Vector3::z()));
    assert!(tilt < 1.0, "rests {tilt} degrees off the slope");
    bench.assert_within_a_millimetre(0, 1, "the slope");
    bench.stays(50);
}

#[test]
fn a_peg_landing_on_its_rim_on_a_gentle_slope_tips_onto_its_end_and_stays() {
    let (slab, tilt) = slope(10.0);
    let mut bench = Bench::new(vec![peg(at(0.0, 0.0, 0.08)), slab], settling());
    let frames = bench.settle();
    assert!(frames as f64 / RATE <= 0.5, "{frames} frames");
    // Its axis along the slope's normal: standing on its end face, not on its rim.
    let axis = bench.poses[0].rotation * Vector3::z();
    let off = axis.angle(&(tilt * Vector3::z())).to_degrees();
    assert!(off < 1.0, "rests {off} degrees off the slope's normal");
    bench.assert_within_a_millimetre(0, 1, "the slope");
    // It turned about the rim it landed on, and slid nowhere: its end's middle is where the
    // upright peg's was, but for the turn about the rim.
    let end = bench.poses[0] * nalgebra::Point3::new(0.0, 0.0, -0.04);
    assert!(end.xy().coords.norm() < 0.001, "its end is at {end:?}");
    bench.stays(100);
}

#[test]
fn a_peg_lying_across_a_slope_rolls_no_more_than_half_a_turn() {
    // Lying along x across the slope's fall line: its support, a line along its side, never
    // holds it; it rolls down, and the bound on the turn stops it.
    let (slab, _) = slope(10.0);
    let lying = Isometry3::from_parts(
        Translation3::new(0.0, 0.0, 0.02),
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2),
    );
    let mut bench = Bench::new(vec![peg(lying), slab], settling());
    bench.settle();
    let turned = bench.poses[0].rotation.angle_to(&lying.rotation);
    assert!(
        turned <= std::f64::consts::PI + 0.01,
        "turned {} degrees",
        turned.to_degrees()
    );
    assert!(turned > 0.1, "did not roll at all");
    bench.stays(50);
}

#[test]
fn a_block_pushed_over_a_table_edge_falls_and_one_still_on_it_stays() {
    // The table's edge at x = 0.2; the block's middle starts 3 cm before it, resting on the top.
    let start = at(0.17, 0.0, 0.0201);
    let floor = ReleaseParams {
        floor: -0.2,
        ..ReleaseParams::default()
    };
    let mut bench = Bench::new(vec![part("block", cube(0.04), start, true), table()], floor);
    // Pushed 2 cm: its middle still over the table. It stays when the push ends.
    for _ in 0..4 {
        bench.frame(Some(Vector3::new(0.005, 0.0, 0.0)));
    }
    bench.frame(None);
    let pushed = bench.poses[0];
    assert!((pushed.translation.x - 0.19).abs() < 1e-4, "{pushed:?}");
    bench.stays(20);
    // 2 cm farther: its middle 1 cm past the edge. It tips over the edge and falls.
    for _ in 0..4 {
        bench.frame(Some(Vector3::new(0.005, 0.0, 0.0)));
    }
    let mut frames = 0;
    while bench.unheld.has_motion_left() || frames == 0 {
        bench.frame(None);
        frames += 1;
        assert!(frames < 10_000, "still settling");
    }
    assert!(
        (bench.lowest(0) + 0.2).abs() < 1e-6,
        "its lowest point rests at {}",
        bench.lowest(0)
    );
    assert!(bench.poses[0].translation.x > 0.2, "{:?}", bench.poses[0]);
}

#[test]
fn a_block_on_a_table_pushed_a_little_downwards_slides_along_it_to_a_wall() {
    // Resting on the table, 0.1 mm off it, its face 4 cm before a wall standing on the table;
    // pushed 5 degrees below the horizontal, as a palm pushes, 2 mm a frame.
    let start = at(0.0, 0.0, 0.0201);
    let wall = part(
        "wall",
        shapes::cuboid(Vector3::new(0.02, 0.2, 0.1), 200),
        at(0.07, 0.0, 0.0501),
        false,
    );
    let block = part("block", cube(0.04), start, true);
    let mut bench = Bench::new(vec![block, table(), wall], settling());
    let down = 5f64.to_radians();
    let push = 0.002 * Vector3::new(down.cos(), 0.0, -down.sin());
    let frames = 10;
    for _ in 0..frames {
        bench.frame(Some(push));
    }
    let moved = bench.poses[0].translation.vector - start.translation.vector;
    let wanted = frames as f64 * push.x;
    assert!(moved.x >= 0.95 * wanted, "moved {moved:?} of {wanted} m");
    bench.assert_within_a_millimetre(0, 1, "the table");
    for _ in 0..frames {
        bench.frame(Some(push));
    }
    bench.assert_within_a_millimetre(0, 2, "the wall");
    bench.assert_within_a_millimetre(0, 1, "the table");
    assert!(bench.poses[0].rotation.angle() < 1e-9, "turned");
}
