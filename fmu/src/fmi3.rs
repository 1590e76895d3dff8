//! FMI 3.0 glue: argument conversion, status mapping and panic containment around [`Instance`].

#![allow(missing_docs, non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]

use std::ffi::c_char;

use crate::ffi::{self, cstring, slice, slice_mut, str_of};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use crate::bindings::fmi3::*;

use crate::instance::{Failure, Instance, Interface, Logger, Res, Status};

struct Fmi3Logger {
    callback: fmi3LogMessageCallback,
    env: fmi3InstanceEnvironment,
}

fn status3(s: Status) -> fmi3Status {
    match s {
        Status::Ok => fmi3Status_fmi3OK,
        Status::Warning => fmi3Status_fmi3Warning,
        Status::Discard => fmi3Status_fmi3Discard,
        Status::Error => fmi3Status_fmi3Error,
        Status::Fatal => fmi3Status_fmi3Fatal,
    }
}

impl Logger for Fmi3Logger {
    fn log(&self, status: Status, category: &str, message: &str) {
        if let Some(cb) = self.callback {
            let (c, m) = (cstring(category), cstring(message));
            // SAFETY: the importer's callback with NUL-terminated strings that outlive the call
            unsafe { cb(self.env, status3(status), c.as_ptr(), m.as_ptr()) };
        }
    }
}

/// Runs `f` on the instance behind `instance`, logging failures and containing panics.
unsafe fn with(instance: fmi3Instance, f: impl FnOnce(&mut Instance) -> Res<()>) -> fmi3Status {
    if instance.is_null() {
        return fmi3Status_fmi3Error;
    }
    let inst = &mut *(instance as *mut Instance);
    match catch_unwind(AssertUnwindSafe(|| f(inst))) {
        Ok(Ok(())) => fmi3Status_fmi3OK,
        Ok(Err(failure)) => status3(inst.report(&failure)),
        Err(_) => {
            let failure = Failure {
                status: Status::Fatal,
                message: "internal error (a panic was contained): the instance must be freed".into(),
            };
            status3(inst.report(&failure))
        }
    }
}

fn unsupported(what: &str) -> Res<()> {
    Err(Failure { status: Status::Error, message: format!("{what} is not supported by this FMU") })
}

