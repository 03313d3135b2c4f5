//! The link thread: the viewer's vas client, on the one thread its iceoryx2 ports may live on.
//!
//! It waits for a server, passes the scene and every frame and event on to the [`Hub`], and
//! carries out the pages' commands. In lockstep a server publishes only when it gets input, so
//! silence alone says nothing; after [`QUIET`] without a frame the link asks the server for its
//! counters, and a server that does not answer is taken as gone: the pages are told "no
//! server", and the link waits for one on the same prefix and starts afresh (new ports, so that
//! the new server's scene arrives as a late joiner's history).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::{Duration, Instant};

use vas_client::{Client, ClientError, Frame, HandFrame, PartsFrame, SceneInfo, Wake};

use crate::commands::Command;
use crate::hub::{CommandRequest, Hub, SceneMessages};
use crate::stats::Stats;
use crate::{events, messages, scene};

/// How long one wait for frames lasts: bounds how late a command or a stop is noticed.
const WAIT: Duration = Duration::from_millis(10);
/// Silence after which the link checks that the server is still there.
const QUIET: Duration = Duration::from_secs(1);
/// How long a server has to answer a control request before it is taken as gone.
const CONTROL_TIMEOUT: Duration = Duration::from_secs(2);
/// How long a scene may take to load.
const LOAD_TIMEOUT: Duration = Duration::from_secs(60);
/// How long one look for a server lasts while there is none.
const LOOK: Duration = Duration::from_millis(250);

/// Runs the link until `stop` is set.
pub fn run(
    prefix: Option<&str>,
    hub: &Hub,
    commands: Receiver<CommandRequest>,
    stop: &AtomicBool,
) {
    let mut link = Link {
        hub,
        commands,
        stop,
        scene_version: 0,
    };
    hub.status.send_replace(Some(messages::status(false, &[])));
    while !stop.load(Ordering::Relaxed) {
        match link.session(prefix) {
            Ok(()) => {}
            Err(error) => tracing::warn!(%error, "lost the vas server"),
        }
        hub.stats.server.store(false, Ordering::Relaxed);
        hub.status.send_replace(Some(messages::status(false, &[])));
    }
}

struct Link<'a> {
    hub: &'a Hub,
    commands: Receiver<CommandRequest>,
    stop: &'a AtomicBool,
    /// Counts the scenes passed on; frames name the scene they belong to.
    scene_version: u64,
}

impl Link<'_> {
    /// One server's lifetime: waits for it, then passes on its output until it goes away or the
    /// viewer stops (then `Ok`).
    fn session(&mut self, prefix: Option<&str>) -> Result<(), ClientError> {
        if !self.wait_for_server(prefix)? {
            return Ok(());
        }
        let mut client = Client::connect(prefix)?;
        let scene = client.scene_info(CONTROL_TIMEOUT)?;
        tracing::info!(scene = scene.name, parts = scene.parts.len(), "server found");
        self.hub.stats.server.store(true, Ordering::Relaxed);
        self.hub
            .status
            .send_replace(Some(messages::status(true, &[])));
        self.publish_scene(&scene);

        let mut latest = Latest::default();
        let mut last_heard = Instant::now();
        while !self.stop.load(Ordering::Relaxed) {
            self.serve_commands(|command| carry_out(&client, command));
            match client.wait(WAIT)? {
                Wake::Ready => {
                    last_heard = Instant::now();
                    self.pass_on(&mut latest, client.receive()?, &scene);
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
        let client = Client::connect(prefix)?;
        while !self.stop.load(Ordering::Relaxed) {
            match client.input_stats(LOOK) {
                Ok(_) => return Ok(true),
                Err(ClientError::Timeout { .. }) => {
                    self.serve_commands(|_| Err("no vas server answers".to_owned()));
                }
                Err(error) => return Err(error),
            }
        }
        Ok(false)
    }

    /// Answers every waiting command with `carry_out`.
    fn serve_commands(&self, mut carry_out: impl FnMut(&Command) -> Result<String, String>) {
        loop {
            match self.commands.try_recv() {
                Ok(request) => {
                    let answer = carry_out(&request.command);
                    tracing::info!(command = request.command.name(), ?answer, "page command");
                    // The page may have gone meanwhile.
                    let _ = request.reply.send(answer);
                }
                Err(TryRecvError::Empty | TryRecvError::Disconnected) => return,
            }
        }
    }

    fn publish_scene(&mut self, scene: &SceneInfo) {
        self.scene_version += 1;
        let messages: SceneMessages = scene::messages(self.scene_version, scene);
        self.hub.scene.send_replace(messages);
        Stats::count(&self.hub.stats.scenes);
    }

    /// Passes on received frames: events each, parts and hand as the newest state.
    fn pass_on(&mut self, latest: &mut Latest, frames: Vec<Frame>, scene: &SceneInfo) {
        let mut changed = false;
        for frame in frames {
            match frame {
                Frame::Parts(parts) => {
                    latest.parts = Some(parts);
                    changed = true;
                }
                Frame::Hand(hand) => {
                    latest.hand = Some(hand);
                    changed = true;
                }
                Frame::Event(event) => {
                    // No page connected is not an error.
                    let _ = self
                        .hub
                        .events
                        .send(events::message(self.scene_version, &event, scene));
                }
                Frame::Force(_) => {}
            }
        }
        if changed {
            Stats::count(&self.hub.stats.frames);
            let message = messages::frame(
                self.scene_version,
                latest.parts.as_ref(),
                latest.hand.as_ref(),
            );
            self.hub.frame.send_replace(Some(message));
        }
    }
}

/// The newest frames received.
#[derive(Default)]
struct Latest {
    parts: Option<PartsFrame>,
    hand: Option<HandFrame>,
}

/// Carries out a page's command on the server; the answer in words either way.
fn carry_out(client: &Client, command: &Command) -> Result<String, String> {
    let done = match command {
        Command::Reset {} => client.reset(CONTROL_TIMEOUT).map(|_| "scene reset".to_owned()),
        Command::SetMetaphor { metaphor } => client
            .set_metaphor((*metaphor).into(), CONTROL_TIMEOUT)
            .map(|_| format!("grasp metaphor: {}", metaphor.words())),
        Command::LoadScene { name } => {
            let _ = (name, LOAD_TIMEOUT);
            Err(ClientError::Ipc {
                action: "load a scene by name",
                reason: "not offered by this server".into(),
            })
        }
    };
    done.map_err(|error| match error {
        ClientError::Refused { message, .. } => message,
        other => other.to_string(),
    })
}
