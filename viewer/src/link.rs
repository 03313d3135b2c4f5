//! The link thread: the viewer's vas client, on the one thread its iceoryx2 ports may live on.
//!
//! It waits for a server, passes the scene and every frame and event on to the [`Hub`], carries
//! out the pages' commands, and publishes a headset's hand joints on the server's hand-joints
//! service (numbered per side, stamped with the wall-clock time they reached the viewer). The
//! link's client takes the render role only, and the input role once a headset sends hand
//! joints, so that a viewer without a headset holds no input publisher. In lockstep a server publishes only when it gets input, so
//! silence alone says nothing; after `QUIET` without a frame the link asks the server for its
//! counters, and a server that does not answer is taken as gone: the pages are told "no
//! server", and the link waits for one on the same prefix and starts afresh (new ports, so that
//! the new server's scene arrives as a late joiner's history).

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use vas_client::protocol::ControlRequest;
use vas_client::{
    ClearanceFrame, Client, ClientError, Frame, HandFrame, PartsFrame, Roles, SceneGeometry,
    SceneInfo, SceneWords, SlidingMetaphor, Wake,
};

use crate::commands::Command;
use crate::hand_joints::Sequence;
use crate::hub::{Hub, Inbox};
use crate::messages::ServerStatus;
use crate::stats::Stats;
use crate::{events, messages, scene};

/// How long one wait for frames lasts: bounds how late a command or a stop is noticed.
const WAIT: Duration = Duration::from_millis(10);
/// How long one wait lasts while a headset sends hand joints: bounds how long they wait to be
/// published (the wait wakes on the server's frames, not on the pages).
const HAND_WAIT: Duration = Duration::from_millis(1);
/// How long after the last hand joints the link keeps waiting [`HAND_WAIT`].
const HANDS_RECENT: Duration = Duration::from_millis(200);
/// Silence after which the link checks that the server is still there.
const QUIET: Duration = Duration::from_secs(1);
/// How often the link asks which sliding metaphor the server uses, so that the pages see one
/// another client set.
const METAPHOR_REFRESH: Duration = Duration::from_secs(1);
/// How long a server has to answer a control request before it is taken as gone.
const CONTROL_TIMEOUT: Duration = Duration::from_secs(2);
/// How long a scene may take to load.
const LOAD_TIMEOUT: Duration = Duration::from_secs(60);
/// How long the link waits before it asks again for room to publish hand joints.
const INPUT_RETRY: Duration = Duration::from_secs(1);
/// How long one look for a server lasts while there is none.
const LOOK: Duration = Duration::from_millis(250);

/// Runs the link until `stop` is set.
pub fn run(prefix: Option<&str>, hub: &Hub, inbox: Inbox, stop: &AtomicBool) {
    let mut link = Link {
        hub,
        inbox,
        stop,
        scene_version: 0,
        sequence: Sequence::default(),
        last_hands: None,
        input_refused: None,
    };
    hub.status
        .send_replace(Some(messages::status(&ServerStatus::default())));
    while !stop.load(Ordering::Relaxed) {
        match link.session(prefix) {
            Ok(()) => {}
            Err(error) => tracing::warn!(%error, "lost the vas server"),
        }
        hub.stats.server.store(false, Ordering::Relaxed);
        hub.status
            .send_replace(Some(messages::status(&ServerStatus::default())));
    }
}

struct Link<'a> {
    hub: &'a Hub,
    inbox: Inbox,
    stop: &'a AtomicBool,
    /// Counts the scenes passed on; frames name the scene they belong to.
    scene_version: u64,
    /// Numbers the hand-joints samples of each side.
    sequence: Sequence,
    /// When hand joints last came from a page.
    last_hands: Option<Instant>,
    /// When the server's input streams last had no room for the link's publisher: asked again
    /// after [`INPUT_RETRY`], said once.
    input_refused: Option<Instant>,
}

