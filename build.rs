//! Builds the FMU's shared library (the `fmu` crate as a cdylib, profile `fmu`: optimised and
//! stripped) and hands it to the `rigtwin` binary, which carries it inside itself: `rigtwin fmu`
//! then works wherever the binary is copied or installed (`RIGTWIN_FMU_LIB` still overrides it
//! at run time). A nested cargo builds it into a folder of its own, `fmu-nested` in the outer
//! build's target folder (its own locks: it never waits on the outer build's), shared by the
//! outer profiles — `cargo clippy`, `cargo test` and `cargo build --release` build the library
//! once, not once each.

use std::env;
use std::path::PathBuf;
use std::process::Command;

fn main() {
    let manifest_dir = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let out_dir = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let inputs = ["fmu/src", "fmu/Cargo.toml", "plant/src", "plant/Cargo.toml", "mpc/src", "mpc/Cargo.toml"];
    for path in inputs.iter().chain(&["Cargo.toml", "Cargo.lock"]) {
        println!("cargo:rerun-if-changed={path}");
    }
    let target = env::var("TARGET").expect("cargo sets TARGET");
    let host = env::var("HOST").expect("cargo sets HOST");
    let target_dir = nested_target_dir(&out_dir);
    let cargo = env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.arg("build")
        .args(["--profile", "fmu", "-p", "fmu", "--lib"])
        .arg("--manifest-path")
        .arg(manifest_dir.join("Cargo.toml"))
        .arg("--target-dir")
        .arg(&target_dir)
        .env_remove("CARGO_TARGET_DIR")
        .env_remove("CARGO_BUILD_TARGET_DIR");
    let mut lib_dir = target_dir.clone();
    if target != host {
        cmd.args(["--target", &target]);
        lib_dir.push(&target);
    }
    lib_dir.push("fmu");
    let status = cmd.status().expect("could not run cargo to build the FMU library");
    if !status.success() {
        panic!("building the FMU library (cargo build --profile fmu -p fmu) failed: {status}");
    }
    let name = match env::var("CARGO_CFG_TARGET_OS").as_deref() {
        Ok("windows") => "rigtwin_fmu.dll",
        Ok("macos") | Ok("ios") => "librigtwin_fmu.dylib",
        _ => "librigtwin_fmu.so",
    };
    let built = lib_dir.join(name);
    std::fs::copy(&built, out_dir.join("rigtwin_fmu_library")).unwrap_or_else(|e| panic!("{}: {e}", built.display()));
}

/// Where the nested cargo builds: `fmu-nested` beside the outer build's profile folders (the
/// first ancestor of `out_dir` that cargo tagged as a target folder with `CACHEDIR.TAG`), or
/// inside `out_dir` where there is none.
fn nested_target_dir(out_dir: &std::path::Path) -> PathBuf {
    out_dir
        .ancestors()
        .find(|dir| dir.join("CACHEDIR.TAG").is_file())
        .map(|target| target.join("fmu-nested"))
        .unwrap_or_else(|| out_dir.join("fmu-target"))
}
