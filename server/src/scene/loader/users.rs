//! The scene's users and their hand models: `[[users]]`, each with a name and one or two hands,
//! or the top-level `hand` / `hands` of a scene of one user.

use std::path::PathBuf;
use std::sync::Arc;

use vas_protocol::{MAX_NAME_BYTES, MAX_USERS};

use super::Loader;
use crate::grasping::HandModel;
use crate::scene::file::UserFile;
use crate::scene::{DEFAULT_USER, SceneError, SceneHand};

/// A user as the config lists them: the key their entry is at, their name, and their hand
/// files with each one's key.
struct ListedUser {
    key: String,
    name: String,
    hands: Vec<(String, PathBuf)>,
}

impl Loader<'_> {
    /// The users' names and every user's hand models, grouped by user: `[[users]]`, or one user
    /// ([`DEFAULT_USER`]) with the top-level `hand` or `hands` (not both, and not beside
    /// `[[users]]`).
    pub(super) fn users(
        &self,
        hand: Option<PathBuf>,
        hands: Option<Vec<PathBuf>>,
        users: Vec<UserFile>,
    ) -> Result<(Vec<String>, Vec<SceneHand>), SceneError> {
        let listed = if users.is_empty() {
            vec![ListedUser {
                key: String::new(),
                name: DEFAULT_USER.to_owned(),
                hands: self.hand_files("", hand, hands)?,
            }]
        } else if hand.is_some() || hands.is_some() {
            let key = if hand.is_some() { "hand" } else { "hands" };
            return Err(self.invalid(
                key,
                "give each user's hands in [[users]], or `hand` / `hands` for one user, not both",
            ));
        } else {
            self.listed_users(users)?
        };
        let mut names = Vec::with_capacity(listed.len());
        let mut scene_hands = Vec::new();
        for (user, listed) in (0u32..).zip(listed) {
            let first = scene_hands.len();
            for (key, file) in listed.hands {
                let path = self.folder.join(&file);
                let model = HandModel::load_within(&path, self.limits)
                    .map_err(|error| self.invalid(&key, error.to_string()))?;
                let ours: &[SceneHand] = &scene_hands[first..];
                if ours.iter().any(|other| other.model.side() == model.side()) {
                    let whose = if listed.key.is_empty() {
                        "a scene's user"
                    } else {
                        "a user"
                    };
                    return Err(self.invalid(
                        key,
                        format!(
                            "a second {} hand: {whose} has at most one of each side",
                            model.side().name()
                        ),
                    ));
                }
                scene_hands.push(SceneHand {
                    user,
                    path,
                    model: Arc::new(model),
                });
            }
            names.push(listed.name);
        }
        Ok((names, scene_hands))
    }

    /// `[[users]]` checked: at most [`MAX_USERS`], each with a name that is not empty, fits the
    /// wire and is no other's, and at least one hand.
    fn listed_users(&self, users: Vec<UserFile>) -> Result<Vec<ListedUser>, SceneError> {
        if users.len() > MAX_USERS {
            return Err(self.invalid(
                "users",
                format!("{} users; a scene has at most {MAX_USERS}", users.len()),
            ));
        }
        let mut listed: Vec<ListedUser> = Vec::with_capacity(users.len());
        for (index, user) in users.into_iter().enumerate() {
            let key = format!("users[{index}]");
            let name_key = format!("{key}.name");
            self.name(&name_key, &user.name)?;
            if user.name.len() > MAX_NAME_BYTES {
                return Err(self.invalid(
                    name_key,
                    format!(
                        "is {} bytes long; a user's name has at most {MAX_NAME_BYTES} (UTF-8), \
                         as it travels in the scene info",
                        user.name.len()
                    ),
                ));
            }
            if let Some(first) = listed.iter().position(|other| other.name == user.name) {
                return Err(self.invalid(name_key, format!("is the name of users[{first}] too")));
            }
            let hands = self.hand_files(&format!("{key}."), user.hand, user.hands)?;
            if hands.is_empty() {
                return Err(self.invalid(key, "has no hand: give `hand` or `hands` (one or two)"));
            }
            listed.push(ListedUser {
                key,
                name: user.name,
                hands,
            });
        }
        Ok(listed)
    }

    /// The hand files of `hand` or `hands` (not both), each with its key under `prefix`.
    fn hand_files(
        &self,
        prefix: &str,
        hand: Option<PathBuf>,
        hands: Option<Vec<PathBuf>>,
    ) -> Result<Vec<(String, PathBuf)>, SceneError> {
        let files = match (hand, hands) {
            (Some(_), Some(_)) => {
                return Err(
                    self.invalid(format!("{prefix}hands"), "give `hand` or `hands`, not both")
                );
            }
            (Some(hand), None) => vec![(format!("{prefix}hand"), hand)],
            (None, Some(hands)) => (0..)
                .zip(hands)
                .map(|(index, hand)| (format!("{prefix}hands[{index}]"), hand))
                .collect(),
            (None, None) => Vec::new(),
        };
        for (key, file) in &files {
            self.one_line(key, file)?;
        }
        Ok(files)
    }
}
