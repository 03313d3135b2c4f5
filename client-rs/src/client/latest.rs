//! The newest state a client received: what a renderer draws from.

use std::sync::Arc;

use vas_protocol::{ClearanceFrame, HandFrame, HandSide, SceneGeometry};

use super::frames::{Frame, PartsFrame};

/// The newest frame of each kind, and of each hand, that [`super::Client::receive`] took.
#[derive(Debug, Default)]
pub(super) struct Latest {
    pub(super) parts: Option<PartsFrame>,
    /// The newest frame of each hand of the current scene, ordered by user, then by
    /// [`HandSide`] code (right, then left): one per hand.
    pub(super) hands: Vec<HandFrame>,
    pub(super) clearance: Option<Box<ClearanceFrame>>,
    pub(super) geometry: Option<Arc<SceneGeometry>>,
}

impl Latest {
    /// Keeps `frame` as the newest of its kind (a hand frame: of its hand); events and force
    /// frames are not state.
    pub(super) fn keep(&mut self, frame: &Frame) {
        match frame {
            Frame::Geometry(geometry) => self.keep_geometry(geometry),
            Frame::Parts(parts) => self.parts = Some(parts.clone()),
            Frame::Hand(hand) => self.keep_hand(hand),
            Frame::Clearance(frame) => self.clearance = Some(frame.clone()),
            Frame::Event(_) | Frame::Force(_) => {}
        }
    }

    /// A new scene generation: forgets the hands the new scene does not have (a hand it has
    /// keeps its frame until the next one, as the server keeps the hand where it was).
    fn keep_geometry(&mut self, geometry: &Arc<SceneGeometry>) {
        self.geometry = Some(Arc::clone(geometry));
        (self.hands).retain(|hand| {
            hand.side()
                .is_some_and(|side| has_hand(Some(geometry), hand.user, side))
        });
    }

    /// Keeps `hand` as its hand's newest frame, unless the current scene has no such hand: a
    /// frame of the scene before a load can still arrive after the new scene's geometry. A
    /// side this build cannot decode has no place in the order and is not kept.
    fn keep_hand(&mut self, hand: &HandFrame) {
        let geometry = self.geometry.as_deref();
        if !hand
            .side()
            .is_some_and(|side| has_hand(geometry, hand.user, side))
        {
            return;
        }
        match (self.hands)
            .binary_search_by_key(&(hand.user, hand.hand), |kept| (kept.user, kept.hand))
        {
            Ok(index) => self.hands[index] = *hand,
            Err(index) => self.hands.insert(index, *hand),
        }
    }

    /// The newest frame of user `user`'s hand on `side`.
    pub(super) fn hand_of(&self, user: u32, side: HandSide) -> Option<&HandFrame> {
        (self.hands.iter()).find(|hand| hand.user == user && hand.hand == side as u32)
    }
}

/// Whether the scene of `geometry` has user `user`'s hand on `side`: one of its hand models,
/// or, in a scene without hand models, the first user's right hand (the tracked hand the server
/// publishes there). Every hand before the first geometry.
fn has_hand(geometry: Option<&SceneGeometry>, user: u32, side: HandSide) -> bool {
    match geometry {
        None => true,
        Some(geometry) if geometry.hands.is_empty() => user == 0 && side == HandSide::Right,
        Some(geometry) => {
            (geometry.hands.iter()).any(|hand| hand.user == user && hand.side == side)
        }
    }
}

#[cfg(test)]
mod tests {
    use vas_protocol::{HandGeometry, SceneGeometry};

    use super::*;

    fn hand(side: HandSide, frame: u64) -> Frame {
        users_hand(0, side, frame)
    }

    fn users_hand(user: u32, side: HandSide, frame: u64) -> Frame {
        Frame::Hand(HandFrame {
            frame,
            hand: side as u32,
            user,
            ..HandFrame::default()
        })
    }

    fn geometry(generation: u64, sides: &[HandSide]) -> Frame {
        users_geometry(
            generation,
            &sides.iter().map(|&side| (0, side)).collect::<Vec<_>>(),
        )
    }

