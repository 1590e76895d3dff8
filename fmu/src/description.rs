//! modelDescription.xml for FMI 3.0 and FMI 2.0, generated from the variable table, and the
//! instantiation token (GUID) — a hash of everything else in the description, so it changes
//! whenever a variable, a unit or a start value does.

use std::fmt::Write as _;

use crate::params::{FmuParams, Plant, RigPlant};
use crate::variables::{parameter_values, variant_number, Causality, Constraint, Kind, Slot, Variable};

/// The model identifier: the shared library's name inside the FMU.
pub const MODEL_IDENTIFIER: &str = "rigtwin";

/// Units used by the table: (name, SI base-unit exponents kg, m, s, rad, the FMI 3 type and
/// quantity that carries it).
const UNITS: [(&str, [i32; 4], &str); 22] = [
    ("s", [0, 0, 1, 0], "Time"),
    ("rad", [0, 0, 0, 1], "Angle"),
    ("rad/s", [0, 0, -1, 1], "AngularVelocity"),
    ("rad/s2", [0, 0, -2, 1], "AngularAcceleration"),
    ("kg.m2", [1, 2, 0, 0], "MomentOfInertia"),
    ("N.m/rad", [1, 2, -2, -1], "TorsionalStiffness"),
    ("N.m.s/rad", [1, 2, -1, -1], "TorsionalDamping"),
    ("N.m", [1, 2, -2, 0], "Torque"),
    ("N", [1, 1, -2, 0], "Force"),
    ("N/m", [1, 0, -2, 0], "Stiffness"),
    ("N.s/m", [1, 0, -1, 0], "Damping"),
    ("kg", [1, 0, 0, 0], "Mass"),
    ("m", [0, 1, 0, 0], "Length"),
    ("m/s", [0, 1, -1, 0], "Velocity"),
    ("m/s2", [0, 1, -2, 0], "Acceleration"),
    ("N.m/s", [1, 2, -3, 0], "TorqueRate"),
    ("N/s", [1, 1, -3, 0], "ForceRate"),
    ("1", [0, 0, 0, 0], "Ratio"),
    // the controller's weights: cost per squared error
    ("s2/rad2", [0, 0, 2, -2], "SpeedErrorWeight"),
    ("1/(N.m)2", [-2, -4, 4, 0], "TorqueErrorWeight"),
    ("s2/m2", [0, -2, 2, 0], "VelocityErrorWeight"),
    ("1/N2", [-2, -2, 4, 0], "ForceErrorWeight"),
];

/// The FMI 3 type declaring a unit.
fn type_of_unit(unit: &str) -> &'static str {
    UNITS.iter().find(|u| u.0 == unit).map(|u| u.2).expect("every unit of the table is declared")
}

/// The FMI 3 type of a state's unit with a nominal other than 1, e.g. `Angle_nominal_1e-3`.
fn nominal_type(unit: &str, nominal: f64) -> String {
    format!("{}_nominal_{nominal:e}", type_of_unit(unit))
}

