//! Every exported FMI function has the signature of the standard's headers as fmi-sys generates
//! them with bindgen: the same checks the crate compiles against its checked-in bindings
//! (`src/bindings`, `scripts/fmi_bindings.sh`), here against fmi-sys. A mismatch fails to compile.
#![allow(non_snake_case, clippy::missing_safety_doc)]

mod fmi3 {
    use fmi_sys::fmi3::*;
    use rigtwin_fmu::fmi3::*;
    include!("../src/fmi3_signatures.rs");
}

mod fmi2 {
    use fmi_sys::fmi2::*;
    use rigtwin_fmu::fmi2::*;
    include!("../src/fmi2_signatures.rs");
}

/// The structs the FMI 2 glue takes (fmi2Instantiate, fmi2NewDiscreteStates) have fmi-sys'
/// layout, field by field.
#[test]
fn structs_match_fmi_sys() {
    use rigtwin_fmu::bindings::fmi2 as ours;
    use std::mem::{align_of, offset_of, size_of};
    macro_rules! same_layout {
        ($t:ident: $($f:ident),*) => {
            assert_eq!(size_of::<ours::$t>(), size_of::<fmi_sys::fmi2::$t>(), stringify!($t));
            assert_eq!(align_of::<ours::$t>(), align_of::<fmi_sys::fmi2::$t>(), stringify!($t));
            $(assert_eq!(offset_of!(ours::$t, $f), offset_of!(fmi_sys::fmi2::$t, $f), stringify!($t.$f));)*
        };
    }
    same_layout!(fmi2CallbackFunctions: logger, allocateMemory, freeMemory, stepFinished, componentEnvironment);
    same_layout!(fmi2EventInfo: newDiscreteStatesNeeded, terminateSimulation, nominalsOfContinuousStatesChanged,
        valuesOfContinuousStatesChanged, nextEventTimeDefined, nextEventTime);
}

/// The checked-in bindings' status codes and boolean values are fmi-sys' (the glue returns them
/// by value, so a renumbered enum would not show in a signature).
#[test]
fn status_codes_match_fmi_sys() {
    use rigtwin_fmu::bindings::{fmi2 as ours2, fmi3 as ours3};
    assert_eq!(
        [
            ours3::fmi3Status_fmi3OK,
            ours3::fmi3Status_fmi3Warning,
            ours3::fmi3Status_fmi3Discard,
            ours3::fmi3Status_fmi3Error,
            ours3::fmi3Status_fmi3Fatal
        ],
        [
            fmi_sys::fmi3::fmi3Status_fmi3OK,
            fmi_sys::fmi3::fmi3Status_fmi3Warning,
            fmi_sys::fmi3::fmi3Status_fmi3Discard,
            fmi_sys::fmi3::fmi3Status_fmi3Error,
            fmi_sys::fmi3::fmi3Status_fmi3Fatal
        ]
    );
    assert_eq!(
        [
            ours2::fmi2Status_fmi2OK,
            ours2::fmi2Status_fmi2Warning,
            ours2::fmi2Status_fmi2Discard,
            ours2::fmi2Status_fmi2Error,
            ours2::fmi2Status_fmi2Fatal,
            ours2::fmi2Status_fmi2Pending
        ],
        [
            fmi_sys::fmi2::fmi2Status_fmi2OK,
            fmi_sys::fmi2::fmi2Status_fmi2Warning,
            fmi_sys::fmi2::fmi2Status_fmi2Discard,
            fmi_sys::fmi2::fmi2Status_fmi2Error,
            fmi_sys::fmi2::fmi2Status_fmi2Fatal,
            fmi_sys::fmi2::fmi2Status_fmi2Pending
        ]
    );
    assert_eq!((ours2::fmi2True, ours2::fmi2False), (fmi_sys::fmi2::fmi2True, fmi_sys::fmi2::fmi2False));
}
