//! The one variable table. Both modelDescription.xml files, the value-reference map of the
//! instances and the instantiation token are generated from it, so they cannot disagree.

use std::borrow::Cow;

use crate::params::FmuParams;
use plant::{Dimension, Domain, DriveModel};

/// Storage type of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// 64-bit float (FMI 2 Real).
    Float64,
    /// 32-bit integer (FMI 2 Integer).
    Int32,
}

/// FMI causality.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    /// Fixed parameter.
    Parameter,
    /// Input.
    Input,
    /// Output.
    Output,
    /// Local (derivatives).
    Local,
    /// Time.
    Independent,
}

/// Where a variable's value lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slot {
    /// Simulation time.
    Time,
    /// Float parameter `i` of [`PARAMETERS`].
    Param(usize),
    /// The variant, 1..=4 for V1..V4.
    Variant,
    /// Continuous state `i`.
    State(usize),
    /// Derivative of continuous state `i` (computed).
    Derivative(usize),
    /// Input `i`.
    Input(usize),
    /// Side-shaft torque `i` (computed).
    Torque(usize),
    /// Absolute angle `i` of [`ANGLES`] that is not a state (computed from the states).
    Angle(usize),
    /// Torque command `i` of the controller FMU (computed from the inputs).
    Command(usize),
}

/// What values a parameter accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Constraint {
    /// Any finite value.
    Finite,
    /// Finite and ≥ 0.
    NonNegative,
    /// Finite and > 0.
    Positive,
    /// Strictly between 0 and 1.
    Fraction,
}

impl Constraint {
    /// Whether `v` is accepted, and what is expected otherwise.
    pub fn check(self, v: f64) -> Result<(), &'static str> {
        let (ok, want) = match self {
            Constraint::Finite => (v.is_finite(), "a finite number"),
            Constraint::NonNegative => (v >= 0.0, ">= 0"),
            Constraint::Positive => (v > 0.0, "> 0"),
            Constraint::Fraction => (v > 0.0 && v < 1.0, "a value strictly between 0 and 1"),
        };
        if ok {
            Ok(())
        } else {
            Err(want)
        }
    }
}

/// One row of the table.
#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    /// Value reference (unique over all types).
    pub vr: u32,
    /// Name (structured naming convention).
    pub name: Cow<'static, str>,
    /// Type.
    pub kind: Kind,
    /// Causality.
    pub causality: Causality,
    /// Storage.
    pub slot: Slot,
    /// Unit name (declared in the unit definitions).
    pub unit: &'static str,
    /// Description.
    pub description: Cow<'static, str>,
    /// The values a parameter accepts (`Finite` for the other variables).
    pub constraint: Constraint,
}

