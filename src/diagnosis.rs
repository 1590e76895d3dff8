//! `rigtwin diagnose`: the declared model of a bundle against its measurement, the effect it
//! lacks, the extended model and the error before and after.

use std::collections::BTreeMap;
use std::path::Path;

use ident::diagnose::CandidateScore;
use serde::Serialize;

use crate::bundle::{load_bearing, load_torsional};

/// The report (the JSON contract's keys first).
#[derive(Debug, Clone, Serialize)]
pub struct DiagnosisReport {
    /// The answer in one word: `explained`, `declared_model_fits` or `not_explained`
    /// (`ident::diagnose::verdict`); `not_explained` exits with code 3.
    pub verdict: ident::diagnose::verdict::Verdict,
    /// Why the verdict is not `explained` where a candidate was chosen: each parameter at or
    /// beyond its physical bound.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub verdict_reasons: Vec<String>,
    /// The chosen effect (with `not_explained`: the best candidate, not a finding).
    pub effect: String,
    /// Where it acts (`drive_test`: "body load", "coupling 2", "input 1").
    #[serde(skip_serializing_if = "Option::is_none")]
    pub at: Option<String>,
    /// Its fitted parameters (SI; the declared ones re-fitted beside them).
    pub parameters: BTreeMap<String, f64>,
    /// 95 % intervals of `parameters`: their spread over the answer fitted without each
    /// held-out fold (`ident::diagnose::jackknife_interval`; `torsional_sweep`, `drive_test`).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub intervals: BTreeMap<String, [f64; 2]>,
    /// Keys of `parameters` whose interval spans more than
    /// `ident::diagnose::HeldOutSettings::determined_within` either way: the record does not
    /// determine them (the text says so in place of the value; each effect's are in `effects`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub not_determined: Vec<String>,
    /// The answer on the folds of the record its fit did not see (`torsional_sweep`,
    /// `drive_test`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub held_out: Option<ident::diagnose::HeldOut>,
    /// Other solutions that fit as well as `parameters` (BIC within
    /// `ident::diagnose::torsional::EQUIVALENT_BIC`), each with its error: when there are any,
    /// the record does not determine the parameters.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub equivalents: Vec<BTreeMap<String, f64>>,
    /// Every effect found, in the order found (`torsional_sweep`: forward selection; the first
    /// is `effect`/`parameters`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub effects: Vec<ident::diagnose::torsional::FoundEffect>,
    /// The answer's path: declared (re-fitted) → +A → +A+B, with the error and score of each.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub path: Vec<ident::diagnose::torsional::PathStep>,
    /// What the search did, where it differs from `path` (effects left out or swapped).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub search: Vec<ident::diagnose::torsional::PathStep>,
    /// Error of the declared model.
    pub error_before: f64,
    /// Error of the extended model.
    pub error_after: f64,
    /// Every candidate, best score first.
    pub candidates: Vec<CandidateScore>,
    /// `torsional_sweep`, `bearing_shake` or `drive_test`.
    pub kind: String,
    /// How the error is defined.
    pub error_definition: String,
    /// The best model still leaves a structured residual.
    pub structured_residual: bool,
    /// What the residual showed.
    pub evidence: serde_json::Value,
    /// Remarks.
    pub notes: Vec<String>,
    /// Unit conversions and sensor calibrations applied to the recorded channels.
    pub conversions: Vec<String>,
}

/// The diagnosis with what is needed to plot it and write the model.
pub struct Diagnosis {
    /// The report.
    pub report: DiagnosisReport,
    /// The extended model as a rig file (TOML).
    pub model_toml: String,
    /// Plot panels.
    pub panels: Vec<crate::plot::Panel>,
    /// The measured and simulated signals, for `--save-signals`.
    pub signals: Signals,
}

/// What `--save-signals` writes: the measured outputs, the declared and the extended model's
/// outputs and the residual on one base (time for a sweep, frequency lines for a shake test).
pub enum Signals {
    /// A sweep: the load machines' speeds, high-passed as the error is.
    Time(ident::diagnose::torsional::Traces),
    /// A drive test: every measured output (its CSV name), high-passed as the error is.
    Outputs {
        /// The outputs' column names.
        names: Vec<String>,
        /// The signals.
        traces: ident::diagnose::drive::DriveTraces,
    },
    /// A shake test: one row per excited line, the header naming the columns.
    Lines {
        /// Column names with units.
        header: Vec<String>,
        /// One row per line.
        rows: Vec<Vec<f64>>,
    },
}

