//! Effects in the drive path that the reduced rig model leaves out, and the powertrain that has
//! them: a dead time and a first-order lag of the drive torque, backlash in the side shafts, and
//! a compliance inside the drive unit (its inertia split into motor and cage). Used by the
//! diagnosis (`ident::diagnose`) to extend a declared model; no I/O.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::error::{non_negative, PlantError, Result};
use crate::rig::{RigParams, Variant};
use crate::statespace::StateSpace;

/// The effects, each off at zero.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveEffects {
    /// Dead time of the drive torque, s.
    #[serde(default)]
    pub time_delay_s: f64,
    /// Time constant of a first-order lag of the drive torque, s.
    #[serde(default)]
    pub actuator_lag_s: f64,
    /// Total play of each side shaft (output side), rad.
    #[serde(default)]
    pub backlash_rad: f64,
    /// Stiffness between the drive's motor and its cage, Nm/rad (0: rigid drive).
    #[serde(default)]
    pub compliance_stiffness_nm_per_rad: f64,
    /// Share of j_drive on the motor side of that compliance (the rest is the cage).
    #[serde(default = "half")]
    pub compliance_motor_fraction: f64,
}

fn half() -> f64 {
    0.5
}

impl Default for DriveEffects {
    fn default() -> Self {
        DriveEffects {
            time_delay_s: 0.0,
            actuator_lag_s: 0.0,
            backlash_rad: 0.0,
            compliance_stiffness_nm_per_rad: 0.0,
            compliance_motor_fraction: 0.5,
        }
    }
}

impl DriveEffects {
    /// Checks ranges; names the key.
    pub fn validate(&self) -> Result<()> {
        non_negative(|| "effects.time_delay_s", self.time_delay_s, "s")?;
        non_negative(|| "effects.actuator_lag_s", self.actuator_lag_s, "s")?;
        non_negative(|| "effects.backlash_rad", self.backlash_rad, "rad")?;
        non_negative(|| "effects.compliance_stiffness_nm_per_rad", self.compliance_stiffness_nm_per_rad, "Nm/rad")?;
        if !(self.compliance_motor_fraction > 0.0 && self.compliance_motor_fraction < 1.0) {
            return Err(PlantError::Invalid(format!(
                "`effects.compliance_motor_fraction` must lie strictly between 0 and 1, got {}",
                self.compliance_motor_fraction
            )));
        }
        Ok(())
    }

    /// True when no effect is on.
    pub fn is_empty(&self) -> bool {
        self.time_delay_s == 0.0
            && self.actuator_lag_s == 0.0
            && self.backlash_rad == 0.0
            && self.compliance_stiffness_nm_per_rad == 0.0
    }
}

/// The open-differential powertrain (section 2.4) driven by the drive torque, with effects.
/// Coordinates: φ_m2, φ_cage, φ_m3 and, with a compliance, φ_motor; then their speeds; then,
/// with a lag, the lagged torque. The side shafts act through the generalised twist
/// s = aᵀq, a = [−1, 2, −1] on (m2, cage, m3), as two springs in series (eq. (A1)).
#[derive(Debug, Clone)]
pub struct Powertrain {
    inertia: DVector<f64>,
    /// Stiffness and damping besides the side shafts (the compliance), and the drag.
    k0: DMatrix<f64>,
    d0: DMatrix<f64>,
    a: DVector<f64>,
    c_s: f64,
    d_s: f64,
    input_dof: usize,
    /// The effects.
    pub effects: DriveEffects,
}

impl Powertrain {
    /// The powertrain of `rig` in `variant` with `effects`.
    pub fn new(rig: &RigParams, variant: Variant, effects: &DriveEffects) -> Result<Self> {
        effects.validate()?;
        let e = rig.effective(variant)?;
        let (cl, cr) = (e.c_left, e.c_right);
        let c_s = cl * cr / (cl + cr);
        // Damping of the series pair as open_differential builds it: each shaft's damping
        // acts on its share of the twist.
        let d_s = e.d_left * (cr / (cl + cr)).powi(2) + e.d_right * (cl / (cl + cr)).powi(2);
        let compliant = effects.compliance_stiffness_nm_per_rad > 0.0;
        let n = if compliant { 4 } else { 3 };
        let mut inertia = DVector::from_vec(vec![e.j_m2, e.j_drive, e.j_m3]);
        let mut k0 = DMatrix::zeros(n, n);
        let mut d0 = DMatrix::zeros(n, n);
        d0[(0, 0)] = e.load_drag;
        d0[(2, 2)] = e.load_drag;
        let mut a = DVector::zeros(n);
        a[0] = -1.0;
        a[1] = 2.0;
        a[2] = -1.0;
        let input_dof = if compliant {
            let f = effects.compliance_motor_fraction;
            inertia = DVector::from_vec(vec![e.j_m2, (1.0 - f) * e.j_drive, e.j_m3, f * e.j_drive]);
            // The compliance gets the side shafts' stiffness-proportional damping, d = (d_s/c_s) k
            // (the generic damping of section 4.3): an undamped internal mode would be a
            // resonance no measurement shows.
            let k = effects.compliance_stiffness_nm_per_rad;
            let d = d_s / c_s * k;
            for (m, v) in [(&mut k0, k), (&mut d0, d)] {
                m[(1, 1)] += v;
                m[(3, 3)] += v;
                m[(1, 3)] -= v;
                m[(3, 1)] -= v;
            }
            3
        } else {
            1
        };
        Ok(Powertrain { inertia, k0, d0, a, c_s, d_s, input_dof, effects: *effects })
    }

