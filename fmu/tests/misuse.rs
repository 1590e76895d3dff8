//! Misuse of the C API that used to return OK with a non-finite or wrong state, each case in a
//! child process with a time limit (a hang or a crash fails the case, not the test binary): a
//! NaN communication point, steps of 1e12 and 1e20 s, an inertia of 1e-300 kg m², an input of
//! 1e308 N·m, model-exchange time going backwards, an FMI 2 stop time before the start time.

use std::ffi::{c_char, c_void, CStr, CString};
use std::process::Command;
use std::time::{Duration, Instant};

use rigtwin_fmu::fmi3::*;
use rigtwin_fmu::variables::{VR_INPUT, VR_PARAM, VR_STATE, VR_TWIST};
use rigtwin_fmu::FmuParams;

const OK: u32 = 0;
const ERROR: u32 = 3;
const CHILD: &str = "RIGTWIN_MISUSE_CHILD";

/// Runs `case` in a child process (this test binary, filtered to `name`), at most 60 s.
fn in_child(name: &str, case: impl FnOnce()) {
    if std::env::var_os(CHILD).is_some() {
        case();
        return;
    }
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args([name, "--exact", "--test-threads=1", "--nocapture"])
        .env(CHILD, "1")
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            assert!(status.success(), "{name}: the child failed ({status})");
            return;
        }
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("{name}: no answer within 60 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

type Log = Vec<(u32, String)>;

unsafe extern "C" fn log3(env: *mut c_void, status: u32, _category: *const c_char, message: *const c_char) {
    let log = &mut *(env as *mut Log);
    log.push((status, CStr::from_ptr(message).to_string_lossy().into_owned()));
}

/// A co-simulation (or model-exchange) FMI 3 instance of the default parameters logging into `log`.
unsafe fn instance(log: &mut Log, me: bool) -> *mut c_void {
    instance_of(log, me, &FmuParams::default(), None)
}

/// An FMI 3 instance of parameter set `p`, whose params.json is in the folder `resources`.
unsafe fn instance_of(log: &mut Log, me: bool, p: &FmuParams, resources: Option<&CStr>) -> *mut c_void {
    let token = CString::new(rigtwin_fmu::token(p)).unwrap();
    let resources = resources.map_or(std::ptr::null(), CStr::as_ptr);
    let env = log as *mut Log as *mut c_void;
    let inst = if me {
        fmi3InstantiateModelExchange(c"me".as_ptr(), token.as_ptr(), resources, false, false, env, Some(log3))
    } else {
        fmi3InstantiateCoSimulation(
            c"cs".as_ptr(),
            token.as_ptr(),
            resources,
            false,
            false,
            false,
            false,
            std::ptr::null(),
            0,
            env,
            Some(log3),
            None,
        )
    };
    assert!(!inst.is_null());
    inst
}

unsafe fn init(inst: *mut c_void) -> u32 {
    let s = fmi3EnterInitializationMode(inst, false, 0.0, 0.0, false, 0.0);
    if s != OK {
        return s;
    }
    fmi3ExitInitializationMode(inst)
}

unsafe fn step(inst: *mut c_void, t: f64, h: f64) -> u32 {
    let (mut a, mut b, mut c, mut last) = (false, false, false, 0.0);
    fmi3DoStep(inst, t, h, true, &mut a, &mut b, &mut c, &mut last)
}

unsafe fn get(inst: *mut c_void, vr: u32) -> (u32, f64) {
    let mut v = 0.0;
    let s = fmi3GetFloat64(inst, &vr, 1, &mut v, 1);
    (s, v)
}

#[test]
fn nan_communication_point_is_refused_and_the_time_stays() {
    in_child("nan_communication_point_is_refused_and_the_time_stays", || unsafe {
        let mut log = Log::new();
        let inst = instance(&mut log, false);
        assert_eq!(init(inst), OK);
        assert_eq!(step(inst, f64::NAN, 1e-3), ERROR);
        assert!(log.last().unwrap().1.contains("NaN"), "{log:?}");
        // the FMU's time is still 0: the next proper step is accepted
        assert_eq!(step(inst, 0.0, 1e-3), OK);
        assert_eq!(step(inst, 1e-3, f64::NAN), ERROR);
        fmi3FreeInstance(inst);
    });
}

#[test]
fn steps_too_long_to_take_exactly_are_refused_and_stop_the_instance() {
    in_child("steps_too_long_to_take_exactly_are_refused_and_stop_the_instance", || unsafe {
        for h in [1e12, 1e20] {
            let mut log = Log::new();
            let inst = instance(&mut log, false);
            let m_drive = VR_INPUT + 1;
            assert_eq!(fmi3SetFloat64(inst, &m_drive, 1, &10.0, 1), OK);
            assert_eq!(init(inst), OK);
            assert_eq!(step(inst, 0.0, h), ERROR, "step of {h} s");
            assert!(log.last().unwrap().1.contains("longer than"), "{log:?}");
            // the instance refuses to go on until it is reset
            assert_eq!(step(inst, 0.0, 1e-3), ERROR);
            assert_eq!(get(inst, VR_STATE + 3).0, OK, "values can still be read");
            fmi3Reset(inst);
            assert_eq!(init(inst), OK);
            assert_eq!(step(inst, 0.0, 1e-3), OK);
            fmi3FreeInstance(inst);
        }
    });
}

#[test]
fn an_inertia_of_1e_300_is_refused_at_initialisation() {
    in_child("an_inertia_of_1e_300_is_refused_at_initialisation", || unsafe {
        let mut log = Log::new();
        let inst = instance(&mut log, false);
        let j_drive = VR_PARAM + 1;
        assert_eq!(fmi3SetFloat64(inst, &j_drive, 1, &1e-300, 1), OK, "positive: accepted as a value");
        assert_eq!(init(inst), ERROR);
        assert!(log.last().unwrap().1.contains("time scales"), "{log:?}");
        fmi3FreeInstance(inst);
    });
}

#[test]
fn an_input_of_1e308_never_gives_ok_with_a_non_finite_state() {
    in_child("an_input_of_1e308_never_gives_ok_with_a_non_finite_state", || unsafe {
        let mut log = Log::new();
        let inst = instance(&mut log, false);
        let m_drive = VR_INPUT + 1;
        assert_eq!(fmi3SetFloat64(inst, &m_drive, 1, &1e308, 1), OK);
        assert_eq!(init(inst), OK);
        let mut failed_at = None;
        for k in 0..100_000 {
            let s = step(inst, k as f64 * 1e-3, 1e-3);
            if s != OK {
                assert_eq!(s, ERROR);
                failed_at = Some(k);
                break;
            }
            // the load machines' angles and the speeds (φ_drive among them), and the twist
            for vr in (VR_STATE..VR_STATE + 6).chain([VR_TWIST]) {
                let (s, v) = get(inst, vr);
                assert!(s == OK && v.is_finite(), "step {k}: OK with value reference {vr} = {v}");
            }
        }
        let k = failed_at.expect("the state overflows within 100 s of 1e308 N·m");
        assert!(log.last().unwrap().1.contains("became"), "{log:?}");
        assert_eq!(step(inst, k as f64 * 1e-3, 1e-3), ERROR, "no step after the failure");
        fmi3FreeInstance(inst);
    });
}

#[test]
fn model_exchange_time_cannot_go_back_before_an_accepted_step() {
    in_child("model_exchange_time_cannot_go_back_before_an_accepted_step", || unsafe {
        let mut log = Log::new();
        let inst = instance(&mut log, true);
        assert_eq!(init(inst), OK);
        assert_eq!(fmi3EnterContinuousTimeMode(inst), OK);
        assert_eq!(fmi3SetTime(inst, 0.2), OK);
        // an integrator may retry from the last accepted point (0 s) ...
        assert_eq!(fmi3SetTime(inst, 0.1), OK);
        let (mut enter, mut terminate) = (false, false);
        assert_eq!(fmi3CompletedIntegratorStep(inst, true, &mut enter, &mut terminate), OK);
        // ... but not before it
        assert_eq!(fmi3SetTime(inst, 0.05), ERROR);
        assert!(log.last().unwrap().1.contains("before the last accepted"), "{log:?}");
        assert_eq!(fmi3SetTime(inst, 0.15), OK);
        fmi3FreeInstance(inst);
    });
}

#[test]
fn a_stop_time_before_the_start_time_is_refused() {
    in_child("a_stop_time_before_the_start_time_is_refused", || unsafe {
        let mut log = Log::new();
        let inst = instance(&mut log, false);
        assert_eq!(fmi3EnterInitializationMode(inst, false, 0.0, 1.0, true, 0.5), ERROR);
        assert!(log.last().unwrap().1.contains("before the start"), "{log:?}");
        fmi3FreeInstance(inst);
        // FMI 2: fmi2SetupExperiment (a null logger: the refusal is the status)
        #[repr(C)]
        struct Callbacks([*mut c_void; 5]);
        let functions = Callbacks([std::ptr::null_mut(); 5]);
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
        assert_eq!(rigtwin_fmu::fmi2::fmi2SetupExperiment(c, 0, 0.0, 1.0, 1, 0.5), ERROR);
        assert_eq!(rigtwin_fmu::fmi2::fmi2SetupExperiment(c, 0, 0.0, 0.0, 1, 0.5), OK);
        rigtwin_fmu::fmi2::fmi2FreeInstance(c);
    });
}

/// The serialized state of `inst` after a few steps with a drive torque (so its states move).
unsafe fn serialized_state(inst: *mut c_void) -> Vec<u8> {
    assert_eq!(init(inst), OK);
    let drive = VR_INPUT + 1;
    for k in 0..20 {
        assert_eq!(fmi3SetFloat64(inst, &drive, 1, &(50.0 * (k as f64 * 0.3).sin()), 1), OK);
        assert_eq!(step(inst, k as f64 * 1e-3, 1e-3), OK);
    }
    let mut state: *mut c_void = std::ptr::null_mut();
    assert_eq!(fmi3GetFMUState(inst, &mut state), OK);
    let mut size = 0usize;
    assert_eq!(fmi3SerializedFMUStateSize(inst, state, &mut size), OK);
    let mut bytes = vec![0u8; size];
    assert_eq!(fmi3SerializeFMUState(inst, state, bytes.as_mut_ptr(), size), OK);
    assert_eq!(fmi3FreeFMUState(inst, &mut state), OK);
    bytes
}

#[test]
fn a_serialized_state_with_a_nan_or_infinite_state_value_is_refused() {
    in_child("a_serialized_state_with_a_nan_or_infinite_state_value_is_refused", || unsafe {
        let mut log = Log::new();
        let inst = instance(&mut log, false);
        let bytes = serialized_state(inst);
        // the round trip itself is accepted
        let mut state: *mut c_void = std::ptr::null_mut();
        assert_eq!(fmi3DeserializeFMUState(inst, bytes.as_ptr(), bytes.len(), &mut state), OK);
        assert_eq!(fmi3SetFMUState(inst, state), OK);
        assert_eq!(fmi3FreeFMUState(inst, &mut state), OK);
        // the time and every continuous state made NaN or infinite in turn
        let states = rigtwin_fmu::instance::Snapshot::from_bytes(&bytes).unwrap().state_bytes();
        assert!(states.len() >= 6 * 8, "the rig has at least six states");
        for at in (states.start - 8..states.end).step_by(8) {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let mut b = bytes.clone();
                b[at..at + 8].copy_from_slice(&bad.to_le_bytes());
                let mut state: *mut c_void = std::ptr::null_mut();
                assert_eq!(fmi3DeserializeFMUState(inst, b.as_ptr(), b.len(), &mut state), ERROR, "byte {at} = {bad}");
                assert!(state.is_null());
                assert!(log.last().unwrap().1.contains("not a finite number"), "{log:?}");
            }
        }
        // the instance keeps its finite state
        for vr in VR_STATE..VR_STATE + 6 {
            let (s, v) = get(inst, vr);
            assert!(s == OK && v.is_finite());
        }
        fmi3FreeInstance(inst);
    });
}

