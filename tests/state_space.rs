//! The open differential's state space (eqs. 35–38) against the paper's uncondensed model.

use approx::{assert_abs_diff_eq, assert_relative_eq};
use nalgebra::{DMatrix, DVector};
use plant::{paper, Output, Variant};

/// Eq. (28) with J_d2 = J_d3 = ε, q = [φm2, φdrive, φd3, φm3], and eq. (29).
fn uncondensed(jm2: f64, jd: f64, jm3: f64, c2: f64, c3: f64, eps: f64) -> (DMatrix<f64>, DMatrix<f64>) {
    #[rustfmt::skip]
    let j = DMatrix::from_row_slice(4, 4, &[
        jm2, 0.0, 0.0, 0.0,
        0.0, jd + 4.0 * eps, -2.0 * eps, 0.0,
        0.0, -2.0 * eps, 2.0 * eps, 0.0,
        0.0, 0.0, 0.0, jm3,
    ]);
    #[rustfmt::skip]
    let v = DMatrix::from_row_slice(4, 4, &[
        c2, -2.0 * c2, c2, 0.0,
        -2.0 * c2, 4.0 * c2, -2.0 * c2, 0.0,
        c2, -2.0 * c2, c2 + c3, -c3,
        0.0, 0.0, -c3, c3,
    ]);
    (j, v)
}

#[test]
fn damped_shuffle_pole_is_the_limit_of_light_side_gears() {
    // Stiffness-proportional shaft damping D = βV: then the condensation on the massless side
    // gear is exact, and the condensed model's shuffle pole must be the ε → 0 limit of the
    // uncondensed model's. The perturbation is O(ε/J) = 1e-6; tolerance 1e-4 relative.
    let p = paper::params(0.529, 1479.0).with_shaft_damping_ratio(0.03, Variant::V1).unwrap();
    let beta = p.d_short / p.c_short;
    let (j, v) = uncondensed(p.j_m2, p.j_drive, p.j_m3, p.c_short, p.c_long(), 1e-6);
    let jinv = j.try_inverse().unwrap();
    let mut a = DMatrix::zeros(8, 8);
    a.view_mut((0, 4), (4, 4)).fill_with_identity();
    a.view_mut((4, 0), (4, 4)).copy_from(&(-&jinv * &v));
    a.view_mut((4, 4), (4, 4)).copy_from(&(-&jinv * &v * beta));
    let full = plant::damp(&a).unwrap();
    let cond = p.open_differential(Variant::V1).unwrap().state_space(&[]).unwrap().damp().unwrap();
    let shuffle = cond.last().unwrap();
    let near = full
        .iter()
        .min_by(|x, y| (x.natural_hz - shuffle.natural_hz).abs().total_cmp(&(y.natural_hz - shuffle.natural_hz).abs()))
        .unwrap();
    assert_relative_eq!(near.natural_hz, shuffle.natural_hz, max_relative = 1e-4);
    assert_relative_eq!(near.damping_ratio.unwrap(), shuffle.damping_ratio.unwrap(), max_relative = 1e-4);
    assert_relative_eq!(shuffle.damping_ratio.unwrap(), 0.03, max_relative = 1e-9);
}

#[test]
fn side_shaft_torques_follow_eqs_27_and_30() {
    let p = paper::params(0.529, 1479.0);
    let (c2, c3) = (p.c_short, p.c_long());
    let ss = p.open_differential(Variant::V1).unwrap().state_space(&[Output::SpringTorques, Output::Speeds]).unwrap();
    assert_eq!(ss.output_names, ["T_short_side_shaft", "T_long_side_shaft", "w_m2", "w_drive", "w_m3"]);
    let q = [0.013, 0.021, -0.004];
    let w = [1.0, 2.0, 3.0];
    let x = DVector::from_iterator(6, q.iter().chain(&w).copied());
    let y = &ss.c * &x;
    // eq. (30): the massless side gear's angle; eq. (27): the other side gear
    let phi_d3 = (2.0 * q[1] * c2 - q[0] * c2 + q[2] * c3) / (c2 + c3);
    let phi_d2 = 2.0 * q[1] - phi_d3;
    assert_relative_eq!(y[0], c2 * (phi_d2 - q[0]), max_relative = 1e-12);
    assert_relative_eq!(y[1], c3 * (phi_d3 - q[2]), max_relative = 1e-12);
    // an open differential splits the torque equally
    assert_relative_eq!(y[0], y[1], max_relative = 1e-12);
    assert_eq!(y.rows(2, 3).iter().copied().collect::<Vec<_>>(), w);
    // B: a drive torque accelerates the drive alone, M/J (eq. 37)
    let u = DVector::from_vec(vec![0.0, 10.0, 0.0]);
    let xdot = &ss.b * &u;
    assert_abs_diff_eq!(xdot[4], 10.0 / 0.529, epsilon = 1e-12);
    assert_eq!((xdot[3], xdot[5]), (0.0, 0.0));
}

#[test]
fn three_mass_shaft_torque_is_the_twist() {
    let p = paper::params(0.529, 1479.0);
    let ss = p.three_mass(Variant::V4).unwrap().state_space(&[Output::SpringTorques]).unwrap();
    let x = DVector::from_vec(vec![0.01, 0.03, 0.0, 0.0, 0.0, 0.0]);
    let y = &ss.c * &x;
    let c_left = 1479.0 * 64_330.0 / (1479.0 + 64_330.0); // eq. (16)
    assert_relative_eq!(y[0], c_left * 0.02, max_relative = 1e-12);
    assert_relative_eq!(y[1], 1479.0 * 7.0 / 9.0 * 0.03, max_relative = 1e-12);
}

#[test]
fn zoh_step_response_matches_the_modal_solution() {
    // Undamped three-mass V1 under a drive-torque step M: the exact solution is the rigid-body
    // parabola plus the two modes' (1 − cos ωt) terms, q(t) = Σ_k φ_k φ_kᵀ M/(φ_kᵀJφ_k) ·
    // (t²/2 for ω = 0, (1 − cos ω_k t)/ω_k² otherwise) — computed here from the modes alone.
    let p = paper::params(0.529, 1479.0);
    let model = p.three_mass(Variant::V1).unwrap();
    let modes = model.modes().unwrap();
    let ss = model.state_space(&[Output::Angles]).unwrap();
    let (dt, n, m) = (1e-3, 500, 10.0);
    let u = DMatrix::from_fn(n, 3, |_, j| if j == 1 { m } else { 0.0 });
    let y = ss.lsim(&u, dt, &DVector::zeros(6)).unwrap();
    let force = DVector::from_vec(vec![0.0, m, 0.0]);
    for k in [1, 137, 499] {
        let t = k as f64 * dt;
        let mut q = DVector::zeros(3);
        for (f, phi) in modes.frequencies_hz.iter().zip(&modes.shapes) {
            let w = 2.0 * std::f64::consts::PI * f;
            let mk = (phi.transpose() * &model.inertia * phi)[0];
            let g = if *f == 0.0 { t * t / 2.0 } else { (1.0 - (w * t).cos()) / (w * w) };
            q += phi * (phi.dot(&force) / mk * g);
        }
        for i in 0..3 {
            assert_abs_diff_eq!(y[(k, i)], q[i], epsilon = 1e-9 * q.amax().max(1e-6));
        }
    }
}
