//! The exact (ZOH) step of a linear model over a communication step: the discretisations per
//! piece length, composed from sub-pieces, and the step as one pass over [Ad Bd]. Shared by the
//! drive models' [`crate::stepper::Stepper`] and the rig FMU's step.

use nalgebra::DMatrix;

use crate::error::{PlantError, Result};

/// Discretisations kept: a co-simulation master uses one or a few step sizes (a dead time
/// adds two piece lengths per step size).
pub const CACHE: usize = 8;

/// Most pieces (exact ZOH pieces, or RK4 sub-steps with backlash) one communication step is
/// split into; a longer step is refused rather than taking unbounded time.
pub const MAX_PIECES: usize = 1_000_000;

/// Fastest time scale a model may have, s (‖[A B]‖₁ ≤ its inverse): below it the parameters are
/// not a machine (an inertia of 1e-300 kg m², say) and no step could be taken.
const FASTEST_TIME_SCALE_S: f64 = 1e-15;

/// The exact (ZOH) discretisations of one linear model, per piece length: a co-simulation master
/// uses one or a few step sizes, a dead time adds piece lengths. Shared by the rig's and the
/// drive models' steps. A piece longer than the model's exponential is accurate for
/// (`max_piece_s`: ‖[A B]‖·h within `crate::statespace::ZOH_MAX_NORM`) is the composition of
/// k equal sub-pieces, composed once here — (Ad, Bd)ₖ = (Ad^k, Σⱼ Ad^j Bd), by doubling — so a
/// step is one pass x ← [Ad Bd][x; u] over a contiguous column-major block, as a C loop over
/// the same matrices makes it.
#[derive(Debug, Clone, Default)]
pub struct ZohCache {
    entries: Vec<ZohEntry>,
    /// The entry used last: a master's steps hit it.
    last: usize,
    /// The step's accumulator beyond 16 states.
    acc: Vec<f64>,
}

#[derive(Debug, Clone)]
struct ZohEntry {
    h: f64,
    ad: DMatrix<f64>,
    bd: DMatrix<f64>,
    /// [Ad Bd], column-major.
    fused: Vec<f64>,
}

/// (Ad, Bd) of k consecutive pieces of (Ad, Bd): x_k = Ad^k x_0 + Σ_{j<k} Ad^j Bd u, by doubling
/// (log₂ k products).
fn composed(ad: DMatrix<f64>, bd: DMatrix<f64>, k: usize) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = ad.nrows();
    // (p, q): the map of 2^bit pieces; (acc_p, acc_q): of the pieces taken so far
    let (mut p, mut q) = (ad, bd);
    let (mut acc_p, mut acc_q) = (DMatrix::identity(n, n), DMatrix::zeros(q.nrows(), q.ncols()));
    let mut k = k;
    while k > 0 {
        if k & 1 == 1 {
            acc_q = &p * &acc_q + &q;
            acc_p = &p * &acc_p;
        }
        k >>= 1;
        if k > 0 {
            q = &p * &q + &q;
            p = &p * &p;
        }
    }
    (acc_p, acc_q)
}

/// Most columns (states and inputs) the fixed-size step takes.
const FIXED_COLUMNS: usize = 32;

/// [Ad Bd][x; u] over `fused`'s columns of `R` rows (at most [`FIXED_COLUMNS`] columns), the sums
/// in fixed-size arrays the compiler keeps in registers: two partial sums (even and odd
/// columns), so that the additions form two chains of half the length. The values are read
/// from `x` and `u` in place.
#[inline]
fn step_fixed<const R: usize>(fused: &[f64], x: &[f64], u: &[f64]) -> [f64; R] {
    let (nx, cols) = (x.len(), x.len() + u.len());
    let value = |k: usize| if k < nx { x[k] } else { u[k - nx] };
    let (mut even, mut odd) = ([0.0; R], [0.0; R]);
    let mut k = 0;
    while k + 1 < cols {
        let (c0, c1) = (&fused[k * R..(k + 1) * R], &fused[(k + 1) * R..(k + 2) * R]);
        let (v0, v1) = (value(k), value(k + 1));
        for r in 0..R {
            even[r] += c0[r] * v0;
            odd[r] += c1[r] * v1;
        }
        k += 2;
    }
    if k < cols {
        let (c0, v0) = (&fused[k * R..(k + 1) * R], value(k));
        for r in 0..R {
            even[r] += c0[r] * v0;
        }
    }
    for r in 0..R {
        even[r] += odd[r];
    }
    even
}