/// Float parameters: (name, unit, description, constraint), in [`Slot::Param`] order: the
/// powertrain and the bearing, then the drive-path effects (`plant::effects::DriveEffects`),
/// which appear in the table only when the parameter set has them on (they change the model's
/// structure, so an FMU without them cannot switch them on, nor one with them off).
pub const PARAMETERS: [(&str, &str, &str, Constraint); NPARAMS] = [
    ("j_m2", "kg.m2", "inertia of load machine M2 with adapters (left, short side shaft)", Constraint::Positive),
    ("j_drive", "kg.m2", "drive unit inertia reduced to the output (differential cage)", Constraint::Positive),
    ("j_m3", "kg.m2", "inertia of load machine M3 with adapters (right, long side shaft)", Constraint::Positive),
    ("c_short", "N.m/rad", "stiffness of the short side shaft", Constraint::Positive),
    ("c_long", "N.m/rad", "stiffness of the long side shaft", Constraint::Positive),
    ("c_delta", "N.m/rad", "stiffness of the additional spring (variants V2-V4)", Constraint::NonNegative),
    ("j_m2_delta", "kg.m2", "M2-side inertia with the additional spring mounted", Constraint::Positive),
    ("j_m3_delta", "kg.m2", "M3-side inertia with the additional spring mounted", Constraint::Positive),
    ("d_short", "N.m.s/rad", "damping of the short side shaft", Constraint::NonNegative),
    ("d_long", "N.m.s/rad", "damping of the long side shaft", Constraint::NonNegative),
    ("load_drag", "N.m.s/rad", "speed-proportional drag of each load machine", Constraint::NonNegative),
    ("bearing.K_xx", "N/m", "bearing stiffness xx", Constraint::Finite),
    ("bearing.K_xy", "N/m", "bearing stiffness xy", Constraint::Finite),
    ("bearing.K_yx", "N/m", "bearing stiffness yx", Constraint::Finite),
    ("bearing.K_yy", "N/m", "bearing stiffness yy", Constraint::Finite),
    ("bearing.C_xx", "N.s/m", "bearing damping xx", Constraint::Finite),
    ("bearing.C_xy", "N.s/m", "bearing damping xy", Constraint::Finite),
    ("bearing.C_yx", "N.s/m", "bearing damping yx", Constraint::Finite),
    ("bearing.C_yy", "N.s/m", "bearing damping yy", Constraint::Finite),
    ("bearing.M_xx", "kg", "bearing added mass xx", Constraint::Finite),
    ("bearing.M_xy", "kg", "bearing added mass xy", Constraint::Finite),
    ("bearing.M_yx", "kg", "bearing added mass yx", Constraint::Finite),
    ("bearing.M_yy", "kg", "bearing added mass yy", Constraint::Finite),
    ("bearing.support.k_x", "N/m", "support stiffness x", Constraint::NonNegative),
    ("bearing.support.k_y", "N/m", "support stiffness y", Constraint::NonNegative),
    ("bearing.support.c_x", "N.s/m", "support damping x", Constraint::NonNegative),
    ("bearing.support.c_y", "N.s/m", "support damping y", Constraint::NonNegative),
    ("bearing.support.m_x", "kg", "support effective mass x", Constraint::Positive),
    ("bearing.support.m_y", "kg", "support effective mass y", Constraint::Positive),
    ("drive.time_delay", "s", "dead time of the drive torque", Constraint::Positive),
    ("drive.actuator_lag", "s", "time constant of a first-order lag of the drive torque", Constraint::Positive),
    ("drive.backlash", "rad", "total play of each side shaft (output side)", Constraint::Positive),
    ("drive.compliance_stiffness", "N.m/rad", "stiffness between the drive's motor and its cage", Constraint::Positive),
    (
        "drive.compliance_motor_fraction",
        "1",
        "share of j_drive on the motor side of the compliance",
        Constraint::Fraction,
    ),
];

/// Number of float parameters, the effects included.
pub const NPARAMS: usize = 34;
/// Index of the first effect parameter in [`PARAMETERS`].
pub const FIRST_EFFECT: usize = 29;

/// Continuous states: (name, unit, description, nominal). Their magnitudes stay bounded, so that
/// an importer's tolerances mean something (model exchange): the side shafts enter through their
/// twist, not through absolute angles that grow without bound under a torque (as Modelica's
/// rotational springs prefer `phi_rel`). The load machines' absolute angles stay states, since
/// model-exchange outputs are functions of the states, but no derivative depends on them, so
/// their tolerance cannot reach the oscillation. The first 10 are always there; the
/// compliance's twist and the motor's speed come with a drive compliance, the lagged torque with
/// an actuator lag. The nominals are the sizes an importer's absolute tolerance is scaled by
/// (fmpy: atol = rtol · nominal): 1 mrad of twist (the default rig twists 15 mrad at 20 N·m per
/// shaft), 10 µm and 1 mm/s for the bearing (its displacements are tens of µm).
pub const STATES: [(&str, &str, &str, f64); 13] = [
    ("phi_m2", "rad", "angle of load machine M2", 1.0),
    ("twist", "rad", "twist of the side shafts through the differential, 2 phi_drive - phi_m2 - phi_m3", 1e-3),
    ("phi_m3", "rad", "angle of load machine M3", 1.0),
    ("w_m2", "rad/s", "speed of load machine M2", 1.0),
    ("w_drive", "rad/s", "speed of the drive", 1.0),
    ("w_m3", "rad/s", "speed of load machine M3", 1.0),
    ("bearing.x", "m", "bearing displacement x", 1e-5),
    ("bearing.y", "m", "bearing displacement y", 1e-5),
    ("bearing.vx", "m/s", "bearing velocity x", 1e-3),
    ("bearing.vy", "m/s", "bearing velocity y", 1e-3),
    ("twist_motor", "rad", "twist of the drive compliance, phi_motor - phi_drive", 1e-3),
    ("w_motor", "rad/s", "speed of the drive's motor (drive compliance)", 1.0),
    ("M_drive_lagged", "N.m", "drive torque after the actuator lag", 10.0),
];

