//! The MPC problem as a parametric QP: min ½zᵀPz + qᵀz s.t. Az + s = b, s ∈ K, where only
//! q = q₀ + Q_θ θ and b = b₀ + B_θ θ change from step to step. θ = [x₀; d; x_s; u_s; u_prev]
//! (estimated state, input-disturbance estimate, steady-state target, previous input).

use clarabel::algebra::CscMatrix;
use clarabel::solver::SupportedConeT;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use crate::model::PredictionModel;
use crate::settings::{Formulation, MpcSettings};

/// Weights and soft bounds of the MPC cost, in the model's physical units.
#[derive(Debug, Clone)]
pub struct Weights {
    /// Stage weight on x − x_s.
    pub q: DMatrix<f64>,
    /// Terminal weight on x_N − x_s.
    pub p: DMatrix<f64>,
    /// Weight on u − u_s, 1/Nm².
    pub r: DMatrix<f64>,
    /// Weight on u[k] − u[k−1], 1/Nm².
    pub s: DMatrix<f64>,
    /// Soft bounds: output row c (1 × n), lower, upper.
    pub soft: Vec<(DMatrix<f64>, Option<f64>, Option<f64>)>,
    /// Hard input bounds (min, max), Nm, and the largest change per step, Nm.
    pub input_bounds: Vec<(f64, f64, f64)>,
}

/// Where the parameters sit in θ.
#[derive(Debug, Clone, Copy)]
pub struct ThetaLayout {
    /// States.
    pub n: usize,
    /// Inputs.
    pub m: usize,
}

impl ThetaLayout {
    /// Length of θ.
    pub fn len(&self) -> usize {
        2 * self.n + 3 * self.m
    }
    /// Never empty.
    pub fn is_empty(&self) -> bool {
        false
    }
    /// Offset of x₀.
    pub fn x0(&self) -> usize {
        0
    }
    /// Offset of d.
    pub fn d(&self) -> usize {
        self.n
    }
    /// Offset of x_s.
    pub fn xs(&self) -> usize {
        self.n + self.m
    }
    /// Offset of u_s.
    pub fn us(&self) -> usize {
        2 * self.n + self.m
    }
    /// Offset of u_prev.
    pub fn uprev(&self) -> usize {
        2 * self.n + 2 * self.m
    }
}

/// The QP with its parameter maps.
#[derive(Debug, Clone)]
pub struct ParametricQp {
    /// Upper triangle of P.
    pub p: CscMatrix<f64>,
    /// Constraint matrix.
    pub a: CscMatrix<f64>,
    /// Cones: equalities first (sparse formulation), then inequalities.
    pub cones: Vec<SupportedConeT<f64>>,
    /// Number of equality rows.
    pub n_eq: usize,
    /// q = q₀ + Q_θ θ.
    pub q0: DVector<f64>,
    /// q = q₀ + Q_θ θ.
    pub q_theta: DMatrix<f64>,
    /// b = b₀ + B_θ θ.
    pub b0: DVector<f64>,
    /// b = b₀ + B_θ θ.
    pub b_theta: DMatrix<f64>,
    /// Physical input plan over the horizon U = G_u z (N·m × n_z), Nm.
    pub plan: DMatrix<f64>,
    /// Layout of θ.
    pub theta: ThetaLayout,
}

/// A QP at one θ, densely, for other solvers (OSQP, DAQP) and checks.
#[derive(Debug, Clone, Serialize)]
pub struct QpSnapshot {
    /// Full symmetric P, row-major.
    pub p: Vec<Vec<f64>>,
    /// q.
    pub q: Vec<f64>,
    /// A, row-major.
    pub a: Vec<Vec<f64>>,
    /// b.
    pub b: Vec<f64>,
    /// The first `n_eq` rows are equalities Az = b, the rest Az ≤ b.
    pub n_eq: usize,
    /// Physical first input u₀ = U0 z, Nm.
    pub u0_map: Vec<Vec<f64>>,
}

