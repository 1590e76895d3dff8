//! The controller: estimate, steady-state target, QP, first input — allocation-free per step.

use std::time::Instant;

use nalgebra::{DMatrix, DVector};
use plant::statespace::StateSpace;

use crate::error::{setting, MpcError, Result};
use crate::estimator::Estimator;
use crate::model::PredictionModel;
use crate::qp::{ParametricQp, QpSnapshot, Weights};
use crate::settings::{MpcSettings, SolverSettings};
use crate::solver::{QpSolver, SolveInfo};
use plant::riccati::dare;

/// What one controller step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepInfo {
    /// The QP solve.
    pub solve: SolveInfo,
    /// The shifted previous plan was applied (solve failed, was infeasible or ran late).
    pub fallback: bool,
    /// Wall-clock time of the whole step (estimate + target + QP + bookkeeping), s.
    pub elapsed_s: f64,
}

/// A model-predictive controller for one plant.
pub struct Controller {
    settings: MpcSettings,
    model: PredictionModel,
    qp: ParametricQp,
    solver: QpSolver,
    estimator: Estimator,
    /// Plant output indices that are measured, in estimator order.
    measured: Vec<usize>,
    /// Plant output indices that have references, then input indices that have references.
    tracked_outputs: Vec<usize>,
    tracked_inputs: Vec<usize>,
    /// [x_s; u_s] = target_d d + target_r r.
    target_d: DMatrix<f64>,
    target_r: DMatrix<f64>,
    bounds: Vec<(f64, f64, f64)>,
    theta: DVector<f64>,
    target: DVector<f64>,
    q: DVector<f64>,
    b: DVector<f64>,
    ymeas: Vec<f64>,
    u: DVector<f64>,
    plan: DVector<f64>,
    plan_step: usize,
    plan_valid: bool,
    fallbacks: usize,
}

impl Controller {
    /// Builds the controller for the continuous plant `plant` (discretised by ZOH here).
    pub fn new(plant: &StateSpace, settings: &MpcSettings) -> Result<Self> {
        Self::with_input_delays(plant, &[], settings)
    }

