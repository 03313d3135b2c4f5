//! The wire's codes in words: parts by name, events and grasps by kind, for tools and pages
//! that show them to people ("grasp peg (power) at sample 44").

use vas_protocol::{ClearancePair, EventKind, GraspType, HAND_PART_ID, HandSide, SimEvent};

use crate::SceneInfo;

/// Names for one scene's codes.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SceneWords {
    parts: Vec<String>,
    /// The users' names, by index.
    users: Vec<String>,
}

impl SceneWords {
    /// The words of `scene`'s parts and users.
    pub fn new(scene: &SceneInfo) -> Self {
        Self {
            parts: scene.parts.iter().map(|part| part.name.clone()).collect(),
            users: scene.users.clone(),
        }
    }

    /// User `user`'s name; "user N" for an index the scene does not have (a frame of another
    /// scene).
    pub fn user(&self, user: u32) -> String {
        match self.users.get(user as usize) {
            Some(name) => name.clone(),
            None => format!("user {user}"),
        }
    }

    /// Whether the sentences name whose hand an event is about: in a scene of several users.
    pub fn names_users(&self) -> bool {
        self.users.len() > 1
    }

    /// Whose hand `event` is about, when the scene has several users: "anna's right hand". A
    /// scene of one user needs no name, and its sentences stay those it always had.
    fn users_hand(&self, event: &SimEvent) -> Option<String> {
        self.names_users()
            .then(|| format!("{}'s {} hand", self.user(event.user), hand_name(event.hand)))
    }

    /// Part `id`'s name; "hand" for [`HAND_PART_ID`], and "part N" for an id the scene does not
    /// have (a frame of another scene).
    pub fn part(&self, id: u32) -> String {
        match self.parts.get(id as usize) {
            Some(name) => name.clone(),
            None if id == HAND_PART_ID => "hand".to_owned(),
            None => format!("part {id}"),
        }
    }

    /// The event in a sentence: "grasp peg (power) at sample 44", "release peg at sample 90",
    /// "push begin block by the right hand at sample 30",
    /// "contact begin peg – block at sample 61", "clearance peg – block 0.8 mm at sample 177",
    /// "clearance restored peg – block 5.6 mm at sample 198". The sample is the input that caused it (the
    /// newest of the frame's tracker, glove and hand-joints samples).
    ///
    /// In a scene of several users, a hand's event starts with whose hand it is: "anna's right
    /// hand grasps peg (power) at sample 44", "... releases peg", "... hands peg over",
    /// "... begins pushing block", "... stops pushing block", and a contact with a hand names
    /// it: "contact begin peg – ben's left hand".
    pub fn event(&self, event: &SimEvent) -> String {
        let sample = [event.tracker, event.glove, event.joints]
            .into_iter()
            .reduce(|newest, stamp| {
                if stamp.timestamp_ns > newest.timestamp_ns {
                    stamp
                } else {
                    newest
                }
            })
            .map_or(0, |stamp| stamp.seq);
        let part = self.part(event.part);
        let kind = EventKind::try_from(event.kind);
        let what = match (kind, self.users_hand(event)) {
            (Ok(EventKind::Grasp), Some(hand)) => {
                format!("{hand} grasps {part} ({})", grasp_name(event.grasp_type))
            }
            (Ok(EventKind::Release), Some(hand)) => format!("{hand} releases {part}"),
            (Ok(EventKind::HandOver), Some(hand)) => format!("{hand} hands {part} over"),
            (Ok(EventKind::PushBegin), Some(hand)) => format!("{hand} begins pushing {part}"),
            (Ok(EventKind::PushEnd), Some(hand)) => format!("{hand} stops pushing {part}"),
            (Ok(kind @ (EventKind::ContactBegin | EventKind::ContactEnd)), Some(hand))
                if event.other == HAND_PART_ID =>
            {
                format!("{} {part} – {hand}", kind.name().replace('_', " "))
            }
            _ => self.single_user_event(event, kind, &part),
        };
        format!("{what} at sample {sample}")
    }

