//! The paper's rig as a preset of the one drive model: [`DriveModel::paper_rig`] builds it from
//! the reduced parameters, the variant and the effects a rig file names ([`DriveEffects`]);
//! [`Dynamics::paper_rig`] steps it as its records are sampled; [`Stepper::paper_rig`] gives it
//! the FMU's twist coordinates; [`record_start`] and [`simulate_record`] are the torsional
//! record as the diagnosis simulates it (the drive torque the only input). No I/O.

use crate::drive::{ActuatorLag, Backlash, Compliance, CoulombFriction, DriveModel, Dynamics, Effect, TimeDelay};
use crate::error::{PlantError, Result};
use crate::integrate::RK4_STEP_TIMES_RATE;
use crate::line::{Coupling, Domain, Line, LineBody, Quantity};
use crate::mechanical::{Layout, MechanicalModel};
use crate::rig::{DriveEffects, RigParams, Variant};
use crate::stepper::Stepper;
use nalgebra::DMatrix;

/// The sample time of the rig's records, s (1 kHz): its integrator steps as they are sampled.
pub const RIG_SAMPLE_S: f64 = 1e-3;

/// Largest integration step across the play, s: an eighth of [`RIG_SAMPLE_S`]
/// ([`crate::drive::FINE_PER_COARSE`]). Contact switching makes the response sensitive to the
/// step: 4 sub-steps per ms left twice the misfit at the true play.
pub const BACKLASH_STEP_S: f64 = RIG_SAMPLE_S / crate::drive::FINE_PER_COARSE;

impl DriveModel {
    /// The paper's rig in `variant` with `effects` as a drive model: bodies `m2`, `drive` (the
    /// differential's cage), `m3` and, with a compliance, `motor` (the drive's inertia split,
    /// `compliance_motor_fraction` of it on the motor); couplings `short_side_shaft` and
    /// `long_side_shaft` on the open differential's twist s = 2φ_drive − φ_m2 − φ_m3, each on its
    /// share of it (eq. (A1): c_r/(c_l + c_r) s and c_l/(c_l + c_r) s, so the pair's stiffness on
    /// s is c_l c_r/(c_l + c_r)), and `drive_compliance` on φ_motor − φ_drive with the shafts'
    /// stiffness-proportional damping; inputs M_m2, the drive torque (on the motor when
    /// compliant), M_m3. The effects: the dead time and lag of the drive torque, the play on
    /// both shafts so that they open together at |s| = `backlash_rad`, the machines' friction.
    pub fn paper_rig(rig: &RigParams, variant: Variant, effects: &DriveEffects) -> Result<DriveModel> {
        effects.validate()?;
        let e = rig.effective(variant)?;
        let (cl, cr) = (e.c_left, e.c_right);
        let (share_l, share_r) = (cr / (cl + cr), cl / (cl + cr));
        let body = |name: &str, inertia: f64, drag: f64| LineBody { name: name.into(), inertia, drag };
        let bodies =
            vec![body("m2", e.j_m2, e.load_drag), body("drive", e.j_drive, 0.0), body("m3", e.j_m3, e.load_drag)];
        let shaft = |name: &str, share: f64, c: f64, d: f64| {
            let el: Vec<f64> = [-1.0, 2.0, -1.0].iter().map(|a| a * share).collect();
            Coupling { name: Some(name.into()), elongation: Some(el), ..Coupling::new(c, d, 1.0) }
        };
        let couplings =
            vec![shaft("short_side_shaft", share_l, cl, e.d_left), shaft("long_side_shaft", share_r, cr, e.d_right)];
        let mut list = Vec::new();
        if effects.time_delay_s > 0.0 {
            list.push(Effect::TimeDelay(TimeDelay { input: 1, delay_s: effects.time_delay_s }));
        }
        if effects.actuator_lag_s > 0.0 {
            list.push(Effect::ActuatorLag(ActuatorLag { input: 1, time_constant_s: effects.actuator_lag_s }));
        }
        if effects.backlash_rad > 0.0 {
            for (k, share) in [share_l, share_r].into_iter().enumerate() {
                list.push(Effect::Backlash(Backlash { coupling: k, backlash: 2.0 * share * effects.backlash_rad }));
            }
        }
        for (b, &friction) in effects.coulomb_friction_nm.iter().enumerate() {
            if friction > 0.0 {
                list.push(Effect::CoulombFriction(CoulombFriction {
                    body: b,
                    friction,
                    smoothing_speed: effects.friction_smoothing_radps,
                }));
            }
        }
        // the drive's compliance splits the drive (its torque and friction go to the motor part)
        // with the side shafts' damping ratio on s, d_s/c_s (section 4.3): the general rule's
        // D_bb/K_bb, written as the rig has always computed it — the torsional search follows
        // the last digits (the other rounding of the same ratio moved two of its tests'
        // answers)
        let compliant = effects.compliance_stiffness_nm_per_rad > 0.0;
        if compliant {
            let k = effects.compliance_stiffness_nm_per_rad;
            let c_s = cl * share_l;
            let d_s = e.d_left * share_l.powi(2) + e.d_right * share_r.powi(2);
            list.push(Effect::Compliance(Compliance {
                body: 1,
                stiffness: k,
                motor_share: effects.compliance_motor_fraction,
                damping: Some(d_s / c_s * k),
            }));
        }
        let declared = DriveModel {
            line: Line { domain: Domain::Rotational, bodies, couplings },
            inputs: vec![0, 1, 2],
            effects: list,
        };
        let mut m = declared.resolved()?.into_owned();
        if compliant {
            // the rig's signal names: the motor part is `motor` (w_motor)
            m.line.bodies[3].name = "motor".into();
        }
        m.validate()?;
        Ok(m)
    }
}