    /// As [`Controller::new`] for a plant whose input j acts `input_delays_s[j]` late (empty:
    /// none): the prediction carries the inputs on their way as states
    /// ([`PredictionModel::with_input_delays`]).
    pub fn with_input_delays(plant: &StateSpace, input_delays_s: &[f64], settings: &MpcSettings) -> Result<Self> {
        settings.validate()?;
        let model = PredictionModel::with_input_delays(plant, settings.dt_s, input_delays_s)?;
        let (n, m) = (model.nstates(), model.ninputs());
        if settings.inputs.len() != m {
            return Err(setting(
                "inputs",
                format!("every plant input needs settings: the plant has {} ({})", m, model.input_names.join(", ")),
            ));
        }
        // Inputs in the plant's order.
        let mut input_of = vec![usize::MAX; m];
        for (i, u) in settings.inputs.iter().enumerate() {
            let j = model.input(&format!("inputs[{i}].name"), &u.name)?;
            if input_of[j] != usize::MAX {
                return Err(setting(format!("inputs[{i}].name"), format!("`{}` is listed twice", u.name)));
            }
            input_of[j] = i;
        }
        let ins: Vec<_> = input_of.iter().map(|&i| &settings.inputs[i]).collect();
        let dt = settings.dt_s;
        let bounds: Vec<(f64, f64, f64)> = ins.iter().map(|u| (u.min_nm, u.max_nm, u.max_rate_nm_per_s * dt)).collect();

        let mut q = DMatrix::zeros(n, n);
        let mut soft = Vec::new();
        let (mut measured, mut noise, mut tracked_outputs) = (Vec::new(), Vec::new(), Vec::new());
        for (i, y) in settings.outputs.iter().enumerate() {
            let j = model.output(&format!("outputs[{i}].name"), &y.name)?;
            let c = model.c.rows(j, 1).into_owned();
            q += c.transpose() * &c * y.weight;
            if let Some(s) = y.noise_std {
                measured.push(j);
                noise.push(s * s);
            }
            if y.tracked {
                tracked_outputs.push(j);
            }
            if y.soft_min.is_some() || y.soft_max.is_some() {
                soft.push((c, y.soft_min, y.soft_max));
            }
        }
        let tracked_inputs: Vec<usize> = (0..m).filter(|&j| ins[j].tracked).collect();
        let r = DMatrix::from_diagonal(&DVector::from_iterator(m, ins.iter().map(|u| u.weight_per_nm2)));
        let s = DMatrix::from_diagonal(&DVector::from_iterator(m, ins.iter().map(|u| u.rate_weight_per_nm2)));
        let p = if settings.terminal_cost {
            // Terminal cost: the infinite-horizon cost-to-go of the LQR for (A, B, Q, R).
            dare(&model.a, &model.b, &q, &r).map_err(|e| MpcError::Numerical(format!("terminal cost: {e}")))?.x
        } else {
            q.clone()
        };
        let weights = Weights { q, p, r, s, soft, input_bounds: bounds.clone() };
        let qp = ParametricQp::new(&model, &weights, settings);
        let solver = QpSolver::new(&qp, &settings.solver)?;

        // Estimator on the measured outputs.
        let c_meas = DMatrix::from_fn(measured.len(), n, |i, j| model.c[(measured[i], j)]);
        let v = DVector::from_vec(noise);
        let vmean = v.mean();
        // the dead-time buffers hold inputs the controller applied: known, no process noise
        let w_x =
            DVector::from_fn(n, |i, _| if i < model.plant_states() { settings.state_noise_ratio * vmean } else { 0.0 });
        let disturbed: Vec<usize> = (0..m).filter(|&j| ins[j].disturbance_std_nm > 0.0).collect();
        let w_d = DVector::from_iterator(disturbed.len(), disturbed.iter().map(|&j| ins[j].disturbance_std_nm.powi(2)));
        let estimator = Estimator::new(&model.a, &model.b, &disturbed, &c_meas, &w_x, &w_d, &v)
            .map_err(|e| MpcError::Numerical(format!("estimator: {e}")))?;

        // Steady-state target: (I − A) x_s − B u_s = B d, C_t x_s = r_y, u_s[t] = r_u.
        let nr = tracked_outputs.len() + tracked_inputs.len();
        let mut eqs = DMatrix::zeros(n + nr, n + m);
        eqs.view_mut((0, 0), (n, n)).copy_from(&(DMatrix::identity(n, n) - &model.a));
        eqs.view_mut((0, n), (n, m)).copy_from(&(-&model.b));
        for (k, &j) in tracked_outputs.iter().enumerate() {
            eqs.view_mut((n + k, 0), (1, n)).copy_from(&model.c.rows(j, 1));
        }
        for (k, &j) in tracked_inputs.iter().enumerate() {
            eqs[(n + tracked_outputs.len() + k, n + j)] = 1.0;
        }
        let svd = eqs.clone().svd(true, true);
        let smax = svd.singular_values.max();
        let rank = svd.singular_values.iter().filter(|&&s| s > 1e-10 * smax).count();
        if rank < n + m {
            return Err(setting(
                "outputs/inputs tracked",
                format!(
                    "the references do not fix a unique steady state ({} of {} conditions independent): track as many independent outputs and inputs as the plant has inputs",
                    rank,
                    n + m
                ),
            ));
        }
        let pinv = svd.pseudo_inverse(1e-10 * smax).map_err(|e| MpcError::Numerical(e.to_string()))?;
        let mut rhs_d = DMatrix::zeros(n + nr, m);
        rhs_d.view_mut((0, 0), (n, m)).copy_from(&model.b);
        let mut rhs_r = DMatrix::zeros(n + nr, nr);
        rhs_r.view_mut((n, 0), (nr, nr)).fill_with_identity();
        let target_d = &pinv * rhs_d;
        let target_r = &pinv * rhs_r;

        let horizon = settings.horizon;
        Ok(Controller {
            theta: DVector::zeros(qp.theta.len()),
            target: DVector::zeros(n + m),
            q: DVector::zeros(qp.nvars()),
            b: DVector::zeros(qp.nrows()),
            ymeas: vec![0.0; measured.len()],
            u: DVector::zeros(m),
            plan: DVector::zeros(horizon * m),
            plan_step: 0,
            plan_valid: false,
            fallbacks: 0,
            settings: settings.clone(),
            model,
            qp,
            solver,
            estimator,
            measured,
            tracked_outputs,
            tracked_inputs,
            target_d,
            target_r,
            bounds,
        })
    }

