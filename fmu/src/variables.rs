//! The one variable table. Both modelDescription.xml files, the value-reference map of the
//! instances and the instantiation token are generated from it, so they cannot disagree.

use std::borrow::Cow;

use crate::params::{FmuParams, Plant, RigPlant};
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

/// One float parameter of the rig's FMU: its name, unit, description and accepted values,
/// whether the parameter set has it (the effects' parameters appear only when their effect is
/// on: they change the model's structure, so an FMU without them cannot switch them on, nor one
/// with them off), and how it is read from and written to a parameter set. One row per
/// parameter: the table, the start values and [`parameter_set`] all come from this list.
#[derive(Clone, Copy)]
pub struct RigParameter {
    /// Name (structured naming convention).
    pub name: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// Description.
    pub description: &'static str,
    /// Accepted values.
    pub constraint: Constraint,
    /// Which parameter sets have it.
    pub present: Presence,
    /// Its value in a parameter set.
    pub get: fn(&RigPlant) -> f64,
    /// Sets it in a parameter set.
    pub set: fn(&mut RigPlant, f64),
}

/// Which of the rig's parameter sets have a parameter.
#[derive(Clone, Copy)]
pub enum Presence {
    /// Every one, at a fixed value reference.
    Always,
    /// Those with a bearing block, at a fixed value reference (kept free without one).
    Bearing,
    /// Those whose effects make this true; after every fixed row.
    Effect(fn(&plant::rig::DriveEffects) -> bool),
}

impl Presence {
    /// Whether the row has a fixed value reference (kept free when the row is absent).
    fn fixed(self) -> bool {
        !matches!(self, Presence::Effect(_))
    }

    /// Whether parameter set `p` has the row.
    fn in_set(self, p: &RigPlant) -> bool {
        match self {
            Presence::Always => true,
            Presence::Bearing => p.bearing.is_some(),
            Presence::Effect(on) => on(&p.effects),
        }
    }
}

impl std::fmt::Debug for RigParameter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

macro_rules! rig_param {
    ($name:literal, $unit:literal, $desc:literal, $c:ident, bearing |$b:ident| $field:expr) => {
        RigParameter {
            name: $name,
            unit: $unit,
            description: $desc,
            constraint: Constraint::$c,
            present: Presence::Bearing,
            get: |p: &RigPlant| p.bearing.as_ref().map_or(0.0, |$b| $field),
            set: |p: &mut RigPlant, v: f64| {
                if let Some($b) = p.bearing.as_mut() {
                    $field = v;
                }
            },
        }
    };
    ($name:literal, $unit:literal, $desc:literal, $c:ident, |$p:ident| $field:expr) => {
        RigParameter {
            name: $name,
            unit: $unit,
            description: $desc,
            constraint: Constraint::$c,
            present: Presence::Always,
            get: |$p: &RigPlant| $field,
            set: |$p: &mut RigPlant, v: f64| $field = v,
        }
    };
    ($name:literal, $unit:literal, $desc:literal, $c:ident, if |$e:ident| $on:expr, |$p:ident| $field:expr) => {
        RigParameter {
            name: $name,
            unit: $unit,
            description: $desc,
            constraint: Constraint::$c,
            present: Presence::Effect(|$e: &plant::rig::DriveEffects| $on),
            get: |$p: &RigPlant| $field,
            set: |$p: &mut RigPlant, v: f64| $field = v,
        }
    };
}

