//! The C functions against a real `vas-server`, called as C calls them: a tracker sample goes
//! in, its answer comes back through the frame accessors, and misuse (null pointers, a missing
//! role, another thread, unknown codes) comes back as status codes with words; the wake-up
//! descriptors wake an engine's poll(2) for a publish and go quiet after a poll.

use std::ffi::{CStr, CString};
use std::ptr;
use std::time::Instant;

use vas_client::*;
use vas_protocol::{HandFrame, PartState, PartsFrameHeader, SimEvent};
use vas_testkit::{PATIENCE, Server, tracker};

/// Milliseconds of [`PATIENCE`].
const PATIENCE_MS: u64 = PATIENCE.as_millis() as u64;

/// A client handle, freed when dropped.
struct Handle(*mut VasClient);

impl Handle {
    fn connect(server: &Server, roles: u32) -> Self {
        let prefix = CString::new(server.prefix()).expect("no NUL");
        let mut client = ptr::null_mut();
        // SAFETY: a valid string and out-pointer.
        let status = unsafe { vas_client_connect(prefix.as_ptr(), roles, false, &mut client) };
        assert_eq!(status, VasStatus::Ok, "{}", last_error());
        Self(client)
    }
}

impl Drop for Handle {
    fn drop(&mut self) {
        // SAFETY: a live handle, freed once, on its thread.
        unsafe { vas_client_free(self.0) };
    }
}

fn last_error() -> String {
    // SAFETY: the library's NUL-terminated message.
    unsafe { CStr::from_ptr(vas_last_error_message()) }
        .to_string_lossy()
        .into_owned()
}

/// Waits and polls until `done` holds, failing after [`PATIENCE`].
fn poll_until(client: &Handle, mut done: impl FnMut() -> bool) {
    let deadline = Instant::now() + PATIENCE;
    while !done() {
        assert!(Instant::now() < deadline, "nothing came");
        let mut wake = VasWake::Timeout;
        // SAFETY: a live handle and a writable wake.
        assert_eq!(
            unsafe { vas_client_wait(client.0, 100, &mut wake) },
            VasStatus::Ok
        );
        // SAFETY: a live handle; no counts wanted.
        assert_eq!(
            unsafe { vas_client_poll(client.0, ptr::null_mut()) },
            VasStatus::Ok
        );
    }
}

#[test]
fn a_sample_goes_in_and_its_answer_comes_out() {
    let mut server = Server::start("c_api");
    drop(server.connect()); // Returns once the server answers.
    let client = Handle::connect(&server, VAS_ROLE_ALL);

    let mut scene = ptr::null();
    // SAFETY: a live handle and a writable pointer.
    let status = unsafe { vas_client_scene_info(client.0, PATIENCE_MS, &mut scene) };
    assert_eq!(status, VasStatus::Ok, "{}", last_error());
    // SAFETY: valid until the next scene info.
    let scene = unsafe { &*scene };
    assert!(scene.part_count > 0);

    let sample = tracker(1, [0.05, -0.1, 1.2]);
    // SAFETY: a live handle and a readable sample.
    assert_eq!(
        unsafe { vas_client_send_tracker(client.0, &sample) },
        VasStatus::Ok
    );
    let mut answer = HandFrame::default();
    poll_until(&client, || {
        // SAFETY: a live handle and a writable frame.
        let status = unsafe { vas_client_latest_hand_of(client.0, 0, VAS_HAND_RIGHT, &mut answer) };
        status == VasStatus::Ok && answer.tracker == sample.stamp()
    });
    assert_eq!(answer.hand, VAS_HAND_RIGHT);

    let (mut hands, mut hand_count) = (ptr::null(), 0);
    // SAFETY: a live handle and writable out-pointers.
    let status = unsafe { vas_client_latest_hands(client.0, &mut hands, &mut hand_count) };
    assert_eq!(status, VasStatus::Ok);
    // SAFETY: `hand_count` frames, valid until the next poll.
    let hands: &[HandFrame] = unsafe { std::slice::from_raw_parts(hands, hand_count) };
    assert!(hands.contains(&answer), "{hands:?}");

    // The meshes come on their own service: they may arrive after the answer.
    let mut geometry = ptr::null();
    poll_until(&client, || {
        // SAFETY: a live handle and a writable pointer.
        unsafe { vas_client_geometry(client.0, &mut geometry) == VasStatus::Ok }
    });
    // SAFETY: valid until another generation is asked for.
    let geometry = unsafe { &*geometry };
    assert_eq!(geometry.part_count, scene.part_count);
    assert_eq!(geometry.generation, scene.generation);
    // SAFETY: `part_count` meshes.
    let meshes = unsafe { std::slice::from_raw_parts(geometry.parts, geometry.part_count) };
    for (mesh, part) in meshes.iter().zip(
        // SAFETY: `part_count` part descriptions.
        unsafe { std::slice::from_raw_parts(scene.parts, scene.part_count) },
    ) {
        // SAFETY: NUL-terminated names the client keeps.
        let (mesh_name, part_name) =
            unsafe { (CStr::from_ptr(mesh.name), CStr::from_ptr(part.name)) };
        assert_eq!(mesh_name, part_name);
        assert!(mesh.vertex_count > 0 && mesh.triangle_count > 0);
    }

    let mut header = PartsFrameHeader::default();
    let (mut parts, mut part_count) = (ptr::null::<PartState>(), 0);
    // SAFETY: a live handle and writable out-pointers.
    let status =
        unsafe { vas_client_latest_parts(client.0, &mut header, &mut parts, &mut part_count) };
    assert_eq!(status, VasStatus::Ok);
    assert_eq!(part_count, scene.part_count);
    assert_eq!(header.part_count as usize, part_count);

    let (mut events, mut event_count, mut dropped) = (ptr::null::<SimEvent>(), 0, u64::MAX);
    // SAFETY: a live handle and writable out-pointers.
    let status =
        unsafe { vas_client_take_events(client.0, &mut events, &mut event_count, &mut dropped) };
    assert_eq!(status, VasStatus::Ok);
    assert_eq!(dropped, 0);

    // SAFETY: a live handle.
    assert_eq!(
        unsafe { vas_client_reset(client.0, PATIENCE_MS) },
        VasStatus::Ok
    );
    let generation = geometry.generation;
    poll_until(&client, || {
        let mut newer = ptr::null();
        // SAFETY: a live handle and a writable pointer.
        let status = unsafe { vas_client_geometry(client.0, &mut newer) };
        // SAFETY: valid until another generation is asked for.
        status == VasStatus::Ok && unsafe { (*newer).generation } > generation
    });
}

