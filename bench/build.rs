//! Builds FCL's OBB-tree harness (`fcl/obb_build.cpp`), the peer of `vas-bench tree-build`, when
//! pkg-config finds FCL (Debian: `libfcl-dev`); without FCL the benchmark compares with a
//! reference figure instead, so nothing fails.

use std::path::PathBuf;
use std::process::Command;

fn main() {
    println!("cargo:rerun-if-changed=fcl/obb_build.cpp");
    println!("cargo:rerun-if-env-changed=PKG_CONFIG_PATH");
    let Some(flags) = Command::new("pkg-config")
        .args(["--cflags", "--libs", "fcl"])
        .output()
        .ok()
        .filter(|output| output.status.success())
        .map(|output| String::from_utf8_lossy(&output.stdout).into_owned())
    else {
        return;
    };
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let harness = out.join("fcl-obb-build");
    let compiler = std::env::var("CXX").unwrap_or_else(|_| "c++".to_owned());
    let built = Command::new(compiler)
        .args(["-O2", "-DNDEBUG", "fcl/obb_build.cpp", "-o"])
        .arg(&harness)
        .args(flags.split_whitespace())
        .status()
        .is_ok_and(|status| status.success());
    if built {
        println!("cargo:rustc-env=VAS_FCL_OBB_BUILD={}", harness.display());
    } else {
        println!("cargo:warning=FCL was found but its OBB-tree harness did not compile");
    }
}
