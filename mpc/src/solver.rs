//! Clarabel set up once for a [`ParametricQp`]; each step only q and b are written.

use clarabel::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus};
use nalgebra::DVector;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Instant;

use crate::error::{MpcError, Result};
use crate::qp::ParametricQp;
use crate::settings::SolverSettings;

/// A Clarabel solver holding the QP's fixed P and A.
pub struct QpSolver {
    solver: DefaultSolver<f64>,
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
        Ok(QpSolver { solver, base, deadline_ns, time_limit_ns })
    }

    /// Solves with new q and b; the solution is [`QpSolver::x`].
    pub fn solve(&mut self, q: &DVector<f64>, b: &DVector<f64>) -> SolveInfo {
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
        &self.solver.solution.x
    }
}
