//! Spectral helpers on uniformly sampled real signals (rustfft).

use num_complex::Complex64;
use rustfft::FftPlanner;

/// The one-sided spectrum X_k, k = 0..=n/2, of a real signal (unscaled DFT).
pub fn rfft(x: &[f64]) -> Vec<Complex64> {
    let n = x.len();
    let mut buf: Vec<Complex64> = x.iter().map(|&v| Complex64::new(v, 0.0)).collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buf);
    buf.truncate(n / 2 + 1);
    buf
}

/// The sample autocorrelation ρ(k), k = 0..=`max_lag`, of `x` (its mean removed; ρ(0) = 1, all
/// zero for a constant), by FFT zero-padded to twice the length (no wrap-around).
pub fn autocorrelation(x: &[f64], max_lag: usize) -> Vec<f64> {
    let n = x.len();
    let max_lag = max_lag.min(n.saturating_sub(1));
    if n == 0 {
        return Vec::new();
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let mut buf: Vec<Complex64> = x.iter().map(|&v| Complex64::new(v - mean, 0.0)).collect();
    buf.resize(2 * n, Complex64::new(0.0, 0.0));
    let mut planner = FftPlanner::new();
    planner.plan_fft_forward(2 * n).process(&mut buf);
    for v in buf.iter_mut() {
        *v = Complex64::new(v.norm_sqr(), 0.0);
    }
    planner.plan_fft_inverse(2 * n).process(&mut buf);
    let r0 = buf[0].re;
    if r0.is_nan() || r0 <= 0.0 {
        return vec![0.0; max_lag + 1];
    }
    buf[..=max_lag].iter().map(|v| v.re / r0).collect()
}

/// The lag beyond which the correlation of `x` is negligible, samples: Politis' empirical rule
/// (Politis 2003; Politis & White 2004, section 3.2), the smallest m with |ρ(m + k)| <
/// 2 √(log₁₀ n / n) for k = 1..=K_n, K_n = max(5, √log₁₀ n). At most `max_lag` (where no m
/// below it passes).
pub fn correlation_lag(x: &[f64], max_lag: usize) -> usize {
    let n = x.len().max(2) as f64;
    let band = 2.0 * (n.log10() / n).sqrt();
    let k_n = (n.log10().sqrt().ceil() as usize).max(5);
    let rho = autocorrelation(x, max_lag + k_n);
    (0..=max_lag).find(|&m| (1..=k_n).all(|k| rho.get(m + k).is_none_or(|r| r.abs() < band))).unwrap_or(max_lag)
}

/// Cross-correlation c[lag] = Σᵢ u[i]·r[i + lag] for |lag| ≤ `max_lag` (clamped to the data's
/// length), by FFT: O(n log n) whatever the lag range. Returns (lag, c) pairs, lag ascending.
pub fn cross_correlation(u: &[f64], r: &[f64], max_lag: usize) -> Vec<(isize, f64)> {
    let n = u.len().min(r.len());
    if n == 0 {
        return Vec::new();
    }
    let max_lag = max_lag.min(n - 1);
    // zero padding to n + max_lag keeps the circular correlation's wrap-around out of the lags
    // asked for; two buffers of that length are all the memory it takes
    let len = (n + max_lag + 1).next_power_of_two();
    let mut planner = FftPlanner::new();
    let fwd = planner.plan_fft_forward(len);
    let spectrum = |x: &[f64]| {
        let mut b: Vec<Complex64> = Vec::with_capacity(len);
        b.extend(x[..n].iter().map(|&v| Complex64::new(v, 0.0)));
        b.resize(len, Complex64::new(0.0, 0.0));
        fwd.process(&mut b);
        b
    };
    let mut c = spectrum(u);
    {
        let rs = spectrum(r);
        for (a, b) in c.iter_mut().zip(&rs) {
            *a = a.conj() * b;
        }
    }
    planner.plan_fft_inverse(len).process(&mut c);
    (-(max_lag as isize)..=max_lag as isize)
        .map(|lag| (lag, c[lag.rem_euclid(len as isize) as usize].re / len as f64))
        .collect()
}

/// Largest magnitude a recorded SI value may have: beyond it a sample is no measurement (an
/// overflowed or uninitialised value), and its square would overflow the sums every analysis
/// forms.
pub const MAX_PLAUSIBLE_MAGNITUDE: f64 = 1e100;

/// How far a sample may lie from its channel's median, in units of the channel's spread (the
/// range of its 1st to 99th percentile): farther is a glitch, not a measurement. A pulse that
/// occupies under 1 % of a record with 0.1 % noise stands 1e3-1e4 spreads out; a glitch of an
/// overflowed value many orders more.
pub const GLITCH_SPREADS: f64 = 1e6;

/// The first sample of `x` that is no measurement: beyond [`MAX_PLAUSIBLE_MAGNITUDE`], or more
/// than [`GLITCH_SPREADS`] spreads from the median. Returns its index and why.
pub fn implausible_sample(x: &[f64]) -> Option<(usize, String)> {
    if let Some(i) = x.iter().position(|v| v.is_nan() || v.abs() > MAX_PLAUSIBLE_MAGNITUDE) {
        return Some((i, format!("{:e} is beyond any measured value (|x| > {MAX_PLAUSIBLE_MAGNITUDE:e})", x[i])));
    }
    let (median, spread) = median_and_spread(x)?;
    if spread > 0.0 {
        if let Some(i) = x.iter().position(|v| (v - median).abs() > GLITCH_SPREADS * spread) {
            return Some((
                i,
                format!(
                    "{} lies {:.1e} times the signal's 1-99 % range ({spread:.4e}) from its median {median:.6}: a glitch, not a measurement",
                    x[i],
                    (x[i] - median).abs() / spread
                ),
            ));
        }
    }
    None
}

/// The median and the 1st-to-99th-percentile range of `x`; None when empty.
pub fn median_and_spread(x: &[f64]) -> Option<(f64, f64)> {
    if x.is_empty() {
        return None;
    }
    let mut s = x.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    let at = |q: f64| s[((s.len() - 1) as f64 * q).round() as usize];
    Some((at(0.5), at(0.99) - at(0.01)))
}

/// What an analysis needs of a record's sampling.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SamplingNeeds {
    /// Highest frequency the analysis uses, Hz.
    pub max_frequency_hz: f64,
    /// Samples per period it needs at that frequency (Nyquist is 2).
    pub samples_per_period: f64,
    /// Shortest record, s.
    pub min_duration_s: f64,
}