impl Dynamics {
    /// The dynamics of the paper rig's model `m` ([`DriveModel::paper_rig`]), stepped as its
    /// records are sampled: with backlash or friction, RK4 steps within a smooth piece of h·rate
    /// ≤ [`RK4_STEP_TIMES_RATE`] of the linear part's fastest rate and at most [`RIG_SAMPLE_S`];
    /// across pieces [`BACKLASH_STEP_S`] with backlash and h·rate ≤ [`RK4_STEP_TIMES_RATE`] of
    /// the friction's slopes T_c/(v_s J).
    pub fn paper_rig(m: &DriveModel) -> Result<Dynamics> {
        let dynamics = Dynamics::new(m)?;
        if !m.is_nonlinear() {
            return Ok(dynamics);
        }
        // the general rule's step within a piece, h·rate ≤ RK4_STEP_TIMES_RATE (its springs
        // give the rig a fastest rate), at most the sample
        let coarse = dynamics.rk4_steps_s().0.clamp(1e-9, RIG_SAMPLE_S);
        let backlash = m.effects.iter().any(|e| matches!(e, Effect::Backlash(_)));
        let mut fine = if backlash { BACKLASH_STEP_S.min(coarse) } else { coarse };
        for e in &m.effects {
            if let Effect::CoulombFriction(CoulombFriction { body, friction, smoothing_speed }) = *e {
                let j = m.line.bodies[body].inertia;
                fine = fine.min((RK4_STEP_TIMES_RATE * smoothing_speed * j / friction).max(1e-9));
            }
        }
        Ok(dynamics.with_steps(coarse, fine))
    }
}

impl Stepper {
    /// The paper rig's model `m` ([`DriveModel::paper_rig`]) as its FMU steps it: the
    /// diagnosis's integrator and steps ([`Dynamics::paper_rig`]), its positions entering as the
    /// load machines' angles φ_m2, φ_m3, the side shafts' generalised twist s = 2φ_drive − φ_m2
    /// − φ_m3 in place of φ_drive (eq. (A1)) and, with a compliance, its twist φ_motor −
    /// φ_drive in place of φ_motor: the rig FMU's states.
    pub fn paper_rig(m: &DriveModel) -> Result<Stepper> {
        if !has_rig_layout(m) {
            return Err(PlantError::Invalid(format!(
                "not the paper rig's model (m2, drive, m3 and a motor with a compliance; two side shafts and the \
                 compliance): {} bodies, {} couplings",
                m.line.bodies.len(),
                m.line.couplings.len()
            )));
        }
        let n = m.line.bodies.len();
        let mut rows = DMatrix::identity(n, n);
        rows[(1, 0)] = -1.0;
        rows[(1, 1)] = 2.0;
        rows[(1, 2)] = -1.0;
        if n == 4 {
            rows[(3, 1)] = -1.0;
        }
        Stepper::with_positions(m, Dynamics::paper_rig(m)?, &rows)
    }
}