/// Computed derivatives: (index in [`STATES`], name, unit); the other states' derivatives
/// are states themselves (the speeds).
pub const DERIVATIVES: [(usize, &str, &str); 9] = [
    (3, "der(w_m2)", "rad/s2"),
    (4, "der(w_drive)", "rad/s2"),
    (5, "der(w_m3)", "rad/s2"),
    (8, "der(bearing.vx)", "m/s2"),
    (9, "der(bearing.vy)", "m/s2"),
    (1, "der(twist)", "rad/s"),
    (10, "der(twist_motor)", "rad/s"),
    (11, "der(w_motor)", "rad/s2"),
    (12, "der(M_drive_lagged)", "N.m/s"),
];

/// States that are the derivative of another: (index in [`STATES`], the index of its derivative).
const STATE_DERIVATIVES: [(usize, usize); 4] = [(0, 3), (2, 5), (6, 8), (7, 9)];

/// Absolute angles that are outputs but not states: (name, description), computed from the
/// states (the drive's from the twist and the load machines' angles, the motor's from the drive's
/// and the compliance's twist).
pub const ANGLES: [(&str, &str); 2] = [
    ("phi_drive", "angle of the drive (differential cage)"),
    ("phi_motor", "angle of the drive's motor (drive compliance)"),
];

/// Inputs: (name, unit, description).
pub const INPUTS: [(&str, &str, &str); 5] = [
    ("M_m2", "N.m", "torque of load machine M2"),
    ("M_drive", "N.m", "drive torque at the differential cage"),
    ("M_m3", "N.m", "torque of load machine M3"),
    ("bearing.F_x", "N", "force on the bearing along x"),
    ("bearing.F_y", "N", "force on the bearing along y"),
];

/// Computed outputs: the side-shaft torques.
pub const TORQUES: [(&str, &str); 2] =
    [("T_short", "torque in the short side shaft"), ("T_long", "torque in the long side shaft")];

/// First value reference of each group of the always-present variables; the effects'
/// variables follow the inputs.
pub const VR_PARAM: u32 = 1;
/// The variant's value reference.
pub const VR_VARIANT: u32 = 30;
/// First state.
pub const VR_STATE: u32 = 31;
/// First derivative.
pub const VR_DERIVATIVE: u32 = 41;
/// First torque output.
pub const VR_TORQUE: u32 = 46;
/// First input.
pub const VR_INPUT: u32 = 48;
/// The side shafts' twist (a state).
pub const VR_TWIST: u32 = 53;

/// The variable table of one parameter set: what the model description lists, in order, with
/// the continuous-state vector it implies.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// The variables; a variable's value reference is its index.
    pub variables: Vec<Variable>,
    /// [`STATES`] indices of the continuous states, in state-vector order.
    pub states: Vec<usize>,
    /// Per state (state-vector order): the state-vector index of the state that is its
    /// derivative, if one is.
    pub derivative_state: Vec<Option<usize>>,
    /// Per state (state-vector order): its nominal.
    pub nominal: Vec<f64>,
}

/// [`STATES`] indices of a powertrain's states (`plant::effects::Powertrain` order: angles,
/// speeds, lagged torque).
pub fn powertrain_states(effects: &plant::effects::DriveEffects) -> Vec<usize> {
    let mut v = if effects.compliance_stiffness_nm_per_rad > 0.0 {
        vec![0, 1, 2, 10, 3, 4, 5, 11]
    } else {
        vec![0, 1, 2, 3, 4, 5]
    };
    if effects.actuator_lag_s > 0.0 {
        v.push(12);
    }
    v
}

