//! The FMU's dynamics of a drivetrain model (`plant::DriveModel`: a line of bodies, couplings
//! and gear stages with its effects). The right-hand side, the outputs and the RK4 step are
//! `plant::Dynamics`' — the ones the diagnosis simulated the record with — so the FMU replays the
//! diagnosis's model, not a copy of it. The states are the plant's: positions, speeds, one per
//! lagged input. Co-simulation: the step is split where a delayed input changes (each input's
//! own dead time, from its history); each piece is exact (ZOH of the linear model, cached per
//! piece length) without friction and backlash, else the record simulation's integrator
//! (`plant::integrate::PiecewiseRk4` with `Dynamics::rk4_steps_s`: coarse steps within a smooth
//! piece, fine ones across a play's edges and a friction's steep band).

use nalgebra::{DMatrix, DVector};

use plant::drive::HeldInputs;
use plant::effects::DelayLine;
use plant::integrate::PiecewiseRk4;
use plant::{DriveModel, Dynamics, Quantity};

use crate::model::{longest_exact_piece, ZohCache, MAX_PIECES};

/// The dynamics of one drive model and the buffers of its step.
#[derive(Debug)]
pub struct DriveDynamics {
    /// The plant's model.
    pub dynamics: Dynamics,
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    /// Longest exact piece, s: ‖[A B]‖₁ · piece = `plant::statespace::ZOH_MAX_NORM` / 2^10.
    max_piece_s: f64,
    /// The nonlinear model's integrator.
    rk: PiecewiseRk4,
    cache: ZohCache,
    breaks: Vec<f64>,
    segments: Vec<(f64, f64)>,
    u_piece: Vec<f64>,
    couplings: usize,
    xs: DVector<f64>,
    next: DVector<f64>,
}

impl DriveDynamics {
    /// The dynamics of `m`; the error names what is wrong.
    pub fn new(m: &DriveModel) -> Result<DriveDynamics, String> {
        let dynamics = Dynamics::new(m).map_err(|e| e.to_string())?;
        let (a, b) = dynamics.linear();
        if a.iter().chain(b.iter()).any(|v| !v.is_finite()) {
            return Err("the parameters give a system matrix with non-finite entries".into());
        }
        let max_piece_s = longest_exact_piece(&a, &b)?;
        let (coarse, fine) = dynamics.rk4_steps_s();
        if dynamics.is_nonlinear() && !(coarse > 0.0 && fine > 0.0 && coarse.is_finite() && fine.is_finite()) {
            return Err("the model's rates are not finite".into());
        }
        let rk = dynamics.integrator();
        let nx = dynamics.nstates();
        let nu = dynamics.ninputs();
        Ok(DriveDynamics {
            max_piece_s,
            rk,
            a,
            b,
            cache: ZohCache::default(),
            breaks: Vec::new(),
            segments: Vec::new(),
            u_piece: vec![0.0; nu],
            couplings: m.line.couplings.len(),
            xs: DVector::zeros(nx),
            next: DVector::zeros(nx),
            dynamics,
        })
    }

    /// Number of states.
    pub fn nx(&self) -> usize {
        self.dynamics.nstates()
    }

    /// Number of couplings (coupling-force outputs).
    pub fn couplings(&self) -> usize {
        self.couplings
    }

    /// ẋ at state `x` with the inputs acting now (after their dead times).
    pub fn derivatives(&self, x: &[f64], u_acting: &[f64], out: &mut [f64]) {
        self.dynamics.rhs(x, u_acting, out);
    }

    /// Force (torque) of coupling `i` at state `x`.
    pub fn coupling_force(&self, x: &[f64], i: usize) -> f64 {
        self.dynamics.output(x, (Quantity::CouplingForce, i))
    }