/// Natural frequencies below this are rigid-body motion, not a mode a record must resolve, Hz.
pub const RIGID_BODY_HZ: f64 = 0.01;

/// The flexible modes among `frequencies_hz` (above [`RIGID_BODY_HZ`]): (slowest, fastest), or
/// `None` without one.
fn flexible_range(frequencies_hz: &[f64]) -> Option<(f64, f64)> {
    let flexible = frequencies_hz.iter().copied().filter(|f| *f > RIGID_BODY_HZ);
    let (lo, hi) = flexible.fold((f64::INFINITY, 0.0f64), |(lo, hi), f| (lo.min(f), hi.max(f)));
    (hi > 0.0).then_some((lo, hi))
}

impl SamplingNeeds {
    /// What the torsional diagnosis of a rig with natural frequencies `frequencies_hz` needs:
    /// 8 samples per period of its highest mode (the paper's sweep resolves the shuffle and
    /// the differential's modes sample by sample), a record of 10 periods of its slowest.
    /// `None` without a flexible mode.
    pub fn torsional_sweep(frequencies_hz: &[f64]) -> Option<SamplingNeeds> {
        flexible_range(frequencies_hz).map(|(lo, hi)| SamplingNeeds {
            max_frequency_hz: hi,
            samples_per_period: 8.0,
            min_duration_s: 10.0 / lo,
        })
    }

    /// What the diagnosis of a drive line with natural frequencies `frequencies_hz` needs: its
    /// slowest flexible mode resolved (4 samples per period) and seen for 10 periods; faster
    /// modes of stiff couplings may lie beyond the record's Nyquist frequency, where the fit
    /// sees them as the quasi-static springs they are. `None` without a flexible mode.
    pub fn drive_test(frequencies_hz: &[f64]) -> Option<SamplingNeeds> {
        flexible_range(frequencies_hz).map(|(lo, _)| SamplingNeeds {
            max_frequency_hz: lo,
            samples_per_period: 4.0,
            min_duration_s: 10.0 / lo,
        })
    }