#[test]
fn misuse_is_a_status_with_words() {
    let mut server = Server::start("c_api_misuse");
    drop(server.connect());
    let control = Handle::connect(&server, VAS_ROLE_CONTROL);

    let mut wake = VasWake::Ready;
    // SAFETY: a live handle and a writable wake.
    let status = unsafe { vas_client_wait(control.0, 0, &mut wake) };
    assert_eq!(status, VasStatus::MissingRole);
    assert!(last_error().contains("render role"), "{}", last_error());
    let sample = tracker(1, [0.0; 3]);
    // SAFETY: as above.
    let status = unsafe { vas_client_send_tracker(control.0, &sample) };
    assert_eq!(status, VasStatus::MissingRole);
    // SAFETY: a live handle and a null sample, which is the point.
    let status = unsafe { vas_client_send_tracker(control.0, ptr::null()) };
    assert_eq!(status, VasStatus::NullArgument);
    assert_eq!(last_error(), "sample is null");

    // SAFETY: a live handle; the metaphor code is unknown.
    let status = unsafe { vas_client_set_metaphor(control.0, 99, PATIENCE_MS) };
    assert_eq!(status, VasStatus::InvalidArgument);
    // SAFETY: a live handle and a side code no hand has.
    let status = unsafe { vas_client_latest_hand_of(control.0, 0, 7, &mut HandFrame::default()) };
    assert_eq!(status, VasStatus::InvalidArgument);
    let name = CString::new("no such scene").expect("no NUL");
    // SAFETY: a live handle and a NUL-terminated name.
    let status = unsafe { vas_client_load_named_scene(control.0, name.as_ptr(), PATIENCE_MS) };
    assert_eq!(status, VasStatus::Refused, "{}", last_error());
    // SAFETY: a live handle; the roles' bits are unknown.
    assert_eq!(
        unsafe { vas_client_take_roles(control.0, 8) },
        VasStatus::InvalidArgument
    );

    // A handle used on another thread is refused there, and stays usable on its own.
    let address = control.0 as usize;
    let elsewhere = std::thread::spawn(move || {
        let mut wake = VasWake::Ready;
        // SAFETY: a live handle, which the library refuses to use off its thread.
        let status = unsafe { vas_client_wait(address as *mut VasClient, 0, &mut wake) };
        (status, last_error())
    });
    let (status, words) = elsewhere.join().expect("the thread ends");
    assert_eq!(status, VasStatus::WrongThread);
    assert!(words.contains("another thread"), "{words}");
    // Nor is it freed there.
    let freed_elsewhere = std::thread::spawn(move || {
        // SAFETY: a live handle, which the library refuses to free off its thread.
        unsafe { vas_client_free(address as *mut VasClient) };
        last_error()
    });
    let words = freed_elsewhere.join().expect("the thread ends");
    assert!(words.contains("another thread"), "{words}");
    // SAFETY: a live handle on its thread.
    assert_eq!(
        unsafe { vas_client_take_roles(control.0, VAS_ROLE_RENDER) },
        VasStatus::Ok
    );
    // SAFETY: as above.
    assert_eq!(
        unsafe { vas_client_wait(control.0, 0, &mut wake) },
        VasStatus::Ok
    );
}

