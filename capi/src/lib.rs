//! # rigtwin-mpc — the rig's MPC behind a C API (`include/rigtwin_mpc.h`)
//!
//! A static and a shared library for C code on real-time targets (and Simulink S-functions,
//! NI VeriStand custom devices, …): create a controller from a rig file or an FMU's
//! `params.json`, reset it at an operating point, step it every millisecond with the measured
//! speeds and the references, free it. The controller is `rigtwin mpc`'s
//! (`mpc::rig::prediction` with the file's effects, `mpc::Controller`); this crate only
//! guards the boundary: no panic crosses it (`catch_unwind` everywhere), non-finite inputs
//! are refused, a non-finite command is never returned, `step` allocates nothing here.

use std::ffi::{c_char, c_int, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use mpc::closed_loop::steady_spin;
use mpc::{Controller, MpcSettings};
use plant::statespace::StateSpace;
use rigtwin_fmu::FmuParams;

/// Measured outputs, in the order of `measured[]`.
pub const MEASURED: [&str; 3] = ["w_m2", "w_drive", "w_m3"];
/// References, in the order of `reference[]`.
pub const REFERENCES: [&str; 3] = ["w_m2", "w_m3", "M_drive"];
/// Commands, in the order of `torques[]`.
pub const COMMANDS: [&str; 3] = ["M_m2", "M_drive", "M_m3"];

/// `rigtwin_mpc_status`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// The QP was solved.
    Ok = 0,
    /// The shifted previous plan was applied.
    Fallback = 1,
    /// A measurement or reference was not finite.
    BadInput = -1,
    /// NULL, or the controller failed internally.
    Invalid = -2,
}

/// `rigtwin_mpc_options`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Prediction horizon, steps.
    pub horizon: c_int,
    /// Number of move blocks (0: every step free).
    pub move_blocks: c_int,
    /// Wall-clock limit of one QP solve, s.
    pub time_limit_s: f64,
}

impl Default for Options {
    /// `rigtwin mpc`'s defaults: N = 50, 4 move blocks, 0.6 ms per solve.
    fn default() -> Self {
        Options { horizon: 50, move_blocks: 4, time_limit_s: MpcSettings::powertrain(1).solver.time_limit_s }
    }
}

impl Options {
    /// The controller settings these options give.
    pub fn settings(&self) -> anyhow::Result<MpcSettings> {
        let horizon =
            usize::try_from(self.horizon).map_err(|_| anyhow::anyhow!("horizon {}: expected 1..1000", self.horizon))?;
        let blocks = usize::try_from(self.move_blocks)
            .map_err(|_| anyhow::anyhow!("move_blocks {}: expected 0 or more", self.move_blocks))?;
        let mut s = MpcSettings::powertrain(horizon);
        s.move_blocks = if blocks == 0 { Vec::new() } else { mpc::exponential_blocks(horizon, blocks) };
        s.solver.time_limit_s = self.time_limit_s;
        s.validate()?;
        Ok(s)
    }
}

/// The controller behind `rigtwin_mpc *`.
pub struct RigtwinMpc {
    controller: Controller,
    model: StateSpace,
    /// Model output index of each `measured[]` entry.
    measured: [usize; 3],
    /// Model input index of each `torques[]` entry.
    commands: [usize; 3],
    y: Vec<f64>,
    last: [f64; 3],
    failed: bool,
}

impl RigtwinMpc {
    /// The controller of parameter set `params` with `options`, at rest.
    pub fn new(params: &FmuParams, options: &Options) -> anyhow::Result<Self> {
        if params.drive.is_some() {
            anyhow::bail!("a drive model: the C API's controller is the paper rig's (give a rig file)");
        }
        let settings = options.settings()?;
        let p = mpc::rig::prediction(&params.powertrain, params.variant, &params.effects, settings.dt_s)?;
        let controller = Controller::with_input_delays(&p.model, &p.input_delays_s, &settings)?;
        if controller.reference_names() != REFERENCES {
            anyhow::bail!("the controller's references are {:?}, not {:?}", controller.reference_names(), REFERENCES);
        }
        let find = |names: &[String], n: &str| {
            names.iter().position(|x| x == n).ok_or_else(|| anyhow::anyhow!("the model has no signal `{n}`"))
        };
        let (mut measured, mut commands) = ([0; 3], [0; 3]);
        for i in 0..3 {
            measured[i] = find(&p.model.output_names, MEASURED[i])?;
            commands[i] = find(&p.model.input_names, COMMANDS[i])?;
        }
        let mut c = RigtwinMpc {
            y: vec![0.0; p.model.output_names.len()],
            controller,
            model: p.model,
            measured,
            commands,
            last: [0.0; 3],
            failed: false,
        };
        c.reset(0.0)?;
        Ok(c)
    }