impl Diagnosis {
    /// The signals as CSV (header line, then one row per sample or line).
    pub fn signals_csv(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        match &self.signals {
            Signals::Time(t) => {
                let mut header = vec!["time_s".to_string()];
                for m in ["m2", "m3"] {
                    for what in ["measured", "declared", "extended", "residual_declared", "residual_extended"] {
                        header.push(format!("speed_{m}_{what}_radps"));
                    }
                }
                let _ = writeln!(s, "{}", header.join(","));
                for k in 0..t.time_s.len() {
                    let _ = write!(s, "{:.9e}", t.time_s[k]);
                    for c in 0..2 {
                        let (m, b, a) = (t.measured[c][k], t.before[c][k], t.after[c][k]);
                        let _ = write!(s, ",{m:.9e},{b:.9e},{a:.9e},{:.9e},{:.9e}", m - b, m - a);
                    }
                    s.push('\n');
                }
            }
            Signals::Outputs { names, traces: t } => {
                let mut header = vec!["time_s".to_string()];
                for name in names {
                    for what in ["measured", "declared", "extended", "residual_declared", "residual_extended"] {
                        header.push(format!("{name}__{what}"));
                    }
                }
                let _ = writeln!(s, "{}", header.join(","));
                for k in 0..t.time_s.len() {
                    let _ = write!(s, "{:.9e}", t.time_s[k]);
                    for c in 0..t.measured.len() {
                        let (m, b, a) = (t.measured[c][k], t.before[c][k], t.after[c][k]);
                        let _ = write!(s, ",{m:.9e},{b:.9e},{a:.9e},{:.9e},{:.9e}", m - b, m - a);
                    }
                    s.push('\n');
                }
            }
            Signals::Lines { header, rows } => {
                let _ = writeln!(s, "{}", header.join(","));
                for r in rows {
                    let cells: Vec<String> = r.iter().map(|v| format!("{v:.9e}")).collect();
                    let _ = writeln!(s, "{}", cells.join(","));
                }
            }
        }
        s
    }
}

/// Diagnoses the bundle `file`, a `drive_test` bundle's search widened by `search`; `progress` is
/// told each candidate as it is fitted.
pub fn diagnose(
    file: &Path,
    progress: &(dyn Fn(&str) + Sync),
    search: &ident::diagnose::drive::SearchSettings,
) -> anyhow::Result<Diagnosis> {
    match crate::bundle::kind_of(file)?.as_str() {
        "torsional_sweep" => torsional(file, progress),
        "bearing_shake" => bearing(file, progress),
        "drive_test" => drive(file, progress, search),
        other => anyhow::bail!(
            "{}: `kind` = \"{other}\": expected torsional_sweep, bearing_shake or drive_test",
            file.display()
        ),
    }
}

fn spectrum(x: &[f64], dt: f64, f_max: f64) -> Vec<(f64, f64)> {
    let s = ident::signal::rfft(x);
    let n = x.len();
    let df = 1.0 / (n as f64 * dt);
    // Average neighbouring lines into ~0.25 Hz bins to keep the plot readable.
    let bin = ((0.25 / df).round() as usize).max(1);
    s.chunks(bin)
        .enumerate()
        .map(|(i, c)| {
            (
                (i * bin) as f64 * df,
                (c.iter().map(|v| v.norm_sqr()).sum::<f64>() / c.len() as f64).sqrt() * 2.0 / n as f64,
            )
        })
        .take_while(|(f, _)| *f <= f_max)
        .collect()
}

/// Where `residual` is largest: a window of `width_s` around its largest magnitude (within the
/// record), for a panel that shows the waveforms sample by sample.
fn zoom_range(residual: &[f64], dt: f64, width_s: f64) -> std::ops::Range<usize> {
    let n = residual.len();
    let peak = residual.iter().enumerate().max_by(|a, b| a.1.abs().total_cmp(&b.1.abs())).map_or(0, |(k, _)| k);
    let half = ((0.5 * width_s / dt).round() as usize).clamp(10, n.max(20) / 2);
    let start = peak.saturating_sub(half).min(n.saturating_sub(2 * half));
    start..(start + 2 * half).min(n)
}

/// The panel of the waveforms where the declared model misses most, every sample.
fn zoom_panel(time: &[f64], series: &[(&str, &[f64])], residual: &[f64], dt: f64, y_desc: &str) -> crate::plot::Panel {
    // ten periods of a 10 Hz mode, at most a tenth of the record
    let width = (1.0f64).min(0.1 * time.len() as f64 * dt);
    let r = zoom_range(residual, dt, width);
    let at = time.get(r.start).copied().unwrap_or(0.0);
    crate::plot::Panel {
        title: format!("zoom where the declared model misses most ({at:.2} s to {:.2} s)", at + width),
        x_desc: "time [s]".into(),
        y_desc: y_desc.into(),
        log_y: false,
        series: series
            .iter()
            .map(|(label, y)| {
                (label.to_string(), r.clone().filter(|&k| k < y.len()).map(|k| (time[k], y[k])).collect())
            })
            .collect(),
    }
}

