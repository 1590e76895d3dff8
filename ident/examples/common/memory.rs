//! The process's memory as Linux reports it (/proc/self/status), for the timing examples.

/// A field of /proc/self/status in kB, where there is one.
pub fn status_kb(field: &str) -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with(field))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Prints the process's peak (VmHWM) and the peak above `before_kb` (its size once the record
/// was made) per sample and channel of a record of `samples` samples in `channels` channels
/// (inputs and outputs).
pub fn print_peak_above(before_kb: Option<u64>, samples: usize, channels: usize) {
    if let (Some(before), Some(peak)) = (before_kb, status_kb("VmHWM")) {
        let above = peak.saturating_sub(before);
        let per = (above as f64 * 1024.0) / (samples as f64 * channels as f64);
        println!(
            "memory: peak {:.1} MB, {:.1} MB above the record, {per:.0} bytes per sample per channel",
            peak as f64 / 1024.0,
            above as f64 / 1024.0
        );
    }
}