    /// Names of the references, in the order [`Controller::step`] takes them: tracked outputs,
    /// then tracked inputs.
    pub fn reference_names(&self) -> Vec<String> {
        self.tracked_outputs
            .iter()
            .map(|&j| self.model.output_names[j].clone())
            .chain(self.tracked_inputs.iter().map(|&j| self.model.input_names[j].clone()))
            .collect()
    }

    /// Starts from the plant state `x_plant` (plant coordinates) with inputs `u`, Nm.
    pub fn reset(&mut self, x_plant: &DVector<f64>, u: &[f64]) {
        let z = self.model.state_of(x_plant, u);
        self.estimator.reset(&z);
        self.u.copy_from_slice(u);
        self.plan_valid = false;
    }

    /// One control step: `y` holds every plant output (the measured ones are picked),
    /// `reference` the references of [`Controller::reference_names`]. Returns the input to
    /// apply now (plant order, Nm) and what happened. Allocation-free.
    pub fn step(&mut self, y: &[f64], reference: &[f64]) -> (&[f64], StepInfo) {
        let start = Instant::now();
        for (k, &j) in self.measured.iter().enumerate() {
            self.ymeas[k] = y[j];
        }
        self.estimator.correct(&self.ymeas);
        let (n, m) = (self.model.nstates(), self.model.ninputs());
        let lay = self.qp.theta;
        self.theta.rows_mut(lay.x0(), n).copy_from(&self.estimator.state());
        self.theta.rows_mut(lay.d(), m).copy_from(self.estimator.disturbance());
        // Target from d and r; references beyond those expected are ignored, missing are 0.
        self.target.gemv(1.0, &self.target_d, &self.theta.rows(lay.d(), m), 0.0);
        for (k, col) in self.target_r.column_iter().enumerate() {
            let rk = reference.get(k).copied().unwrap_or(0.0);
            self.target.axpy(rk, &col, 1.0);
        }
        self.theta.rows_mut(lay.xs(), n).copy_from(&self.target.rows(0, n));
        self.theta.rows_mut(lay.us(), m).copy_from(&self.target.rows(n, m));
        self.theta.rows_mut(lay.uprev(), m).copy_from(&self.u);
        self.qp.evaluate(&self.theta, &mut self.q, &mut self.b);
        let solve = self.solver.solve(&self.q, &self.b);
        let fallback = !solve.ok;
        if solve.ok {
            let z = nalgebra::DVectorView::from_slice(self.solver.x(), self.qp.nvars());
            self.plan.gemv(1.0, &self.qp.plan, &z, 0.0);
            self.plan_step = 0;
            self.plan_valid = true;
        } else {
            self.fallbacks += 1;
            self.plan_step += 1;
        }
        // Apply: the plan's current step (the shifted previous plan on fallback; its last
        // input beyond the horizon; the previous input when there never was a plan), kept
        // within the hard bounds and rate limits.
        for i in 0..m {
            let planned = if self.plan_valid {
                let k = self.plan_step.min(self.settings.horizon - 1);
                self.plan[k * m + i]
            } else {
                self.u[i]
            };
            let (lo, hi, dmax) = self.bounds[i];
            let prev = self.u[i];
            self.u[i] = planned.clamp(prev - dmax, prev + dmax).clamp(lo, hi);
        }
        self.estimator.predict(&self.u);
        let info = StepInfo { solve, fallback, elapsed_s: start.elapsed().as_secs_f64() };
        (self.u.as_slice(), info)
    }