impl Table {
    /// The table of parameter set `p`: the paper rig's, or a drive model's.
    pub fn new(p: &FmuParams) -> Table {
        if p.controller.is_some() {
            return Table::of_controller();
        }
        if let Some(m) = &p.drive {
            return Table::of_drive(m);
        }
        let e = &p.effects;
        let compliant = e.compliance_stiffness_nm_per_rad > 0.0;
        let effect_on = [e.time_delay_s > 0.0, e.actuator_lag_s > 0.0, e.backlash_rad > 0.0, compliant, compliant];
        let params: Vec<usize> = (0..NPARAMS).filter(|&i| i < FIRST_EFFECT || effect_on[i - FIRST_EFFECT]).collect();
        let mut states: Vec<usize> = (0..10).collect();
        states.extend(powertrain_states(e).into_iter().filter(|&s| s >= 10));
        let mut v = vec![time_row()];
        let push =
            |v: &mut Vec<Variable>, name: &'static str, kind, causality, slot, unit, description: &'static str| {
                let vr = v.len() as u32;
                let constraint = match slot {
                    Slot::Param(i) => PARAMETERS[i].3,
                    _ => Constraint::Finite,
                };
                v.push(Variable {
                    vr,
                    name: name.into(),
                    kind,
                    causality,
                    slot,
                    unit,
                    description: description.into(),
                    constraint,
                });
            };
        let float = Kind::Float64;
        // the always-present variables first, at fixed value references
        for &i in params.iter().filter(|&&i| i < FIRST_EFFECT) {
            let (name, unit, description, _) = PARAMETERS[i];
            push(&mut v, name, float, Causality::Parameter, Slot::Param(i), unit, description);
        }
        push(
            &mut v,
            "variant",
            Kind::Int32,
            Causality::Parameter,
            Slot::Variant,
            "",
            "rig variant: 1 original, 2 spring both sides, 3 right (M3), 4 left (M2)",
        );
        let derivative_rows = |v: &mut Vec<Variable>, states: &[usize], which: &[usize]| {
            for &(s, name, unit) in DERIVATIVES.iter().filter(|d| which.contains(&d.0)) {
                if let Some(k) = states.iter().position(|&x| x == s) {
                    push(v, name, float, Causality::Local, Slot::Derivative(k), unit, "state derivative");
                }
            }
        };
        let state_row = |v: &mut Vec<Variable>, k: usize| {
            let (name, unit, description, _) = STATES[states[k]];
            push(v, name, float, Causality::Output, Slot::State(k), unit, description);
        };
        let angle_row = |v: &mut Vec<Variable>, i: usize| {
            let (name, description) = ANGLES[i];
            push(v, name, float, Causality::Output, Slot::Angle(i), "rad", description);
        };
        // the value references of the absolute angles (phi_drive among them) are those of the
        // rigtwin versions whose states they were; the twist states come after the inputs
        state_row(&mut v, 0);
        angle_row(&mut v, 0);
        for k in 2..10 {
            state_row(&mut v, k);
        }
        derivative_rows(&mut v, &states, &[3, 4, 5, 8, 9]);
        for (i, &(name, description)) in TORQUES.iter().enumerate() {
            push(&mut v, name, float, Causality::Output, Slot::Torque(i), "N.m", description);
        }
        for (i, &(name, unit, description)) in INPUTS.iter().enumerate() {
            push(&mut v, name, float, Causality::Input, Slot::Input(i), unit, description);
        }
        state_row(&mut v, 1);
        derivative_rows(&mut v, &states, &[1]);
        // then the effects'
        for &i in params.iter().filter(|&&i| i >= FIRST_EFFECT) {
            let (name, unit, description, _) = PARAMETERS[i];
            push(&mut v, name, float, Causality::Parameter, Slot::Param(i), unit, description);
        }
        if compliant {
            angle_row(&mut v, 1);
        }
        for k in 10..states.len() {
            state_row(&mut v, k);
        }
        derivative_rows(&mut v, &states, &[10, 11, 12]);
        let derivative_state = states
            .iter()
            .map(|s| STATE_DERIVATIVES.iter().find(|d| d.0 == *s).and_then(|d| states.iter().position(|&x| x == d.1)))
            .collect();
        let nominal = states.iter().map(|&s| STATES[s].3).collect();
        Table { variables: v, states, derivative_state, nominal }
    }

