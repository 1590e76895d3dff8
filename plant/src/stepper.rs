//! A drivetrain model (`DriveModel`: a line of bodies, couplings and gear stages with its
//! effects) stepped over communication steps, as its FMU and the closed loops of `mpc` run it.
//! The right-hand side, the outputs and the RK4 step are [`Dynamics`]' — the ones the diagnosis
//! simulated the record with — so the FMU replays the diagnosis's model, not a copy of it. The states are z = [P q; q̇; lagged inputs]: the
//! positions enter as the couplings' twists (P's rows are the couplings' elongations, as many as
//! are independent) and, where the twists do not fix every position, a body's own position (the
//! line's rigid-body coordinate), so their magnitudes stay bounded under a torque that spins the
//! line up (as the rig's twist states; Modelica's `phi_rel`): an importer's tolerances then
//! bound the error of the coupling forces, which absolute angles of thousands of radians would
//! not (their difference loses the digits). The linear model is stepped and differentiated in z
//! itself; friction and backlash are evaluated at x = T z. Co-simulation: the step is split where a delayed input changes (each input's
//! own dead time, from its history); each piece is exact (ZOH of the linear model, cached per
//! piece length) without friction and backlash, else the record simulation's integrator
//! (`plant::integrate::PiecewiseRk4` with `Dynamics::rk4_steps_s`: coarse steps within a smooth
//! piece, fine ones across a play's edges and a friction's steep band).

use nalgebra::{DMatrix, DVector};

use crate::delay_line::DelayLine;
use crate::drive::{ExactSteps, HeldInputs, MAX_INPUTS};
use crate::error::{PlantError, Result};
use crate::integrate::PiecewiseRk4;
use crate::line::MAX_BODIES;
use crate::zoh_step::{longest_exact_piece, ZohCache, CACHE, MAX_PIECES};
use crate::{DriveModel, Dynamics, Quantity};

/// Most states a drive model has: positions and speeds of the largest line, one lag per input.
pub const MAX_STATES: usize = 2 * MAX_BODIES + MAX_INPUTS;

/// A position coordinate of the stepped state vector.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coordinate {
    /// The twist (elongation) of coupling i: eᵢᵀq.
    Twist(usize),
    /// The position of body i.
    Position(usize),
}

/// The position coordinates of `m` and the matrix P whose rows give them from the bodies'
/// positions (z_pos = P q): the couplings' elongations in order, each that is independent of
/// those before, then the bodies' own positions in order until P is invertible.
pub fn coordinates(m: &DriveModel) -> Result<(Vec<Coordinate>, DMatrix<f64>)> {
    let n = m.line.bodies.len();
    let springs = m.line.model()?.springs;
    let candidates = springs
        .iter()
        .enumerate()
        .map(|(k, s)| (Coordinate::Twist(k), s.elongation.clone()))
        .chain((0..n).map(|b| (Coordinate::Position(b), DVector::from_fn(n, |i, _| f64::from(u8::from(i == b))))));
    let (mut chosen, mut rows, mut basis): (Vec<Coordinate>, Vec<DVector<f64>>, Vec<DVector<f64>>) =
        (Vec::new(), Vec::new(), Vec::new());
    for (c, v) in candidates {
        if chosen.len() == n {
            break;
        }
        // Gram-Schmidt: what of v the rows chosen so far do not span
        let mut r = v.clone();
        for b in &basis {
            r -= b * b.dot(&v);
        }
        if r.norm() > 1e-9 * v.norm() {
            basis.push(&r / r.norm());
            chosen.push(c);
            rows.push(v);
        }
    }
    let p = DMatrix::from_fn(n, n, |i, j| rows[i][j]);
    Ok((chosen, p))
}