    /// What a bearing shake test over the band `f_min_hz`..`f_max_hz` needs: 2.5 samples per
    /// period at `f_max_hz` (Nyquist is 2) and five periods of the band's lower end (a tenth of
    /// `f_max_hz` at least).
    pub fn bearing_shake(f_min_hz: f64, f_max_hz: f64) -> SamplingNeeds {
        SamplingNeeds {
            max_frequency_hz: f_max_hz,
            samples_per_period: 2.5,
            min_duration_s: 5.0 / f_min_hz.max(0.1 * f_max_hz),
        }
    }

    /// Why a record of `n` samples every `dt_s` cannot serve, if it cannot.
    pub fn problem(&self, dt_s: f64, n: usize) -> Option<String> {
        let have = 1.0 / (dt_s * self.max_frequency_hz);
        if have.is_nan() || have < self.samples_per_period {
            return Some(format!(
                "a sample every {dt_s} s gives {have:.3} samples per period at {:.2} Hz; the analysis needs {} (a step of at most {:.3e} s)",
                self.max_frequency_hz,
                self.samples_per_period,
                1.0 / (self.samples_per_period * self.max_frequency_hz)
            ));
        }
        let duration = dt_s * n.saturating_sub(1) as f64;
        if duration.is_nan() || duration < self.min_duration_s {
            return Some(format!(
                "the record lasts {duration} s; the analysis needs at least {} s",
                self.min_duration_s
            ));
        }
        None
    }
}

/// The standard deviation of the white noise on a sampled signal, from its third differences
/// (a difference-based estimate: Hall, Kay & Titterington 1990): they remove what a smooth
/// signal holds to within its (ω dt)³ — 0.7 % of a 30 Hz component's amplitude at 1 kHz — and
/// turn white noise of deviation σ into a sequence of deviation √20 σ. Their spread is taken
/// as 1.4826 times their median absolute deviation, so that the few samples where a step,
/// a PRBS flip or an impact makes the difference large do not count. 0 for fewer than 4
/// samples.
pub fn noise_sd(x: &[f64]) -> f64 {
    let mut d: Vec<f64> = x.windows(4).map(|w| w[3] - 3.0 * w[2] + 3.0 * w[1] - w[0]).collect();
    if d.is_empty() {
        return 0.0;
    }
    let middle = d.len() / 2;
    let median = *d.select_nth_unstable_by(middle, f64::total_cmp).1;
    for v in &mut d {
        *v = (*v - median).abs();
    }
    1.4826 * *d.select_nth_unstable_by(middle, f64::total_cmp).1 / 20f64.sqrt()
}

/// Removes the least-squares straight line (offset and drift).
pub fn detrend(x: &[f64]) -> Vec<f64> {
    let n = x.len() as f64;
    let tm = (n - 1.0) / 2.0;
    let xm = x.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (i, &v) in x.iter().enumerate() {
        let t = i as f64 - tm;
        sxy += t * (v - xm);
        sxx += t * t;
    }
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    x.iter().enumerate().map(|(i, &v)| v - xm - slope * (i as f64 - tm)).collect()
}

/// Zero-phase high-pass: the DFT lines below `cutoff_hz` removed (section 3's 1 Hz filter).
pub fn high_pass(x: &[f64], dt_s: f64, cutoff_hz: f64) -> Vec<f64> {
    let n = x.len();
    let mut buf: Vec<Complex64> = x.iter().map(|&v| Complex64::new(v, 0.0)).collect();
    let mut planner = FftPlanner::new();
    planner.plan_fft_forward(n).process(&mut buf);
    let df = 1.0 / (n as f64 * dt_s);
    for (k, line) in buf.iter_mut().enumerate() {
        if (k.min(n - k) as f64) * df < cutoff_hz {
            *line = Complex64::new(0.0, 0.0);
        }
    }
    planner.plan_fft_inverse(n).process(&mut buf);
    buf.iter().map(|c| c.re / n as f64).collect()
}

/// Hann-windowed frames of a signal and their DFTs: one FFT plan and one window for all the
/// frames (and all the signals) they are made for.
#[derive(Clone)]
struct HannFrames {
    fft: std::sync::Arc<dyn rustfft::Fft<f64>>,
    hann: Vec<f64>,
}