    /// The table of a drive model: its parameters (`plant::DriveModel::parameter_list`), its
    /// states (positions and speeds as outputs, lagged inputs), the speeds' and lags'
    /// derivatives, the couplings' forces (outputs) and the inputs; every name from the plant's
    /// one set of signal names.
    fn of_drive(m: &DriveModel) -> Table {
        let domain = m.line.domain;
        let mut v = vec![time_row()];
        let mut push = |name: String, causality, slot, unit, description: String, constraint| {
            float_row(&mut v, name.into(), causality, slot, unit, description.into(), constraint)
        };
        for (i, p) in m.parameter_list().into_iter().enumerate() {
            let constraint = if p.zero_allowed { Constraint::NonNegative } else { Constraint::Positive };
            push(p.name, Causality::Parameter, Slot::Param(i), unit_of(p.dimension, domain), p.description, constraint);
        }
        let names = m.state_names();
        let n = m.line.bodies.len();
        let nx = names.len();
        let (q, w, f) = (
            unit_of(Dimension::Coordinate, domain),
            unit_of(Dimension::Speed, domain),
            unit_of(Dimension::Force, domain),
        );
        let (acc, rate) = match domain {
            Domain::Rotational => ("rad/s2", "N.m/s"),
            Domain::Translational => ("m/s2", "N/s"),
        };
        let bodies: Vec<&str> = m.line.bodies.iter().map(|b| b.name.as_str()).collect();
        for (k, name) in names.iter().enumerate() {
            let (unit, description) = if k < n {
                (q, format!("position (angle) of {}", bodies[k]))
            } else if k < 2 * n {
                (w, format!("speed of {}", bodies[k - n]))
            } else {
                (f, "force (torque) after the actuator lag".to_string())
            };
            push(name.clone(), Causality::Output, Slot::State(k), unit, description, Constraint::Finite);
        }
        for (k, name) in names.iter().enumerate().skip(n) {
            let unit = if k < 2 * n { acc } else { rate };
            push(
                format!("der({name})"),
                Causality::Local,
                Slot::Derivative(k),
                unit,
                "state derivative".into(),
                Constraint::Finite,
            );
        }
        for (i, name) in m.coupling_force_names().into_iter().enumerate() {
            let description = format!("force (torque) in coupling {} ({}-{})", i + 1, bodies[i], bodies[i + 1]);
            push(name, Causality::Output, Slot::Torque(i), f, description, Constraint::Finite);
        }
        for (j, name) in m.input_names().into_iter().enumerate() {
            let description = format!("force (torque) on {}", bodies[m.inputs[j]]);
            push(name, Causality::Input, Slot::Input(j), f, description, Constraint::Finite);
        }
        let derivative_state = (0..nx).map(|k| (k < n).then_some(k + n)).collect();
        Table { variables: v, states: Vec::new(), derivative_state, nominal: vec![1.0; nx] }
    }

    /// The table of the controller FMU (`crate::controller`): its tunable settings, the
    /// measured speeds and references as inputs, the torque commands as outputs; no states.
    fn of_controller() -> Table {
        use crate::controller::{INPUTS, OUTPUTS, PARAMETERS};
        let mut v = vec![time_row()];
        let mut push = |name: &'static str, causality, slot, unit, description: &'static str, constraint| {
            float_row(&mut v, name.into(), causality, slot, unit, description.into(), constraint)
        };
        for (i, &(name, unit, description, constraint)) in PARAMETERS.iter().enumerate() {
            push(name, Causality::Parameter, Slot::Param(i), unit, description, constraint);
        }
        for (i, &(name, unit, description)) in INPUTS.iter().enumerate() {
            push(name, Causality::Input, Slot::Input(i), unit, description, Constraint::Finite);
        }
        for (i, &(name, description)) in OUTPUTS.iter().enumerate() {
            push(name, Causality::Output, Slot::Command(i), "N.m", description, Constraint::Finite);
        }
        Table { variables: v, states: Vec::new(), derivative_state: Vec::new(), nominal: Vec::new() }
    }

    /// Number of continuous states.
    pub fn nx(&self) -> usize {
        self.nominal.len()
    }

    /// The nominal of each continuous state, in state-vector order.
    pub fn nominals(&self) -> impl Iterator<Item = f64> + '_ {
        self.nominal.iter().copied()
    }

    /// The variable with value reference `vr`: value references are the table's indices.
    pub fn lookup(&self, vr: u32) -> Option<&Variable> {
        self.variables.get(vr as usize)
    }

    /// The variable of `slot`.
    pub fn find(&self, slot: Slot) -> Option<&Variable> {
        self.variables.iter().find(|v| v.slot == slot)
    }

    /// Number of inputs.
    pub fn nu(&self) -> usize {
        self.variables.iter().filter(|v| v.causality == Causality::Input).count()
    }
}

/// Appends a Float64 row at the next value reference.
fn float_row(
    v: &mut Vec<Variable>,
    name: Cow<'static, str>,
    causality: Causality,
    slot: Slot,
    unit: &'static str,
    description: Cow<'static, str>,
    constraint: Constraint,
) {
    let vr = v.len() as u32;
    v.push(Variable { vr, name, kind: Kind::Float64, causality, slot, unit, description, constraint });
}

