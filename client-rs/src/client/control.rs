//! Control requests: the scene and its parts, input counters, loads, reset, metaphor.

use std::time::{Duration, Instant};

use serde::Serialize;
use vas_protocol::{
    ControlRequest, ControlRequestKind, ControlResponse, ControlStatus, HandSide, InputStats,
    MAX_PATH_BYTES, PART_MOVABLE, SlidingMetaphor, WirePose, WireText,
};

use super::Client;
use crate::ClientError;
use crate::wait::deadline_after;

/// How long a control request that reached no server waits before it is sent again (a server
/// may be starting).
const CONTROL_RETRY: Duration = Duration::from_millis(20);

/// The server's scene, as the control service describes it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneInfo {
    /// The scene's name.
    pub name: String,
    /// The file the server loaded it from.
    pub source: String,
    /// Every part, indexed by id.
    pub parts: Vec<PartInfo>,
    /// The server's input counters at the time of the answer.
    pub stats: InputStats,
    /// The world's up direction (z up).
    pub up: [f64; 3],
    /// Metres per unit of every length (1: metres).
    pub metres_per_unit: f64,
    /// The scene's users' names, by the index that samples and frames name them with: those of
    /// its `[[users]]`, or one (`user`) for a scene that names its hands without users.
    pub users: Vec<String>,
    /// The scene's hands: user, side and model name, grouped by user.
    pub hands: Vec<HandInfo>,
    /// How many scenes the server may load by name ([`Client::scene_names`]).
    pub scenes_offered: u32,
    /// The scene's generation: one more after every load or reset, the same number as its
    /// geometry's ([`SceneGeometry::generation`](vas_protocol::SceneGeometry::generation)).
    pub generation: u64,
    /// The sliding metaphor in use: the scene's own, or the one a client set since the last
    /// load or reset.
    pub metaphor: SlidingMetaphor,
}

impl SceneInfo {
    /// The name of user `user`; "user N" for an index the scene does not have (a frame of
    /// another scene).
    pub fn user_name(&self, user: u32) -> String {
        match self.users.get(user as usize) {
            Some(name) => name.clone(),
            None => format!("user {user}"),
        }
    }

    /// The index of the user called `name`, if the scene has one.
    pub fn user_index(&self, name: &str) -> Option<u32> {
        (0u32..)
            .zip(&self.users)
            .find(|(_, user)| *user == name)
            .map(|(index, _)| index)
    }
}

/// A hand of the scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HandInfo {
    /// Whose hand: an index into [`SceneInfo::users`].
    pub user: u32,
    /// Which hand.
    pub side: HandSide,
    /// The hand model's name.
    pub model: String,
}

/// One part of the scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PartInfo {
    /// The id used in parts frames.
    pub id: u32,
    /// The part's name.
    pub name: String,
    /// Its collision group.
    pub group: String,
    /// Its geometry: the mesh path the server resolved, or a procedural shape's description.
    pub mesh_source: String,
    /// Whether it can be grasped and moved.
    pub movable: bool,
    /// Its pose when the scene was loaded.
    pub initial_pose: WirePose,
    /// The scale the scene applies to its mesh (already applied to the mesh on the wire).
    pub scale: f64,
    /// Whether a name or path was cut to fit the wire.
    pub truncated: bool,
}

impl Client {
    /// Asks for the scene: its summary, then every part; `timeout` bounds the whole exchange.
    /// The answers describe one scene generation: when a load or reset comes between them, the
    /// questions are asked again.
    pub fn scene_info(&self, timeout: Duration) -> Result<SceneInfo, ClientError> {
        let deadline = deadline_after(timeout);
        loop {
            let summary = self.request(ControlRequest::scene_info(), deadline, timeout)?;
            if let Some(parts) = self.parts_of(&summary, deadline, timeout)? {
                return scene_info_of(&summary, parts);
            }
        }
    }

    /// Every part of the scene `summary` describes, or `None` if another generation of the
    /// scene answered meanwhile.
    fn parts_of(
        &self,
        summary: &ControlResponse,
        deadline: Instant,
        timeout: Duration,
    ) -> Result<Option<Vec<PartInfo>>, ClientError> {
        let mut parts = Vec::with_capacity(summary.part_count as usize);
        for id in 0..summary.part_count {
            let answer = self.exchange(ControlRequest::part_info(id), deadline, timeout)?;
            if answer.generation != summary.generation {
                return Ok(None);
            }
            let part = check_status(ControlRequestKind::PartInfo, answer)?.part;
            parts.push(PartInfo {
                id: part.id,
                name: part.name.as_str()?.to_owned(),
                group: part.group.as_str()?.to_owned(),
                mesh_source: part.mesh_source.as_str()?.to_owned(),
                movable: part.flags & PART_MOVABLE != 0,
                initial_pose: part.initial_pose,
                scale: part.scale,
                truncated: part.truncated != 0,
            });
        }
        Ok(Some(parts))
    }

    /// The server's input counters (rejected, clamped and accepted samples).
    pub fn input_stats(&self, timeout: Duration) -> Result<InputStats, ClientError> {
        Ok(self.control(ControlRequest::scene_info(), timeout)?.stats)
    }

    /// Asks the server to load the scene file at `path` (as the server's file system sees it).
    pub fn load_scene(
        &self,
        path: &str,
        timeout: Duration,
    ) -> Result<ControlResponse, ClientError> {
        let path = WireText::<MAX_PATH_BYTES>::new(path)?;
        self.control(ControlRequest::load_scene(path), timeout)
    }

