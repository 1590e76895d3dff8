//! C-boundary helpers shared by the FMI 2 and FMI 3 glue.

use std::ffi::{c_char, CStr, CString};

use crate::instance::{Failure, Status};

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
