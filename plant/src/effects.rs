//! The paper rig's powertrain with its drive-path effects ([`DriveEffects`]): its drive model
//! ([`DriveModel::paper_rig`]) integrated the way the torsional diagnosis and the rig's FMU
//! step it, and the delay line of a dead time. No I/O.

use nalgebra::DMatrix;

use crate::drive::{DriveModel, Dynamics, HeldInputs};
use crate::error::{PlantError, Result};
use crate::integrate::{AffineStep, PiecewiseRk4};
use crate::line::Quantity;
use crate::rig::{DriveEffects, RigParams, Variant};
use crate::statespace::StateSpace;

/// Largest integration step with backlash, s: the RK4 step of [`Powertrain::simulate`] (8 per
/// 1 ms sample) and of the FMU's co-simulation step. Contact switching makes the response
/// sensitive to the step: 4 sub-steps per ms left twice the misfit at the true play.
pub const BACKLASH_STEP_S: f64 = 1.25e-4;

/// The open-differential powertrain (section 2.4) with effects, driven by the load-machine and
/// drive torques [M_m2, M_drive, M_m3]: the paper rig's view of its [`DriveModel`]
/// ([`DriveModel::paper_rig`]), whose [`Dynamics`] it integrates — one right-hand side, one
/// linearisation per piece with every other drivetrain. Coordinates: φ_m2, φ_drive (the cage),
/// φ_m3 and, with a compliance, φ_motor; then their speeds; then, with a lag, the lagged drive
/// torque. The side shafts act through the generalised twist s = aᵀq, a = [−1, 2, −1] on (m2,
/// cage, m3), as two springs in series (eq. (A1)); the drive torque acts on the motor (the cage
/// when rigid).
#[derive(Debug, Clone)]
pub struct Powertrain {
    model: DriveModel,
    dynamics: Dynamics,
    /// Stiffness of the side shafts in series on s, Nm/rad (eq. (A1)).
    c_s: f64,
    /// RK4 steps within a piece and across pieces, s.
    coarse_s: f64,
    fine_s: f64,
    /// The effects.
    pub effects: DriveEffects,
}

impl Powertrain {
    /// The powertrain of `rig` in `variant` with `effects`.
    pub fn new(rig: &RigParams, variant: Variant, effects: &DriveEffects) -> Result<Self> {
        let model = DriveModel::paper_rig(rig, variant, effects)?;
        let e = rig.effective(variant)?;
        let c_s = e.c_left * e.c_right / (e.c_left + e.c_right);
        let mut dynamics = Dynamics::new(&model)?;
        let input_dof = model.inputs[1];
        let (mut coarse_s, mut fine_s) = (8.0 * BACKLASH_STEP_S, BACKLASH_STEP_S);
        if effects.is_nonlinear() {
            // within a smooth piece h·rate ≤ 0.5 of the linear part's fastest rate, at most the
            // 1 ms sample; across pieces BACKLASH_STEP_S with backlash and h·rate ≤ 0.5 of the
            // friction's slopes T_c/(v_s J)
            let coarse =
                (crate::integrate::RK4_STEP_TIMES_RATE / dynamics.fastest_rate()).clamp(1e-9, 8.0 * BACKLASH_STEP_S);
            let mut fine = if effects.backlash_rad > 0.0 { BACKLASH_STEP_S.min(coarse) } else { coarse };
            let v = effects.friction_smoothing_radps;
            for (&b, &tc) in [0, input_dof, 2].iter().zip(&effects.coulomb_friction_nm) {
                if tc > 0.0 {
                    let j = model.line.bodies[b].inertia;
                    fine = fine.min((crate::integrate::RK4_STEP_TIMES_RATE * v * j / tc).max(1e-9));
                }
            }
            dynamics = dynamics.with_steps(coarse, fine);
            (coarse_s, fine_s) = (coarse, fine);
        }
        Ok(Powertrain { model, dynamics, c_s, coarse_s, fine_s, effects: *effects })
    }

    /// The rig as a drive model ([`DriveModel::paper_rig`]).
    pub fn model(&self) -> &DriveModel {
        &self.model
    }

