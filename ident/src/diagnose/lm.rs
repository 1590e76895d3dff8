//! A small Levenberg–Marquardt for the diagnosis' fits: forward-difference Jacobian, parameters
//! in whatever space the caller chooses (log for positive ones).

use nalgebra::{DMatrix, DVector};

/// The damping beyond which no step is tried (relative to JᵀJ's diagonal: a step 1e-10 of a
/// gradient step's scale; the fit has converged or the cost is flat to rounding).
pub const LAMBDA_MAX: f64 = 1e10;

/// Minimises ‖f(x)‖² from `x0`; `f` returns `None` where the model cannot be evaluated.
/// Returns the best x and its sum of squares. Stops after `max_iter` iterations, when a step
/// gains less than `rel_tol` of the cost, or when [`NOTCH_RAISES`] tenfold raises of the damping
/// find no step that lowers it: the cost of a model with play or friction has notches, and a fit
/// caught beside one is moved on by the search's restarts, not by ever shorter steps.
pub fn minimise_to(
    f: &(dyn Fn(&[f64]) -> Option<Vec<f64>> + Sync),
    x0: &[f64],
    max_iter: usize,
    rel_tol: f64,
) -> (Vec<f64>, f64) {
    minimise(f, x0, max_iter, rel_tol, NOTCH_RAISES)
}

/// [`minimise_to`] for a smooth cost (a linear model's: the declared model re-fitted): the
/// damping is raised until a step lowers the cost (up to [`LAMBDA_MAX`]). In a long curved valley,
/// after a run of good steps has taken it to its floor, eight raises leave it at 0.1, and the
/// fit stopped at twice the minimum (a survey record's declared model, `scripts/refit_check.py`).
pub fn minimise_smooth(
    f: &(dyn Fn(&[f64]) -> Option<Vec<f64>> + Sync),
    x0: &[f64],
    max_iter: usize,
    rel_tol: f64,
) -> (Vec<f64>, f64) {
    minimise(f, x0, max_iter, rel_tol, usize::MAX)
}

/// Tenfold raises of the damping [`minimise_to`] tries in one iteration.
pub const NOTCH_RAISES: usize = 8;

fn minimise(
    f: &(dyn Fn(&[f64]) -> Option<Vec<f64>> + Sync),
    x0: &[f64],
    max_iter: usize,
    rel_tol: f64,
    raises: usize,
) -> (Vec<f64>, f64) {
    let p = x0.len();
    let mut x = x0.to_vec();
    let Some(mut r) = f(&x) else { return (x, f64::INFINITY) };
    let mut cost: f64 = r.iter().map(|v| v * v).sum();
    let mut lambda = 1e-3;
    for _ in 0..max_iter {
        let Some(columns) = jacobian_columns(f, &x, &r) else { break };
        let mut jtj = DMatrix::zeros(p, p);
        let mut g = DVector::zeros(p);
        for j in 0..p {
            g[j] = columns[j].iter().zip(&r).map(|(a, b)| *a as f64 * b).sum::<f64>();
            for k in 0..=j {
                let v = columns[j].iter().zip(&columns[k]).map(|(a, b)| *a as f64 * *b as f64).sum::<f64>();
                jtj[(j, k)] = v;
                jtj[(k, j)] = v;
            }
        }
        if jtj.iter().chain(g.iter()).any(|v: &f64| !v.is_finite()) {
            break;
        }
        drop(columns);
        let mut improved = false;
        let mut tried = 0;
        while tried < raises && lambda <= LAMBDA_MAX {
            tried += 1;
            let mut a = jtj.clone();
            for j in 0..p {
                a[(j, j)] += lambda * jtj[(j, j)].max(1e-12);
            }
            let Some(step) = a.lu().solve(&(-&g)) else {
                lambda *= 10.0;
                continue;
            };
            let xn: Vec<f64> = x.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
            if let Some(rn) = f(&xn) {
                let cn: f64 = rn.iter().map(|v| v * v).sum();
                if cn < cost {
                    let rel = (cost - cn) / cost;
                    x = xn;
                    r = rn;
                    cost = cn;
                    lambda = (lambda / 5.0).max(1e-9);
                    improved = true;
                    if rel < rel_tol {
                        return (x, cost);
                    }
                    break;
                }
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    (x, cost)
}

/// The Jacobian of `f` at `x` (where `f(x)` = `r`) by forward differences, column by column,
/// kept in single precision (half the memory of a long record; a forward difference is good to
/// a few digits anyway); `None` where `f` cannot be evaluated beside `x`.
pub fn jacobian_columns(
    f: &(dyn Fn(&[f64]) -> Option<Vec<f64>> + Sync),
    x: &[f64],
    r: &[f64],
) -> Option<Vec<Vec<f32>>> {
    let p = x.len();
    let column = |j: usize| -> Option<Vec<f32>> {
        // 0.1 % steps (log parameters): large enough to step over the roughness that contact
        // switching in the backlash model puts into the cost.
        let h = 1e-3 * x[j].abs().max(1.0);
        let mut xp = x.to_vec();
        xp[j] += h;
        let rp = f(&xp)?;
        Some(rp.iter().zip(r).map(|(a, b)| ((a - b) / h) as f32).collect())
    };
    // on both cores where one is idle (this fit the only work, or the other worker out of
    // jobs): the same columns, sooner
    if p >= 2 && super::spare_core() {
        super::on_two_workers(p, &column).into_iter().collect()
    } else {
        (0..p).map(column).collect()
    }
}

/// Golden-section minimisation of a 1-D function on [a, b].
pub fn golden(f: &dyn Fn(f64) -> f64, mut a: f64, mut b: f64, iters: usize) -> f64 {
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..iters {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    if fc < fd {
        c
    } else {
        d
    }
}
