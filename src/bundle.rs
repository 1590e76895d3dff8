//! Measurement bundles (`../shared/DATA.md`): a TOML file naming the data and the declared
//! model, and the recorded signals as CSV.

use serde::Deserialize;
use std::path::{Path, PathBuf};

use ident::Sweep;
use plant::{RigParams, Variant};

use crate::units::{Calibration, Dimension};
use modelfile::drive::BodyRef;
use modelfile::rig::parse_rig;

/// A bundle that cannot be used: which file, which line if known, and what is wrong.
#[derive(Debug, thiserror::Error)]
#[error("{}{}: {message}", file.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct BundleError {
    /// The file.
    pub file: PathBuf,
    /// 1-based line, where the problem has one.
    pub line: Option<usize>,
    /// What is wrong and what was expected.
    pub message: String,
}

fn error(file: &Path, line: Option<usize>, message: impl Into<String>) -> BundleError {
    BundleError { file: file.to_path_buf(), line, message: message.into() }
}

/// The files a bundle reads: the TOML itself and the data files it names (as far as they can
/// be read from it), so that no output is written over them.
pub fn input_files(file: &Path) -> Vec<PathBuf> {
    #[derive(Deserialize)]
    struct Names {
        data: Option<String>,
        tests: Option<Vec<String>>,
    }
    let mut out = vec![file.to_path_buf()];
    let dir = file.parent().unwrap_or(Path::new("."));
    if let Some(names) = crate::files::read_text(file).ok().and_then(|t| toml::from_str::<Names>(&t).ok()) {
        out.extend(names.data.into_iter().chain(names.tests.unwrap_or_default()).map(|n| dir.join(n)));
    }
    out
}

/// A `torsional_sweep` bundle, loaded.
#[derive(Debug, Clone)]
pub struct TorsionalBundle {
    /// The TOML file.
    pub file: PathBuf,
    /// Rig variant of the run.
    pub variant: Variant,
    /// The declared model.
    pub model: RigParams,
    /// The recorded sweep.
    pub sweep: Sweep,
    /// Unit conversions and calibrations applied to the recorded channels.
    pub conversions: Vec<String>,
}

#[derive(Deserialize)]
struct Header {
    kind: String,
    data: Option<String>,
    variant: Option<toml::Value>,
    columns: Option<std::collections::BTreeMap<String, ColumnFile>>,
    time: Option<String>,
    sample_rate_hz: Option<f64>,
    resample: Option<bool>,
}

/// Where the samples' times come from: a column (variable, channel), or a sample rate.
#[derive(Debug, Clone, PartialEq)]
enum TimeBase {
    /// The time signal (the first spec) is read like the others; `true`: non-uniform stamps
    /// are resampled (the bundle's `resample = true`).
    Column(bool),
    /// Uniform samples at this rate, starting at 0 s.
    Rate(f64),
}

/// The time base of a bundle from its `time` and `sample_rate_hz` keys; `time` renames the
/// time signal (the first of `specs`).
fn time_base(
    file: &Path,
    time: Option<&str>,
    rate: Option<f64>,
    resample: Option<bool>,
    specs: &mut [SignalSpec],
) -> Result<TimeBase, BundleError> {
    let resample = resample.unwrap_or(false);
    if resample && rate.is_some() {
        return Err(error(file, None, "`resample = true` needs time stamps: it cannot go with `sample_rate_hz`"));
    }
    match (time, rate) {
        (Some(_), Some(_)) => {
            Err(error(file, None, "give either `time` (the time signal) or `sample_rate_hz`, not both"))
        }
        (Some(t), None) => {
            specs[0].channel = t.to_string();
            Ok(TimeBase::Column(resample))
        }
        (None, Some(r)) if r.is_finite() && r > 0.0 => Ok(TimeBase::Rate(r)),
        (None, Some(r)) => Err(error(file, None, format!("`sample_rate_hz` = {r}: expected a positive, finite rate"))),
        (None, None) => Ok(TimeBase::Column(resample)),
    }
}

/// Where a signal of a kind with fixed column names is in the file, and how its values become SI
/// (`[columns]`, `../shared/DATA.md`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ColumnFile {
    channel: Option<String>,
    unit: Option<String>,
    #[serde(default = "unit_gain")]
    gain: f64,
    #[serde(default)]
    offset: f64,
}

fn unit_gain() -> f64 {
    1.0
}

/// One signal a reader needs: its name in the format, where it is in the file, what it measures
/// and how its recorded values become SI; `key` names its calibration in the bundle.
struct SignalSpec {
    name: String,
    channel: String,
    dimension: Dimension,
    calibration: Calibration,
    key: String,
}

/// The specs of the fixed columns `expected` (name, dimension), remapped by `[columns]`.
fn fixed_columns(
    file: &Path,
    columns: Option<&std::collections::BTreeMap<String, ColumnFile>>,
    expected: &[(&str, Dimension)],
) -> Result<Vec<SignalSpec>, BundleError> {
    if let Some(map) = columns {
        if let Some(k) = map.keys().find(|k| !expected.iter().any(|(n, _)| n == k)) {
            let names: Vec<&str> = expected.iter().map(|(n, _)| *n).collect();
            return Err(error(
                file,
                None,
                format!("`columns.{k}` is not a signal of this kind: expected {}", names.join(", ")),
            ));
        }
    }
    Ok(expected
        .iter()
        .map(|&(name, dimension)| {
            let c = columns.and_then(|m| m.get(name));
            SignalSpec {
                name: name.into(),
                channel: c.and_then(|c| c.channel.clone()).unwrap_or_else(|| name.into()),
                dimension,
                calibration: c
                    .map(|c| Calibration { unit: c.unit.clone(), gain: c.gain, offset: c.offset })
                    .unwrap_or_default(),
                key: format!("columns.{name}"),
            }
        })
        .collect())
}

/// What the calibrations of `specs` do to the recorded values, one line each (none for SI columns
/// read as they are).
fn conversions_of(specs: &[SignalSpec]) -> Vec<String> {
    specs.iter().filter_map(|s| s.calibration.describe(&s.name, &s.channel, s.dimension)).collect()
}

