//! Shared by the FMU tests: the packaged FMUs, built once per test binary.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// Packages both FMUs with the default parameters into a temporary folder (the library is the
/// one the `rigtwin` binary carries); returns that folder.
pub fn fmu_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir =
            std::env::temp_dir().join(format!("rigtwin-fmus-{}-{:?}", std::process::id(), std::thread::current().id()));
        let out =
            Command::new(env!("CARGO_BIN_EXE_rigtwin")).args(["fmu", "--out", dir.to_str().unwrap()]).output().unwrap();
        assert!(out.status.success(), "rigtwin fmu: {}", String::from_utf8_lossy(&out.stderr));
        dir
    })
}

/// Caps the data segment (heap, large allocations: RLIMIT_DATA) of the process `cmd` starts at
/// `bytes`: an allocation beyond it fails, and the run ends without its message.
pub fn limit_data(cmd: &mut Command, bytes: u64) {
    use std::os::unix::process::CommandExt;
    // SAFETY: setrlimit is async-signal-safe; nothing else runs between fork and exec
    unsafe {
        cmd.pre_exec(move || {
            let l = libc::rlimit { rlim_cur: bytes, rlim_max: bytes };
            if libc::setrlimit(libc::RLIMIT_DATA, &l) == 0 {
                Ok(())
            } else {
                Err(std::io::Error::last_os_error())
            }
        });
    }
}

/// The Python of the venv `.ci/run` makes (override with RIGTWIN_PYTHON).
pub fn python() -> PathBuf {
    if let Ok(p) = std::env::var("RIGTWIN_PYTHON") {
        return PathBuf::from(p);
    }
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(".venv/bin/python");
    assert!(
        p.exists(),
        "{} is missing: `bash .ci/run` creates the venv with fmpy, fmu-manipulation-toolbox and libcosimpy",
        p.display()
    );
    p
}

/// Value reference of the default FMU's variable `name`.
pub fn vr(name: &str) -> u32 {
    rigtwin_fmu::table(&rigtwin_fmu::FmuParams::default())
        .variables
        .into_iter()
        .find(|v| v.name == name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .vr
}

/// An example bundle's file in `../shared/data`.
pub fn shared(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data").join(name)
}

/// A fresh scratch folder for test `case` of test file `file`.
pub fn scratch(file: &str, case: &str) -> Scratch {
    Scratch::new(&format!("rigtwin-{file}-{}-{case}", std::process::id()))
}

/// A scratch folder in the temporary directory, removed with what is in it when dropped (some
/// tests write hundreds of megabytes there).
pub struct Scratch(PathBuf);

impl Scratch {
    /// The empty folder `name` in the temporary directory.
    pub fn new(name: &str) -> Scratch {
        let d = std::env::temp_dir().join(name);
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        Scratch(d)
    }
}

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for Scratch {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs `scripts/<script>` (a survey script: `--rigtwin`, `--seeds`, `--out`) with this build's
/// rigtwin on survey seeds `seeds`, its records in a scratch folder, and returns the JSON it
/// writes to the file given with `result_flag`; its log is printed, and a failed run fails the
/// test with it.
pub fn survey_script(script: &str, seeds: &str, result_flag: &str) -> serde_json::Value {
    survey_script_with(script, seeds, result_flag, &[])
}

/// [`survey_script`] with the script's further arguments `extra` (`["--only", "compliance"]`).
pub fn survey_script_with(script: &str, seeds: &str, result_flag: &str, extra: &[&str]) -> serde_json::Value {
    // one folder per call: two tests of one script run at once
    let name = format!("records-{}{}", seeds.replace([',', '-'], "_"), extra.concat().replace('-', "_"));
    let dir = scratch(script.trim_end_matches(".py"), &name);
    let result = dir.join("result.json");
    let out = Command::new(python())
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts").join(script))
        .args(["--rigtwin", env!("CARGO_BIN_EXE_rigtwin"), "--seeds", seeds, "--out"])
        .arg(&dir)
        .arg(result_flag)
        .arg(&result)
        .args(extra)
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    eprintln!("{log}");
    assert!(out.status.success(), "{script} failed: {log}");
    serde_json::from_str(&std::fs::read_to_string(&result).unwrap()).unwrap()
}