    /// The controller of the parameter file `path` (`None`: the embedded paper rig).
    pub fn from_file(path: Option<&Path>, options: &Options) -> anyhow::Result<Self> {
        let params = match path {
            None => FmuParams::default(),
            Some(p) if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("json")) => {
                let text = std::fs::read_to_string(p).map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?;
                serde_json::from_str(&text).map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?
            }
            Some(p) => rigtwin::fmu_package::params_of_file(p)?,
        };
        Self::new(&params, options).map_err(|e| match path {
            Some(p) => anyhow::anyhow!("{}: {e}", p.display()),
            None => e,
        })
    }

    /// Steady spinning at `speed_radps`.
    pub fn reset(&mut self, speed_radps: f64) -> anyhow::Result<()> {
        if !speed_radps.is_finite() {
            anyhow::bail!("speed {speed_radps} rad/s: expected a finite value");
        }
        let (x0, u0) = steady_spin(&self.model, speed_radps)?;
        self.controller.reset(&x0, &u0);
        self.last = self.commands.map(|j| u0[j]);
        self.failed = false;
        Ok(())
    }

    /// One step (see `rigtwin_mpc_step`). Allocation-free here.
    pub fn step(&mut self, measured: &[f64; 3], reference: &[f64; 3], torques: &mut [f64; 3]) -> Status {
        if self.failed {
            *torques = self.last;
            return Status::Invalid;
        }
        if measured.iter().chain(reference).any(|v| !v.is_finite()) {
            *torques = self.last;
            return Status::BadInput;
        }
        for (k, &j) in self.measured.iter().enumerate() {
            self.y[j] = measured[k];
        }
        let (u, info) = self.controller.step(&self.y, reference);
        let next = self.commands.map(|j| u[j]);
        if next.iter().any(|v| !v.is_finite()) {
            self.failed = true;
            *torques = self.last;
            return Status::Invalid;
        }
        self.last = next;
        *torques = next;
        if info.fallback {
            Status::Fallback
        } else {
            Status::Ok
        }
    }
}

/// Writes `message` NUL-terminated into `error` (at most `len` bytes).
///
/// # Safety
/// `error` is NULL or points to `len` writable bytes.
unsafe fn write_error(error: *mut c_char, len: usize, message: &str) {
    if error.is_null() || len == 0 {
        return;
    }
    let bytes = message.as_bytes();
    let n = bytes.len().min(len - 1);
    // SAFETY: the caller guarantees `len` writable bytes at `error`; n + 1 ≤ len
    unsafe {
        std::ptr::copy_nonoverlapping(bytes.as_ptr(), error.cast::<u8>(), n);
        *error.add(n) = 0;
    }
}

/// See `rigtwin_mpc.h`.
///
/// # Safety
/// `options` is NULL or points to a `rigtwin_mpc_options`.
#[no_mangle]
pub unsafe extern "C" fn rigtwin_mpc_default_options(options: *mut Options) {
    if !options.is_null() {
        // SAFETY: non-NULL and, by the contract, a valid options struct
        unsafe { *options = Options::default() };
    }
}

/// See `rigtwin_mpc.h`.
///
/// # Safety
/// `params_path` is NULL or a NUL-terminated string; `options` NULL or valid; `error` NULL or
/// `error_len` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn rigtwin_mpc_create(
    params_path: *const c_char,
    options: *const Options,
    error: *mut c_char,
    error_len: usize,
) -> *mut RigtwinMpc {
    let made = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: by the contract, NULL or valid
        let options = if options.is_null() { Options::default() } else { unsafe { *options } };
        let path = if params_path.is_null() {
            None
        } else {
            // SAFETY: by the contract, a NUL-terminated string
            let s = unsafe { CStr::from_ptr(params_path) };
            Some(s.to_str().map_err(|_| anyhow::anyhow!("params_path is not UTF-8"))?.to_string())
        };
        RigtwinMpc::from_file(path.as_deref().map(Path::new), &options)
    }));
    match made {
        Ok(Ok(c)) => Box::into_raw(Box::new(c)),
        Ok(Err(e)) => {
            // SAFETY: by the contract
            unsafe { write_error(error, error_len, &format!("{e:#}")) };
            std::ptr::null_mut()
        }
        Err(_) => {
            // SAFETY: by the contract
            unsafe { write_error(error, error_len, "internal error while creating the controller") };
            std::ptr::null_mut()
        }
    }
}

/// See `rigtwin_mpc.h`.
///
/// # Safety
/// `controller` is NULL or from `rigtwin_mpc_create` and not freed.
#[no_mangle]
pub unsafe extern "C" fn rigtwin_mpc_reset(controller: *mut RigtwinMpc, speed_radps: f64) -> Status {
    // SAFETY: by the contract, NULL or a live controller
    let Some(c) = (unsafe { controller.as_mut() }) else { return Status::Invalid };
    if !speed_radps.is_finite() {
        return Status::BadInput;
    }
    match catch_unwind(AssertUnwindSafe(|| c.reset(speed_radps))) {
        Ok(Ok(())) => Status::Ok,
        Ok(Err(_)) => Status::BadInput,
        Err(_) => {
            c.failed = true;
            Status::Invalid
        }
    }
}

/// See `rigtwin_mpc.h`.
///
/// # Safety
/// `controller` is NULL or live; the arrays are NULL or hold 3 doubles each.
#[no_mangle]
pub unsafe extern "C" fn rigtwin_mpc_step(
    controller: *mut RigtwinMpc,
    measured: *const f64,
    reference: *const f64,
    torques: *mut f64,
) -> Status {
    if measured.is_null() || reference.is_null() || torques.is_null() {
        return Status::Invalid;
    }
    // SAFETY: by the contract, NULL or a live controller
    let Some(c) = (unsafe { controller.as_mut() }) else { return Status::Invalid };
    // SAFETY: non-NULL and, by the contract, 3 doubles each
    let (m, r, t) = unsafe {
        (&*(measured as *const [f64; 3]), &*(reference as *const [f64; 3]), &mut *(torques as *mut [f64; 3]))
    };
    match catch_unwind(AssertUnwindSafe(|| c.step(m, r, t))) {
        Ok(s) => s,
        Err(_) => {
            c.failed = true;
            *t = c.last;
            Status::Invalid
        }
    }
}

/// See `rigtwin_mpc.h`.
///
/// # Safety
/// `controller` is NULL or from `rigtwin_mpc_create` and not yet freed.
#[no_mangle]
pub unsafe extern "C" fn rigtwin_mpc_free(controller: *mut RigtwinMpc) {
    if !controller.is_null() {
        // SAFETY: by the contract, from Box::into_raw and freed once
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(controller) })));
    }
}