    /// The event's words in a scene of one user (and the events of no hand in any scene).
    fn single_user_event(
        &self,
        event: &SimEvent,
        kind: Result<EventKind, vas_protocol::UnknownCode>,
        part: &str,
    ) -> String {
        match kind {
            Ok(EventKind::Grasp) => format!("grasp {part} ({})", grasp_name(event.grasp_type)),
            Ok(EventKind::Release) => format!("release {part}"),
            Ok(EventKind::HandOver) => {
                format!("hand over {part} from the {} hand", hand_name(event.hand))
            }
            Ok(kind @ (EventKind::PushBegin | EventKind::PushEnd)) => {
                let verb = kind.name().replace('_', " ");
                format!("{verb} {part} by the {} hand", hand_name(event.hand))
            }
            Ok(kind @ (EventKind::ContactBegin | EventKind::ContactEnd)) => {
                let verb = kind.name().replace('_', " ");
                format!("{verb} {part} – {}", self.part(event.other))
            }
            Ok(kind @ (EventKind::ClearanceBelow | EventKind::ClearanceRestored)) => {
                let verb = match kind {
                    EventKind::ClearanceBelow => "clearance",
                    _ => "clearance restored",
                };
                let other = self.part(event.other);
                format!("{verb} {part} – {other} {}", millimetres(event.distance))
            }
            Err(unknown) => format!("{unknown} about {part}"),
        }
    }
}

impl SceneWords {
    /// A clearance pair in words: "peg – block 0.8 mm", with " (stale)" when it carries an
    /// earlier frame's measurement.
    pub fn clearance(&self, pair: &ClearancePair) -> String {
        let stale = if pair.is_stale() { " (stale)" } else { "" };
        let (part, other) = (self.part(pair.part), self.part(pair.other));
        format!("{part} – {other} {}{stale}", millimetres(pair.distance))
    }
}

/// A distance in metres as millimetres to a tenth: "0.8 mm".
fn millimetres(metres: f64) -> String {
    format!("{:.1} mm", metres * 1e3)
}

/// A grasp type code in words (`power`, `tip_pinch`...), or "unknown" for a code this client
/// does not know.
pub fn grasp_name(code: u32) -> &'static str {
    GraspType::try_from(code).map_or("unknown", GraspType::name)
}

/// An event kind code in words (`grasp`, `contact_begin`...), or "unknown".
pub fn event_name(code: u32) -> &'static str {
    EventKind::try_from(code).map_or("unknown", EventKind::name)
}

/// A hand side code in words (`right`, `left`), or "unknown".
pub fn hand_name(code: u32) -> &'static str {
    HandSide::try_from(code).map_or("unknown", HandSide::name)
}

#[cfg(test)]
mod tests {
    use vas_protocol::{InputStamp, InputStats, WirePose};

    use super::*;
    use crate::PartInfo;

    fn words() -> SceneWords {
        words_of_users(&["user"])
    }

    fn words_of_users(users: &[&str]) -> SceneWords {
        let part = |id: u32, name: &str| PartInfo {
            id,
            name: name.to_owned(),
            group: String::new(),
            mesh_source: String::new(),
            movable: true,
            initial_pose: WirePose::IDENTITY,
            scale: 1.0,
            truncated: false,
        };
        SceneWords::new(&SceneInfo {
            name: "s".into(),
            source: "s.toml".into(),
            parts: vec![part(0, "block"), part(1, "peg")],
            stats: InputStats::default(),
            up: [0.0, 0.0, 1.0],
            metres_per_unit: 1.0,
            users: users.iter().map(|&user| user.to_owned()).collect(),
            hands: Vec::new(),
            scenes_offered: 0,
            generation: 1,
            metaphor: vas_protocol::SlidingMetaphor::default(),
        })
    }

    fn event(kind: EventKind, grasp: GraspType, part: u32, other: u32) -> SimEvent {
        SimEvent {
            frame: 3,
            tracker: InputStamp {
                seq: 44,
                timestamp_ns: 2,
            },
            glove: InputStamp {
                seq: 7,
                timestamp_ns: 1,
            },
            joints: InputStamp::default(),
            timestamp_ns: 5,
            kind: kind as u32,
            grasp_type: grasp as u32,
            part,
            other,
            hand: HandSide::Right as u32,
            segment: 0,
            point: [0.0; 3],
            normal: [0.0; 3],
            other_point: [0.0; 3],
            distance: 0.0,
            user: 0,
            reserved: 0,
        }
    }