/// The rig's float parameters in [`Slot::Param`] order: the powertrain and the bearing, then the
/// drive-path effects (`plant::rig::DriveEffects`). New rows go at the end: the value
/// references of the existing ones stay.
pub const PARAMETERS: &[RigParameter] = &[
    rig_param!("j_m2", "kg.m2", "inertia of load machine M2 with adapters (left, short side shaft)", Positive, |p| p
        .powertrain
        .j_m2),
    rig_param!("j_drive", "kg.m2", "drive unit inertia reduced to the output (differential cage)", Positive, |p| p
        .powertrain
        .j_drive),
    rig_param!("j_m3", "kg.m2", "inertia of load machine M3 with adapters (right, long side shaft)", Positive, |p| p
        .powertrain
        .j_m3),
    rig_param!("c_short", "N.m/rad", "stiffness of the short side shaft", Positive, |p| p.powertrain.c_short),
    RigParameter {
        name: "c_long",
        unit: "N.m/rad",
        description: "stiffness of the long side shaft",
        constraint: Constraint::Positive,
        present: Presence::Always,
        get: |p| p.powertrain.c_long(),
        // after c_short (the rows are applied in order): the ratio follows both
        set: |p, v| {
            p.powertrain.c_long = Some(v);
            p.powertrain.c_long_ratio = v / p.powertrain.c_short;
        },
    },
    rig_param!("c_delta", "N.m/rad", "stiffness of the additional spring (variants V2-V4)", NonNegative, |p| p
        .powertrain
        .c_delta),
    RigParameter {
        name: "j_m2_delta",
        unit: "kg.m2",
        description: "M2-side inertia with the additional spring mounted",
        constraint: Constraint::Positive,
        present: Presence::Always,
        get: |p| p.powertrain.j_m2_delta.unwrap_or(p.powertrain.j_m2),
        set: |p, v| p.powertrain.j_m2_delta = Some(v),
    },
    RigParameter {
        name: "j_m3_delta",
        unit: "kg.m2",
        description: "M3-side inertia with the additional spring mounted",
        constraint: Constraint::Positive,
        present: Presence::Always,
        get: |p| p.powertrain.j_m3_delta.unwrap_or(p.powertrain.j_m3),
        set: |p, v| p.powertrain.j_m3_delta = Some(v),
    },
    rig_param!("d_short", "N.m.s/rad", "damping of the short side shaft", NonNegative, |p| p.powertrain.d_short),
    rig_param!("d_long", "N.m.s/rad", "damping of the long side shaft", NonNegative, |p| p.powertrain.d_long),
    rig_param!("load_drag", "N.m.s/rad", "speed-proportional drag of each load machine", NonNegative, |p| p
        .powertrain
        .load_drag),
    rig_param!("bearing.K_xx", "N/m", "bearing stiffness xx", Finite, bearing | b | b.element.k_n_per_m[0][0]),
    rig_param!("bearing.K_xy", "N/m", "bearing stiffness xy", Finite, bearing | b | b.element.k_n_per_m[0][1]),
    rig_param!("bearing.K_yx", "N/m", "bearing stiffness yx", Finite, bearing | b | b.element.k_n_per_m[1][0]),
    rig_param!("bearing.K_yy", "N/m", "bearing stiffness yy", Finite, bearing | b | b.element.k_n_per_m[1][1]),
    rig_param!("bearing.C_xx", "N.s/m", "bearing damping xx", Finite, bearing | b | b.element.c_ns_per_m[0][0]),
    rig_param!("bearing.C_xy", "N.s/m", "bearing damping xy", Finite, bearing | b | b.element.c_ns_per_m[0][1]),
    rig_param!("bearing.C_yx", "N.s/m", "bearing damping yx", Finite, bearing | b | b.element.c_ns_per_m[1][0]),
    rig_param!("bearing.C_yy", "N.s/m", "bearing damping yy", Finite, bearing | b | b.element.c_ns_per_m[1][1]),
    rig_param!("bearing.M_xx", "kg", "bearing added mass xx", Finite, bearing | b | b.element.m_kg[0][0]),
    rig_param!("bearing.M_xy", "kg", "bearing added mass xy", Finite, bearing | b | b.element.m_kg[0][1]),
    rig_param!("bearing.M_yx", "kg", "bearing added mass yx", Finite, bearing | b | b.element.m_kg[1][0]),
    rig_param!("bearing.M_yy", "kg", "bearing added mass yy", Finite, bearing | b | b.element.m_kg[1][1]),
    rig_param!("bearing.support.k_x", "N/m", "support stiffness x", NonNegative, bearing | b | b.support.k_x),
    rig_param!("bearing.support.k_y", "N/m", "support stiffness y", NonNegative, bearing | b | b.support.k_y),
    rig_param!("bearing.support.c_x", "N.s/m", "support damping x", NonNegative, bearing | b | b.support.c_x),
    rig_param!("bearing.support.c_y", "N.s/m", "support damping y", NonNegative, bearing | b | b.support.c_y),
    rig_param!("bearing.support.m_x", "kg", "support effective mass x", Positive, bearing | b | b.support.m_x),
    rig_param!("bearing.support.m_y", "kg", "support effective mass y", Positive, bearing | b | b.support.m_y),
    rig_param!("drive.time_delay", "s", "dead time of the drive torque", Positive,
        if |e| e.time_delay_s > 0.0, |p| p.effects.time_delay_s),
    rig_param!("drive.actuator_lag", "s", "time constant of a first-order lag of the drive torque", Positive,
        if |e| e.actuator_lag_s > 0.0, |p| p.effects.actuator_lag_s),
    rig_param!("drive.backlash", "rad", "total play of each side shaft (output side)", Positive,
        if |e| e.backlash_rad > 0.0, |p| p.effects.backlash_rad),
    rig_param!("drive.compliance_stiffness", "N.m/rad", "stiffness between the drive's motor and its cage", Positive,
        if |e| e.compliance_stiffness_nm_per_rad > 0.0, |p| p.effects.compliance_stiffness_nm_per_rad),
    rig_param!("drive.compliance_motor_fraction", "1", "share of j_drive on the motor side of the compliance", Fraction,
        if |e| e.compliance_stiffness_nm_per_rad > 0.0, |p| p.effects.compliance_motor_fraction),
    rig_param!("m2.coulomb_friction", "N.m", "Coulomb friction of load machine M2", Positive,
        if |e| e.coulomb_friction_nm[0] > 0.0, |p| p.effects.coulomb_friction_nm[0]),
    rig_param!("drive.coulomb_friction", "N.m", "Coulomb friction of the drive (its motor when compliant)", Positive,
        if |e| e.coulomb_friction_nm[1] > 0.0, |p| p.effects.coulomb_friction_nm[1]),
    rig_param!("m3.coulomb_friction", "N.m", "Coulomb friction of load machine M3", Positive,
        if |e| e.coulomb_friction_nm[2] > 0.0, |p| p.effects.coulomb_friction_nm[2]),
    rig_param!("friction_smoothing_speed", "rad/s",
        "smoothing speed v_s of the Coulomb friction, T = T_c w / sqrt(w^2 + v_s^2)", Positive,
        if |e| e.coulomb_friction_nm.iter().any(|&f| f > 0.0), |p| p.effects.friction_smoothing_radps),
];