fn base_unit(e: &[i32; 4]) -> String {
    let mut s = String::from("<BaseUnit");
    for (name, v) in ["kg", "m", "s", "rad"].iter().zip(e) {
        if *v != 0 {
            let _ = write!(s, " {name}=\"{v}\"");
        }
    }
    s + "/>"
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// Start values of the variables that have one, by value reference.
fn start(p: &FmuParams, values: &[f64], slot: Slot) -> Option<String> {
    match slot {
        Slot::Param(i) => Some(format!("{:?}", values[i])),
        Slot::Variant => p.plant.rig().map(|r| variant_number(r.variant).to_string()),
        Slot::State(_) | Slot::Input(_) => Some("0.0".into()),
        _ => None,
    }
}

/// The rig FMU's description and whether it needs CompletedIntegratorStep (a dead time's
/// history is pruned there): the paper rig's model as its preset builds it
/// (`plant::DriveModel::paper_rig`), described as any model's effects and step are.
fn rig_description(p: &RigPlant) -> (String, bool) {
    let mut desc = String::from("Open-differential powertrain of a HIL test rig (Hübner & Prokop, Vehicles 2026)");
    if p.bearing.is_some() {
        desc += " and a bearing K/C/M block on its support (San Andrés 2011)";
    }
    match p.drive_model() {
        Ok(m) => {
            if m.line.bodies.len() > 3 {
                // a drive compliance splits the drive into its cage and motor
                let names: Vec<&str> = m.line.bodies.iter().map(|b| b.name.as_str()).collect();
                let _ = write!(desc, "; bodies {}", names.join(", "));
            }
            desc += &effects_and_step(&m);
            (desc, has_dead_time(&m))
        }
        // not a valid rig (refused where the FMU is built): its effects as they are written
        Err(_) => (desc, p.effects.time_delay_s > 0.0),
    }
}

/// A drive model's description: its bodies, gear stages and effects, and the co-simulation
/// step it takes.
fn drive_description(m: &plant::DriveModel) -> (String, bool) {
    let names: Vec<&str> = m.line.bodies.iter().map(|b| b.name.as_str()).collect();
    let gears = m.line.couplings.iter().filter(|c| c.ratio != 1.0).count();
    let domain = match m.line.domain {
        plant::Domain::Rotational => "rotational",
        plant::Domain::Translational => "translational",
    };
    let mut desc = format!("Drivetrain ({domain}): {} in line", names.join(", "));
    if gears > 0 {
        let _ = write!(desc, ", {gears} gear stage(s)");
    }
    desc += &effects_and_step(m);
    (desc, has_dead_time(m))
}

/// "; with" a model's effects ([`plant::Effect::summary`]), and the co-simulation step it takes
/// (`plant::Stepper`, as rigtwin's diagnosis simulates: [`plant::Dynamics::exact_steps`] where
/// it has them, RK4 sub-steps elsewhere).
fn effects_and_step(m: &plant::DriveModel) -> String {
    let mut words = String::new();
    let effects: Vec<String> = m.effects.iter().map(|e| e.summary(m)).collect();
    if !effects.is_empty() {
        let _ = write!(words, "; with {}", effects.join(", "));
    }
    words += if m.is_nonlinear() {
        "; co-simulation step as rigtwin's diagnosis simulates: whole steps by matrix exponentials where a play is \
         the only nonlinearity or every body with friction slides, RK4 sub-steps of h |lambda|max <= 0.5 elsewhere"
    } else if effects.is_empty() {
        "; linear, exact zero-order-hold co-simulation step"
    } else {
        "; exact zero-order-hold co-simulation step"
    };
    words
}

/// Whether a model has a dead time (its history is pruned at CompletedIntegratorStep).
fn has_dead_time(m: &plant::DriveModel) -> bool {
    m.effects.iter().any(|e| matches!(e, plant::Effect::TimeDelay(_)))
}

/// The controller FMU's communication step (its control period), s.
pub const CONTROL_PERIOD_S: f64 = 1e-3;

/// The controller FMU's description: what it controls and with which prediction model.
fn controller_description(p: &FmuParams, c: &crate::params::ControllerSpec) -> String {
    if let Plant::Drive(m) = &p.plant {
        let ports = match c.ports(p) {
            Ok(ports) => ports,
            Err(e) => return format!("rigtwin's model-predictive controller of a drive model (not valid: {e})"),
        };
        let names =
            |list: &[crate::variables::Port]| list.iter().map(|q| q.name.as_ref()).collect::<Vec<_>>().join(", ");
        let mut d = format!(
            "rigtwin's model-predictive controller of a drive model of {} bodies (Clarabel QP, horizon {} steps of {} s, Kalman filter with input disturbances): it measures {}, follows {}, commands {}",
            m.line.bodies.len(),
            c.horizon,
            CONTROL_PERIOD_S,
            names(&ports.inputs[..ports.measured]),
            names(&ports.inputs[ports.measured..]),
            names(&ports.outputs),
        );
        if let Ok(pred) = mpc::prediction::drive_prediction(m, CONTROL_PERIOD_S) {
            for note in pred.notes {
                let _ = write!(d, "; {note}");
            }
        }
        return d;
    }
    let mut d = format!(
        "rigtwin's model-predictive controller of the open-differential HIL rig (Clarabel QP, horizon {} steps of {} s, Kalman filter with input disturbances): the load machines hold their speed references, the drive follows its torque reference, the side-shaft oscillation is penalised",
        c.horizon, CONTROL_PERIOD_S
    );
    if let Ok(pred) = p.plant.design().prediction(CONTROL_PERIOD_S) {
        for note in pred.notes {
            let _ = write!(d, "; {note}");
        }
    }
    d
}

/// Which FMI version to describe.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Version {
    /// FMI 3.0.
    Fmi3,
    /// FMI 2.0.
    Fmi2,
}