/// The dynamics of one drive model and the buffers of its step.
#[derive(Debug)]
pub struct Stepper {
    /// The plant's model.
    pub dynamics: Dynamics,
    /// Number of position coordinates (bodies).
    npos: usize,
    /// x = to_x z (the plant's state from the stepped one).
    to_x: DMatrix<f64>,
    /// z = to_z x.
    to_z: DMatrix<f64>,
    /// The linear model in z: ż = a z + b u.
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    /// The couplings' forces in contact, rows over z.
    forces: DMatrix<f64>,
    /// Scratch: the plant's state and its derivative.
    x_plant: Vec<f64>,
    dx_plant: Vec<f64>,
    /// Longest exact piece, s: ‖[A B]‖₁ · piece = `plant::statespace::ZOH_MAX_NORM` / 2^10.
    max_piece_s: f64,
    /// The nonlinear model's integrator.
    rk: PiecewiseRk4,
    cache: ZohCache,
    /// Whole steps of a model whose only nonlinearity is play that engages at once or friction
    /// (`Dynamics::exact_steps`), per piece length (at most [`CACHE`] lengths).
    exact_steps: Vec<ExactSteps>,
    /// Whether `exact_steps` applies to this model.
    has_exact_steps: bool,
    /// No input has a dead time.
    undelayed: bool,
    breaks: Vec<f64>,
    segments: Vec<(f64, f64)>,
    u_piece: Vec<f64>,
    couplings: usize,
    xs: DVector<f64>,
}

impl Stepper {
    /// The dynamics of `m`, its positions entering as [`coordinates`] chooses them; the error
    /// names what is wrong.
    pub fn new(m: &DriveModel) -> Result<Stepper> {
        let (_, p) = coordinates(m)?;
        Stepper::with_positions(m, Dynamics::new(m)?, &p)
    }

