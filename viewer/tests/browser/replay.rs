//! A recorded scenario replayed through the real server while headless Chromium shows the page:
//! the page draws every part at the pose last published, the held peg in the grasped colour
//! where its published pose projects through the page's camera, contact markers on the part
//! they touched, every colour in its legend, the events as `vas-client replay` words them (with
//! the hand), and latency only for input stamped as it is sent (a paced replay's), not for a
//! lockstep replay's back-dated stamps.

use std::io::{BufRead, BufReader};
use std::process::Stdio;

use serde::Deserialize;
use vas_client::recording::Recording;
use vas_client::{Client, PART_GRASPED, PartsFrame};
use vas_testkit::{PATIENCE, Server, Spawned, configs_dir, fixtures_dir};

use crate::harness::{Browser, Screenshot, Viewer};

/// A part as the page reports it on `window.vasViewer.parts()`.
#[derive(Debug, Deserialize)]
pub struct DrawnPart {
    id: u32,
    pub name: String,
    visible: bool,
    position: [f64; 3],
    quaternion: [f64; 4],
    pub state: String,
    pub colour: String,
}

/// True on the page once no part is drawn as grasped.
pub const ALL_RELEASED: &str = "window.vasViewer.parts().every((part) => part.state !== 'grasped')";

/// The page's grasped colour (view.js `COLOURS.grasped`).
pub const GRASPED: &str = "#2fd15a";

/// How far (CSS pixels) the drawn peg may be from where its pose projects.
const PIXELS: i64 = 3;

#[tokio::test]
async fn the_page_draws_the_published_poses_and_the_held_peg_where_it_is() {
    let scene = configs_dir().join("peg_insert.toml");
    let mut server = Server::start_with(
        "viewer_replay",
        &["--lockstep", "--scene", scene.to_str().expect("UTF-8")],
    );
    let mut client = server.connect();
    let viewer = Viewer::start(server.prefix());
    let browser = Browser::start(1280, 800).await;
    browser
        .client
        .goto(&viewer.url())
        .await
        .expect("open the page");
    browser
        .wait_for("window.vasViewer?.server && window.vasViewer.drawn.lastParts > 0")
        .await;

    // The recording in two halves: the peg is held after the first.
    let (_halves, files) = recording_halves();
    let mut replayed = replay(&server, &files[0]);
    let published = newest_parts(&mut client);
    let peg = published
        .parts
        .iter()
        .find(|part| part.flags & PART_GRASPED != 0)
        .expect("the peg is held halfway through the recording");
    let drawn = drawn_as_published(&browser, &published).await;
    let drawn_peg = &drawn[peg.id as usize];
    assert_eq!(drawn_peg.name, "peg");
    assert_eq!(
        (drawn_peg.state.as_str(), drawn_peg.colour.as_str()),
        ("grasped", GRASPED)
    );
    let shot = browser.screenshot().await;
    check_drawn_at(&browser, &shot, peg.position, peg.rotation).await;
    // The README's picture of the viewer is this moment (viewer/README.md says how to make it).
    if let Some(file) = std::env::var_os("VAS_VIEWER_SCREENSHOT") {
        std::fs::write(&file, &shot.png).expect("write the screenshot");
    }

    check_legend(&browser).await;
    // A lockstep replay's stamps lie in the past: no latency is taken from them.
    browser.wait_for("window.vasViewer.fps > 0").await;
    let latencies: Vec<f64> = browser.eval("window.vasViewer.latencies").await;
    assert!(
        latencies.is_empty(),
        "latencies of back-dated input: {latencies:?}"
    );
    let perf: String = browser.eval("window.vasViewer.panel().perf").await;
    assert!(perf.ends_with("latency –"), "{perf}");

    // The second half at the recording's pace, as a person watches it: the peg touches the
    // block while the hand still moves it.
    let mut second = spawn_replay(&server, &files[1], &["--pace"]);
    check_markers_follow_their_part(&browser, &mut second.tool).await;
    replayed.extend(finish_replay(second));
    let published = newest_parts(&mut client);
    drawn_as_published(&browser, &published).await;
    check_legend(&browser).await;
    // The peg does not move once released, so a frame from before the release has the same
    // poses: the page's state settles on the release.
    browser.wait_for(ALL_RELEASED).await;
    let events: Vec<String> = browser.eval("window.vasViewer.events").await;
    let grasp = events
        .iter()
        .position(|text| text.starts_with("right hand: grasp peg ("))
        .unwrap_or_else(|| panic!("a grasp by the right hand in words: {events:?}"));
    assert!(
        events[grasp..]
            .iter()
            .any(|text| text.starts_with("right hand: release peg at sample")),
        "a release after the grasp: {events:?}"
    );
    // The page's words are the replay's, sample numbers and all, with the hand named.
    let unnamed: Vec<&str> = events
        .iter()
        .map(|text| text.strip_prefix("right hand: ").unwrap_or(text))
        .collect();
    assert_eq!(unnamed, replayed, "the page's events and the replay's");
    // A paced replay's samples are stamped as they are sent, as live input is.
    let latencies: Vec<f64> = browser.eval("window.vasViewer.latencies").await;
    assert!(
        !latencies.is_empty() && latencies.iter().all(|ms| ms.is_finite() && *ms >= 0.0),
        "input-to-drawn latencies of paced input: {latencies:?}"
    );
    browser.close().await;
}

