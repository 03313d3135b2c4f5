//! Pushed and settling parts among static ones, checked after every frame by parry (in
//! millimetres), an oracle independent of the DOP-trees the sliding machinery uses.

use std::sync::Arc;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use parry3d::query::{distance, intersection_test};

use super::*;
use crate::collision::orientation::DEFAULT_K;
use crate::collision::parry_mesh::{millimetre_pose, millimetre_trimesh};
use crate::geometry::{TriMesh, shapes};
use crate::scene::{Part, PartTree, ReleaseParams};

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
    let gap = bench.gap(0, 1);
    assert!(
        (0.0..=0.001).contains(&gap),
        "rests {gap} m above the table"
    );
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
    let gap = bench.gap(0, 1);
    assert!(
        (0.0..=0.001).contains(&gap),
        "rests {gap} m above the slope"
    );
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
    let wall = part(
        "wall",
        shapes::cuboid(Vector3::new(0.02, 0.2, 0.2), 200),
        at(0.06, 0.0, 0.0),
        false,
    );
    let block = part("block", cube(0.04), at(0.0, 0.0, 0.0), true);
    let mut bench = Bench::new(vec![block, wall], settling());
    for _ in 0..20 {
        bench.frame(Some(Vector3::new(0.005, 0.0, 0.0)));
    }
    let gap = bench.gap(0, 1);
    assert!((0.0..=0.001).contains(&gap), "stops {gap} m from the wall");
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
    let gap = bench.gap(0, 3);
    assert!(
        (0.0..=0.001).contains(&gap),
        "stops {gap} m from the slot's end"
    );
    assert!(bench.poses[0].translation.y.abs() <= 0.0005 + 1e-9);
}

#[test]
fn pushes_name_their_part_and_a_rested_hand_moves_nothing() {
    let block = part("block", cube(0.04), at(0.0, 0.0, 0.0), true);
    let mut bench = Bench::new(vec![block], settling());
    bench.frame(Some(Vector3::zeros()));
    assert_eq!(bench.unheld.pushed_by(0), [0]);
    assert_eq!(bench.poses[0], at(0.0, 0.0, 0.0));
    bench.frame(None);
    assert!(bench.unheld.pushed_by(0).is_empty());
}