    /// The dynamics it integrates.
    pub fn dynamics(&self) -> &Dynamics {
        &self.dynamics
    }

    /// Degrees of freedom: 3, or 4 with a compliance (φ_motor last).
    pub fn dofs(&self) -> usize {
        self.model.line.bodies.len()
    }

    /// Number of states.
    pub fn nstates(&self) -> usize {
        self.dynamics.nstates()
    }

    /// Names of the states, in order (the drive model's; the lagged torque is the drive's).
    pub fn state_names(&self) -> Vec<String> {
        let mut names = self.model.state_names();
        if self.nstates() > 2 * self.dofs() {
            names[2 * self.dofs()] = "M_drive_lagged".into();
        }
        names
    }

    /// The linear part with inputs [M_m2, M_drive, M_m3] and outputs the side-shaft torques
    /// [T_short, T_long], the dead time left out: (A, B, C). `contact`: the shafts engaged
    /// (backlash closed, eq. (A1)); false: inside the play, where they carry nothing.
    pub fn linear(&self, contact: bool) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        let ns = self.nstates();
        let (a, b) = self.dynamics.linear_piece(contact);
        let c = if contact || self.effects.backlash_rad == 0.0 {
            self.model.coupling_forces(ns).rows(0, 2).into_owned()
        } else {
            DMatrix::zeros(2, ns)
        };
        (a, b, c)
    }

    /// The linear part (backlash closed, the dead time left out): input the drive torque,
    /// outputs w_m2 and w_m3.
    pub fn state_space(&self) -> StateSpace {
        let n = self.dofs();
        let ns = self.nstates();
        let (a, b, _) = self.linear(true);
        let mut c = DMatrix::zeros(2, ns);
        c[(0, n)] = 1.0;
        c[(1, n + 2)] = 1.0;
        StateSpace {
            a,
            b: b.columns(1, 1).into_owned(),
            c,
            d: DMatrix::zeros(2, 1),
            state_names: self.state_names(),
            input_names: vec!["M_drive".into()],
            output_names: vec!["w_m2".into(), "w_m3".into()],
        }
    }

    /// The linear part (backlash closed, the dead time left out — see [`Powertrain::delay_s`])
    /// as the controller sees the rig: inputs [M_m2, M_drive, M_m3], outputs the speeds
    /// [w_m2, w_drive, w_m3] (w_drive the cage's), the side-shaft torques
    /// [T_short_side_shaft, T_long_side_shaft] and, with a compliance, w_motor. Without effects
    /// it is `RigParams::open_differential(..).state_space(&[Speeds, SpringTorques])`.
    pub fn control_state_space(&self) -> StateSpace {
        let n = self.dofs();
        let ns = self.nstates();
        let (a, b, torques) = self.linear(true);
        let mut rows = vec![n, n + 1, n + 2];
        if n == 4 {
            rows.push(n + 3);
        }
        let ny = 5 + usize::from(n == 4);
        let mut c = DMatrix::zeros(ny, ns);
        for (k, &i) in rows[..3].iter().enumerate() {
            c[(k, i)] = 1.0;
        }
        c.view_mut((3, 0), (2, ns)).copy_from(&torques);
        if n == 4 {
            c[(5, n + 3)] = 1.0;
        }
        let mut output_names: Vec<String> =
            ["w_m2", "w_drive", "w_m3", "T_short_side_shaft", "T_long_side_shaft"].map(String::from).into();
        if n == 4 {
            output_names.push("w_motor".into());
        }
        StateSpace {
            a,
            b,
            d: DMatrix::zeros(ny, 3),
            c,
            state_names: self.state_names(),
            input_names: ["M_m2", "M_drive", "M_m3"].map(String::from).into(),
            output_names,
        }
    }

    /// Dead time of each input of [`Powertrain::control_state_space`], s: the drive torque's.
    pub fn delay_s(&self) -> [f64; 3] {
        [0.0, self.effects.time_delay_s, 0.0]
    }

    /// Natural frequencies of the undamped linear part, Hz, ascending (the compliance adds
    /// one above the shuffle).
    pub fn frequencies_hz(&self) -> Vec<f64> {
        let m = match self.model.line.model() {
            Ok(m) => m,
            Err(_) => return Vec::new(),
        };
        let k = m.stiffness_matrix();
        let j = m.inertia.diagonal();
        let s = DMatrix::from_fn(k.nrows(), k.ncols(), |r, c| k[(r, c)] / (j[r] * j[c]).sqrt());
        let mut f: Vec<f64> =
            s.symmetric_eigenvalues().iter().map(|&l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)).collect();
        f.sort_by(|a, b| a.total_cmp(b));
        f
    }

    /// Load-machine speeds (w_m2, w_m3) for the drive torque `torque` sampled every `dt_s`
    /// (held between samples), from the steady state under `torque[0]` with every speed at
    /// `speed0`. Linear cases are exact (ZOH, the dead time by interpolating the torque);
    /// backlash and friction are integrated by RK4 with steps of at most [`BACKLASH_STEP_S`], the FMU's
    /// integrator: about zero torque the rattling in the play is so sensitive that a 0.1 %
    /// change of the play, or an exact step of each linear piece, moved the error of a fitted
    /// model from 0.13 to 0.16–0.23, so the diagnosis and the FMU share one integrator.
    pub fn simulate(&self, torque: &[f64], dt_s: f64, speed0: f64) -> Result<(Vec<f64>, Vec<f64>)> {
        let u = delayed(torque, dt_s, self.effects.time_delay_s);
        let x0 = self.steady_state(u.first().copied().unwrap_or(0.0), speed0);
        if self.effects.is_nonlinear() {
            let worst = self.integrator(0).counts(dt_s).map_or(f64::INFINITY, |(c, f)| c as f64 * f as f64);
            if worst > crate::drive::FINE_PER_COARSE * crate::drive::MAX_SUBSTEPS as f64 {
                return Err(PlantError::Invalid(format!(
                    "the model needs up to {worst:.0} integration steps per {dt_s} s sample (steps of {:.3e} s, {:.3e} s \
                     across the play or the friction's steep band): faster than the record resolves",
                    self.coarse_s, self.fine_s
                )));
            }
            return Ok(self.simulate_rk4(&u, dt_s, x0));
        }
        let n = self.dofs();
        let (mut w2, mut w3) = (Vec::with_capacity(u.len()), Vec::with_capacity(u.len()));
        self.run_linear(&u, dt_s, x0, |x| {
            w2.push(x[n]);
            w3.push(x[n + 2]);
        })?;
        Ok((w2, w3))
    }

    /// The short side shaft's torque (the long one's differs only by its damping share) under
    /// the drive torque `torque` of the linear part (backlash closed, friction left out), as
    /// [`Powertrain::simulate`] starts it: where it changes sign the play can show.
    pub fn simulate_shaft_torque(&self, torque: &[f64], dt_s: f64, speed0: f64) -> Result<Vec<f64>> {
        let u = delayed(torque, dt_s, self.effects.time_delay_s);
        let x0 = self.steady_state(u.first().copied().unwrap_or(0.0), speed0);
        let (_, _, c) = self.linear(true);
        let mut t = Vec::with_capacity(u.len());
        self.run_linear(&u, dt_s, x0, |x| t.push(c.row(0).iter().zip(x).map(|(a, b)| a * b).sum()))?;
        Ok(t)
    }

    /// The linear part stepped exactly (ZOH) under the drive torque `u`; `out` sees each
    /// sample's state.
    fn run_linear(&self, u: &[f64], dt_s: f64, x0: Vec<f64>, mut out: impl FnMut(&[f64])) -> Result<()> {
        let ss = self.state_space();
        let d = ss.c2d(dt_s)?;
        let ns = self.nstates();
        let step = AffineStep::new(d.ad.as_slice(), d.bd.column(0).as_slice(), &vec![0.0; ns])
            .ok_or_else(|| PlantError::Invalid(format!("{ns} states: more than an exact step takes")))?;
        let mut x = x0;
        let mut next = vec![0.0; ns];
        for &uk in u {
            out(&x);
            step.apply(&x, &[uk], &mut next);
            std::mem::swap(&mut x, &mut next);
        }
        Ok(())
    }

    /// Equilibrium under a constant torque: speeds equal (`speed0`; the drag then needs a
    /// torque the constant input may not supply, but only the twist matters to the response)
    /// and the side shafts carrying their static share.
    pub fn steady_state(&self, torque: f64, speed0: f64) -> Vec<f64> {
        let n = self.dofs();
        let mut x = vec![0.0; self.nstates()];
        for i in 0..n {
            x[n + i] = speed0;
        }
        // Static twist: the cage passes the torque to the shafts, a·T = input, T = torque/2;
        // with backlash the twist is beyond the play.
        let t_shaft = torque / 2.0;
        let s = t_shaft / self.c_s + self.effects.backlash_rad * t_shaft.signum() * f64::from(t_shaft != 0.0);
        // Put the twist on the cage: s = 2 φ_cage.
        x[1] = s / 2.0;
        if n == 4 {
            x[3] = x[1] + torque / self.effects.compliance_stiffness_nm_per_rad.max(1e-300);
        }
        if self.effects.actuator_lag_s > 0.0 {
            x[2 * n] = torque;
        }
        x
    }

    /// Side-shaft torques [T_short, T_long] of state `x`: stiffness on the twist beyond the
    /// play, damping only in contact.
    pub fn shaft_torques(&self, x: &[f64]) -> [f64; 2] {
        [0, 1].map(|k| self.dynamics.output(x, (Quantity::CouplingForce, k)))
    }

    /// ẋ for the torques [M_m2, M_drive, M_m3] (the drive torque already delayed).
    #[inline]
    pub fn derivative(&self, x: &[f64], torques: [f64; 3], dx: &mut [f64]) {
        self.dynamics.rhs(x, &torques, dx);
    }

    /// The RK4 steps of the nonlinear model (coarse, fine), s, in the diagnosis and in the FMU
    /// alike ([`crate::integrate::PiecewiseRk4`]): within a smooth piece h·rate ≤ 0.5 of the
    /// linear part's fastest rate, at most [`BACKLASH_STEP_S`] × 8; where a step leaves its piece,
    /// [`BACKLASH_STEP_S`] with backlash (contact switching makes the response sensitive to the
    /// step) and h·rate ≤ 0.5 of the friction's slopes T_c/(v_s J).
    pub fn rk4_steps_s(&self) -> (f64, f64) {
        (self.coarse_s, self.fine_s)
    }

    /// An integrator of this model ([`Powertrain::rk4_steps_s`]) for `nstates` states (the
    /// powertrain's, or a larger model's that embeds it).
    pub fn integrator(&self, nstates: usize) -> PiecewiseRk4 {
        PiecewiseRk4::new(nstates, self.coarse_s, self.fine_s)
    }

    /// The nonlinear model under the drive torque `u` (already delayed), stepped as every drive
    /// model is ([`HeldInputs`] on the diagnosis's integrator, the play's pieces exactly where
    /// it is the only nonlinearity: [`Dynamics::play_maps`]).
    fn simulate_rk4(&self, u: &[f64], dt_s: f64, mut x: Vec<f64>) -> (Vec<f64>, Vec<f64>) {
        let n = self.dofs();
        let mut rk = self.dynamics.integrator();
        let maps = self.dynamics.play_maps(&[dt_s]).and_then(|mut m| m.pop());
        let (mut w2, mut w3) = (Vec::with_capacity(u.len()), Vec::with_capacity(u.len()));
        // each sample starts in the piece the last one ended in
        let mut piece = None;
        let mut torques = [0.0; 3];
        for &uk in u {
            w2.push(x[n]);
            w3.push(x[n + 2]);
            torques[1] = uk;
            let held = &mut HeldInputs { d: &self.dynamics, u: &torques, maps: maps.as_ref() };
            piece = rk.advance_from(held, &mut x, dt_s, piece).1;
        }
        (w2, w3)
    }
}