impl ParametricQp {
    /// Poses the QP of `settings.formulation` for `model` with `weights`.
    pub fn new(model: &PredictionModel, weights: &Weights, settings: &MpcSettings) -> Self {
        let (n, m, horizon) = (model.nstates(), model.ninputs(), settings.horizon);
        let theta = ThetaLayout { n, m };
        let nth = theta.len();
        let blocks = settings.blocks();
        let nb = blocks.len();
        let scale = settings.input_scale_nm;
        // Expansion of blocked moves v (nb·m, scaled) into the physical plan U (N·m).
        let mut expand = DMatrix::zeros(horizon * m, nb * m);
        let mut k = 0;
        for (b, &len) in blocks.iter().enumerate() {
            for _ in 0..len {
                for i in 0..m {
                    expand[(k * m + i, b * m + i)] = scale;
                }
                k += 1;
            }
        }
        // Prediction x_k = A^k x₀ + Σ_{j<k} A^{k−1−j} B (u_j + d), k = 1..N.
        let mut phi = DMatrix::zeros(horizon * n, n);
        let mut gamma = DMatrix::zeros(horizon * n, horizon * m);
        let mut apow = DMatrix::identity(n, n); // A^{k-1}
        let mut apow_b = Vec::with_capacity(horizon); // A^{j} B
        for k in 0..horizon {
            apow_b.push(&apow * &model.b);
            apow = &model.a * &apow;
            phi.view_mut((k * n, 0), (n, n)).copy_from(&apow);
        }
        for k in 0..horizon {
            for j in 0..=k {
                gamma.view_mut((k * n, j * m), (n, m)).copy_from(&apow_b[k - j]);
            }
        }
        let gamma_d = DMatrix::from_fn(horizon * n, m, |r, c| (0..horizon).map(|j| gamma[(r, j * m + c)]).sum());

        // Decision vector z and the maps X = Gx z + Fx θ, U = Gu z.
        let (nz, gx, fx, gu, eq) = match settings.formulation {
            Formulation::Condensed => {
                let nz = nb * m + 1;
                let mut gx = DMatrix::zeros(horizon * n, nz);
                gx.view_mut((0, 0), (horizon * n, nb * m)).copy_from(&(&gamma * &expand));
                let mut fx = DMatrix::zeros(horizon * n, nth);
                fx.view_mut((0, theta.x0()), (horizon * n, n)).copy_from(&phi);
                fx.view_mut((0, theta.d()), (horizon * n, m)).copy_from(&gamma_d);
                let mut gu = DMatrix::zeros(horizon * m, nz);
                gu.view_mut((0, 0), (horizon * m, nb * m)).copy_from(&expand);
                (nz, gx, fx, gu, None)
            }
            Formulation::Sparse => {
                let nx = horizon * n;
                let nz = nx + nb * m + 1;
                let mut gx = DMatrix::zeros(nx, nz);
                gx.view_mut((0, 0), (nx, nx)).fill_with_identity();
                let fx = DMatrix::zeros(nx, nth);
                let mut gu = DMatrix::zeros(horizon * m, nz);
                gu.view_mut((0, nx), (horizon * m, nb * m)).copy_from(&expand);
                // Dynamics x_{k+1} − A x_k − B u_k = B d (x_0 = x₀ from θ): A_eq z = b_eq.
                let mut a_eq = DMatrix::zeros(nx, nz);
                let mut b_eq = DMatrix::zeros(nx, nth);
                for k in 0..horizon {
                    a_eq.view_mut((k * n, k * n), (n, n)).fill_with_identity();
                    if k > 0 {
                        a_eq.view_mut((k * n, (k - 1) * n), (n, n)).copy_from(&(-&model.a));
                    } else {
                        b_eq.view_mut((0, theta.x0()), (n, n)).copy_from(&model.a);
                    }
                    b_eq.view_mut((k * n, theta.d()), (n, m)).copy_from(&model.b);
                }
                let bu = DMatrix::from_fn(
                    nx,
                    horizon * m,
                    |r, c| if r / n == c / m { model.b[(r % n, c % m)] } else { 0.0 },
                );
                let rows = -(bu * &gu);
                a_eq += rows;
                (nz, gx, fx, gu, Some((a_eq, b_eq)))
            }
        };
        let slack = nz - 1;

        // Cost: (X − X_s)ᵀ Q̄ (X − X_s) + (U − U_s)ᵀ R̄ (U − U_s) + ΔUᵀ S̄ ΔU + ρ₂ε² + ρ₁ε.
        let mut sx = DMatrix::zeros(horizon * n, nth);
        let mut su = DMatrix::zeros(horizon * m, nth);
        let mut qbar = DMatrix::zeros(horizon * n, horizon * n);
        let mut rbar = DMatrix::zeros(horizon * m, horizon * m);
        let mut sbar = DMatrix::zeros(horizon * m, horizon * m);
        let mut diff = DMatrix::zeros(horizon * m, horizon * m); // ΔU = D U − E u_prev
        let mut e_prev = DMatrix::zeros(horizon * m, nth);
        for k in 0..horizon {
            sx.view_mut((k * n, theta.xs()), (n, n)).fill_with_identity();
            su.view_mut((k * m, theta.us()), (m, m)).fill_with_identity();
            let w = if k + 1 == horizon { &weights.p } else { &weights.q };
            qbar.view_mut((k * n, k * n), (n, n)).copy_from(w);
            rbar.view_mut((k * m, k * m), (m, m)).copy_from(&weights.r);
            sbar.view_mut((k * m, k * m), (m, m)).copy_from(&weights.s);
            diff.view_mut((k * m, k * m), (m, m)).fill_with_identity();
            if k > 0 {
                diff.view_mut((k * m, (k - 1) * m), (m, m)).copy_from(&(-DMatrix::identity(m, m)));
            }
        }
        e_prev.view_mut((0, theta.uprev()), (m, m)).fill_with_identity();
        let dgu = &diff * &gu;
        let ex = &fx - &sx;
        let mut p =
            (gx.transpose() * &qbar * &gx + gu.transpose() * &rbar * &gu + dgu.transpose() * &sbar * &dgu) * 2.0;
        p[(slack, slack)] += 2.0 * settings.slack_quadratic;
        let q_theta =
            (gx.transpose() * &qbar * &ex - gu.transpose() * &rbar * &su - dgu.transpose() * &sbar * &e_prev) * 2.0;
        let mut q0 = DVector::zeros(nz);
        q0[slack] = settings.slack_linear;

        // Inequalities A z ≤ b₀ + B_θ θ.
        let mut rows: Vec<(DVector<f64>, f64, DVector<f64>)> = Vec::new(); // (a, b0, b_theta)
        let unit = |j: usize, v: f64| {
            let mut r = DVector::zeros(nz);
            r[j] = v;
            r
        };
        let v0 = match settings.formulation {
            Formulation::Condensed => 0,
            Formulation::Sparse => horizon * n,
        };
        for b in 0..nb {
            for (i, &(lo, hi, dmax)) in weights.input_bounds.iter().enumerate() {
                let j = v0 + b * m + i;
                rows.push((unit(j, scale), hi, DVector::zeros(nth)));
                rows.push((unit(j, -scale), -lo, DVector::zeros(nth)));
                // Rate bound at the start of each block: the input moves in one step.
                let mut up = unit(j, scale);
                let mut bt = DVector::zeros(nth);
                if b == 0 {
                    bt[theta.uprev() + i] = 1.0;
                } else {
                    up[j - m] = -scale;
                }
                rows.push((up.clone(), dmax, bt.clone()));
                rows.push((-up, dmax, -bt));
            }
        }
        // Soft bounds at every step, or at the last step of every move block (where the
        // plan's shape is decided; 10 instead of 50 rows per bound at N = 50).
        let bound_steps: Vec<usize> = if settings.soft_bounds_every_step {
            (0..horizon).collect()
        } else {
            blocks
                .iter()
                .scan(0, |end, &len| {
                    *end += len;
                    Some(*end - 1)
                })
                .collect()
        };
        for (c, lo, hi) in &weights.soft {
            for &k in &bound_steps {
                let gxk = gx.view((k * n, 0), (n, nz));
                let fxk = fx.view((k * n, 0), (n, nth));
                let cg: DVector<f64> = (c * gxk).transpose().column(0).into_owned();
                let cf: DVector<f64> = (c * fxk).transpose().column(0).into_owned();
                if let Some(hi) = hi {
                    let mut a = cg.clone();
                    a[slack] -= 1.0;
                    rows.push((a, *hi, -cf.clone()));
                }
                if let Some(lo) = lo {
                    let mut a = -cg.clone();
                    a[slack] -= 1.0;
                    rows.push((a, -*lo, cf.clone()));
                }
            }
        }
        rows.push((unit(slack, -1.0), 0.0, DVector::zeros(nth)));

        let n_eq = eq.as_ref().map_or(0, |(a, _)| a.nrows());
        let mrows = n_eq + rows.len();
        let mut a = DMatrix::zeros(mrows, nz);
        let mut b0 = DVector::zeros(mrows);
        let mut b_theta = DMatrix::zeros(mrows, nth);
        if let Some((a_eq, b_eq)) = &eq {
            a.view_mut((0, 0), (n_eq, nz)).copy_from(a_eq);
            b_theta.view_mut((0, 0), (n_eq, nth)).copy_from(b_eq);
        }
        for (i, (ar, b, bt)) in rows.iter().enumerate() {
            a.set_row(n_eq + i, &ar.transpose());
            b0[n_eq + i] = *b;
            b_theta.set_row(n_eq + i, &bt.transpose());
        }
        let mut cones = Vec::new();
        if n_eq > 0 {
            cones.push(SupportedConeT::ZeroConeT(n_eq));
        }
        cones.push(SupportedConeT::NonnegativeConeT(rows.len()));
        ParametricQp { p: csc(&p, true), a: csc(&a, false), cones, n_eq, q0, q_theta, b0, b_theta, plan: gu, theta }
    }