/// |Y/U| of a record on the lines its input excites (whole-record DFT; lines at least ten times
/// the median line of the input: a sweep's band, a multisine's tones, not the leakage between), averaged in 1/12-octave bands: the record's frequency
/// response beside the models' (`y` their outputs under the same input).
fn frequency_response(u: &[f64], y: &[f64], dt: f64, f_max: f64) -> Vec<(f64, f64)> {
    let n = u.len().min(y.len());
    if n < 16 {
        return Vec::new();
    }
    let (su, sy) = (ident::signal::rfft(&u[..n]), ident::signal::rfft(&y[..n]));
    let df = 1.0 / (n as f64 * dt);
    let mut mags: Vec<f64> = su.iter().skip(1).map(|c| c.norm()).collect();
    mags.sort_by(|a, b| a.total_cmp(b));
    let largest = mags.last().copied().unwrap_or(0.0);
    let floor = (10.0 * mags[mags.len() / 2]).max(1e-3 * largest);
    let mut bands: std::collections::BTreeMap<i64, (f64, f64, usize)> = std::collections::BTreeMap::new();
    for (k, (a, b)) in su.iter().zip(&sy).enumerate().skip(1) {
        let f = k as f64 * df;
        if f > f_max || a.norm() < floor || a.norm() == 0.0 {
            continue;
        }
        let band = (12.0 * f.log2()).floor() as i64;
        let e = bands.entry(band).or_insert((0.0, 0.0, 0));
        e.0 += f;
        e.1 += b.norm() / a.norm();
        e.2 += 1;
    }
    bands.values().map(|&(f, h, c)| (f / c as f64, h / c as f64)).collect()
}

/// Most points of a plotted time series.
const PLOT_POINTS: usize = 6000;

fn torsional(file: &Path, progress: &(dyn Fn(&str) + Sync)) -> anyhow::Result<Diagnosis> {
    let b = load_torsional(file)?;
    let d = ident::diagnose::torsional::diagnose(&b.sweep, &b.model, b.variant, progress)
        .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
    // the search is reported where it went elsewhere than the answer's path
    let same_steps =
        d.search.len() == d.path.len() && d.search.iter().zip(&d.path).all(|(a, b)| a.effects == b.effects);
    let model_toml = rig_toml(&d.model.rig, d.model.variant, &d.model.effects, None)?;
    let dt = b.sweep.dt_s;
    let t = &d.traces;
    let res_before: Vec<f64> = t.measured[0].iter().zip(&t.before[0]).map(|(a, b)| a - b).collect();
    let res_after: Vec<f64> = t.measured[0].iter().zip(&t.after[0]).map(|(a, b)| a - b).collect();
    // an SVG line of more points than a screen has pixels only costs memory: every k-th sample
    let stride = t.time_s.len().div_ceil(PLOT_POINTS).max(1);
    let pts = |y: &[f64]| t.time_s.iter().zip(y).step_by(stride).map(|(&a, &b)| (a, b)).collect::<Vec<_>>();
    let with = format!("with {}", d.effect);
    let u = &b.sweep.torque_nm;
    let panels = vec![
        crate::plot::Panel {
            title: "M2 speed, the whole record (offsets and drift removed)".into(),
            x_desc: "time [s]".into(),
            y_desc: "speed_m2 [rad/s]".into(),
            log_y: false,
            series: vec![
                ("measured".into(), pts(&t.measured[0])),
                ("declared model".into(), pts(&t.before[0])),
                (with.clone(), pts(&t.after[0])),
            ],
        },
        zoom_panel(
            &t.time_s,
            &[("measured", &t.measured[0]), ("declared model", &t.before[0]), (&with, &t.after[0])],
            &res_before,
            dt,
            "speed_m2 [rad/s]",
        ),
        crate::plot::Panel {
            title: "frequency response, drive torque to M2 speed".into(),
            x_desc: "frequency [Hz]".into(),
            y_desc: "|speed_m2 / torque_drive| [rad/s/(N·m)]".into(),
            log_y: true,
            series: vec![
                ("measured".into(), frequency_response(u, &t.measured[0], dt, 60.0)),
                ("declared model".into(), frequency_response(u, &t.before[0], dt, 60.0)),
                (with.clone(), frequency_response(u, &t.after[0], dt, 60.0)),
            ],
        },
        crate::plot::Panel {
            title: "residual spectrum (M2 speed)".into(),
            x_desc: "frequency [Hz]".into(),
            y_desc: "amplitude [rad/s]".into(),
            log_y: true,
            series: vec![
                ("measured speed".into(), spectrum(&t.measured[0], dt, 60.0)),
                ("declared model".into(), spectrum(&res_before, dt, 60.0)),
                (with, spectrum(&res_after, dt, 60.0)),
            ],
        },
    ];
    Ok(Diagnosis {
        report: DiagnosisReport {
            verdict: d.verdict,
            verdict_reasons: d.verdict_reasons,
            effect: d.effect,
            at: d.at,
            parameters: d.parameters,
            intervals: d.intervals,
            not_determined: d.not_determined,
            held_out: Some(d.held_out),
            equivalents: d.equivalents,
            effects: d.effects,
            search: if same_steps { Vec::new() } else { d.search },
            path: d.path,
            error_before: d.error_before,
            error_after: d.error_after,
            candidates: d.candidates,
            kind: "torsional_sweep".into(),
            error_definition: format!(
                "‖y_meas − y_model‖/‖y_meas‖ over both load-machine speeds, below {:.3} Hz removed",
                d.high_pass_hz
            ),
            structured_residual: d.structured_residual,
            evidence: serde_json::to_value(&d.evidence)?,
            notes: d.notes,
            conversions: b.conversions.clone(),
        },
        model_toml,
        panels,
        signals: Signals::Time(d.traces),
    })
}