/// Index in [`PARAMETERS`] of the parameter `name`.
pub fn rig_parameter(name: &str) -> Option<usize> {
    PARAMETERS.iter().position(|p| p.name == name)
}

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

/// [`STATES`] indices of the bearing block's states (a rig with a bearing block has them).
const BEARING_STATES: [usize; 4] = [6, 7, 8, 9];

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

/// One variable of the controller FMU: a tunable parameter, an input or an output.
#[derive(Debug, Clone, PartialEq)]
pub struct Port {
    /// Name (structured naming convention).
    pub name: Cow<'static, str>,
    /// Unit.
    pub unit: &'static str,
    /// Description.
    pub description: Cow<'static, str>,
    /// The values a parameter accepts (`Finite` for inputs and outputs).
    pub constraint: Constraint,
}

impl Port {
    pub(crate) fn of(
        name: impl Into<Cow<'static, str>>,
        unit: &'static str,
        description: impl Into<Cow<'static, str>>,
    ) -> Port {
        Port { name: name.into(), unit, description: description.into(), constraint: Constraint::Finite }
    }
}

/// The controller FMU's variables, generated from its model: tunable parameters (in
/// [`crate::params::ControllerSpec::values`] order), inputs (measured, then references), outputs (commands).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Ports {
    /// Tunable parameters.
    pub parameters: Vec<Port>,
    /// Inputs: the measured outputs, then the references.
    pub inputs: Vec<Port>,
    /// How many of the inputs are measurements.
    pub measured: usize,
    /// Outputs: the commands.
    pub outputs: Vec<Port>,
}

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
    /// Number of input slots (a rig without a bearing block keeps the bearing forces' slots,
    /// unlisted and at zero).
    pub input_slots: usize,
}

