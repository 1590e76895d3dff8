//! C-boundary helpers shared by the FMI 2 and FMI 3 glue.

use std::ffi::{c_char, c_void, CStr, CString};

use crate::instance::{Failure, Instance, Res, Snapshot, Status};

/// A C string of `s` (interior NULs become spaces).
pub(crate) fn cstring(s: &str) -> CString {
    CString::new(s.replace('\0', " ")).expect("NULs replaced")
}

/// The UTF-8 text of a C string; "" for null or invalid text.
pub(crate) unsafe fn str_of<'a>(p: *const c_char) -> &'a str {
    if p.is_null() {
        ""
    } else {
        CStr::from_ptr(p).to_str().unwrap_or("")
    }
}

fn null_array() -> Failure {
    Failure { status: Status::Error, message: "a null array was passed with a non-zero length".into() }
}

/// A slice from a pointer and a length; a null pointer is only fine for length 0.
pub(crate) unsafe fn slice<'a, T>(p: *const T, n: usize) -> Result<&'a [T], Failure> {
    match (n, p.is_null()) {
        (0, _) => Ok(&[]),
        (_, true) => Err(null_array()),
        _ => Ok(std::slice::from_raw_parts(p, n)),
    }
}

/// A mutable slice from a pointer and a length; a null pointer is only fine for length 0.
pub(crate) unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Result<&'a mut [T], Failure> {
    match (n, p.is_null()) {
        (0, _) => Ok(&mut []),
        (_, true) => Err(null_array()),
        _ => Ok(std::slice::from_raw_parts_mut(p, n)),
    }
}

// FMU states: both versions hand them over as `void*` (fmi2FMUstate, fmi3FMUState).

fn null_argument(function: &str) -> Failure {
    Failure { status: Status::Error, message: format!("{function}: a null pointer was passed") }
}

/// GetFMUState: a new state, or the given one overwritten.
pub(crate) unsafe fn get_state(inst: &Instance, state: *mut *mut c_void, function: &str) -> Res<()> {
    if state.is_null() {
        return Err(null_argument(function));
    }
    let snap = inst.snapshot();
    if (*state).is_null() {
        *state = Box::into_raw(Box::new(snap)) as *mut c_void;
    } else {
        *((*state) as *mut Snapshot) = snap;
    }
    Ok(())
}

/// SetFMUState.
pub(crate) unsafe fn set_state(inst: &mut Instance, state: *mut c_void, function: &str) -> Res<()> {
    if state.is_null() {
        return Err(null_argument(function));
    }
    inst.restore(&*(state as *const Snapshot))
}

/// FreeFMUState: frees and nulls the state (a null state is fine).
pub(crate) unsafe fn free_state(state: *mut *mut c_void) -> Res<()> {
    if !state.is_null() && !(*state).is_null() {
        drop(Box::from_raw(*state as *mut Snapshot));
        *state = std::ptr::null_mut();
    }
    Ok(())
}

/// SerializedFMUStateSize of `state`.
pub(crate) unsafe fn state_size(state: *mut c_void, size: *mut usize, function: &str) -> Res<()> {
    if size.is_null() || state.is_null() {
        return Err(null_argument(function));
    }
    *size = (*(state as *const Snapshot)).byte_len();
    Ok(())
}

/// SerializeFMUState into `size` bytes at `out`.
pub(crate) unsafe fn serialize_state(state: *mut c_void, out: *mut u8, size: usize, function: &str) -> Res<()> {
    if state.is_null() {
        return Err(null_argument(function));
    }
    let snap = &*(state as *const Snapshot);
    if size < snap.byte_len() {
        return Err(Failure {
            status: Status::Error,
            message: format!("{function}: {} bytes are needed, {size} given", snap.byte_len()),
        });
    }
    let bytes = snap.to_bytes();
    slice_mut(out, size)?[..bytes.len()].copy_from_slice(&bytes);
    Ok(())
}

/// DeserializeFMUState into a new state.
pub(crate) unsafe fn deserialize_state(
    inst: &Instance,
    bytes: *const u8,
    size: usize,
    state: *mut *mut c_void,
    function: &str,
) -> Res<()> {
    let snap = Snapshot::from_bytes(slice(bytes, size)?)
        .map_err(|why| Failure { status: Status::Error, message: format!("{function}: {why}") })?;
    inst.check_state(&snap).map_err(|f| Failure { message: format!("{function}: {}", f.message), ..f })?;
    if state.is_null() {
        return Err(null_argument(function));
    }
    *state = Box::into_raw(Box::new(snap)) as *mut c_void;
    Ok(())
}
