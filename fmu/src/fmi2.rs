//! FMI 2.0 glue: argument conversion, status mapping and panic containment around [`Instance`].

#![allow(missing_docs, non_snake_case, clippy::missing_safety_doc)]

use std::ffi::{c_char, CString};

use crate::ffi::{self, cstring, slice, slice_mut, str_of};
use std::panic::{catch_unwind, AssertUnwindSafe};

use crate::bindings::fmi2::*;

use crate::instance::{Failure, Instance, Interface, Logger, Mode, Res, Status};

struct Fmi2Logger {
    functions: fmi2CallbackFunctions,
    name: CString,
}

fn status2(s: Status) -> fmi2Status {
    match s {
        Status::Ok => fmi2Status_fmi2OK,
        Status::Warning => fmi2Status_fmi2Warning,
        Status::Discard => fmi2Status_fmi2Discard,
        Status::Error => fmi2Status_fmi2Error,
        Status::Fatal => fmi2Status_fmi2Fatal,
    }
}

impl Logger for Fmi2Logger {
    fn log(&self, status: Status, category: &str, message: &str) {
        if let Some(cb) = self.functions.logger {
            let (c, m) = (cstring(category), cstring(message));
            // SAFETY: the logger is printf-like; the message goes in as the argument of a "%s"
            // format, so no '%' in it is ever interpreted.
            unsafe {
                cb(
                    self.functions.componentEnvironment,
                    self.name.as_ptr(),
                    status2(status),
                    c.as_ptr(),
                    c"%s".as_ptr(),
                    m.as_ptr(),
                )
            };
        }
    }
}

/// An FMI 2 instance: the shared instance plus what FMI 2 keeps apart (the start time of
/// fmi2SetupExperiment).
struct Component {
    inner: Instance,
    start_time: f64,
    stop_time: Option<f64>,
}

unsafe fn with(c: fmi2Component, f: impl FnOnce(&mut Component) -> Res<()>) -> fmi2Status {
    if c.is_null() {
        return fmi2Status_fmi2Error;
    }
    let comp = &mut *(c as *mut Component);
    match catch_unwind(AssertUnwindSafe(|| f(comp))) {
        Ok(Ok(())) => fmi2Status_fmi2OK,
        Ok(Err(failure)) => status2(comp.inner.report(&failure)),
        Err(_) => {
            let failure = Failure {
                status: Status::Fatal,
                message: "internal error (a panic was contained): the instance must be freed".into(),
            };
            status2(comp.inner.report(&failure))
        }
    }
}

fn unsupported(what: &str) -> Res<()> {
    Err(Failure { status: Status::Error, message: format!("{what} is not supported by this FMU") })
}