fn time_row() -> Variable {
    Variable {
        vr: 0,
        name: "time".into(),
        kind: Kind::Float64,
        causality: Causality::Independent,
        slot: Slot::Time,
        unit: "s",
        description: "simulation time".into(),
        constraint: Constraint::Finite,
    }
}

/// The FMI unit of a drive-model quantity in its domain.
pub fn unit_of(d: Dimension, domain: Domain) -> &'static str {
    let rotational = domain == Domain::Rotational;
    match d {
        Dimension::Inertia => {
            if rotational {
                "kg.m2"
            } else {
                "kg"
            }
        }
        Dimension::Stiffness => {
            if rotational {
                "N.m/rad"
            } else {
                "N/m"
            }
        }
        Dimension::Damping => {
            if rotational {
                "N.m.s/rad"
            } else {
                "N.s/m"
            }
        }
        Dimension::Force => {
            if rotational {
                "N.m"
            } else {
                "N"
            }
        }
        Dimension::Coordinate => {
            if rotational {
                "rad"
            } else {
                "m"
            }
        }
        Dimension::Speed => {
            if rotational {
                "rad/s"
            } else {
                "m/s"
            }
        }
        Dimension::Time => "s",
        Dimension::Ratio => "1",
    }
}

/// The float parameters of a parameter set: the rig's in [`PARAMETERS`] order, a drive
/// model's in `plant::DriveModel::parameter_list` order.
pub fn parameter_values(p: &FmuParams) -> Vec<f64> {
    if let Some(c) = &p.controller {
        return c.values.clone();
    }
    if let Some(m) = &p.drive {
        return m.parameter_list().iter().map(|q| q.value).collect();
    }
    rig_parameter_values(p).to_vec()
}

fn rig_parameter_values(p: &FmuParams) -> [f64; NPARAMS] {
    let w = &p.powertrain;
    let b = &p.bearing;
    let (k, c, m) = (b.element.k_n_per_m, b.element.c_ns_per_m, b.element.m_kg);
    let s = b.support;
    [
        w.j_m2,
        w.j_drive,
        w.j_m3,
        w.c_short,
        w.c_long(),
        w.c_delta,
        w.j_m2_delta.unwrap_or(w.j_m2),
        w.j_m3_delta.unwrap_or(w.j_m3),
        w.d_short,
        w.d_long,
        w.load_drag,
        k[0][0],
        k[0][1],
        k[1][0],
        k[1][1],
        c[0][0],
        c[0][1],
        c[1][0],
        c[1][1],
        m[0][0],
        m[0][1],
        m[1][0],
        m[1][1],
        s.k_x,
        s.k_y,
        s.c_x,
        s.c_y,
        s.m_x,
        s.m_y,
        p.effects.time_delay_s,
        p.effects.actuator_lag_s,
        p.effects.backlash_rad,
        p.effects.compliance_stiffness_nm_per_rad,
        p.effects.compliance_motor_fraction,
    ]
}

/// The parameter set of float parameters `v` and variant 1..=4, of the structure of `like`
/// (the rig's, or a drive model's with its bodies, couplings, inputs and effects).
pub fn parameter_set(like: &FmuParams, v: &[f64], variant: i32) -> Result<FmuParams, String> {
    if let Some(c) = &like.controller {
        let spec = crate::controller::ControllerSpec { values: v.to_vec(), ..c.clone() };
        return Ok(FmuParams { controller: Some(spec), ..like.clone() });
    }
    if let Some(m) = &like.drive {
        let drive = m.with_parameter_values(v).map_err(|e| e.to_string())?;
        return Ok(FmuParams { drive: Some(drive), ..like.clone() });
    }
    let v: &[f64; NPARAMS] =
        v.try_into().map_err(|_| format!("{} parameter values for the rig's {NPARAMS}", v.len()))?;
    use plant::{BearingModel, Coefficients, RigParams, Support, Variant};
    let variant = match variant {
        1 => Variant::V1,
        2 => Variant::V2,
        3 => Variant::V3,
        4 => Variant::V4,
        other => return Err(format!("`variant` = {other}: expected 1, 2, 3 or 4")),
    };
    Ok(FmuParams {
        powertrain: RigParams {
            j_m2: v[0],
            j_drive: v[1],
            j_m3: v[2],
            c_short: v[3],
            c_long: Some(v[4]),
            c_long_ratio: v[4] / v[3],
            c_delta: v[5],
            j_m2_delta: Some(v[6]),
            j_m3_delta: Some(v[7]),
            d_short: v[8],
            d_long: v[9],
            load_drag: v[10],
        },
        variant,
        bearing: BearingModel {
            element: Coefficients {
                k_n_per_m: [[v[11], v[12]], [v[13], v[14]]],
                c_ns_per_m: [[v[15], v[16]], [v[17], v[18]]],
                m_kg: [[v[19], v[20]], [v[21], v[22]]],
            },
            support: Support { k_x: v[23], k_y: v[24], c_x: v[25], c_y: v[26], m_x: v[27], m_y: v[28] },
            table: None,
        },
        effects: plant::effects::DriveEffects {
            time_delay_s: v[29],
            actuator_lag_s: v[30],
            backlash_rad: v[31],
            compliance_stiffness_nm_per_rad: v[32],
            compliance_motor_fraction: v[33],
        },
        drive: None,
        controller: None,
    })
}