/// The history of a piecewise-constant signal for a dead time: (time from which a value
/// holds, value), times increasing. Feeds the FMU's delayed drive torque.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DelayLine {
    records: Vec<(f64, f64)>,
}

impl DelayLine {
    /// The line of stored records (times increasing).
    pub fn from_records(records: Vec<(f64, f64)>) -> Option<DelayLine> {
        // the first record may start at −∞: the value held before the start
        let ok = records.windows(2).all(|w| w[0].0 < w[1].0)
            && records.iter().enumerate().all(|(i, r)| r.0.is_finite() || (i == 0 && r.0 == f64::NEG_INFINITY));
        ok.then_some(DelayLine { records })
    }

    /// The stored records.
    pub fn records(&self) -> &[(f64, f64)] {
        &self.records
    }

    /// The signal takes `value` from time `t` on (`f64::NEG_INFINITY`: the value it had before
    /// any recorded time, e.g. at initialisation). Records after `t` are dropped: an importer
    /// that goes back (a rejected solver step) overwrites what it set there.
    pub fn record(&mut self, t: f64, value: f64) {
        while self.records.last().is_some_and(|r| r.0 >= t) {
            self.records.pop();
        }
        if self.records.last().is_none_or(|r| r.1 != value) {
            self.records.push((t, value));
        }
    }