/// The bearing's candidates are linear fits and two 1-D searches (well under a second), so
/// there is no progress to report.
fn bearing(file: &Path, _progress: &(dyn Fn(&str) + Sync)) -> anyhow::Result<Diagnosis> {
    let b = load_bearing(file)?;
    let imp = ident::Impedances::from_tests([&b.tests[0], &b.tests[1]], b.band_hz)
        .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
    let d = ident::diagnose::bearing::diagnose(&imp, &b.support, b.structure, b.coupling)
        .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
    let f = &imp.frequencies_hz;
    let w_ref = d.reference_radps;
    let bearing_model =
        plant::BearingModel { element: d.model.equivalent_element(w_ref), support: b.support, table: None };
    let rig = rigtwin_fmu::RigPlant::default();
    let model_toml = rig_toml(&rig.powertrain, rig.variant, &Default::default(), Some(&bearing_model))?;
    let none = d.declared_fit.clone();
    let signals = {
        let mut header = vec!["frequency_hz".to_string()];
        for term in ["xx", "xy", "yx", "yy"] {
            for what in ["measured", "declared", "extended"] {
                header.push(format!("H{term}_{what}_re_N_per_m"));
                header.push(format!("H{term}_{what}_im_N_per_m"));
            }
        }
        let w = |hz: f64| 2.0 * std::f64::consts::PI * hz;
        let rows = f
            .iter()
            .zip(&imp.h)
            .map(|(&hz, h)| {
                let (decl, ext) =
                    (none.measured_impedance(&b.support, w(hz)), d.model.measured_impedance(&b.support, w(hz)));
                let mut r = vec![hz];
                for (i, j) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                    for z in [h[(i, j)], decl[(i, j)], ext[(i, j)]] {
                        r.extend([z.re, z.im]);
                    }
                }
                r
            })
            .collect();
        Signals::Lines { header, rows }
    };
    let w = |hz: f64| 2.0 * std::f64::consts::PI * hz;
    let mut panels = Vec::new();
    for (i, name) in [(0usize, "H_xx"), (1, "H_yy")] {
        for re in [true, false] {
            let part = |c: num_complex::Complex64| if re { c.re } else { c.im };
            panels.push(crate::plot::Panel {
                title: format!("{} {name}", if re { "Re" } else { "Im" }),
                x_desc: "frequency [Hz]".into(),
                y_desc: "[N/m]".into(),
                log_y: false,
                series: vec![
                    ("measured".into(), f.iter().zip(&imp.h).map(|(&x, h)| (x, part(h[(i, i)]))).collect()),
                    (
                        "declared model".into(),
                        f.iter().map(|&x| (x, part(none.measured_impedance(&b.support, w(x))[(i, i)]))).collect(),
                    ),
                    (
                        format!("with {}", d.effect),
                        f.iter().map(|&x| (x, part(d.model.measured_impedance(&b.support, w(x))[(i, i)]))).collect(),
                    ),
                ],
            });
        }
    }
    let misfit = |m: &ident::diagnose::bearing::BearingModelFit| {
        f.iter()
            .zip(&imp.h)
            .map(|(&x, h)| {
                (x, (h - m.measured_impedance(&b.support, w(x))).iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt())
            })
            .collect::<Vec<_>>()
    };
    panels.push(crate::plot::Panel {
        title: "residual spectrum: ‖H_meas − H_model‖ per line".into(),
        x_desc: "frequency [Hz]".into(),
        y_desc: "[N/m]".into(),
        log_y: true,
        series: vec![("declared model".into(), misfit(&none)), (format!("with {}", d.effect), misfit(&d.model))],
    });
    let mut evidence = serde_json::to_value(&d.evidence)?;
    evidence["r2_before"] = serde_json::to_value(d.r2_before)?;
    evidence["r2_after"] = serde_json::to_value(d.r2_after)?;
    Ok(Diagnosis {
        report: DiagnosisReport {
            verdict: d.verdict,
            verdict_reasons: d.verdict_reasons,
            effect: d.effect,
            at: None,
            parameters: d.parameters,
            intervals: BTreeMap::new(),
            not_determined: Vec::new(),
            held_out: None,
            equivalents: Vec::new(),
            effects: vec![],
            path: vec![],
            search: vec![],
            error_before: d.error_before,
            error_after: d.error_after,
            candidates: d.candidates,
            kind: "bearing_shake".into(),
            error_definition: "‖H_meas − H_model‖/‖H_meas‖ over the excited lines (Frobenius)".into(),
            structured_residual: d.structured_residual,
            evidence,
            notes: d.notes,
            conversions: b.conversions.clone(),
        },
        model_toml,
        panels,
        signals,
    })
}