    /// Index of the soft bounds' slack (the last decision variable).
    pub fn slack(&self) -> usize {
        self.q0.len() - 1
    }

    /// Number of decision variables.
    pub fn nvars(&self) -> usize {
        self.q0.len()
    }

    /// Number of constraint rows.
    pub fn nrows(&self) -> usize {
        self.b0.len()
    }

    /// Writes q(θ) and b(θ) into `q` and `b` without allocating.
    pub fn evaluate(&self, theta: &DVector<f64>, q: &mut DVector<f64>, b: &mut DVector<f64>) {
        q.copy_from(&self.q0);
        q.gemv(1.0, &self.q_theta, theta, 1.0);
        b.copy_from(&self.b0);
        b.gemv(1.0, &self.b_theta, theta, 1.0);
    }

    /// The QP at θ, densely.
    pub fn snapshot(&self, theta: &DVector<f64>) -> QpSnapshot {
        let mut q = DVector::zeros(self.nvars());
        let mut b = DVector::zeros(self.nrows());
        self.evaluate(theta, &mut q, &mut b);
        let rows = |m: &DMatrix<f64>| (0..m.nrows()).map(|i| m.row(i).iter().copied().collect()).collect();
        let mut p = dense(&self.p);
        let upper = p.clone();
        p += upper.transpose() - DMatrix::from_diagonal(&upper.diagonal());
        let m = self.theta.m;
        QpSnapshot {
            p: rows(&p),
            q: q.iter().copied().collect(),
            a: rows(&dense(&self.a)),
            b: b.iter().copied().collect(),
            n_eq: self.n_eq,
            u0_map: rows(&self.plan.rows(0, m).into_owned()),
        }
    }
}

/// Dense → CSC, dropping exact zeros (the pattern never changes: P and A are fixed).
pub(crate) fn csc(m: &DMatrix<f64>, upper: bool) -> CscMatrix<f64> {
    let (mut colptr, mut rowval, mut nzval) = (vec![0], Vec::new(), Vec::new());
    for j in 0..m.ncols() {
        let last = if upper { (j + 1).min(m.nrows()) } else { m.nrows() };
        for i in 0..last {
            let v = m[(i, j)];
            if v != 0.0 {
                rowval.push(i);
                nzval.push(v);
            }
        }
        colptr.push(rowval.len());
    }
    CscMatrix::new(m.nrows(), m.ncols(), colptr, rowval, nzval)
}

pub(crate) fn dense(m: &CscMatrix<f64>) -> DMatrix<f64> {
    let mut d = DMatrix::zeros(m.m, m.n);
    for j in 0..m.n {
        for k in m.colptr[j]..m.colptr[j + 1] {
            d[(m.rowval[k], j)] = m.nzval[k];
        }
    }
    d
}
