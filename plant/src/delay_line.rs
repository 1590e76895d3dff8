//! The history of a piecewise-constant input for its dead time ([`DelayLine`]): what an FMU
//! and a closed loop keep of each delayed input between steps. No I/O.

/// The history of a piecewise-constant signal for a dead time: (time from which a value
/// holds, value), times increasing. Feeds an FMU's or a closed loop's delayed input.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DelayLine {
    records: Vec<(f64, f64)>,
}

impl DelayLine {
    /// The line of stored records (times increasing).
    pub fn from_records(records: Vec<(f64, f64)>) -> Option<DelayLine> {
        // the first record may start at −∞: the value held before the start
        let ok = records.windows(2).all(|w| w[0].0 < w[1].0)
            && records.iter().enumerate().all(|(i, r)| r.0.is_finite() || (i == 0 && r.0 == f64::NEG_INFINITY));
        ok.then_some(DelayLine { records })
    }

    /// The stored records.
    pub fn records(&self) -> &[(f64, f64)] {
        &self.records
    }

    /// The signal takes `value` from time `t` on (`f64::NEG_INFINITY`: the value it had before
    /// any recorded time, e.g. at initialisation). Records after `t` are dropped: an importer
    /// that goes back (a rejected solver step) overwrites what it set there.
    pub fn record(&mut self, t: f64, value: f64) {
        while self.records.last().is_some_and(|r| r.0 >= t) {
            self.records.pop();
        }
        if self.records.last().is_none_or(|r| r.1 != value) {
            self.records.push((t, value));
        }
    }

    /// The value at time `s`: the first value held before the first record; `current` if
    /// nothing was recorded.
    pub fn value_at(&self, s: f64, current: f64) -> f64 {
        match self.records.iter().rposition(|r| r.0 <= s) {
            Some(i) => self.records[i].1,
            None => self.records.first().map_or(current, |r| r.1),
        }
    }

    /// The signal delayed by `delay_s` over [t0, t1) as pieces (length, value), appended to `out`.
    pub fn segments(&self, t0: f64, t1: f64, delay_s: f64, current: f64, out: &mut Vec<(f64, f64)>) {
        let mut start = t0;
        let mut value = self.value_at(t0 - delay_s, current);
        for &(t, v) in &self.records {
            let at = t + delay_s;
            // breakpoints closer than 1e-12 of the step to its ends are the ends
            let tol = 1e-12 * (t1 - t0).abs().max(t1.abs());
            if at > start + tol && at < t1 - tol {
                out.push((at - start, value));
                start = at;
            }
            if at <= start + tol {
                value = v;
            }
        }
        out.push((t1 - start, value));
    }

    /// Drops what is no longer needed once the time reached `t`: records before the one in
    /// force at `t − delay_s`.
    pub fn forget_before(&mut self, t: f64, delay_s: f64) {
        if self.records.len() < 2 {
            return;
        }
        if let Some(i) = self.records.iter().rposition(|r| r.0 <= t - delay_s).filter(|&i| i > 0) {
            self.records.drain(..i);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delay_line_shifts_a_held_signal() {
        let mut d = DelayLine::default();
        assert_eq!(d.value_at(5.0, 7.0), 7.0, "nothing recorded: the current value");
        d.record(0.0, 1.0);
        d.record(1e-3, 2.0);
        d.record(2e-3, 2.0); // unchanged: no new record
        assert_eq!(d.records().len(), 2);
        let mut out = Vec::new();
        // u(s − 1.5 ms) over [2 ms, 3 ms): 1 until 2.5 ms, then 2
        d.segments(2e-3, 3e-3, 1.5e-3, 2.0, &mut out);
        assert_eq!(out.len(), 2);
        assert!((out[0].0 - 0.5e-3).abs() < 1e-15 && out[0].1 == 1.0);
        assert!((out[1].0 - 0.5e-3).abs() < 1e-15 && out[1].1 == 2.0);
        // before the first record the first value holds
        assert_eq!(d.value_at(-1.0, 9.0), 1.0);
        // a rejected step: setting at an earlier time drops the later records
        d.record(0.5e-3, 4.0);
        assert_eq!(d.records(), &[(0.0, 1.0), (0.5e-3, 4.0)]);
        d.forget_before(10.0, 1e-3);
        assert_eq!(d.records(), &[(0.5e-3, 4.0)]);
    }
}