/// The state a torsional record of the paper rig's model `m` starts in: every body at
/// `speed0` (the load machines hold the speed: the drag then needs a torque the drive's may not
/// supply, but only the twist matters to the response), the side shafts carrying their static
/// half of the drive torque `torque` (the cage passes it on, a·T = torque) beyond the play, the
/// compliance its whole, a lag at its steady value. A model that is not the rig's starts
/// untwisted.
pub fn record_start(m: &DriveModel, torque: f64, speed0: f64) -> Vec<f64> {
    let n = m.line.bodies.len();
    let mut x = vec![0.0; m.nstates()];
    x[n..2 * n].fill(speed0);
    if !has_rig_layout(m) {
        return x;
    }
    let (cl, cr) = (m.line.couplings[0].stiffness, m.line.couplings[1].stiffness);
    // the shafts in series on s (eq. (A1)); the play of the short one is its share of s's
    let c_s = cl * cr / (cl + cr);
    let share = cr / (cl + cr);
    let play_of_s = m
        .effects
        .iter()
        .find_map(|e| match *e {
            Effect::Backlash(Backlash { coupling: 0, backlash }) => Some(backlash / (2.0 * share)),
            _ => None,
        })
        .unwrap_or(0.0);
    let t_shaft = torque / 2.0;
    let s = t_shaft / c_s + play_of_s * t_shaft.signum() * f64::from(t_shaft != 0.0);
    // the twist on the cage: s = 2 φ_cage
    x[1] = s / 2.0;
    if n == 4 {
        x[3] = x[1] + torque / m.line.couplings[2].stiffness;
    }
    if x.len() > 2 * n {
        x[2 * n] = torque;
    }
    x
}

/// Whether `m` is laid out as [`DriveModel::paper_rig`] builds the rig: bodies m2, drive, m3
/// and, with a compliance, the motor; the two side shafts and, with a compliance, the
/// compliance.
fn has_rig_layout(m: &DriveModel) -> bool {
    let (n, c) = (m.line.bodies.len(), m.line.couplings.len());
    (n == 3 && c == 2) || (n == 4 && c == 3)
}

/// A torsional record of the paper rig's model `m`: the drive torque `torque` sampled every
/// `dt_s` (held over each sample, the load machines' torques zero) from [`record_start`] at
/// `speed0`; the `outputs` at the sample instants. One simulation with every drive model
/// ([`Dynamics::simulate_from`] of `dynamics`, [`Dynamics::paper_rig`]'s steps), except the
/// drive torque's dead time: the record is shifted by it, interpolating between samples
/// ([`delayed`]), where a drive model's simulation and the FMU split each sample at the dead
/// time's fraction. The two agree at whole samples; in between, the interpolated record is
/// what the torsional diagnosis has always fitted a dead time to, and its answers stay the
/// same.
pub fn simulate_record(
    m: &DriveModel,
    dynamics: &Dynamics,
    torque: &[f64],
    dt_s: f64,
    speed0: f64,
    outputs: &[(Quantity, usize)],
) -> Result<Vec<Vec<f64>>> {
    let x0 = record_start(m, torque.first().copied().unwrap_or(0.0), speed0);
    let zero = vec![0.0; torque.len()];
    let delay_s = dynamics.delay_s(1);
    if delay_s > 0.0 {
        let shifted = delayed(torque, dt_s, delay_s);
        return dynamics.without_delays().simulate_from(x0, &[&zero, &shifted, &zero], dt_s, outputs);
    }
    dynamics.simulate_from(x0, &[&zero, torque, &zero], dt_s, outputs)
}

/// `x` delayed by `delay_s` (linear interpolation between samples, the first sample held
/// before the start).
pub fn delayed(x: &[f64], dt_s: f64, delay_s: f64) -> Vec<f64> {
    if delay_s <= 0.0 || x.is_empty() {
        return x.to_vec();
    }
    let shift = delay_s / dt_s;
    let whole = shift.floor() as usize;
    let frac = shift - whole as f64;
    (0..x.len())
        .map(|k| {
            let at = |i: isize| if i < 0 { x[0] } else { x[i as usize] };
            let i = k as isize - whole as isize;
            (1.0 - frac) * at(i) + frac * at(i - 1)
        })
        .collect()
}

