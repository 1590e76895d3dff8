//! A drive model's one-step-ahead predictor (the prediction-error method: Ljung, *System
//! Identification*, 2nd ed., ch. 7): the model stepped as [`Dynamics::simulate_flat_from`] steps
//! it — its plays, frictions, dead times and lags included — with its state corrected after each
//! sample toward the measured outputs by the steady-state Kalman gain of its linear part (every
//! play closed, no friction). Sample k's prediction has seen the measurement up to k − 1.
//!
//! Why: the error of a simulation over a whole record does not measure what happens where
//! nothing holds the bodies together. Inside a play that rattles about zero torque, the input
//! sensor's noise, integrated twice, moves where the bodies are and so when they strike; the
//! truth itself, simulated from the recorded input, then errs 0.3–0.9 where the record's noise
//! floor is 0.001–0.004, and that error has no minimum at the true play. The predictor restarts
//! from the measurement at every sample, and its error has (docs/validation.md, step 14).
//!
//! The gain is computed in the stepped coordinates of [`crate::stepper::coordinates`] without the
//! line's rigid-body positions, which no speed or force measures (unless an output is a
//! position): twists, speeds and lagged inputs, z = S x. The process noise is the inputs' noise
//! held over a sample (Γ diag(σ_u²) Γᵀ), the measurement noise each output's own (diag(σ_y²)).

use nalgebra::DMatrix;

use crate::error::{PlantError, Result};
use crate::line::Quantity;
use crate::riccati::dare;
use crate::statespace::zoh;
use crate::stepper::{coordinates, Coordinate};
use crate::{DriveModel, Dynamics};

/// The noise a predictor's gain is built for: standard deviations in the signals' units.
#[derive(Debug, Clone, PartialEq)]
pub struct Noise {
    /// Each input's noise, held over a sample (≥ 0).
    pub inputs_sd: Vec<f64>,
    /// A torque (force) on every body that the model lacks (≥ 0).
    pub disturbance_sd: f64,
    /// Each output's noise (> 0).
    pub outputs_sd: Vec<f64>,
}

/// The steady-state Kalman gain of a drive model for its sampled outputs.
#[derive(Debug, Clone)]
pub struct Predictor {
    /// L (states × outputs): after sample k the state moves by L (y_k − ŷ_k).
    pub gain: DMatrix<f64>,
}

impl DriveModel {
    /// The one-step-ahead prediction of the `outputs` from rest as [`DriveModel::simulate_flat`]
    /// starts (every body at `initial_speed` of the first), held to the `measured` outputs (one
    /// signal per output, as long as the inputs) by the gain of [`Predictor::new`] for `noise`:
    /// [`Dynamics::predict_flat_from`].
    pub fn predict_flat(
        &self,
        inputs: &[Vec<f64>],
        dt_s: f64,
        initial_speed: f64,
        outputs: &[(Quantity, usize)],
        measured: &[Vec<f64>],
        noise: &Noise,
    ) -> Result<Vec<f64>> {
        // a structural effect (a compliance splitting a body) written into the line: the
        // predictor's disturbances and outputs are over the bodies the dynamics have
        let m = self.resolved()?;
        let d = Dynamics::new(&m)?;
        let p = Predictor::of(&m, &d, dt_s, outputs, noise)?;
        let signals: Vec<&[f64]> = inputs.iter().map(Vec::as_slice).collect();
        let measured: Vec<&[f64]> = measured.iter().map(Vec::as_slice).collect();
        d.predict_flat_from(d.record_start(inputs, initial_speed), &signals, dt_s, outputs, &measured, &p.gain)
    }
}

impl Predictor {
    /// The gain of model `m` sampled every `dt_s` for `outputs` and `noise`.
    pub fn new(m: &DriveModel, dt_s: f64, outputs: &[(Quantity, usize)], noise: &Noise) -> Result<Predictor> {
        let m = m.resolved()?;
        Predictor::of(&m, &Dynamics::new(&m)?, dt_s, outputs, noise)
    }

