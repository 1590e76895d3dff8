//! Reading a text input safely: it must be a regular file of a sane size (not `/dev/zero`, not
//! a FIFO, not 200 GB).

use std::path::{Path, PathBuf};

/// Largest TOML file read (a rig file or a bundle's header), bytes.
pub const MAX_TEXT_BYTES: u64 = 16 << 20;
/// An input that cannot be read: the file and what is wrong with it (shown as "FILE: message";
/// a caller that names the file itself takes `message`).
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct InputError {
    /// The file.
    pub path: PathBuf,
    /// What is wrong, without the file's name.
    pub message: String,
}

/// Checks that `path` is a regular file of at most `max_bytes`.
pub fn check_input(path: &Path, max_bytes: u64) -> Result<(), InputError> {
    let fail = |message: String| InputError { path: path.to_path_buf(), message };
    if path.as_os_str().is_empty() {
        return Err(fail("an empty file name was given".into()));
    }
    let meta = std::fs::metadata(path).map_err(|e| fail(format!("cannot read: {e}")))?;
    if !meta.is_file() {
        return Err(fail(format!("not a regular file ({}): expected a file to read", file_kind(&meta))));
    }
    if meta.len() > max_bytes {
        return Err(fail(format!("{} bytes is more than the {max_bytes} bytes such a file may have", meta.len())));
    }
    Ok(())
}

/// Reads a text input (TOML), checked first.
pub fn read_text(path: &Path) -> Result<String, InputError> {
    check_input(path, MAX_TEXT_BYTES)?;
    std::fs::read_to_string(path)
        .map_err(|e| InputError { path: path.to_path_buf(), message: format!("cannot read: {e}") })
}

/// What a path that is not a regular file is, in words.
#[cfg(unix)]
pub fn file_kind(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_dir() {
        "a directory"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

/// What a path that is not a regular file is, in words.
#[cfg(not(unix))]
pub fn file_kind(meta: &std::fs::Metadata) -> &'static str {
    if meta.is_dir() {
        "a directory"
    } else {
        "not a regular file"
    }
}
