//! The C types of the FMI 2.0 and FMI 3.0 headers, generated once by `scripts/fmi_bindings.sh`
//! (bindgen) and checked in, so that building the FMU needs no libclang.
#![allow(non_upper_case_globals, non_camel_case_types, non_snake_case, dead_code, missing_docs, clippy::all)]

pub mod fmi2;
pub mod fmi3;