    /// ∂ẋ/∂[x u] and ∂(coupling forces)/∂x at `x`, `u` by central differences of the plant's
    /// right-hand side (exact for the linear pieces up to rounding; the friction's smoothed
    /// slope and the backlash's piece where the state is). Steps: 1e-6 of the variable's size
    /// or of 1e-3 (a step of 1e-6 rad on a mrad twist).
    pub fn jacobians(&self, x: &[f64], u: &[f64]) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        let (nx, nu) = (x.len(), u.len());
        let nc = self.couplings;
        let mut a = DMatrix::zeros(nx, nx);
        let mut b = DMatrix::zeros(nx, nu);
        let mut c = DMatrix::zeros(nc, nx);
        let (mut xp, mut up) = (x.to_vec(), u.to_vec());
        let (mut fp, mut fm) = (vec![0.0; nx], vec![0.0; nx]);
        for j in 0..nx + nu {
            let v = if j < nx { x[j] } else { u[j - nx] };
            let h = 1e-6 * v.abs().max(1e-3);
            let set = |xp: &mut Vec<f64>, up: &mut Vec<f64>, to: f64| {
                if j < nx {
                    xp[j] = to
                } else {
                    up[j - nx] = to
                }
            };
            set(&mut xp, &mut up, v + h);
            self.dynamics.rhs(&xp, &up, &mut fp);
            let cp: Vec<f64> = (0..nc).map(|i| self.coupling_force(&xp, i)).collect();
            set(&mut xp, &mut up, v - h);
            self.dynamics.rhs(&xp, &up, &mut fm);
            let cm: Vec<f64> = (0..nc).map(|i| self.coupling_force(&xp, i)).collect();
            set(&mut xp, &mut up, v);
            for i in 0..nx {
                let d = (fp[i] - fm[i]) / (2.0 * h);
                if j < nx {
                    a[(i, j)] = d;
                } else {
                    b[(i, j - nx)] = d;
                }
            }
            if j < nx {
                for i in 0..nc {
                    c[(i, j)] = (cp[i] - cm[i]) / (2.0 * h);
                }
            }
        }
        (a, b, c)
    }

    /// One communication step of `x` over [t, t + h] with the inputs `u` set now (input j's
    /// past values in `delays[j]` when it has a dead time). A step longer than
    /// [`MAX_PIECES`] pieces or sub-steps is refused, and so is a state that comes out
    /// non-finite; `x` is then left as it was. Allocates only when a new piece length is
    /// discretised.
    pub fn step(
        &mut self,
        x: &mut DVector<f64>,
        u: &[f64],
        t: f64,
        h: f64,
        delays: &[DelayLine],
    ) -> Result<(), String> {
        let nonlinear = self.dynamics.is_nonlinear();
        let sub_steps = if nonlinear { h / self.rk.fine_s } else { h / self.max_piece_s };
        if sub_steps.is_nan() || sub_steps > MAX_PIECES as f64 {
            return Err(format!("a step of {h} s needs more than {MAX_PIECES} pieces for this model"));
        }
        // the instants in (t, t+h) where a delayed input switches
        self.breaks.clear();
        self.breaks.push(t);
        for (j, line) in delays.iter().enumerate() {
            let tau = self.dynamics.delay_s(j);
            if tau > 0.0 {
                self.segments.clear();
                line.segments(t, t + h, tau, u[j], &mut self.segments);
                let mut at = t;
                for &(len, _) in &self.segments[..self.segments.len().saturating_sub(1)] {
                    at += len;
                    self.breaks.push(at);
                }
            }
        }
        self.breaks.push(t + h);
        self.breaks.sort_by(|a, b| a.total_cmp(b));
        let tol = 1e-12 * h.max(t.abs());
        self.breaks.dedup_by(|b, a| (*b - *a).abs() <= tol);
        if self.breaks.len() < 2 {
            self.breaks.push(t + h);
        }
        let mut state = std::mem::take(&mut self.xs);
        state.copy_from(x);
        let mut result = Ok(());
        for p in 0..self.breaks.len() - 1 {
            let (a, b) = (self.breaks[p], self.breaks[p + 1]);
            let len = b - a;
            if len <= 0.0 {
                continue;
            }
            let mid = 0.5 * (a + b);
            for (j, value) in self.u_piece.iter_mut().enumerate() {
                let tau = self.dynamics.delay_s(j);
                *value = if tau > 0.0 { delays[j].value_at(mid - tau, u[j]) } else { u[j] };
            }
            if nonlinear {
                self.rk.advance(&mut HeldInputs { d: &self.dynamics, u: &self.u_piece }, state.as_mut_slice(), len);
            } else {
                let n = (len / self.max_piece_s).ceil().max(1.0) as usize;
                let i = match self.cache.index(&self.a, &self.b, len / n as f64) {
                    Ok(i) => i,
                    Err(e) => {
                        result = Err(e);
                        break;
                    }
                };
                for _ in 0..n {
                    self.cache.step(i, state.as_slice(), &self.u_piece, self.next.as_mut_slice());
                    state.copy_from(&self.next);
                }
            }
        }
        if result.is_ok() {
            if let Some(i) = state.iter().position(|v| !v.is_finite()) {
                result = Err(format!("state {i} became {} over the step from {t} s", state[i]));
            } else {
                x.copy_from(&state);
            }
        }
        self.xs = state;
        result
    }
}
