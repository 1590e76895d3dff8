//! One fixed-step integrator for the nonlinear models (backlash, Coulomb friction), shared by
//! the simulations of the diagnosis and the FMU's co-simulation step.
//!
//! The right-hand sides are smooth *within pieces*: a coupling in contact or inside its play,
//! a machine's speed clear of the steep band of its smoothed friction. Inside one piece the
//! model is linear or gently nonlinear and classical RK4 is accurate at steps set by the linear
//! part's fastest rate; only where a step crosses from one piece to another (a kink of the
//! backlash, the friction's steep slope near zero speed) does RK4 lose its order. So each step
//! is tried whole and kept when its start, its three stage states and its end lie in one piece;
//! otherwise it is taken again in fine sub-steps. A rattling shaft crosses the play twice a
//! period, so most of a record is stepped coarsely. Where the pieces are linear (backlash
//! alone) the system may step a piece exactly instead, kept when the end lies in the start's
//! piece; where friction is the only nonlinearity, a sample while every body with friction
//! slides is stepped whole with the linear part exact and the frictions as forces
//! ([`ForcedMaps`]), RK4 taking over where one comes near zero speed.

use nalgebra::DMatrix;

/// A right-hand side that is smooth within pieces.
pub trait PiecewiseSmooth {
    /// ẋ at `x` (inputs held over the step).
    fn rhs(&mut self, x: &[f64], dx: &mut [f64]);
    /// The piece `x` lies in: equal keys at a step's start, stages and end mean the step never
    /// left one smooth piece.
    fn piece(&mut self, x: &[f64]) -> u64;
    /// Steps `x` over `h` exactly into `out` as if it stayed in `piece` (a linear piece: its
    /// matrix exponential); false where the system has none, and RK4 steps are taken.
    fn exact(&mut self, _piece: u64, _x: &[f64], _h: f64, _out: &mut [f64]) -> bool {
        false
    }
}

/// Classical RK4 with steps of at most `coarse_s`, each retaken in sub-steps of at most
/// `fine_s` where it leaves its piece.
#[derive(Debug, Clone)]
pub struct PiecewiseRk4 {
    /// Longest step within one piece, s.
    pub coarse_s: f64,
    /// Longest step across pieces, s.
    pub fine_s: f64,
    work: [Vec<f64>; 6],
    /// The counts of the last interval length (a record's samples are all one length).
    last: (f64, Option<(usize, usize)>),
}

impl PiecewiseRk4 {
    /// An integrator for `nstates` states.
    pub fn new(nstates: usize, coarse_s: f64, fine_s: f64) -> Self {
        PiecewiseRk4 {
            coarse_s,
            fine_s: fine_s.min(coarse_s),
            work: std::array::from_fn(|_| vec![0.0; nstates]),
            last: (f64::NAN, None),
        }
    }

    /// Number of coarse steps and fine sub-steps per coarse step for an interval of `h`
    /// seconds; `None` when either count is not finite.
    pub fn counts(&self, h: f64) -> Option<(usize, usize)> {
        let coarse = (h / self.coarse_s - 1e-9).ceil().max(1.0);
        let fine = (h / coarse / self.fine_s - 1e-9).ceil().max(1.0);
        (coarse.is_finite() && fine.is_finite()).then_some((coarse as usize, fine as usize))
    }

    /// Advances `x` over `h` seconds with the inputs held; the number of steps is bounded by
    /// [`PiecewiseRk4::counts`]. Returns the number of fine sub-steps taken.
    pub fn advance(&mut self, sys: &mut impl PiecewiseSmooth, x: &mut [f64], h: f64) -> usize {
        self.advance_from(sys, x, h, None).0
    }