/// Checks that every colour the page draws parts, hand segments and markers in is in its
/// legend.
async fn check_legend(browser: &Browser) {
    let drawn: Vec<String> = browser
        .eval(
            "[...window.vasViewer.parts(), ...window.vasViewer.hands().flatMap((hand) => \
             hand.segments), ...window.vasViewer.markers].map((drawn) => drawn.colour)",
        )
        .await;
    let legend: Vec<String> = browser.eval("window.vasViewer.panel().legend").await;
    for colour in drawn {
        let rgb = u32::from_str_radix(colour.trim_start_matches('#'), 16).expect("#rrggbb");
        let css = format!("rgb({}, {}, {})", rgb >> 16, (rgb >> 8) & 0xff, rgb & 0xff);
        assert!(
            legend.contains(&css),
            "{colour} is not in the legend {legend:?}"
        );
    }
}

/// A contact marker as the page reports it on `window.vasViewer.markers`.
#[derive(Debug, Deserialize)]
struct Marker {
    part: Option<usize>,
    position: [f64; 3],
    local: [f64; 3],
}

/// Checks at every look, while `replay` moves the held peg, that each contact marker kept on a
/// part is drawn at its point in the part's frame, wherever the part is; done once a marker is
/// seen drawn away from where it was put, or, should the page's looks miss the part moving
/// while a marker is on it (a loaded machine draws seldom), once the replay has ended with at
/// least one marker on a part checked.
async fn check_markers_follow_their_part(browser: &Browser, replay: &mut Spawned) {
    let deadline = std::time::Instant::now() + PATIENCE;
    // Where each marker was first seen, by its point in its part's frame.
    let mut first_seen: Vec<([f64; 3], [f64; 3])> = Vec::new();
    loop {
        let replaying = replay.is_running();
        let (markers, parts): (Vec<Marker>, Vec<DrawnPart>) = browser
            .eval("[window.vasViewer.markers, window.vasViewer.parts()]")
            .await;
        for marker in &markers {
            let Some(part) = marker.part.map(|id| &parts[id]) else {
                continue;
            };
            let expected = std::array::from_fn::<f64, 3, _>(|i| {
                part.position[i] + rotate(part.quaternion, marker.local)[i]
            });
            let off = (0..3).map(|i| (marker.position[i] - expected[i]).abs());
            assert!(
                off.fold(0.0, f64::max) < 1e-6,
                "a marker on {} drawn at {:?}, not at its point {expected:?}",
                part.name,
                marker.position
            );
            match first_seen.iter().find(|(local, _)| *local == marker.local) {
                Some((_, at)) if distance(*at, marker.position) > 1e-3 => return,
                Some(_) => {}
                None => first_seen.push((marker.local, marker.position)),
            }
        }
        if !replaying && !first_seen.is_empty() {
            return;
        }
        if std::time::Instant::now() >= deadline {
            let events: Vec<String> = browser.eval("window.vasViewer.events").await;
            panic!(
                "no marker on a part moved with it: {first_seen:?}; markers {markers:?}; {events:?}"
            );
        }
        tokio::time::sleep(std::time::Duration::from_millis(20)).await;
    }
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}

/// `peg_insert.jsonl` cut in two recordings (in a temporary folder, returned with them): after
/// the first the peg is held, after the second it lies in the hole.
pub fn recording_halves() -> (tempfile::TempDir, [std::path::PathBuf; 2]) {
    let recording =
        std::fs::read_to_string(fixtures_dir().join("peg_insert.jsonl")).expect("the fixture");
    let samples = Recording::load(&fixtures_dir().join("peg_insert.jsonl"))
        .expect("the fixture parses")
        .samples
        .len();
    let mut lines = recording.lines();
    let header = lines.next().expect("a header line");
    let (first, second): (Vec<_>, Vec<_>) = lines
        .enumerate()
        .partition(|(index, _)| *index < samples / 2);
    let folder = tempfile::tempdir().expect("a directory");
    let files = [("first.jsonl", first), ("second.jsonl", second)].map(|(name, half)| {
        let path = folder.path().join(name);
        let body: Vec<&str> = std::iter::once(header)
            .chain(half.into_iter().map(|(_, line)| line))
            .collect();
        std::fs::write(&path, body.join("\n") + "\n").expect("write a half");
        path
    });
    (folder, files)
}

/// Replays `file` in lockstep with the `vas-client` tool, waits for it to finish, and returns
/// the events it printed, in words.
pub fn replay(server: &Server, file: &std::path::Path) -> Vec<String> {
    finish_replay(spawn_replay(server, file, &[]))
}