fn null_arg(function: &str) -> Failure {
    Failure { status: Status::Error, message: format!("{function}: a null pointer was passed") }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    logging_on: fmi2Boolean,
    _n: usize,
    _categories: *const fmi2String,
) -> fmi2Status {
    with(c, |comp| {
        comp.inner.logging_on = logging_on != 0;
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    name: fmi2String,
    fmu_type: fmi2Type,
    guid: fmi2String,
    resource_location: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    logging_on: fmi2Boolean,
) -> fmi2Component {
    if functions.is_null() {
        return std::ptr::null_mut();
    }
    let logger = Fmi2Logger { functions: *functions, name: cstring(str_of(name)) };
    let result = catch_unwind(AssertUnwindSafe(|| {
        let interface = match fmu_type {
            t if t == fmi2Type_fmi2ModelExchange => Interface::ModelExchange,
            t if t == fmi2Type_fmi2CoSimulation => Interface::CoSimulation,
            other => return Err(format!("unknown fmuType {other}")),
        };
        let location = str_of(resource_location);
        let resources = if location.is_empty() { None } else { crate::path_of_uri(location) };
        let params = crate::checked_params(resources.as_deref(), str_of(guid), "GUID")?;
        if params.controller.is_some() && interface == Interface::ModelExchange {
            return Err("the controller FMU is a co-simulation FMU only".to_string());
        }
        Ok((interface, params))
    }));
    match result {
        Ok(Ok((interface, params))) => {
            let inner = Instance::new(str_of(name), interface, Box::new(logger), logging_on != 0, &params);
            Box::into_raw(Box::new(Component { inner, start_time: 0.0, stop_time: None })) as fmi2Component
        }
        Ok(Err(message)) => {
            logger.log(Status::Error, "logStatusError", &message);
            std::ptr::null_mut()
        }
        Err(_) => {
            logger.log(Status::Fatal, "logStatusError", "internal error during instantiation");
            std::ptr::null_mut()
        }
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    if !c.is_null() {
        let _ = catch_unwind(AssertUnwindSafe(|| drop(Box::from_raw(c as *mut Component))));
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    _tolerance_defined: fmi2Boolean,
    _tolerance: fmi2Real,
    start_time: fmi2Real,
    stop_time_defined: fmi2Boolean,
    stop_time: fmi2Real,
) -> fmi2Status {
    with(c, |comp| {
        comp.inner.expect("fmi2SetupExperiment", &[Mode::Instantiated])?;
        if stop_time_defined != 0 && (stop_time.is_nan() || stop_time < start_time) {
            return Err(Failure {
                status: Status::Error,
                message: format!(
                    "fmi2SetupExperiment: stop time {stop_time} s is before the start time {start_time} s"
                ),
            });
        }
        comp.start_time = start_time;
        comp.stop_time = (stop_time_defined != 0).then_some(stop_time);
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    with(c, |comp| comp.inner.enter_initialization_mode(comp.start_time, comp.stop_time))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    with(c, |comp| comp.inner.exit_initialization_mode())
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    with(c, |comp| comp.inner.terminate())
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    with(c, |comp| {
        comp.inner.reset();
        comp.start_time = 0.0;
        comp.stop_time = None;
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    values: *mut fmi2Real,
) -> fmi2Status {
    with(c, |comp| comp.inner.get_f64(slice(vr, n)?, slice_mut(values, n)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    values: *const fmi2Real,
) -> fmi2Status {
    with(c, |comp| comp.inner.set_f64(slice(vr, n)?, slice(values, n)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    values: *mut fmi2Integer,
) -> fmi2Status {
    with(c, |comp| comp.inner.get_i32(slice(vr, n)?, slice_mut(values, n)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    values: *const fmi2Integer,
) -> fmi2Status {
    with(c, |comp| comp.inner.set_i32(slice(vr, n)?, slice(values, n)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    n: usize,
    _values: *mut fmi2Boolean,
) -> fmi2Status {
    with(c, |_| if n == 0 { Ok(()) } else { unsupported("this FMU has no Boolean variables: getting them") })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    n: usize,
    _values: *const fmi2Boolean,
) -> fmi2Status {
    with(c, |_| if n == 0 { Ok(()) } else { unsupported("this FMU has no Boolean variables: setting them") })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    n: usize,
    _values: *mut fmi2String,
) -> fmi2Status {
    with(c, |_| if n == 0 { Ok(()) } else { unsupported("this FMU has no String variables: getting them") })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    n: usize,
    _values: *const fmi2String,
) -> fmi2Status {
    with(c, |_| if n == 0 { Ok(()) } else { unsupported("this FMU has no String variables: setting them") })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    with(c, |comp| ffi::get_state(&comp.inner, state, "fmi2GetFMUstate"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status {
    with(c, |comp| ffi::set_state(&mut comp.inner, state, "fmi2SetFMUstate"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    with(c, |_| ffi::free_state(state))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    _state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    with(c, |_| ffi::state_size(_state, size, "fmi2SerializedFMUstateSize"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    state: fmi2FMUstate,
    out: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    with(c, |_| ffi::serialize_state(state, out as *mut u8, size, "fmi2SerializeFMUstate"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    bytes: *const fmi2Byte,
    size: usize,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    with(c, |comp| ffi::deserialize_state(&comp.inner, bytes as *const u8, size, state, "fmi2DeSerializeFMUstate"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    unknowns: *const fmi2ValueReference,
    n_unknown: usize,
    knowns: *const fmi2ValueReference,
    n_known: usize,
    dv_known: *const fmi2Real,
    dv_unknown: *mut fmi2Real,
) -> fmi2Status {
    with(c, |comp| {
        comp.inner.directional_derivative(
            slice(unknowns, n_unknown)?,
            slice(knowns, n_known)?,
            slice(dv_known, n_known)?,
            slice_mut(dv_unknown, n_unknown)?,
        )
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2EnterEventMode(c: fmi2Component) -> fmi2Status {
    with(c, |comp| comp.inner.enter_event_mode())
}

#[no_mangle]
pub unsafe extern "C" fn fmi2NewDiscreteStates(c: fmi2Component, info: *mut fmi2EventInfo) -> fmi2Status {
    with(c, |comp| {
        comp.inner.expect("fmi2NewDiscreteStates", &[Mode::EventMode])?;
        if info.is_null() {
            return Err(null_arg("fmi2NewDiscreteStates"));
        }
        *info = fmi2EventInfo::default();
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: fmi2Component) -> fmi2Status {
    with(c, |comp| comp.inner.enter_continuous_time_mode())
}

#[no_mangle]
pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
    c: fmi2Component,
    _no_set_state_prior: fmi2Boolean,
    enter_event_mode: *mut fmi2Boolean,
    terminate: *mut fmi2Boolean,
) -> fmi2Status {
    with(c, |comp| {
        comp.inner.completed_integrator_step()?;
        for p in [enter_event_mode, terminate] {
            if !p.is_null() {
                *p = 0;
            }
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetTime(c: fmi2Component, time: fmi2Real) -> fmi2Status {
    with(c, |comp| comp.inner.set_time(time))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetContinuousStates(c: fmi2Component, x: *const fmi2Real, n: usize) -> fmi2Status {
    with(c, |comp| comp.inner.set_continuous_states(slice(x, n)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetDerivatives(c: fmi2Component, dx: *mut fmi2Real, n: usize) -> fmi2Status {
    with(c, |comp| comp.inner.derivatives(slice_mut(dx, n)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetEventIndicators(c: fmi2Component, _z: *mut fmi2Real, n: usize) -> fmi2Status {
    with(c, |_| if n == 0 { Ok(()) } else { unsupported("event indicators (the model has none)") })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetContinuousStates(c: fmi2Component, x: *mut fmi2Real, n: usize) -> fmi2Status {
    with(c, |comp| comp.inner.continuous_states(slice_mut(x, n)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
    c: fmi2Component,
    nominals: *mut fmi2Real,
    n: usize,
) -> fmi2Status {
    with(c, |comp| comp.inner.nominals(slice_mut(nominals, n)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _n: usize,
    _order: *const fmi2Integer,
    _values: *const fmi2Real,
) -> fmi2Status {
    with(c, |_| unsupported("input derivatives (canInterpolateInputs = false)"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _n: usize,
    _order: *const fmi2Integer,
    _values: *mut fmi2Real,
) -> fmi2Status {
    with(c, |_| unsupported("output derivatives (maxOutputDerivativeOrder = 0)"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    t: fmi2Real,
    h: fmi2Real,
    _no_set_state_prior: fmi2Boolean,
) -> fmi2Status {
    with(c, |comp| comp.inner.do_step(t, h))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    with(c, |_| unsupported("fmi2CancelStep (doStep never returns pending)"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetStatus(c: fmi2Component, _kind: fmi2StatusKind, _value: *mut fmi2Status) -> fmi2Status {
    with(c, |_| unsupported("fmi2GetStatus (doStep never returns pending)"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Real) -> fmi2Status {
    with(c, |comp| {
        if kind != fmi2StatusKind_fmi2LastSuccessfulTime {
            return unsupported("this status kind");
        }
        if value.is_null() {
            return Err(null_arg("fmi2GetRealStatus"));
        }
        *value = comp.inner.time();
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: fmi2Component,
    _kind: fmi2StatusKind,
    _value: *mut fmi2Integer,
) -> fmi2Status {
    with(c, |_| unsupported("fmi2GetIntegerStatus"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    with(c, |_| {
        if kind != fmi2StatusKind_fmi2Terminated {
            return unsupported("this status kind");
        }
        if value.is_null() {
            return Err(null_arg("fmi2GetBooleanStatus"));
        }
        *value = 0;
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: fmi2Component,
    _kind: fmi2StatusKind,
    _value: *mut fmi2String,
) -> fmi2Status {
    with(c, |_| unsupported("fmi2GetStringStatus"))
}

include!("fmi2_signatures.rs");

// The two functions whose arguments are the header's structs (nominal types, so checked against
// the checked-in bindings only; tests/signatures.rs compares the structs with fmi-sys').
const _: () = {
    let _: fmi2InstantiateTYPE = Some(fmi2Instantiate);
    let _: fmi2NewDiscreteStatesTYPE = Some(fmi2NewDiscreteStates);
};