/// Reads the signals `specs` (the time first) from the record `path` (a CSV, a `.mat` file or
/// an MDF 4 file; named in the bundle `file`) and converts them to SI. An MDF channel without a
/// `unit` in the bundle gets its own unit (written into `specs`); without a `time` key its
/// group's master channel gives the time, and channels of different groups are resampled onto
/// one time base (said in the returned note).
fn read_signals(
    file: &Path,
    path: &Path,
    specs: &mut [SignalSpec],
    time: &TimeBase,
) -> Result<(Vec<Vec<f64>>, Option<String>), BundleError> {
    let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let mdf = matches!(extension.as_deref(), Some("mf4" | "mdf"));
    let column = matches!(time, TimeBase::Column(_));
    let master = mdf && column && specs[0].channel == "time_s";
    let first = if column && !master { 0 } else { 1 };
    let channels: Vec<String> = specs[first..].iter().map(|s| s.channel.clone()).collect();
    let channels: Vec<&str> = channels.iter().map(String::as_str).collect();
    let mut note: Option<String> = None;
    let mut cols = match extension.as_deref() {
        Some("mat") => read_mat(path, &channels)?,
        Some("mf4" | "mdf") => {
            let mut m = read_mdf_channels(path, &channels)?;
            for (s, unit) in specs[first..].iter_mut().zip(&m.units) {
                if s.calibration.unit.is_none() && !unit.trim().is_empty() {
                    s.calibration.unit = Some(unit.trim().to_string());
                }
            }
            if master {
                let (t, n) = common_time_base(path, &channels, &mut m.times, &mut m.values)?;
                note = n;
                m.values.insert(0, t);
            } else if m.values.iter().any(|v| v.len() != m.values[0].len()) {
                return Err(error(path, None, "the channels have different lengths: leave out `time`/`sample_rate_hz` to resample them on their master times"));
            }
            m.values
        }
        _ => read_columns(path, &channels)?,
    };
    if let TimeBase::Rate(r) = time {
        let n = cols[0].len();
        cols.insert(0, (0..n).map(|k| k as f64 / r).collect());
    }
    for (s, col) in specs.iter().zip(cols.iter_mut()) {
        let (scale, offset) = s.calibration.resolve(s.dimension).map_err(|e| {
            let channel = if mdf { format!(" (channel `{}`)", s.channel) } else { String::new() };
            error(file, None, format!("`{}`{channel}: {e}", s.key))
        })?;
        if (scale, offset) != (1.0, 0.0) {
            for v in col.iter_mut() {
                *v = scale * *v + offset;
            }
        }
    }
    if *time == TimeBase::Column(true) {
        let (t, rest) = cols.split_first_mut().expect("a time column");
        let n = resample_uniform(path, t, rest)?;
        note = Some(match note {
            Some(a) => format!("{a}; {n}"),
            None => n,
        });
    }
    Ok((cols, note))
}

/// `resample = true`: samples whose stamp does not increase are dropped (the first of a
/// repeated stamp is kept), and every signal is interpolated linearly onto a uniform grid at
/// the median step from the first to the last stamp. Returns the note for the report (how
/// many samples were dropped, the largest gap bridged).
fn resample_uniform(path: &Path, t: &mut Vec<f64>, cols: &mut [Vec<f64>]) -> Result<String, BundleError> {
    if let Some(k) = t.iter().position(|v| !v.is_finite()) {
        return Err(error(path, Some(k + 2), format!("time stamp {} is not a number", t[k])));
    }
    let mut keep = vec![true; t.len()];
    let mut last = f64::NEG_INFINITY;
    for (k, v) in t.iter().enumerate() {
        if *v <= last {
            keep[k] = false;
        } else {
            last = *v;
        }
    }
    let dropped = keep.iter().filter(|k| !**k).count();
    let pick = |v: &[f64]| -> Vec<f64> { v.iter().zip(&keep).filter(|(_, k)| **k).map(|(v, _)| *v).collect() };
    let ts = pick(t);
    if ts.len() < 2 {
        return Err(error(path, None, "fewer than two increasing time stamps: nothing to resample"));
    }
    let mut steps: Vec<f64> = ts.windows(2).map(|w| w[1] - w[0]).collect();
    let gap = steps.iter().copied().fold(0.0, f64::max);
    steps.sort_by(|a, b| a.total_cmp(b));
    let dt = steps[steps.len() / 2];
    let n = ((ts[ts.len() - 1] - ts[0]) / dt + 1e-9).floor() as usize + 1;
    if n > 4 * ts.len() + 16 {
        return Err(error(
            path,
            None,
            format!(
                "resampling at the median step {dt} s would make {n} samples of {}: the stamps are too irregular",
                ts.len()
            ),
        ));
    }
    let grid: Vec<f64> = (0..n).map(|k| ts[0] + k as f64 * dt).collect();
    for col in cols.iter_mut() {
        *col = interpolate(&ts, &pick(col), &grid);
    }
    *t = grid;
    Ok(format!(
        "resampled (resample = true) by linear interpolation onto {:.6} Hz: {dropped} samples with a repeated or earlier stamp dropped, largest gap {gap:.6} s ({:.1} steps)",
        1.0 / dt,
        gap / dt
    ))
}

/// `v` sampled at the increasing times `t` (at least two), linearly interpolated at each point
/// of the increasing `grid` (held at the ends outside `t`).
fn interpolate(t: &[f64], v: &[f64], grid: &[f64]) -> Vec<f64> {
    let mut j = 0;
    grid.iter()
        .map(|&g| {
            while j + 2 < t.len() && t[j + 1] < g {
                j += 1;
            }
            let w = ((g - t[j]) / (t[j + 1] - t[j])).clamp(0.0, 1.0);
            v[j] + w * (v[j + 1] - v[j])
        })
        .collect()
}

/// A record must be a regular file of sane size.
fn check_data_file(path: &Path) -> Result<(), BundleError> {
    crate::files::check_input(path, crate::files::MAX_DATA_BYTES).map_err(|e| error(path, None, e.message))
}

/// Reads a bundle's TOML (a regular file of sane size).
fn read_toml(file: &Path) -> Result<String, BundleError> {
    crate::files::read_text(file).map_err(|e| error(file, None, e.message))
}

/// The data file a bundle names in `key`, relative to the bundle.
fn data_path(file: &Path, key: &str, name: &str) -> Result<PathBuf, BundleError> {
    if name.trim().is_empty() {
        return Err(error(
            file,
            None,
            format!("`{key}` is empty: expected the name of the CSV file, relative to this file"),
        ));
    }
    Ok(file.parent().unwrap_or(Path::new(".")).join(name))
}

/// Every sample of every column a measurement (no overflowed values or glitches orders of
/// magnitude off the rest): the error names the line and the column.
fn check_glitches(path: &Path, names: &[&str], cols: &[Vec<f64>]) -> Result<(), BundleError> {
    for (name, col) in names.iter().zip(cols).skip(1) {
        if let Some((i, why)) = ident::signal::implausible_sample(col) {
            return Err(error(path, Some(i + 2), format!("`{name}` = {why}")));
        }
    }
    Ok(())
}

/// A column that must vary for the analysis (an excitation, a response).
fn check_varies(path: &Path, name: &str, col: &[f64], why: &str) -> Result<(), BundleError> {
    match ident::signal::median_and_spread(col) {
        Some((_, spread)) if spread > 0.0 => Ok(()),
        _ => Err(error(
            path,
            None,
            format!("`{name}` does not vary (constant {}): {why}", col.first().copied().unwrap_or(0.0)),
        )),
    }
}

/// The sampling against what the analysis needs; names a time column written in milliseconds.
fn check_sampling(path: &Path, t: &[f64], dt_s: f64, needs: &ident::signal::SamplingNeeds) -> Result<(), BundleError> {
    if let Some(problem) = needs.problem(dt_s, t.len()) {
        let integral = t.iter().all(|v| v.fract() == 0.0);
        let hint = if integral && dt_s >= 0.5 {
            format!("`time_s` looks like milliseconds (step {dt_s} s): time must be in seconds; ")
        } else {
            String::new()
        };
        return Err(error(path, None, format!("{hint}{problem}")));
    }
    Ok(())
}