/// The extended model as a rig file that `rigtwin fmu --params` reads.
pub fn rig_toml(
    rig: &plant::RigParams,
    variant: plant::Variant,
    effects: &plant::rig::DriveEffects,
    bearing: Option<&plant::BearingModel>,
) -> anyhow::Result<String> {
    #[derive(Serialize)]
    struct Out<'a> {
        name: String,
        variant: plant::Variant,
        model: &'a plant::RigParams,
        #[serde(skip_serializing_if = "Option::is_none")]
        effects: Option<&'a plant::rig::DriveEffects>,
        #[serde(skip_serializing_if = "Option::is_none")]
        bearing: Option<&'a plant::BearingModel>,
    }
    let out = Out {
        name: "extended model written by rigtwin diagnose".into(),
        variant,
        model: rig,
        effects: (!effects.is_empty()).then_some(effects),
        bearing,
    };
    Ok(toml::to_string(&out)?)
}

/// Text for the terminal.
pub fn human(r: &DiagnosisReport) -> String {
    let named = |effect: &str, at: Option<&String>| match at {
        Some(a) => format!("{} at {a}", effect_name(effect)),
        None => effect_name(effect).to_string(),
    };
    // the answer's effects, each where it acts ("a dead time at input 1 and Coulomb friction at
    // body b1")
    let answer_named = || match r.effects.len() {
        0 | 1 => named(&r.effect, r.at.as_ref()),
        _ => r.effects.iter().map(|e| named(&e.effect, e.at.as_ref())).collect::<Vec<_>>().join(" and "),
    };
    let kind = r.kind.replace('_', " ");
    let explained = r.verdict != ident::diagnose::verdict::Verdict::NotExplained;
    let mut s = if !explained {
        let mut s = format!(
            "{kind}: NOT EXPLAINED — the record shows something missing that no candidate explains with physical parameters, or that several explain alike\n"
        );
        for why in &r.verdict_reasons {
            s += &format!("  {why}\n");
        }
        if r.effect != "none" {
            s += &format!(
                "  the best candidate, {}, is therefore no finding (its error is among the candidates below)\n",
                answer_named()
            );
        }
        s
    } else if r.effect == "none" {
        format!("{kind}: the declared model fits (no effect improves it clearly)\n")
    } else {
        format!("{kind}: the declared model lacks {}\n", answer_named())
    };
    let one = |k: &String, v: f64, interval: Option<&[f64; 2]>, loose: &[String]| {
        if loose.contains(k) {
            crate::units::display_not_determined(k, interval)
        } else {
            crate::units::display_within(k, v, interval)
        }
    };
    let show =
        |p: &mut dyn Iterator<Item = (&String, &f64)>, intervals: &BTreeMap<String, [f64; 2]>, loose: &[String]| {
            p.map(|(k, v)| one(k, *v, intervals.get(k), loose)).collect::<Vec<_>>().join(", ")
        };
    if explained && !r.equivalents.is_empty() {
        s += &format!(
            "  the record does NOT DETERMINE the parameters: {} other fit(s) as good (BIC within {}); one solution:\n",
            r.equivalents.len(),
            ident::diagnose::torsional::EQUIVALENT_BIC
        );
    }
    if !explained {
        // no parameter of an unexplained record is shown as a finding
    } else if r.effects.len() > 1 {
        for e in &r.effects {
            // what the record leaves open of the effect: its sizes', and what the answer's
            // profile left open beside them (a compliance's motor share)
            let loose: Vec<String> = e.not_determined.iter().chain(&r.not_determined).cloned().collect();
            s += &format!(
                "  {}: {}\n",
                named(&e.effect, e.at.as_ref()),
                show(&mut e.parameters.iter(), &e.intervals, &loose)
            );
        }
        let of_effects = |k: &String| r.effects.iter().any(|e| e.parameters.contains_key(k));
        let rest: Vec<(&String, &f64)> = r.parameters.iter().filter(|(k, _)| !of_effects(k)).collect();
        if !rest.is_empty() {
            s += &format!("  declared, re-fitted: {}\n", show(&mut rest.into_iter(), &r.intervals, &r.not_determined));
        }
    } else {
        for (k, v) in &r.parameters {
            s += &format!("  {}\n", one(k, *v, r.intervals.get(k), &r.not_determined));
        }
    }
    for e in r.equivalents.iter().filter(|_| explained) {
        s += &format!("  as good: {}\n", show(&mut e.iter(), &BTreeMap::new(), &[]));
    }
    s += &format!("  error {:.4} → {:.4}  ({})\n", r.error_before, r.error_after, r.error_definition);
    if let Some(h) = &r.held_out {
        let blocks = format!("{} folds of {} blocks", h.folds, crate::units::quantity(h.block_s, "s"));
        if h.unmoved_folds == h.folds {
            // its "held-out" error is then the fitted error: no number is shown as a check
            s += &format!(
                "  held out: not checked on data its fit did not see — no fit without a fold moved from the fit to the whole record, which saw every fold, so no intervals are given (the declared model: {:.4}; {blocks})\n",
                h.declared_error_held_out
            );
        } else {
            s += &format!(
                "  held out: error {:.4} on the folds its fit did not see (the declared model: {:.4}; {blocks})\n",
                h.error_held_out, h.declared_error_held_out
            );
        }
        if h.unmoved_folds > 0 && h.unmoved_folds < h.folds {
            s += &format!(
                "  on {} of the {} folds no fit without the fold moved from the fit to the whole record: those folds are predicted by a fit that saw them, and the folds' spread is no interval (none given)\n",
                h.unmoved_folds, h.folds
            );
        }
        if h.damped_folds > 0 {
            // where intervals are given at all (no unmoved fold), what the damping does to them
            let intervals = if h.unmoved_folds == 0 {
                " (an interval of a parameter the record hardly determines is then too narrow)"
            } else {
                ""
            };
            s += &format!(
                "  {} of the {} fits without a fold needed a damped step{intervals}\n",
                h.damped_folds, h.folds
            );
        }
    }
    if explained && r.structured_residual {
        s += "  the residual is still structured: something the candidates do not describe remains\n";
    }
    s += "  candidates, best first:\n";
    for c in &r.candidates {
        s += &format!(
            "    {:<36} error {:.4}  score {:>10.1}\n",
            named(&c.effect, c.at.as_ref()),
            c.error_after,
            c.score
        );
    }
    for n in &r.notes {
        s += &format!("  note: {n}\n");
    }
    for c in &r.conversions {
        s += &format!("  converted: {c}\n");
    }
    s
}

