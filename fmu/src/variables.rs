//! The one variable table. Both modelDescription.xml files, the value-reference map of the
//! instances and the instantiation token are generated from it, so they cannot disagree.

use crate::params::FmuParams;

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
}

/// One row of the table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Variable {
    /// Value reference (unique over all types).
    pub vr: u32,
    /// Name (structured naming convention).
    pub name: &'static str,
    /// Type.
    pub kind: Kind,
    /// Causality.
    pub causality: Causality,
    /// Storage.
    pub slot: Slot,
    /// Unit name (declared in the unit definitions).
    pub unit: &'static str,
    /// Description.
    pub description: &'static str,
}

/// Float parameters: (name, unit, description, constraint), in [`Slot::Param`] order.
pub const PARAMETERS: [(&str, &str, &str, Constraint); 29] = [
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
];

/// Continuous states: (name, unit, description); the speeds are the angles' derivatives.
pub const STATES: [(&str, &str, &str); 10] = [
    ("phi_m2", "rad", "angle of load machine M2"),
    ("phi_drive", "rad", "angle of the drive (differential cage)"),
    ("phi_m3", "rad", "angle of load machine M3"),
    ("w_m2", "rad/s", "speed of load machine M2"),
    ("w_drive", "rad/s", "speed of the drive"),
    ("w_m3", "rad/s", "speed of load machine M3"),
    ("bearing.x", "m", "bearing displacement x"),
    ("bearing.y", "m", "bearing displacement y"),
    ("bearing.vx", "m/s", "bearing velocity x"),
    ("bearing.vy", "m/s", "bearing velocity y"),
];

/// States that are the derivative of another state: (state, its derivative state).
pub const STATE_DERIVATIVES: [(usize, usize); 5] = [(0, 3), (1, 4), (2, 5), (6, 8), (7, 9)];

/// Computed derivatives: (state index, name, unit).
pub const DERIVATIVES: [(usize, &str, &str); 5] = [
    (3, "der(w_m2)", "rad/s2"),
    (4, "der(w_drive)", "rad/s2"),
    (5, "der(w_m3)", "rad/s2"),
    (8, "der(bearing.vx)", "m/s2"),
    (9, "der(bearing.vy)", "m/s2"),
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

/// First value reference of each group.
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

/// The whole table, in modelDescription order.
pub fn table() -> Vec<Variable> {
    let mut v = vec![Variable {
        vr: 0,
        name: "time",
        kind: Kind::Float64,
        causality: Causality::Independent,
        slot: Slot::Time,
        unit: "s",
        description: "simulation time",
    }];
    for (i, &(name, unit, description, _)) in PARAMETERS.iter().enumerate() {
        v.push(Variable {
            vr: VR_PARAM + i as u32,
            name,
            kind: Kind::Float64,
            causality: Causality::Parameter,
            slot: Slot::Param(i),
            unit,
            description,
        });
    }
    v.push(Variable {
        vr: VR_VARIANT,
        name: "variant",
        kind: Kind::Int32,
        causality: Causality::Parameter,
        slot: Slot::Variant,
        unit: "",
        description: "rig variant: 1 original, 2 spring both sides, 3 right (M3), 4 left (M2)",
    });
    for (i, &(name, unit, description)) in STATES.iter().enumerate() {
        v.push(Variable {
            vr: VR_STATE + i as u32,
            name,
            kind: Kind::Float64,
            causality: Causality::Output,
            slot: Slot::State(i),
            unit,
            description,
        });
    }
    for (i, &(state, name, unit)) in DERIVATIVES.iter().enumerate() {
        v.push(Variable {
            vr: VR_DERIVATIVE + i as u32,
            name,
            kind: Kind::Float64,
            causality: Causality::Local,
            slot: Slot::Derivative(state),
            unit,
            description: "state derivative",
        });
    }
    for (i, &(name, description)) in TORQUES.iter().enumerate() {
        v.push(Variable {
            vr: VR_TORQUE + i as u32,
            name,
            kind: Kind::Float64,
            causality: Causality::Output,
            slot: Slot::Torque(i),
            unit: "N.m",
            description,
        });
    }
    for (i, &(name, unit, description)) in INPUTS.iter().enumerate() {
        v.push(Variable {
            vr: VR_INPUT + i as u32,
            name,
            kind: Kind::Float64,
            causality: Causality::Input,
            slot: Slot::Input(i),
            unit,
            description,
        });
    }
    v
}

/// The variable with value reference `vr`: value references are the table's indices.
pub fn lookup(vr: u32) -> Option<Variable> {
    static TABLE: std::sync::OnceLock<Vec<Variable>> = std::sync::OnceLock::new();
    TABLE.get_or_init(table).get(vr as usize).copied()
}

/// The float parameters of a parameter set, in [`PARAMETERS`] order.
pub fn parameter_values(p: &FmuParams) -> [f64; 29] {
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
    ]
}

/// The parameter set of float parameters `v` (in [`PARAMETERS`] order) and variant 1..=4.
pub fn parameter_set(v: &[f64; 29], variant: i32) -> Result<FmuParams, String> {
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
        let t = table();
        for (i, v) in t.iter().enumerate() {
            assert_eq!(v.vr as usize, i, "value references are the table's indices");
        }
        for v in &t {
            assert_eq!(lookup(v.vr), Some(*v));
        }
        assert_eq!(lookup(999), None);
    }

    #[test]
    fn parameters_round_trip() {
        let p = FmuParams::default();
        let back = parameter_set(&parameter_values(&p), variant_number(p.variant)).unwrap();
        assert_eq!(parameter_values(&back), parameter_values(&p));
        let a = p.powertrain.open_differential(p.variant).unwrap().stiffness_matrix();
        let b = back.powertrain.open_differential(back.variant).unwrap().stiffness_matrix();
        assert!((a - b).norm() < 1e-9);
    }
}
