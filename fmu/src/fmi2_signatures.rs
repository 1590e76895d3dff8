// Every export has the signature of the standard's header: the function types of
// fmi2Functions.h (`crate::bindings::fmi2` in the crate; fmi-sys' own bindgen output in
// `tests/signatures.rs`, which includes this file too). The two functions that take the
// header's structs are checked in fmi2.rs; the test compares the structs' layouts.
const _: () = {
    let _: fmi2GetTypesPlatformTYPE = Some(fmi2GetTypesPlatform);
    let _: fmi2GetVersionTYPE = Some(fmi2GetVersion);
    let _: fmi2SetDebugLoggingTYPE = Some(fmi2SetDebugLogging);
    let _: fmi2FreeInstanceTYPE = Some(fmi2FreeInstance);
    let _: fmi2SetupExperimentTYPE = Some(fmi2SetupExperiment);
    let _: fmi2EnterInitializationModeTYPE = Some(fmi2EnterInitializationMode);
    let _: fmi2ExitInitializationModeTYPE = Some(fmi2ExitInitializationMode);
    let _: fmi2TerminateTYPE = Some(fmi2Terminate);
    let _: fmi2ResetTYPE = Some(fmi2Reset);
    let _: fmi2GetRealTYPE = Some(fmi2GetReal);
    let _: fmi2GetIntegerTYPE = Some(fmi2GetInteger);
    let _: fmi2GetBooleanTYPE = Some(fmi2GetBoolean);
    let _: fmi2GetStringTYPE = Some(fmi2GetString);
    let _: fmi2SetRealTYPE = Some(fmi2SetReal);
    let _: fmi2SetIntegerTYPE = Some(fmi2SetInteger);
    let _: fmi2SetBooleanTYPE = Some(fmi2SetBoolean);
    let _: fmi2SetStringTYPE = Some(fmi2SetString);
    let _: fmi2GetFMUstateTYPE = Some(fmi2GetFMUstate);
    let _: fmi2SetFMUstateTYPE = Some(fmi2SetFMUstate);
    let _: fmi2FreeFMUstateTYPE = Some(fmi2FreeFMUstate);
    let _: fmi2SerializedFMUstateSizeTYPE = Some(fmi2SerializedFMUstateSize);
    let _: fmi2SerializeFMUstateTYPE = Some(fmi2SerializeFMUstate);
    let _: fmi2DeSerializeFMUstateTYPE = Some(fmi2DeSerializeFMUstate);
    let _: fmi2GetDirectionalDerivativeTYPE = Some(fmi2GetDirectionalDerivative);
    let _: fmi2EnterEventModeTYPE = Some(fmi2EnterEventMode);
    let _: fmi2EnterContinuousTimeModeTYPE = Some(fmi2EnterContinuousTimeMode);
    let _: fmi2CompletedIntegratorStepTYPE = Some(fmi2CompletedIntegratorStep);
    let _: fmi2SetTimeTYPE = Some(fmi2SetTime);
    let _: fmi2SetContinuousStatesTYPE = Some(fmi2SetContinuousStates);
    let _: fmi2GetDerivativesTYPE = Some(fmi2GetDerivatives);
    let _: fmi2GetEventIndicatorsTYPE = Some(fmi2GetEventIndicators);
    let _: fmi2GetContinuousStatesTYPE = Some(fmi2GetContinuousStates);
    let _: fmi2GetNominalsOfContinuousStatesTYPE = Some(fmi2GetNominalsOfContinuousStates);
    let _: fmi2SetRealInputDerivativesTYPE = Some(fmi2SetRealInputDerivatives);
    let _: fmi2GetRealOutputDerivativesTYPE = Some(fmi2GetRealOutputDerivatives);
    let _: fmi2DoStepTYPE = Some(fmi2DoStep);
    let _: fmi2CancelStepTYPE = Some(fmi2CancelStep);
    let _: fmi2GetStatusTYPE = Some(fmi2GetStatus);
    let _: fmi2GetRealStatusTYPE = Some(fmi2GetRealStatus);
    let _: fmi2GetIntegerStatusTYPE = Some(fmi2GetIntegerStatus);
    let _: fmi2GetBooleanStatusTYPE = Some(fmi2GetBooleanStatus);
    let _: fmi2GetStringStatusTYPE = Some(fmi2GetStringStatus);
};