    fn dofs(&self) -> usize {
        self.inertia.len()
    }

    /// Number of states.
    pub fn nstates(&self) -> usize {
        2 * self.dofs() + usize::from(self.effects.actuator_lag_s > 0.0)
    }

    /// The linear part (backlash closed, the dead time left out): input the drive torque,
    /// outputs w_m2 and w_m3.
    pub fn state_space(&self) -> StateSpace {
        let n = self.dofs();
        let ns = self.nstates();
        let aat = &self.a * self.a.transpose();
        let k = &self.k0 + &aat * self.c_s;
        let d = &self.d0 + &aat * self.d_s;
        let mut a = DMatrix::zeros(ns, ns);
        let mut b = DMatrix::zeros(ns, 1);
        for i in 0..n {
            a[(i, n + i)] = 1.0;
            for j in 0..n {
                a[(n + i, j)] = -k[(i, j)] / self.inertia[i];
                a[(n + i, n + j)] = -d[(i, j)] / self.inertia[i];
            }
        }
        if self.effects.actuator_lag_s > 0.0 {
            let tau = self.effects.actuator_lag_s;
            a[(n + self.input_dof, 2 * n)] = 1.0 / self.inertia[self.input_dof];
            a[(2 * n, 2 * n)] = -1.0 / tau;
            b[(2 * n, 0)] = 1.0 / tau;
        } else {
            b[(n + self.input_dof, 0)] = 1.0 / self.inertia[self.input_dof];
        }
        let mut c = DMatrix::zeros(2, ns);
        c[(0, n)] = 1.0;
        c[(1, n + 2)] = 1.0;
        let mut names: Vec<String> =
            ["phi_m2", "phi_cage", "phi_m3", "phi_motor"][..n].iter().map(|s| s.to_string()).collect();
        names.extend(["w_m2", "w_cage", "w_m3", "w_motor"][..n].iter().map(|s| s.to_string()));
        if ns > 2 * n {
            names.push("M_drive_lagged".into());
        }
        StateSpace {
            a,
            b,
            c,
            d: DMatrix::zeros(2, 1),
            state_names: names,
            input_names: vec!["M_drive".into()],
            output_names: vec!["w_m2".into(), "w_m3".into()],
        }
    }