/// The load machines' speeds (w_m2, w_m3) of a torsional record of the rig `rig` in
/// `variant` with `effects` ([`simulate_record`] of its model and dynamics).
pub fn record_speeds(
    rig: &RigParams,
    variant: Variant,
    effects: &DriveEffects,
    torque: &[f64],
    dt_s: f64,
    speed0: f64,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let m = DriveModel::paper_rig(rig, variant, effects)?;
    let d = Dynamics::paper_rig(&m)?;
    let mut w = simulate_record(&m, &d, torque, dt_s, speed0, &[(Quantity::Speed, 0), (Quantity::Speed, 2)])?;
    let w3 = w.pop().unwrap_or_default();
    Ok((w.pop().unwrap_or_default(), w3))
}

impl RigParams {
    /// The open differential (section 2.4): side gears massless (J_d2 = J_d3 = 0), cage angle
    /// φ_drive = (φ_d2 + φ_d3)/2 (eq. (27)). Eliminating φ_d3 with eq. (30) leaves the two side
    /// shafts in series between the generalised angle 2φ_drive − φ_m2 − φ_m3 and ground: with
    /// a = [−1, 2, −1], the short shaft twists by c_r/(c_l + c_r) aᵀq and the long one by
    /// c_l/(c_l + c_r) aᵀq, so C = c_l c_r/(c_l + c_r) a aᵀ — eq. (A1) — and the damping matrix
    /// follows the same way. Modes: rigid body and the outputs' antiphase motion at 0 Hz, and
    /// the shuffle at ω² = c_l c_r/(c_l + c_r) (1/J_m2 + 4/J_drive + 1/J_m3).
    ///
    /// Built from the rig's one drive model ([`DriveModel::paper_rig`], no effects),
    /// the model the diagnosis, the FMU and the MPC integrate.
    pub fn open_differential(&self, variant: Variant) -> Result<MechanicalModel> {
        let model = DriveModel::paper_rig(self, variant, &DriveEffects::default())?;
        let mut m = model.line.model()?;
        m.layout = Some(Layout { m2: 0, drive: Some(1), m3: 2, short_shaft: (0, 1), long_shaft: (1, 2) });
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanical::Output;
    use crate::rig::RigParams;
    use crate::DelayLine;

    /// The rig's model and dynamics with `effects`.
    fn rig_model(rig: &RigParams, variant: Variant, effects: &DriveEffects) -> (DriveModel, Dynamics) {
        let m = DriveModel::paper_rig(rig, variant, effects).unwrap();
        let d = Dynamics::paper_rig(&m).unwrap();
        (m, d)
    }

    /// A model that is not the rig's (two bodies, one shaft) is refused by the rig's FMU
    /// coordinates with the layout it has, and starts a record untwisted, not with a panic.
    #[test]
    fn a_model_that_is_not_the_rig_is_refused_not_indexed() {
        let body = |name: &str| LineBody { name: name.into(), inertia: 0.1, drag: 0.0 };
        let m = DriveModel {
            line: Line {
                domain: Domain::Rotational,
                bodies: vec![body("a"), body("b")],
                couplings: vec![Coupling::new(100.0, 0.1, 1.0)],
            },
            inputs: vec![0],
            effects: vec![],
        };
        match Stepper::paper_rig(&m) {
            Err(e) => assert!(e.to_string().contains("2 bodies, 1 couplings"), "{e}"),
            Ok(_) => panic!("a two-body line is not the rig"),
        }
        assert_eq!(record_start(&m, 5.0, 3.0), [0.0, 0.0, 3.0, 3.0]);
    }

    fn rig() -> RigParams {
        crate::paper::damped_params()
    }

    /// The rig's FMU step ([`Stepper::paper_rig`]: the one drive-model step, in the rig's
    /// twist coordinates) replays what the diagnosis simulates ([`simulate_record`]) — with
    /// play alone (exact pieces), with friction and a compliance (RK4), with a dead time of 2
    /// samples (the record simulation shifts the record, the FMU splits its step where its
    /// delay line's history changes: the two agree at whole samples) and a lag (exact ZOH
    /// pieces) —
    /// under a torque that reverses through the play. The two share the right-hand side and
    /// the nonlinear integrator but not their loops, the dead time's handling, the linear
    /// model's discretisation or the coordinates (the FMU's twists against absolute angles):
    /// agreement to 1e-9 of the speeds' range is rounding, not a matched error.
    #[test]
    fn the_rig_stepper_replays_the_diagnosis_simulation() {
        let cases = [
            DriveEffects { backlash_rad: 0.004, ..Default::default() },
            DriveEffects {
                compliance_stiffness_nm_per_rad: 2500.0,
                compliance_motor_fraction: 0.4,
                coulomb_friction_nm: [0.7, 0.3, 1.1],
                ..Default::default()
            },
            DriveEffects { time_delay_s: 2e-3, actuator_lag_s: 0.01, ..Default::default() },
        ];
        let dt = 1e-3;
        let torque: Vec<f64> =
            (0..600).map(|k| 30.0 * (2.0 * std::f64::consts::PI * 3.0 * k as f64 * dt).sin()).collect();
        for effects in cases {
            let (m, _) = rig_model(&rig(), Variant::V1, &effects);
            let (w2, w3) = record_speeds(&rig(), Variant::V1, &effects, &torque, dt, 5.0).unwrap();
            let mut stepper = Stepper::paper_rig(&m).unwrap();
            let n = m.line.bodies.len();
            let mut z = stepper.state_of(&record_start(&m, torque[0], 5.0));
            let mut lines = vec![DelayLine::default(); 3];
            for line in &mut lines {
                line.record(f64::NEG_INFINITY, 0.0);
            }
            lines[1] = DelayLine::default();
            lines[1].record(f64::NEG_INFINITY, torque[0]);
            let range = w2.iter().chain(&w3).fold(0.0_f64, |m, v| m.max((v - 5.0).abs()));
            for (k, &uk) in torque.iter().enumerate() {
                let t = k as f64 * dt;
                assert!((z[n] - w2[k]).abs() <= 1e-9 * range, "{effects:?} sample {k}: w_m2 {} vs {}", z[n], w2[k]);
                assert!(
                    (z[n + 2] - w3[k]).abs() <= 1e-9 * range,
                    "{effects:?} sample {k}: w_m3 {} vs {}",
                    z[n + 2],
                    w3[k]
                );
                if effects.time_delay_s > 0.0 {
                    lines[1].record(t, uk);
                }
                stepper.step(&mut z, &[0.0, uk, 0.0], t, dt, &lines).unwrap();
            }
        }
    }

    /// The rig's right-hand side — the drive model's one [`Dynamics`] — against the open
    /// differential written out by hand (eq. (A1): the side shafts in series on s = aᵀq,
    /// a = [−1, 2, −1], stiffness c_l c_r/(c_l + c_r) beyond the play |s| > b, damping
    /// d_l (c_r/(c_l+c_r))² + d_r (c_l/(c_l+c_r))²; the compliance between cage and motor; the
    /// machines' friction T_c w/√(w² + v_s²); the lag τ ż = u − z), at states spread over
    /// contact on either side and inside the play. Agreement to round-off (1e-12 of the
    /// largest term).
    #[test]
    fn the_rig_right_hand_side_is_the_open_differential_by_hand() {
        let rig = rig();
        let effects = DriveEffects {
            backlash_rad: 0.004,
            actuator_lag_s: 0.003,
            compliance_stiffness_nm_per_rad: 2500.0,
            compliance_motor_fraction: 0.4,
            coulomb_friction_nm: [0.7, 0.3, 1.1],
            ..Default::default()
        };
        let (_, d) = rig_model(&rig, Variant::V1, &effects);
        let e = rig.effective(Variant::V1).unwrap();
        let (cl, cr) = (e.c_left, e.c_right);
        let c_s = cl * cr / (cl + cr);
        let d_s = e.d_left * (cr / (cl + cr)).powi(2) + e.d_right * (cl / (cl + cr)).powi(2);
        let (k, f) = (effects.compliance_stiffness_nm_per_rad, effects.compliance_motor_fraction);
        let d_k = d_s / c_s * k;
        let j = [e.j_m2, (1.0 - f) * e.j_drive, e.j_m3, f * e.j_drive];
        let a = [-1.0, 2.0, -1.0, 0.0];
        let b = effects.backlash_rad;
        let vs = effects.friction_smoothing_radps;
        let u = [4.0, 35.0, -6.0];
        let mut dx = vec![0.0; 9];
        for (case, s_target) in [0.011, -0.009, 0.0015, -0.0031, 0.0].iter().enumerate() {
            // angles and speeds spread, the cage placed so that s = s_target
            let mut x: Vec<f64> = (0..9).map(|i| 0.01 * ((i * 7 + case * 3) % 5) as f64 - 0.02).collect();
            x[1] = (s_target + x[0] + x[2]) / 2.0;
            let s: f64 = (0..4).map(|i| a[i] * x[i]).sum();
            let sdot: f64 = (0..4).map(|i| a[i] * x[4 + i]).sum();
            let t = if s > b {
                c_s * (s - b) + d_s * sdot
            } else if s < -b {
                c_s * (s + b) + d_s * sdot
            } else {
                0.0
            };
            let compliance = k * (x[3] - x[1]) + d_k * (x[7] - x[5]);
            let friction = |tc: f64, w: f64| tc * w / (w * w + vs * vs).sqrt();
            let force = [
                -a[0] * t + u[0] - e.load_drag * x[4] - friction(0.7, x[4]),
                -a[1] * t + compliance,
                -a[2] * t + u[2] - e.load_drag * x[6] - friction(1.1, x[6]),
                -compliance + x[8] - friction(0.3, x[7]),
            ];
            let mut by_hand = x[4..8].to_vec();
            by_hand.extend((0..4).map(|i| force[i] / j[i]));
            by_hand.push((u[1] - x[8]) / effects.actuator_lag_s);
            d.rhs(&x, &u, &mut dx);
            let scale = by_hand.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for i in 0..9 {
                assert!(
                    (dx[i] - by_hand[i]).abs() <= 1e-12 * scale,
                    "s = {s_target}, state {i}: {} vs {}",
                    dx[i],
                    by_hand[i]
                );
            }
            let torque = d.output(&x, (Quantity::CouplingForce, 0));
            let t_short = if t == 0.0 { 0.0 } else { t - d_s * sdot + e.d_left * cr / (cl + cr) * sdot };
            assert!((torque - t_short).abs() <= 1e-12 * c_s, "{} vs {t_short}", torque);
        }
    }

    /// The paper rig's drive model in V1–V4 has the shuffle frequency of the closed form
    /// ω² = c_l c_r/(c_l + c_r) (1/J_m2 + 4/J_drive + 1/J_m3) (section 2.4) and two rigid modes.
    #[test]
    fn the_paper_rig_model_has_the_closed_form_shuffle() {
        for variant in [Variant::V1, Variant::V2, Variant::V3, Variant::V4] {
            let m = DriveModel::paper_rig(&rig(), variant, &DriveEffects::default()).unwrap();
            let e = rig().effective(variant).unwrap();
            let c_s = e.c_left * e.c_right / (e.c_left + e.c_right);
            let w = (c_s * (1.0 / e.j_m2 + 4.0 / e.j_drive + 1.0 / e.j_m3)).sqrt();
            let f = m.line.model().unwrap().modes().unwrap().frequencies_hz;
            assert!(f[0].abs() < 1e-6 && f[1].abs() < 1e-6, "{f:?}");
            assert!((f[2] - w / (2.0 * std::f64::consts::PI)).abs() < 1e-9 * f[2], "{variant}: {f:?} vs {w}");
            assert_eq!(m.coupling_force_names(), ["T_short_side_shaft", "T_long_side_shaft"]);
            assert_eq!(m.state_names(), ["phi_m2", "phi_drive", "phi_m3", "w_m2", "w_drive", "w_m3"]);
        }
    }

    #[test]
    fn linear_part_is_the_open_differential() {
        // The same model assembled by MechanicalModel from the springs' elongation vectors.
        for variant in [Variant::V1, Variant::V3] {
            let (m, d) = rig_model(&rig(), variant, &DriveEffects::default());
            let (a, b) = d.linear_piece(true);
            let c = m.coupling_forces(a.nrows());
            let ss = rig().open_differential(variant).unwrap().state_space(&[Output::SpringTorques]).unwrap();
            assert!((&a - &ss.a).abs().max() < 1e-9 * ss.a.abs().max(), "A differs");
            assert!((&b - &ss.b).abs().max() < 1e-12 * ss.b.abs().max(), "B differs");
            assert!((&c - &ss.c).abs().max() < 1e-9 * ss.c.abs().max(), "C differs");
        }
    }

    #[test]
    fn derivative_is_the_linear_part_in_contact_and_free_inside_the_play() {
        let effects = DriveEffects {
            backlash_rad: 0.01,
            actuator_lag_s: 0.004,
            compliance_stiffness_nm_per_rad: 2000.0,
            ..Default::default()
        };
        let (m, d) = rig_model(&rig(), Variant::V1, &effects);
        let ns = d.nstates();
        assert_eq!(ns, 9);
        let u = [3.0, 40.0, -5.0];
        let mut dx = vec![0.0; ns];
        for (twist, contact) in [(0.03, true), (0.004, false)] {
            // s = 2 φ_cage
            let mut x: Vec<f64> = (0..ns).map(|i| 1e-3 * (i as f64 - 3.0)).collect();
            x[0] = 0.0;
            x[2] = 0.0;
            x[1] = twist / 2.0;
            d.rhs(&x, &u, &mut dx);
            let (a, b) = d.linear_piece(true);
            let c = m.coupling_forces(ns);
            let (a_open, b_open) = d.linear_piece(false);
            let shift = DMatrix::from_fn(ns, 1, |i, _| if i == 1 { effects.backlash_rad / 2.0 } else { 0.0 });
            let xv = DMatrix::from_column_slice(ns, 1, &x);
            // the shafts' elastic term acts on s − b (beyond the play), the rest on x
            let uv = DMatrix::from_column_slice(3, 1, &u);
            let lin = if contact {
                &a_open * &xv + &b_open * &uv + (&a - &a_open) * (&xv - &shift)
            } else {
                &a_open * &xv + &b_open * &uv
            };
            assert_eq!(b, b_open);
            for i in 0..ns {
                assert!((dx[i] - lin[i]).abs() < 1e-9 * lin.abs().max(), "state {i}: {} vs {}", dx[i], lin[i]);
            }
            let t = [0, 1].map(|k| d.output(&x, (Quantity::CouplingForce, k)));
            let t_lin = if contact { &c * (&xv - &shift) } else { DMatrix::zeros(2, 1) };
            assert!((t[0] - t_lin[0]).abs() < 1e-9 && (t[1] - t_lin[1]).abs() < 1e-9);
        }
    }

    /// Friction takes angular momentum out at its own rate: the side shafts' torques cancel in
    /// Σ J_i w_i (aᵀ1 = 0), so with no drag and no input d/dt Σ J_i w_i = −T_c w/√(w² + v_s²)
    /// at the drive, ≈ −T_c (1 − v_s²/(2w²)) while the drive turns fast; and the slope the FMU's
    /// Jacobian adds is the right-hand side's own derivative (central difference).
    #[test]
    fn friction_takes_momentum_out_at_its_rate() {
        let rig = RigParams { load_drag: 0.0, ..rig() };
        let tc = 3.0;
        let effects = DriveEffects { coulomb_friction_nm: [0.0, tc, 0.0], ..Default::default() };
        let (_, d) = rig_model(&rig, Variant::V1, &effects);
        let e = rig.effective(Variant::V1).unwrap();
        let j = [e.j_m2, e.j_drive, e.j_m3];
        let (w0, dt, n) = (20.0, 1e-3, 1000);
        let (w2, w3) = record_speeds(&rig, Variant::V1, &effects, &vec![0.0; n], dt, w0).unwrap();
        // the drive's speed from momentum is not an output; check the momentum through the two
        // load machines and the twist-free mean: with the twist small, w_drive ≈ (w2 + w3)/2
        let momentum0 = (j[0] + j[1] + j[2]) * w0;
        let t = (n - 1) as f64 * dt;
        let w_end = 0.5 * (w2[n - 1] + w3[n - 1]);
        let momentum = j[0] * w2[n - 1] + j[1] * w_end + j[2] * w3[n - 1];
        let expected = momentum0 - tc * t;
        // the shuffle's oscillation about the mean puts w_drive off (w2 + w3)/2 by its twist
        // rate: bounded by the amplitude that a 3 Nm change of torque excites, < 1 % here
        assert!((momentum - expected).abs() < 0.01 * tc * t, "{momentum} vs {expected}");
        let x = vec![0.01, -0.02, 0.005, 1.0, 0.03, -2.0];
        let slopes = d.friction_slopes(&x);
        assert_eq!(slopes.len(), 1);
        let (i, slope) = slopes[0];
        let h = 1e-6;
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[i] += h;
        xm[i] -= h;
        let (mut dp, mut dm) = (vec![0.0; 6], vec![0.0; 6]);
        d.rhs(&xp, &[0.0; 3], &mut dp);
        d.rhs(&xm, &[0.0; 3], &mut dm);
        // the springs' damping also depends on the speed: take it out through the linear part
        let (a, _) = d.linear_piece(true);
        let fd = (dp[i] - dm[i]) / (2.0 * h) - a[(i, i)];
        assert!((fd - slope).abs() < 1e-6 * slope.abs(), "{fd} vs {slope}");
    }

    /// The reference: one plain classical RK4 step of length `h` with the torques held; `work` holds 5 scratch
    /// vectors of the state's length.
    fn rk4_step(d: &Dynamics, x: &mut [f64], torques: [f64; 3], h: f64, work: &mut [Vec<f64>; 5]) {
        let ns = x.len();
        let [k1, k2, k3, k4, tmp] = work;
        d.rhs(x, &torques, k1);
        for i in 0..ns {
            tmp[i] = x[i] + 0.5 * h * k1[i];
        }
        d.rhs(tmp, &torques, k2);
        for i in 0..ns {
            tmp[i] = x[i] + 0.5 * h * k2[i];
        }
        d.rhs(tmp, &torques, k3);
        for i in 0..ns {
            tmp[i] = x[i] + h * k3[i];
        }
        d.rhs(tmp, &torques, k4);
        for i in 0..ns {
            x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }

    #[test]
    fn a_model_faster_than_the_record_is_refused_not_integrated_for_minutes() {
        // friction beside a lag of 0.1 µs: RK4 would need 10⁴ steps per 1 ms sample
        let e = DriveEffects {
            coulomb_friction_nm: [1.0, 0.0, 1.0],
            friction_smoothing_radps: 0.01,
            actuator_lag_s: 1e-7,
            ..Default::default()
        };
        let t0 = std::time::Instant::now();
        let r = record_speeds(&rig(), Variant::V1, &e, &vec![1.0; 60_000], 1e-3, 0.0);
        assert!(matches!(r, Err(PlantError::Invalid(ref m)) if m.contains("integration steps")), "{r:?}");
        assert!(t0.elapsed().as_secs_f64() < 1.0);
    }

    #[test]
    fn play_and_friction_step_like_fine_rk4() {
        // a sweep about 0 Nm, so the shafts cross the play twice a period and the machines'
        // speeds reverse, against plain RK4 with 0.025 ms steps everywhere (5× finer than the
        // fine steps, 40× finer than the coarse ones) over 5 s, before the rattling's
        // sensitivity builds up
        let play = DriveEffects { backlash_rad: 0.004, ..Default::default() };
        let friction =
            DriveEffects { coulomb_friction_nm: [1.0, 0.5, 1.0], friction_smoothing_radps: 0.01, ..Default::default() };
        for effects in [play, friction] {
            let (m, d) = rig_model(&rig(), Variant::V1, &effects);
            let dt = 1e-3;
            let torque: Vec<f64> = (0..5000)
                .map(|k| {
                    let t = k as f64 * dt;
                    8.0 * (2.0 * std::f64::consts::PI * (1.0 * t + 1.5 * t * t)).sin()
                })
                .collect();
            let (w2, _) = record_speeds(&rig(), Variant::V1, &effects, &torque, dt, 0.0).unwrap();
            let mut x = record_start(&m, torque[0], 0.0);
            let mut work: [Vec<f64>; 5] = std::array::from_fn(|_| vec![0.0; x.len()]);
            let mut reference = Vec::new();
            for &u in &torque {
                reference.push(x[3]);
                for _ in 0..40 {
                    rk4_step(&d, &mut x, [0.0, u, 0.0], dt / 40.0, &mut work);
                }
            }
            let range = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let worst = w2.iter().zip(&reference).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            // the kinks inside the fine sub-steps are where RK4 loses its order: 3e-4 (play) and
            // 7e-4 (friction) of the range seen; 1 ms steps across the play leave 3e-3
            assert!(worst < 1e-3 * range, "{effects:?}: max |Δw_m2| {worst} of {range}");
            // and the pieces are left: some samples inside the play, speeds reversing
            let crossings = reference.windows(2).filter(|w| w[0].signum() != w[1].signum()).count();
            assert!(crossings > 20, "{crossings}");
        }
    }
}