impl Link<'_> {
    /// One server's lifetime: waits for it, then passes on its output until it goes away or the
    /// viewer stops (then `Ok`).
    fn session(&mut self, prefix: Option<&str>) -> Result<(), ClientError> {
        if !self.wait_for_server(prefix)? {
            return Ok(());
        }
        let mut client = Client::builder()
            .prefix(prefix)
            .roles(Roles::RENDER)
            .connect()?;
        let mut scene = client.scene_info(CONTROL_TIMEOUT)?;
        let scene_names = client.scene_names(CONTROL_TIMEOUT)?;
        tracing::info!(
            scene = scene.name,
            parts = scene.parts.len(),
            "server found"
        );
        self.hub.stats.server.store(true, Ordering::Relaxed);
        let mut status = ServerStatus::default();
        // The sliding metaphor in use, as the server's last answer said.
        let (mut metaphor, mut metaphor_asked) = (scene.metaphor, Instant::now());

        let mut latest = Latest::default();
        let mut last_heard = Instant::now();
        while !self.stop.load(Ordering::Relaxed) {
            self.serve_commands(|command| carry_out(&client, command, &mut metaphor));
            if metaphor_asked.elapsed() >= METAPHOR_REFRESH {
                let answer = client.control(ControlRequest::scene_info(), CONTROL_TIMEOUT)?;
                metaphor = SlidingMetaphor::try_from(answer.metaphor)?;
                metaphor_asked = Instant::now();
            }
            let now = ServerStatus {
                server: true,
                scene: offered_name(&scene, &scene_names),
                scene_names: scene_names.clone(),
                metaphor,
            };
            if now != status {
                self.hub.status.send_replace(Some(messages::status(&now)));
                status = now;
            }
            self.publish_hand_joints(&mut client)?;
            let hands_recent = (self.last_hands).is_some_and(|at| at.elapsed() < HANDS_RECENT);
            match client.wait(if hands_recent { HAND_WAIT } else { WAIT })? {
                Wake::Ready => {
                    last_heard = Instant::now();
                    let frames = client.receive()?;
                    if let Some(geometry) = new_geometry(&frames, latest.generation) {
                        // A load or a reset: the names may have changed with the scene.
                        scene = client.scene_info(CONTROL_TIMEOUT)?;
                        metaphor = scene.metaphor;
                        latest = Latest {
                            generation: Some(geometry.generation),
                            words: SceneWords::new(&scene),
                            ..Latest::default()
                        };
                        self.publish_scene(&scene, geometry);
                    }
                    self.pass_on(&mut latest, frames);
                }
                Wake::Timeout if last_heard.elapsed() >= QUIET => {
                    client.input_stats(CONTROL_TIMEOUT)?;
                    last_heard = Instant::now();
                }
                Wake::Timeout => {}
                Wake::Terminated => return Ok(()),
            }
        }
        Ok(())
    }

    /// Looks for a server until one answers (true) or the viewer stops (false); commands meanwhile
    /// are refused.
    fn wait_for_server(&mut self, prefix: Option<&str>) -> Result<bool, ClientError> {
        let client = Client::builder()
            .prefix(prefix)
            .roles(Roles::CONTROL)
            .connect()?;
        while !self.stop.load(Ordering::Relaxed) {
            match client.input_stats(LOOK) {
                Ok(_) => return Ok(true),
                Err(ClientError::Timeout { .. }) => {
                    self.serve_commands(|_| Err("no vas server answers".to_owned()));
                    self.drop_hand_joints();
                }
                Err(error) => return Err(error),
            }
        }
        Ok(false)
    }

    /// Publishes every waiting hand-joints message on the server's hand-joints service, taking
    /// the input role at the first; while the input streams have no room for the link, the
    /// messages are dropped and counted.
    fn publish_hand_joints(&mut self, client: &mut Client) -> Result<(), ClientError> {
        while let Ok((joints, arrived_ns)) = self.inbox.hand_joints.try_recv() {
            self.last_hands = Some(Instant::now());
            if !client.roles().contains(Roles::INPUT) && !self.take_input(client)? {
                Stats::count(&self.hub.stats.hand_joints_dropped);
                continue;
            }
            let sample = joints.sample(self.sequence.next(&joints), arrived_ns);
            client.send_hand_joints(&sample)?;
            Stats::count(&self.hub.stats.hand_joints_published);
        }
        Ok(())
    }

    /// Takes the input role for `client`; false while the input streams have no room for it
    /// (asked again after [`INPUT_RETRY`], said once until it gets room).
    fn take_input(&mut self, client: &mut Client) -> Result<bool, ClientError> {
        if (self.input_refused).is_some_and(|at| at.elapsed() < INPUT_RETRY) {
            return Ok(false);
        }
        match client.take_roles(Roles::INPUT) {
            Ok(()) => {
                self.input_refused = None;
                Ok(true)
            }
            Err(error @ ClientError::Full { .. }) => {
                if self.input_refused.is_none() {
                    tracing::warn!(%error, "cannot publish hand joints");
                }
                self.input_refused = Some(Instant::now());
                Ok(false)
            }
            Err(error) => Err(error),
        }
    }

    /// Drops every waiting hand-joints message: there is no server to publish them to.
    fn drop_hand_joints(&self) {
        while self.inbox.hand_joints.try_recv().is_ok() {
            Stats::count(&self.hub.stats.hand_joints_dropped);
        }
    }

    /// Answers every waiting command with `carry_out`.
    fn serve_commands(&self, mut carry_out: impl FnMut(&Command) -> Result<String, String>) {
        while let Ok(request) = self.inbox.commands.try_recv() {
            let answer = carry_out(&request.command);
            tracing::info!(command = request.command.name(), ?answer, "page command");
            // The page may have gone meanwhile.
            let _ = request.reply.send(answer);
        }
    }

    fn publish_scene(&mut self, scene: &SceneInfo, geometry: &SceneGeometry) {
        self.scene_version += 1;
        tracing::info!(
            scene = scene.name,
            generation = geometry.generation,
            "passing the scene on"
        );
        let messages = scene::messages(self.scene_version, scene, geometry);
        self.hub.scene.send_replace(messages);
        Stats::count(&self.hub.stats.scenes);
    }

    /// Passes on received frames: events each, parts and hands as the newest state.
    fn pass_on(&mut self, latest: &mut Latest, frames: Vec<Frame>) {
        let mut changed = false;
        for frame in frames {
            match frame {
                Frame::Parts(parts) => {
                    latest.parts = Some(parts);
                    changed = true;
                }
                Frame::Hand(hand) => {
                    latest.hands.insert(hand.hand, hand);
                    changed = true;
                }
                Frame::Event(event) => {
                    let message = events::message(self.scene_version, &event, &latest.words);
                    // No page connected is not an error.
                    let _ = self.hub.events.send(message);
                }
                Frame::Clearance(clearance) => {
                    latest.clearance = Some(clearance);
                    changed = true;
                }
                Frame::Geometry(_) | Frame::Force(_) => {}
            }
        }
        // Frames before the first geometry have no scene to be drawn in.
        if changed && latest.generation.is_some() {
            Stats::count(&self.hub.stats.frames);
            let message = messages::frame(
                self.scene_version,
                latest.parts.as_ref(),
                latest.hands.values(),
                latest.clearance.as_deref(),
            );
            self.hub.frame.send_replace(Some(message));
        }
    }
}

