//! A small Levenberg–Marquardt for the diagnosis' fits: forward-difference Jacobian, parameters
//! in whatever space the caller chooses (log for positive ones).

use nalgebra::{DMatrix, DVector};

/// The damping beyond which no step is tried (relative to JᵀJ's diagonal: a step 1e-10 of a
/// gradient step's scale; the fit has converged or the cost is flat to rounding).
pub const LAMBDA_MAX: f64 = 1e10;

/// `x` moved into the box |x_i| ≤ `max_abs[i]` (empty: unchanged).
pub(crate) fn into_box(x: &mut [f64], max_abs: &[f64]) {
    for (v, m) in x.iter_mut().zip(max_abs) {
        *v = v.clamp(-m, *m);
    }
}

/// Tenfold raises of the damping a notched fit tries in one iteration ([`Fit::raises`]).
pub const NOTCH_RAISES: usize = 8;

/// How a fit runs ([`minimise`]). [`Fit::new`] is the notched fit of a model with play or
/// friction, without a trust region or a box; the builders add each.
#[derive(Debug, Clone, Copy)]
pub struct Fit<'a> {
    /// Most iterations.
    pub max_iter: usize,
    /// A step that gains less than this share of the cost ends the fit.
    pub rel_tol: f64,
    /// Tenfold raises of the damping tried in one iteration before the fit stops:
    /// [`NOTCH_RAISES`] (the cost of a model with play or friction has notches, and a fit caught
    /// beside one is moved on by the search's restarts, not by ever shorter steps), or without
    /// limit up to [`LAMBDA_MAX`] for a smooth cost ([`Fit::smooth`]).
    pub raises: usize,
    /// Central differences for the Jacobian ([`Fit::central`]); forward differences otherwise.
    pub central: bool,
    /// The trust region's radius: no step longer than this (Euclidean, in the fit's
    /// parameters) is evaluated (∞: none; [`Fit::within`]).
    pub max_step: f64,
    /// Bounds |x_i| ≤ `max_abs[i]` (∞: free; empty: none; [`Fit::boxed`]).
    pub max_abs: &'a [f64],
}

impl<'a> Fit<'a> {
    /// At most `max_iter` iterations, ended by a step that gains less than `rel_tol` of the
    /// cost or by [`NOTCH_RAISES`] raises of the damping that find no lower cost.
    pub fn new(max_iter: usize, rel_tol: f64) -> Fit<'static> {
        Fit { max_iter, rel_tol, raises: NOTCH_RAISES, central: false, max_step: f64::INFINITY, max_abs: &[] }
    }

    /// For a smooth cost (a linear model's: the declared model re-fitted): the damping is
    /// raised until a step lowers the cost (up to [`LAMBDA_MAX`]). In a long curved valley,
    /// after a run of good steps has taken it to its floor, eight raises leave it at 0.1, and
    /// the fit stopped at twice the minimum (a survey record's declared model,
    /// `scripts/refit_check.py`).
    pub fn smooth(self, smooth: bool) -> Self {
        Fit { raises: if smooth { usize::MAX } else { NOTCH_RAISES }, ..self }
    }

    /// The Jacobian's columns by central differences (twice the simulations), for a smooth cost
    /// of many parameters some of which trade against each other (a drive line's stiffnesses
    /// in series): the valley's direction is then what the Jacobian must get right. Forward
    /// differences' error, of the order of their step (1e-3 of the column), left the
    /// Gauss–Newton steps gaining 0.3 % each, and a 9-parameter line's re-fit stopped after 60
    /// of them at 23 times the minimum scipy's `least_squares` reaches (survey record 2100,
    /// `scripts/refit_check_lines.py`); with central differences (error of the order of the
    /// step squared) it reaches that minimum in 7 iterations.
    pub fn central(self) -> Self {
        Fit { central: true, ..self }
    }

    /// Within a trust region: no step longer than `max_step` is evaluated; the damping is
    /// doubled until the step fits, which bends it from the Gauss–Newton step towards the
    /// gradient (the Levenberg–Marquardt step is the minimiser of the linearised cost within a
    /// ball, Moré 1978). Where a parameter is weakly determined, an almost Gauss–Newton step can
    /// move it by orders of magnitude, lower the cost and land the fit in another valley;
    /// scipy's `least_squares` starts its trust region at a step of one for the same reason.
    pub fn within(self, max_step: f64) -> Self {
        Fit { max_step, ..self }
    }

    /// Within the box |x_i| ≤ `max_abs[i]` about the start's origin (the declared values, in
    /// logarithms): the start is moved into it, a parameter on its bound that the gradient
    /// pushes outward is held for the step, and every step is clipped to the box (a projected
    /// Levenberg–Marquardt with an active set).
    pub fn boxed<'b>(self, max_abs: &'b [f64]) -> Fit<'b>
    where
        'a: 'b,
    {
        Fit { max_abs, ..self }
    }
}