impl HannFrames {
    fn new(window: usize) -> HannFrames {
        let hann =
            (0..window).map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / window as f64).cos()).collect();
        HannFrames { fft: FftPlanner::new().plan_fft_forward(window), hann }
    }

    /// `visit(start, dft)` for every whole frame of `x`, frames `hop` (at least 1) samples apart.
    fn each(&self, x: &[f64], hop: usize, mut visit: impl FnMut(usize, &[Complex64])) {
        let window = self.hann.len();
        let mut buf = vec![Complex64::new(0.0, 0.0); window];
        let mut scratch = vec![Complex64::new(0.0, 0.0); self.fft.get_inplace_scratch_len()];
        let mut start = 0;
        while start + window <= x.len() {
            for ((b, v), h) in buf.iter_mut().zip(&x[start..start + window]).zip(&self.hann) {
                *b = Complex64::new(v * h, 0.0);
            }
            self.fft.process_with_scratch(&mut buf, &mut scratch);
            visit(start, &buf);
            start += hop.max(1);
        }
    }
}

/// Short-time spectral magnitudes: Hann-windowed frames of `window` samples every half window,
/// the magnitudes of DFT lines 1 to `lines` of each. They keep a response's amplitude over time
/// and frequency and drop its phase.
#[derive(Clone)]
pub struct Spectrogram {
    frames: HannFrames,
    lines: usize,
}

impl std::fmt::Debug for Spectrogram {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Spectrogram").field("window", &self.frames.hann.len()).field("lines", &self.lines).finish()
    }
}

impl Spectrogram {
    /// Frames of `window` samples (at least 4), lines 1..=`lines` (at most half the window).
    pub fn new(window: usize, lines: usize) -> Spectrogram {
        let window = window.max(4);
        Spectrogram { frames: HannFrames::new(window), lines: lines.clamp(1, window / 2) }
    }

    /// The magnitudes of every whole frame of `x`, frame by frame, appended to `out`.
    pub fn magnitudes(&self, x: &[f64], out: &mut Vec<f64>) {
        let lines = self.lines;
        self.frames.each(x, self.frames.hann.len() / 2, |_, dft| out.extend(dft[1..=lines].iter().map(|c| c.norm())));
    }
}

/// Power of `x` in `[f_lo, f_hi]` over time: Hann-windowed frames of `window` samples every
/// `hop` samples; returns (frame centre times in s, band power).
pub fn band_power_over_time(
    x: &[f64],
    dt_s: f64,
    window: usize,
    hop: usize,
    f_lo: f64,
    f_hi: f64,
) -> (Vec<f64>, Vec<f64>) {
    let df = 1.0 / (window as f64 * dt_s);
    let (k_lo, k_hi) = ((f_lo / df).ceil() as usize, ((f_hi / df).floor() as usize).min(window / 2));
    let mut times = Vec::new();
    let mut power = Vec::new();
    HannFrames::new(window).each(x, hop, |start, dft| {
        power.push(dft[k_lo..=k_hi].iter().map(|c| c.norm_sqr()).sum());
        times.push((start as f64 + window as f64 / 2.0) * dt_s);
    });
    (times, power)
}

