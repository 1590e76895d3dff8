//! Clarabel set up once for a [`ParametricQp`]; each step only q and b are written.

use clarabel::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus};
use nalgebra::DVector;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Instant;

use crate::error::{MpcError, Result};
use crate::qp::ParametricQp;
use crate::settings::SolverSettings;

/// The optimum with every inequality inactive and the slack at 0: z_r = −P_rr⁻¹ q_r over the
/// other variables (the slack enters P only on its diagonal). It is the QP's optimum when it
/// satisfies every row of A z ≤ b: the inactive rows' multipliers are 0 and the slack's bound
/// s ≥ 0 is active with multiplier ∂cost/∂s = q_s ≥ 0 (its linear penalty) — the KKT
/// conditions hold exactly.
struct Unconstrained {
    factor: nalgebra::Cholesky<f64, nalgebra::Dyn>,
    /// A without the slack's column, dense.
    a_r: nalgebra::DMatrix<f64>,
    slack: usize,
    z_r: DVector<f64>,
    az: DVector<f64>,
    /// The solution of the last solve when it came from here.
    x: Vec<f64>,
}

impl Unconstrained {
    fn new(qp: &ParametricQp) -> Option<Unconstrained> {
        if qp.n_eq > 0 {
            return None;
        }
        let p = crate::qp::dense(&qp.p);
        let slack = qp.slack();
        let n = qp.nvars();
        // the slack must enter the cost on its own (upper triangle: its column above the diagonal)
        if (0..slack).any(|i| p[(i, slack)] != 0.0) || qp.q_theta.row(slack).iter().any(|&v| v != 0.0) {
            return None;
        }
        let keep: Vec<usize> = (0..n).filter(|&j| j != slack).collect();
        let p_rr = nalgebra::DMatrix::from_fn(keep.len(), keep.len(), |i, j| {
            let (a, b) = (keep[i].min(keep[j]), keep[i].max(keep[j]));
            p[(a, b)]
        });
        let factor = p_rr.cholesky()?;
        let a = crate::qp::dense(&qp.a);
        let a_r = nalgebra::DMatrix::from_fn(a.nrows(), keep.len(), |i, j| a[(i, keep[j])]);
        Some(Unconstrained {
            factor,
            slack,
            z_r: DVector::zeros(keep.len()),
            az: DVector::zeros(a.nrows()),
            a_r,
            x: vec![0.0; n],
        })
    }

    /// The optimum if no inequality is active at it; allocation-free.
    fn solve(&mut self, q: &DVector<f64>, b: &DVector<f64>) -> bool {
        if q[self.slack] < 0.0 {
            return false;
        }
        for (k, j) in (0..q.len()).filter(|&j| j != self.slack).enumerate() {
            self.z_r[k] = -q[j];
        }
        self.factor.solve_mut(&mut self.z_r);
        self.az.gemv(1.0, &self.a_r, &self.z_r, 0.0);
        if !self.az.iter().zip(b.iter()).all(|(a, b)| *a <= *b) {
            return false;
        }
        let mut k = 0;
        for (j, x) in self.x.iter_mut().enumerate() {
            if j == self.slack {
                *x = 0.0;
            } else {
                *x = self.z_r[k];
                k += 1;
            }
        }
        self.x.iter().all(|v| v.is_finite())
    }
}

/// A Clarabel solver holding the QP's fixed P and A.
pub struct QpSolver {
    solver: DefaultSolver<f64>,
    unconstrained: Option<Unconstrained>,
    /// The last solve was the unconstrained optimum.
    last_unconstrained: bool,
    /// The time base of the deadline.
    base: Instant,
    /// Deadline of the running solve, ns after `base`, read by the termination callback.
    deadline_ns: Arc<AtomicU64>,
    time_limit_ns: u64,
}

/// What one solve gave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveInfo {
    /// Clarabel's status.
    pub status: SolverStatus,
    /// Interior-point iterations.
    pub iterations: u32,
    /// The solution can be used (solved or almost solved).
    pub ok: bool,
}