    /// The value at time `s`: the first value held before the first record; `current` if
    /// nothing was recorded.
    pub fn value_at(&self, s: f64, current: f64) -> f64 {
        match self.records.iter().rposition(|r| r.0 <= s) {
            Some(i) => self.records[i].1,
            None => self.records.first().map_or(current, |r| r.1),
        }
    }

    /// The signal delayed by `delay_s` over [t0, t1) as pieces (length, value), appended to `out`.
    pub fn segments(&self, t0: f64, t1: f64, delay_s: f64, current: f64, out: &mut Vec<(f64, f64)>) {
        let mut start = t0;
        let mut value = self.value_at(t0 - delay_s, current);
        for &(t, v) in &self.records {
            let at = t + delay_s;
            // breakpoints closer than 1e-12 of the step to its ends are the ends
            let tol = 1e-12 * (t1 - t0).abs().max(t1.abs());
            if at > start + tol && at < t1 - tol {
                out.push((at - start, value));
                start = at;
            }
            if at <= start + tol {
                value = v;
            }
        }
        out.push((t1 - start, value));
    }

    /// Drops what is no longer needed once the time reached `t`: records before the one in
    /// force at `t − delay_s`.
    pub fn forget_before(&mut self, t: f64, delay_s: f64) {
        if self.records.len() < 2 {
            return;
        }
        if let Some(i) = self.records.iter().rposition(|r| r.0 <= t - delay_s).filter(|&i| i > 0) {
            self.records.drain(..i);
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanical::Output;

    fn rig() -> RigParams {
        crate::paper::damped_params()
    }

    /// The rig's FMU step ([`crate::Stepper::paper_rig`]: the one drive-model step, in the rig's
    /// twist coordinates) replays what the diagnosis simulates ([`Powertrain::simulate`]) —
    /// with play alone (exact pieces), with friction and a compliance (RK4), with a dead time
    /// of whole samples (the diagnosis shifts the record; the FMU's delay line is exact at
    /// any dead time) and a lag (exact ZOH pieces) — under a torque that reverses through the
    /// play. The two share the right-hand side and the nonlinear integrator but not their
    /// loops, the dead time's handling, the linear model's discretisation or the coordinates
    /// (the FMU's twists against absolute angles): agreement to 1e-9 of the speeds' range is
    /// rounding, not a matched error.
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
            let p = Powertrain::new(&rig(), Variant::V1, &effects).unwrap();
            let (w2, w3) = p.simulate(&torque, dt, 5.0).unwrap();
            let mut stepper = crate::Stepper::paper_rig(&p).unwrap();
            let n = p.dofs();
            let mut z = stepper.state_of(&p.steady_state(torque[0], 5.0));
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
        let p = Powertrain::new(&rig, Variant::V1, &effects).unwrap();
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
            p.derivative(&x, u, &mut dx);
            let scale = by_hand.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for i in 0..9 {
                assert!(
                    (dx[i] - by_hand[i]).abs() <= 1e-12 * scale,
                    "s = {s_target}, state {i}: {} vs {}",
                    dx[i],
                    by_hand[i]
                );
            }
            let torques = p.shaft_torques(&x);
            let t_short = if t == 0.0 { 0.0 } else { t - d_s * sdot + e.d_left * cr / (cl + cr) * sdot };
            assert!((torques[0] - t_short).abs() <= 1e-12 * c_s, "{} vs {t_short}", torques[0]);
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
            let p = Powertrain::new(&rig(), variant, &DriveEffects::default()).unwrap();
            assert!((p.frequencies_hz()[2] - f[2]).abs() < 1e-9 * f[2]);
            assert_eq!(m.coupling_force_names(), ["T_short_side_shaft", "T_long_side_shaft"]);
            assert_eq!(m.state_names(), ["phi_m2", "phi_drive", "phi_m3", "w_m2", "w_drive", "w_m3"]);
        }
    }