/// An effect's name as a person reads it (the JSON keeps the identifier).
pub fn effect_name(effect: &str) -> &str {
    match effect {
        "time_delay" => "a dead time",
        "actuator_lag" => "an actuator lag",
        "backlash" => "play (backlash)",
        "coulomb_friction" => "Coulomb friction",
        "drive_compliance" => "a drive compliance",
        "shaft_damping" => "shaft damping",
        "sensor_delay" => "a sensor delay",
        "added_mass" => "an added mass (inertia of the element)",
        "damping" => "damping",
        "none" => "none (the declared model)",
        other => other,
    }
}

fn drive(
    file: &Path,
    progress: &(dyn Fn(&str) + Sync),
    search: &ident::diagnose::drive::SearchSettings,
) -> anyhow::Result<Diagnosis> {
    let b = crate::bundle::load_drive_test(file)?;
    let model = &b.model;
    let outputs: Vec<(plant::Quantity, usize)> =
        b.outputs.iter().map(|s| (s.quantity.unwrap_or(plant::Quantity::Speed), s.at)).collect();
    let rec = ident::diagnose::drive::DriveRecord {
        model,
        inputs: &b.input_data,
        outputs: &outputs,
        measured: &b.output_data,
        dt_s: b.dt_s,
    };
    let d = ident::diagnose::drive::diagnose_with(rec, progress, search)
        .map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
    let model_toml = drive_model_toml(&d.model, &b)?;
    // each output with its SI unit (the record's own units were converted on reading)
    let domain = b.model.line.domain;
    let unit = |q: Option<plant::Quantity>| crate::units::quantity_unit(q.unwrap_or(plant::Quantity::Speed), domain);
    let names: Vec<String> = b.outputs.iter().map(|s| s.column.clone()).collect();
    let axes: Vec<String> = b.outputs.iter().map(|s| format!("{} [{}]", s.column, unit(s.quantity))).collect();
    let t = &d.traces;
    let stride = t.time_s.len().div_ceil(PLOT_POINTS).max(1);
    let pts = |y: &[f64]| t.time_s.iter().zip(y).step_by(stride).map(|(&a, &b)| (a, b)).collect::<Vec<_>>();
    let label = match &d.at {
        _ if d.effects.len() > 1 => format!(
            "with {}",
            d.effects
                .iter()
                .map(|e| format!("{} at {}", e.effect, e.at.as_deref().unwrap_or("?")))
                .collect::<Vec<_>>()
                .join(" and ")
        ),
        Some(a) => format!("with {} at {a}", d.effect),
        None => format!("with {}", d.effect),
    };
    let mut panels: Vec<crate::plot::Panel> = axes
        .iter()
        .enumerate()
        .map(|(c, name)| crate::plot::Panel {
            title: format!("{name} (offsets and drift below {:.3} Hz removed)", d.high_pass_hz),
            x_desc: "time [s]".into(),
            y_desc: name.clone(),
            log_y: false,
            series: vec![
                ("measured".into(), pts(&t.measured[c])),
                ("declared model".into(), pts(&t.before[c])),
                (label.clone(), pts(&t.after[c])),
            ],
        })
        .collect();
    let res = |y: &[f64]| t.measured[0].iter().zip(y).map(|(a, b)| a - b).collect::<Vec<f64>>();
    let f_max = 0.5 / b.dt_s;
    panels.insert(
        1,
        zoom_panel(
            &t.time_s,
            &[("measured", &t.measured[0]), ("declared model", &t.before[0]), (&label, &t.after[0])],
            &res(&t.before[0]),
            b.dt_s,
            &axes[0],
        ),
    );
    let u = &b.input_data[0];
    panels.push(crate::plot::Panel {
        title: format!("frequency response, {} to {}", b.inputs[0].column, b.outputs[0].column),
        x_desc: "frequency [Hz]".into(),
        y_desc: format!(
            "|{} / {}| [{}/{}]",
            b.outputs[0].column,
            b.inputs[0].column,
            unit(b.outputs[0].quantity),
            crate::units::quantity_unit(plant::Quantity::CouplingForce, domain)
        ),
        log_y: true,
        series: vec![
            ("measured".into(), frequency_response(u, &t.measured[0], b.dt_s, f_max)),
            ("declared model".into(), frequency_response(u, &t.before[0], b.dt_s, f_max)),
            (label.clone(), frequency_response(u, &t.after[0], b.dt_s, f_max)),
        ],
    });
    panels.push(crate::plot::Panel {
        title: format!("residual spectrum ({})", b.outputs[0].column),
        x_desc: "frequency [Hz]".into(),
        y_desc: format!("amplitude [{}]", unit(b.outputs[0].quantity)),
        log_y: true,
        series: vec![
            ("measured".into(), spectrum(&t.measured[0], b.dt_s, f_max)),
            ("declared model".into(), spectrum(&res(&t.before[0]), b.dt_s, f_max)),
            (label, spectrum(&res(&t.after[0]), b.dt_s, f_max)),
        ],
    });
    Ok(Diagnosis {
        report: DiagnosisReport {
            verdict: d.verdict,
            verdict_reasons: d.verdict_reasons.clone(),
            effect: d.effect.clone(),
            at: d.at.clone(),
            parameters: d.parameters.clone(),
            intervals: d.intervals.clone(),
            not_determined: d.not_determined.clone(),
            held_out: Some(d.held_out.clone()),
            equivalents: Vec::new(),
            effects: d.effects.clone(),
            path: vec![],
            search: vec![],
            error_before: d.error_before,
            error_after: d.error_after,
            candidates: d.candidates.clone(),
            kind: "drive_test".into(),
            error_definition: format!(
                "RMS over the outputs of ‖y_meas − y_model‖/‖y_meas‖, each output below {:.3} Hz removed{}",
                d.high_pass_hz,
                if d.scored_by_prediction {
                    "; y_model the one-step-ahead prediction (the model held to the measured outputs after each sample)"
                } else {
                    ""
                }
            ),
            structured_residual: d.structured_residual,
            evidence: serde_json::json!({
                "high_pass_hz": d.high_pass_hz,
                "scored_by": if d.scored_by_prediction { "one_step_prediction" } else { "simulation" },
            }),
            notes: d.notes.clone(),
            conversions: b.conversions.clone(),
        },
        model_toml,
        panels,
        signals: Signals::Outputs { names, traces: d.traces },
    })
}

