//! Clients take only the ports of their roles, and the control service keeps a reserve for
//! operators (issue 50, point 8): with 16 `vas-client watch` processes and an input device
//! connected, an operator's `vas-client reset` still connects, and so with 16 renderer examples
//! (issue 52). Before, every client held an input publisher and a control client, so that 15
//! watchers and a viewer refused every other client "too many clients".

use std::io::{BufRead, BufReader, Read};
use std::process::Stdio;

use vas_client::{Client, ClientError, Roles};
use vas_protocol::services::clients::{OPERATORS, READERS, SENDERS};
use vas_testkit::{PATIENCE, Server, Spawned, example, tracker};

/// How many renderers the services take ([`vas_protocol::services::output::MAX_SUBSCRIBERS`]
/// leaves room for input devices that read their answers beside them).
const RENDERERS: usize = 16;

/// Returns `process` once it has printed a first line starting with `first` (so that it holds
/// its ports); its output is read on until it ends, so that it never blocks on a full pipe.
fn holding_its_ports(mut process: Spawned, first: &str) -> Spawned {
    let mut stdout = BufReader::new(process.take_stdout().expect("piped"));
    let mut line = String::new();
    stdout.read_line(&mut line).expect("read its output");
    assert!(
        line.starts_with(first),
        "it prints no {first:?} line: {line:?}\n{}",
        process.log()
    );
    std::thread::spawn(move || std::io::copy(&mut stdout.take(u64::MAX), &mut std::io::sink()));
    process
}

/// `vas-client watch`, once it has printed its first frame.
fn watcher(server: &Server) -> Spawned {
    holding_its_ports(server.client_tool(&["watch"], Stdio::piped()), "{")
}

/// The renderer example, once it has drawn the scene's meshes.
fn renderer(server: &Server) -> Spawned {
    let args = ["--prefix", server.prefix()];
    holding_its_ports(
        Spawned::start(&example("renderer"), &args, Stdio::piped()),
        "mesh ",
    )
}

/// With `renderers` running, an input device connects and its sample is answered, and an
/// operator's `vas-client reset` connects and succeeds; the renderers run on.
fn an_input_device_and_an_operator_find_room_beside(server: &Server, mut renderers: Vec<Spawned>) {
    // An input device that reads the answers to its samples, as a headset's bridge or a
    // lockstep replay connects.
    let mut device = Client::builder()
        .prefix(Some(server.prefix()))
        .roles(Roles::INPUT | Roles::RENDER)
        .connect()
        .expect("the input device connects");
    let sample = tracker(1, [0.1, 0.0, 0.2]);
    device.send_tracker(&sample).expect("send");
    let answer = device
        .wait_for_hand_frame(PATIENCE, |frame| frame.tracker == sample.stamp(), drop)
        .expect("wait for the answer");
    assert!(
        answer.is_some(),
        "no hand frame answered the device's sample"
    );

    let mut reset = server.client_tool(&["reset"], Stdio::piped());
    let mut printed = String::new();
    reset
        .take_stdout()
        .expect("piped")
        .read_to_string(&mut printed)
        .expect("read the reset's answer");
    let status = reset.wait_exit(PATIENCE).expect("the reset ends");
    assert!(status.success(), "the operator's reset: {}", reset.log());
    assert!(printed.contains("\"scene\""), "{printed}");

    for renderer in &mut renderers {
        assert!(
            renderer.is_running(),
            "a renderer ended: {}",
            renderer.log()
        );
    }
    drop(device);
    drop(renderers);
}

#[test]
fn sixteen_watchers_and_an_input_device_leave_room_for_an_operators_reset() {
    let mut server = Server::start("operator_reserve");
    drop(server.connect());
    let watchers = (0..RENDERERS).map(|_| watcher(&server)).collect();
    an_input_device_and_an_operator_find_room_beside(&server, watchers);
}

/// The renderer example takes the render role only: were it to take the input ports too, 16 of
/// them would fill the input streams and refuse the input device.
#[test]
fn sixteen_renderer_examples_and_an_input_device_leave_room_for_an_operators_reset() {
    let mut server = Server::start("renderer_reserve");
    drop(server.connect());
    let renderers = (0..RENDERERS).map(|_| renderer(&server)).collect();
    an_input_device_and_an_operator_find_room_beside(&server, renderers);
}

/// A client of `roles` on the server's prefix.
fn open(server: &Server, roles: Roles) -> Result<Client, ClientError> {
    Client::builder()
        .prefix(Some(server.prefix()))
        .roles(roles)
        .connect()
}

/// The kind of port a client of `roles` is refused, when the services are full.
fn refused(server: &Server, roles: Roles) -> &'static str {
    match open(server, roles) {
        Err(ClientError::Full { kind }) => kind,
        Err(other) => panic!("a {roles} client too many: {other}"),
        Ok(_) => panic!("a {roles} client too many connected"),
    }
}

#[test]
fn clients_hold_only_their_roles_ports_and_operators_find_room_when_every_other_slot_is_taken() {
    let mut server = Server::start("roles_reserve");
    drop(server.connect());
    let mut renderers: Vec<Client> = (0..READERS)
        .map(|_| open(&server, Roles::RENDER).expect("a renderer within the limit"))
        .collect();
    let senders: Vec<Client> = (0..SENDERS)
        .map(|_| open(&server, Roles::INPUT).expect("a sender within the limit"))
        .collect();
    assert_eq!(refused(&server, Roles::RENDER), "subscribers");
    assert_eq!(refused(&server, Roles::INPUT), "publishers");

    // Each renderer and sender holds a control client; the operators' are left.
    let operators: Vec<Client> = (0..OPERATORS)
        .map(|_| open(&server, Roles::CONTROL).expect("an operator finds room"))
        .collect();
    for operator in &operators {
        assert_eq!(operator.roles(), Roles::CONTROL);
        operator.reset(PATIENCE).expect("the operator resets");
    }
    assert_eq!(refused(&server, Roles::CONTROL), "control clients");

    // A sender's sample is answered to a renderer; neither can do the other's part.
    let sample = tracker(1, [0.1, 0.0, 0.2]);
    senders[0].send_tracker(&sample).expect("send");
    let renderer = &mut renderers[0];
    let answer = renderer
        .wait_for_hand_frame(PATIENCE, |frame| frame.tracker == sample.stamp(), drop)
        .expect("wait for the answer");
    assert!(
        answer.is_some(),
        "no hand frame answered the sender's sample"
    );
    match renderer.send_tracker(&tracker(2, [0.0; 3])) {
        Err(ClientError::MissingRole { role, .. }) => assert_eq!(role, Roles::INPUT),
        other => panic!("a renderer sent: {other:?}"),
    }
    let mut operator = operators.into_iter().next().expect("an operator");
    match operator.receive() {
        Err(ClientError::MissingRole { role, .. }) => assert_eq!(role, Roles::RENDER),
        other => panic!("an operator received: {other:?}"),
    }

    // A role taken later: the input streams are full until a sender goes.
    assert!(matches!(
        operator.take_roles(Roles::INPUT),
        Err(ClientError::Full { kind: "publishers" })
    ));
    assert_eq!(operator.roles(), Roles::CONTROL);
    drop(senders);
    operator
        .take_roles(Roles::INPUT)
        .expect("room for a sender again");
    assert_eq!(operator.roles(), Roles::INPUT);
    operator
        .send_tracker(&tracker(3, [0.0; 3]))
        .expect("the operator now sends");
    drop((renderers, operator));
}
