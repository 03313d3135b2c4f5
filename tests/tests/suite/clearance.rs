//! The clearance watch end to end: `peg_insert.jsonl` replayed in lockstep through the real
//! `vas-server` on `configs/peg_insert_clearance.toml` (5 mm, the held peg against the block).
//! Every published clearance frame is checked against the parts frame it names, by brute force
//! over the triangle pairs: each listed pair's distance and closest triangles, and that no pair
//! closer than the threshold is missing. The events alternate below and restored, each with the
//! distance its frame lists.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use nalgebra::{Isometry3, Point3};
use vas_client::recording::Recording;
use vas_client::{ClearanceFrame, Client, Frame, SimEvent};
use vas_protocol::{EventKind, InputStamp, wall_clock_ns};
use vas_server::collision::distance::triangle_distance;
use vas_server::geometry::TriMesh;
use vas_server::scene::Scene;
use vas_server::simulation::clearance::HYSTERESIS;
use vas_testkit::{PATIENCE, Server};

/// How close the published distances must be to the brute force's (metres): both are exact
/// f64 computations of the same triangles, posed through the wire's poses.
const TOLERANCE: f64 = 1e-9;

fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The samples a frame answers, as its stamps name them.
fn seqs(tracker: InputStamp, glove: InputStamp, joints: InputStamp) -> [u64; 3] {
    [tracker.seq, glove.seq, joints.seq]
}

/// What the replay published.
#[derive(Default)]
struct Published {
    /// Every parts frame's poses, by frame number.
    parts: BTreeMap<u64, Vec<Isometry3<f64>>>,
    clearance: Vec<ClearanceFrame>,
    /// Clearance events, in order.
    events: Vec<SimEvent>,
}

impl Published {
    fn take(&mut self, frames: Vec<Frame>) -> Vec<u64> {
        let mut answered = Vec::new();
        for frame in frames {
            match frame {
                Frame::Parts(parts) => {
                    let poses = parts.parts.iter().map(|p| p.pose().to_isometry()).collect();
                    self.parts.insert(parts.header.frame, poses);
                }
                Frame::Clearance(clearance) => self.clearance.push(*clearance),
                Frame::Event(event)
                    if matches!(
                        EventKind::try_from(event.kind),
                        Ok(EventKind::ClearanceBelow | EventKind::ClearanceRestored)
                    ) =>
                {
                    self.events.push(event);
                }
                Frame::Hand(hand) => answered.push(hand.tracker.seq.max(hand.glove.seq)),
                _ => {}
            }
        }
        answered
    }
}

/// Replays the recording in lockstep, each sample after the answer to the previous one, then
/// waits for the last frame's clearance.
fn replay(client: &mut Client, recording: &Recording) -> Published {
    let mut published = Published::default();
    let start_ns = wall_clock_ns().saturating_sub(recording.duration_ns());
    for (index, recorded) in recording.samples.iter().enumerate() {
        let input = recorded.stamped(start_ns);
        client.send_input(&input).expect("send");
        let deadline = Instant::now() + PATIENCE;
        loop {
            assert!(Instant::now() < deadline, "sample {index}: no answer");
            client.wait(PATIENCE).expect("wait");
            let frames = client.receive().expect("receive");
            let answered = frames
                .iter()
                .any(|frame| matches!(frame, Frame::Hand(hand) if input.is_answered_by(hand)));
            published.take(frames);
            if answered {
                break;
            }
        }
    }
    let last_parts = *published.parts.keys().last().expect("parts frames");
    let deadline = Instant::now() + PATIENCE;
    while published
        .clearance
        .last()
        .is_none_or(|c| c.frame < last_parts)
    {
        assert!(Instant::now() < deadline, "no clearance for the last frame");
        client.wait(Duration::from_millis(100)).expect("wait");
        let frames = client.receive().expect("receive");
        published.take(frames);
    }
    published
}

/// The least distance between `a` at `pose_a` and `b` at `pose_b` if it is below `bound`, with
/// the triangles, by brute force over the triangle pairs whose bounding boxes come within
/// `bound` of each other's mesh.
fn brute_force_below(
    (a, pose_a): (&TriMesh, &Isometry3<f64>),
    (b, pose_b): (&TriMesh, &Isometry3<f64>),
    bound: f64,
) -> Option<(f64, [u32; 2])> {
    let posed = |mesh: &TriMesh, pose: &Isometry3<f64>| -> Vec<[Point3<f64>; 3]> {
        (0..mesh.triangles().len())
            .map(|i| mesh.triangle(i).map(|p| pose * p))
            .collect()
    };
    let (ta, tb) = (posed(a, pose_a), posed(b, pose_b));
    let aabb = |points: &mut dyn Iterator<Item = &Point3<f64>>| {
        points.fold(
            (Point3::from([f64::MAX; 3]), Point3::from([f64::MIN; 3])),
            |(lo, hi), p| (lo.inf(p), hi.sup(p)),
        )
    };
    let near = |(lo, hi): (Point3<f64>, Point3<f64>), (olo, ohi): (Point3<f64>, Point3<f64>)| {
        (0..3).all(|i| lo[i] - bound <= ohi[i] && olo[i] <= hi[i] + bound)
    };
    let whole_a = aabb(&mut ta.iter().flatten());
    let whole_b = aabb(&mut tb.iter().flatten());
    let near_a: Vec<(usize, _)> = (ta.iter().enumerate())
        .map(|(i, t)| (i, aabb(&mut t.iter())))
        .filter(|(_, boxed)| near(*boxed, whole_b))
        .collect();
    let near_b: Vec<(usize, _)> = (tb.iter().enumerate())
        .map(|(i, t)| (i, aabb(&mut t.iter())))
        .filter(|(_, boxed)| near(*boxed, whole_a))
        .collect();
    let mut best: Option<(f64, [u32; 2])> = None;
    for &(i, box_a) in &near_a {
        for &(j, box_b) in &near_b {
            if !near(box_a, box_b) {
                continue;
            }
            let distance = triangle_distance(&ta[i], &tb[j]).distance;
            if distance < bound && best.is_none_or(|(d, _)| distance < d) {
                best = Some((distance, [i as u32, j as u32]));
            }
        }
    }
    best
}