    #[test]
    fn linear_part_is_the_open_differential() {
        // The same model assembled by MechanicalModel from the springs' elongation vectors.
        for variant in [Variant::V1, Variant::V3] {
            let p = Powertrain::new(&rig(), variant, &DriveEffects::default()).unwrap();
            let (a, b, c) = p.linear(true);
            let ss = rig().open_differential(variant).unwrap().state_space(&[Output::SpringTorques]).unwrap();
            assert!((&a - &ss.a).abs().max() < 1e-9 * ss.a.abs().max(), "A differs");
            assert!((&b - &ss.b).abs().max() < 1e-12 * ss.b.abs().max(), "B differs");
            assert!((&c - &ss.c).abs().max() < 1e-9 * ss.c.abs().max(), "C differs");
        }
    }

    #[test]
    fn control_state_space_is_the_open_differential_with_its_names() {
        // what the MPC predicts with: the MechanicalModel path's state space, names included
        let p = Powertrain::new(&rig(), Variant::V2, &DriveEffects::default()).unwrap();
        let ss = p.control_state_space();
        let reference = rig()
            .open_differential(Variant::V2)
            .unwrap()
            .state_space(&[Output::Speeds, Output::SpringTorques])
            .unwrap();
        assert_eq!(ss.state_names, reference.state_names);
        assert_eq!(ss.input_names, reference.input_names);
        assert_eq!(ss.output_names, reference.output_names);
        for (m, r) in [(&ss.a, &reference.a), (&ss.b, &reference.b), (&ss.c, &reference.c)] {
            assert!((m - r).abs().max() < 1e-9 * r.abs().max(), "{m} vs {r}");
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
        let p = Powertrain::new(&rig(), Variant::V1, &effects).unwrap();
        let ns = p.nstates();
        assert_eq!(ns, 9);
        let u = [3.0, 40.0, -5.0];
        let mut dx = vec![0.0; ns];
        for (twist, contact) in [(0.03, true), (0.004, false)] {
            // s = 2 φ_cage
            let mut x: Vec<f64> = (0..ns).map(|i| 1e-3 * (i as f64 - 3.0)).collect();
            x[0] = 0.0;
            x[2] = 0.0;
            x[1] = twist / 2.0;
            p.derivative(&x, u, &mut dx);
            let (a, b, c) = p.linear(true);
            let (a_open, b_open, _) = p.linear(false);
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
            let t = p.shaft_torques(&x);
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
        let p = Powertrain::new(&rig, Variant::V1, &effects).unwrap();
        let e = rig.effective(Variant::V1).unwrap();
        let j = [e.j_m2, e.j_drive, e.j_m3];
        let (w0, dt, n) = (20.0, 1e-3, 1000);
        let (w2, w3) = p.simulate(&vec![0.0; n], dt, w0).unwrap();
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
        let slopes = p.dynamics().friction_slopes(&x);
        assert_eq!(slopes.len(), 1);
        let (i, slope) = slopes[0];
        let h = 1e-6;
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[i] += h;
        xm[i] -= h;
        let (mut dp, mut dm) = (vec![0.0; 6], vec![0.0; 6]);
        p.derivative(&xp, [0.0; 3], &mut dp);
        p.derivative(&xm, [0.0; 3], &mut dm);
        // the springs' damping also depends on the speed: take it out through the linear part
        let (a, _, _) = p.linear(true);
        let fd = (dp[i] - dm[i]) / (2.0 * h) - a[(i, i)];
        assert!((fd - slope).abs() < 1e-6 * slope.abs(), "{fd} vs {slope}");
    }

    /// The reference: one plain classical RK4 step of length `h` with the torques held; `work` holds 5 scratch
    /// vectors of the state's length.
    fn rk4_step(p: &Powertrain, x: &mut [f64], torques: [f64; 3], h: f64, work: &mut [Vec<f64>; 5]) {
        let ns = x.len();
        let [k1, k2, k3, k4, tmp] = work;
        p.derivative(x, torques, k1);
        for i in 0..ns {
            tmp[i] = x[i] + 0.5 * h * k1[i];
        }
        p.derivative(tmp, torques, k2);
        for i in 0..ns {
            tmp[i] = x[i] + 0.5 * h * k2[i];
        }
        p.derivative(tmp, torques, k3);
        for i in 0..ns {
            tmp[i] = x[i] + h * k3[i];
        }
        p.derivative(tmp, torques, k4);
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
        let p = Powertrain::new(&rig(), Variant::V1, &e).unwrap();
        let t0 = std::time::Instant::now();
        let r = p.simulate(&vec![1.0; 60_000], 1e-3, 0.0);
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
            let p = Powertrain::new(&rig(), Variant::V1, &effects).unwrap();
            let dt = 1e-3;
            let torque: Vec<f64> = (0..5000)
                .map(|k| {
                    let t = k as f64 * dt;
                    8.0 * (2.0 * std::f64::consts::PI * (1.0 * t + 1.5 * t * t)).sin()
                })
                .collect();
            let (w2, _) = p.simulate(&torque, dt, 0.0).unwrap();
            let mut x = p.steady_state(torque[0], 0.0);
            let mut work: [Vec<f64>; 5] = std::array::from_fn(|_| vec![0.0; x.len()]);
            let mut reference = Vec::new();
            for &u in &torque {
                reference.push(x[3]);
                for _ in 0..40 {
                    rk4_step(&p, &mut x, [0.0, u, 0.0], dt / 40.0, &mut work);
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

    #[test]
    fn delay_line_shifts_a_held_signal() {
        let mut d = DelayLine::default();
        assert_eq!(d.value_at(5.0, 7.0), 7.0, "nothing recorded: the current value");
        d.record(0.0, 1.0);
        d.record(1e-3, 2.0);
        d.record(2e-3, 2.0); // unchanged: no new record
        assert_eq!(d.records().len(), 2);
        let mut out = Vec::new();
        // u(s − 1.5 ms) over [2 ms, 3 ms): 1 until 2.5 ms, then 2
        d.segments(2e-3, 3e-3, 1.5e-3, 2.0, &mut out);
        assert_eq!(out.len(), 2);
        assert!((out[0].0 - 0.5e-3).abs() < 1e-15 && out[0].1 == 1.0);
        assert!((out[1].0 - 0.5e-3).abs() < 1e-15 && out[1].1 == 2.0);
        // before the first record the first value holds
        assert_eq!(d.value_at(-1.0, 9.0), 1.0);
        // a rejected step: setting at an earlier time drops the later records
        d.record(0.5e-3, 4.0);
        assert_eq!(d.records(), &[(0.0, 1.0), (0.5e-3, 4.0)]);
        d.forget_before(10.0, 1e-3);
        assert_eq!(d.records(), &[(0.5e-3, 4.0)]);
    }
}
