//! # rigtwin-mpc — rigtwin's MPC behind a C API (`include/rigtwin_mpc.h`)
//!
//! A static and a shared library for C code on real-time targets (and Simulink S-functions,
//! NI VeriStand custom devices, …): create a controller from a model file (the paper rig's
//! file, a drive model, a `drive_test` bundle; its `[mpc]` section), ask for its signals, reset
//! it at an operating point, step it every sample with the measurements and the references,
//! free it. The controller is `rigtwin mpc`'s (`mpc::Design::controller`, `mpc::RealTime`, the
//! same core as the controller FMU's); this crate only guards the boundary: no panic crosses it
//! (`catch_unwind` everywhere), wrong pointers are refused, the core refuses non-finite inputs
//! and never returns a non-finite command, `step` allocates nothing here. It depends on `mpc`
//! and `modelfile` (which reads the model file) and what they need, nothing more.

use std::ffi::{c_char, c_int, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use modelfile::{Model, ModelFile};
use mpc::{MpcSection, MpcSettings, RealTime};

pub use mpc::Status;

/// `rigtwin_mpc_signals`: which of a controller's signal lists.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Signals {
    /// `measured[]`: the plant outputs the controller reads.
    Measured = 0,
    /// `reference[]`: the tracked outputs, then the tracked inputs.
    References = 1,
    /// `commands[]`: the plant's inputs.
    Commands = 2,
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
    /// The horizon, checked.
    fn horizon(&self) -> anyhow::Result<usize> {
        usize::try_from(self.horizon)
            .ok()
            .filter(|h| (1..=mpc::MAX_HORIZON).contains(h))
            .ok_or_else(|| anyhow::anyhow!("horizon {}: expected 1..={}", self.horizon, mpc::MAX_HORIZON))
    }

    /// Applies the move blocks and the time limit to `s` and checks the result.
    fn apply(&self, s: &mut MpcSettings) -> anyhow::Result<()> {
        let blocks = usize::try_from(self.move_blocks)
            .map_err(|_| anyhow::anyhow!("move_blocks {}: expected 0 or more", self.move_blocks))?;
        s.move_blocks = if blocks == 0 { Vec::new() } else { mpc::exponential_blocks(s.horizon, blocks) };
        s.solver.time_limit_s = self.time_limit_s;
        s.validate()?;
        Ok(())
    }
}

/// The controller behind `rigtwin_mpc *`: the real-time core and its signals' names as C
/// strings.
pub struct RigtwinMpc {
    core: RealTime,
    names: [Vec<CString>; 3],
}

impl RigtwinMpc {
    /// The controller of the model `file` (its `[mpc]` section and `options`), at rest.
    pub fn new(file: &ModelFile, options: &Options) -> anyhow::Result<Self> {
        let (prediction, mut settings) = file.model.design().controller(&file.mpc, options.horizon()?)?;
        options.apply(&mut settings)?;
        let core = RealTime::new(&prediction, &settings)?;
        let c_names = |names: &[String]| -> anyhow::Result<Vec<CString>> {
            names
                .iter()
                .map(|n| CString::new(n.as_str()).map_err(|_| anyhow::anyhow!("signal `{n}` holds a NUL")))
                .collect()
        };
        let names = [c_names(core.measured_names())?, c_names(core.reference_names())?, c_names(core.command_names())?];
        Ok(RigtwinMpc { core, names })
    }

    /// The controller of the model file `path` (`None`: the embedded paper rig).
    pub fn from_file(path: Option<&Path>, options: &Options) -> anyhow::Result<Self> {
        let file = match path {
            None => {
                ModelFile { model: Model::Rig(Box::new(plant::paper::rig())), mpc: MpcSection::default(), kind: None }
            }
            Some(p) => modelfile::read(p)?,
        };
        Self::new(&file, options).map_err(|e| match path {
            Some(p) => anyhow::anyhow!("{}: {e}", p.display()),
            None => e,
        })
    }

