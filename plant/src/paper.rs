//! The paper's rig (Hübner & Prokop, Vehicles 2026, 8, 12): Tables A1 and A2, and the
//! parameter sets of Tables 4 and 5. The embedded default of every command.

use crate::chain::Body;
use crate::rig::{AdditionalSpring, Rig, RigChain, RigParams, Variant};

fn body(name: &str, j_1e3_kgm2: f64, c_1e8_nm_per_rad: f64) -> Body {
    Body { name: name.into(), inertia_kgm2: j_1e3_kgm2 * 1e-3, stiffness_nm_per_rad: c_1e8_nm_per_rad * 1e8 }
}

/// Table A1: the 15 bodies from M2 to M3 (J8 and J10 are integrated in J9). Table A1 prints the
/// side shafts as c7 = c11 = 0.0001e8 Nm/rad; their values c7 = 13,254 and c11 = 10,308 Nm/rad
/// are those of Table 1's remarks.
pub fn table_a1() -> Vec<Body> {
    vec![
        body("J1 rotor shaft dynamometer M2", 850.0, 0.0872),
        body("J2 torque sensor", 38.0, 0.0460),
        body("J3 adapter segment 1", 18.8, 7.2907),
        body("J4 adapter segment 2", 0.7, 0.0169),
        body("J5 adapter segment 3", 3.7, 2.7171),
        body("J6 flange of side shaft", 3.4, 0.1408),
        body("J7 side shaft (short)", 0.3, 13_254.0e-8),
        body("J9 drive unit reduced to load axle", 3500.0, 0.7266),
        body("J11 side shaft (long)", 0.4, 10_308.0e-8),
        body("J12 flange of side shaft", 3.4, 0.1408),
        body("J13 adapter segment 3", 3.7, 2.7171),
        body("J14 adapter segment 2", 0.7, 0.0169),
        body("J15 adapter segment 1", 18.8, 7.2907),
        body("J16 torque sensor", 38.0, 0.0460),
        body("J17 rotor shaft dynamometer M3", 850.0, 0.0872),
    ]
}

/// Table A2: the seven segments of the additional spring, from the M2 side (adapter segment 3,
/// J5) to the flange (J6).
pub fn table_a2() -> Vec<Body> {
    vec![
        body("spring segment 1", 3.9, 3.0530),
        body("spring segment 2", 0.1, 0.0035),
        body("spring segment 3", 0.4, 0.0010),
        body("spring segment 4", 0.1, 0.0036),
        body("spring segment 5", 0.4, 0.4165),
        body("spring segment 6", 0.3, 0.0880),
        body("spring segment 7", 3.7, 2.7187),
    ]
}

/// c_TΔ of the additional spring, Nm/rad (section 2.3).
pub const C_DELTA_NM_PER_RAD: f64 = 64_330.0;
/// J1 = J17 of the reduced rig (Table 1), kg m².
pub const J_LOAD_KGM2: f64 = 0.9148;
/// J1Δ with the additional spring on the M2 side (Table 2), kg m².
pub const J_M2_DELTA_KGM2: f64 = 0.9222;
/// J17Δ with the additional spring on the M3 side (Table 2), kg m².
pub const J_M3_DELTA_KGM2: f64 = 0.9225;

/// A parameter set of Table 4: (name, j_drive in kg m², c_short in Nm/rad).
pub const PARAMETER_SETS: [(&str, f64, f64); 3] =
    [("V1/V2", 0.529, 1479.0), ("V1/V4-1", 0.736, 1888.0), ("V1/V4-2", 7.570, 7073.0)];

/// The reduced rig with a drive inertia and short-shaft stiffness, the paper's load inertias and
/// spring, c_long = 7/9 c_short, undamped.
pub fn params(j_drive: f64, c_short: f64) -> RigParams {
    RigParams {
        j_m2_delta: Some(J_M2_DELTA_KGM2),
        j_m3_delta: Some(J_M3_DELTA_KGM2),
        ..RigParams::new(J_LOAD_KGM2, j_drive, J_LOAD_KGM2, c_short, C_DELTA_NM_PER_RAD)
    }
}

/// The paper's V1/V2 set (Table 4) with the side-shaft dampings and load-machine drag declared
/// in the example bundles (`../shared/DATA.md`): d_short 1.12, d_long 0.87 Nm s/rad, drag
/// 0.5 Nm s/rad. The one default parameter set: the model of [`rig`], so of every command
/// that writes or runs the model (the FMUs of `run` and `fmu`, the MPC's plant). The paper
/// gives no damping values; without them a disturbance would ring for ever.
pub fn damped_params() -> RigParams {
    RigParams { d_short: 1.12, d_long: 0.87, load_drag: 0.5, c_long: Some(1479.0 * 7.0 / 9.0), ..params(0.529, 1479.0) }
}

/// The chain of Table A1 with the spring of Table A2 between J5 and J6 on the left and,
/// mirrored, between J12 and J13 on the right.
pub fn chain() -> RigChain {
    RigChain {
        bodies: table_a1(),
        drive: 8,
        short_shaft: 7,
        long_shaft: 9,
        additional_spring: Some(AdditionalSpring { bodies: table_a2(), left_after: 5, right_after: 10 }),
    }
}

/// The embedded default rig: Tables A1/A2 and the V1/V2 parameter set (Table 4).
pub fn rig() -> Rig {
    Rig {
        name: "Hübner & Prokop 2026 powertrain HIL rig (Tables A1, A2; parameter set V1/V2)".into(),
        variant: Variant::V1,
        model: damped_params(),
        chain: Some(chain()),
        bending: None, // the paper gives no geometry of its spring
        bearing: None,
        effects: Default::default(),
    }
}
