//! One page's WebSocket: what it is sent, and the commands it may send.
//!
//! On connecting, a page is sent the server's status, the scene and the newest frame; then
//! whatever changes, newest state first-come (see [`crate::hub`]). Frames are flow-controlled:
//! a page acknowledges each frame it takes, and is sent a frame only while fewer than
//! [`FRAMES_IN_FLIGHT`] are unacknowledged, so a slow page is sent the newest frame when it is
//! ready for one and no backlog builds up in the socket or the browser. A page has at most one
//! command waiting for the server; another sent meanwhile is answered with a refusal. Hand
//! joints from a WebXR session go to the link thread as they come (see [`Hub::submit_hand_joints`]).
//! A page that sends nothing for the idle time-out, not even the pong a browser answers the
//! viewer's pings with, is gone or hostile: it is closed, so that it does not hold a place.

use std::sync::Arc;
use std::time::Duration;

use axum::extract::ws::{CloseFrame, Message, WebSocket, close_code};
use tokio::sync::broadcast::error::RecvError;
use vas_client::wall_clock_ns;

use crate::commands::{self, MAX_COMMAND_BYTES, PageMessage, Refusal};
use crate::hand_joints::{self, HandJoints};
use crate::hub::Hub;
use crate::messages;
use crate::stats::Stats;

/// The largest WebSocket message or frame read from a page at all: beyond it the connection
/// fails in the WebSocket layer. Between [`MAX_COMMAND_BYTES`] and this, a message is read and
/// refused as oversized.
pub const MAX_READ_BYTES: usize = 4 * MAX_COMMAND_BYTES;

/// Frames a page may have been sent and not yet acknowledged. Two keep one frame on its way
/// while the page takes the other, so a fast page loses no time to the round trip.
pub const FRAMES_IN_FLIGHT: u32 = 2;

/// The frames sent to a page and not yet acknowledged.
#[derive(Debug, Default)]
pub struct InFlight(u32);

impl InFlight {
    /// Whether another frame may be sent.
    pub fn has_room(&self) -> bool {
        self.0 < FRAMES_IN_FLIGHT
    }

    /// Counts a frame sent.
    pub fn sent(&mut self) {
        self.0 += 1;
    }

    /// Counts an acknowledgement; one for no frame is refused (the page is broken or hostile).
    pub fn acked(&mut self) -> Result<(), Refusal> {
        self.0 = self.0.checked_sub(1).ok_or(Refusal::Malformed)?;
        Ok(())
    }
}

/// Why a page's connection ended.
#[derive(Debug, PartialEq)]
pub enum End {
    /// The page closed it, or it broke.
    Gone,
    /// The page sent nothing for the idle time-out.
    Idle,
    /// The page sent something that is not a command.
    Refused(Refusal),
}

/// Serves one page until it goes away, is refused or stays silent for `idle`.
pub async fn serve(mut socket: WebSocket, hub: Arc<Hub>, idle: Duration) {
    Stats::count(&hub.stats.pages_served);
    Stats::count(&hub.stats.pages_open);
    let end = run(&mut socket, &hub, idle).await;
    hub.stats
        .pages_open
        .fetch_sub(1, std::sync::atomic::Ordering::Relaxed);
    if end == End::Idle {
        Stats::count(&hub.stats.timed_out_pages);
        tracing::info!(
            ?idle,
            "a page sent nothing for the idle time-out; closed it"
        );
        let close = CloseFrame {
            code: close_code::AWAY,
            reason: "idle: nothing received for the idle time-out".into(),
        };
        let _ = socket.send(Message::Close(Some(close))).await;
    }
    if let End::Refused(refusal) = end {
        Stats::count(match refusal {
            Refusal::Malformed => &hub.stats.refused_malformed,
            Refusal::Oversized => &hub.stats.refused_oversized,
            Refusal::Unknown => &hub.stats.refused_unknown,
            Refusal::HandJoints(_) => &hub.stats.hand_joints_rejected,
        });
        tracing::warn!(
            reason = refusal.reason(),
            "a page sent a bad message; closed it"
        );
        let close = CloseFrame {
            code: close_code::POLICY,
            reason: refusal.reason().into(),
        };
        // The page may be gone already; nothing else to do then.
        let _ = socket.send(Message::Close(Some(close))).await;
    }
}