    fn users_geometry(generation: u64, hands: &[(u32, HandSide)]) -> Frame {
        Frame::Geometry(Arc::new(SceneGeometry {
            generation,
            hands: (hands.iter())
                .map(|&(user, side)| HandGeometry {
                    user,
                    side,
                    model: String::new(),
                    segments: Vec::new(),
                })
                .collect(),
            ..SceneGeometry::default()
        }))
    }

    /// The kept hands as (side, frame) pairs.
    fn kept(latest: &Latest) -> Vec<(u32, u64)> {
        (latest.hands.iter())
            .map(|hand| (hand.hand, hand.frame))
            .collect()
    }

    #[test]
    fn keeps_the_newest_frame_of_each_hand_right_first() {
        let (right, left) = (HandSide::Right as u32, HandSide::Left as u32);
        let mut latest = Latest::default();
        latest.keep(&geometry(1, &[HandSide::Right, HandSide::Left]));
        latest.keep(&hand(HandSide::Left, 4));
        assert_eq!(kept(&latest), [(left, 4)]);
        latest.keep(&hand(HandSide::Right, 5));
        latest.keep(&hand(HandSide::Left, 5));
        assert_eq!(kept(&latest), [(right, 5), (left, 5)]);
        latest.keep(&hand(HandSide::Right, 6));
        assert_eq!(kept(&latest), [(right, 6), (left, 5)]);
        assert_eq!(latest.hand_of(0, HandSide::Left).map(|h| h.frame), Some(5));

        let unknown = Frame::Hand(HandFrame {
            hand: 7,
            ..HandFrame::default()
        });
        latest.keep(&unknown);
        assert_eq!(kept(&latest), [(right, 6), (left, 5)]);
    }

    #[test]
    fn a_new_scene_forgets_the_hands_it_does_not_have() {
        let (right, left) = (HandSide::Right as u32, HandSide::Left as u32);
        let mut latest = Latest::default();
        latest.keep(&hand(HandSide::Right, 1));
        latest.keep(&hand(HandSide::Left, 1));
        latest.keep(&geometry(2, &[HandSide::Left]));
        assert_eq!(kept(&latest), [(left, 1)]);
        // A frame of the old scene that comes after the new geometry is not kept.
        latest.keep(&hand(HandSide::Right, 2));
        assert_eq!(kept(&latest), [(left, 1)]);
        assert!(latest.hand_of(0, HandSide::Right).is_none());

        // A scene without hand models has the tracked hand, the right one.
        latest.keep(&geometry(3, &[]));
        assert!(latest.hands.is_empty());
        latest.keep(&hand(HandSide::Left, 3));
        latest.keep(&hand(HandSide::Right, 3));
        assert_eq!(kept(&latest), [(right, 3)]);
    }

    #[test]
    fn every_users_hands_are_kept_apart_in_user_order() {
        let (right, left) = (HandSide::Right, HandSide::Left);
        let mut latest = Latest::default();
        latest.keep(&users_geometry(1, &[(0, right), (1, right), (1, left)]));
        latest.keep(&users_hand(1, left, 2));
        latest.keep(&users_hand(1, right, 2));
        latest.keep(&users_hand(0, right, 2));
        latest.keep(&users_hand(0, left, 2));
        latest.keep(&users_hand(2, right, 2));
        let kept: Vec<(u32, u32)> = (latest.hands.iter()).map(|h| (h.user, h.hand)).collect();
        assert_eq!(
            kept,
            [(0, 0), (1, 0), (1, 1)],
            "user 0 has no left hand, user 2 none"
        );
        latest.keep(&users_hand(1, right, 3));
        assert_eq!(latest.hand_of(1, right).map(|h| h.frame), Some(3));
        assert_eq!(latest.hand_of(0, right).map(|h| h.frame), Some(2));
        latest.keep(&users_geometry(2, &[(1, right)]));
        assert_eq!(latest.hands.len(), 1);
        assert!(latest.hand_of(0, right).is_none());
    }
}
