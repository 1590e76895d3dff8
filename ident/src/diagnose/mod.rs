//! Closing the loop with measured data: the declared model's residual, the evidence on what it
//! lacks, every candidate effect fitted with the declared parameters re-fitted, and the choice
//! by error reduction and an information criterion (BIC with the residual's effective sample
//! count).

pub mod bearing;
pub mod drive;
mod lm;
pub mod torsional;
pub mod verdict;

use std::collections::BTreeMap;

use serde::Serialize;

/// Offsets and drift are removed below max(`HIGH_PASS_PERIODS` / record length, the diagnosis's
/// lowest corner): a few periods of the record's length, whatever the excitation.
pub const HIGH_PASS_PERIODS: f64 = 3.0;

/// The high-pass corner of a record of `n` samples of `dt_s`, at least `min_hz`, Hz.
pub fn high_pass_corner_hz(n: usize, dt_s: f64, min_hz: f64) -> f64 {
    (HIGH_PASS_PERIODS / (n as f64 * dt_s)).max(min_hz)
}

/// The fits stop when a step gains less than this fraction of the cost: the score (BIC) then
/// moves by less than n_eff × 1e-5, under one unit for records of up to 100 000 effective
/// samples, far below what the information criterion tells apart.
pub const LM_REL_TOL: f64 = 1e-5;

/// Smoothing speed of a fitted Coulomb friction, as a fraction of an RMS speed of the record
/// (or wider, where the friction's slope would be faster than the integration resolves).
pub const FRICTION_SMOOTHING_FRACTION: f64 = 0.01;

/// Root mean square of `v`.
pub fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

/// One candidate's result.
#[derive(Debug, Clone, Serialize)]
pub struct CandidateScore {
    /// Effect name (the report's vocabulary).
    pub effect: String,
    /// Where it acts ("body load", "coupling 2", "input 1"), for effects at an element.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at: Option<String>,
    /// Fitted parameters (effect and re-fitted declared ones), SI, keys with units.
    pub parameters: BTreeMap<String, f64>,
    /// Normalised error after fitting.
    pub error_after: f64,
    /// Bayesian information criterion n_eff ln(SSR/n) + k ln(n_eff); lower is better.
    pub score: f64,
    /// Number of fitted parameters.
    pub fitted_parameters: usize,
    /// Its re-fitted declared parameters moved beyond what is plausible (it imitates a missing
    /// effect by distorting the declared mechanics): not chosen.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub implausible: bool,
    /// Why it is implausible: how its re-fit moved the declared mechanics beyond what its
    /// effect explains ([`verdict::declared_moved`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub implausible_because: Vec<String>,
}

/// Bayesian information criterion of a residual of `n` values whose effective count is
/// `n_eff`, with sum of squares `ssr` and `k` fitted parameters.
pub fn bic(ssr: f64, n: usize, n_eff: f64, k: usize) -> f64 {
    n_eff * (ssr / n as f64).max(1e-300).ln() + k as f64 * n_eff.max(2.0).ln()
}

/// Lag-1 autocorrelation of `r` (0 for white noise).
pub fn lag1_autocorrelation(r: &[f64]) -> f64 {
    let m = r.iter().sum::<f64>() / r.len().max(1) as f64;
    let den: f64 = r.iter().map(|v| (v - m).powi(2)).sum();
    if den == 0.0 {
        return 0.0;
    }
    r.windows(2).map(|w| (w[0] - m) * (w[1] - m)).sum::<f64>() / den
}

/// Effective sample count of an AR(1)-like residual: n (1 − ρ)/(1 + ρ), at least 10.
pub fn effective_count(n: usize, rho: f64) -> f64 {
    let rho = rho.clamp(-0.99, 0.999_999);
    (n as f64 * (1.0 - rho) / (1.0 + rho)).max(10.0)
}

/// Worker threads of [`on_two_workers`] running jobs now, at every depth.
static RUNNING: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Whether a core is idle: fewer than two workers are running (none on the calling thread's
/// own, when it is not a worker; one when the other worker has run out of jobs while this one
/// still fits). A fit then computes its Jacobian's columns on two threads.
pub(crate) fn spare_core() -> bool {
    RUNNING.load(std::sync::atomic::Ordering::Relaxed) < 2
}

/// Counts a worker as running while it lives (also when its job panics).
struct Running;
impl Running {
    fn start() -> Running {
        RUNNING.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Running
    }
}
impl Drop for Running {
    fn drop(&mut self) {
        RUNNING.fetch_sub(1, std::sync::atomic::Ordering::Relaxed);
    }
}

/// Runs `job(i)` for i in 0..count on two worker threads taking the indices in turn (this is a
/// 2-core machine's worth of threads: memory then holds two fits' Jacobians and simulations,
/// not one per candidate); the results in index order.
pub(crate) fn on_two_workers<T: Send>(count: usize, job: &(dyn Fn(usize) -> T + Sync)) -> Vec<T> {
    if count == 1 {
        // one job: on this thread, whose fits may then share their Jacobians' columns
        // between the two cores ([`spare_core`])
        return vec![job(0)];
    }
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut done: Vec<(usize, T)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..2)
            .map(|_| {
                scope.spawn(|| {
                    let _running = Running::start();
                    let mut done = Vec::new();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        if i >= count {
                            break done;
                        }
                        done.push((i, job(i)));
                    }
                })
            })
            .collect();
        workers.into_iter().filter_map(|h| h.join().ok()).flatten().collect()
    });
    done.sort_by_key(|d| d.0);
    done.into_iter().map(|d| d.1).collect()
}