/// [`STATES`] indices of the rig model's states (`plant::Stepper::paper_rig` order: angles,
/// speeds, lagged torque).
pub fn powertrain_states(effects: &plant::rig::DriveEffects) -> Vec<usize> {
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
    /// The table of the plant of parameter set `p`: the paper rig's, or a drive model's (a
    /// controller FMU's is [`Table::of_ports`]; `crate::table` chooses).
    pub fn of_plant(p: &Plant) -> Table {
        match p {
            Plant::PaperRig(r) => Table::of_rig(r),
            Plant::Drive(m) => Table::of_drive(m),
        }
    }

    /// The paper rig's table. The fixed rows keep their value references whether or not the
    /// parameter set has them (a rig without a bearing block leaves the bearing's free), so
    /// that a user's SSP file points at the same variables; the effects' rows follow.
    fn of_rig(p: &RigPlant) -> Table {
        let e = &p.effects;
        let bearing = p.bearing.is_some();
        let compliant = e.compliance_stiffness_nm_per_rad > 0.0;
        let mut states: Vec<usize> = (0..6).collect();
        if bearing {
            states.extend(BEARING_STATES);
        }
        states.extend(powertrain_states(e).into_iter().filter(|&s| s >= 10));
        let mut rows = Rows { v: vec![time_row()], next_vr: 1 };
        // the fixed rows first, at fixed value references
        for (i, r) in PARAMETERS.iter().enumerate().filter(|(_, r)| r.present.fixed()) {
            let row = (Causality::Parameter, Slot::Param(i), r.unit, r.description, r.constraint);
            rows.push_if(r.present.in_set(p), r.name, Kind::Float64, row);
        }
        let variant = (
            Causality::Parameter,
            Slot::Variant,
            "",
            "rig variant: 1 original, 2 spring both sides, 3 right (M3), 4 left (M2)",
            Constraint::Finite,
        );
        rows.push_if(true, "variant", Kind::Int32, variant);
        let state_row = |rows: &mut Rows, s: usize| {
            let (name, unit, description, _) = STATES[s];
            let k = states.iter().position(|&x| x == s);
            let row = (Causality::Output, Slot::State(k.unwrap_or(0)), unit, description, Constraint::Finite);
            rows.push_if(k.is_some(), name, Kind::Float64, row);
        };
        let derivative_rows = |rows: &mut Rows, which: &[usize], fixed: bool| {
            for &(s, name, unit) in DERIVATIVES.iter().filter(|d| which.contains(&d.0)) {
                let k = states.iter().position(|&x| x == s);
                let row =
                    (Causality::Local, Slot::Derivative(k.unwrap_or(0)), unit, "state derivative", Constraint::Finite);
                if fixed || k.is_some() {
                    rows.push_if(k.is_some(), name, Kind::Float64, row);
                }
            }
        };
        let angle_row = |rows: &mut Rows, i: usize| {
            let (name, description) = ANGLES[i];
            rows.push_if(
                true,
                name,
                Kind::Float64,
                (Causality::Output, Slot::Angle(i), "rad", description, Constraint::Finite),
            );
        };
        // the value references of the absolute angles (phi_drive among them) are those of the
        // rigtwin versions whose states they were; the twist states come after the inputs
        state_row(&mut rows, 0);
        angle_row(&mut rows, 0);
        for s in 2..10 {
            state_row(&mut rows, s);
        }
        derivative_rows(&mut rows, &[3, 4, 5, 8, 9], true);
        for (i, &(name, description)) in TORQUES.iter().enumerate() {
            rows.push_if(
                true,
                name,
                Kind::Float64,
                (Causality::Output, Slot::Torque(i), "N.m", description, Constraint::Finite),
            );
        }
        for (i, &(name, unit, description)) in INPUTS.iter().enumerate() {
            let row = (Causality::Input, Slot::Input(i), unit, description, Constraint::Finite);
            rows.push_if(i < 3 || bearing, name, Kind::Float64, row);
        }
        state_row(&mut rows, 1);
        derivative_rows(&mut rows, &[1], true);
        // then the effects'
        for (i, r) in PARAMETERS.iter().enumerate().filter(|(_, r)| !r.present.fixed() && r.present.in_set(p)) {
            let row = (Causality::Parameter, Slot::Param(i), r.unit, r.description, r.constraint);
            rows.push_if(true, r.name, Kind::Float64, row);
        }
        if compliant {
            angle_row(&mut rows, 1);
        }
        for s in 10..STATES.len() {
            if states.contains(&s) {
                state_row(&mut rows, s);
            }
        }
        derivative_rows(&mut rows, &[10, 11, 12], false);
        let derivative_state = states
            .iter()
            .map(|s| STATE_DERIVATIVES.iter().find(|d| d.0 == *s).and_then(|d| states.iter().position(|&x| x == d.1)))
            .collect();
        let nominal = states.iter().map(|&s| STATES[s].3).collect();
        Table { variables: rows.v, states, derivative_state, nominal, input_slots: INPUTS.len() }
    }

    /// The table of a drive model: its parameters (`plant::DriveModel::parameter_list`), its
    /// states (the couplings' twists and, where they do not fix every position, a body's
    /// position — `plant::stepper::coordinates` —, the speeds, lagged inputs; all outputs), the
    /// derivatives that are not states themselves, the positions that are not states (outputs),
    /// the couplings' forces (outputs) and the inputs; every name from the plant's one set of
    /// signal names. Nominals: 1 mrad of twist (10 µm of elongation), 1 for the rest.
    fn of_drive(m: &DriveModel) -> Table {
        let domain = m.line.domain;
        let mut rows = Rows { v: vec![time_row()], next_vr: 1 };
        let mut push = |name: String, causality, slot, unit, description: String, constraint| {
            rows.push_if(true, name, Kind::Float64, (causality, slot, unit, description, constraint))
        };
        for (i, p) in m.parameter_list().into_iter().enumerate() {
            let constraint = if p.zero_allowed { Constraint::NonNegative } else { Constraint::Positive };
            push(p.name, Causality::Parameter, Slot::Param(i), p.dimension.unit(domain), p.description, constraint);
        }
        let names = m.state_names();
        let n = m.line.bodies.len();
        let nx = names.len();
        let (q, w, f) =
            (Dimension::Coordinate.unit(domain), Dimension::Speed.unit(domain), Dimension::Force.unit(domain));
        let (acc, rate, twist, what, twist_nominal) = match domain {
            Domain::Rotational => ("rad/s2", "N.m/s", "twist", "angle", 1e-3),
            Domain::Translational => ("m/s2", "N/s", "elongation", "position", 1e-5),
        };
        let bodies: Vec<&str> = m.line.bodies.iter().map(|b| b.name.as_str()).collect();
        let labels = m.coupling_labels();
        // a line that cannot be stepped has no coordinates: its table keeps the plant's names
        // (the instance refuses it with the reason when it is built)
        let coordinates = plant::stepper::coordinates(m)
            .map(|(c, _)| c)
            .unwrap_or_else(|_| (0..n).map(plant::Coordinate::Position).collect());
        let mut nominal = vec![1.0; nx];
        let mut derivative_state: Vec<Option<usize>> = (0..nx).map(|_| None).collect();
        for (k, c) in coordinates.iter().enumerate() {
            let (name, description) = match *c {
                plant::Coordinate::Twist(i) => {
                    nominal[k] = twist_nominal;
                    (format!("{twist}_{}", labels[i]), format!("{twist} of coupling {} ({})", i + 1, labels[i]))
                }
                plant::Coordinate::Position(b) => {
                    derivative_state[k] = Some(n + b);
                    (names[b].clone(), format!("{what} of {}", bodies[b]))
                }
            };
            push(name, Causality::Output, Slot::State(k), q, description, Constraint::Finite);
        }
        for (k, name) in names.iter().enumerate().skip(n) {
            let (unit, description) = if k < 2 * n {
                (w, format!("speed of {}", bodies[k - n]))
            } else {
                (f, format!("{} after the actuator lag", force_word(domain)))
            };
            push(name.clone(), Causality::Output, Slot::State(k), unit, description, Constraint::Finite);
        }
        for (k, c) in coordinates.iter().enumerate() {
            if let plant::Coordinate::Twist(i) = *c {
                let name = format!("der({twist}_{})", labels[i]);
                push(name, Causality::Local, Slot::Derivative(k), w, "state derivative".into(), Constraint::Finite);
            }
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
        for b in 0..n {
            if !coordinates.contains(&plant::Coordinate::Position(b)) {
                push(
                    names[b].clone(),
                    Causality::Output,
                    Slot::Angle(b),
                    q,
                    format!("{what} of {}", bodies[b]),
                    Constraint::Finite,
                );
            }
        }
        for (i, name) in m.coupling_force_names().into_iter().enumerate() {
            let c = &m.line.couplings[i];
            let description = match (&c.elongation, &c.name) {
                (None, _) => format!("{} in coupling {} ({}-{})", force_word(domain), i + 1, bodies[i], bodies[i + 1]),
                (Some(_), Some(name)) => format!("{} in coupling {} ({name})", force_word(domain), i + 1),
                (Some(_), None) => format!("{} in coupling {}", force_word(domain), i + 1),
            };
            push(name, Causality::Output, Slot::Torque(i), f, description, Constraint::Finite);
        }
        for (j, name) in m.input_names().into_iter().enumerate() {
            let description = format!("{} on {}", force_word(domain), bodies[m.inputs[j]]);
            push(name, Causality::Input, Slot::Input(j), f, description, Constraint::Finite);
        }
        let input_slots = m.inputs.len();
        Table { variables: rows.v, states: Vec::new(), derivative_state, nominal, input_slots }
    }

    /// The table of the controller FMU (`crate::controller`): its tunable settings, the
    /// measurements and references as inputs, the commands as outputs; no states. The paper
    /// rig's names and value references are fixed; a drive model's come from its model and
    /// `[mpc]` section (`ControllerSpec::ports`).
    pub fn of_ports(ports: &Ports) -> Table {
        let mut rows = Rows { v: vec![time_row()], next_vr: 1 };
        let mut push = |q: &Port, causality, slot| {
            rows.push_if(
                true,
                q.name.clone(),
                Kind::Float64,
                (causality, slot, q.unit, q.description.clone(), q.constraint),
            )
        };
        for (i, q) in ports.parameters.iter().enumerate() {
            push(q, Causality::Parameter, Slot::Param(i));
        }
        for (i, q) in ports.inputs.iter().enumerate() {
            push(q, Causality::Input, Slot::Input(i));
        }
        for (i, q) in ports.outputs.iter().enumerate() {
            push(q, Causality::Output, Slot::Command(i));
        }
        Table {
            variables: rows.v,
            states: Vec::new(),
            derivative_state: Vec::new(),
            nominal: Vec::new(),
            input_slots: ports.inputs.len(),
        }
    }

    /// Number of continuous states.
    pub fn nx(&self) -> usize {
        self.nominal.len()
    }

    /// The nominal of each continuous state, in state-vector order.
    pub fn nominals(&self) -> impl Iterator<Item = f64> + '_ {
        self.nominal.iter().copied()
    }

    /// The variable with value reference `vr` (the rows are in value-reference order).
    pub fn lookup(&self, vr: u32) -> Option<&Variable> {
        self.variables.binary_search_by_key(&vr, |v| v.vr).ok().map(|i| &self.variables[i])
    }

    /// The variable of `slot`.
    pub fn find(&self, slot: Slot) -> Option<&Variable> {
        self.variables.iter().find(|v| v.slot == slot)
    }

    /// Number of input slots.
    pub fn nu(&self) -> usize {
        self.input_slots
    }
}

