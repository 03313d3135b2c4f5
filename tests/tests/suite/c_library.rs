//! The C library from C and C++: `client-c/examples/renderer.c`, compiled with the system's `cc`
//! against the committed header alone, and `renderer.cpp`, compiled with `c++` against it and
//! its C++ wrapper, each run under valgrind beside the Rust renderer example while a server
//! replays the two-hand fixture in lockstep. All print every frame they draw; on every frame
//! both drew, their lines must be the same, and valgrind must find no error.

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Instant;

use vas_client::Wake;
use vas_testkit::{PATIENCE, Server, Spawned, binary, configs_dir, example, fixtures_dir};

/// The lines a renderer printed so far, gathered by a thread reading its stdout.
struct Printed {
    lines: Arc<Mutex<Vec<String>>>,
    reader: JoinHandle<()>,
}

impl Printed {
    fn gather(process: &mut Spawned) -> Self {
        let stdout = process.take_stdout().expect("stdout is piped");
        let lines = Arc::new(Mutex::new(Vec::new()));
        let kept = Arc::clone(&lines);
        let reader = std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                kept.lock().expect("not poisoned").push(line);
            }
        });
        Self { lines, reader }
    }

    fn has(&self, start: &str) -> bool {
        let lines = self.lines.lock().expect("not poisoned");
        lines.iter().any(|line| line.starts_with(start))
    }

    /// Every line, once the renderer has ended.
    fn finish(self) -> Vec<String> {
        self.reader
            .join()
            .expect("the reader ends with the process");
        Arc::into_inner(self.lines)
            .expect("the reader has ended")
            .into_inner()
            .expect("not poisoned")
    }
}