impl QpSolver {
    /// Builds the solver (presolve off so that q and b may be updated; structural zeros kept).
    pub fn new(qp: &ParametricQp, settings: &SolverSettings) -> Result<Self> {
        let s = DefaultSettingsBuilder::default()
            .verbose(false)
            .presolve_enable(false)
            .input_sparse_dropzeros(false)
            .max_iter(settings.max_iter)
            .tol_gap_abs(settings.tol_gap)
            .tol_gap_rel(settings.tol_gap)
            .tol_feas(settings.tol_feas)
            .equilibrate_enable(settings.equilibrate)
            .iterative_refinement_enable(settings.iterative_refinement)
            // QDLDL: Clarabel's faer-sparse LDLᵀ measured no faster on these QPs (full resolution,
            // sparse: 1451 vs 1440 us median; condensed: max 37.7 vs 24.5 ms) and allocates
            // ~1260 times per solve (`rigtwin mpc --direct-solver faer` at commit cbea5cc)
            .direct_solve_method("qdldl".to_string())
            .build()
            .map_err(|e| MpcError::Solver(e.to_string()))?;
        let q = vec![0.0; qp.nvars()];
        let b: Vec<f64> = qp.b0.iter().copied().collect();
        let mut solver =
            DefaultSolver::new(&qp.p, &q, &qp.a, &b, &qp.cones, s).map_err(|e| MpcError::Solver(e.to_string()))?;
        // Clarabel's own `time_limit` counts the set-up time too (its timers are summed over
        // the solver's life), so every later solve would stop at once: the deadline is kept
        // here and checked by a termination callback after each iteration.
        let base = Instant::now();
        let deadline_ns = Arc::new(AtomicU64::new(u64::MAX));
        let deadline = Arc::clone(&deadline_ns);
        solver.set_termination_callback(move |_: &clarabel::solver::DefaultInfo<f64>| {
            base.elapsed().as_nanos() as u64 > deadline.load(Ordering::Relaxed)
        });
        let time_limit_ns =
            if settings.time_limit_s.is_finite() { (settings.time_limit_s * 1e9) as u64 } else { u64::MAX / 2 };
        let unconstrained = if settings.unconstrained_check { Unconstrained::new(qp) } else { None };
        Ok(QpSolver { solver, unconstrained, last_unconstrained: false, base, deadline_ns, time_limit_ns })
    }

    /// Solves with new q and b; the solution is [`QpSolver::x`].
    pub fn solve(&mut self, q: &DVector<f64>, b: &DVector<f64>) -> SolveInfo {
        self.last_unconstrained = self.unconstrained.as_mut().is_some_and(|u| u.solve(q, b));
        if self.last_unconstrained {
            return SolveInfo { status: SolverStatus::Solved, iterations: 0, ok: true };
        }
        let updated = self.solver.update_q(q.data.as_vec()).and_then(|_| self.solver.update_b(b.data.as_vec()));
        if updated.is_err() {
            return SolveInfo { status: SolverStatus::NumericalError, iterations: 0, ok: false };
        }
        let now = self.base.elapsed().as_nanos() as u64;
        self.deadline_ns.store(now.saturating_add(self.time_limit_ns), Ordering::Relaxed);
        self.solver.solve();
        let status = self.solver.solution.status;
        SolveInfo {
            status,
            iterations: self.solver.solution.iterations,
            ok: matches!(status, SolverStatus::Solved | SolverStatus::AlmostSolved)
                && self.solver.solution.x.iter().all(|v| v.is_finite()),
        }
    }

    /// The last solution.
    pub fn x(&self) -> &[f64] {
        match &self.unconstrained {
            Some(u) if self.last_unconstrained => &u.x,
            _ => &self.solver.solution.x,
        }
    }

    /// Whether the last solve was the unconstrained optimum (no interior-point iteration).
    pub fn last_was_unconstrained(&self) -> bool {
        self.last_unconstrained
    }
}