/// Minimises ‖f(x)‖² from `x0` as `fit` says; `f` returns `None` where the model cannot be
/// evaluated. Returns the best x and its sum of squares.
pub fn minimise(f: &(dyn Fn(&[f64]) -> Option<Vec<f64>> + Sync), x0: &[f64], fit: Fit) -> (Vec<f64>, f64) {
    let Fit { max_iter, rel_tol, raises, central, max_step, max_abs } = fit;
    let p = x0.len();
    let mut x = x0.to_vec();
    into_box(&mut x, max_abs);
    let Some(mut r) = f(&x) else { return (x, f64::INFINITY) };
    let mut cost: f64 = r.iter().map(|v| v * v).sum();
    let mut lambda = 1e-3;
    for _ in 0..max_iter {
        let Some(columns) = jacobian_columns(f, &x, &r, central) else { break };
        let Some((mut jtj, mut g)) = normal_sums(&columns, &r, 1, &|_| 0).pop() else { break };
        drop(columns);
        if jtj.iter().chain(g.iter()).any(|v: &f64| !v.is_finite()) {
            break;
        }
        // a parameter on its bound that the descent direction −g pushes outward is held, and
        // one whose box is empty (|x_i| ≤ 0: held at the origin) throughout
        for (i, m) in max_abs.iter().enumerate() {
            if x[i].abs() >= *m && (*m == 0.0 || x[i] * -g[i] > 0.0) {
                jtj.row_mut(i).fill(0.0);
                jtj.column_mut(i).fill(0.0);
                jtj[(i, i)] = 1.0;
                g[i] = 0.0;
            }
        }
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
            if step.norm() > max_step {
                // outside the trust region: not evaluated, and not counted as a raise
                tried -= 1;
                lambda *= 2.0;
                continue;
            }
            let mut xn: Vec<f64> = x.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
            into_box(&mut xn, max_abs);
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

/// JᵀJ and Jᵀr of `f`'s Jacobian J at `x` (where `f(x)` = `r`), summed over each of `groups`
/// groups of rows (`group_of(row)` < `groups`): the normal equations of a Gauss–Newton step on
/// all rows or on some. `None` where `f` cannot be evaluated beside `x`.
///
/// The columns are forward differences ([`jacobian_columns`], as a notched fit's) in 16 bits ([`Column`]), held
/// only while the sums are formed.
pub fn normal_equations(
    f: &(dyn Fn(&[f64]) -> Option<Vec<f64>> + Sync),
    x: &[f64],
    r: &[f64],
    groups: usize,
    group_of: &dyn Fn(usize) -> usize,
) -> Option<Vec<(DMatrix<f64>, DVector<f64>)>> {
    let columns = jacobian_columns(f, x, r, false)?;
    Some(normal_sums(&columns, r, groups, group_of))
}

/// JᵀJ and Jᵀr of the Jacobian whose columns are `columns`, summed over each of `groups` groups
/// of rows ([`normal_equations`]): each entry summed over the rows in order, column pair by
/// column pair, over runs of rows that share a group and a scale.
pub fn normal_sums(
    columns: &[Column],
    r: &[f64],
    groups: usize,
    group_of: &dyn Fn(usize) -> usize,
) -> Vec<(DMatrix<f64>, DVector<f64>)> {
    let p = columns.len();
    let runs = runs(r.len(), groups, group_of);
    let mut sums: Vec<(DMatrix<f64>, DVector<f64>)> =
        (0..groups).map(|_| (DMatrix::zeros(p, p), DVector::zeros(p))).collect();
    for (a, ca) in columns.iter().enumerate() {
        for &(start, end, k) in &runs {
            let sa = ca.scale[start >> Column::BLOCK_BITS];
            let acc = &mut sums[k].1[a];
            for (q, ri) in ca.q[start..end].iter().zip(&r[start..end]) {
                *acc += *q as f64 * sa * ri;
            }
        }
        for (b, cb) in columns[..=a].iter().enumerate() {
            for &(start, end, k) in &runs {
                let (sa, sb) = (ca.scale[start >> Column::BLOCK_BITS], cb.scale[start >> Column::BLOCK_BITS]);
                let acc = &mut sums[k].0[(a, b)];
                for (qa, qb) in ca.q[start..end].iter().zip(&cb.q[start..end]) {
                    *acc += *qa as f64 * sa * (*qb as f64 * sb);
                }
            }
        }
    }
    for (m, _) in &mut sums {
        m.fill_upper_triangle_with_lower_triangle();
    }
    sums
}

/// The rows 0..n as runs (start, end, group) of one group ([`normal_sums`]) and one scale block
/// of the columns ([`Column::BLOCK_BITS`]).
fn runs(n: usize, groups: usize, group_of: &dyn Fn(usize) -> usize) -> Vec<(usize, usize, usize)> {
    let block = 1 << Column::BLOCK_BITS;
    let mut runs = Vec::new();
    let mut start = 0;
    let mut group = if groups > 1 && n > 0 { group_of(0) } else { 0 };
    for i in 1..=n {
        let next = if groups > 1 && i < n { group_of(i) } else { 0 };
        if i == n || i % block == 0 || next != group {
            runs.push((start, i, group));
            start = i;
            group = next;
        }
    }
    runs
}

/// The Jacobian of `f` at `x` (where `f(x)` = `r`) by forward differences, or `central` ones
/// ([`Fit::central`]: twice the simulations), column by column ([`Column`]); `None` where `f`
/// cannot be evaluated beside `x`.
fn jacobian_columns(
    f: &(dyn Fn(&[f64]) -> Option<Vec<f64>> + Sync),
    x: &[f64],
    r: &[f64],
    central: bool,
) -> Option<Vec<Column>> {
    let column = |j: usize| -> Option<Column> {
        // 0.1 % steps (log parameters): large enough to step over the roughness that contact
        // switching in the backlash model puts into the cost.
        let h = 1e-3 * x[j].abs().max(1.0);
        let mut xp = x.to_vec();
        xp[j] += h;
        // a residual of another length than `r` cannot be differenced: no column
        let rp = f(&xp).filter(|rp| rp.len() == r.len())?;
        if central {
            xp[j] -= 2.0 * h;
            let rm = f(&xp).filter(|rm| rm.len() == r.len())?;
            return Some(Column::of(&rp, &rm, 2.0 * h));
        }
        Some(Column::of(&rp, r, h))
    };
    // on both cores where one is idle (this fit the only work, or the other worker out of
    // jobs): the same columns, sooner
    if x.len() >= 2 && super::spare_core() {
        super::on_two_workers(x.len(), &column).into_iter().collect()
    } else {
        (0..x.len()).map(column).collect()
    }
}

/// A Jacobian column in 16 bits an entry, each block of 2^[`Column::BLOCK_BITS`] rows scaled by
/// its largest magnitude: within 1.5e-5 of that (half a step of 1/32767), below the forward
/// difference's own error (its step is 1e-3 of the parameter, and its truncation error of that
/// order relative to the column), in a quarter of a double's memory. A long record's Jacobian is
/// the largest thing a diagnosis holds (a 13 s record of 7 outputs: 182 kB a column so, 728 kB
/// in doubles).
pub struct Column {
    scale: Vec<f64>,
    q: Vec<i16>,
}

impl Column {
    /// Rows sharing one scale: 2^10.
    const BLOCK_BITS: u32 = 10;

    /// The difference quotient (`rp` − `r`) / `h` (`r` the residual at the step's other end).
    pub fn of(rp: &[f64], r: &[f64], h: f64) -> Column {
        let rows = 1 << Self::BLOCK_BITS;
        let mut scale = Vec::with_capacity(rp.len() / rows + 1);
        let mut q = Vec::with_capacity(rp.len());
        for (bp, b) in rp.chunks(rows).zip(r.chunks(rows)) {
            let value = |k: usize| (bp[k] - b[k]) / h;
            let (largest, finite) =
                (0..bp.len()).map(value).fold((0.0f64, true), |(m, f), v| (m.max(v.abs()), f && v.is_finite()));
            // a non-finite entry makes its block's scale NaN: the normal equations then are
            // not finite, and the fit stops, as for a column of doubles
            let s = if finite { largest / i16::MAX as f64 } else { f64::NAN };
            scale.push(s);
            // to the nearest step, half away from zero (`f64::round` without its library call;
            // the cast saturates)
            q.extend((0..bp.len()).map(|k| {
                let y = if s > 0.0 { value(k) / s } else { 0.0 };
                (y + 0.5f64.copysign(y)) as i16
            }));
        }
        Column { scale, q }
    }

    /// Entry `i`.
    pub fn get(&self, i: usize) -> f64 {
        self.q[i] as f64 * self.scale[i >> Self::BLOCK_BITS]
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Values whose magnitude changes by decades from block to block, with a sign change.
    fn values(n: usize, j: usize) -> Vec<f64> {
        (0..n).map(|k| 10f64.powi((k / 1500) as i32 - 2) * ((k as f64 * 0.013 * (j + 1) as f64).sin() - 0.3)).collect()
    }

    /// Half a quantisation step of the block holding row `k` of `v`: the largest error a 16-bit
    /// entry may have.
    fn half_step(v: &[f64], k: usize) -> f64 {
        let rows = 1 << Column::BLOCK_BITS;
        let block = &v[(k / rows) * rows..((k / rows + 1) * rows).min(v.len())];
        block.iter().fold(0.0f64, |m, x| m.max(x.abs())) / i16::MAX as f64 / 2.0
    }

    #[test]
    fn a_column_keeps_each_entry_within_half_a_step_of_its_block() {
        let v = values(5000, 0);
        let base: Vec<f64> = (0..v.len()).map(|k| k as f64 * 1e-3).collect();
        let h = 1e-3;
        let rp: Vec<f64> = v.iter().zip(&base).map(|(d, b)| b + d * h).collect();
        let c = Column::of(&rp, &base, h);
        for (k, &x) in v.iter().enumerate() {
            // the difference itself is formed in doubles: 1e-12 beside the step's bound
            assert!((c.get(k) - x).abs() <= half_step(&v, k) * (1.0 + 1e-6) + 1e-12, "row {k}: {} for {x}", c.get(k));
        }
    }

    /// Rosenbrock's valley, r = (10 (x₂ − x₁²), 1 − x₁), from the classic start (−1.2, 1): the
    /// smooth fit with the declared re-fits' trust region reaches its minimum at (1, 1) (cost 0)
    /// to the rounding of the 16-bit columns, well within the iterations a declared re-fit has.
    #[test]
    fn the_smooth_fit_reaches_the_end_of_a_curved_valley() {
        let f = |x: &[f64]| Some(vec![10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]]);
        let (x, cost) = minimise(&f, &[-1.2, 1.0], Fit::new(60, 1e-12).smooth(true).central().within(1.0));
        assert!(cost < 1e-12, "cost {cost} at {x:?}");
        assert!((x[0] - 1.0).abs() < 1e-6 && (x[1] - 1.0).abs() < 1e-6, "{x:?}");
    }

    /// A parameter whose box is empty stays at the origin, and the others reach the minimum
    /// with it held there: for f = (x0 − 1, x1 − 2 + x0), x0 held at 0, the least squares
    /// minimum is x1 = 2 (analytic).
    #[test]
    fn a_parameter_with_an_empty_box_is_held_at_the_origin() {
        let f = |x: &[f64]| Some(vec![x[0] - 1.0, x[1] - 2.0 + x[0]]);
        let (x, cost) = minimise(&f, &[0.5, 0.0], Fit::new(40, 1e-14).boxed(&[0.0, f64::INFINITY]));
        assert_eq!(x[0], 0.0, "{x:?}");
        assert!((x[1] - 2.0).abs() < 1e-6, "{x:?}");
        assert!((cost - 1.0).abs() < 1e-9, "cost {cost}");
    }

    #[test]
    fn a_non_finite_entry_makes_the_normal_sums_non_finite() {
        let mut v = values(3000, 1);
        v[2100] = f64::NAN;
        let c = Column::of(&v, &vec![0.0; v.len()], 1.0);
        let sums = normal_sums(&[c], &vec![1.0; v.len()], 1, &|_| 0);
        assert!(!sums[0].0[(0, 0)].is_finite() && !sums[0].1[0].is_finite());
    }

    #[test]
    fn normal_sums_match_the_sums_of_the_doubles_within_the_quantisation_bound() {
        let (n, p) = (6000, 3);
        let cols: Vec<Vec<f64>> = (0..p).map(|j| values(n, j)).collect();
        let r: Vec<f64> = (0..n).map(|k| (k as f64 * 0.0037).cos()).collect();
        let zeros = vec![0.0; n];
        let quantised: Vec<Column> = cols.iter().map(|c| Column::of(c, &zeros, 1.0)).collect();
        let group_of = |k: usize| (k / 700) % 2;
        let sums = normal_sums(&quantised, &r, 2, &group_of);
        for (g, (jtj, grad)) in sums.iter().enumerate() {
            let rows: Vec<usize> = (0..n).filter(|&k| group_of(k) == g).collect();
            for a in 0..p {
                // |Σ (x + δx) r − Σ x r| ≤ Σ |δx| |r|, |δx| at most half a step
                let exact: f64 = rows.iter().map(|&k| cols[a][k] * r[k]).sum();
                let bound: f64 = rows.iter().map(|&k| half_step(&cols[a], k) * r[k].abs()).sum();
                assert!((grad[a] - exact).abs() <= bound * 1.001 + 1e-12, "g[{a}] {} for {exact}", grad[a]);
                for b in 0..p {
                    // |Σ (x + δx)(y + δy) − Σ x y| ≤ Σ |x||δy| + |y||δx| + |δx||δy|
                    let exact: f64 = rows.iter().map(|&k| cols[a][k] * cols[b][k]).sum();
                    let bound: f64 = rows
                        .iter()
                        .map(|&k| {
                            let (da, db) = (half_step(&cols[a], k), half_step(&cols[b], k));
                            cols[a][k].abs() * db + cols[b][k].abs() * da + da * db
                        })
                        .sum();
                    assert!(
                        (jtj[(a, b)] - exact).abs() <= bound * 1.001 + 1e-12,
                        "JᵀJ[{a},{b}] {} for {exact}",
                        jtj[(a, b)]
                    );
                    assert_eq!(jtj[(a, b)], jtj[(b, a)]);
                }
            }
        }
    }
}
