//! Builds the peers' harnesses when their libraries are found; without them the benchmarks say
//! the peer is missing (or compare with a reference figure), so nothing fails.
//!
//! * FCL (pkg-config `fcl`, Debian: `libfcl-dev`): `fcl/obb_build.cpp`, the peer of
//!   `vas-bench tree-build`, and `fcl/distance.cpp`, a peer of `vas-bench distance`.
//! * coal 3 (pip `coal`, whose wheel carries the C++ headers and library in its `cmeel.prefix`):
//!   `coal/distance.cpp`, the peer of `vas-bench distance`. The prefix is `COAL_PREFIX`, or the
//!   one the `python3` on the path reports (`python3 -m cmeel lib`, a virtualenv with coal).

use std::path::{Path, PathBuf};
use std::process::{Child, Command};

/// One harness to compile: its source, its binary's name, the variable that tells the benchmark
/// where it is, and the compiler's flags for its library.
struct Harness {
    source: &'static str,
    binary: &'static str,
    variable: &'static str,
    flags: Vec<String>,
}

fn main() {
    for source in [
        "fcl/obb_build.cpp",
        "fcl/distance.cpp",
        "fcl/distance_harness.h",
        "coal/distance.cpp",
    ] {
        println!("cargo:rerun-if-changed={source}");
    }
    for variable in ["PKG_CONFIG_PATH", "COAL_PREFIX", "VIRTUAL_ENV", "CXX"] {
        println!("cargo:rerun-if-env-changed={variable}");
    }
    let mut harnesses = Vec::new();
    if let Some(flags) = pkg_config("fcl", None) {
        for (source, binary, variable) in [
            ("fcl/obb_build.cpp", "fcl-obb-build", "VAS_FCL_OBB_BUILD"),
            ("fcl/distance.cpp", "fcl-distance", "VAS_FCL_DISTANCE"),
        ] {
            harnesses.push(Harness {
                source,
                binary,
                variable,
                flags: flags.clone(),
            });
        }
    }
    if let Some(prefix) = coal_prefix() {
        match pkg_config("coal", Some(&prefix.join("lib/pkgconfig"))) {
            Some(mut flags) => {
                flags.push(format!("-Wl,-rpath,{}", prefix.join("lib").display()));
                harnesses.push(Harness {
                    source: "coal/distance.cpp",
                    binary: "coal-distance",
                    variable: "VAS_COAL_DISTANCE",
                    flags,
                });
            }
            None => println!(
                "cargo:warning=coal's prefix {} has no usable coal.pc (or eigen3 is missing)",
                prefix.display()
            ),
        }
    }
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    // The harnesses compile side by side: each takes several seconds of template-heavy C++.
    let compiling: Vec<(Harness, PathBuf, Option<Child>)> = harnesses
        .into_iter()
        .map(|harness| {
            let binary = out.join(harness.binary);
            let child = compile(&harness, &binary);
            (harness, binary, child)
        })
        .collect();
    for (harness, binary, child) in compiling {
        let built = child.is_some_and(|mut child| child.wait().is_ok_and(|s| s.success()));
        if built {
            println!("cargo:rustc-env={}={}", harness.variable, binary.display());
        } else {
            println!(
                "cargo:warning={} did not compile; its peer is left out",
                harness.source
            );
        }
    }
}

/// The compiler and linker flags of a pkg-config package, looked up in `extra_path` first.
fn pkg_config(package: &str, extra_path: Option<&Path>) -> Option<Vec<String>> {
    let mut command = Command::new("pkg-config");
    command.args(["--cflags", "--libs", package]);
    if let Some(extra) = extra_path {
        let mut paths = vec![extra.to_path_buf()];
        if let Some(existing) = std::env::var_os("PKG_CONFIG_PATH") {
            paths.extend(std::env::split_paths(&existing));
        }
        command.env("PKG_CONFIG_PATH", std::env::join_paths(paths).ok()?);
    }
    let output = command.output().ok().filter(|o| o.status.success())?;
    Some(
        String::from_utf8_lossy(&output.stdout)
            .split_whitespace()
            .map(str::to_owned)
            .collect(),
    )
}

/// The cmeel prefix holding coal's `include/coal` and `lib/libcoal.so`, if there is one.
fn coal_prefix() -> Option<PathBuf> {
    let prefix = match std::env::var_os("COAL_PREFIX") {
        Some(prefix) => PathBuf::from(prefix),
        None => {
            let output = Command::new("python3")
                .args(["-m", "cmeel", "lib"])
                .output()
                .ok()
                .filter(|o| o.status.success())?;
            let lib = String::from_utf8_lossy(&output.stdout);
            PathBuf::from(lib.lines().next()?.trim())
                .parent()?
                .to_path_buf()
        }
    };
    prefix
        .join("include/coal/distance.h")
        .is_file()
        .then_some(prefix)
}

/// Starts compiling `harness` into `binary`; `None` when the compiler cannot be started.
fn compile(harness: &Harness, binary: &Path) -> Option<Child> {
    let compiler = std::env::var("CXX").unwrap_or_else(|_| "c++".to_owned());
    Command::new(compiler)
        .args(["-O2", "-DNDEBUG", "-std=c++17", harness.source, "-o"])
        .arg(binary)
        .args(&harness.flags)
        .spawn()
        .ok()
}