#[test]
fn the_state_of_another_model_with_the_same_dimensions_is_refused() {
    in_child("the_state_of_another_model_with_the_same_dimensions_is_refused", || unsafe {
        // another parameter set of the same structure: same states, inputs and parameters
        let mut rig = rigtwin_fmu::RigPlant::default();
        rig.powertrain.j_drive *= 1.5;
        let other = FmuParams::of_rig(rig);
        assert_ne!(rigtwin_fmu::token(&other), rigtwin_fmu::token(&FmuParams::default()));
        let dir = std::env::temp_dir().join(format!("rigtwin-misuse-other-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join(rigtwin_fmu::PARAMS_RESOURCE), serde_json::to_vec(&other).unwrap()).unwrap();
        let resources = CString::new(dir.to_str().unwrap()).unwrap();
        let mut their_log = Log::new();
        let theirs = instance_of(&mut their_log, false, &other, Some(&resources));
        let bytes = serialized_state(theirs);
        fmi3FreeInstance(theirs);
        let mut log = Log::new();
        let inst = instance(&mut log, false);
        let own = serialized_state(inst);
        assert_eq!(own.len(), bytes.len(), "the two states have the same dimensions");
        let mut state: *mut c_void = std::ptr::null_mut();
        assert_eq!(fmi3DeserializeFMUState(inst, bytes.as_ptr(), bytes.len(), &mut state), ERROR);
        assert!(state.is_null());
        assert!(log.last().unwrap().1.contains("only fits the model it came from"), "{log:?}");
        fmi3FreeInstance(inst);
    });
}