/// 1..=4 for V1..V4.
pub fn variant_number(v: plant::Variant) -> i32 {
    match v {
        plant::Variant::V1 => 1,
        plant::Variant::V2 => 2,
        plant::Variant::V3 => 3,
        plant::Variant::V4 => 4,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn value_references_are_unique_and_all_found() {
        let t = Table::new(&FmuParams::default());
        assert_eq!(t.nx(), 10);
        for (i, v) in t.variables.iter().enumerate() {
            assert_eq!(v.vr as usize, i, "value references are the table's indices");
            assert_eq!(t.lookup(v.vr), Some(v));
        }
        assert_eq!(t.lookup(999), None);
        // the always-present groups keep their value references
        assert_eq!(t.find(Slot::Param(0)).unwrap().vr, VR_PARAM);
        assert_eq!(t.find(Slot::Variant).unwrap().vr, VR_VARIANT);
        assert_eq!(t.find(Slot::State(0)).unwrap().vr, VR_STATE);
        assert_eq!(t.find(Slot::Derivative(3)).unwrap().vr, VR_DERIVATIVE);
        assert_eq!(t.find(Slot::Torque(0)).unwrap().vr, VR_TORQUE);
        assert_eq!(t.find(Slot::Input(0)).unwrap().vr, VR_INPUT);
        assert_eq!(t.find(Slot::State(1)).unwrap().vr, VR_TWIST);
        // the names of rigtwin's first FMUs keep their value references
        assert_eq!(t.lookup(VR_STATE + 1).unwrap().name, "phi_drive");
        assert_eq!(t.lookup(VR_STATE + 3).unwrap().name, "w_m2");
    }

    #[test]
    fn effects_add_their_parameters_and_states_after_the_rest() {
        let mut p = FmuParams::default();
        let base = Table::new(&p);
        p.effects.actuator_lag_s = 0.004;
        p.effects.compliance_stiffness_nm_per_rad = 2000.0;
        let t = Table::new(&p);
        assert_eq!(t.nx(), 13);
        assert_eq!(&t.variables[..base.variables.len()], &base.variables[..]);
        let names: Vec<&str> = t.variables[base.variables.len()..].iter().map(|v| v.name.as_ref()).collect();
        assert_eq!(
            names,
            [
                "drive.actuator_lag",
                "drive.compliance_stiffness",
                "drive.compliance_motor_fraction",
                "phi_motor",
                "twist_motor",
                "w_motor",
                "M_drive_lagged",
                "der(twist_motor)",
                "der(w_motor)",
                "der(M_drive_lagged)"
            ]
        );
        // the twists' and the lagged torque's derivatives are computed; φ_m2's is w_m2
        assert_eq!(t.derivative_state[10], None);
        assert_eq!(t.derivative_state[12], None);
        assert_eq!(t.derivative_state[0], Some(3));
    }

    #[test]
    fn parameters_round_trip() {
        let p = FmuParams::default();
        let mut p = p;
        p.effects.backlash_rad = 0.002;
        let back = parameter_set(&p, &parameter_values(&p), variant_number(p.variant)).unwrap();
        assert_eq!(back.effects, p.effects);
        assert_eq!(parameter_values(&back), parameter_values(&p));
        let a = p.powertrain.open_differential(p.variant).unwrap().stiffness_matrix();
        let b = back.powertrain.open_differential(back.variant).unwrap().stiffness_matrix();
        assert!((a - b).norm() < 1e-9);
    }
}
