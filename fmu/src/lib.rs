//! # fmu — the rigtwin FMU
//!
//! One shared library that exports the open-differential powertrain (Hübner & Prokop, section
//! 2.4) and the bearing K/C/M block on its support (San Andrés 2011) through FMI 3.0 and FMI 2.0,
//! co-simulation and model exchange. The parts, after the Reference FMUs:
//!
//! - [`params`]: the parameter set an FMU is built from;
//! - [`variables`]: the one variable table — both modelDescription.xml files ([`description`]),
//!   the value-reference map and the instantiation token come from it;
//! - [`controller`]: rigtwin's MPC as a co-simulation FMU;
//! - [`model`]: the paper rig's dynamics with its co-simulation step (a drive model's is
//!   `plant::Stepper`; both take the exact zero-order-hold steps of `plant::zoh_step`);
//! - [`instance`]: the state machine every call goes through, version-independent;
//! - [`fmi3`], [`fmi2`]: thin `extern "C"` glue, the exported C API. Every body runs under `catch_unwind`, so no panic
//!   crosses into the importer; every signature is checked at compile time against the
//!   standard's headers (bindings generated once by `scripts/fmi_bindings.sh`; a test checks
//!   them against fmi-sys). There is no global mutable state: instances run in parallel.
#![warn(missing_docs)]

#[doc(hidden)]
pub mod bindings;
pub mod controller;
pub mod description;
mod ffi;
pub mod fmi2;
pub mod fmi3;
pub mod instance;
pub mod model;
pub mod params;
pub mod variables;

pub use description::{describe, token, Version, MODEL_IDENTIFIER};
pub use params::{ControllerSpec, FmuParams, Plant, RigPlant};

use std::path::{Path, PathBuf};

/// Name of the parameter file in the FMU's resources folder.
pub const PARAMS_RESOURCE: &str = "params.json";

/// Checks that a parameter set describes a model an FMU can run (the rig's or a drive
/// model's); the error names what is wrong.
pub fn check(p: &FmuParams) -> Result<(), String> {
    if p.controller.is_some() {
        return controller::ControllerMachine::new(p).map(|_| ());
    }
    model::Model::new(&p.plant).map(|_| ())
}

/// The variable table of parameter set `p`: the controller FMU's (its ports, generated from the
/// model and its `[mpc]` section), or the plant's (the paper rig's or a drive model's).
pub fn table(p: &FmuParams) -> variables::Table {
    match &p.controller {
        Some(spec) => variables::Table::of_ports(&spec.ports(p).unwrap_or_default()),
        None => variables::Table::of_plant(&p.plant),
    }
}

/// The parameter set an instance starts from: `params.json` in the resources folder if it
/// is there, else the built-in default.
pub(crate) fn load_params(resources: Option<&Path>) -> Result<FmuParams, String> {
    let Some(dir) = resources else { return Ok(FmuParams::default()) };
    let file = dir.join(PARAMS_RESOURCE);
    if !file.exists() {
        return Ok(FmuParams::default());
    }
    let text = std::fs::read_to_string(&file).map_err(|e| format!("{}: {e}", file.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", file.display()))
}

/// The parameter set of an instance, if `given` is its token (`what` names the token in the
/// message: "GUID" in FMI 2, "instantiation token" in FMI 3).
pub(crate) fn checked_params(resources: Option<&Path>, given: &str, what: &str) -> Result<FmuParams, String> {
    let params = load_params(resources).map_err(|e| format!("cannot read the parameters: {e}"))?;
    let expected = token(&params);
    if given != expected {
        return Err(format!("{what} {given} does not match this FMU's {expected}"));
    }
    Ok(params)
}

/// FMI 2's resource location is a URI (`file:///path` or `file:/path`); the local path of it.
pub(crate) fn path_of_uri(uri: &str) -> Option<PathBuf> {
    let rest = uri.strip_prefix("file://").or_else(|| uri.strip_prefix("file:"))?;
    // "file://host/path": only the local host (empty or "localhost") is a local file
    let rest = rest.strip_prefix("localhost").unwrap_or(rest);
    let mut out = Vec::with_capacity(rest.len());
    let b = rest.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let Ok(v) = u8::from_str_radix(std::str::from_utf8(&b[i + 1..i + 3]).ok()?, 16) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    Some(PathBuf::from(String::from_utf8(out).ok()?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resource_uris() {
        assert_eq!(path_of_uri("file:///tmp/a%20b/resources"), Some(PathBuf::from("/tmp/a b/resources")));
        assert_eq!(path_of_uri("file:/tmp/x"), Some(PathBuf::from("/tmp/x")));
        assert_eq!(path_of_uri("file://localhost/tmp/x"), Some(PathBuf::from("/tmp/x")));
        assert_eq!(path_of_uri("http://example/x"), None);
    }
}
