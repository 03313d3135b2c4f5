//! The input thread: tracker, glove and hand-joints samples from zenoh into the server's input
//! streams.
//!
//! A sample goes into the server as it came, once its bytes are the message its key carries
//! (length, envelope code and version) and its user is one the bridge accepts; the server then
//! validates it as any local input and counts it in its own counters. Refusals are counted in
//! the bridge's ([`crate::stats`]); the first of each run is a warning, later ones debug logs.
//! It blocks on the zenoh subscriber, not on a poll, so that a sample reaches iceoryx2 at once.

use vas_client::{Client, ClientError, Roles};
use vas_protocol::{ControlRequest, GloveSample, HandJointsSample, TrackerSample};
use zenoh::handlers::FifoChannelHandler;
use zenoh::pubsub::Subscriber;
use zenoh::sample::Sample;

use crate::keys::Input;
use crate::server::{CONTROL_TIMEOUT, Follower, Shared};
use crate::wire::{self, Refusal};

/// Which users' samples the bridge takes.
#[derive(Debug)]
struct Users {
    /// The names given with `--user`; empty: everyone.
    names: Vec<String>,
    /// The indices of those names in the scene of `known`: (epoch, generation, indices).
    known: Option<(u64, u64, Vec<u32>)>,
}

impl Users {
    /// Whether a sample of user `user` is taken, asking the server for its users' names when
    /// the server or its scene changed.
    fn accepts(&mut self, user: u32, client: &Client, shared: &Shared) -> bool {
        if self.names.is_empty() {
            return true;
        }
        let now = (
            shared.epoch(),
            shared.generation.load(std::sync::atomic::Ordering::Acquire),
        );
        if self
            .known
            .as_ref()
            .is_none_or(|(epoch, generation, _)| (*epoch, *generation) != now)
        {
            match client.control(ControlRequest::scene_info(), CONTROL_TIMEOUT) {
                Ok(response) => {
                    let indices = (self.names.iter())
                        .filter_map(|name| {
                            let index = response.user_index(name);
                            if index.is_none() {
                                tracing::warn!(user = name, "the scene has no such user");
                            }
                            index
                        })
                        .collect();
                    self.known = Some((now.0, now.1, indices));
                }
                Err(error) => {
                    tracing::warn!(%error, "cannot learn the scene's users");
                    return false;
                }
            }
        }
        (self.known.as_ref()).is_some_and(|(_, _, indices)| indices.contains(&user))
    }
}

/// Forwards samples from `subscriber` until the bridge stops.
pub fn run(
    subscriber: Subscriber<FifoChannelHandler<Sample>>,
    prefix: Option<&str>,
    users: Vec<String>,
    shared: &Shared,
) {
    let mut follower = Follower::new(prefix, Roles::INPUT);
    let mut users = Users {
        names: users,
        known: None,
    };
    let mut warned = false;
    while let Some(sample) = shared.next(&subscriber, "input subscriber") {
        let Some(client) = follower.client(shared) else {
            shared.stats.refused_by_server();
            continue;
        };
        let name = sample.key_expr().as_str().rsplit('/').next();
        let Some(stream) = Input::ALL
            .into_iter()
            .find(|stream| name == Some(stream.name()))
        else {
            continue;
        };
        match forward(
            stream,
            &sample.payload().to_bytes(),
            client,
            &mut users,
            shared,
        ) {
            Ok(()) => shared.stats.forwarded(stream),
            Err(refused) => {
                if warned {
                    tracing::debug!(stream = stream.name(), %refused, "input refused");
                } else {
                    let stream = stream.name();
                    tracing::warn!(stream, %refused, "input refused; more refusals are counted");
                    warned = true;
                }
                if let Refused::Server(_) = refused {
                    follower.drop_client();
                }
            }
        }
    }
}

/// Why a sample was not forwarded (each counted where it is decided).
#[derive(Debug, thiserror::Error)]
enum Refused {
    #[error(transparent)]
    Bytes(#[from] Refusal),
    #[error("user {0} is not one the bridge takes input for")]
    User(u32),
    #[error("the server's input stream refused it: {0}")]
    Server(#[from] ClientError),
}

/// Decodes a sample of `stream` and hands it to the server.
fn forward(
    stream: Input,
    bytes: &[u8],
    client: &Client,
    users: &mut Users,
    shared: &Shared,
) -> Result<(), Refused> {
    let counted = |refusal: Refusal| {
        shared.stats.refused(&refusal);
        refusal
    };
    let accept = |user: u32, users: &mut Users| {
        if users.accepts(user, client, shared) {
            Ok(())
        } else {
            shared.stats.refused_user();
            Err(Refused::User(user))
        }
    };
    let sent = match stream {
        Input::Tracker => {
            let sample = wire::decode::<TrackerSample>(bytes).map_err(counted)?;
            accept(sample.user, users)?;
            client.send_tracker(&sample)
        }
        Input::Glove => {
            let sample = wire::decode::<GloveSample>(bytes).map_err(counted)?;
            accept(sample.user, users)?;
            client.send_glove(&sample)
        }
        Input::HandJoints => {
            let sample = wire::decode::<HandJointsSample>(bytes).map_err(counted)?;
            accept(sample.user, users)?;
            client.send_hand_joints(&sample)
        }
    };
    sent.map_err(|error| {
        shared.stats.refused_by_server();
        Refused::Server(error)
    })
}
