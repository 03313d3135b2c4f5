//! A scene's users: `[[users]]` with names and one or two hands each, or the `hand` / `hands` of
//! one user; every way of getting them wrong is refused with the key and the reason.

use vas_protocol::HandSide;
use vas_server::scene::{DEFAULT_USER, Scene};

use crate::scene_refusals::refused;
use crate::scenes::{PEG, configs, scratch_dir, write};

/// The right and left hand model files, as a config quotes them.
fn hand_files() -> [String; 2] {
    ["right", "left"].map(|side| format!("{:?}", configs().join(format!("hands/{side}.toml"))))
}

/// A `[[users]]` entry named `name` with the hand files `hands`.
fn user(name: &str, hands: &[&String]) -> String {
    let list: Vec<&str> = hands.iter().map(|hand| hand.as_str()).collect();
    format!(
        "[[users]]\nname = {name:?}\nhands = [{}]\n",
        list.join(", ")
    )
}

#[test]
fn users_own_their_hands_in_order() {
    let [right, left] = hand_files();
    let dir = scratch_dir("users");
    let path = write(
        &dir,
        "scene.toml",
        &format!(
            "name = \"s\"\n{PEG}{}{}",
            user("anna", &[&right, &left]),
            user("ben", &[&left])
        ),
    );
    let scene = Scene::load(&path).expect("two users load");
    assert_eq!(scene.users, ["anna", "ben"]);
    let hands: Vec<(u32, HandSide)> = (scene.hands.iter())
        .map(|hand| (hand.user, hand.model.side()))
        .collect();
    assert_eq!(
        hands,
        [
            (0, HandSide::Right),
            (0, HandSide::Left),
            (1, HandSide::Left)
        ]
    );
}

#[test]
fn hand_and_hands_mean_one_user() {
    let [right, left] = hand_files();
    let dir = scratch_dir("one_user");
    let path = write(
        &dir,
        "scene.toml",
        &format!("name = \"s\"\nhands = [{right}, {left}]\n{PEG}"),
    );
    let scene = Scene::load(&path).expect("loads");
    assert_eq!(scene.users, [DEFAULT_USER]);
    assert!(scene.hands.iter().all(|hand| hand.user == 0));
    let handless = write(&dir, "handless.toml", &format!("name = \"s\"\n{PEG}"));
    let scene = Scene::load(&handless).expect("loads");
    assert_eq!((scene.users.len(), scene.hands.len()), (1, 0));
}

#[test]
fn wrong_users_are_refused_with_the_key_and_the_reason() {
    let [right, left] = hand_files();
    let five: String = (0..5).map(|i| user(&format!("u{i}"), &[&right])).collect();
    refused(
        "five_users",
        &format!("name = \"s\"\n{PEG}{five}"),
        &["users", "at most 4"],
    );
    refused(
        "same_name",
        &format!(
            "name = \"s\"\n{PEG}{}{}",
            user("anna", &[&right]),
            user("anna", &[&left])
        ),
        &["users[1].name", "is the name of users[0] too"],
    );
    refused(
        "two_right_hands",
        &format!("name = \"s\"\n{PEG}{}", user("anna", &[&right, &right])),
        &[
            "users[0].hands[1]",
            "a user has",
            "at most one of each side",
        ],
    );
    refused(
        "empty_name",
        &format!("name = \"s\"\n{PEG}{}", user(" ", &[&right])),
        &["users[0].name", "must not be empty"],
    );
    let long = "ä".repeat(33);
    refused(
        "long_name",
        &format!("name = \"s\"\n{PEG}{}", user(&long, &[&right])),
        &["users[0].name", "66 bytes", "at most 64"],
    );
    refused(
        "no_hand",
        &format!("name = \"s\"\n{PEG}{}", user("anna", &[])),
        &["users[0]", "has no hand"],
    );
    refused(
        "users_and_hand",
        &format!(
            "name = \"s\"\nhand = {right}\n{PEG}{}",
            user("anna", &[&left])
        ),
        &["hand", "not both"],
    );
    refused(
        "hand_and_hands_of_a_user",
        &format!(
            "name = \"s\"\n{PEG}[[users]]\nname = \"anna\"\nhand = {right}\nhands = [{left}]\n"
        ),
        &["users[0].hands", "not both"],
    );
}
