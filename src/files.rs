//! Reading inputs and writing outputs safely: an input must be a regular file of a sane size
//! (not `/dev/zero`, not a FIFO, not 200 GB); an output is written to a unique temporary file
//! beside it and renamed over a regular file or a new name, written through to a character
//! device (`/dev/null`, a terminal), and refused when it is anything else or one of the inputs.
//! Nothing half-written is left behind: a failed write removes its temporary file.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Largest data file read (a CSV record), bytes: 4 GiB, far above a 200 s, 10 kHz, 8-channel
/// record in CSV (≈ 0.3 GB).
pub const MAX_DATA_BYTES: u64 = 4 << 30;

pub use modelfile::input::{check_input, file_kind, read_text, InputError, MAX_TEXT_BYTES};

#[cfg(unix)]
fn is_char_device(meta: &std::fs::Metadata) -> bool {
    std::os::unix::fs::FileTypeExt::is_char_device(&meta.file_type())
}

#[cfg(not(unix))]
fn is_char_device(_: &std::fs::Metadata) -> bool {
    false
}

/// Where an output goes, decided before anything is computed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Target {
    /// A regular file or a new name: written to a temporary file beside it, then renamed
    /// over it (a symbolic link is followed, so the link stays and its target is replaced).
    File(PathBuf),
    /// A character device (`/dev/null`, a terminal): written through.
    Device(PathBuf),
    /// Standard output (`-` or `/dev/stdout`, whatever it is connected to: a terminal, a pipe,
    /// a file).
    Stdout,
}

/// Where `path` writes to: a symbolic link is followed to the file it names (also when that
/// file does not exist yet, so a dangling link is written through, not replaced), an existing
/// file is canonical, a new name is its canonical folder joined with the name.
fn resolve_output(path: &Path, named: &dyn Fn() -> String) -> anyhow::Result<PathBuf> {
    let mut p = path.to_path_buf();
    // a chain of links ends within 40 steps (the kernel's own limit), else it is a loop
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let target = std::fs::read_link(&p).map_err(|e| anyhow::anyhow!("{}: {e}", named()))?;
                p = match p.parent() {
                    Some(dir) if target.is_relative() => dir.join(target),
                    _ => target,
                };
            }
            Ok(_) => return std::fs::canonicalize(&p).map_err(|e| anyhow::anyhow!("{}: {e}", named())),
            Err(_) => {
                // a new name (or a link's missing target): its folder must exist
                let parent = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
                let dir = std::fs::canonicalize(parent).map_err(|e| {
                    anyhow::anyhow!("{}: the folder {} does not exist ({e})", named(), parent.display())
                })?;
                let name = p.file_name().ok_or_else(|| anyhow::anyhow!("{}: not a file name", named()))?;
                return Ok(dir.join(name));
            }
        }
    }
    anyhow::bail!("{}: too many levels of symbolic links", named())
}

/// Checks an output path before the computation starts: its folder exists and is writable, it
/// is a regular file, a new name (a dangling symbolic link names its target) or a character
/// device, and it is none of `inputs`.
pub fn output(path: &Path, option: &str, inputs: &[PathBuf]) -> anyhow::Result<Target> {
    let named = || format!("{option} {}", path.display());
    if path.as_os_str().is_empty() {
        anyhow::bail!("{option}: an empty file name was given");
    }
    if path == Path::new("-") || path == Path::new("/dev/stdout") {
        return Ok(Target::Stdout);
    }
    let resolved = resolve_output(path, &named)?;
    for input in inputs {
        if std::fs::canonicalize(input).map(|i| i == resolved).unwrap_or(false) {
            anyhow::bail!(
                "{}: this is an input of the command ({}); refusing to overwrite it",
                named(),
                input.display()
            );
        }
    }
    match std::fs::metadata(&resolved) {
        Ok(meta) if meta.is_file() => {}
        Ok(meta) if is_char_device(&meta) => return Ok(Target::Device(resolved)),
        Ok(meta) => anyhow::bail!("{}: {}; expected a file to write", named(), file_kind(&meta)),
        Err(_) => {}
    }
    let dir = resolved.parent().unwrap_or(Path::new("."));
    let probe = temporary(&resolved);
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .map_err(|e| anyhow::anyhow!("{}: cannot write in {}: {e}", named(), dir.display()))?;
    let _ = std::fs::remove_file(&probe);
    Ok(Target::File(resolved))
}

/// The outputs of one command, checked together before the first is written: each as
/// [`output`] checks it, none one of the command's inputs, no file named by two options.
#[derive(Debug, Default)]
pub struct Outputs {
    inputs: Vec<PathBuf>,
    claimed: Vec<(PathBuf, String)>,
}

impl Outputs {
    /// The outputs of a command reading `inputs` (every file it reads, data files included).
    pub fn new(inputs: &[PathBuf]) -> Self {
        Outputs { inputs: inputs.to_vec(), claimed: Vec::new() }
    }

    /// Checks `path` as the output of `option` and claims it.
    pub fn file(&mut self, path: &Path, option: &str) -> anyhow::Result<Target> {
        let target = output(path, option, &self.inputs)?;
        // standard output is claimed as `-`; a device may be written by several
        let claim = match &target {
            Target::File(resolved) => resolved.clone(),
            Target::Stdout => PathBuf::from("-"),
            Target::Device(_) => return Ok(target),
        };
        if let Some((_, other)) = self.claimed.iter().find(|(p, _)| *p == claim) {
            anyhow::bail!("{option} {}: {other} writes there too; give each output its own file", path.display());
        }
        self.claimed.push((claim, option.to_string()));
        Ok(target)
    }