/// The extended model of a drive test as TOML: the bundle's model section with the re-fitted
/// values, its inputs and the effects (positions 1-based, as in the bundle).
pub fn drive_model_toml(m: &plant::DriveModel, b: &crate::bundle::DriveTestBundle) -> anyhow::Result<String> {
    #[derive(Serialize)]
    struct Model<'a> {
        bodies: &'a [plant::LineBody],
        couplings: &'a [plant::Coupling],
    }
    #[derive(Serialize)]
    struct Input<'a> {
        column: &'a str,
        body: &'a str,
    }
    #[derive(Serialize)]
    struct Out<'a> {
        kind: &'a str,
        name: &'a str,
        domain: plant::Domain,
        model: Model<'a>,
        inputs: Vec<Input<'a>>,
        effects: Vec<plant::Effect>,
        mpc: mpc::MpcSection,
    }
    // the controller's input bounds: the bundle's own [mpc] section, else the record's peak
    // |input| (what the actuators reached), so that `rigtwin mpc --params` takes the model as
    // written; the file says which
    let mut section = b.mpc.clone();
    let derived = section.bound_by_record(&b.input_data);
    // 1-based positions, as in the bundle
    let effects = m.effects.iter().map(|e| e.at_index(e.element_index().0 + 1)).collect();
    let out = Out {
        kind: "drive_model",
        name: "extended model written by rigtwin diagnose",
        domain: m.line.domain,
        model: Model { bodies: &m.line.bodies, couplings: &m.line.couplings },
        inputs: b
            .inputs
            .iter()
            .zip(&m.inputs)
            .map(|(s, &body)| Input { column: &s.column, body: &m.line.bodies[body].name })
            .collect(),
        effects,
        mpc: section,
    };
    let bounds = if derived {
        "\n# [mpc] input_max: the record's peak |input| of each input (the actuators reached it);\n# raise it to the actuators' limits before running the controller on the rig\n"
    } else {
        ""
    };
    Ok(format!(
        "# the extended model of {}; positions (body, coupling, input) are 1-based as in the bundle{bounds}\n{}",
        b.file.display(),
        toml::to_string(&out)?
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use ident::diagnose::torsional::FoundEffect;
    use ident::diagnose::verdict::Verdict;

    /// A pair whose compliance's motor share the profile leaves open (its interval reaching 1):
    /// the share is in the answer's `not_determined`, not in the effect's (a share is no size,
    /// so it does not make the effect no finding), and the effect's own line must say so
    /// rather than print the profile's best share as a value.
    #[test]
    fn a_pairs_effect_line_says_what_the_answer_leaves_open() {
        let share = "compliance_motor_share_1".to_string();
        let stiffness = "compliance_stiffness_Nm_per_rad".to_string();
        let friction = "friction_Nm".to_string();
        let effect = |name: &str, keys: &[(&String, f64, [f64; 2])]| FoundEffect {
            effect: name.into(),
            at: Some("body b2".into()),
            parameters: keys.iter().map(|(k, v, _)| ((*k).clone(), *v)).collect(),
            intervals: keys.iter().map(|(k, _, i)| ((*k).clone(), *i)).collect(),
            error_without: 0.5,
            not_determined: vec![],
        };
        let effects = vec![
            effect("compliance", &[(&stiffness, 1500.0, [1400.0, 1600.0]), (&share, 0.6, [0.3, 1.0])]),
            effect("coulomb_friction", &[(&friction, 0.4, [0.38, 0.42])]),
        ];
        let parameters: BTreeMap<String, f64> = effects.iter().flat_map(|e| e.parameters.clone()).collect();
        let intervals = effects.iter().flat_map(|e| e.intervals.clone()).collect();
        let r = DiagnosisReport {
            verdict: Verdict::Explained,
            verdict_reasons: vec![],
            effect: "compliance".into(),
            at: Some("body b2".into()),
            parameters,
            intervals,
            not_determined: vec![share.clone()],
            held_out: None,
            equivalents: vec![],
            effects,
            path: vec![],
            search: vec![],
            error_before: 1.0,
            error_after: 0.1,
            candidates: vec![],
            kind: "drive_test".into(),
            error_definition: String::new(),
            structured_residual: false,
            evidence: serde_json::Value::Null,
            notes: vec![],
            conversions: vec![],
        };
        let text = human(&r);
        let line = text.lines().find(|l| l.contains("compliance_motor_share")).expect(&text);
        assert!(line.contains("not determined"), "{text}");
        assert!(!line.contains("0.6"), "the share's best value is printed as a finding: {line}");
        // the sizes the record determines keep their values
        assert!(text.lines().any(|l| l.contains("friction") && l.contains("0.4")), "{text}");
    }
}