#[test]
fn clearance_of_the_held_peg_matches_brute_force_frame_by_frame() {
    let scene_path = repository().join("configs/peg_insert_clearance.toml");
    let scene = Scene::load(&scene_path).expect("the scene loads");
    let threshold = scene.params.clearance.threshold.expect("a threshold");
    let restore_at = threshold * (1.0 + HYSTERESIS);
    let id = |name: &str| {
        scene
            .parts
            .iter()
            .position(|p| p.name == name)
            .expect("a part")
    };
    let (block, peg) = (id("block"), id("peg"));
    let recording = Recording::load(&repository().join("tests/fixtures/peg_insert.jsonl"))
        .expect("the recording loads");
    let scene_arg = scene_path.display().to_string();
    let mut server = Server::start_with("clearance", &["--lockstep", "--scene", &scene_arg]);
    let mut client = server.connect();
    let published = replay(&mut client, &recording);

    // One clearance frame per frame, none stale in lockstep, each on a published parts frame.
    let answered = recording.samples.len();
    assert!(
        published.clearance.len() >= answered,
        "{} clearance frames for {answered} samples",
        published.clearance.len()
    );
    let mut listed_frames = 0;
    let mut below_at: BTreeMap<[u64; 3], f64> = BTreeMap::new();
    for clearance in &published.clearance {
        assert_eq!(clearance.threshold, threshold);
        let poses = &published.parts[&clearance.frame];
        let (pose_block, pose_peg) = (&poses[block], &poses[peg]);
        let truth = brute_force_below(
            (&scene.parts[peg].mesh, pose_peg),
            (&scene.parts[block].mesh, pose_block),
            restore_at,
        );
        let listed = clearance.listed();
        assert!(listed.len() <= 1 && clearance.more == 0, "{clearance:?}");
        match (listed.first(), truth) {
            (Some(pair), Some((distance, triangles))) => {
                listed_frames += 1;
                assert_eq!((pair.part, pair.other), (peg as u32, block as u32));
                assert!(
                    !pair.is_stale(),
                    "frame {}: stale in lockstep",
                    clearance.frame
                );
                assert!(
                    (pair.distance - distance).abs() < TOLERANCE,
                    "frame {}: published {} m, brute force {distance} m",
                    clearance.frame,
                    pair.distance
                );
                // The published points are that far apart, on the triangles named.
                let (on_peg, on_block) = (Point3::from(pair.point), Point3::from(pair.other_point));
                assert!(((on_peg - on_block).norm() - pair.distance).abs() < TOLERANCE);
                let posed = |part: usize, pose: &Isometry3<f64>, triangle: u32| {
                    scene.parts[part]
                        .mesh
                        .triangle(triangle as usize)
                        .map(|p| pose * p)
                };
                let named = triangle_distance(
                    &posed(peg, pose_peg, pair.triangles[0]),
                    &posed(block, pose_block, pair.triangles[1]),
                );
                assert!(
                    (named.distance - distance).abs() < TOLERANCE,
                    "frame {}: triangles {:?} are {} m apart, brute force's {triangles:?} {distance} m",
                    clearance.frame,
                    pair.triangles,
                    named.distance
                );
                below_at.insert(
                    seqs(clearance.tracker, clearance.glove, clearance.joints),
                    pair.distance,
                );
            }
            // Closer than the threshold is always listed; between it and the hysteresis's end
            // only while below.
            (None, Some((distance, _))) => assert!(
                distance >= threshold,
                "frame {}: the pair is {distance} m apart and not listed",
                clearance.frame
            ),
            (Some(pair), None) => panic!(
                "frame {}: {pair:?} listed, brute force finds nothing within {restore_at} m",
                clearance.frame
            ),
            (None, None) => {}
        }
    }
    assert!(listed_frames > 0, "the peg never came within the threshold");

    // Events: below first, then alternating, each with its frame's listed distance.
    let kinds: Vec<EventKind> = (published.events.iter())
        .map(|event| EventKind::try_from(event.kind).expect("a clearance event"))
        .collect();
    assert_eq!(kinds.first(), Some(&EventKind::ClearanceBelow), "{kinds:?}");
    for (index, (event, kind)) in published.events.iter().zip(&kinds).enumerate() {
        let expected = if index % 2 == 0 {
            EventKind::ClearanceBelow
        } else {
            EventKind::ClearanceRestored
        };
        assert_eq!(*kind, expected, "event {index} of {kinds:?}");
        assert_eq!((event.part, event.other), (peg as u32, block as u32));
        let at = seqs(event.tracker, event.glove, event.joints);
        match kind {
            EventKind::ClearanceBelow => {
                assert!(event.distance < threshold, "{event:?}");
                assert_eq!(below_at.get(&at), Some(&event.distance), "{event:?}");
            }
            _ => {
                assert!(event.distance >= restore_at, "{event:?}");
                assert!(
                    !below_at.contains_key(&at),
                    "restored yet listed: {event:?}"
                );
            }
        }
        let gap = Point3::from(event.point) - Point3::from(event.other_point);
        assert!((gap.norm() - event.distance).abs() < TOLERANCE, "{event:?}");
    }
    eprintln!(
        "clearance: {} frames, {listed_frames} listing the peg, events {kinds:?}",
        published.clearance.len()
    );
}