/// The client's wake-up descriptors, as `vas_client_wake_descriptors` gives them.
fn wake_descriptors(client: &Handle) -> Result<Vec<i32>, VasStatus> {
    let mut count = 0;
    // SAFETY: a live handle; a null `fds` with no room asks for the number.
    let status = unsafe { vas_client_wake_descriptors(client.0, ptr::null_mut(), 0, &mut count) };
    if status != VasStatus::Ok {
        return Err(status);
    }
    let mut fds = vec![-1; count];
    // SAFETY: a live handle and room for `count` descriptors.
    let status =
        unsafe { vas_client_wake_descriptors(client.0, fds.as_mut_ptr(), fds.len(), &mut count) };
    assert_eq!(status, VasStatus::Ok, "{}", last_error());
    assert_eq!(count, fds.len());
    Ok(fds)
}

/// How many of `fds` poll(2) reports readable within `timeout_ms`.
#[cfg(unix)]
fn readable(fds: &[i32], timeout_ms: u64) -> usize {
    let mut polled: Vec<libc::pollfd> = (fds.iter())
        .map(|&fd| libc::pollfd {
            fd,
            events: libc::POLLIN,
            revents: 0,
        })
        .collect();
    let timeout = libc::c_int::try_from(timeout_ms).expect("a short time-out");
    // SAFETY: `polled` holds `polled.len()` initialised entries for the call's duration.
    let ready = unsafe { libc::poll(polled.as_mut_ptr(), polled.len() as libc::nfds_t, timeout) };
    assert!(ready >= 0, "poll: {}", std::io::Error::last_os_error());
    assert!(
        polled
            .iter()
            .all(|entry| entry.revents & !libc::POLLIN == 0),
        "an error on a descriptor: {polled:?}"
    );
    ready as usize
}

/// An engine's loop on the descriptors: quiet while the server has published nothing new,
/// readable once a sample's answer is published, quiet again right after a poll.
#[cfg(unix)]
#[test]
fn wake_descriptors_are_readable_from_a_publish_until_a_poll() {
    let mut server = Server::start("c_api_wake");
    drop(server.connect());
    let client = Handle::connect(&server, VAS_ROLE_ALL);
    let fds = wake_descriptors(&client).expect("descriptors");
    assert_eq!(fds.len(), 6, "one per output service: {fds:?}");

    let mut count = 0;
    let mut few = [-1; 2];
    // SAFETY: a live handle and room for two descriptors.
    let status = unsafe { vas_client_wake_descriptors(client.0, few.as_mut_ptr(), 2, &mut count) };
    assert_eq!(status, VasStatus::InvalidArgument);
    assert_eq!(
        (count, few),
        (6, [-1; 2]),
        "the number, and nothing written"
    );

    // The frames a new client finds queued are taken by a first poll; nothing wakes after it.
    // SAFETY: a live handle; no counts wanted.
    assert_eq!(
        unsafe { vas_client_poll(client.0, ptr::null_mut()) },
        VasStatus::Ok
    );
    assert_eq!(readable(&fds, 0), 0, "nothing published since the poll");

    let sample = tracker(1, [0.05, -0.1, 1.2]);
    // SAFETY: a live handle and a readable sample.
    assert_eq!(
        unsafe { vas_client_send_tracker(client.0, &sample) },
        VasStatus::Ok
    );
    let mut answer = HandFrame::default();
    // The server publishes the answer's frame service by service, its hand last.
    while answer.tracker != sample.stamp() {
        assert!(readable(&fds, PATIENCE_MS) > 0, "the answer wakes them");
        // SAFETY: a live handle; no counts wanted.
        assert_eq!(
            unsafe { vas_client_poll(client.0, ptr::null_mut()) },
            VasStatus::Ok
        );
        // SAFETY: a live handle and a writable frame.
        unsafe { vas_client_latest_hand_of(client.0, 0, VAS_HAND_RIGHT, &mut answer) };
    }
    assert_eq!(readable(&fds, 0), 0, "quiet right after the poll");

    let control = Handle::connect(&server, VAS_ROLE_CONTROL);
    assert_eq!(wake_descriptors(&control), Err(VasStatus::MissingRole));
}

/// Without file descriptors the call says so.
#[cfg(not(unix))]
#[test]
fn wake_descriptors_are_unsupported_without_file_descriptors() {
    let mut server = Server::start("c_api_wake");
    drop(server.connect());
    let client = Handle::connect(&server, VAS_ROLE_RENDER);
    assert_eq!(wake_descriptors(&client), Err(VasStatus::Unsupported));
    assert!(last_error().contains("Unix only"), "{}", last_error());
}