    /// [`PiecewiseRk4::advance`] where the caller may know the piece `x` lies in (`start`: the
    /// end piece the last call returned, `x` unchanged since), saving its evaluation. Returns
    /// the fine sub-steps taken and the piece of the end state (`None` where `h` has no step
    /// counts and nothing was stepped).
    pub fn advance_from(
        &mut self,
        sys: &mut impl PiecewiseSmooth,
        x: &mut [f64],
        h: f64,
        start: Option<u64>,
    ) -> (usize, Option<u64>) {
        if h != self.last.0 {
            self.last = (h, self.counts(h));
        }
        let Some((coarse, fine)) = self.last.1 else { return (0, None) };
        let piece = start.unwrap_or_else(|| sys.piece(x));
        let [.., end] = &mut self.work;
        if sys.exact(piece, x, h, end) {
            if sys.piece(end) == piece {
                x.copy_from_slice(end);
                return (0, Some(piece));
            }
            // the piece was left: the whole interval in fine sub-steps
            let n = coarse * fine;
            for _ in 0..n {
                rk4(sys, x, h / n as f64, &mut self.work, None);
            }
            return (n, Some(sys.piece(x)));
        }
        let hc = h / coarse as f64;
        let mut taken = 0;
        // the piece of each step's start: the last step's end where it was kept whole
        let mut start_piece = piece;
        for _ in 0..coarse {
            let [start, ..] = &mut self.work;
            start.copy_from_slice(x);
            match rk4(sys, x, hc, &mut self.work, Some(start_piece)) {
                Some(end) => start_piece = end,
                None => {
                    x.copy_from_slice(&self.work[0]);
                    for _ in 0..fine {
                        rk4(sys, x, hc / fine as f64, &mut self.work, None);
                    }
                    taken += fine;
                    start_piece = sys.piece(x);
                }
            }
        }
        (taken, Some(start_piece))
    }
}

/// RK4 sub-step bound: h·|λ|max ≤ this (RK4 is stable to 2.8 on both axes; 0.5 keeps the
/// amplitude error of the fastest mode per sub-step below 1e-4).
pub const RK4_STEP_TIMES_RATE: f64 = 0.5;

/// Half-width of the band |w| < w_b about zero speed where a Coulomb friction `friction`
/// smoothed as F_c w/√(w² + v_s²) (`smoothing` v_s, on inertia `inertia`) has a slope
/// F_c v_s²/(J (w² + v_s²)^{3/2}) steeper than steps of `coarse_s` resolve (h·slope >
/// [`RK4_STEP_TIMES_RATE`]); 0 where the coarse step resolves it everywhere.
pub fn friction_band(coarse_s: f64, friction: f64, smoothing: f64, inertia: f64) -> f64 {
    let v2 = smoothing * smoothing;
    let w2 = (coarse_s * friction * v2 / (RK4_STEP_TIMES_RATE * inertia)).powf(2.0 / 3.0) - v2;
    w2.max(0.0).sqrt()
}

/// Most states of an [`AffineStep`].
pub const AFFINE_MAX_STATES: usize = 16;

/// x⁺ = Φ x + Γ u + e for up to [`AFFINE_MAX_STATES`] states: the exact step of a linear piece
/// (the ZOH of its matrix exponential) with its inputs held. Stored by columns, padded, so the
/// product is a sum of columns that the compiler vectorises.
#[derive(Debug, Clone)]
pub struct AffineStep {
    ns: usize,
    phi: Vec<[f64; AFFINE_MAX_STATES]>,
    gamma: Vec<[f64; AFFINE_MAX_STATES]>,
    offset: [f64; AFFINE_MAX_STATES],
}

impl AffineStep {
    /// The step of Φ (`ns` × `ns`), Γ (`ns` × inputs), both column-major as nalgebra stores
    /// them, and e; `None` for more than [`AFFINE_MAX_STATES`] states or mismatched lengths.
    pub fn new(phi_column_major: &[f64], gamma_column_major: &[f64], offset: &[f64]) -> Option<Self> {
        let ns = offset.len();
        if ns == 0
            || ns > AFFINE_MAX_STATES
            || phi_column_major.len() != ns * ns
            || !gamma_column_major.len().is_multiple_of(ns)
        {
            return None;
        }
        let pad = |v: &[f64]| {
            let mut p = [0.0; AFFINE_MAX_STATES];
            p[..ns].copy_from_slice(v);
            p
        };
        Some(AffineStep {
            ns,
            phi: phi_column_major.chunks(ns).map(pad).collect(),
            gamma: gamma_column_major.chunks(ns).map(pad).collect(),
            offset: pad(offset),
        })
    }