    #[test]
    fn events_of_several_users_name_whose_hand() {
        let words = words_of_users(&["anna", "ben"]);
        let mut grasp = event(EventKind::Grasp, GraspType::Power, 1, HAND_PART_ID);
        assert_eq!(
            words.event(&grasp),
            "anna's right hand grasps peg (power) at sample 44"
        );
        grasp.user = 1;
        grasp.hand = HandSide::Left as u32;
        assert_eq!(
            words.event(&grasp),
            "ben's left hand grasps peg (power) at sample 44"
        );
        let sentence = |kind: EventKind, other: u32| {
            let mut event = event(kind, GraspType::None, 1, other);
            event.user = 1;
            words.event(&event)
        };
        assert_eq!(
            sentence(EventKind::Release, HAND_PART_ID),
            "ben's right hand releases peg at sample 44"
        );
        assert_eq!(
            sentence(EventKind::HandOver, HAND_PART_ID),
            "ben's right hand hands peg over at sample 44"
        );
        assert_eq!(
            sentence(EventKind::PushBegin, HAND_PART_ID),
            "ben's right hand begins pushing peg at sample 44"
        );
        assert_eq!(
            sentence(EventKind::ContactBegin, HAND_PART_ID),
            "contact begin peg – ben's right hand at sample 44"
        );
        assert_eq!(
            sentence(EventKind::ContactEnd, 0),
            "contact end peg – block at sample 44",
            "a contact between parts names no hand"
        );
        grasp.user = 7;
        assert_eq!(
            words.event(&grasp),
            "user 7's left hand grasps peg (power) at sample 44"
        );
    }

    #[test]
    fn events_read_as_sentences_with_part_names() {
        let words = words();
        let grasp = event(EventKind::Grasp, GraspType::Power, 1, HAND_PART_ID);
        assert_eq!(words.event(&grasp), "grasp peg (power) at sample 44");
        let contact = event(EventKind::ContactBegin, GraspType::None, 1, 0);
        assert_eq!(
            words.event(&contact),
            "contact begin peg – block at sample 44"
        );
        let mut release = event(EventKind::Release, GraspType::None, 1, HAND_PART_ID);
        release.glove.timestamp_ns = 9;
        assert_eq!(words.event(&release), "release peg at sample 7");
        release.joints = InputStamp {
            seq: 12,
            timestamp_ns: 10,
        };
        assert_eq!(words.event(&release), "release peg at sample 12");
        let mut hand_over = event(EventKind::HandOver, GraspType::None, 1, HAND_PART_ID);
        hand_over.hand = HandSide::Left as u32;
        assert_eq!(
            words.event(&hand_over),
            "hand over peg from the left hand at sample 44"
        );
        let push = event(EventKind::PushBegin, GraspType::None, 1, HAND_PART_ID);
        assert_eq!(
            words.event(&push),
            "push begin peg by the right hand at sample 44"
        );
        let push_end = event(EventKind::PushEnd, GraspType::None, 1, HAND_PART_ID);
        assert_eq!(
            words.event(&push_end),
            "push end peg by the right hand at sample 44"
        );
        let mut below = event(EventKind::ClearanceBelow, GraspType::None, 1, 0);
        below.distance = 0.000_8;
        assert_eq!(
            words.event(&below),
            "clearance peg – block 0.8 mm at sample 44"
        );
        let mut restored = event(EventKind::ClearanceRestored, GraspType::None, 1, 0);
        restored.distance = 0.005_62;
        assert_eq!(
            words.event(&restored),
            "clearance restored peg – block 5.6 mm at sample 44"
        );
        let mut pair = ClearancePair {
            part: 1,
            other: 0,
            distance: 0.001_3,
            ..ClearancePair::default()
        };
        assert_eq!(words.clearance(&pair), "peg – block 1.3 mm");
        pair.flags = vas_protocol::CLEARANCE_STALE;
        assert_eq!(words.clearance(&pair), "peg – block 1.3 mm (stale)");
        assert_eq!(words.part(HAND_PART_ID), "hand");
        assert_eq!(words.part(5), "part 5");
        assert_eq!(
            (grasp_name(99), event_name(0), hand_name(1)),
            ("unknown", "unknown", "left")
        );
    }
}
