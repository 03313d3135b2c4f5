//! The server as a process: it stops cleanly on a signal, runs its loops under the real-time
//! policy and CPU latency asked for (or says why it cannot), and refuses a second server on its
//! prefix.

use std::process::Stdio;
use std::time::Duration;

use vas_server::runtime::priority::RealtimePriority;
use vas_testkit::{PATIENCE, Server, Spawned, tracker};

use crate::end_to_end::hand_answering;

fn stops_cleanly_on(signal: libc::c_int, test: &str) {
    let mut server = Server::start(test);
    server.connect();
    server.process.signal(signal);
    let status = server
        .process
        .wait_exit(Duration::from_secs(10))
        .expect("the server stops within 10 s");
    assert!(
        status.success(),
        "exit status {status}:\n{}",
        server.process.log()
    );
    assert!(server.process.log().contains("shutting down"));
}

#[test]
fn sigterm_stops_the_server_promptly_and_successfully() {
    stops_cleanly_on(libc::SIGTERM, "sigterm");
}

#[test]
fn sigint_stops_the_server_promptly_and_successfully() {
    stops_cleanly_on(libc::SIGINT, "sigint");
}

/// Whether this process may put a thread under `SCHED_FIFO` (as root, or with an rtprio limit):
/// the server, its child, may too.
fn realtime_permitted() -> bool {
    let lowest = RealtimePriority::new(1).expect("in range");
    std::thread::spawn(move || lowest.raise_this_thread().is_ok())
        .join()
        .expect("the probing thread ends")
}

/// Each thread of process `pid`: its name, realtime priority and policy, from `/proc`.
fn thread_policies(pid: u32) -> Vec<(String, u32, u32)> {
    let tasks = std::fs::read_dir(format!("/proc/{pid}/task")).expect("the server's threads");
    tasks
        .map(|task| {
            let stat = std::fs::read_to_string(task.expect("a thread").path().join("stat"))
                .expect("the thread's stat");
            // "tid (name) state ...": the name may hold spaces; fields 40 and 41 are the
            // realtime priority and the policy.
            let (head, tail) = stat.rsplit_once(") ").expect("a stat line");
            let name = head
                .split_once(" (")
                .expect("the thread's name")
                .1
                .to_owned();
            let fields: Vec<&str> = tail.split_whitespace().collect();
            let field = |number: usize| fields[number - 3].parse().expect("a number");
            (name, field(40), field(41))
        })
        .collect()
}

/// Waits for a server that must refuse to start to exit unsuccessfully; what it wrote to stderr.
fn refusal_of(server: &mut Spawned) -> String {
    let status = server.wait_exit(PATIENCE).expect("the server gives up");
    assert!(!status.success(), "exit status {status}:\n{}", server.log());
    server.log()
}

#[test]
fn a_realtime_server_runs_its_loops_under_fifo_or_says_why_it_cannot() {
    let mut server = Server::start_with("realtime", &["--realtime", "7"]);
    if !realtime_permitted() {
        let log = refusal_of(&mut server.process);
        assert!(
            log.contains("cannot run at realtime priority 7: ") && log.contains("ulimit -r 7"),
            "says why and what permits it: {log}"
        );
        return;
    }
    let mut client = server.connect();
    let sample = tracker(1, [0.0, 0.0, 0.0]);
    client.send_tracker(&sample).expect("send");
    hand_answering(&mut client, sample.stamp());
    drop(client);
    let threads = thread_policies(server.process.id());
    // The I/O thread, the loops, and the thread that lends its pool to the collision loop.
    let raised = [
        "vas-server",
        "grasping",
        "sliding",
        "collision-pool",
        "collision",
    ];
    for name in raised {
        let found = threads.iter().find(|thread| thread.0 == name);
        assert_eq!(
            found.map(|thread| (thread.1, thread.2)),
            Some((7, libc::SCHED_FIFO as u32)),
            "{name} at priority 7 under SCHED_FIFO: {threads:?}"
        );
    }
    let others: Vec<_> = (threads.iter())
        .filter(|thread| !raised.contains(&&*thread.0))
        .collect();
    assert!(
        !others.is_empty(),
        "the server starts other threads: {threads:?}"
    );
    assert!(
        others
            .iter()
            .all(|thread| thread.2 == libc::SCHED_OTHER as u32),
        "the threads the raised ones start keep the normal policy: {threads:?}"
    );
}

/// The CPU latency request the kernel holds the cores to (the least of all requests made), in
/// microseconds.
fn cpu_latency_in_force() -> i32 {
    let mut value = [0; 4];
    std::fs::File::open(vas_server::runtime::cpu_latency::DEVICE)
        .and_then(|mut device| std::io::Read::read_exact(&mut device, &mut value))
        .expect("the CPU latency device is readable");
    i32::from_ne_bytes(value)
}

#[test]
fn a_server_holds_the_cpu_latency_asked_for_while_it_runs_or_says_why_it_cannot() {
    let device = vas_server::runtime::cpu_latency::DEVICE;
    // Opening the device without writing to it requests nothing.
    let permitted = std::fs::OpenOptions::new().write(true).open(device).is_ok();
    let mut server = Server::start_with("cpulatency", &["--cpu-latency", "7"]);
    if !permitted {
        let log = refusal_of(&mut server.process);
        assert!(
            log.contains(&format!(
                "cannot hold the CPU wake-up latency at 7 us through {device}"
            )),
            "says why: {log}"
        );
        return;
    }
    drop(server.connect());
    assert_eq!(cpu_latency_in_force(), 7, "held while the server runs");
    server.process.stop();
    assert!(cpu_latency_in_force() > 7, "withdrawn when it ends");
}

#[test]
fn a_second_server_on_the_same_prefix_is_refused() {
    let mut first = Server::start("twice");
    first.connect();
    let mut second = vas_testkit::Spawned::start(
        &vas_testkit::binary("vas-server"),
        &["run", "--prefix", first.prefix()],
        Stdio::null(),
    );
    let log = refusal_of(&mut second);
    assert!(
        log.contains("another vas server already serves this prefix"),
        "says why in words: {log}"
    );
    assert!(first.process.is_running());
}