    /// out = Φ x + Γ u + e (`u` as many as Γ has columns).
    #[inline]
    pub fn apply(&self, x: &[f64], u: &[f64], out: &mut [f64]) {
        // the columns summed over whole groups of four lanes (one AVX register each)
        // (N the state count where it is small: the result's copy is then a few moves, not a
        // call of memcpy — 9 % of the torsional diagnosis's time, measured with perf)
        fn sum<const W: usize, const N: usize>(s: &AffineStep, x: &[f64], u: &[f64], out: &mut [f64]) {
            let mut acc = [0.0; W];
            acc.copy_from_slice(&s.offset[..W]);
            for (col, &v) in s.phi.iter().zip(x).chain(s.gamma.iter().zip(u)) {
                for (a, c) in acc.iter_mut().zip(&col[..W]) {
                    *a += c * v;
                }
            }
            let n = if N > 0 { N } else { s.ns };
            out[..n].copy_from_slice(&acc[..n]);
        }
        match self.ns {
            4 => sum::<4, 4>(self, x, u, out),
            5 => sum::<8, 5>(self, x, u, out),
            6 => sum::<8, 6>(self, x, u, out),
            7 => sum::<8, 7>(self, x, u, out),
            8 => sum::<8, 8>(self, x, u, out),
            0..=3 => sum::<4, 0>(self, x, u, out),
            9..=12 => sum::<12, 0>(self, x, u, out),
            _ => sum::<AFFINE_MAX_STATES, 0>(self, x, u, out),
        }
    }
}