/// The token of a parameter set: 128 bits of two FNV-1a hashes over the description written
/// with a placeholder token, formatted as a GUID.
pub fn token(p: &FmuParams) -> String {
    let body = format!("{}{}", describe_with(p, Version::Fmi3, "TOKEN"), describe_with(p, Version::Fmi2, "TOKEN"));
    let fnv = |seed: u64| body.bytes().fold(seed, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3));
    let (a, b) = (fnv(0xcbf2_9ce4_8422_2325), fnv(0x8422_2325_cbf2_9ce4));
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}

/// The modelDescription.xml of `version` for a parameter set.
pub fn describe(p: &FmuParams, version: Version) -> String {
    describe_with(p, version, &token(p))
}

/// The FMU's `modelName`, which importers show: what the FMU is, so that a plant, a drive line
/// and a controller side by side in a tool are told apart.
pub fn model_name(p: &FmuParams) -> String {
    match (&p.plant, &p.controller) {
        (_, Some(_)) => "rigtwin MPC controller".into(),
        (Plant::PaperRig(_), None) => "rigtwin open-differential rig".into(),
        (Plant::Drive(m), None) => {
            let kind = match m.line.domain {
                plant::Domain::Rotational => "drive line",
                plant::Domain::Translational => "linear axis",
            };
            format!("rigtwin {kind} ({} bodies)", m.line.bodies.len())
        }
    }
}