    /// [`Predictor::new`] with `d` the dynamics of `m`.
    fn of(m: &DriveModel, d: &Dynamics, dt_s: f64, outputs: &[(Quantity, usize)], noise: &Noise) -> Result<Predictor> {
        let Noise { inputs_sd: input_sd, disturbance_sd, outputs_sd: output_sd } = noise;
        let disturbance_sd = *disturbance_sd;
        let (ns, nu, ny) = (d.nstates(), d.ninputs(), outputs.len());
        if input_sd.len() != nu || input_sd.iter().any(|s| !(s.is_finite() && *s >= 0.0)) {
            return Err(PlantError::Invalid(format!("one finite input noise ≥ 0 per input ({nu})")));
        }
        if !(disturbance_sd.is_finite() && disturbance_sd >= 0.0) {
            return Err(PlantError::Invalid(format!("disturbance noise {disturbance_sd}")));
        }
        if output_sd.len() != ny || output_sd.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(PlantError::Invalid(format!("one finite output noise > 0 per output ({ny})")));
        }
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(PlantError::Invalid(format!("sample time {dt_s} s")));
        }
        let (a, b) = d.linear();
        let c = output_rows(m, d, outputs)?;
        let (s, s_inv) = observed_coordinates(m, ns, outputs)?;
        let n = m.line.bodies.len();
        // the inputs, then a torque on every body (what the model lacks: its effects' forces
        // beyond the linear part, a mechanics error)
        let mut b_all = DMatrix::zeros(ns, nu + n);
        b_all.columns_mut(0, nu).copy_from(&b);
        for j in 0..n {
            b_all[(n + j, nu + j)] = 1.0 / m.line.bodies[j].inertia;
        }
        let (a_r, b_r, c_r) = (&s * &a * &s_inv, &s * &b_all, &c * &s_inv);
        let (phi, gamma) = zoh(&a_r, &b_r, dt_s)?;
        let nr = phi.nrows();
        let variances = input_sd.iter().map(|s| s * s).chain(std::iter::repeat_n(disturbance_sd * disturbance_sd, n));
        let mut q =
            &gamma * DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(nu + n, variances)) * gamma.transpose();
        // a floor far below the noise keeps every mode's covariance defined (a mode nothing
        // reaches, which the Riccati equation must still see as detectable)
        let floor = 1e-12 * (q.trace() / nr as f64).max(f64::MIN_POSITIVE);
        for i in 0..nr {
            q[(i, i)] += floor;
        }
        let r = DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(ny, output_sd.iter().map(|s| s * s)));
        // the filter's Riccati equation is the control one of (Φᵀ, Cᵀ); P the prior covariance
        let p = dare(&phi.transpose(), &c_r.transpose(), &q, &r)?.x;
        let innovation = &c_r * &p * c_r.transpose() + &r;
        let l_r = innovation
            .cholesky()
            .ok_or_else(|| PlantError::Numerical("predictor: C P Cᵀ + R is not positive definite".into()))?
            .solve(&(&c_r * &p))
            .transpose();
        let gain = &s_inv * l_r;
        if !gain.iter().all(|v| v.is_finite()) {
            return Err(PlantError::Numerical("predictor: the gain is not finite".into()));
        }
        Ok(Predictor { gain })
    }
}

/// The outputs' rows over the model's states: a position or speed read off, a coupling's force
/// in contact (c·eᵀq + d·eᵀq̇).
fn output_rows(m: &DriveModel, d: &Dynamics, outputs: &[(Quantity, usize)]) -> Result<DMatrix<f64>> {
    let (ns, n) = (d.nstates(), m.line.bodies.len());
    let forces = m.coupling_forces(ns);
    let mut c = DMatrix::zeros(outputs.len(), ns);
    for (i, &(q, at)) in outputs.iter().enumerate() {
        match q {
            Quantity::Position if at < n => c[(i, at)] = 1.0,
            Quantity::Speed if at < n => c[(i, n + at)] = 1.0,
            Quantity::CouplingForce if at < forces.nrows() => c.set_row(i, &forces.row(at)),
            _ => return Err(PlantError::Invalid(format!("output {q:?} of element {} is outside the line", at + 1))),
        }
    }
    Ok(c)
}