/// One RK4 step of `h`. With `check` = the piece of `x`: `None` (and `x` undefined) when a
/// stage or the end leaves that piece, else the end's piece (that piece). Without: `Some(0)`.
/// `w[0]` is kept for the caller.
fn rk4(
    sys: &mut impl PiecewiseSmooth,
    x: &mut [f64],
    h: f64,
    w: &mut [Vec<f64>; 6],
    check: Option<u64>,
) -> Option<u64> {
    let [_, k1, k2, k3, k4, tmp] = w;
    // tmp = x + c·k (the slices' lengths told once, so the loop carries no bounds checks)
    fn stage(tmp: &mut [f64], x: &[f64], k: &[f64], c: f64) {
        for ((t, xi), ki) in tmp.iter_mut().zip(x).zip(k) {
            *t = xi + c * ki;
        }
    }
    let left = |sys: &mut _, y: &[f64]| check.is_some_and(|p| PiecewiseSmooth::piece(sys, y) != p);
    sys.rhs(x, k1);
    stage(tmp, x, k1, 0.5 * h);
    if left(sys, tmp) {
        return None;
    }
    sys.rhs(tmp, k2);
    stage(tmp, x, k2, 0.5 * h);
    if left(sys, tmp) {
        return None;
    }
    sys.rhs(tmp, k3);
    stage(tmp, x, k3, h);
    if left(sys, tmp) {
        return None;
    }
    sys.rhs(tmp, k4);
    let ns = x.len();
    let (k1, k2, k3, k4) = (&k1[..ns], &k2[..ns], &k3[..ns], &k4[..ns]);
    for (i, xi) in x.iter_mut().enumerate() {
        *xi += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    if left(sys, x) {
        return None;
    }
    Some(check.unwrap_or(0))
}

/// The exact steps of the three pieces of a model whose only nonlinearity is a play (inside the
/// play, beyond it, below it: pieces 0, 1, 2, as `Dynamics::play_piece_key` keys them) over `h`
/// seconds.
#[derive(Debug, Clone)]
pub struct PieceMaps {
    h: f64,
    maps: [AffineStep; 3],
}

impl PieceMaps {
    /// The maps of `h` for the three pieces' systems (A, B), each B's last column the piece's
    /// offset, an input held at 1 (`Dynamics::play_pieces`): x⁺ = Φ x + Γ u + e per piece.
    pub fn new(h: f64, pieces: &[(DMatrix<f64>, DMatrix<f64>); 3]) -> Option<PieceMaps> {
        let map = |(a, b): &(DMatrix<f64>, DMatrix<f64>)| -> Option<AffineStep> {
            let (ns, m) = (a.nrows(), b.ncols().checked_sub(1)?);
            let (phi, gamma) = crate::statespace::zoh(a, b, h).ok()?;
            let g = gamma.as_slice();
            AffineStep::new(phi.as_slice(), &g[..ns * m], &g[ns * m..])
        };
        Some(PieceMaps { h, maps: [map(&pieces[0])?, map(&pieces[1])?, map(&pieces[2])?] })
    }

    /// The step length, s.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// x⁺ of piece `piece` under the inputs `u` held over `h`; false for another step length or
    /// an unknown piece.
    pub fn step(&self, piece: u64, x: &[f64], u: &[f64], h: f64, out: &mut [f64]) -> bool {
        let Some(m) = self.maps.get(piece as usize).filter(|_| h == self.h) else { return false };
        m.apply(x, u, out);
        true
    }
}

/// The steps of a linear system ẋ = A x + B u + F g under held inputs `u` and a few smooth
/// forces g(x) (exponential time differencing, second order: Cox & Matthews 2002, ETD2RK), over
/// `h`: the predictor a = Φ x + Γ u + Γ₀ g(x), then x⁺ = a + Γ₁ (g(a) − g(x)), with
/// Γ₀ = ∫₀ʰ e^{A(h−s)} F ds and Γ₁ = ∫₀ʰ e^{A(h−s)} F s/h ds. The linear part is stepped exactly
/// and the forces as if linear in time over the step: its error is of the order of (h·slope)³
/// of the forces' own slopes, nothing of the linear rates.
#[derive(Debug, Clone)]
pub struct ForcedMaps {
    h: f64,
    /// Φ, [Γ Γ₀].
    predict: AffineStep,
    /// Γ₁'s columns.
    correct: Vec<[f64; AFFINE_MAX_STATES]>,
    ns: usize,
}

impl ForcedMaps {
    /// The maps of `h` for A (`ns` × `ns`), B (`ns` × inputs) and F (`ns` × forces); `None` for
    /// more than [`AFFINE_MAX_STATES`] states or a step too long to discretise.
    pub fn new(h: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, f: &DMatrix<f64>) -> Option<ForcedMaps> {
        let (ns, m, k) = (a.nrows(), b.ncols(), f.ncols());
        if ns > AFFINE_MAX_STATES || b.nrows() != ns || f.nrows() != ns {
            return None;
        }
        // ż = M z with z = [x; u; g; ġ·h] (u and ġ held, g growing by ġ): exp(M h)'s first
        // block row is [Φ Γ Γ₀ Γ₁] (Van Loan's block exponential)
        let size = ns + m + 2 * k;
        let mut mh = DMatrix::zeros(size, size);
        mh.view_mut((0, 0), (ns, ns)).copy_from(&(a * h));
        mh.view_mut((0, ns), (ns, m)).copy_from(&(b * h));
        mh.view_mut((0, ns + m), (ns, k)).copy_from(&(f * h));
        for j in 0..k {
            mh[(ns + m + j, ns + m + k + j)] = 1.0;
        }
        let e = crate::statespace::block_exponential(&mh, h).ok()?;
        let top = e.view((0, 0), (ns, size));
        let phi = top.columns(0, ns).into_owned();
        let gamma = top.columns(ns, m + k).into_owned();
        let predict = AffineStep::new(phi.as_slice(), gamma.as_slice(), &vec![0.0; ns])?;
        let correct = (0..k)
            .map(|j| {
                let mut c = [0.0; AFFINE_MAX_STATES];
                for (r, v) in c.iter_mut().take(ns).enumerate() {
                    *v = top[(r, ns + m + k + j)];
                }
                c
            })
            .collect();
        Some(ForcedMaps { h, predict, correct, ns })
    }

    /// The step length, s.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// The predictor: out = Φ x + Γ u + Γ₀ g, `inputs_and_forces` = [u; g(x)].
    #[inline]
    pub fn predict(&self, x: &[f64], inputs_and_forces: &[f64], out: &mut [f64]) {
        self.predict.apply(x, inputs_and_forces, out);
    }

    /// The corrector: out += Γ₁ (g(a) − g(x)), `change` = g(a) − g(x).
    #[inline]
    pub fn correct(&self, change: &[f64], out: &mut [f64]) {
        for (col, &d) in self.correct.iter().zip(change) {
            for (o, c) in out[..self.ns].iter_mut().zip(&col[..self.ns]) {
                *o += c * d;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mass on a spring with play ±b and a stop: ẍ = −k·(x ∓ b) beyond the play.
    struct Play {
        k: f64,
        b: f64,
        calls: usize,
    }

    impl PiecewiseSmooth for Play {
        fn rhs(&mut self, x: &[f64], dx: &mut [f64]) {
            self.calls += 1;
            dx[0] = x[1];
            dx[1] = if x[0] > self.b {
                -self.k * (x[0] - self.b)
            } else if x[0] < -self.b {
                -self.k * (x[0] + self.b)
            } else {
                0.0
            };
        }
        fn piece(&mut self, x: &[f64]) -> u64 {
            u64::from(x[0] > self.b) + 2 * u64::from(x[0] < -self.b)
        }
    }

    #[test]
    fn rattling_in_a_play_matches_its_exact_period() {
        // analytic: in contact a half period π/ω (ω = √k), across the play 2b/v at the speed
        // v = ω·A of the contact arc's amplitude A; started at the play's edge with speed v
        let (k, b, v) = (400.0f64, 0.05, 1.0);
        let w = k.sqrt();
        let period = 2.0 * (std::f64::consts::PI / w + 2.0 * b / v);
        let mut sys = Play { k, b, calls: 0 };
        let mut rk = PiecewiseRk4::new(2, 0.01, 0.01 / 16.0);
        let mut x = [b, v];
        let h = 0.01;
        let steps = (10.0 * period / h).round() as usize;
        let mut crossings = Vec::new();
        let mut prev = x[0];
        for k in 0..steps {
            rk.advance(&mut sys, &mut x, h);
            // upward crossings of the play's centre, interpolated
            if prev < 0.0 && x[0] >= 0.0 {
                crossings.push((k as f64 + prev / (prev - x[0])) * h);
            }
            prev = x[0];
        }
        let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
        // 1e-4 of the period: the kinks are crossed in 1/16 ms sub-steps (first order there)
        assert!((measured - period).abs() < 1e-4 * period, "{measured} vs {period}");
        // energy ½v² + ½k·e² (e beyond the play) kept
        let e = (x[0].abs() - b).max(0.0);
        let energy = 0.5 * x[1] * x[1] + 0.5 * k * e * e;
        assert!((energy / (0.5 * v * v) - 1.0).abs() < 1e-3, "energy {energy}");
        // and most steps were taken whole: fewer calls than all-fine stepping (16 × 4 per ms)
        assert!(sys.calls < steps * 4 * 16 / 3, "{} calls for {steps} steps", sys.calls);
    }

    /// ETD2RK on ẋ = a x + g(x), g = b x, against the closed form x0 e^{(a+b)T}: a constant
    /// force is stepped exactly (b's part only from the corrector) and the error falls as h²
    /// (second order: a quarter per halved step).
    #[test]
    fn forced_steps_are_second_order_in_the_force() {
        let (a, b, x0, t_end) = (-30.0, -8.0, 1.0, 0.5);
        let error = |steps: usize| {
            let h = t_end / steps as f64;
            let maps = ForcedMaps::new(
                h,
                &DMatrix::from_element(1, 1, a),
                &DMatrix::zeros(1, 0),
                &DMatrix::from_element(1, 1, 1.0),
            )
            .unwrap();
            let (mut x, mut out) = ([x0], [0.0]);
            for _ in 0..steps {
                let g0 = b * x[0];
                maps.predict(&x, &[g0], &mut out);
                let change = b * out[0] - g0;
                maps.correct(&[change], &mut out);
                x = out;
            }
            (x[0] - x0 * ((a + b) * t_end).exp()).abs()
        };
        let (coarse, fine) = (error(50), error(100));
        let order = (coarse / fine).log2();
        assert!((order - 2.0).abs() < 0.15, "order {order:.3} ({coarse:.3e}, {fine:.3e})");
        // a force that does not change is stepped exactly: ẋ = a x + 1, x(T) = −1/a + (x0 + 1/a) e^{aT}
        let maps = ForcedMaps::new(
            t_end,
            &DMatrix::from_element(1, 1, a),
            &DMatrix::zeros(1, 0),
            &DMatrix::from_element(1, 1, 1.0),
        )
        .unwrap();
        let mut out = [0.0];
        maps.predict(&[x0], &[1.0], &mut out);
        let exact = -1.0 / a + (x0 + 1.0 / a) * (a * t_end).exp();
        assert!((out[0] - exact).abs() < 1e-14, "{} against {exact}", out[0]);
    }
}
