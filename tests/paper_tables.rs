//! The paper's published numbers (Hübner & Prokop, Vehicles 2026, 8, 12), reproduced from the
//! paper's own inputs (Tables A1, A2 and the parameter sets of Table 4).
//!
//! Tolerances come from the printed precision:
//! - frequencies printed with two decimals are met within half a unit of the last digit,
//!   0.005 Hz, unless stated otherwise;
//! - Table A1/A2 print inertias to 0.1e-3 kg m², and every reduced inertia collects shares of
//!   several of them: reduced inertias are met within 1e-4 kg m² (two half units);
//! - Table A1 prints stiffnesses with four decimals of 1e8 Nm/rad (±5,000 Nm/rad on every
//!   segment), which moves the reduced side-shaft stiffness by up to 0.01 %;
//! - Table A2's spring segment 3 is printed as 0.0010e8 Nm/rad (±5 %), and it holds most of the
//!   spring's compliance: Table 2's stiffnesses and frequencies agree to about 0.2 % only.

use approx::assert_abs_diff_eq;
use plant::{paper, reduce, ModeKind, Variant};

const HZ_PRINTED: f64 = 0.005;
const J_PRINTED: f64 = 1e-4;

#[test]
fn table_a1_chain_has_f2_17_59_and_f3_22_47_with_the_paper_mode_shapes() {
    let (chain, layout) = paper::chain().chain(Variant::V1).unwrap();
    assert_eq!(chain.len(), 15);
    let modes = chain.mechanical().modes().unwrap();
    assert_eq!(modes.frequencies_hz[0], 0.0);
    assert_abs_diff_eq!(modes.frequencies_hz[1], 17.59, epsilon = HZ_PRINTED);
    assert_abs_diff_eq!(modes.frequencies_hz[2], 22.47, epsilon = HZ_PRINTED);
    // Figure 4: vector 2 is the outputs against each other, vector 3 the shuffle; the rest lie
    // above 1000 Hz (section 2.2).
    let kinds = modes.kinds(&layout);
    assert_eq!(kinds[..3], [ModeKind::RigidBody, ModeKind::OutputsAntiphase, ModeKind::Shuffle]);
    assert!(modes.frequencies_hz[3] > 1000.0, "{:?}", modes.frequencies_hz);
}

#[test]
fn table_1_reduction_to_three_masses() {
    let (chain, layout) = paper::chain().chain(Variant::V1).unwrap();
    let r = reduce(&chain, 3).unwrap();
    let j = &r.chain.inertias_kgm2;
    let c = &r.chain.stiffnesses_nm_per_rad;
    assert_abs_diff_eq!(j[0], 0.9148, epsilon = J_PRINTED);
    assert_abs_diff_eq!(j[1], 3.5003, epsilon = J_PRINTED);
    assert_abs_diff_eq!(j[2], 0.9148, epsilon = J_PRINTED);
    assert_abs_diff_eq!(c[0], 13_093.0, epsilon = 13_093.0 * 1e-4);
    assert_abs_diff_eq!(c[1], 10_211.0, epsilon = 10_211.0 * 1e-4);
    // The sum of inertias is kept exactly (text after eq. (12)).
    assert_abs_diff_eq!(r.chain.total_inertia_kgm2(), chain.total_inertia_kgm2(), epsilon = 1e-12);
    let modes = r.chain.mechanical().modes().unwrap();
    assert_abs_diff_eq!(modes.frequencies_hz[1], 17.59, epsilon = HZ_PRINTED);
    assert_abs_diff_eq!(modes.frequencies_hz[2], 22.46, epsilon = HZ_PRINTED);
    // The reduced masses still stand for M2, the drive and M3; mode 3 is still the shuffle.
    let reduced_layout = paper::chain().reduced_layout(&layout, &r.chain).unwrap();
    assert_eq!(reduced_layout.drive, Some(1));
    assert_eq!(modes.shuffle_mode(&reduced_layout), Some(2));
}

#[test]
fn table_2_additional_spring_on_both_sides() {
    let (chain, layout) = paper::chain().chain(Variant::V2).unwrap();
    assert_eq!(chain.len(), 29);
    let r = reduce(&chain, 3).unwrap();
    let j = &r.chain.inertias_kgm2;
    let c = &r.chain.stiffnesses_nm_per_rad;
    assert_abs_diff_eq!(j[0], 0.9222, epsilon = J_PRINTED);
    assert_abs_diff_eq!(j[1], 3.5030, epsilon = J_PRINTED);
    assert_abs_diff_eq!(j[2], 0.9225, epsilon = J_PRINTED);
    assert_abs_diff_eq!(c[0], 10_861.0, epsilon = 10_861.0 * 2e-3);
    assert_abs_diff_eq!(c[1], 8_801.0, epsilon = 8_801.0 * 2e-3);
    let f = r.chain.mechanical().modes().unwrap().frequencies_hz;
    assert_abs_diff_eq!(f[1], 16.18, epsilon = 16.18 * 2e-3);
    assert_abs_diff_eq!(f[2], 20.50, epsilon = 20.50 * 2e-3);
    // the full 29-mass chain too
    let full = chain.mechanical().modes().unwrap();
    assert_abs_diff_eq!(full.frequencies_hz[1], 16.18, epsilon = 16.18 * 2e-3);
    assert_abs_diff_eq!(full.frequencies_hz[2], 20.50, epsilon = 20.50 * 2e-3);
    assert_eq!(full.shuffle_mode(&layout), Some(2));
}