/// A table being written: its rows and the next value reference.
struct Rows {
    v: Vec<Variable>,
    next_vr: u32,
}

impl Rows {
    /// Appends the row (causality, slot, unit, description, constraint) at the next value
    /// reference if `present`; that value reference is taken either way.
    fn push_if<D: Into<Cow<'static, str>>>(
        &mut self,
        present: bool,
        name: impl Into<Cow<'static, str>>,
        kind: Kind,
        (causality, slot, unit, description, constraint): (Causality, Slot, &'static str, D, Constraint),
    ) {
        if present {
            let (name, description) = (name.into(), description.into());
            self.v.push(Variable { vr: self.next_vr, name, kind, causality, slot, unit, description, constraint });
        }
        self.next_vr += 1;
    }
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

/// What a coupling or an actuator transmits in `domain`, for descriptions.
fn force_word(domain: Domain) -> &'static str {
    match domain {
        Domain::Rotational => "torque",
        Domain::Translational => "force",
    }
}

/// The float parameters of a parameter set: a controller's tunables, the rig's in
/// [`PARAMETERS`] order, a drive model's in `plant::DriveModel::parameter_list` order.
pub fn parameter_values(p: &FmuParams) -> Vec<f64> {
    if let Some(c) = &p.controller {
        return c.values.clone();
    }
    match &p.plant {
        Plant::PaperRig(r) => PARAMETERS.iter().map(|row| (row.get)(r)).collect(),
        Plant::Drive(m) => m.parameter_list().iter().map(|q| q.value).collect(),
    }
}