    /// The dynamics `dynamics` of `m` (a preset may choose its integrator's steps) with the
    /// position coordinates z_pos = P q of the invertible `p` (a preset may choose its own
    /// twists, as the paper rig's FMU keeps the differential's twist and the load machines'
    /// angles); the error names what is wrong.
    pub fn with_positions(m: &DriveModel, dynamics: Dynamics, p: &DMatrix<f64>) -> Result<Stepper> {
        let (a, b) = dynamics.linear();
        if a.iter().chain(b.iter()).any(|v| !v.is_finite()) {
            return Err(PlantError::Invalid("the parameters give a system matrix with non-finite entries".into()));
        }
        let nx = dynamics.nstates();
        if nx > MAX_STATES {
            return Err(PlantError::Invalid(format!("{nx} states: at most {MAX_STATES}")));
        }
        let n = m.line.bodies.len();
        if p.shape() != (n, n) {
            return Err(PlantError::Invalid(format!("{} position coordinates for {n} bodies", p.nrows())));
        }
        let p_inv = p
            .clone()
            .try_inverse()
            .ok_or_else(|| PlantError::Invalid("the couplings' elongations and the positions are dependent".into()))?;
        let mut to_z = DMatrix::identity(nx, nx);
        let mut to_x = DMatrix::identity(nx, nx);
        to_z.view_mut((0, 0), (n, n)).copy_from(p);
        to_x.view_mut((0, 0), (n, n)).copy_from(&p_inv);
        let (a, b) = (&to_z * a * &to_x, &to_z * b);
        let forces = m.coupling_forces(nx) * &to_x;
        let max_piece_s = longest_exact_piece(&a, &b)?;
        let (coarse, fine) = dynamics.rk4_steps_s();
        if dynamics.is_nonlinear() && !(coarse > 0.0 && fine > 0.0 && coarse.is_finite() && fine.is_finite()) {
            return Err(PlantError::Invalid("the model's rates are not finite".into()));
        }
        let rk = dynamics.integrator();
        let nu = dynamics.ninputs();
        let has_exact_steps = dynamics.has_exact_steps();
        let undelayed = (0..nu).all(|j| dynamics.delay_s(j) <= 0.0);
        Ok(Stepper {
            npos: n,
            to_x,
            to_z,
            forces,
            x_plant: vec![0.0; nx],
            dx_plant: vec![0.0; nx],
            max_piece_s,
            rk,
            a,
            b,
            cache: ZohCache::default(),
            exact_steps: Vec::new(),
            has_exact_steps,
            undelayed,
            breaks: Vec::new(),
            segments: Vec::new(),
            u_piece: vec![0.0; nu],
            couplings: m.line.couplings.len(),
            xs: DVector::zeros(nx),
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

    /// The stepped state of the plant's state `x`.
    pub fn state_of(&self, x: &[f64]) -> DVector<f64> {
        &self.to_z * DVector::from_column_slice(x)
    }

    /// Every body's position at state `z`.
    pub fn positions(&self, z: &[f64]) -> Vec<f64> {
        let mut q = vec![0.0; self.npos];
        self.positions_into(z, &mut q);
        q
    }

    /// Every body's position at state `z` into `out` (at least one slot per body).
    /// Allocation-free.
    pub fn positions_into(&self, z: &[f64], out: &mut [f64]) {
        let n = self.npos;
        for (i, o) in out.iter_mut().take(n).enumerate() {
            *o = (0..n).map(|j| self.to_x[(i, j)] * z[j]).sum();
        }
    }

    /// Number of bodies.
    pub fn bodies(&self) -> usize {
        self.npos
    }

    /// ∂(position of body i)/∂z_j.
    pub fn position_gradient(&self, i: usize, j: usize) -> f64 {
        if j < self.npos {
            self.to_x[(i, j)]
        } else {
            0.0
        }
    }

    /// ż at state `z` with the inputs acting now (after their dead times). Allocation-free.
    pub fn derivatives(&mut self, z: &[f64], u_acting: &[f64], out: &mut [f64]) {
        if self.dynamics.is_nonlinear() {
            self.set_plant_state(z);
            self.dynamics.rhs(&self.x_plant, u_acting, &mut self.dx_plant);
            for (i, o) in out.iter_mut().enumerate() {
                *o = self.to_z.row(i).iter().zip(&self.dx_plant).map(|(t, v)| t * v).sum();
            }
        } else {
            for (i, o) in out.iter_mut().enumerate() {
                let ax: f64 = self.a.row(i).iter().zip(z).map(|(a, v)| a * v).sum();
                *o = ax + self.b.row(i).iter().zip(u_acting).map(|(b, v)| b * v).sum::<f64>();
            }
        }
    }

    /// x_plant ← to_x z.
    fn set_plant_state(&mut self, z: &[f64]) {
        for (i, x) in self.x_plant.iter_mut().enumerate() {
            *x = self.to_x.row(i).iter().zip(z).map(|(t, v)| t * v).sum();
        }
    }

    /// Every coupling's force (torque) at state `z` into `out` (one per coupling): from the
    /// twists themselves while the model is linear, else the plant's (play, friction) at
    /// x = T z. Allocation-free.
    pub fn coupling_forces(&mut self, z: &[f64], out: &mut [f64]) {
        if self.dynamics.is_nonlinear() {
            self.set_plant_state(z);
            for (i, o) in out.iter_mut().enumerate() {
                *o = self.dynamics.output(&self.x_plant, (Quantity::CouplingForce, i));
            }
        } else {
            for (i, o) in out.iter_mut().enumerate() {
                *o = self.forces.row(i).iter().zip(z).map(|(c, v)| c * v).sum();
            }
        }
    }

    /// ∂ż/∂[z u] and ∂(coupling forces)/∂z at `z`, `u`: the plant's by central differences of
    /// its right-hand side at x = T z (exact for the linear pieces up to rounding; the
    /// friction's smoothed slope and the backlash's piece where the state is; steps 1e-6 of
    /// the variable's size or of 1e-3), in z.
    pub fn jacobians(&self, z: &[f64], u: &[f64]) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
        if !self.dynamics.is_nonlinear() {
            return (self.a.clone(), self.b.clone(), self.forces.clone());
        }
        let x = &self.to_x * DVector::from_column_slice(z);
        let x = x.as_slice();
        let (nx, nu) = (x.len(), u.len());
        let nc = self.couplings;
        let mut a = DMatrix::zeros(nx, nx);
        let mut b = DMatrix::zeros(nx, nu);
        let mut c = DMatrix::zeros(nc, nx);
        let (mut xp, mut up) = (x.to_vec(), u.to_vec());
        let (mut fp, mut fm) = (vec![0.0; nx], vec![0.0; nx]);
        let force = |x: &[f64], i: usize| self.dynamics.output(x, (Quantity::CouplingForce, i));
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
            let cp: Vec<f64> = (0..nc).map(|i| force(&xp, i)).collect();
            set(&mut xp, &mut up, v - h);
            self.dynamics.rhs(&xp, &up, &mut fm);
            let cm: Vec<f64> = (0..nc).map(|i| force(&xp, i)).collect();
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
        (&self.to_z * a * &self.to_x, &self.to_z * b, c * &self.to_x)
    }

    /// One communication step of `x` over [t, t + h] with the inputs `u` set now (input j's
    /// past values in `delays[j]` when it has a dead time). A step longer than
    /// [`MAX_PIECES`] pieces or sub-steps is refused, and so is a state that comes out
    /// non-finite; `x` is then left as it was. Allocates only when a new piece length is
    /// discretised.
    pub fn step(&mut self, x: &mut DVector<f64>, u: &[f64], t: f64, h: f64, delays: &[DelayLine]) -> Result<()> {
        let nonlinear = self.dynamics.is_nonlinear();
        // the common case — linear, no dead time: one exact step over [Ad Bd]
        if !nonlinear && self.undelayed && h <= MAX_PIECES as f64 * self.max_piece_s {
            let i = self.cache.index(&self.a, &self.b, h, self.max_piece_s)?;
            return self
                .cache
                .advance(i, x.as_mut_slice(), u)
                .map_err(|k| PlantError::Invalid(format!("state {k} became non-finite over the step from {t} s")));
        }
        let finest = if nonlinear { self.rk.fine_s } else { self.max_piece_s };
        let sub_steps = h / finest;
        if sub_steps.is_nan() || sub_steps > MAX_PIECES as f64 {
            let longest = MAX_PIECES as f64 * finest;
            return Err(PlantError::Invalid(format!(
                "a step of {h} s is longer than this model integrates exactly (at most {longest:.4e} s: {MAX_PIECES} \
                 pieces)"
            )));
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
        // the linear model steps z itself; the nonlinear one the plant's x = T z
        let mut state = std::mem::take(&mut self.xs);
        if nonlinear {
            state.gemv(1.0, &self.to_x, x, 0.0);
        } else {
            state.copy_from(x);
        }
        let mut result = Ok(());
        for p in 0..self.breaks.len() - 1 {
            let (a, b) = (self.breaks[p], self.breaks[p + 1]);
            // one piece is the whole step: its length exactly h (a cached piece length)
            let len = if self.breaks.len() == 2 { h } else { b - a };
            if len <= 0.0 {
                continue;
            }
            let mid = 0.5 * (a + b);
            for (j, value) in self.u_piece.iter_mut().enumerate() {
                let tau = self.dynamics.delay_s(j);
                *value = if tau > 0.0 { delays[j].value_at(mid - tau, u[j]) } else { u[j] };
            }
            if nonlinear {
                let maps = self.exact_steps_for(len);
                self.rk.advance(
                    &mut HeldInputs { d: &self.dynamics, u: &self.u_piece, maps: maps.map(|i| &self.exact_steps[i]) },
                    state.as_mut_slice(),
                    len,
                );
            } else {
                let i = match self.cache.index(&self.a, &self.b, len, self.max_piece_s) {
                    Ok(i) => i,
                    Err(e) => {
                        result = Err(e);
                        break;
                    }
                };
                if let Err(k) = self.cache.advance(i, state.as_mut_slice(), &self.u_piece) {
                    result = Err(PlantError::Invalid(format!("state {k} became non-finite over the step from {t} s")));
                    break;
                }
            }
        }
        if result.is_ok() {
            if let Some(i) = state.iter().position(|v| !v.is_finite()) {
                result = Err(PlantError::Invalid(format!("state {i} became {} over the step from {t} s", state[i])));
            } else {
                if nonlinear {
                    x.gemv(1.0, &self.to_z, &state, 0.0);
                } else {
                    x.copy_from(&state);
                }
            }
        }
        self.xs = state;
        result
    }

    /// The index of the exact piece steps of length `h` (built on first use, [`CACHE`]
    /// lengths kept); `None` where the model's pieces are not linear (RK4 alone then).
    fn exact_steps_for(&mut self, h: f64) -> Option<usize> {
        if !self.has_exact_steps {
            return None;
        }
        if let Some(i) = self.exact_steps.iter().position(|m| m.h() == h) {
            return Some(i);
        }
        let maps = self.dynamics.exact_steps(&[h])?.pop()?;
        if self.exact_steps.len() >= CACHE {
            self.exact_steps.remove(0);
        }
        self.exact_steps.push(maps);
        Some(self.exact_steps.len() - 1)
    }

    /// (Ad, Bd) of the linear model in z over `h` (the common step's matrices: a reference
    /// implementation can be run on them).
    pub fn discretisation(&mut self, h: f64) -> Result<(&DMatrix<f64>, &DMatrix<f64>)> {
        let i = self.cache.index(&self.a, &self.b, h, self.max_piece_s)?;
        Ok(self.cache.get(i))
    }
}