/// Table 5: (parameter set, [[f2, f3] for V1, V2, V3, V4]).
const TABLE_5: [(&str, [[f64; 2]; 4]); 3] = [
    ("V1/V2", [[5.97, 12.77], [5.89, 12.62], [5.93, 12.72], [5.93, 12.67]]),
    ("V1/V4-1", [[6.74, 12.77], [6.63, 12.59], [6.68, 12.71], [6.69, 12.65]]),
    ("V1/V4-2", [[12.77, 15.07], [12.19, 14.28], [12.26, 15.01], [12.65, 14.39]]),
];
/// Table 5, first row: the measured natural frequencies of V1–V4.
const MEASURED_HZ: [f64; 4] = [12.77, 12.62, 12.67, 12.65];

#[test]
fn table_5_three_mass_frequencies_of_all_variants() {
    for (set, rows) in TABLE_5 {
        let &(_, j_drive, c_short) = paper::PARAMETER_SETS.iter().find(|p| p.0 == set).unwrap();
        let p = paper::params(j_drive, c_short);
        for (variant, want) in Variant::ALL.into_iter().zip(rows) {
            let model = p.three_mass(variant).unwrap();
            let modes = model.modes().unwrap();
            let f = &modes.frequencies_hz;
            for k in 0..2 {
                // the issue asks for 0.01 Hz; the printed precision allows 0.005 + rounding of inputs
                assert_abs_diff_eq!(f[k + 1], want[k], epsilon = 0.01);
            }
            // The shuffle is always the third mode (f3) of the smooth strand ...
            let layout = model.layout.unwrap();
            assert_eq!(modes.shuffle_mode(&layout), Some(2), "{set} {variant}");
        }
    }
}

#[test]
fn table_5_only_v1_v4_2_places_the_measurement_off_the_shuffle_mode() {
    // ... and the paper's check (section 3): the measured frequency must be the shuffle
    // frequency. V1/V4-2 meets 12.77 Hz of V1 with its antiphase mode f2 instead.
    for (set, j_drive, c_short) in paper::PARAMETER_SETS {
        let p = paper::params(j_drive, c_short);
        let model = p.three_mass(Variant::V1).unwrap();
        let modes = model.modes().unwrap();
        let nearest = (0..3)
            .min_by(|&a, &b| {
                (modes.frequencies_hz[a] - MEASURED_HZ[0])
                    .abs()
                    .total_cmp(&(modes.frequencies_hz[b] - MEASURED_HZ[0]).abs())
            })
            .unwrap();
        let kind = modes.kinds(&model.layout.unwrap())[nearest];
        if set == "V1/V4-2" {
            assert_eq!(kind, ModeKind::OutputsAntiphase);
        } else {
            assert_eq!(kind, ModeKind::Shuffle, "{set}");
        }
    }
}

#[test]
fn figure_14_open_differential_and_smooth_strand() {
    let p = paper::params(0.529, 1479.0);
    let diff = p.open_differential(Variant::V1).unwrap();
    let m = diff.modes().unwrap();
    assert_eq!(m.frequencies_hz[..2], [0.0, 0.0]);
    assert_abs_diff_eq!(m.frequencies_hz[2], 12.64, epsilon = HZ_PRINTED);
    let kinds = m.kinds(&diff.layout.unwrap());
    assert_eq!(kinds, vec![ModeKind::RigidBody, ModeKind::OutputsAntiphase, ModeKind::Shuffle]);
    // The zero-frequency antiphase mode of the outputs (J_m2 = J_m3): [1, 0, -1].
    assert_abs_diff_eq!(m.shapes[1][1], 0.0, epsilon = 1e-9);
    assert_abs_diff_eq!(m.shapes[1][0], -m.shapes[1][2], epsilon = 1e-9);

    let smooth = p.three_mass(Variant::V1).unwrap().modes().unwrap();
    assert_abs_diff_eq!(smooth.frequencies_hz[1], 5.97, epsilon = HZ_PRINTED);
    assert_abs_diff_eq!(smooth.frequencies_hz[2], 12.77, epsilon = HZ_PRINTED);
}

#[test]
fn state_space_poles_agree_with_the_symmetric_eigensolver() {
    // Two independent routes (real Schur of A vs Cholesky + symmetric eigen of (J, C)), and
    // the analytic damping ratios of stiffness-proportional damping, ζ_k = β ω_k / 2.
    let p = paper::params(0.529, 1479.0);
    for variant in Variant::ALL {
        let model = p.three_mass(variant).unwrap();
        let f = model.modes().unwrap().frequencies_hz;
        let poles = model.state_space(&[]).unwrap().damp().unwrap();
        let osc: Vec<f64> = poles.iter().filter(|p| p.natural_hz > 0.0).map(|p| p.natural_hz).collect();
        assert_eq!(osc.len(), 2);
        assert_abs_diff_eq!(osc[0], f[1], epsilon = 1e-9 * f[2]);
        assert_abs_diff_eq!(osc[1], f[2], epsilon = 1e-9 * f[2]);
    }
    let beta = 1e-3; // s
    let damped = plant::RigParams { d_short: beta * p.c_short, d_long: beta * p.c_long(), ..p.clone() };
    let model = damped.three_mass(Variant::V1).unwrap();
    let f = model.modes().unwrap().frequencies_hz;
    let poles = model.state_space(&[]).unwrap().damp().unwrap();
    let osc: Vec<_> = poles.iter().filter(|p| p.natural_hz > 0.0).collect();
    for (pole, fk) in osc.iter().zip(&f[1..]) {
        let w = 2.0 * std::f64::consts::PI * fk;
        assert_abs_diff_eq!(pole.natural_hz, *fk, epsilon = 1e-9 * fk);
        assert_abs_diff_eq!(pole.damping_ratio.unwrap(), beta * w / 2.0, epsilon = 1e-9);
    }
}
