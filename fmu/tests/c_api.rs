//! The exported C API as an importer calls it: every refused call returns Error *and* logs a
//! line through the importer's callback, also for FMI 2's printf-like logger.

use std::ffi::{c_char, c_void, CStr, CString};

use rigtwin_fmu::variables::{VR_INPUT, VR_PARAM, VR_STATE};
use rigtwin_fmu::FmuParams;

type Log = Vec<(u32, String)>;

unsafe extern "C" fn log3(env: *mut c_void, status: u32, _category: *const c_char, message: *const c_char) {
    let log = &mut *(env as *mut Log);
    log.push((status, CStr::from_ptr(message).to_string_lossy().into_owned()));
}

#[test]
fn fmi3_refusals_return_error_and_log_why() {
    use rigtwin_fmu::fmi3::*;
    let mut log: Log = Vec::new();
    let token = CString::new(rigtwin_fmu::token(&FmuParams::default())).unwrap();
    let env = &mut log as *mut Log as *mut c_void;
    unsafe {
        let inst = fmi3InstantiateCoSimulation(
            c"a".as_ptr(),
            token.as_ptr(),
            std::ptr::null(),
            false,
            false,
            false,
            false,
            std::ptr::null(),
            0,
            env,
            Some(log3),
            None,
        );
        assert!(!inst.is_null());
        let error = 3;
        let mut v = 0.0;
        let bad = 9999u32;
        assert_eq!(fmi3GetFloat64(inst, &bad, 1, &mut v, 1), error);
        assert!(log.last().unwrap().1.contains("9999"), "{log:?}");
        let j_drive = VR_PARAM + 1;
        assert_eq!(fmi3SetFloat64(inst, &j_drive, 1, &0.0, 1), error);
        assert!(log.last().unwrap().1.contains("j_drive"), "{log:?}");
        let m_drive = VR_INPUT + 1;
        assert_eq!(fmi3SetFloat64(inst, &m_drive, 1, &f64::NAN, 1), error);
        assert!(log.last().unwrap().1.contains("M_drive"), "{log:?}");
        let (mut a, mut b, mut c, mut t) = (false, false, false, 0.0);
        assert_eq!(fmi3DoStep(inst, 0.0, 1e-3, true, &mut a, &mut b, &mut c, &mut t), error);
        assert!(log.last().unwrap().1.contains("DoStep"), "{log:?}");
        // null arrays with a non-zero length are refused, not dereferenced
        assert_eq!(fmi3GetFloat64(inst, std::ptr::null(), 2, std::ptr::null_mut(), 2), error);
        assert!(log.iter().all(|(s, _)| *s == error), "{log:?}");
        // the instance still works
        assert_eq!(fmi3EnterInitializationMode(inst, false, 0.0, 0.0, false, 0.0), 0);
        assert_eq!(fmi3ExitInitializationMode(inst), 0);
        assert_eq!(fmi3DoStep(inst, 0.0, 1e-3, true, &mut a, &mut b, &mut c, &mut t), 0);
        fmi3FreeInstance(inst);
        // a wrong token is refused at instantiation, with a log line and a null instance
        let n = log.len();
        let inst = fmi3InstantiateCoSimulation(
            c"b".as_ptr(),
            c"{wrong}".as_ptr(),
            std::ptr::null(),
            false,
            false,
            false,
            false,
            std::ptr::null(),
            0,
            env,
            Some(log3),
            None,
        );
        assert!(inst.is_null());
        assert!(log[n..].iter().any(|(_, m)| m.contains("token")), "{log:?}");
        // calls on a null instance are an error, not a crash
        assert_eq!(fmi3ExitInitializationMode(std::ptr::null_mut()), error);
    }
}

// FMI 2's logger is variadic (printf-like); a C-ABI variadic function cannot be defined in
// stable Rust, so the test's logger is a tiny C function compiled here with gcc.
#[test]
fn fmi2_logger_gets_the_message_through_a_percent_s_format() {
    use fmi_sys_types::*;
    let dir = std::env::temp_dir().join(format!("rigtwin-log2-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let src = dir.join("log2.c");
    std::fs::write(
        &src,
        r#"#include <stdarg.h>
#include <stdio.h>
static char last[4096];
void logger2(void *env, const char *name, int status, const char *category, const char *fmt, ...) {
    va_list ap; va_start(ap, fmt); vsnprintf(last, sizeof last, fmt, ap); va_end(ap);
    (void)env; (void)name; (void)status; (void)category;
}
const char *last_message(void) { return last; }
"#,
    )
    .unwrap();
    let lib = dir.join("liblog2.so");
    let ok = std::process::Command::new("gcc").args(["-O1", "-shared", "-fPIC", "-o"]).arg(&lib).arg(&src).status();
    assert!(matches!(ok, Ok(s) if s.success()), "gcc builds the test logger");
    unsafe {
        let l = libloading::Library::new(&lib).unwrap();
        let logger: libloading::Symbol<Logger2> = l.get(b"logger2").unwrap();
        let last: libloading::Symbol<unsafe extern "C" fn() -> *const c_char> = l.get(b"last_message").unwrap();
        let functions = Callbacks {
            logger: Some(*logger),
            allocate: None,
            free: None,
            step_finished: None,
            env: std::ptr::null_mut(),
        };
        let guid = CString::new(rigtwin_fmu::token(&FmuParams::default())).unwrap();
        let c = rigtwin_fmu::fmi2::fmi2Instantiate(
            c"c".as_ptr(),
            1,
            guid.as_ptr(),
            std::ptr::null(),
            &functions as *const Callbacks as *const _,
            0,
            0,
        );
        assert!(!c.is_null());
        let vr = VR_STATE + 1;
        assert_eq!(rigtwin_fmu::fmi2::fmi2SetReal(c, &vr, 1, &f64::INFINITY), 3);
        let msg = CStr::from_ptr(last()).to_string_lossy().into_owned();
        assert!(msg.contains("phi_drive") && msg.contains("inf"), "{msg}");
        rigtwin_fmu::fmi2::fmi2FreeInstance(c);
        // a refused GUID is echoed in the message: were the message the format, "%s%n" would
        // read and write through garbage pointers; as the argument of "%s" it arrives verbatim
        let c = rigtwin_fmu::fmi2::fmi2Instantiate(
            c"d".as_ptr(),
            1,
            c"{%s%n%s}".as_ptr(),
            std::ptr::null(),
            &functions as *const Callbacks as *const _,
            0,
            0,
        );
        assert!(c.is_null());
        let msg = CStr::from_ptr(last()).to_string_lossy().into_owned();
        assert!(msg.contains("{%s%n%s}"), "{msg}");
    }
}

/// The FMI 2 callback struct as the header lays it out (fmi2CallbackFunctions).
mod fmi_sys_types {
    use std::ffi::{c_char, c_void};
    pub type Logger2 = unsafe extern "C" fn(*mut c_void, *const c_char, u32, *const c_char, *const c_char, ...);
    #[repr(C)]
    pub struct Callbacks {
        pub logger: Option<Logger2>,
        pub allocate: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
        pub free: Option<unsafe extern "C" fn(*mut c_void)>,
        pub step_finished: Option<unsafe extern "C" fn(*mut c_void, u32)>,
        pub env: *mut c_void,
    }
}