/// A `vas-client replay` under way, and the thread that reads the events it prints (read as
/// they come: a full pipe would stop the replay).
struct RunningReplay {
    tool: Spawned,
    events: std::thread::JoinHandle<Vec<String>>,
}

/// Starts replaying `file` in lockstep with the `vas-client` tool, with `options` of its own.
fn spawn_replay(server: &Server, file: &std::path::Path, options: &[&str]) -> RunningReplay {
    let file = file.to_str().expect("UTF-8");
    let args = [&["replay", "--lockstep", file], options].concat();
    let mut tool = server.client_tool(&args, Stdio::piped());
    let stdout = tool.take_stdout().expect("stdout is piped");
    let events = std::thread::spawn(move || {
        BufReader::new(stdout)
            .lines()
            .map_while(Result::ok)
            .filter_map(|line| {
                let frame: serde_json::Value = serde_json::from_str(&line).expect("a JSON line");
                Some(frame.get("event")?["text"].as_str()?.to_owned())
            })
            .collect()
    });
    RunningReplay { tool, events }
}

/// Waits for `replay` to finish, and returns the events it printed, in words.
fn finish_replay(replay: RunningReplay) -> Vec<String> {
    let RunningReplay { mut tool, events } = replay;
    let status = tool.wait_exit(PATIENCE * 4).expect("the replay finishes");
    assert!(status.success(), "the replay failed:\n{}", tool.log());
    events.join().expect("the replay's output is read")
}

/// The newest parts frame the server published, read as any renderer reads it.
pub fn newest_parts(client: &mut Client) -> PartsFrame {
    client.poll().expect("poll");
    client.latest_parts().cloned().expect("a parts frame")
}

/// Waits until the page has drawn every part at its pose in `published`, and returns the parts
/// as drawn. The poses travel as JSON numbers printed to round-trip, so they must be equal.
pub async fn drawn_as_published(browser: &Browser, published: &PartsFrame) -> Vec<DrawnPart> {
    let expected: Vec<([f64; 3], [f64; 4])> = published
        .parts
        .iter()
        .map(|part| (part.position, part.rotation))
        .collect();
    let deadline = std::time::Instant::now() + PATIENCE;
    loop {
        let drawn: Vec<DrawnPart> = browser.eval("window.vasViewer.parts()").await;
        let poses: Vec<([f64; 3], [f64; 4])> = drawn
            .iter()
            .map(|part| (part.position, part.quaternion))
            .collect();
        if poses == expected && drawn.iter().all(|part| part.visible) {
            for (index, part) in drawn.iter().enumerate() {
                assert_eq!(part.id as usize, index);
            }
            return drawn;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "the page draws {drawn:?}, the server published {expected:?}"
        );
        tokio::time::sleep(std::time::Duration::from_millis(20)).await;
    }
}

/// Checks in `shot` that the peg (a cylinder 24 cm long along its own z) is drawn in the grasped
/// colour at the projections of points on its axis, and not beside it.
async fn check_drawn_at(
    browser: &Browser,
    shot: &Screenshot,
    position: [f64; 3],
    rotation: [f64; 4],
) {
    let axis = rotate(rotation, [0.0, 0.0, 1.0]);
    let side = rotate(rotation, [1.0, 0.0, 0.0]);
    let at = |along: f64, beside: f64| -> [f64; 3] {
        std::array::from_fn(|i| position[i] + along * axis[i] + beside * side[i])
    };
    let rect: serde_json::Value = browser.eval("window.vasViewer.canvasRect()").await;
    let offset = (
        rect["left"].as_f64().expect("left"),
        rect["top"].as_f64().expect("top"),
    );
    let pixel = |point: [f64; 3]| async move {
        let [x, y, z] = point;
        let [px, py]: [f64; 2] = browser
            .eval(&format!("window.vasViewer.project({x}, {y}, {z})"))
            .await;
        (px + offset.0, py + offset.1)
    };
    for along in [-0.1, -0.06, 0.06, 0.1] {
        let point = pixel(at(along, 0.0)).await;
        assert!(
            shot.any_near(point, PIXELS, is_grasped_colour),
            "the held peg is not drawn at {point:?} ({along} m along its axis)"
        );
    }
    for beside in [-0.06, 0.06] {
        let point = pixel(at(0.1, beside)).await;
        assert!(
            !shot.any_near(point, 0, is_grasped_colour),
            "something grasped is drawn at {point:?}, {beside} m beside the peg"
        );
    }
}

/// Green well above red and blue: the grasped colour under any of the page's lights.
fn is_grasped_colour([r, g, b]: [u8; 3]) -> bool {
    let (r, g, b) = (i32::from(r), i32::from(g), i32::from(b));
    g > 60 && g > r + 40 && g > b + 40
}

/// `v` rotated by the unit quaternion `q` (x, y, z, w).
fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let [x, y, z, w] = q;
    let u = [x, y, z];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let t = cross(u, v).map(|c| 2.0 * c);
    let ut = cross(u, t);
    std::array::from_fn(|i| v[i] + w * t[i] + ut[i])
}