/// S (z = S x: the twists, then the speeds and lagged inputs) and its right inverse S⁺ (x = S⁺ z
/// moves no rigid-body position); S = I where an output measures a position.
fn observed_coordinates(
    m: &DriveModel,
    ns: usize,
    outputs: &[(Quantity, usize)],
) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
    let n = m.line.bodies.len();
    if outputs.iter().any(|o| o.0 == Quantity::Position) {
        return Ok((DMatrix::identity(ns, ns), DMatrix::identity(ns, ns)));
    }
    let (chosen, p) = coordinates(m)?;
    let twists: Vec<usize> = (0..chosen.len()).filter(|&i| matches!(chosen[i], Coordinate::Twist(_))).collect();
    let k = twists.len();
    let p_tw = DMatrix::from_fn(k, n, |i, j| p[(twists[i], j)]);
    // the twists' rows are independent (`coordinates`): P_tw P_twᵀ is invertible
    let p_tw_inv = match (&p_tw * p_tw.transpose()).try_inverse() {
        Some(g) => p_tw.transpose() * g,
        None if k == 0 => DMatrix::zeros(n, 0),
        None => return Err(PlantError::Numerical("predictor: the twists are not independent".into())),
    };
    let nr = k + ns - n;
    let mut s = DMatrix::zeros(nr, ns);
    let mut s_inv = DMatrix::zeros(ns, nr);
    s.view_mut((0, 0), (k, n)).copy_from(&p_tw);
    s_inv.view_mut((0, 0), (n, k)).copy_from(&p_tw_inv);
    for i in 0..ns - n {
        s[(k + i, n + i)] = 1.0;
        s_inv[(n + i, k + i)] = 1.0;
    }
    Ok((s, s_inv))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::line::{Coupling, Domain, Line, LineBody};
    use crate::Effect;

    fn noise(inputs_sd: &[f64], disturbance_sd: f64, outputs_sd: &[f64]) -> Noise {
        Noise { inputs_sd: inputs_sd.to_vec(), disturbance_sd, outputs_sd: outputs_sd.to_vec() }
    }

    fn one_body(inertia: f64, drag: f64) -> DriveModel {
        DriveModel {
            line: Line {
                domain: Domain::Rotational,
                bodies: vec![LineBody { name: "b".into(), inertia, drag }],
                couplings: vec![],
            },
            inputs: vec![0],
            effects: Vec::<Effect>::new(),
        }
    }

    /// One body with drag, driven by a torque, its speed measured: the scalar filter Riccati
    /// equation p = Φ² p R/(p + R) + Q has the positive root of p² + (R(1 − Φ²) − Q) p − Q R = 0,
    /// the gain is l = p/(p + R), and the predictor is w⁺ = w + l (y − w), w_{k+1} = Φ w⁺ + Γ u_k
    /// with Φ = e^{−d h/J}, Γ = (1 − Φ)/d: written out here, against the model's predictor to
    /// rounding.
    #[test]
    fn a_body_with_drag_is_predicted_as_the_scalar_kalman_filter() {
        let (j, d, h) = (0.2, 0.5, 1e-3);
        let (su, sy) = (0.3, 0.02);
        let m = one_body(j, d);
        let outputs = [(Quantity::Speed, 0)];
        let pred = Predictor::new(&m, h, &outputs, &noise(&[su], 0.0, &[sy])).unwrap();
        let phi = (-d * h / j).exp();
        let gamma = (1.0 - phi) / d;
        let (q, r) = (gamma * gamma * su * su, sy * sy);
        let bq = r * (1.0 - phi * phi) - q;
        let p = (-bq + (bq * bq + 4.0 * q * r).sqrt()) / 2.0;
        let l = p / (p + r);
        // the floor on Q (1e-12 of it) moves the gain by far less than this
        approx::assert_relative_eq!(pred.gain[(1, 0)], l, max_relative = 1e-9);
        assert_eq!(pred.gain[(0, 0)], 0.0, "the rigid-body position is not corrected");

        let len = 400;
        let u: Vec<f64> = (0..len).map(|k| (k as f64 * 0.05).sin() + 0.3).collect();
        let y: Vec<f64> = (0..len).map(|k| 0.4 * (k as f64 * 0.031).cos() + 0.01 * ((k * 7919) % 13) as f64).collect();
        let dynamics = Dynamics::new(&m).unwrap();
        let predicted = dynamics.predict_flat_from(vec![0.0, 0.0], &[&u], h, &outputs, &[&y], &pred.gain).unwrap();
        let mut w = 0.0;
        for k in 0..len {
            approx::assert_relative_eq!(predicted[k], w, max_relative = 1e-10, epsilon = 1e-13);
            let corrected = w + l * (y[k] - w);
            w = phi * corrected + gamma * u[k];
        }
    }

    /// Two bodies on a coupling, speeds measured: the gain moves the twist (both positions, in
    /// opposite directions by the pseudo-inverse of the elongation [−1, 1]) and never the rigid
    /// position (their mean); a prediction with output noise far above the signals is the
    /// simulation.
    #[test]
    fn the_gain_moves_twists_not_the_rigid_position() {
        let line = Line {
            domain: Domain::Rotational,
            bodies: vec![
                LineBody { name: "a".into(), inertia: 0.1, drag: 0.01 },
                LineBody { name: "b".into(), inertia: 0.3, drag: 0.02 },
            ],
            couplings: vec![Coupling::new(2000.0, 0.5, 1.0)],
        };
        let m = DriveModel { line, inputs: vec![0], effects: vec![] };
        let outputs = [(Quantity::Speed, 0), (Quantity::Speed, 1)];
        let pred = Predictor::new(&m, 1e-3, &outputs, &noise(&[0.5], 0.01, &[1e-3, 1e-3])).unwrap();
        for o in 0..2 {
            let (ga, gb) = (pred.gain[(0, o)], pred.gain[(1, o)]);
            assert!(ga.abs() > 1e-9, "output {o} corrects the twist");
            approx::assert_relative_eq!(ga, -gb, max_relative = 1e-9);
        }
        let quiet = Predictor::new(&m, 1e-3, &outputs, &noise(&[0.5], 0.01, &[1e9, 1e9])).unwrap();
        let u: Vec<f64> = (0..300).map(|k| (k as f64 * 0.02).sin()).collect();
        let y = vec![5.0; 300];
        let d = Dynamics::new(&m).unwrap();
        let x0 = vec![0.0; d.nstates()];
        let simulated = d.simulate_flat_from(x0.clone(), &[&u], 1e-3, &outputs).unwrap();
        let predicted = d.predict_flat_from(x0, &[&u], 1e-3, &outputs, &[&y, &y], &quiet.gain).unwrap();
        for (a, b) in simulated.iter().zip(&predicted) {
            assert!((a - b).abs() <= 1e-9 * a.abs().max(1.0), "{a} against {b}");
        }
    }

    /// A compliance inside a body is structure: its predictor is that of the same line split by
    /// hand — the body's part that its coupling joins, the motor part (appended last) that the
    /// input drives, a spring between them on φ_motor − φ_body — gain for gain, and its
    /// predictions over a record are the hand-split line's. (The predictor once counted the
    /// bodies of the line as declared, one short of the dynamics' states.)
    #[test]
    fn a_compliance_is_predicted_as_the_line_split_by_hand() {
        let (jm, jl, k1, k2, share, d2) = (0.02, 0.5, 3000.0, 900.0, 0.3, 0.4);
        let motor = |inertia| LineBody { name: "motor".into(), inertia, drag: 1e-3 };
        let load = LineBody { name: "load".into(), inertia: jl, drag: 2e-3 };
        let declared = DriveModel {
            line: Line {
                domain: Domain::Rotational,
                bodies: vec![motor(jm), load.clone()],
                couplings: vec![Coupling::new(k1, 0.6, 1.0)],
            },
            inputs: vec![0],
            effects: vec![crate::Compliance { body: 0, stiffness: k2, motor_share: share, damping: Some(d2) }.into()],
        };
        let split = DriveModel {
            line: Line {
                domain: Domain::Rotational,
                bodies: vec![
                    motor((1.0 - share) * jm),
                    load,
                    LineBody { name: "motor_motor".into(), inertia: share * jm, drag: 0.0 },
                ],
                couplings: vec![
                    Coupling { elongation: Some(vec![1.0, -1.0, 0.0]), ..Coupling::new(k1, 0.6, 1.0) },
                    Coupling { elongation: Some(vec![-1.0, 0.0, 1.0]), ..Coupling::new(k2, d2, 1.0) },
                ],
            },
            inputs: vec![2],
            effects: vec![],
        };
        let outputs = [(Quantity::Speed, 0), (Quantity::Speed, 1)];
        let n = noise(&[0.5], 0.01, &[1e-3, 2e-3]);
        let (a, b) = (
            Predictor::new(&declared, 1e-3, &outputs, &n).unwrap(),
            Predictor::new(&split, 1e-3, &outputs, &n).unwrap(),
        );
        assert_eq!(a.gain.shape(), (6, 2));
        approx::assert_relative_eq!(a.gain, b.gain, max_relative = 1e-9, epsilon = 1e-12);
        let u: Vec<f64> = (0..500).map(|k| (k as f64 * 0.03).sin()).collect();
        let y: Vec<f64> = (0..500).map(|k| 0.2 * (k as f64 * 0.011).cos()).collect();
        let run = |m: &DriveModel| {
            m.predict_flat(std::slice::from_ref(&u), 1e-3, 0.0, &outputs, &[y.clone(), y.clone()], &n).unwrap()
        };
        let (pa, pb) = (run(&declared), run(&split));
        for (p, q) in pa.iter().zip(&pb) {
            assert!((p - q).abs() <= 1e-9 * p.abs().max(1e-3), "{p} against {q}");
        }
    }
}