/// Reads a `torsional_sweep` bundle and its CSV.
pub fn load_torsional(file: &Path) -> Result<TorsionalBundle, BundleError> {
    let text = read_toml(file)?;
    let header: Header = toml::from_str(&text).map_err(|e| error(file, None, e.to_string().trim_end().to_string()))?;
    if header.kind != "torsional_sweep" {
        return Err(error(file, None, format!("`kind` = \"{}\": expected \"torsional_sweep\"", header.kind)));
    }
    let data = header.data.ok_or_else(|| error(file, None, "missing key `data`: the CSV file of the sweep"))?;
    if header.variant.is_none() {
        return Err(error(file, None, "missing key `variant`: the rig variant of the run (V1, V2, V3 or V4)"));
    }
    // the TOML is a rig description too: [model] and variant, validated with named keys
    let rig = parse_rig(&text, file).map_err(|e| error(file, None, e.message))?;
    let csv_path = data_path(file, "data", &data)?;
    // the declared model's modes must be resolved (`SamplingNeeds::torsional_sweep`)
    let modes = rig
        .model
        .open_differential(rig.variant)
        .and_then(|m| m.modes())
        .map_err(|e| error(file, None, e.to_string()))?;
    let needs = ident::signal::SamplingNeeds::torsional_sweep(&modes.frequencies_hz);
    let mut specs = fixed_columns(file, header.columns.as_ref(), &SWEEP_SIGNALS)?;
    let time = time_base(file, header.time.as_deref(), header.sample_rate_hz, header.resample, &mut specs)?;
    let (sweep, note) = read_sweep_csv(file, &csv_path, &mut specs, &time, needs.as_ref())?;
    let conversions: Vec<String> = conversions_of(&specs).into_iter().chain(note).collect();
    check_varies(
        &csv_path,
        "torque_drive_Nm",
        &sweep.torque_nm,
        "nothing excites the rig, so nothing can be identified",
    )?;
    Ok(TorsionalBundle { file: file.to_path_buf(), variant: rig.variant, model: rig.model, sweep, conversions })
}

/// The signals of a sweep (their CSV columns unless `[columns]` maps them) and what they measure.
pub const SWEEP_SIGNALS: [(&str, Dimension); 4] = [
    ("time_s", Dimension::Time),
    ("torque_drive_Nm", Dimension::Torque),
    ("speed_m2_radps", Dimension::AngularSpeed),
    ("speed_m3_radps", Dimension::AngularSpeed),
];

/// Most samples a record may have per channel: 10 million (2.8 h at 1 kHz). A diagnosis holds
/// about 90 bytes per sample and channel, so a four-channel record of this length needs about
/// 3.6 GB; a longer one is refused before it is read whole (cut it, or decimate it).
pub const MAX_SAMPLES: usize = 10_000_000;

/// The refusal of a record longer than [`MAX_SAMPLES`].
fn too_many_samples(path: &Path, n: impl std::fmt::Display) -> BundleError {
    error(
        path,
        None,
        format!("{n} samples per channel: rigtwin takes records of at most {MAX_SAMPLES} (cut the record to the part of interest, or decimate it)"),
    )
}

/// Longest line of a CSV record, bytes: a header of thousands of named columns fits; a file
/// without line breaks (or one long binary run) is refused after this many bytes, not held whole.
pub const MAX_CSV_LINE_BYTES: usize = 1 << 20;

/// A reader that fails on a line longer than [`MAX_CSV_LINE_BYTES`] or on a NUL byte (binary
/// data, not a text CSV), naming the line; so what the CSV parser holds stays one bounded line.
struct TextLines<R> {
    inner: R,
    line: usize,
    line_bytes: usize,
    /// The fault found in the last read, returned by the next (the good bytes before it first).
    fault: Option<String>,
}

impl<R> TextLines<R> {
    fn new(inner: R) -> Self {
        TextLines { inner, line: 1, line_bytes: 0, fault: None }
    }
}

impl<R: std::io::Read> std::io::Read for TextLines<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if let Some(fault) = self.fault.take() {
            return Err(std::io::Error::new(std::io::ErrorKind::InvalidData, fault));
        }
        let n = self.inner.read(buf)?;
        for (i, &b) in buf[..n].iter().enumerate() {
            if b == b'\n' {
                self.line += 1;
                self.line_bytes = 0;
                continue;
            }
            self.line_bytes += 1;
            let fault = if b == 0 {
                format!("line {}: a NUL byte: not a text CSV", self.line)
            } else if self.line_bytes > MAX_CSV_LINE_BYTES {
                format!(
                    "line {} is longer than {MAX_CSV_LINE_BYTES} bytes: not a CSV record (one line per sample)",
                    self.line
                )
            } else {
                continue;
            };
            // the good bytes before the fault first, the fault with the next read
            if i == 0 {
                return Err(std::io::Error::new(std::io::ErrorKind::InvalidData, fault));
            }
            self.fault = Some(fault);
            return Ok(i);
        }
        Ok(n)
    }
}

/// Reads named columns of a numeric CSV with a header line; returns them in the order asked.
/// A name that heads two columns is refused (which one is meant cannot be told).
pub fn read_columns(path: &Path, names: &[&str]) -> Result<Vec<Vec<f64>>, BundleError> {
    check_data_file(path)?;
    let file = std::fs::File::open(path).map_err(|e| error(path, None, format!("cannot read: {e}")))?;
    let text = TextLines::new(std::io::BufReader::new(file));
    let mut rdr = csv::ReaderBuilder::new().trim(csv::Trim::All).from_reader(text);
    let headers = rdr.headers().map_err(|e| error(path, Some(1), format!("cannot read the header: {e}")))?.clone();
    for n in names {
        let at: Vec<usize> = headers.iter().enumerate().filter(|(_, h)| h == n).map(|(i, _)| i + 1).collect();
        if at.len() > 1 {
            return Err(error(
                path,
                Some(1),
                format!("column `{n}` appears {} times (columns {at:?}): name each signal once", at.len()),
            ));
        }
    }
    let index: Vec<usize> = names
        .iter()
        .map(|n| {
            headers.iter().position(|h| h == *n).ok_or_else(|| {
                let line = headers.iter().collect::<Vec<_>>().join(",");
                let hint = match [';', '\t'].into_iter().find(|d| line.contains(*d)) {
                    Some(';') => " (the header is separated by semicolons: the file must be comma-separated)",
                    Some(_) => " (the header is separated by tabs: the file must be comma-separated)",
                    None => "",
                };
                error(path, Some(1), format!("missing column `{n}`: expected the columns {}{hint}", names.join(", ")))
            })
        })
        .collect::<Result<_, _>>()?;
    let mut cols = vec![Vec::new(); names.len()];
    for (row, rec) in rdr.records().enumerate() {
        if row >= MAX_SAMPLES {
            return Err(too_many_samples(path, format!("more than {MAX_SAMPLES}")));
        }
        let line = row + 2;
        let rec = rec.map_err(|e| match e.kind() {
            // the line reader's own message names its line
            csv::ErrorKind::Io(io) => error(path, None, io.to_string()),
            _ => error(path, Some(line), e.to_string()),
        })?;
        for (c, &i) in index.iter().enumerate() {
            let field =
                rec.get(i).ok_or_else(|| error(path, Some(line), format!("missing value of `{}`", names[c])))?;
            let v: f64 = field
                .parse()
                .map_err(|_| error(path, Some(line), format!("`{}`: expected a number, got `{field}`", names[c])))?;
            if !v.is_finite() {
                return Err(error(
                    path,
                    Some(line),
                    format!("`{}`: expected a finite number, got `{field}`", names[c]),
                ));
            }
            cols[c].push(v);
        }
    }
    if cols[0].len() < 2 {
        return Err(error(path, None, format!("{} data rows: a recording needs at least two", cols[0].len())));
    }
    Ok(cols)
}