/// Waits until `done` holds, failing with `what` and the renderers' logs after [`PATIENCE`].
fn wait_until(what: &str, renderers: &[&Spawned], mut done: impl FnMut() -> bool) {
    let deadline = Instant::now() + PATIENCE;
    while !done() {
        assert!(
            Instant::now() < deadline,
            "{what}; the renderers' logs:\n{}",
            renderers
                .iter()
                .map(|r| r.log())
                .collect::<Vec<_>>()
                .join("\n")
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// A renderer's lines by what they draw: the meshes, each parts frame, each frame's hands.
fn drawings(lines: &[String]) -> BTreeMap<(String, u64), Vec<String>> {
    let mut drawn: BTreeMap<(String, u64), Vec<String>> = BTreeMap::new();
    for line in lines {
        let word = line.split(' ').next().unwrap_or_default();
        let frame = || -> u64 {
            let value = line.split(" frame=").nth(1).expect("a frame number");
            let number = value.split(' ').next().unwrap_or_default();
            number.parse().expect("a frame number")
        };
        let key = match word {
            "mesh" => ("mesh".to_owned(), 0),
            "part" => ("parts".to_owned(), frame()),
            "hand" | "segment" => ("hands".to_owned(), frame()),
            _ => panic!("an unexpected line {line:?}"),
        };
        drawn.entry(key).or_default().push(line.clone());
    }
    drawn
}

/// Compiles the example `source` (`renderer.c` as C11 with `cc`, `renderer.cpp` as C++17 with
/// `c++`) against the headers and the shared library, with every warning an error. The library
/// is the one the test run built: the suite's first use of [`binary`] builds every member of the
/// workspace, `vas-client-c` among them, so no second cargo invocation (and no second build
/// lock) is needed. Built as a dependency of the crate's tests, its `cdylib` lies in the `deps`
/// folder beside the binaries (cargo copies it beside them only when it builds the library
/// alone, so a copy there may be stale).
fn compile_renderer(out: &Path, source: &str) -> PathBuf {
    let target = binary("vas-server");
    let target = target
        .parent()
        .expect("the binaries' directory")
        .join("deps");
    let target = target.as_path();
    let library = target.join("libvas_client.so");
    assert!(library.exists(), "{} is not built", library.display());
    let client_c = Path::new(env!("CARGO_MANIFEST_DIR")).join("../client-c");
    let program = out.join(source.replace('.', "_"));
    let (compiler, standard) = match source.ends_with(".cpp") {
        true => ("c++", "-std=c++17"),
        false => ("cc", "-std=c11"),
    };
    let compiled = Command::new(compiler)
        .args([standard, "-Wall", "-Wextra", "-Werror", "-g", "-I"])
        .arg(client_c.join("include"))
        .arg(client_c.join("examples").join(source))
        .arg("-L")
        .arg(target)
        // An RPATH, not a RUNPATH: it comes before the LD_LIBRARY_PATH cargo sets for tests,
        // which names the binaries' directory, where an older copy of the library may lie.
        .arg(format!(
            "-Wl,--disable-new-dtags,-rpath,{}",
            target.display()
        ))
        .args(["-lvas_client", "-o"])
        .arg(&program)
        .output()
        .unwrap_or_else(|error| panic!("{compiler} does not run: {error}"));
    assert!(
        compiled.status.success(),
        "{source} does not compile:\n{}",
        String::from_utf8_lossy(&compiled.stderr)
    );
    program
}

/// A renderer at work: its process and what it printed.
struct Renderer {
    name: String,
    process: Spawned,
    printed: Printed,
}

impl Renderer {
    fn start(name: &str, program: &Path, args: &[&str]) -> Self {
        let mut process = Spawned::start(program, args, Stdio::piped());
        let printed = Printed::gather(&mut process);
        Self {
            name: name.to_owned(),
            process,
            printed,
        }
    }

    /// Stops it with SIGTERM, as Ctrl-C would, and returns what it drew once it exited cleanly.
    fn stop(mut self) -> BTreeMap<(String, u64), Vec<String>> {
        self.process.signal(libc::SIGTERM);
        let status = (self.process.wait_exit(PATIENCE))
            .unwrap_or_else(|| panic!("the {} renderer does not end", self.name));
        assert!(
            status.success(),
            "the {} renderer failed ({status}):\n{}",
            self.name,
            self.process.log()
        );
        drawings(&self.printed.finish())
    }
}

/// The frames both drew, checked to be drawn alike: how many parts frames and hand frames.
fn compare(
    c: &BTreeMap<(String, u64), Vec<String>>,
    rust: &BTreeMap<(String, u64), Vec<String>>,
) -> (usize, usize) {
    let common: Vec<_> = c.keys().filter(|key| rust.contains_key(*key)).collect();
    for key in &common {
        assert_eq!(c[*key], rust[*key], "{key:?}");
    }
    let count = |kind: &str| common.iter().filter(|(k, _)| k == kind).count();
    (count("parts"), count("hands"))
}

#[test]
fn the_c_renderer_prints_what_the_rust_renderer_prints_and_valgrind_finds_no_error() {
    draws_like_the_rust_renderer("renderer.c", "C");
}

#[test]
fn the_cpp_renderer_prints_what_the_rust_renderer_prints_and_valgrind_finds_no_error() {
    draws_like_the_rust_renderer("renderer.cpp", "C++");
}

/// Runs the example `source` in `language` beside the Rust renderer, as the module says.
fn draws_like_the_rust_renderer(source: &str, language: &str) {
    let scratch = tempfile::tempdir().expect("a scratch folder");
    let program = compile_renderer(scratch.path(), source);
    let program = program.to_str().expect("a UTF-8 path");
    let scene = configs_dir().join("two_hand_handover.toml");
    let scene = scene.to_str().expect("a UTF-8 path");
    let test = format!("c_library_{}", source.replace('.', "_"));
    let mut server = Server::start_with(&test, &["--lockstep", "--scene", scene]);
    let mut watcher = server.connect();
    let prefix = server.prefix().to_owned();

    // The renderer twice: at full speed, drawing about as many frames as the Rust one, and
    // under valgrind, where every error it finds (memory errors, and leaks the program loses for
    // good) makes it exit with 99.
    let valgrind = [
        "--error-exitcode=99",
        "--leak-check=full",
        "--errors-for-leak-kinds=definite",
        "--show-leak-kinds=definite",
        "--quiet",
        program,
        "--prefix",
        &prefix,
    ];
    let under_valgrind = format!("{language} under valgrind");
    let renderers = [
        Renderer::start(language, Path::new(program), &["--prefix", &prefix]),
        Renderer::start(&under_valgrind, Path::new("valgrind"), &valgrind),
        Renderer::start("Rust", &example("renderer"), &["--prefix", &prefix]),
    ];
    let processes: Vec<&Spawned> = renderers.iter().map(|r| &r.process).collect();
    // Each draws the meshes once connected: the replay starts after, so that all see all of it.
    wait_until("a renderer printed no mesh", &processes, || {
        renderers.iter().all(|r| r.printed.has("mesh "))
    });

    let fixture = fixtures_dir().join("two_hand_handover.jsonl");
    let fixture = fixture.to_str().expect("a UTF-8 path");
    let mut replay = server.client_tool(&["replay", "--lockstep", fixture], Stdio::null());
    let status = replay.wait_exit(PATIENCE).expect("the replay ends");
    assert!(status.success(), "the replay failed:\n{}", replay.log());

    // The hands' last frame, the answer to the last sample, which every renderer draws in the
    // end (parts frames may go on: the hand frames are the ones that end with the input).
    assert_eq!(watcher.wait(PATIENCE).expect("wait"), Wake::Ready);
    watcher.poll().expect("poll");
    let hands = watcher.latest_hands();
    assert_eq!(hands.len(), 2, "the scene has two hands");
    let last_hands = hands[0].frame;
    let drawn_last = format!("hand frame={last_hands} ");
    wait_until(
        "a renderer did not draw the hands' last frame",
        &processes,
        || renderers.iter().all(|r| r.printed.has(&drawn_last)),
    );

    let [c, valgrind, rust] = renderers.map(Renderer::stop);
    for drawn in [&c, &valgrind] {
        assert_eq!(
            drawn.get(&("mesh".to_owned(), 0)),
            rust.get(&("mesh".to_owned(), 0))
        );
    }
    let (parts_frames, hand_frames) = compare(&c, &rust);
    assert!(
        parts_frames > 0 && hand_frames > 0,
        "no frame drawn by both"
    );
    let (valgrind_parts, valgrind_hands) = compare(&valgrind, &rust);
    eprintln!(
        "the {language} and Rust renderers drew {parts_frames} parts frames and {hand_frames} hand \
         frames alike, the {language} renderer under valgrind {valgrind_parts} and \
         {valgrind_hands}, of {last_hands} hand frames; valgrind found no error"
    );
}