    /// Number of entries in the list `which`.
    pub fn count(&self, which: Signals) -> usize {
        self.names[which as usize].len()
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
/// `model_path` is NULL or a NUL-terminated string; `options` NULL or valid; `error` NULL or
/// `error_len` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn rigtwin_mpc_create(
    model_path: *const c_char,
    options: *const Options,
    error: *mut c_char,
    error_len: usize,
) -> *mut RigtwinMpc {
    let made = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: by the contract, NULL or valid
        let options = if options.is_null() { Options::default() } else { unsafe { *options } };
        let path = if model_path.is_null() {
            None
        } else {
            // SAFETY: by the contract, a NUL-terminated string
            let s = unsafe { CStr::from_ptr(model_path) };
            Some(s.to_str().map_err(|_| anyhow::anyhow!("model_path is not UTF-8"))?.to_string())
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
pub unsafe extern "C" fn rigtwin_mpc_count(controller: *const RigtwinMpc, which: c_int) -> usize {
    // SAFETY: by the contract, NULL or a live controller
    let Some(c) = (unsafe { controller.as_ref() }) else { return 0 };
    signals(which).map_or(0, |w| c.count(w))
}

/// See `rigtwin_mpc.h`.
///
/// # Safety
/// `controller` is NULL or from `rigtwin_mpc_create` and not freed.
#[no_mangle]
pub unsafe extern "C" fn rigtwin_mpc_name(controller: *const RigtwinMpc, which: c_int, index: usize) -> *const c_char {
    // SAFETY: by the contract, NULL or a live controller
    let Some(c) = (unsafe { controller.as_ref() }) else { return std::ptr::null() };
    match signals(which).and_then(|w| c.names[w as usize].get(index)) {
        Some(name) => name.as_ptr(),
        None => std::ptr::null(),
    }
}

/// The list `which` names (`rigtwin_mpc_signals`), if any.
fn signals(which: c_int) -> Option<Signals> {
    match which {
        0 => Some(Signals::Measured),
        1 => Some(Signals::References),
        2 => Some(Signals::Commands),
        _ => None,
    }
}

/// See `rigtwin_mpc.h`.
///
/// # Safety
/// `controller` is NULL or from `rigtwin_mpc_create` and not freed.
#[no_mangle]
pub unsafe extern "C" fn rigtwin_mpc_reset(controller: *mut RigtwinMpc, speed: f64) -> Status {
    // SAFETY: by the contract, NULL or a live controller
    let Some(c) = (unsafe { controller.as_mut() }) else { return Status::Invalid };
    if !speed.is_finite() {
        return Status::BadInput;
    }
    match catch_unwind(AssertUnwindSafe(|| c.core.reset(speed))) {
        Ok(Ok(())) => Status::Ok,
        Ok(Err(_)) => Status::BadInput,
        Err(_) => {
            c.core.fail();
            Status::Invalid
        }
    }
}

/// See `rigtwin_mpc.h`.
///
/// # Safety
/// `controller` is NULL or live; the arrays are NULL or hold `rigtwin_mpc_count` doubles each.
#[no_mangle]
pub unsafe extern "C" fn rigtwin_mpc_step(
    controller: *mut RigtwinMpc,
    measured: *const f64,
    reference: *const f64,
    commands: *mut f64,
) -> Status {
    // SAFETY: by the contract, NULL or a live controller
    let Some(c) = (unsafe { controller.as_mut() }) else { return Status::Invalid };
    let (nm, nr, nc) = (c.count(Signals::Measured), c.count(Signals::References), c.count(Signals::Commands));
    // an empty list may come as NULL; a list with entries may not
    let null = |p: bool, n: usize| p && n > 0;
    if null(measured.is_null(), nm) || null(reference.is_null(), nr) || null(commands.is_null(), nc) {
        return Status::Invalid;
    }
    let slice = |p: *const f64, n: usize| -> &[f64] {
        if n == 0 {
            &[]
        } else {
            // SAFETY: non-NULL and, by the contract, n doubles
            unsafe { std::slice::from_raw_parts(p, n) }
        }
    };
    let (m, r) = (slice(measured, nm), slice(reference, nr));
    // SAFETY: non-NULL (nc > 0: every model has an input) and, by the contract, nc doubles
    let out = unsafe { std::slice::from_raw_parts_mut(commands, nc) };
    match catch_unwind(AssertUnwindSafe(|| c.core.step(m, r, out))) {
        Ok(s) => s,
        Err(_) => {
            c.core.fail();
            out.copy_from_slice(c.core.commands());
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