    /// The names of the scenes the server may load by name ([`Client::load_named_scene`]);
    /// `timeout` bounds the whole exchange.
    pub fn scene_names(&self, timeout: Duration) -> Result<Vec<String>, ClientError> {
        let deadline = deadline_after(timeout);
        let first = self.request(ControlRequest::list_scene(0), deadline, timeout);
        let count = match &first {
            Ok(response) => response.listed_count,
            // An empty list refuses index 0.
            Err(ClientError::Refused { .. }) => return Ok(Vec::new()),
            Err(_) => return first.map(|_| Vec::new()),
        };
        let mut names = vec![first?.listed.as_str()?.to_owned()];
        for index in 1..count {
            let response = self.request(ControlRequest::list_scene(index), deadline, timeout)?;
            names.push(response.listed.as_str()?.to_owned());
        }
        Ok(names)
    }

    /// Asks the server to load the scene it offers as `name` (one of [`Client::scene_names`]).
    pub fn load_named_scene(
        &self,
        name: &str,
        timeout: Duration,
    ) -> Result<ControlResponse, ClientError> {
        let name = WireText::<MAX_PATH_BYTES>::new(name)?;
        self.control(ControlRequest::load_named_scene(name), timeout)
    }

    /// Asks the server to put the scene back to its initial state.
    pub fn reset(&self, timeout: Duration) -> Result<ControlResponse, ClientError> {
        self.control(ControlRequest::reset(), timeout)
    }

    /// Asks the server to slide grasped parts with `metaphor`.
    pub fn set_metaphor(
        &self,
        metaphor: SlidingMetaphor,
        timeout: Duration,
    ) -> Result<ControlResponse, ClientError> {
        self.control(ControlRequest::set_metaphor(metaphor), timeout)
    }

    /// Sends any control request and waits for its answer; a status other than
    /// [`ControlStatus::Ok`] is a [`ClientError::Refused`].
    pub fn control(
        &self,
        request: ControlRequest,
        timeout: Duration,
    ) -> Result<ControlResponse, ClientError> {
        self.request(request, deadline_after(timeout), timeout)
    }

    /// Sends `request` and waits for its answer, refusing any status but [`ControlStatus::Ok`].
    fn request(
        &self,
        request: ControlRequest,
        deadline: Instant,
        timeout: Duration,
    ) -> Result<ControlResponse, ClientError> {
        let kind = ControlRequestKind::try_from(request.kind)?;
        check_status(kind, self.exchange(request, deadline, timeout)?)
    }

    /// Sends `request` and waits for its answer, whatever its status.
    fn exchange(
        &self,
        request: ControlRequest,
        deadline: Instant,
        timeout: Duration,
    ) -> Result<ControlResponse, ClientError> {
        let kind = ControlRequestKind::try_from(request.kind)?;
        let timed_out = || ClientError::Timeout {
            what: format!("the control request {kind:?}"),
            timeout,
        };
        loop {
            let pending = self
                .control
                .send_copy(request)
                .map_err(|error| ClientError::ipc("send a control request", error))?;
            self.control_notifier
                .notify()
                .map_err(|error| ClientError::ipc("notify the control service", error))?;
            loop {
                if let Some(response) = pending
                    .receive()
                    .map_err(|error| ClientError::ipc("receive a control response", error))?
                {
                    return Ok(*response.payload());
                }
                let remaining = deadline.saturating_duration_since(Instant::now());
                if remaining.is_zero() {
                    return Err(timed_out());
                }
                // A request that reached a server is never sent again (loading a scene twice
                // would be wrong); one that reached none is sent again once a server may be up.
                // The nap is a sleep: this client's own notification wakes its control
                // listener at once, so that waiting on it would send the request again and
                // again, spinning for as long as no server is up.
                if pending.number_of_server_connections() == 0 {
                    std::thread::sleep(remaining.min(CONTROL_RETRY));
                    break;
                }
                self.control_listener
                    .timed_wait(|_| {}, remaining)
                    .map_err(|error| ClientError::ipc("wait for a control response", error))?;
            }
        }
    }
}

/// The scene `summary` describes, with its `parts`.
fn scene_info_of(
    summary: &ControlResponse,
    parts: Vec<PartInfo>,
) -> Result<SceneInfo, ClientError> {
    let hands = (summary.hands.iter())
        .take(summary.hand_count as usize)
        .map(|hand| {
            Ok(HandInfo {
                user: hand.user,
                side: HandSide::try_from(hand.side)?,
                model: hand.model.as_str()?.to_owned(),
            })
        })
        .collect::<Result<_, ClientError>>()?;
    Ok(SceneInfo {
        name: summary.scene_name.as_str()?.to_owned(),
        source: summary.scene_source.as_str()?.to_owned(),
        parts,
        stats: summary.stats,
        up: summary.up,
        metres_per_unit: summary.metres_per_unit,
        users: summary.user_names().map(str::to_owned).collect(),
        hands,
        scenes_offered: summary.listed_count,
        generation: summary.generation,
        metaphor: SlidingMetaphor::try_from(summary.metaphor)?,
    })
}

fn check_status(
    kind: ControlRequestKind,
    response: ControlResponse,
) -> Result<ControlResponse, ClientError> {
    match ControlStatus::try_from(response.status)? {
        ControlStatus::Ok => Ok(response),
        status => Err(ClientError::Refused {
            request: kind,
            status,
            message: response.message.as_str()?.to_owned(),
        }),
    }
}