/// Checks `time_s` is strictly increasing and uniform; returns the sample time.
pub fn uniform_sample_time(path: &Path, t: &[f64]) -> Result<f64, BundleError> {
    if t.len() < 2 {
        return Err(error(path, None, format!("{} samples: a recording needs at least two", t.len())));
    }
    // the median step is the reference: one bad row cannot move it
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(|a, b| a.total_cmp(b));
    let median = steps[steps.len() / 2];
    for (i, w) in t.windows(2).enumerate() {
        let d = w[1] - w[0];
        if d <= 0.0 {
            return Err(error(
                path,
                Some(i + 3),
                format!("`time_s` = {} is not after the previous {}: time must increase (or set `resample = true` in the bundle to drop such samples and resample)", w[1], w[0]),
            ));
        }
        // CSV values carry a rounding of the printed digits; 1 % of a step is far above that
        if (d - median).abs() > 0.01 * median {
            return Err(error(
                path,
                Some(i + 3),
                format!("`time_s` step {d} s differs from the typical step {median} s: sampling must be uniform (or set `resample = true` in the bundle to interpolate linearly onto a uniform grid)"),
            ));
        }
    }
    Ok((t[t.len() - 1] - t[0]) / (t.len() - 1) as f64)
}

fn read_sweep_csv(
    file: &Path,
    path: &Path,
    specs: &mut [SignalSpec],
    time: &TimeBase,
    needs: Option<&ident::signal::SamplingNeeds>,
) -> Result<(Sweep, Option<String>), BundleError> {
    let (mut cols, note) = read_signals(file, path, specs, time)?;
    let dt_s = uniform_sample_time(path, &cols[0])?;
    if let Some(needs) = needs {
        check_sampling(path, &cols[0], dt_s, needs)?;
    }
    let channels: Vec<&str> = specs.iter().map(|s| s.channel.as_str()).collect();
    check_glitches(path, &channels, &cols)?;
    let speed_m3_radps = cols.pop().expect("4 columns");
    let speed_m2_radps = cols.pop().expect("4 columns");
    let torque_nm = cols.pop().expect("4 columns");
    Ok((Sweep { dt_s, torque_nm, speed_m2_radps, speed_m3_radps }, note))
}