/// z ← `next` when every value is finite; else the index of the first that is not, `z` unchanged.
#[inline]
fn commit(z: &mut [f64], next: &[f64]) -> std::result::Result<(), usize> {
    match next.iter().position(|v| !v.is_finite()) {
        Some(k) => Err(k),
        None => {
            z.copy_from_slice(next);
            Ok(())
        }
    }
}

impl ZohCache {
    /// The entry of piece length `h`, discretised if new (the oldest of [`CACHE`] dropped): the
    /// exponential of sub-pieces no longer than `max_piece_s`, composed.
    #[inline]
    pub fn index(&mut self, a: &DMatrix<f64>, b: &DMatrix<f64>, h: f64, max_piece_s: f64) -> Result<usize> {
        // a master's steps: the length of the step before
        if self.entries.get(self.last).is_some_and(|e| e.h == h) {
            return Ok(self.last);
        }
        self.find_or_discretise(a, b, h, max_piece_s)
    }

    /// [`ZohCache::index`] beyond the entry used last (every piece of a step split by a dead
    /// time).
    fn find_or_discretise(&mut self, a: &DMatrix<f64>, b: &DMatrix<f64>, h: f64, max_piece_s: f64) -> Result<usize> {
        // piece lengths from a dead time carry rounding: equal within 1e-12 is the same
        let same = |e: &ZohEntry| (e.h - h).abs() <= 1e-12 * h;
        let i = match self.entries.iter().position(same) {
            Some(i) => i,
            None => {
                let k = (h / max_piece_s).ceil().max(1.0);
                if k.is_nan() || k > MAX_PIECES as f64 {
                    return Err(PlantError::Invalid(format!(
                        "a piece of {h} s needs more than {MAX_PIECES} exact sub-pieces for this model"
                    )));
                }
                let (ad, bd) = crate::statespace::zoh(a, b, h / k)?;
                let (ad, bd) = composed(ad, bd, k as usize);
                if ad.iter().chain(bd.iter()).any(|v| !v.is_finite()) {
                    return Err(PlantError::Invalid(format!("the exact step of {h} s is not finite")));
                }
                if self.entries.len() == CACHE {
                    self.entries.remove(0);
                }
                let fused = ad.iter().chain(bd.iter()).copied().collect();
                self.acc.resize(ad.nrows(), 0.0);
                self.entries.push(ZohEntry { h, ad, bd, fused });
                self.entries.len() - 1
            }
        };
        self.last = i;
        Ok(i)
    }

    /// (Ad, Bd) of entry `i`.
    pub fn get(&self, i: usize) -> (&DMatrix<f64>, &DMatrix<f64>) {
        (&self.entries[i].ad, &self.entries[i].bd)
    }

    /// z ← Ad z + Bd u with entry `i` (`u` of the inputs' length); a non-finite result is
    /// refused (the index of the first such state), `z` unchanged. Allocation-free; up to 16
    /// states (the rig has 6 to 13) the sums stay in registers.
    pub fn advance(&mut self, i: usize, z: &mut [f64], u: &[f64]) -> std::result::Result<(), usize> {
        let (fused, n) = (&self.entries[i].fused, z.len());
        macro_rules! fixed {
            ($($r:literal)*) => {
                match n {
                    $($r => return commit(z, &step_fixed::<$r>(fused, z, u)),)*
                    _ => {}
                }
            };
        }
        if n + u.len() <= FIXED_COLUMNS {
            fixed!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16);
        }
        let acc = &mut self.acc[..n];
        acc.fill(0.0);
        for (column, &v) in fused.chunks_exact(n).zip(z.iter().chain(u)) {
            for (a, c) in acc.iter_mut().zip(column) {
                *a += c * v;
            }
        }
        commit(z, acc)
    }
}

/// Longest exact piece of x' = A x + B u, s: ‖[A B]‖₁ · piece = `crate::statespace::ZOH_MAX_NORM`
/// / 2^10; refuses time scales below `FASTEST_TIME_SCALE_S` (parameters that are no machine).
pub fn longest_exact_piece(a: &DMatrix<f64>, b: &DMatrix<f64>) -> Result<f64> {
    let norm = a.column_iter().chain(b.column_iter()).map(|c| c.lp_norm(1)).fold(0.0, f64::max);
    if norm.is_nan() || norm * FASTEST_TIME_SCALE_S > 1.0 {
        return Err(PlantError::Invalid(format!(
            "the parameters give time scales of {:.1e} s (an inertia, mass or stiffness far off)",
            1.0 / norm
        )));
    }
    Ok(crate::statespace::ZOH_MAX_NORM / 1024.0 / norm.max(1e-300))
}