/// The newest geometry among `frames` when its generation is not `current`.
fn new_geometry(frames: &[Frame], current: Option<u64>) -> Option<&SceneGeometry> {
    frames
        .iter()
        .rev()
        .find_map(|frame| match frame {
            Frame::Geometry(geometry) => Some(geometry.as_ref()),
            _ => None,
        })
        .filter(|geometry| Some(geometry.generation) != current)
}

/// What the link passes on of the current scene: its newest frames, and its words for events.
#[derive(Default)]
struct Latest {
    /// The geometry generation the frames belong to; `None` before the first geometry.
    generation: Option<u64>,
    words: SceneWords,
    parts: Option<PartsFrame>,
    /// Each hand's newest frame, by side code.
    hands: BTreeMap<u32, HandFrame>,
    /// The newest clearance frame (none while the scene has no threshold).
    clearance: Option<Box<ClearanceFrame>>,
}

/// The name the server offers `scene` under among `names`: the one its file is named after. The
/// server names the scenes it offers by their files' stems, and a scene by its own `name`.
fn offered_name(scene: &SceneInfo, names: &[String]) -> Option<String> {
    let stem = std::path::Path::new(&scene.source).file_stem()?.to_str()?;
    names.iter().find(|name| *name == stem).cloned()
}

/// Carries out a page's command on the server; the answer in words either way. `metaphor`
/// takes the one the answer says is in use (a reset or a load brings the scene's own back).
fn carry_out(
    client: &Client,
    command: &Command,
    metaphor: &mut SlidingMetaphor,
) -> Result<String, String> {
    let (answer, done) = match command {
        Command::Reset {} => (client.reset(CONTROL_TIMEOUT), "scene reset".to_owned()),
        Command::SetMetaphor { metaphor } => (
            client.set_metaphor(*metaphor, CONTROL_TIMEOUT),
            format!("sliding metaphor: {metaphor}"),
        ),
        Command::LoadScene { name } => (
            client.load_named_scene(name, LOAD_TIMEOUT),
            format!("loaded {name}"),
        ),
    };
    let answer = answer.map_err(|error| match error {
        ClientError::Refused { message, .. } => message,
        other => other.to_string(),
    })?;
    if let Ok(in_use) = SlidingMetaphor::try_from(answer.metaphor) {
        *metaphor = in_use;
    }
    Ok(done)
}

#[cfg(test)]
mod tests {
    use super::*;
    use vas_client::InputStats;

    #[test]
    fn the_served_scene_is_offered_under_its_files_stem() {
        let scene = |source: &str| SceneInfo {
            name: "peg insert".into(),
            source: source.into(),
            parts: Vec::new(),
            stats: InputStats::default(),
            up: [0.0, 0.0, 1.0],
            metres_per_unit: 1.0,
            users: vec!["user".into()],
            hands: Vec::new(),
            scenes_offered: 2,
            generation: 1,
            metaphor: SlidingMetaphor::default(),
        };
        let names = ["peg_in_hole".to_owned(), "peg_insert".to_owned()];
        assert_eq!(
            offered_name(&scene("configs/peg_insert.toml"), &names).as_deref(),
            Some("peg_insert")
        );
        assert_eq!(offered_name(&scene("elsewhere/gear.toml"), &names), None);
    }
}