/// A `bearing_shake` bundle, loaded.
#[derive(Debug, Clone)]
pub struct BearingBundle {
    /// The TOML file.
    pub file: PathBuf,
    /// The two tests (x-excitation, y-excitation).
    pub tests: [ident::ShakeTest; 2],
    /// Excited band, Hz.
    pub band_hz: (f64, f64),
    /// Dry-system support.
    pub support: plant::Support,
    /// Declared element structure.
    pub structure: ident::Structure,
    /// Declared coupling.
    pub coupling: ident::Coupling,
    /// Unit conversions and calibrations applied to the recorded channels.
    pub conversions: Vec<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BearingFile {
    kind: String,
    tests: Vec<String>,
    f_min_hz: f64,
    f_max_hz: f64,
    support: plant::Support,
    model: BearingModelFile,
    columns: Option<std::collections::BTreeMap<String, ColumnFile>>,
    time: Option<String>,
    sample_rate_hz: Option<f64>,
    resample: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BearingModelFile {
    structure: ident::Structure,
    coupling: ident::Coupling,
}

/// The signals of a shake test (their CSV columns unless `[columns]` maps them) and what they
/// measure.
pub const SHAKE_SIGNALS: [(&str, Dimension); 5] = [
    ("time_s", Dimension::Time),
    ("force_x_N", Dimension::Force),
    ("force_y_N", Dimension::Force),
    ("disp_x_m", Dimension::Length),
    ("disp_y_m", Dimension::Length),
];

/// Reads a `bearing_shake` bundle and its two CSVs.
pub fn load_bearing(file: &Path) -> Result<BearingBundle, BundleError> {
    let text = read_toml(file)?;
    let header: Header = toml::from_str(&text).map_err(|e| error(file, None, e.to_string().trim_end().to_string()))?;
    if header.kind != "bearing_shake" {
        return Err(error(file, None, format!("`kind` = \"{}\": expected \"bearing_shake\"", header.kind)));
    }
    let raw: BearingFile =
        toml::from_str(&text).map_err(|e| error(file, None, e.to_string().trim_end().to_string()))?;
    debug_assert_eq!(raw.kind, "bearing_shake");
    if raw.tests.len() != 2 {
        return Err(error(
            file,
            None,
            format!("`tests` lists {} files: expected two (x then y excitation)", raw.tests.len()),
        ));
    }
    if !(raw.f_min_hz >= 0.0 && raw.f_max_hz > raw.f_min_hz) {
        return Err(error(
            file,
            None,
            format!("`f_min_hz` = {} and `f_max_hz` = {}: expected 0 ≤ f_min < f_max", raw.f_min_hz, raw.f_max_hz),
        ));
    }
    raw.support.validate("support").map_err(|e| error(file, None, e.to_string()))?;
    let paths = [data_path(file, "tests[0]", &raw.tests[0])?, data_path(file, "tests[1]", &raw.tests[1])?];
    if let (Ok(a), Ok(b)) = (std::fs::canonicalize(&paths[0]), std::fs::canonicalize(&paths[1])) {
        if a == b {
            return Err(error(
                file,
                None,
                format!(
                    "`tests` names {} twice: expected two different runs (x then y excitation)",
                    paths[0].display()
                ),
            ));
        }
    }
    // the band must be resolved (`SamplingNeeds::bearing_shake`)
    let needs = ident::signal::SamplingNeeds::bearing_shake(raw.f_min_hz, raw.f_max_hz);
    let mut specs = fixed_columns(file, raw.columns.as_ref(), &SHAKE_SIGNALS)?;
    let time = time_base(file, raw.time.as_deref(), raw.sample_rate_hz, raw.resample, &mut specs)?;
    let mut notes = Vec::new();
    let mut read = |path: &Path| -> Result<ident::ShakeTest, BundleError> {
        let path = path.to_path_buf();
        let (mut cols, note) = read_signals(file, &path, &mut specs, &time)?;
        notes.extend(note);
        let channels: Vec<&str> = specs.iter().map(|s| s.channel.as_str()).collect();
        let dt_s = uniform_sample_time(&path, &cols[0])?;
        check_glitches(&path, &channels, &cols)?;
        check_sampling(&path, &cols[0], dt_s, &needs).map_err(|mut e| {
            e.message = format!("{} (f_min_hz = {}, f_max_hz = {})", e.message, raw.f_min_hz, raw.f_max_hz);
            e
        })?;
        for (name, col) in channels.iter().zip(&cols).skip(1) {
            check_varies(&path, name, col, "each test must excite and move the element")?;
        }
        let disp_y_m = cols.pop().expect("5 columns");
        let disp_x_m = cols.pop().expect("5 columns");
        let force_y_n = cols.pop().expect("5 columns");
        let force_x_n = cols.pop().expect("5 columns");
        Ok(ident::ShakeTest { dt_s, force_x_n, force_y_n, disp_x_m, disp_y_m })
    };
    let tests = [read(&paths[0])?, read(&paths[1])?];
    Ok(BearingBundle {
        file: file.to_path_buf(),
        tests,
        conversions: conversions_of(&specs).into_iter().chain(notes).collect(),
        band_hz: (raw.f_min_hz, raw.f_max_hz),
        support: raw.support,
        structure: raw.model.structure,
        coupling: raw.model.coupling,
    })
}

/// A measured signal of a `drive_test` bundle: its CSV column, where it acts or is measured
/// (0-based body, or coupling for coupling forces) and, for outputs, what it is.
#[derive(Debug, Clone, PartialEq)]
pub struct DriveSignal {
    /// CSV column.
    pub column: String,
    /// 0-based body (inputs, positions, speeds) or coupling (coupling forces).
    pub at: usize,
    /// What an output measures (None for inputs).
    pub quantity: Option<plant::Quantity>,
}

/// A `drive_test` bundle (`../shared/DATA.md`), loaded: any line of bodies, its measured inputs
/// and outputs.
#[derive(Debug, Clone)]
pub struct DriveTestBundle {
    /// The TOML file.
    pub file: PathBuf,
    /// The declared model: its line and the bodies its inputs act on (`modelfile`'s reading of
    /// the same text, no effects).
    pub model: plant::DriveModel,
    /// Its `[mpc]` section (empty when it has none).
    pub mpc: mpc::MpcSection,
    /// Free text of the bundle.
    pub description: Option<String>,
    /// Forces (torques) on bodies.
    pub inputs: Vec<DriveSignal>,
    /// Measured outputs.
    pub outputs: Vec<DriveSignal>,
    /// Sample time, s.
    pub dt_s: f64,
    /// The inputs' samples, one vector per input.
    pub input_data: Vec<Vec<f64>>,
    /// The outputs' samples, one vector per output.
    pub output_data: Vec<Vec<f64>>,
    /// Unit conversions and calibrations applied to the recorded channels.
    pub conversions: Vec<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DriveFile {
    // read through `Header`; listed so that deny_unknown_fields accepts it
    #[serde(rename = "kind")]
    _kind: String,
    data: String,
    domain: plant::Domain,
    description: Option<String>,
    /// The declared model, read by `modelfile::parse`.
    #[allow(dead_code)]
    model: toml::Value,
    time: Option<String>,
    sample_rate_hz: Option<f64>,
    resample: Option<bool>,
    #[serde(default)]
    inputs: Vec<DriveInputFile>,
    #[serde(default)]
    outputs: Vec<DriveOutputFile>,
    /// The controller's section, read by `modelfile::parse`.
    #[allow(dead_code)]
    mpc: Option<toml::Value>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DriveInputFile {
    column: String,
    /// The body it acts on, read by `modelfile::parse`.
    #[allow(dead_code)]
    body: toml::Value,
    unit: Option<String>,
    #[serde(default = "unit_gain")]
    gain: f64,
    #[serde(default)]
    offset: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DriveOutputFile {
    column: String,
    body: Option<BodyRef>,
    coupling: Option<i64>,
    quantity: String,
    unit: Option<String>,
    #[serde(default = "unit_gain")]
    gain: f64,
    #[serde(default)]
    offset: f64,
}

/// Most measured outputs a `drive_test` may have (a speed and a force or torque at every body of
/// the largest line).
pub const MAX_OUTPUTS: usize = 2 * plant::MAX_BODIES;

/// Reads a `drive_test` bundle and its CSV: the line validated with named keys, every input and
/// output resolved to its body or coupling, the columns read and checked as for the other kinds.
pub fn load_drive_test(file: &Path) -> Result<DriveTestBundle, BundleError> {
    drive_test_of(&read_toml(file)?, file)
}

/// The `drive_test` bundle whose TOML `file` holds `text` (see [`load_drive_test`]).
pub fn drive_test_of(text: &str, file: &Path) -> Result<DriveTestBundle, BundleError> {
    let header: Header = toml::from_str(text).map_err(|e| error(file, None, e.to_string().trim_end().to_string()))?;
    if header.kind != "drive_test" {
        return Err(error(file, None, format!("`kind` = \"{}\": expected \"drive_test\"", header.kind)));
    }
    let raw: DriveFile = toml::from_str(text).map_err(|e| error(file, None, e.to_string().trim_end().to_string()))?;
    // the declared model and its [mpc] section as every model file is read
    let (model, mpc) = match modelfile::parse(text, file).map_err(|e| error(file, None, e.message))? {
        modelfile::ModelFile { model: modelfile::Model::Drive(m), mpc, .. } => (m, mpc),
        _ => return Err(error(file, None, "expected a drive line's [model]")),
    };
    let line = &model.line;
    let n = line.bodies.len();
    let nc = line.couplings.len();
    let body = |r: &BodyRef, key: &str| -> Result<usize, BundleError> {
        match r {
            BodyRef::Name(name) => line.body(name).ok_or_else(|| {
                let names: Vec<&str> = line.bodies.iter().map(|b| b.name.as_str()).collect();
                error(file, None, format!("`{key}` = \"{name}\": no such body (the bodies are {})", names.join(", ")))
            }),
            BodyRef::Position(p) if (1..=n as i64).contains(p) => Ok(*p as usize - 1),
            BodyRef::Position(p) => {
                Err(error(file, None, format!("`{key}` = {p}: expected a body's name or a position from 1 to {n}")))
            }
        }
    };
    if raw.inputs.is_empty() || raw.outputs.is_empty() {
        return Err(error(file, None, "expected at least one [[inputs]] and one [[outputs]] entry"));
    }
    if raw.inputs.len() > plant::drive::MAX_INPUTS || raw.outputs.len() > MAX_OUTPUTS {
        return Err(error(
            file,
            None,
            format!(
                "{} [[inputs]] and {} [[outputs]]: a drive test takes at most {} inputs and {MAX_OUTPUTS} outputs",
                raw.inputs.len(),
                raw.outputs.len(),
                plant::drive::MAX_INPUTS
            ),
        ));
    }
    let inputs: Vec<DriveSignal> = raw
        .inputs
        .iter()
        .zip(&model.inputs)
        .map(|(i, &at)| DriveSignal { column: i.column.clone(), at, quantity: None })
        .collect();
    let mut outputs = Vec::new();
    for (k, o) in raw.outputs.iter().enumerate() {
        let key = |f: &str| format!("outputs[{}].{f}", k + 1);
        let quantity = match o.quantity.as_str() {
            "angle" | "position" => plant::Quantity::Position,
            "speed" => plant::Quantity::Speed,
            "coupling_torque" | "coupling_force" => plant::Quantity::CouplingForce,
            other => {
                return Err(error(
                    file,
                    None,
                    format!("`{}` = \"{other}\": expected \"angle\" (\"position\"), \"speed\" or \"coupling_torque\" (\"coupling_force\")", key("quantity")),
                ))
            }
        };
        let at = match (quantity, &o.body, o.coupling) {
            (plant::Quantity::CouplingForce, None, Some(c)) if (1..=nc as i64).contains(&c) => c as usize - 1,
            (plant::Quantity::CouplingForce, None, Some(c)) => {
                return Err(error(
                    file,
                    None,
                    format!("`{}` = {c}: expected a coupling from 1 to {nc}", key("coupling")),
                ))
            }
            (plant::Quantity::CouplingForce, _, _) => {
                return Err(error(
                    file,
                    None,
                    format!("`{}`: a coupling force names `coupling = k` (1-based), not `body`", key("quantity")),
                ))
            }
            (_, Some(b), None) => body(b, &key("body"))?,
            _ => {
                return Err(error(
                    file,
                    None,
                    format!("`{}`: an angle, position or speed names `body`, not `coupling`", key("quantity")),
                ))
            }
        };
        outputs.push(DriveSignal { column: o.column.clone(), at, quantity: Some(quantity) });
    }
    let columns: Vec<&str> = inputs.iter().chain(&outputs).map(|s| s.column.as_str()).collect();
    if let Some((_, c)) = columns.iter().enumerate().find(|(k, c)| columns[..*k].contains(c) || **c == "time_s") {
        return Err(error(
            file,
            None,
            format!("column `{c}` is named twice (or is the time): each signal needs its own column"),
        ));
    }
    let csv_path = data_path(file, "data", &raw.data)?;
    let rotational = raw.domain == plant::Domain::Rotational;
    let dimension_of = |q: Option<plant::Quantity>| match (q, rotational) {
        (None | Some(plant::Quantity::CouplingForce), true) => Dimension::Torque,
        (None | Some(plant::Quantity::CouplingForce), false) => Dimension::Force,
        (Some(plant::Quantity::Position), true) => Dimension::Angle,
        (Some(plant::Quantity::Position), false) => Dimension::Length,
        (Some(plant::Quantity::Speed), true) => Dimension::AngularSpeed,
        (Some(plant::Quantity::Speed), false) => Dimension::Speed,
    };
    let calibrations = raw
        .inputs
        .iter()
        .map(|i| (&i.unit, i.gain, i.offset))
        .chain(raw.outputs.iter().map(|o| (&o.unit, o.gain, o.offset)));
    let keys = (1..=raw.inputs.len())
        .map(|k| format!("inputs[{k}]"))
        .chain((1..=raw.outputs.len()).map(|k| format!("outputs[{k}]")));
    let mut specs = vec![SignalSpec {
        name: "time_s".into(),
        channel: "time_s".into(),
        dimension: Dimension::Time,
        calibration: Calibration::default(),
        key: "time_s".into(),
    }];
    for ((s, (unit, gain, offset)), key) in inputs.iter().chain(&outputs).zip(calibrations).zip(keys) {
        specs.push(SignalSpec {
            name: s.column.clone(),
            channel: s.column.clone(),
            dimension: dimension_of(s.quantity),
            calibration: Calibration { unit: unit.clone(), gain, offset },
            key,
        });
    }
    let time = time_base(file, raw.time.as_deref(), raw.sample_rate_hz, raw.resample, &mut specs)?;
    let (mut cols, note) = read_signals(file, &csv_path, &mut specs, &time)?;
    let names: Vec<&str> = specs.iter().map(|s| s.channel.as_str()).collect();
    let dt_s = uniform_sample_time(&csv_path, &cols[0])?;
    check_glitches(&csv_path, &names, &cols)?;
    // the line's slowest flexible mode must be resolved (`SamplingNeeds::drive_test`)
    let modes = line.model().and_then(|m| m.modes()).map_err(|e| error(file, None, e.to_string()))?;
    if let Some(needs) = ident::signal::SamplingNeeds::drive_test(&modes.frequencies_hz) {
        check_sampling(&csv_path, &cols[0], dt_s, &needs)?;
    }
    let output_data = cols.split_off(1 + inputs.len());
    let input_data = cols.split_off(1);
    for (s, data) in inputs.iter().zip(&input_data) {
        check_varies(&csv_path, &s.column, data, "nothing excites the drive, so nothing can be identified")?;
    }
    Ok(DriveTestBundle {
        file: file.to_path_buf(),
        model,
        mpc,
        description: raw.description,
        inputs,
        outputs,
        dt_s,
        input_data,
        output_data,
        conversions: conversions_of(&specs).into_iter().chain(note).collect(),
    })
}

/// Reads the variables `names` of a MATLAB `.mat` file (v5 or v7, compressed or not) as
/// vectors, converted to f64 from any real numeric class. v7.3 files (HDF5) are refused with
/// the fix; a file the reader cannot parse — or on which it panics — is an error naming it.
pub fn read_mat(path: &Path, names: &[&str]) -> Result<Vec<Vec<f64>>, BundleError> {
    check_data_file(path)?;
    let bytes = std::fs::read(path).map_err(|e| error(path, None, format!("cannot read: {e}")))?;
    if bytes.starts_with(b"MATLAB 7.3 MAT-file") || bytes.get(512..520) == Some(b"\x89HDF\r\n\x1a\n") {
        return Err(error(
            path,
            None,
            "a MATLAB v7.3 (HDF5) file: rigtwin reads v5 and v7 .mat files; save it with save(file, '-v7')",
        ));
    }
    if !bytes.starts_with(b"MATLAB 5.0 MAT-file") || bytes.len() < 128 {
        return Err(error(
            path,
            None,
            "not a MATLAB v5/v7 .mat file (its header does not say \"MATLAB 5.0 MAT-file\")",
        ));
    }
    // The first 116 bytes are descriptive text; matrw wants MATLAB's own wording
    // ("MATLAB 5.0 MAT-file, Platform: …") where scipy writes "MATLAB 5.0 MAT-file Platform: …".
    let mut bytes = bytes;
    let text = b"MATLAB 5.0 MAT-file, written by another tool";
    bytes[..text.len()].copy_from_slice(text);
    bytes[text.len()..116].fill(b' ');
    // the parser unwraps in places (a corrupt zlib stream): a panic on a hostile file is
    // contained and reported as the file's error, and the default hook's message kept quiet
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let parsed = std::panic::catch_unwind(|| matrw::load_matfile_from_u8(&bytes));
    std::panic::set_hook(hook);
    let mat = match parsed {
        Ok(Ok(m)) => m,
        Ok(Err(e)) => return Err(error(path, None, format!("cannot parse the .mat file: {}", parser_message(&e)))),
        Err(_) => return Err(error(path, None, "cannot parse the .mat file (the reader failed on its contents)")),
    };
    let available: Vec<String> = mat.iter().map(|(k, _)| k.clone()).collect();
    let mut out: Vec<Vec<f64>> = Vec::with_capacity(names.len());
    for name in names {
        let Some((_, var)) = mat.iter().find(|(k, _)| k.as_str() == *name) else {
            return Err(error(path, None, format!("no variable `{name}` (the file has {})", available.join(", "))));
        };
        let dims = var.dim();
        if dims.iter().filter(|&&d| d > 1).count() > 1 {
            return Err(error(
                path,
                None,
                format!("variable `{name}` is a {dims:?} array: expected a row or column vector"),
            ));
        }
        if var.is_complex() == Some(true) {
            return Err(error(
                path,
                None,
                format!("variable `{name}` is complex: a measured signal is real (save its real part, or abs(), as the signal)"),
            ));
        }
        let values: Option<Vec<f64>> = var
            .to_vec::<f64>()
            .or_else(|| var.to_vec::<f32>().map(|v| v.into_iter().map(f64::from).collect()))
            .or_else(|| var.to_vec::<i32>().map(|v| v.into_iter().map(f64::from).collect()))
            .or_else(|| var.to_vec::<i16>().map(|v| v.into_iter().map(f64::from).collect()))
            .or_else(|| var.to_vec::<u16>().map(|v| v.into_iter().map(f64::from).collect()))
            .or_else(|| var.to_vec::<i8>().map(|v| v.into_iter().map(f64::from).collect()))
            .or_else(|| var.to_vec::<u8>().map(|v| v.into_iter().map(f64::from).collect()))
            .or_else(|| var.to_vec::<u32>().map(|v| v.into_iter().map(f64::from).collect()))
            .or_else(|| var.to_vec::<i64>().map(|v| v.into_iter().map(|x| x as f64).collect()))
            .or_else(|| var.to_vec::<u64>().map(|v| v.into_iter().map(|x| x as f64).collect()));
        let Some(values) = values else {
            return Err(error(path, None, format!("variable `{name}` is not a real numeric array")));
        };
        if values.len() > MAX_SAMPLES {
            return Err(too_many_samples(path, values.len()));
        }
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(error(
                path,
                None,
                format!("variable `{name}`, sample {}: {} is not a finite number", k + 1, values[k]),
            ));
        }
        if let Some(first) = out.first() {
            if first.len() != values.len() {
                return Err(error(
                    path,
                    None,
                    format!(
                        "variable `{name}` has {} samples, `{}` has {}: the signals must have one length",
                        values.len(),
                        names[0],
                        first.len()
                    ),
                ));
            }
        }
        out.push(values);
    }
    if out.first().map_or(0, |c| c.len()) < 2 {
        return Err(error(path, None, "fewer than two samples: a recording needs at least two"));
    }
    Ok(out)
}

/// A third-party parser's error as one plain line: its first line, terminal colour codes and
/// control characters removed, at most 200 characters (some parsers print a backtrace with the
/// build machine's paths in their `Display`).
fn parser_message(e: &dyn std::fmt::Display) -> String {
    let text = e.to_string();
    let mut plain = String::new();
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            // an ANSI escape: ESC [ parameters final-letter
            if chars.peek() == Some(&'[') {
                chars.next();
                for p in chars.by_ref() {
                    if p.is_ascii_alphabetic() {
                        break;
                    }
                }
            }
        } else if c == '\n' {
            break;
        } else if !c.is_control() {
            plain.push(c);
        }
    }
    let plain = plain.trim();
    match plain.char_indices().nth(200) {
        Some((i, _)) => format!("{}…", &plain[..i]),
        None => plain.to_string(),
    }
}

/// Channels of an MDF 4 file (`.mf4`, `.mdf`), read with falcon_mdf: each channel's values
/// (converted by the file's own conversion rules), its unit, and its group's master time.
struct MdfChannels {
    values: Vec<Vec<f64>>,
    units: Vec<String>,
    /// per channel its group's master time; an empty vector stands for the first channel's
    /// times (same group), so one group's time base is held once
    times: Vec<Vec<f64>>,
}

/// Records decoded per window when streaming a channel group: the group's record buffer is
/// never assembled whole, so memory is the selected channels' values plus one window.
const MDF_WINDOW_RECORDS: usize = 1 << 16;

fn read_mdf_channels(path: &Path, names: &[&str]) -> Result<MdfChannels, BundleError> {
    check_data_file(path)?;
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let result = std::panic::catch_unwind(|| -> Result<MdfChannels, BundleError> {
        let f = falcon_mdf::Mf4File::open_buffered(path)
            .map_err(|e| error(path, None, format!("not a readable MDF 4 file: {}", parser_message(&e))))?;
        let mut channels = Vec::with_capacity(names.len());
        for name in names {
            channels.push(
                f.find_channel(name).ok_or_else(|| error(path, None, format!("no channel `{name}` in the file")))?,
            );
        }
        let group_of = |i: usize| (channels[i].data_group_index, channels[i].channel_group_index);
        let n = names.len();
        let mut out =
            MdfChannels { values: vec![Vec::new(); n], units: vec![String::new(); n], times: vec![Vec::new(); n] };
        let mut done = vec![false; n];
        let file_size = usize::try_from(f.file_size()).unwrap_or(usize::MAX);
        for lead in 0..n {
            if done[lead] {
                continue;
            }
            // one pass over the group's records: its selected channels and its master together
            let members: Vec<usize> = (lead..n).filter(|&i| group_of(i) == group_of(lead)).collect();
            let (dg, cg) = group_of(lead);
            let group = &f.data_groups()[dg].channel_groups[cg];
            let master = group.master_channel();
            if group.sample_count > MAX_SAMPLES as u64 {
                return Err(too_many_samples(path, group.sample_count));
            }
            let record_bytes = group.record_size(0) as u64;
            if record_bytes > f.file_size() {
                return Err(error(
                    path,
                    None,
                    format!(
                        "channel `{}`: its group declares records of {record_bytes} bytes in a file of {} bytes: the file is corrupt",
                        names[lead],
                        f.file_size()
                    ),
                ));
            }
            let mut read: Vec<&falcon_mdf::model::Channel> = members.iter().map(|&i| channels[i]).collect();
            read.extend(master);
            // the declared count is only a capacity hint, bounded by what the file can hold
            let hint =
                usize::try_from(group.sample_count).unwrap_or(usize::MAX).min(file_size / group.record_size(0).max(1));
            let mut values: Vec<Vec<f64>> = read.iter().map(|_| Vec::with_capacity(hint)).collect();
            let failed = |k: usize, e: falcon_mdf::error::Mf4Error| {
                let name = members.get(k).map_or("its master (time)", |&i| names[i]);
                error(path, None, format!("channel `{name}`: {}", parser_message(&e)))
            };
            for window in f.signals_chunks(&read, MDF_WINDOW_RECORDS).map_err(|e| failed(0, e))? {
                let window = window.map_err(|e| failed(0, e))?;
                for (k, (sig, v)) in window.iter().zip(values.iter_mut()).enumerate() {
                    v.extend_from_slice(&sig.values_f64().map_err(|e| failed(k, e))?);
                }
            }
            let time: Vec<f64> = match master {
                Some(_) => values.pop().unwrap_or_default(),
                None => (0..values.first().map_or(0, Vec::len)).map(|k| k as f64).collect(),
            };
            if time.len() < 2 {
                return Err(error(
                    path,
                    None,
                    format!("channel `{}`: {} samples: a recording needs at least two", names[lead], time.len()),
                ));
            }
            for (&i, v) in members.iter().zip(values) {
                if v.len() != time.len() {
                    return Err(error(
                        path,
                        None,
                        format!("channel `{}`: {} values for {} time stamps", names[i], v.len(), time.len()),
                    ));
                }
                out.units[i] = channels[i].unit.clone();
                out.values[i] = v;
                done[i] = true;
            }
            if lead == 0 {
                out.times[0] = time;
            } else {
                // another group than the first channel's: each of its channels carries the times
                for &i in &members {
                    out.times[i] = time.clone();
                }
            }
        }
        Ok(out)
    });
    std::panic::set_hook(hook);
    match result {
        Ok(r) => r,
        Err(_) => Err(error(path, None, "cannot read the MDF file (the reader failed on its contents)")),
    }
}

/// Signals of different channel groups on one uniform time base: the finest group's step over
/// the interval all groups cover, each signal linearly interpolated. Returns the time base and
/// the note for the report.
fn common_time_base(
    path: &Path,
    names: &[&str],
    times: &mut [Vec<f64>],
    values: &mut [Vec<f64>],
) -> Result<(Vec<f64>, Option<String>), BundleError> {
    if times[1..].iter().all(|t| t.is_empty() || *t == times[0]) {
        return Ok((std::mem::take(&mut times[0]), None));
    }
    let first = times[0].clone();
    for t in times[1..].iter_mut().filter(|t| t.is_empty()) {
        *t = first.clone();
    }
    let mut dt = f64::INFINITY;
    let (mut start, mut end) = (f64::NEG_INFINITY, f64::INFINITY);
    for (t, name) in times.iter().zip(names) {
        let not_increasing = |w: &[f64]| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater);
        if t.len() < 2 || t.windows(2).any(not_increasing) {
            let k = t.windows(2).position(not_increasing).map_or(0, |k| k + 1);
            return Err(error(
                path,
                None,
                format!("channel `{name}`: its time stamps do not increase (sample {})", k + 1),
            ));
        }
        let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        steps.sort_by(|a, b| a.total_cmp(b));
        dt = dt.min(steps[steps.len() / 2]);
        start = start.max(t[0]);
        end = end.min(t[t.len() - 1]);
    }
    let n = ((end - start) / dt + 1e-9).floor() + 1.0;
    if !(2.0..=1e9).contains(&n) {
        return Err(error(
            path,
            None,
            format!("the channels share no common interval long enough to resample ({start} s to {end} s)"),
        ));
    }
    let grid: Vec<f64> = (0..n as usize).map(|k| start + k as f64 * dt).collect();
    for (v, t) in values.iter_mut().zip(times.iter()) {
        *v = interpolate(t, v, &grid);
    }
    let note = format!(
        "channels of different groups resampled by linear interpolation onto {:.6} Hz over {start} s to {} s",
        1.0 / dt,
        grid[grid.len() - 1]
    );
    Ok((grid, Some(note)))
}

/// The `kind` of the bundle `file` (torsional_sweep, bearing_shake, drive_test), read before
/// the bundle itself.
pub fn kind_of(file: &Path) -> Result<String, BundleError> {
    #[derive(Deserialize)]
    struct Kind {
        kind: Option<String>,
    }
    let text = read_toml(file)?;
    let k: Kind = toml::from_str(&text).map_err(|e| error(file, None, e.to_string().trim_end().to_string()))?;
    k.kind.ok_or_else(|| error(file, None, "missing key `kind` (torsional_sweep, bearing_shake or drive_test)"))
}

/// What `rigtwin check` prints: the bundle read and validated as a diagnosis would read it —
/// its kind, samples, sample time, signals and the conversions applied.
pub fn summary(file: &Path) -> anyhow::Result<String> {
    let (kind, samples, dt_s, signals, conversions): (&str, usize, f64, Vec<String>, Vec<String>) =
        match kind_of(file)?.as_str() {
            "torsional_sweep" => {
                let b = load_torsional(file)?;
                let names = SWEEP_SIGNALS.iter().map(|(n, _)| n.to_string()).collect();
                ("torsional_sweep", b.sweep.torque_nm.len(), b.sweep.dt_s, names, b.conversions)
            }
            "bearing_shake" => {
                let b = load_bearing(file)?;
                let names = SHAKE_SIGNALS.iter().map(|(n, _)| n.to_string()).collect();
                ("bearing_shake", b.tests[0].force_x_n.len(), b.tests[0].dt_s, names, b.conversions)
            }
            "drive_test" => {
                let b = load_drive_test(file)?;
                let names = b
                    .inputs
                    .iter()
                    .map(|s| format!("input {} on body {}", s.column, b.model.line.bodies[s.at].name))
                    .chain(b.outputs.iter().map(|s| {
                        format!(
                            "output {} ({} at {})",
                            s.column,
                            crate::report::words(&s.quantity.unwrap_or(plant::Quantity::Speed)),
                            match s.quantity {
                                Some(plant::Quantity::CouplingForce) => format!("coupling {}", s.at + 1),
                                _ => format!("body {}", b.model.line.bodies[s.at].name),
                            }
                        )
                    }))
                    .collect();
                ("drive_test", b.input_data[0].len(), b.dt_s, names, b.conversions)
            }
            other => anyhow::bail!(
                "{}: `kind` = \"{other}\": expected torsional_sweep, bearing_shake or drive_test",
                file.display()
            ),
        };
    let mut s = format!(
        "{}: {kind}, {samples} samples at {dt_s} s ({:.3} Hz), {:.3} s\n",
        file.display(),
        1.0 / dt_s,
        samples as f64 * dt_s
    );
    for n in signals {
        s += &format!("  signal: {n}\n");
    }
    for c in conversions {
        s += &format!("  converted: {c}\n");
    }
    Ok(s)
}