/// The parameter set of float parameters `v` and variant 1..=4, of the structure of `like`
/// (the rig's, or a drive model's with its bodies, couplings, inputs and effects).
pub fn parameter_set(like: &FmuParams, v: &[f64], variant: i32) -> Result<FmuParams, String> {
    if let Some(c) = &like.controller {
        let spec = crate::params::ControllerSpec { values: v.to_vec(), ..c.clone() };
        return Ok(FmuParams { controller: Some(spec), ..like.clone() });
    }
    let plant = match &like.plant {
        Plant::Drive(m) => Plant::Drive(m.with_parameter_values(v).map_err(|e| e.to_string())?),
        Plant::PaperRig(r) => Plant::PaperRig(rig_parameter_set(r, v, variant)?),
    };
    Ok(FmuParams { plant, controller: None })
}

/// The rig of float parameters `v` ([`PARAMETERS`] order) and variant 1..=4, with the bearing
/// block and effects of `like`.
fn rig_parameter_set(like: &RigPlant, v: &[f64], variant: i32) -> Result<RigPlant, String> {
    if v.len() != PARAMETERS.len() {
        return Err(format!("{} parameter values for the rig's {}", v.len(), PARAMETERS.len()));
    }
    use plant::Variant;
    let variant = match variant {
        1 => Variant::V1,
        2 => Variant::V2,
        3 => Variant::V3,
        4 => Variant::V4,
        other => return Err(format!("`variant` = {other}: expected 1, 2, 3 or 4")),
    };
    let mut r = RigPlant { variant, ..like.clone() };
    if let Some(b) = r.bearing.as_mut() {
        b.table = None;
    }
    for (row, &value) in PARAMETERS.iter().zip(v) {
        (row.set)(&mut r, value);
    }
    Ok(r)
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
        let t = Table::of_plant(&FmuParams::with_sfd_bearing().plant);
        assert_eq!(t.nx(), 10);
        for (i, v) in t.variables.iter().enumerate() {
            assert_eq!(v.vr as usize, i, "with a bearing block the value references are the table's indices");
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

    /// Without a bearing block (the paper rig's default) the bearing's parameters, states,
    /// derivatives and forces are absent and every other variable keeps its value reference.
    #[test]
    fn a_rig_without_a_bearing_keeps_the_other_value_references() {
        let with = Table::of_plant(&FmuParams::with_sfd_bearing().plant);
        let without = Table::of_plant(&FmuParams::default().plant);
        assert_eq!(without.nx(), 6);
        assert_eq!(without.nu(), 5, "the forces' slots stay, unlisted");
        let kept: Vec<(u32, &str)> =
            with.variables.iter().filter(|v| !v.name.contains("bearing")).map(|v| (v.vr, v.name.as_ref())).collect();
        let got: Vec<(u32, &str)> = without.variables.iter().map(|v| (v.vr, v.name.as_ref())).collect();
        assert_eq!(got, kept);
        assert_eq!(with.variables.len() - without.variables.len(), 18 + 4 + 2 + 2);
        // the states after the bearing's move up in the state vector, their names stay
        assert_eq!(without.lookup(VR_TWIST).unwrap().slot, Slot::State(1));
        assert_eq!(without.lookup(VR_STATE + 3).unwrap().slot, Slot::State(3));
    }

    #[test]
    fn effects_add_their_parameters_and_states_after_the_rest() {
        let mut p = RigPlant::default();
        let base = Table::of_rig(&p);
        p.effects.actuator_lag_s = 0.004;
        p.effects.compliance_stiffness_nm_per_rad = 2000.0;
        let t = Table::of_rig(&p);
        assert_eq!(t.nx(), base.nx() + 3);
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
        let at = |s: usize| t.states.iter().position(|&x| x == s).unwrap();
        assert_eq!(t.derivative_state[at(10)], None);
        assert_eq!(t.derivative_state[at(12)], None);
        assert_eq!(t.derivative_state[at(0)], Some(at(3)));
    }

    /// Friction brings its three frictions' rows that are on and the smoothing speed, after
    /// every other row; each row reads and writes its own field.
    #[test]
    fn friction_rows_come_last_and_round_trip() {
        let mut r = RigPlant::default();
        let base = Table::of_rig(&r);
        r.effects.coulomb_friction_nm = [0.8, 0.0, 1.1];
        r.effects.friction_smoothing_radps = 0.02;
        let t = Table::of_rig(&r);
        let p = FmuParams::of_rig(r);
        assert_eq!(&t.variables[..base.variables.len()], &base.variables[..]);
        let names: Vec<&str> = t.variables[base.variables.len()..].iter().map(|v| v.name.as_ref()).collect();
        assert_eq!(names, ["m2.coulomb_friction", "m3.coulomb_friction", "friction_smoothing_speed"]);
        let mut values = parameter_values(&p);
        values[rig_parameter("m3.coulomb_friction").unwrap()] = 2.5;
        values[rig_parameter("j_drive").unwrap()] = 0.6;
        let back = parameter_set(&p, &values, 1).unwrap();
        let rig = back.plant.rig().unwrap();
        assert_eq!(rig.effects.coulomb_friction_nm, [0.8, 0.0, 2.5]);
        assert_eq!(rig.effects.friction_smoothing_radps, 0.02);
        assert_eq!(rig.powertrain.j_drive, 0.6);
        assert_eq!(parameter_values(&back), values);
    }

    #[test]
    fn parameters_round_trip() {
        let mut r = RigPlant::default();
        r.effects.backlash_rad = 0.002;
        let p = FmuParams::of_rig(r.clone());
        let back = parameter_set(&p, &parameter_values(&p), variant_number(r.variant)).unwrap();
        assert_eq!(parameter_values(&back), parameter_values(&p));
        let back = back.plant.rig().unwrap();
        assert_eq!(back.effects, r.effects);
        let a = r.powertrain.open_differential(r.variant).unwrap().stiffness_matrix();
        let b = back.powertrain.open_differential(back.variant).unwrap().stiffness_matrix();
        assert!((a - b).norm() < 1e-9);
    }
}