async fn run(socket: &mut WebSocket, hub: &Hub, idle: Duration) -> End {
    let mut scene = hub.scene.subscribe();
    let mut frame = hub.frame.subscribe();
    let mut status = hub.status.subscribe();
    let mut events = hub.events.subscribe();
    // Everything current counts as changed, so the first turns of the loop send it all.
    scene.mark_changed();
    frame.mark_changed();
    status.mark_changed();
    let mut waiting: Option<(&'static str, tokio::sync::oneshot::Receiver<_>)> = None;
    let mut in_flight = InFlight::default();
    // Pinged twice per idle time-out: a live browser answers each ping, so only a page that is
    // gone or does not read stays silent for the whole of it.
    let mut ping = tokio::time::interval(idle / 2);
    ping.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    ping.tick().await;
    let silence = tokio::time::sleep(idle);
    tokio::pin!(silence);

    loop {
        // Biased: the status and scene go before the frames that refer to them, and answers
        // and events before the next frame.
        let sent = tokio::select! {
            biased;
            Ok(()) = status.changed() => {
                let message = status.borrow_and_update().clone();
                send_all(socket, message).await
            }
            Ok(()) = scene.changed() => {
                let messages = scene.borrow_and_update().clone();
                send_all(socket, messages.description.into_iter().chain(messages.meshes)).await
            }
            answer = async { (&mut waiting.as_mut().expect("guarded").1).await },
                if waiting.is_some() =>
            {
                let (command, _) = waiting.take().expect("guarded");
                let answer = answer.unwrap_or_else(|_| Err("the viewer is stopping".to_owned()));
                Stats::count(&hub.stats.commands);
                send_all(socket, Some(messages::reply(command, &answer))).await
            }
            event = events.recv() => match event {
                Ok(message) => send_all(socket, Some(message)).await,
                Err(RecvError::Lagged(missed)) => {
                    hub.stats
                        .events_dropped
                        .fetch_add(missed, std::sync::atomic::Ordering::Relaxed);
                    tracing::warn!(missed, "a page fell behind; it missed the oldest events");
                    let warning = format!("{missed} events were dropped: this page fell behind");
                    send_all(socket, Some(messages::warning(&warning))).await
                }
                Err(RecvError::Closed) => return End::Gone,
            },
            Ok(()) = frame.changed(), if in_flight.has_room() => {
                let newest = frame.borrow_and_update().clone();
                match newest {
                    Some(message) => {
                        in_flight.sent();
                        send_all(socket, Some(message)).await
                    }
                    None => true,
                }
            }
            received = socket.recv() => match received {
                Some(Ok(message)) => {
                    silence.as_mut().reset(tokio::time::Instant::now() + idle);
                    match judge(&message) {
                    Judged::Ack => match in_flight.acked() {
                        Ok(()) => true,
                        Err(refusal) => return End::Refused(refusal),
                    },
                    Judged::Command(command) if waiting.is_some() => {
                        let busy = Err("the last command is not answered yet; try again".into());
                        send_all(socket, Some(messages::reply(command.name(), &busy))).await
                    }
                    Judged::Command(command) => {
                        waiting = Some((command.name(), hub.submit(command)));
                        true
                    }
                    Judged::HandJoints(joints) => {
                        hub.submit_hand_joints(*joints, wall_clock_ns());
                        true
                    }
                    Judged::Refused(refusal) => return End::Refused(refusal),
                    Judged::Nothing => true,
                    Judged::Closed => return End::Gone,
                    }
                }
                None => return End::Gone,
                Some(Err(error)) => return ended_by(error),
            },
            () = &mut silence => return End::Idle,
            _ = ping.tick() => send_all(socket, Some(Message::Ping(Default::default()))).await,
        };
        if !sent {
            return End::Gone;
        }
    }
}

/// Why reading from a page failed: a connection dropped without a close frame (a tab closed, a
/// network gone) is no bad message; a frame beyond [`MAX_READ_BYTES`] is oversized, and any other
/// broken frame malformed.
pub fn ended_by(error: axum::Error) -> End {
    use tungstenite::error::{Error, ProtocolError};
    match error.into_inner().downcast::<Error>().map(|error| *error) {
        Ok(
            Error::Io(_)
            | Error::ConnectionClosed
            | Error::AlreadyClosed
            | Error::Protocol(ProtocolError::ResetWithoutClosingHandshake),
        ) => End::Gone,
        Ok(Error::Capacity(_)) => End::Refused(Refusal::Oversized),
        _ => End::Refused(Refusal::Malformed),
    }
}

/// What a message from a page comes to.
#[derive(Debug, PartialEq)]
pub enum Judged {
    /// The page took a frame.
    Ack,
    /// A command to carry out.
    Command(commands::Command),
    /// One hand of a WebXR session's frame, to publish.
    HandJoints(Box<HandJoints>),
    /// Not a command: the page is closed, and the refusal counted.
    Refused(Refusal),
    /// Nothing to do (the WebSocket layer answers pings itself).
    Nothing,
    /// The page closes its connection.
    Closed,
}

/// Judges one message from a page: only a text message holding a command or an acknowledgement,
/// and a binary hand-joints message, are taken.
pub fn judge(message: &Message) -> Judged {
    match message {
        Message::Text(text) => match commands::parse(text.as_str()) {
            Ok(PageMessage::Ack) => Judged::Ack,
            Ok(PageMessage::Command(command)) => Judged::Command(command),
            Err(refusal) => Judged::Refused(refusal),
        },
        Message::Binary(bytes) if hand_joints::is_hand_joints(bytes) => {
            match HandJoints::parse(bytes) {
                Ok(joints) => Judged::HandJoints(Box::new(joints)),
                Err(error) => Judged::Refused(Refusal::HandJoints(error)),
            }
        }
        Message::Binary(bytes) if bytes.len() > MAX_COMMAND_BYTES => {
            Judged::Refused(Refusal::Oversized)
        }
        Message::Binary(_) => Judged::Refused(Refusal::Malformed),
        Message::Ping(_) | Message::Pong(_) => Judged::Nothing,
        Message::Close(_) => Judged::Closed,
    }
}

/// Sends `messages` in order; false once the page is gone.
async fn send_all(socket: &mut WebSocket, messages: impl IntoIterator<Item = Message>) -> bool {
    for message in messages {
        if socket.send(message).await.is_err() {
            return false;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hand_joints::{HandJointsError, WEBXR_JOINT_COUNT, encode};

    #[test]
    fn binary_hand_joints_are_taken_and_other_binary_refused() {
        let untracked = encode(0, 1, &[None; WEBXR_JOINT_COUNT]);
        match judge(&Message::Binary(untracked.clone().into())) {
            Judged::HandJoints(joints) => assert!(!joints.any_valid()),
            other => panic!("{other:?}"),
        }
        let mut huge = untracked.clone();
        huge.resize(10 * MAX_COMMAND_BYTES, 0);
        assert_eq!(
            judge(&Message::Binary(huge.into())),
            Judged::Refused(Refusal::HandJoints(HandJointsError::Length))
        );
        let mut no_side = untracked;
        no_side[8] = 9;
        assert_eq!(
            judge(&Message::Binary(no_side.into())),
            Judged::Refused(Refusal::HandJoints(HandJointsError::Side))
        );
        assert_eq!(
            judge(&Message::Binary(vec![2, 0, 0, 0].into())),
            Judged::Refused(Refusal::Malformed)
        );
        // The same bytes as text are no command.
        let text = String::from_utf8_lossy(&encode(0, 0, &[None; WEBXR_JOINT_COUNT])).into_owned();
        assert_eq!(
            judge(&Message::Text(text.into())),
            Judged::Refused(Refusal::Malformed)
        );
    }

    #[test]
    fn frames_wait_for_room_and_acks_for_no_frame_are_refused() {
        let mut in_flight = InFlight::default();
        for _ in 0..FRAMES_IN_FLIGHT {
            assert!(in_flight.has_room());
            in_flight.sent();
        }
        assert!(!in_flight.has_room());
        assert_eq!(in_flight.acked(), Ok(()));
        assert!(in_flight.has_room());
        for _ in 1..FRAMES_IN_FLIGHT {
            assert_eq!(in_flight.acked(), Ok(()));
        }
        assert_eq!(in_flight.acked(), Err(Refusal::Malformed));
    }
}