/// Instantaneous frequency of an oscillating signal from its upward zero crossings: one
/// (time in s, frequency in Hz) point per period, at the period's middle. A crossing counts
/// only after the signal has been below −0.2·RMS (hysteresis), so noise near zero adds none.
pub fn zero_crossing_frequency(x: &[f64], dt_s: f64) -> Vec<(f64, f64)> {
    let rms = (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt();
    let h = 0.2 * rms;
    let mut armed = false;
    let mut crossings = Vec::new();
    for i in 1..x.len() {
        if x[i] < -h {
            armed = true;
        }
        if armed && x[i - 1] < 0.0 && x[i] >= 0.0 {
            let frac = -x[i - 1] / (x[i] - x[i - 1]);
            crossings.push((i as f64 - 1.0 + frac) * dt_s);
            armed = false;
        }
    }
    crossings.windows(2).map(|w| (0.5 * (w[0] + w[1]), 1.0 / (w[1] - w[0]))).collect()
}

/// Linear interpolation in a table sorted by its first column (clamped at the ends).
pub fn interpolate(table: &[(f64, f64)], x: f64) -> Option<f64> {
    let first = table.first()?;
    let last = table.last()?;
    if x <= first.0 {
        return Some(first.1);
    }
    if x >= last.0 {
        return Some(last.1);
    }
    let i = table.partition_point(|p| p.0 <= x);
    let (a, b) = (table[i - 1], table[i]);
    Some(a.1 + (b.1 - a.1) * (x - a.0) / (b.0 - a.0))
}

/// Zero-phase second-order Butterworth high-pass (bilinear transform, run forward then
/// backward): O(n), for removing offsets and drift from signals compared with each other
/// through the same filter.
pub fn filtfilt_high_pass(x: &[f64], dt_s: f64, cutoff_hz: f64) -> Vec<f64> {
    let mut y = x.to_vec();
    filtfilt_high_pass_in_place(&mut y, dt_s, cutoff_hz);
    y
}

/// [`filtfilt_high_pass`] overwriting its input (no second buffer for a long record).
pub fn filtfilt_high_pass_in_place(x: &mut [f64], dt_s: f64, cutoff_hz: f64) {
    filtfilt_high_pass_pair(x, &mut [], dt_s, cutoff_hz);
}

/// [`filtfilt_high_pass_in_place`] of two signals at once (an empty one is left alone): the
/// recurrence is bound by its own latency, so two independent ones run in the time of one.
pub fn filtfilt_high_pass_pair(x: &mut [f64], y: &mut [f64], dt_s: f64, cutoff_hz: f64) {
    let k = (std::f64::consts::PI * cutoff_hz * dt_s).tan();
    let q = std::f64::consts::FRAC_1_SQRT_2;
    let norm = 1.0 / (1.0 + k / q + k * k);
    let (b0, b1, b2) = (norm, -2.0 * norm, norm);
    let (a1, a2) = (2.0 * (k * k - 1.0) * norm, (1.0 - k / q + k * k) * norm);
    let c = [b0, b1, b2, a1, a2];
    /// One direction of the biquad, started from rest at its first value (no step into the
    /// filter).
    #[derive(Clone, Copy)]
    struct Biquad {
        x1: f64,
        x2: f64,
        y1: f64,
        y2: f64,
    }
    impl Biquad {
        fn start(v: f64) -> Self {
            Biquad { x1: v, x2: v, y1: 0.0, y2: 0.0 }
        }
        #[inline(always)]
        fn next(&mut self, v: f64, c: &[f64; 5]) -> f64 {
            let [b0, b1, b2, a1, a2] = *c;
            let y = b0 * v + b1 * self.x1 + b2 * self.x2 - a1 * self.y1 - a2 * self.y2;
            self.x2 = self.x1;
            self.x1 = v;
            self.y2 = self.y1;
            self.y1 = y;
            y
        }
    }
    for backward in [false, true] {
        let (n, m) = (x.len(), y.len());
        let at = |i: usize, len: usize| if backward { len - 1 - i } else { i };
        let mut fx = x.first().map(|_| Biquad::start(x[at(0, n)]));
        let mut fy = y.first().map(|_| Biquad::start(y[at(0, m)]));
        let both = if fx.is_some() && fy.is_some() { n.min(m) } else { 0 };
        if let (Some(p), Some(q)) = (fx.as_mut(), fy.as_mut()) {
            for i in 0..both {
                let (ix, iy) = (at(i, n), at(i, m));
                x[ix] = p.next(x[ix], &c);
                y[iy] = q.next(y[iy], &c);
            }
        }
        if let Some(p) = fx.as_mut() {
            for i in both..n {
                let ix = at(i, n);
                x[ix] = p.next(x[ix], &c);
            }
        }
        if let Some(q) = fy.as_mut() {
            for i in both..m {
                let iy = at(i, m);
                y[iy] = q.next(y[iy], &c);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use std::f64::consts::PI;

    /// White noise of a known deviation on a 5 Hz sine sampled at 1 kHz, and on a PRBS of ±1
    /// held 20 ms: the estimate holds it to 5 % beside the sine (its own standard error over
    /// 20 000 samples is about 1 %; the sine's third differences add 0.1 % of σ) and to 15 %
    /// beside the PRBS, whose flips leave 3 large differences in every 40 samples: 7.5 % of them
    /// outliers, which raise a median absolute deviation by about a tenth.
    #[test]
    fn noise_is_estimated_beside_a_smooth_signal_and_steps() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let sigma = 0.01;
        let noise = Normal::new(0.0, sigma).unwrap();
        let n = 20_000;
        let sine: Vec<f64> = (0..n).map(|k| (2.0 * std::f64::consts::PI * 5.0 * k as f64 * 1e-3).sin()).collect();
        // a level flipped with probability 1/2 every 20 samples (as the survey's PRBS)
        let mut level = 1.0;
        let prbs: Vec<f64> = (0..n)
            .map(|k| {
                if k % 20 == 0 && (k / 20 * 7919) % 2 == 0 {
                    level = -level;
                }
                level
            })
            .collect();
        for (signal, within) in [(&sine, 0.05), (&prbs, 0.15)] {
            let x: Vec<f64> = signal.iter().map(|v| v + noise.sample(&mut rng)).collect();
            let estimate = noise_sd(&x);
            assert!((estimate / sigma - 1.0).abs() < within, "{estimate} against {sigma}");
        }
        assert_eq!(noise_sd(&sine[..3]), 0.0);
        assert!(noise_sd(&sine) < 1e-3 * sigma, "a noise-free sine: {}", noise_sd(&sine));
    }

    #[test]
    fn the_correlation_lag_of_white_noise_is_short_and_of_an_ar1_series_its_decay() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let white: Vec<f64> = (0..20_000).map(|_| Distribution::<f64>::sample(&StandardNormal, &mut rng)).collect();
        // white noise: ρ(k) = 0 for k ≥ 1, within the band 2√(log₁₀ n/n) = 0.029 but for the
        // chance excursion (5 % of lags pass 1.96/√n = 0.014, far fewer 0.029)
        assert!(correlation_lag(&white, 1000) <= 2, "{}", correlation_lag(&white, 1000));
        // AR(1) with φ = 0.99: ρ(k) = 0.99^k falls below 0.029 at k = ln 0.029 / ln 0.99 = 352;
        // the estimate's own noise (Bartlett: σ ≈ √((1+φ²)/(1−φ²)/n) = 0.07) moves it by
        // about a hundred lags either way
        let mut ar = vec![0.0; 20_000];
        for k in 1..ar.len() {
            ar[k] = 0.99 * ar[k - 1] + white[k];
        }
        let m = correlation_lag(&ar, 5000);
        assert!((150..700).contains(&m), "{m}");
        let rho = autocorrelation(&ar, 10);
        assert!((rho[1] - 0.99).abs() < 0.01, "{}", rho[1]);
        assert_eq!(autocorrelation(&[1.0; 10], 3), vec![0.0; 4]);
    }

    #[test]
    fn rfft_of_a_cosine_has_one_line() {
        let n = 1000;
        let x: Vec<f64> = (0..n).map(|i| (2.0 * PI * 50.0 * i as f64 / n as f64).cos()).collect();
        let s = rfft(&x);
        assert_eq!(s.len(), 501);
        assert_relative_eq!(s[50].re, n as f64 / 2.0, epsilon = 1e-8);
        assert!(s[49].norm() < 1e-8);
    }

    #[test]
    fn two_signals_filtered_together_are_each_filtered_alone() {
        // the pair interleaves two recurrences: neither may see the other, whatever the lengths;
        // and each direction is the biquad's recurrence (checked at one sample by hand)
        let (dt, fc) = (1e-3, 2.0);
        let a: Vec<f64> = (0..3000).map(|i| (i as f64 * 0.013).sin() + 0.5).collect();
        let b: Vec<f64> = (0..1700).map(|i| (i as f64 * 0.031).cos() * 2.0 - 1.0).collect();
        let (mut pa, mut pb) = (a.clone(), b.clone());
        filtfilt_high_pass_pair(&mut pa, &mut pb, dt, fc);
        let (mut sa, mut sb) = (a.clone(), b.clone());
        filtfilt_high_pass_pair(&mut sa, &mut [], dt, fc);
        filtfilt_high_pass_pair(&mut [], &mut sb, dt, fc);
        assert_eq!(pa, sa);
        assert_eq!(pb, sb);
        let (mut pb2, mut pa2) = (b.clone(), a.clone());
        filtfilt_high_pass_pair(&mut pb2, &mut pa2, dt, fc);
        assert_eq!(pa2, sa);
        assert_eq!(pb2, sb);
        // forward pass alone at sample 2 from rest at the first value: y0 = 0 (x1 = x2 = x0),
        // y1 = b0 x1 + b1 x0 + b2 x0 − a1·0
        let k = (PI * fc * dt).tan();
        let q = std::f64::consts::FRAC_1_SQRT_2;
        let norm = 1.0 / (1.0 + k / q + k * k);
        let y1 = norm * (a[1] - 2.0 * a[0] + a[0]);
        let mut fwd = a[..2].to_vec();
        // a two-sample signal filtered both ways: backward starts from rest at y1
        filtfilt_high_pass_pair(&mut fwd, &mut [], dt, fc);
        assert_relative_eq!(fwd[1], 0.0, epsilon = 1e-15);
        assert_relative_eq!(fwd[0], norm * (0.0 - 2.0 * y1 + y1), epsilon = 1e-12);
    }

    #[test]
    fn detrend_and_high_pass_remove_offset_drift_and_low_lines() {
        let dt = 1e-3;
        let x: Vec<f64> = (0..4000)
            .map(|i| {
                3.0 + 0.5 * i as f64 * dt
                    + (2.0 * PI * 0.5 * i as f64 * dt).cos()
                    + (2.0 * PI * 10.0 * i as f64 * dt).sin()
            })
            .collect();
        let d = detrend(&x);
        assert!(d.iter().sum::<f64>().abs() < 1e-6);
        let h = high_pass(&d, dt, 1.0);
        for (i, v) in h.iter().enumerate().skip(500).take(3000) {
            let want = (2.0 * PI * 10.0 * i as f64 * dt).sin();
            assert!((v - want).abs() < 0.05, "{i}: {v} vs {want}");
        }
    }

    #[test]
    fn zero_crossings_track_a_linear_chirp() {
        // f(t) = 1 + 2t Hz → phase 2π(t + t²)
        let dt = 1e-4;
        let x: Vec<f64> = (0..100_000)
            .map(|i| {
                let t = i as f64 * dt;
                (2.0 * PI * (t + t * t)).sin()
            })
            .collect();
        let f = zero_crossing_frequency(&x, dt);
        let at = interpolate(&f, 5.0).unwrap();
        assert_relative_eq!(at, 11.0, max_relative = 1e-3);
    }

    #[test]
    fn cross_correlation_by_fft_is_the_direct_sum() {
        let u: Vec<f64> = (0..200).map(|i| ((i * 37 % 101) as f64 - 50.0) / 50.0).collect();
        let r: Vec<f64> = (0..200).map(|i| ((i * 53 % 97) as f64 - 48.0) / 48.0).collect();
        for (lag, c) in cross_correlation(&u, &r, 30) {
            let direct: f64 = (0..200isize)
                .filter_map(|i| {
                    let j = i + lag;
                    (0..200).contains(&j).then(|| u[i as usize] * r[j as usize])
                })
                .sum();
            assert!((c - direct).abs() < 1e-9, "lag {lag}: {c} vs {direct}");
        }
        // a lag range beyond the data is clamped to it
        assert_eq!(cross_correlation(&u[..5], &r[..5], 1_000_000).len(), 9);
    }

    #[test]
    fn glitches_and_overflowed_values_are_found_pulses_are_not() {
        let mut x: Vec<f64> = (0..1000).map(|i| 40.0 + (i as f64 * 0.1).sin()).collect();
        assert_eq!(implausible_sample(&x), None);
        x[500] = 1e200;
        assert_eq!(implausible_sample(&x).map(|p| p.0), Some(500));
        x[500] = 5e6; // 2.5e6 spreads of 2 from the median
        assert_eq!(implausible_sample(&x).map(|p| p.0), Some(500));
        // a pulse excitation: zero with 0.1 % noise, five pulses of 10
        let mut p: Vec<f64> = (0..1000).map(|i| 1e-3 * ((i * 7919 % 200) as f64 / 100.0 - 1.0)).collect();
        for k in [100, 300, 500, 700, 900] {
            p[k] = 10.0;
        }
        assert_eq!(implausible_sample(&p), None);
    }

    #[test]
    fn sampling_needs_name_the_step_they_need() {
        let needs = SamplingNeeds { max_frequency_hz: 12.5, samples_per_period: 8.0, min_duration_s: 2.0 };
        assert_eq!(needs.problem(1e-3, 60_001), None);
        assert!(needs.problem(1.0, 60_001).unwrap().contains("at most 1.000e-2 s"));
        assert!(needs.problem(1e-3, 1000).unwrap().contains("lasts"));
    }
}