    /// Natural frequencies of the undamped linear part, Hz, ascending (the compliance adds
    /// one above the shuffle).
    pub fn frequencies_hz(&self) -> Vec<f64> {
        let n = self.dofs();
        let k = &self.k0 + &self.a * self.a.transpose() * self.c_s;
        let s = DMatrix::from_fn(n, n, |i, j| k[(i, j)] / (self.inertia[i] * self.inertia[j]).sqrt());
        let mut f: Vec<f64> =
            s.symmetric_eigenvalues().iter().map(|&l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)).collect();
        f.sort_by(|a, b| a.total_cmp(b));
        f
    }

    /// Load-machine speeds (w_m2, w_m3) for the drive torque `torque` sampled every `dt_s`
    /// (held between samples), from the steady state under `torque[0]` with every speed at
    /// `speed0`. Linear cases are exact (ZOH, the dead time by interpolating the torque);
    /// backlash is integrated by RK4 with 8 sub-steps per sample (contact switching makes the
    /// response sensitive to the step: 4 sub-steps left twice the misfit at the true play).
    pub fn simulate(&self, torque: &[f64], dt_s: f64, speed0: f64) -> Result<(Vec<f64>, Vec<f64>)> {
        let u = delayed(torque, dt_s, self.effects.time_delay_s);
        let x0 = self.steady_state(u.first().copied().unwrap_or(0.0), speed0);
        if self.effects.backlash_rad > 0.0 {
            return Ok(self.simulate_backlash(&u, dt_s, x0));
        }
        let ss = self.state_space();
        let d = ss.c2d(dt_s)?;
        let ns = self.nstates();
        let n = self.dofs();
        let ad: Vec<f64> = (0..ns * ns).map(|k| d.ad[(k / ns, k % ns)]).collect();
        let bd: Vec<f64> = (0..ns).map(|i| d.bd[(i, 0)]).collect();
        let (mut w2, mut w3) = (Vec::with_capacity(u.len()), Vec::with_capacity(u.len()));
        let mut x = x0;
        let mut next = vec![0.0; ns];
        for &uk in &u {
            w2.push(x[n]);
            w3.push(x[n + 2]);
            for i in 0..ns {
                let row = &ad[i * ns..(i + 1) * ns];
                next[i] = row.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>() + bd[i] * uk;
            }
            std::mem::swap(&mut x, &mut next);
        }
        Ok((w2, w3))
    }

    /// Equilibrium under a constant torque: speeds equal (`speed0`; the drag then needs a
    /// torque the constant input may not supply, but only the twist matters to the response)
    /// and the side shafts carrying their static share.
    fn steady_state(&self, torque: f64, speed0: f64) -> Vec<f64> {
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

    /// Shaft torque of the series pair at twist s and rate ṡ: dead zone of half-width b (each
    /// shaft's total play b/2 on either side, two in series), damping only in contact.
    fn shaft_torque(&self, s: f64, sdot: f64) -> f64 {
        let b = self.effects.backlash_rad;
        if s > b {
            self.c_s * (s - b) + self.d_s * sdot
        } else if s < -b {
            self.c_s * (s + b) + self.d_s * sdot
        } else {
            0.0
        }
    }

    fn derivative(&self, x: &[f64], u: f64, dx: &mut [f64], k0: &[f64], d0: &[f64], a: &[f64]) {
        let n = self.dofs();
        let s: f64 = (0..n).map(|i| a[i] * x[i]).sum();
        let sdot: f64 = (0..n).map(|i| a[i] * x[n + i]).sum();
        let t = self.shaft_torque(s, sdot);
        let drive = if self.effects.actuator_lag_s > 0.0 { x[2 * n] } else { u };
        for i in 0..n {
            dx[i] = x[n + i];
            let mut f = -a[i] * t;
            for j in 0..n {
                f -= k0[i * n + j] * x[j] + d0[i * n + j] * x[n + j];
            }
            if i == self.input_dof {
                f += drive;
            }
            dx[n + i] = f / self.inertia[i];
        }
        if self.effects.actuator_lag_s > 0.0 {
            dx[2 * n] = (u - x[2 * n]) / self.effects.actuator_lag_s;
        }
    }

    fn simulate_backlash(&self, u: &[f64], dt_s: f64, mut x: Vec<f64>) -> (Vec<f64>, Vec<f64>) {
        let n = self.dofs();
        let ns = x.len();
        let sub = 8;
        let k0: Vec<f64> = (0..n * n).map(|k| self.k0[(k / n, k % n)]).collect();
        let d0: Vec<f64> = (0..n * n).map(|k| self.d0[(k / n, k % n)]).collect();
        let a: Vec<f64> = self.a.iter().copied().collect();
        let h = dt_s / sub as f64;
        let (mut k1, mut k2, mut k3, mut k4, mut tmp) =
            (vec![0.0; ns], vec![0.0; ns], vec![0.0; ns], vec![0.0; ns], vec![0.0; ns]);
        let (mut w2, mut w3) = (Vec::with_capacity(u.len()), Vec::with_capacity(u.len()));
        for &uk in u {
            w2.push(x[n]);
            w3.push(x[n + 2]);
            for _ in 0..sub {
                self.derivative(&x, uk, &mut k1, &k0, &d0, &a);
                for i in 0..ns {
                    tmp[i] = x[i] + 0.5 * h * k1[i];
                }
                self.derivative(&tmp, uk, &mut k2, &k0, &d0, &a);
                for i in 0..ns {
                    tmp[i] = x[i] + 0.5 * h * k2[i];
                }
                self.derivative(&tmp, uk, &mut k3, &k0, &d0, &a);
                for i in 0..ns {
                    tmp[i] = x[i] + h * k3[i];
                }
                self.derivative(&tmp, uk, &mut k4, &k0, &d0, &a);
                for i in 0..ns {
                    x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
                }
            }
        }
        (w2, w3)
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