    /// Length of the record of [`Controller::save_state`].
    pub fn state_len(&self) -> usize {
        self.estimator.state_len() + self.u.len() + self.plan.len() + 3
    }

    /// Writes what the controller carries from step to step — the Kalman filter's estimates,
    /// the last input, the plan and where in it the controller is, the fallback count — into
    /// `out` (length [`Controller::state_len`]); no allocation. With
    /// [`Controller::restore_state`], an FMU's get/set/serialize state.
    pub fn save_state(&self, out: &mut [f64]) {
        let ne = self.estimator.state_len();
        let (m, np) = (self.u.len(), self.plan.len());
        self.estimator.save(&mut out[..ne]);
        out[ne..ne + m].copy_from_slice(self.u.as_slice());
        out[ne + m..ne + m + np].copy_from_slice(self.plan.as_slice());
        out[ne + m + np] = self.plan_step as f64;
        out[ne + m + np + 1] = f64::from(u8::from(self.plan_valid));
        out[ne + m + np + 2] = self.fallbacks as f64;
    }

    /// Restores a record of [`Controller::save_state`] from a controller of the same
    /// structure (horizon, model); false (and nothing changed) when its length or content
    /// cannot be one.
    pub fn restore_state(&mut self, s: &[f64]) -> bool {
        if s.len() != self.state_len() || s.iter().any(|v| !v.is_finite()) {
            return false;
        }
        let ne = self.estimator.state_len();
        let (m, np) = (self.u.len(), self.plan.len());
        let count = |v: f64| (v >= 0.0 && v.fract() == 0.0 && v < 1e12).then_some(v as usize);
        let (Some(step), Some(fallbacks)) = (count(s[ne + m + np]), count(s[ne + m + np + 2])) else {
            return false;
        };
        self.estimator.restore(&s[..ne]);
        self.u.as_mut_slice().copy_from_slice(&s[ne..ne + m]);
        self.plan.as_mut_slice().copy_from_slice(&s[ne + m..ne + m + np]);
        self.plan_step = step;
        self.plan_valid = s[ne + m + np + 1] != 0.0;
        self.fallbacks = fallbacks;
        true
    }

    /// Steps that used the fallback so far.
    pub fn fallbacks(&self) -> usize {
        self.fallbacks
    }

    /// The prediction model.
    pub fn model(&self) -> &PredictionModel {
        &self.model
    }

    /// The posed QP.
    pub fn qp(&self) -> &ParametricQp {
        &self.qp
    }

    /// The last step's parameter vector θ.
    pub fn theta(&self) -> &DVector<f64> {
        &self.theta
    }

    /// The last step's QP, densely (for other solvers).
    pub fn snapshot(&self) -> QpSnapshot {
        self.qp.snapshot(&self.theta)
    }

    /// The first input of the last step's QP solved to 1e-12 (Clarabel, no time limit), Nm;
    /// the reference against which the real-time solve's first input is judged.
    pub fn exact_first_input(&self) -> Result<Vec<f64>> {
        let tight = SolverSettings {
            tol_gap: 1e-12,
            tol_feas: 1e-12,
            max_iter: 500,
            time_limit_s: f64::INFINITY,
            equilibrate: true,
            iterative_refinement: true,
            // the reference is the interior-point solve, whatever the real-time path took
            unconstrained_check: false,
        };
        let mut solver = QpSolver::new(&self.qp, &tight)?;
        let info = solver.solve(&self.q, &self.b);
        if !info.ok {
            return Err(MpcError::Solver(format!("reference solve ended {:?}", info.status)));
        }
        let z = DVector::from_column_slice(solver.x());
        let m = self.model.ninputs();
        Ok((self.qp.plan.rows(0, m) * z).iter().copied().collect())
    }

    /// The first input of the last real-time solve (before rate/bound clamping), Nm.
    pub fn planned_first_input(&self) -> Vec<f64> {
        self.plan.rows(0, self.model.ninputs()).iter().copied().collect()
    }

    /// The current estimate of the input disturbances, Nm (plant input order).
    pub fn disturbance(&self) -> Vec<f64> {
        self.estimator.disturbance().iter().copied().collect()
    }
}