fn describe_with(p: &FmuParams, version: Version, token: &str) -> String {
    let table = crate::table(p);
    let vars = &table.variables;
    let params = parameter_values(p);
    let mut x = String::new();
    let controller = p.controller.is_some();
    let (desc, needs_completed) = match (&p.plant, &p.controller) {
        (_, Some(c)) => (controller_description(p, c), false),
        (Plant::PaperRig(r), None) => rig_description(r),
        (Plant::Drive(m), None) => drive_description(m),
    };
    let _ = writeln!(x, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>");
    match version {
        Version::Fmi3 => {
            let _ = writeln!(
                x,
                "<fmiModelDescription fmiVersion=\"3.0\" modelName=\"{}\" description=\"{}\" generationTool=\"rigtwin {}\" instantiationToken=\"{token}\" variableNamingConvention=\"structured\">",
                xml_escape(&model_name(p)),
                xml_escape(&desc),
                env!("CARGO_PKG_VERSION")
            );
            if controller {
                let _ = writeln!(x, "  <CoSimulation modelIdentifier=\"{MODEL_IDENTIFIER}\" canHandleVariableCommunicationStepSize=\"false\" fixedInternalStepSize=\"{CONTROL_PERIOD_S:?}\" canGetAndSetFMUState=\"true\" canSerializeFMUState=\"true\" hasEventMode=\"false\"/>");
            } else {
                let _ = writeln!(x, "  <ModelExchange modelIdentifier=\"{MODEL_IDENTIFIER}\" canGetAndSetFMUState=\"true\" canSerializeFMUState=\"true\" providesDirectionalDerivatives=\"true\" needsCompletedIntegratorStep=\"{needs_completed}\"/>");
                let _ = writeln!(x, "  <CoSimulation modelIdentifier=\"{MODEL_IDENTIFIER}\" canHandleVariableCommunicationStepSize=\"true\" canGetAndSetFMUState=\"true\" canSerializeFMUState=\"true\" providesDirectionalDerivatives=\"true\" hasEventMode=\"false\"/>");
            }
        }
        Version::Fmi2 => {
            let _ = writeln!(
                x,
                "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"{}\" guid=\"{token}\" description=\"{}\" generationTool=\"rigtwin {}\" variableNamingConvention=\"structured\" numberOfEventIndicators=\"0\">",
                xml_escape(&model_name(p)),
                xml_escape(&desc),
                env!("CARGO_PKG_VERSION")
            );
            if controller {
                let _ = writeln!(x, "  <CoSimulation modelIdentifier=\"{MODEL_IDENTIFIER}\" canHandleVariableCommunicationStepSize=\"false\" canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\"/>");
            } else {
                let _ = writeln!(x, "  <ModelExchange modelIdentifier=\"{MODEL_IDENTIFIER}\" canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\" providesDirectionalDerivative=\"true\" completedIntegratorStepNotNeeded=\"{}\"/>", !needs_completed);
                let _ = writeln!(x, "  <CoSimulation modelIdentifier=\"{MODEL_IDENTIFIER}\" canHandleVariableCommunicationStepSize=\"true\" canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\" providesDirectionalDerivative=\"true\"/>");
            }
        }
    }
    let _ = writeln!(x, "  <UnitDefinitions>");
    // only the units the table uses (a translational drive declares no angles)
    let used = |unit: &str| vars.iter().any(|v| v.unit == unit);
    for (name, e, _) in UNITS.into_iter().filter(|u| used(u.0)) {
        let _ = writeln!(x, "    <Unit name=\"{name}\">{}</Unit>", base_unit(&e));
    }
    let _ = writeln!(x, "  </UnitDefinitions>");
    if version == Version::Fmi3 {
        // FMI 3 carries units through declared types (as the Reference FMUs do)
        let _ = writeln!(x, "  <TypeDefinitions>");
        for (unit, _, name) in UNITS.into_iter().filter(|u| used(u.0)) {
            let _ = writeln!(x, "    <Float64Type name=\"{name}\" quantity=\"{name}\" unit=\"{unit}\"/>");
        }
        // the states' nominals through types of their own (rust-fmi 0.8 reads `nominal` on a
        // type, not on a variable)
        let mut nominal_types: Vec<(&str, f64)> = Vec::new();
        for (s, n) in table.nominals().enumerate() {
            let unit = vars.iter().find(|v| v.slot == Slot::State(s)).expect("state in table").unit;
            if n != 1.0 && !nominal_types.contains(&(unit, n)) {
                nominal_types.push((unit, n));
            }
        }
        for (unit, n) in nominal_types {
            let quantity = type_of_unit(unit);
            let _ = writeln!(
                x,
                "    <Float64Type name=\"{}\" quantity=\"{quantity}\" unit=\"{unit}\" nominal=\"{n:?}\"/>",
                nominal_type(unit, n)
            );
        }
        let _ = writeln!(x, "  </TypeDefinitions>");
    }
    let _ = writeln!(x, "  <LogCategories>");
    for (c, d) in [("logStatusWarning", "warnings"), ("logStatusError", "errors"), ("logEvents", "instance events")] {
        let _ = writeln!(x, "    <Category name=\"{c}\" description=\"{d}\"/>");
    }
    let _ = writeln!(x, "  </LogCategories>");
    let _ = writeln!(x, "  <DefaultExperiment startTime=\"0\" stopTime=\"2\" stepSize=\"{CONTROL_PERIOD_S:?}\"/>");
    let _ = writeln!(x, "  <ModelVariables>");
    // FMI 2 refers to variables by their 1-based position; FMI 3 by value reference
    let derivative_of = |state: usize| table.derivative_state.iter().position(|d| *d == Some(state));
    let nominals: Vec<f64> = table.nominals().collect();
    // FMI 2 leaves the optional `time` out: older FMI Libraries (OSP libcosim's) ask an
    // independent variable for a start value, which the standard forbids
    let listed: Vec<&Variable> =
        vars.iter().filter(|v| version == Version::Fmi3 || v.causality != Causality::Independent).collect();
    for &v in &listed {
        let caus = match v.causality {
            Causality::Parameter => "parameter",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Local => "local",
            Causality::Independent => "independent",
        };
        let (variability, initial) = match (v.causality, v.slot) {
            (Causality::Parameter, _) if controller => ("tunable", Some("exact")),
            (Causality::Parameter, _) => ("fixed", Some("exact")),
            // the commands change at communication points only
            (_, Slot::Command(_)) => ("discrete", Some("calculated")),
            (Causality::Independent, _) => ("continuous", None),
            (Causality::Input, _) => ("continuous", None),
            (_, Slot::State(_)) => ("continuous", Some("exact")),
            _ => ("continuous", Some("calculated")),
        };
        // which state a variable is the derivative of
        let der = match v.slot {
            Slot::State(i) => derivative_of(i),
            Slot::Derivative(i) => Some(i),
            _ => None,
        };
        let start = start(p, &params, v.slot);
        let nominal = match v.slot {
            Slot::State(i) => Some(format!("{:?}", nominals[i])),
            _ => None,
        };
        let unit = if v.unit.is_empty() { String::new() } else { format!(" unit=\"{}\"", v.unit) };
        match version {
            Version::Fmi3 => {
                let tag = match v.kind {
                    Kind::Float64 => "Float64",
                    Kind::Int32 => "Int32",
                };
                let mut attrs = format!(
                    "name=\"{}\" valueReference=\"{}\" causality=\"{caus}\" variability=\"{}\" description=\"{}\"",
                    xml_escape(&v.name),
                    v.vr,
                    if v.kind == Kind::Int32 { "fixed" } else { variability },
                    xml_escape(&v.description)
                );
                if let Some(i) = initial {
                    let _ = write!(attrs, " initial=\"{i}\"");
                }
                if v.kind == Kind::Float64 {
                    let declared = match v.slot {
                        Slot::State(i) if nominals[i] != 1.0 => nominal_type(v.unit, nominals[i]),
                        _ => type_of_unit(v.unit).to_string(),
                    };
                    let _ = write!(attrs, " declaredType=\"{declared}\"");
                    if v.constraint == Constraint::Fraction {
                        attrs += " min=\"0\" max=\"1\"";
                    }
                } else {
                    attrs += " min=\"1\" max=\"4\"";
                }
                if let Some(d) = der {
                    let vr = table.find(Slot::State(d)).expect("state in table").vr;
                    let _ = write!(attrs, " derivative=\"{vr}\"");
                }
                if let Some(s) = &start {
                    let _ = write!(attrs, " start=\"{s}\"");
                }
                let _ = writeln!(x, "    <{tag} {attrs}/>");
            }
            Version::Fmi2 => {
                let mut attrs = format!(
                    "name=\"{}\" valueReference=\"{}\" causality=\"{caus}\" variability=\"{}\" description=\"{}\"",
                    xml_escape(&v.name),
                    v.vr,
                    variability,
                    xml_escape(&v.description)
                );
                if let Some(i) = initial {
                    let _ = write!(attrs, " initial=\"{i}\"");
                }
                let mut inner = match v.kind {
                    Kind::Float64 => format!("<Real{unit}"),
                    Kind::Int32 => "<Integer min=\"1\" max=\"4\"".into(),
                };
                if let Some(d) = der {
                    // 1-based position of the state in ModelVariables
                    let pos = listed.iter().position(|w| w.slot == Slot::State(d)).expect("state in table") + 1;
                    let _ = write!(inner, " derivative=\"{pos}\"");
                }
                if let Some(s) = &start {
                    let _ = write!(inner, " start=\"{s}\"");
                }
                if let Some(n) = &nominal {
                    let _ = write!(inner, " nominal=\"{n}\"");
                }
                let _ = writeln!(x, "    <ScalarVariable {attrs}>{inner}/></ScalarVariable>");
            }
        }
    }
    let _ = writeln!(x, "  </ModelVariables>");
    let _ = writeln!(x, "  <ModelStructure>");
    let vars = &listed;
    let outputs: Vec<usize> = (0..vars.len()).filter(|&i| vars[i].causality == Causality::Output).collect();
    // one derivative per state, in the state vector's order: that order defines the
    // continuous-state vector of GetContinuousStates and friends in both standards
    let derivatives: Vec<usize> = (0..table.nx())
        .map(|s| {
            let slot = match table.derivative_state[s] {
                Some(d) => Slot::State(d),
                None => Slot::Derivative(s),
            };
            vars.iter().position(|v| v.slot == slot).expect("every state has a derivative variable")
        })
        .collect();
    let initial_unknowns: Vec<usize> = (0..vars.len())
        .filter(|&i| matches!(vars[i].slot, Slot::Derivative(_) | Slot::Torque(_) | Slot::Angle(_) | Slot::Command(_)))
        .collect();
    // the controller's commands depend directly on every input; the other models' outputs are
    // left to the standard's default (they may depend on all knowns)
    let inputs: Vec<usize> = (0..vars.len()).filter(|&i| vars[i].causality == Causality::Input).collect();
    let depends = |i: usize, version: Version| -> String {
        if !matches!(vars[i].slot, Slot::Command(_)) {
            return String::new();
        }
        let list: Vec<String> = inputs
            .iter()
            .map(|&j| match version {
                Version::Fmi3 => vars[j].vr.to_string(),
                Version::Fmi2 => (j + 1).to_string(),
            })
            .collect();
        format!(" dependencies=\"{}\"", list.join(" "))
    };
    match version {
        Version::Fmi3 => {
            for &i in &outputs {
                let _ = writeln!(x, "    <Output valueReference=\"{}\"{}/>", vars[i].vr, depends(i, version));
            }
            for &i in &derivatives {
                let _ = writeln!(x, "    <ContinuousStateDerivative valueReference=\"{}\"/>", vars[i].vr);
            }
            for &i in &initial_unknowns {
                let _ = writeln!(x, "    <InitialUnknown valueReference=\"{}\"{}/>", vars[i].vr, depends(i, version));
            }
        }
        Version::Fmi2 => {
            let _ = writeln!(x, "    <Outputs>");
            for &i in &outputs {
                let _ = writeln!(x, "      <Unknown index=\"{}\"{}/>", i + 1, depends(i, version));
            }
            let _ = writeln!(x, "    </Outputs>");
            // the schema refuses an empty list (the controller has no states)
            if !derivatives.is_empty() {
                let _ = writeln!(x, "    <Derivatives>");
                for &i in &derivatives {
                    let _ = writeln!(x, "      <Unknown index=\"{}\"/>", i + 1);
                }
                let _ = writeln!(x, "    </Derivatives>");
            }
            let _ = writeln!(x, "    <InitialUnknowns>");
            for &i in &initial_unknowns {
                let _ = writeln!(x, "      <Unknown index=\"{}\"{}/>", i + 1, depends(i, version));
            }
            let _ = writeln!(x, "    </InitialUnknowns>");
        }
    }
    let _ = writeln!(x, "  </ModelStructure>");
    let _ = writeln!(x, "</fmiModelDescription>");
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rig's description names its preset model's effects where they act, with their
    /// sizes, and its bodies where a compliance split the drive; the default rig's is the
    /// linear one.
    #[test]
    fn the_rig_is_described_by_its_preset_model() {
        let (plain, _) = rig_description(&RigPlant::default());
        assert!(plain.ends_with("; linear, exact zero-order-hold co-simulation step"), "{plain}");
        let mut p = RigPlant::default();
        p.effects.time_delay_s = 0.002;
        p.effects.compliance_stiffness_nm_per_rad = 2000.0;
        p.effects.coulomb_friction_nm = [0.0, 0.0, 1.1];
        let (desc, delayed) = rig_description(&p);
        assert!(delayed, "{desc}");
        for part in [
            "; bodies m2, drive, m3, motor",
            "time_delay at input 2 (delay_s = 0.002)",
            "coulomb_friction at body m3 (friction_Nm = 1.1",
            "RK4 sub-steps",
        ] {
            assert!(desc.contains(part), "{part}: {desc}");
        }
    }

    #[test]
    fn token_follows_the_start_values() {
        let a = FmuParams::default();
        let mut r = RigPlant::default();
        r.powertrain.j_drive *= 1.5;
        let b = FmuParams::of_rig(r);
        assert_ne!(token(&a), token(&b));
        assert_eq!(token(&a), token(&a.clone()));
        assert!(describe(&a, Version::Fmi3).contains(&token(&a)));
        assert!(describe(&a, Version::Fmi2).contains(&token(&a)));
    }
}
