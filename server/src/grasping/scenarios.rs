//! Scripted glove and tracker trajectories against procedural parts: the grasps the hand must
//! recognise, with every frame checked for penetration by parry, independently of the DOP-trees.

use std::sync::Arc;

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
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
/// at these sizes is well below it, and the clasp leaves a gap of up to its tolerance.
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
    root: Isometry3<f64>,
    flex: FlexVector,
}

/// Samples keyframes at [`RATE`], interpolating linearly (the rotation by slerp).
fn sample(keys: &[Key]) -> Vec<(Isometry3<f64>, FlexVector)> {
    let mut out = Vec::new();
    for pair in keys.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let n = ((b.time - a.time) * RATE).round() as usize;
        for i in 0..n {
            let t = i as f64 / n as f64;
            let flex = std::array::from_fn(|v| a.flex[v] + t * (b.flex[v] - a.flex[v]));
            out.push((a.root.lerp_slerp(&b.root, t), flex));
        }
    }
    let last = keys[keys.len() - 1];
    out.push((last.root, last.flex));
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

    /// Feeds the samples with the cart at `cart`, moving held parts with the hand and checking
    /// every frame for penetration.
    fn play(&mut self, samples: &[(Isometry3<f64>, FlexVector)], cart: Isometry3<f64>) {
        for (tracker, flex) in samples {
            let input = HandInput {
                cart,
                tracker: *tracker,
                flex: flex.map(|v| v as f32),
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

    #[allow(dead_code)]
    fn describe(&self, every: usize) {
        for (i, f) in self.frames.iter().enumerate().step_by(every) {
            println!(
                "{i:5} {:?} steps {:2} checks {:3} grasp {:?} held {:?} z {:.4} touching {:?}",
                f.mode,
                f.clasp_steps,
                f.segment_checks,
                f.grasp,
                f.held.map(|h| h.0),
                f.pose.root.translation.z,
                self.touching(i)
            );
        }
        println!("events {:?}", self.events);
    }
}

/// A handle: a cylinder of radius 1.6 cm and length 12 cm along x.
fn handle(id: PartId, centre: [f64; 3]) -> ScenePart {
    let mesh = shapes::cylinder(0.016, 0.12, 2_000);
    let along_x = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
    ScenePart::new(id, mesh, pose(centre, along_x))
}

#[test]
fn a_power_grasp_of_a_cylinder_handle_holds_it_and_it_follows_the_hand() {
    // The handle lies across the palm, 3 cm below the palm's inside face.
    let mut run = Run::new(
        vec![handle(7, [-0.005, 0.075, -0.0125 - 0.016 - 0.03])],
        pose([0.0, 0.0, 0.0], UnitQuaternion::identity()),
    );
    let open = posture(&[(0, -30.0), (3, 45.0)]);
    let fist = posture(&[
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
    ]);
    let up = UnitQuaternion::identity();
    let tilted = UnitQuaternion::from_euler_angles(0.4, 0.2, 0.3);
    let keys = [
        Key {
            time: 0.0,
            root: pose([0.0, 0.0, 0.02], up),
            flex: open,
        },
        // Down onto the handle, pressing 5 mm into it.
        Key {
            time: 0.2,
            root: pose([0.0, 0.0, -0.035], up),
            flex: open,
        },
        // Close the fist around it.
        Key {
            time: 0.45,
            root: pose([0.0, 0.0, -0.035], up),
            flex: fist,
        },
        Key {
            time: 0.5,
            root: pose([0.0, 0.0, -0.035], up),
            flex: fist,
        },
        // Carry it away, turning the hand.
        Key {
            time: 0.8,
            root: pose([0.05, 0.1, 0.04], tilted),
            flex: fist,
        },
        Key {
            time: 0.85,
            root: pose([0.05, 0.1, 0.04], tilted),
            flex: fist,
        },
        // Open the hand.
        Key {
            time: 1.05,
            root: pose([0.05, 0.1, 0.04], tilted),
            flex: open,
        },
        Key {
            time: 1.1,
            root: pose([0.05, 0.1, 0.04], tilted),
            flex: open,
        },
    ];
    run.play(&sample(&keys), Isometry3::identity());
    run.describe(50);
    run.assert_no_penetration();
}