unsafe fn instantiate(
    interface: Interface,
    name: fmi3String,
    token: fmi3String,
    resource_path: fmi3String,
    logging_on: fmi3Boolean,
    env: fmi3InstanceEnvironment,
    log: fmi3LogMessageCallback,
) -> fmi3Instance {
    let logger = Fmi3Logger { callback: log, env };
    let result = catch_unwind(AssertUnwindSafe(|| {
        let resources = (!resource_path.is_null()).then(|| Path::new(str_of(resource_path)).to_path_buf());
        let params = crate::checked_params(resources.as_deref(), str_of(token), "instantiation token")?;
        if params.controller.is_some() && interface == Interface::ModelExchange {
            return Err("the controller FMU is a co-simulation FMU only".to_string());
        }
        Ok(params)
    }));
    match result {
        Ok(Ok(params)) => {
            let inst = Instance::new(str_of(name), interface, Box::new(logger), logging_on, &params);
            Box::into_raw(Box::new(inst)) as fmi3Instance
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
pub unsafe extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: fmi3Instance,
    logging_on: fmi3Boolean,
    _n: usize,
    _categories: *const fmi3String,
) -> fmi3Status {
    with(instance, |i| {
        i.logging_on = logging_on;
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    name: fmi3String,
    token: fmi3String,
    resource_path: fmi3String,
    _visible: fmi3Boolean,
    logging_on: fmi3Boolean,
    env: fmi3InstanceEnvironment,
    log: fmi3LogMessageCallback,
) -> fmi3Instance {
    instantiate(Interface::ModelExchange, name, token, resource_path, logging_on, env, log)
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    name: fmi3String,
    token: fmi3String,
    resource_path: fmi3String,
    _visible: fmi3Boolean,
    logging_on: fmi3Boolean,
    event_mode_used: fmi3Boolean,
    _early_return_allowed: fmi3Boolean,
    _required: *const fmi3ValueReference,
    _n_required: usize,
    env: fmi3InstanceEnvironment,
    log: fmi3LogMessageCallback,
    _intermediate: fmi3IntermediateUpdateCallback,
) -> fmi3Instance {
    if event_mode_used {
        Fmi3Logger { callback: log, env }.log(
            Status::Error,
            "logStatusError",
            "event mode is not supported (hasEventMode = false)",
        );
        return std::ptr::null_mut();
    }
    instantiate(Interface::CoSimulation, name, token, resource_path, logging_on, env, log)
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    _name: fmi3String,
    _token: fmi3String,
    _resource_path: fmi3String,
    _visible: fmi3Boolean,
    _logging_on: fmi3Boolean,
    env: fmi3InstanceEnvironment,
    log: fmi3LogMessageCallback,
    _clock_update: fmi3ClockUpdateCallback,
    _lock: fmi3LockPreemptionCallback,
    _unlock: fmi3UnlockPreemptionCallback,
) -> fmi3Instance {
    Fmi3Logger { callback: log, env }.log(
        Status::Error,
        "logStatusError",
        "scheduled execution is not supported by this FMU",
    );
    std::ptr::null_mut()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3FreeInstance(instance: fmi3Instance) {
    if !instance.is_null() {
        let _ = catch_unwind(AssertUnwindSafe(|| drop(Box::from_raw(instance as *mut Instance))));
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    instance: fmi3Instance,
    _tolerance_defined: fmi3Boolean,
    _tolerance: fmi3Float64,
    start_time: fmi3Float64,
    stop_time_defined: fmi3Boolean,
    stop_time: fmi3Float64,
) -> fmi3Status {
    with(instance, |i| i.enter_initialization_mode(start_time, stop_time_defined.then_some(stop_time)))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status {
    with(instance, |i| i.exit_initialization_mode())
}

#[no_mangle]
pub unsafe extern "C" fn fmi3EnterEventMode(instance: fmi3Instance) -> fmi3Status {
    with(instance, |i| i.enter_event_mode())
}

#[no_mangle]
pub unsafe extern "C" fn fmi3Terminate(instance: fmi3Instance) -> fmi3Status {
    with(instance, |i| i.terminate())
}

#[no_mangle]
pub unsafe extern "C" fn fmi3Reset(instance: fmi3Instance) -> fmi3Status {
    with(instance, |i| {
        i.reset();
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetFloat64(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    values: *mut fmi3Float64,
    n_values: usize,
) -> fmi3Status {
    with(instance, |i| i.get_f64(slice(vrs, n_vrs)?, slice_mut(values, n_values)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetFloat64(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    values: *const fmi3Float64,
    n_values: usize,
) -> fmi3Status {
    with(instance, |i| i.set_f64(slice(vrs, n_vrs)?, slice(values, n_values)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetInt32(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    values: *mut fmi3Int32,
    n_values: usize,
) -> fmi3Status {
    with(instance, |i| i.get_i32(slice(vrs, n_vrs)?, slice_mut(values, n_values)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetInt32(
    instance: fmi3Instance,
    vrs: *const fmi3ValueReference,
    n_vrs: usize,
    values: *const fmi3Int32,
    n_values: usize,
) -> fmi3Status {
    with(instance, |i| i.set_i32(slice(vrs, n_vrs)?, slice(values, n_values)?))
}

/// Getters and setters of types this FMU has no variables of: fine for no value references,
/// an error naming the type otherwise.
macro_rules! no_variables_of_type {
    ($get:ident, $set:ident, $t:ty, $name:literal) => {
        #[no_mangle]
        pub unsafe extern "C" fn $get(
            instance: fmi3Instance,
            _vrs: *const fmi3ValueReference,
            n_vrs: usize,
            _values: *mut $t,
            _n_values: usize,
        ) -> fmi3Status {
            with(instance, |_| {
                if n_vrs == 0 {
                    Ok(())
                } else {
                    unsupported(concat!("this FMU has no ", $name, " variables: getting them"))
                }
            })
        }
        #[no_mangle]
        pub unsafe extern "C" fn $set(
            instance: fmi3Instance,
            _vrs: *const fmi3ValueReference,
            n_vrs: usize,
            _values: *const $t,
            _n_values: usize,
        ) -> fmi3Status {
            with(instance, |_| {
                if n_vrs == 0 {
                    Ok(())
                } else {
                    unsupported(concat!("this FMU has no ", $name, " variables: setting them"))
                }
            })
        }
    };
}

no_variables_of_type!(fmi3GetFloat32, fmi3SetFloat32, fmi3Float32, "Float32");
no_variables_of_type!(fmi3GetInt8, fmi3SetInt8, fmi3Int8, "Int8");
no_variables_of_type!(fmi3GetUInt8, fmi3SetUInt8, fmi3UInt8, "UInt8");
no_variables_of_type!(fmi3GetInt16, fmi3SetInt16, fmi3Int16, "Int16");
no_variables_of_type!(fmi3GetUInt16, fmi3SetUInt16, fmi3UInt16, "UInt16");
no_variables_of_type!(fmi3GetUInt32, fmi3SetUInt32, fmi3UInt32, "UInt32");
no_variables_of_type!(fmi3GetInt64, fmi3SetInt64, fmi3Int64, "Int64");
no_variables_of_type!(fmi3GetUInt64, fmi3SetUInt64, fmi3UInt64, "UInt64");
no_variables_of_type!(fmi3GetBoolean, fmi3SetBoolean, fmi3Boolean, "Boolean");
no_variables_of_type!(fmi3GetString, fmi3SetString, fmi3String, "String");

#[no_mangle]
pub unsafe extern "C" fn fmi3GetClock(
    instance: fmi3Instance,
    _vrs: *const fmi3ValueReference,
    n_vrs: usize,
    _values: *mut fmi3Clock,
) -> fmi3Status {
    with(instance, |_| if n_vrs == 0 { Ok(()) } else { unsupported("this FMU has no clocks: getting them") })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetClock(
    instance: fmi3Instance,
    _vrs: *const fmi3ValueReference,
    n_vrs: usize,
    _values: *const fmi3Clock,
) -> fmi3Status {
    with(instance, |_| if n_vrs == 0 { Ok(()) } else { unsupported("this FMU has no clocks: setting them") })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetBinary(
    instance: fmi3Instance,
    _vrs: *const fmi3ValueReference,
    n_vrs: usize,
    _sizes: *mut usize,
    _values: *mut fmi3Binary,
    _n: usize,
) -> fmi3Status {
    with(instance, |_| if n_vrs == 0 { Ok(()) } else { unsupported("this FMU has no Binary variables: getting them") })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetBinary(
    instance: fmi3Instance,
    _vrs: *const fmi3ValueReference,
    n_vrs: usize,
    _sizes: *const usize,
    _values: *const fmi3Binary,
    _n: usize,
) -> fmi3Status {
    with(instance, |_| if n_vrs == 0 { Ok(()) } else { unsupported("this FMU has no Binary variables: setting them") })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetNumberOfVariableDependencies(
    instance: fmi3Instance,
    _vr: fmi3ValueReference,
    _n: *mut usize,
) -> fmi3Status {
    with(instance, |_| {
        unsupported("fmi3GetNumberOfVariableDependencies (the model description declares no dependencies)")
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetVariableDependencies(
    instance: fmi3Instance,
    _dependent: fmi3ValueReference,
    _element_indices_of_dependent: *mut usize,
    _independents: *mut fmi3ValueReference,
    _element_indices_of_independents: *mut usize,
    _kinds: *mut fmi3DependencyKind,
    _n: usize,
) -> fmi3Status {
    with(instance, |_| unsupported("fmi3GetVariableDependencies (the model description declares no dependencies)"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetFMUState(instance: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status {
    with(instance, |i| ffi::get_state(i, state, "fmi3GetFMUState"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetFMUState(instance: fmi3Instance, state: fmi3FMUState) -> fmi3Status {
    with(instance, |i| ffi::set_state(i, state, "fmi3SetFMUState"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3FreeFMUState(instance: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status {
    with(instance, |_| ffi::free_state(state))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    instance: fmi3Instance,
    state: fmi3FMUState,
    size: *mut usize,
) -> fmi3Status {
    with(instance, |_| ffi::state_size(state, size, "fmi3SerializedFMUStateSize"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    instance: fmi3Instance,
    state: fmi3FMUState,
    out: *mut fmi3Byte,
    size: usize,
) -> fmi3Status {
    with(instance, |_| ffi::serialize_state(state, out, size, "fmi3SerializeFMUState"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    instance: fmi3Instance,
    bytes: *const fmi3Byte,
    size: usize,
    state: *mut fmi3FMUState,
) -> fmi3Status {
    with(instance, |inst| ffi::deserialize_state(inst, bytes, size, state, "fmi3DeserializeFMUState"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetDirectionalDerivative(
    instance: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    n_unknowns: usize,
    knowns: *const fmi3ValueReference,
    n_knowns: usize,
    seed: *const fmi3Float64,
    n_seed: usize,
    sensitivity: *mut fmi3Float64,
    n_sensitivity: usize,
) -> fmi3Status {
    with(instance, |i| {
        i.directional_derivative(
            slice(unknowns, n_unknowns)?,
            slice(knowns, n_knowns)?,
            slice(seed, n_seed)?,
            slice_mut(sensitivity, n_sensitivity)?,
        )
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetAdjointDerivative(
    instance: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    n_unknowns: usize,
    knowns: *const fmi3ValueReference,
    n_knowns: usize,
    seed: *const fmi3Float64,
    n_seed: usize,
    sensitivity: *mut fmi3Float64,
    n_sensitivity: usize,
) -> fmi3Status {
    with(instance, |i| {
        let (u, k, s, out) = (
            slice(unknowns, n_unknowns)?,
            slice(knowns, n_knowns)?,
            slice(seed, n_seed)?,
            slice_mut(sensitivity, n_sensitivity)?,
        );
        if s.len() != u.len() || out.len() != k.len() {
            return Err(Failure {
                status: Status::Error,
                message: "the numbers of value references, seeds and results differ".into(),
            });
        }
        // sensitivity_j = Σ_i seed_i ∂unknown_i/∂known_j, one known at a time
        for (j, kj) in k.iter().enumerate() {
            let mut column = vec![0.0; u.len()];
            i.directional_derivative(u, std::slice::from_ref(kj), &[1.0], &mut column)?;
            out[j] = column.iter().zip(s).map(|(a, b)| a * b).sum();
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3EnterConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    with(instance, |_| unsupported("configuration mode (no structural parameters)"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3ExitConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    with(instance, |_| unsupported("configuration mode (no structural parameters)"))
}

macro_rules! no_clocks {
    ($($name:ident($($arg:ident: $t:ty),*);)*) => {$(
        #[no_mangle]
        pub unsafe extern "C" fn $name(instance: fmi3Instance, $($arg: $t),*) -> fmi3Status {
            $(let _ = $arg;)*
            with(instance, |_| unsupported(concat!(stringify!($name), " (the FMU has no clocks)")))
        }
    )*};
}

no_clocks! {
    fmi3GetIntervalDecimal(vrs: *const fmi3ValueReference, n: usize, intervals: *mut fmi3Float64, qualifiers: *mut fmi3IntervalQualifier);
    fmi3GetIntervalFraction(vrs: *const fmi3ValueReference, n: usize, counters: *mut fmi3UInt64, resolutions: *mut fmi3UInt64, qualifiers: *mut fmi3IntervalQualifier);
    fmi3GetShiftDecimal(vrs: *const fmi3ValueReference, n: usize, shifts: *mut fmi3Float64);
    fmi3GetShiftFraction(vrs: *const fmi3ValueReference, n: usize, counters: *mut fmi3UInt64, resolutions: *mut fmi3UInt64);
    fmi3SetIntervalDecimal(vrs: *const fmi3ValueReference, n: usize, intervals: *const fmi3Float64);
    fmi3SetIntervalFraction(vrs: *const fmi3ValueReference, n: usize, counters: *const fmi3UInt64, resolutions: *const fmi3UInt64);
    fmi3SetShiftDecimal(vrs: *const fmi3ValueReference, n: usize, shifts: *const fmi3Float64);
    fmi3SetShiftFraction(vrs: *const fmi3ValueReference, n: usize, counters: *const fmi3UInt64, resolutions: *const fmi3UInt64);
    fmi3ActivateModelPartition(clock: fmi3ValueReference, time: fmi3Float64);
}

#[no_mangle]
pub unsafe extern "C" fn fmi3EvaluateDiscreteStates(instance: fmi3Instance) -> fmi3Status {
    with(instance, |_| Ok(())) // no discrete states
}

#[no_mangle]
pub unsafe extern "C" fn fmi3UpdateDiscreteStates(
    instance: fmi3Instance,
    need_update: *mut fmi3Boolean,
    terminate: *mut fmi3Boolean,
    nominals_changed: *mut fmi3Boolean,
    values_changed: *mut fmi3Boolean,
    next_time_defined: *mut fmi3Boolean,
    _next_time: *mut fmi3Float64,
) -> fmi3Status {
    with(instance, |i| {
        i.expect("fmi3UpdateDiscreteStates", &[crate::instance::Mode::EventMode])?;
        for p in [need_update, terminate, nominals_changed, values_changed, next_time_defined] {
            if !p.is_null() {
                *p = false;
            }
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(instance: fmi3Instance) -> fmi3Status {
    with(instance, |i| i.enter_continuous_time_mode())
}

#[no_mangle]
pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
    instance: fmi3Instance,
    _no_set_state_prior: fmi3Boolean,
    enter_event_mode: *mut fmi3Boolean,
    terminate: *mut fmi3Boolean,
) -> fmi3Status {
    with(instance, |i| {
        i.completed_integrator_step()?;
        for p in [enter_event_mode, terminate] {
            if !p.is_null() {
                *p = false;
            }
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetTime(instance: fmi3Instance, time: fmi3Float64) -> fmi3Status {
    with(instance, |i| i.set_time(time))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetContinuousStates(
    instance: fmi3Instance,
    x: *const fmi3Float64,
    n: usize,
) -> fmi3Status {
    with(instance, |i| i.set_continuous_states(slice(x, n)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(
    instance: fmi3Instance,
    dx: *mut fmi3Float64,
    n: usize,
) -> fmi3Status {
    with(instance, |i| i.derivatives(slice_mut(dx, n)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetEventIndicators(instance: fmi3Instance, _z: *mut fmi3Float64, n: usize) -> fmi3Status {
    with(instance, |_| if n == 0 { Ok(()) } else { unsupported("event indicators (the model has none)") })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetContinuousStates(instance: fmi3Instance, x: *mut fmi3Float64, n: usize) -> fmi3Status {
    with(instance, |i| i.continuous_states(slice_mut(x, n)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(
    instance: fmi3Instance,
    nominals: *mut fmi3Float64,
    n: usize,
) -> fmi3Status {
    with(instance, |i| i.nominals(slice_mut(nominals, n)?))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetNumberOfEventIndicators(instance: fmi3Instance, n: *mut usize) -> fmi3Status {
    with(instance, |_| {
        if !n.is_null() {
            *n = 0;
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(instance: fmi3Instance, n: *mut usize) -> fmi3Status {
    with(instance, |i| {
        if !n.is_null() {
            *n = i.nx();
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3EnterStepMode(instance: fmi3Instance) -> fmi3Status {
    with(instance, |_| unsupported("fmi3EnterStepMode (the FMU has no event mode in co-simulation)"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetOutputDerivatives(
    instance: fmi3Instance,
    _vrs: *const fmi3ValueReference,
    _n: usize,
    _orders: *const fmi3Int32,
    _values: *mut fmi3Float64,
    _n_values: usize,
) -> fmi3Status {
    with(instance, |_| unsupported("output derivatives (maxOutputDerivativeOrder = 0)"))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3DoStep(
    instance: fmi3Instance,
    t: fmi3Float64,
    h: fmi3Float64,
    _no_set_state_prior: fmi3Boolean,
    event_handling_needed: *mut fmi3Boolean,
    terminate: *mut fmi3Boolean,
    early_return: *mut fmi3Boolean,
    last_successful_time: *mut fmi3Float64,
) -> fmi3Status {
    with(instance, |i| {
        let r = i.do_step(t, h);
        for p in [event_handling_needed, terminate, early_return] {
            if !p.is_null() {
                *p = false;
            }
        }
        if !last_successful_time.is_null() {
            *last_successful_time = i.time();
        }
        r
    })
}

include!("fmi3_signatures.rs");