    /// Checks `path` as an SVG output of `option` and claims it.
    pub fn svg(&mut self, path: &Path, option: &str) -> anyhow::Result<Target> {
        if path.extension().and_then(|e| e.to_str()).map(|e| e.eq_ignore_ascii_case("svg")) != Some(true)
            && !path.starts_with("/dev")
        {
            anyhow::bail!("{option} {}: the plot is written as SVG; give a file name ending in .svg", path.display());
        }
        self.file(path, option)
    }

    /// `names` in the folder `dir` of `option` (created if missing), each checked and claimed.
    pub fn in_folder<const N: usize>(
        &mut self,
        dir: &Path,
        option: &str,
        names: [&str; N],
    ) -> anyhow::Result<[Target; N]> {
        let resolved = output_dir(dir, option)?;
        let mut out = Vec::with_capacity(N);
        for name in names {
            out.push(self.file(&resolved.join(name), option)?);
        }
        Ok(out.try_into().expect("N targets"))
    }
}

/// A folder for outputs (`--out`, `--descriptions`): created if missing; refused if it is not a
/// folder or cannot be written.
pub fn output_dir(dir: &Path, option: &str) -> anyhow::Result<PathBuf> {
    std::fs::create_dir_all(dir)
        .map_err(|e| anyhow::anyhow!("{option} {}: cannot create the folder: {e}", dir.display()))?;
    let resolved = std::fs::canonicalize(dir).map_err(|e| anyhow::anyhow!("{option} {}: {e}", dir.display()))?;
    if !resolved.is_dir() {
        anyhow::bail!("{option} {}: not a folder", dir.display());
    }
    let probe = temporary(&resolved.join("probe"));
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .map_err(|e| anyhow::anyhow!("{option} {}: cannot write in the folder: {e}", dir.display()))?;
    let _ = std::fs::remove_file(&probe);
    Ok(resolved)
}

/// A temporary name beside `path`, unique to this process and call.
fn temporary(path: &Path) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!(".{name}.{}-{n}.partial", std::process::id()))
}

/// Writes `bytes` to a checked target: through a device, or to a unique temporary file that is
/// renamed over the target; on any failure the temporary file is removed.
pub fn write(target: &Target, bytes: &[u8]) -> anyhow::Result<()> {
    match target {
        Target::Stdout => {
            // a reader that has gone (`| head`) is no error of ours
            let mut out = std::io::stdout().lock();
            let _ = out.write_all(bytes).and_then(|()| out.flush());
            Ok(())
        }
        Target::Device(p) => {
            let mut f =
                std::fs::OpenOptions::new().write(true).open(p).map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?;
            f.write_all(bytes).map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))
        }
        Target::File(p) => {
            let tmp = temporary(p);
            let result = (|| {
                let mut f = std::fs::OpenOptions::new().write(true).create_new(true).open(&tmp)?;
                f.write_all(bytes)?;
                f.sync_all()?;
                std::fs::rename(&tmp, p)
            })();
            result.map_err(|e| {
                let _ = std::fs::remove_file(&tmp);
                anyhow::anyhow!("{}: {e}", p.display())
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("rigtwin-files-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn devices_are_written_through_and_symlinks_keep_their_link() {
        assert_eq!(output(Path::new("/dev/null"), "--json", &[]).unwrap(), Target::Device("/dev/null".into()));
        write(&output(Path::new("/dev/null"), "--json", &[]).unwrap(), b"x").unwrap();
        assert!(is_char_device(&std::fs::metadata("/dev/null").unwrap()), "/dev/null is still a device");
        let d = scratch("link");
        std::fs::write(d.join("real.json"), "old").unwrap();
        std::os::unix::fs::symlink(d.join("real.json"), d.join("link.json")).unwrap();
        write(&output(&d.join("link.json"), "--json", &[]).unwrap(), b"new").unwrap();
        assert!(std::fs::symlink_metadata(d.join("link.json")).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read_to_string(d.join("real.json")).unwrap(), "new");
        // nothing else is left in the folder
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 2);
    }

    #[test]
    fn inputs_fifos_folders_and_missing_folders_are_refused() {
        let d = scratch("refuse");
        let input = d.join("bundle.toml");
        std::fs::write(&input, "x").unwrap();
        let e = output(&input, "--write-model", std::slice::from_ref(&input)).unwrap_err().to_string();
        assert!(e.contains("input"), "{e}");
        let e = output(&d, "--json", &[]).unwrap_err().to_string();
        assert!(e.contains("directory"), "{e}");
        let e = output(&d.join("no/such/x.json"), "--json", &[]).unwrap_err().to_string();
        assert!(e.contains("does not exist"), "{e}");
        let fifo = d.join("fifo");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
        let e = output(&fifo, "--json", &[]).unwrap_err().to_string();
        assert!(e.contains("FIFO"), "{e}");
        let e = check_input(Path::new("/dev/zero"), MAX_DATA_BYTES).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
    }
}
