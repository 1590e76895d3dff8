//! `rigtwin bearing`: the identified element, its fit quality, and the impedance plot.

use serde::Serialize;
use std::fmt::Write as _;

use ident::bearing::{fit, Averaging};
use ident::{Coupling, Impedances, IvfmSettings, Method, Structure, R2};
use plant::{Coefficients, Support};

use crate::bundle::BearingBundle;

/// N/m per klbf/in.
pub const N_PER_M_PER_KLBF_PER_IN: f64 = 175_126.8;
/// N s/m per lbf s/in.
pub const NS_PER_M_PER_LBF_S_PER_IN: f64 = 175.1268;
/// kg per lb.
pub const KG_PER_LB: f64 = 0.453_592_37;

/// Another structure's fit, for comparison.
#[derive(Debug, Clone, Serialize)]
pub struct Alternative {
    /// Structure.
    pub structure: Structure,
    /// Coupling.
    pub coupling: Coupling,
    /// Its r².
    pub r2: R2,
    /// Its coefficients.
    #[serde(flatten)]
    pub element: Coefficients,
}

/// The report; `K_N_per_m`, `C_Ns_per_m`, `M_kg`, `r2`, `condition_number_max` and `method`
/// are the contract.
#[derive(Debug, Clone, Serialize)]
pub struct BearingReport {
    /// Bundle.
    pub file: String,
    /// The element's coefficients, support subtracted.
    #[serde(flatten)]
    pub element: Coefficients,
    /// r² of each impedance term, [re, im].
    pub r2: R2,
    /// Largest condition number of [Z1 Z2] over the lines.
    pub condition_number_max: f64,
    /// Estimator.
    pub method: Method,
    /// Structure fitted.
    pub structure: Structure,
    /// Coupling fitted.
    pub coupling: Coupling,
    /// Structure the bundle declares.
    pub declared_structure: Structure,
    /// Coupling the bundle declares.
    pub declared_coupling: Coupling,
    /// IVFM iterations after least squares.
    pub iterations: usize,
    /// IVFM settled.
    pub converged: bool,
    /// Spectral averaging.
    pub averaging: Averaging,
    /// Lines used.
    pub lines: usize,
    /// Band, Hz.
    pub band_hz: (f64, f64),
    /// Lines whose condition number exceeds 10 (slide 20), Hz.
    pub ill_conditioned_lines_hz: Vec<f64>,
    /// The support subtracted.
    pub support: Support,
    /// The same estimator with the other structures.
    pub alternatives: Vec<Alternative>,
    /// Things the engineer should know.
    pub warnings: Vec<String>,
    /// Unit conversions and sensor calibrations applied to the tests' channels.
    pub conversions: Vec<String>,
}

/// Identifies the element of a bundle; `structure`/`coupling` override the declared ones.
pub fn identify(
    b: &BearingBundle,
    structure: Option<Structure>,
    coupling: Option<Coupling>,
    method: Method,
) -> anyhow::Result<(BearingReport, Impedances)> {
    let imp = Impedances::from_tests([&b.tests[0], &b.tests[1]], b.band_hz)
        .map_err(|e| anyhow::anyhow!("{}: {e}", b.file.display()))?;
    let (s, c) = (structure.unwrap_or(b.structure), coupling.unwrap_or(b.coupling));
    let settings = IvfmSettings::default();
    let f = fit(&imp, &b.support, s, c, method, &settings)?;
    let mut warnings = Vec::new();
    let bad = imp.ill_conditioned_hz();
    if !bad.is_empty() {
        warnings.push(format!(
            "{} of {} lines have a condition number of [Z1 Z2] above {}: the two tests are not independent enough there (slide 20)",
            bad.len(),
            imp.h.len(),
            ident::bearing::CONDITION_WARNING
        ));
    }
    if method == Method::Ivfm && !f.converged {
        warnings.push(format!("the IVFM did not settle in {} iterations", f.iterations));
    }
    let mut alternatives = Vec::new();
    for alt_s in [Structure::KC, Structure::KCM] {
        for alt_c in [Coupling::Direct, Coupling::Full] {
            if (alt_s, alt_c) != (s, c) {
                let a = fit(&imp, &b.support, alt_s, alt_c, method, &settings)?;
                alternatives.push(Alternative { structure: alt_s, coupling: alt_c, r2: a.r2, element: a.element });
            }
        }
    }
    // what the fitted structure misses, told from the direct terms' r²
    let worst = f.r2.lowest_direct();
    if worst < ident::bearing::MIN_DIRECT_R2 {
        if let Some(better) = alternatives
            .iter()
            .filter(|a| a.r2.lowest_direct() >= ident::bearing::MIN_DIRECT_R2)
            .min_by_key(|a| (a.structure == Structure::KCM) as u8 * 2 + (a.coupling == Coupling::Full) as u8)
        {
            warnings.push(format!(
                "the {}/{} model does not reproduce the direct impedances (lowest r² {worst:.3}); \
                 {}/{} does (Re Hxx r² {:.4}, Re Hyy r² {:.4}){}",
                crate::report::words(&s),
                crate::report::words(&c),
                crate::report::words(&better.structure),
                crate::report::words(&better.coupling),
                better.r2.hxx[0],
                better.r2.hyy[0],
                if s == Structure::KC && better.structure == Structure::KCM {
                    ": the real parts fall with ω² — the element has inertia, which a KC model can only mimic with a wrong stiffness"
                } else {
                    ""
                }
            ));
        }
    }
    let report = BearingReport {
        file: b.file.display().to_string(),
        element: f.element,
        r2: f.r2,
        condition_number_max: imp.condition_max(),
        method,
        structure: s,
        coupling: c,
        declared_structure: b.structure,
        declared_coupling: b.coupling,
        iterations: f.iterations,
        converged: f.converged,
        averaging: imp.averaging,
        lines: imp.h.len(),
        band_hz: b.band_hz,
        ill_conditioned_lines_hz: bad,
        support: b.support,
        alternatives,
        warnings,
        conversions: b.conversions.clone(),
    };
    Ok((report, imp))
}

impl BearingReport {
    /// Human-readable form, in SI and in the field's units.
    pub fn human(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "Bearing identification — {}: {}, structure {}, coupling {} (declared {}, {})",
            self.file,
            crate::report::words(&self.method),
            crate::report::words(&self.structure),
            crate::report::words(&self.coupling),
            crate::report::words(&self.declared_structure),
            crate::report::words(&self.declared_coupling)
        );
        let avg = match self.averaging {
            Averaging::Periodic { periods } => format!("periodic excitation, {periods} periods averaged"),
            Averaging::H1 { segments } => format!("H1 estimate over {segments} segments"),
            Averaging::Given => "spectra given".into(),
        };
        let _ = writeln!(
            s,
            "  {} lines in {}–{} Hz, {avg}; condition number of [Z1 Z2] ≤ {:.2}",
            self.lines, self.band_hz.0, self.band_hz.1, self.condition_number_max
        );
        for c in &self.conversions {
            let _ = writeln!(s, "  converted: {c}");
        }
        if self.method == Method::Ivfm {
            let _ = writeln!(
                s,
                "  IVFM: {} iterations after least squares, {}",
                self.iterations,
                if self.converged { "converged" } else { "NOT converged" }
            );
        }
        let _ = writeln!(s, "  coefficient          SI                      field units");
        let e = &self.element;
        for (i, j, ij) in [(0, 0, "xx"), (0, 1, "xy"), (1, 0, "yx"), (1, 1, "yy")] {
            let _ = writeln!(
                s,
                "  K{ij}  {:>14.4e} N/m      {:>10.3} klbf/in",
                e.k_n_per_m[i][j],
                e.k_n_per_m[i][j] / N_PER_M_PER_KLBF_PER_IN
            );
        }
        for (i, j, ij) in [(0, 0, "xx"), (0, 1, "xy"), (1, 0, "yx"), (1, 1, "yy")] {
            let _ = writeln!(
                s,
                "  C{ij}  {:>14.2} N s/m    {:>10.3} lbf s/in",
                e.c_ns_per_m[i][j],
                e.c_ns_per_m[i][j] / NS_PER_M_PER_LBF_S_PER_IN
            );
        }
        for (i, j, ij) in [(0, 0, "xx"), (0, 1, "xy"), (1, 0, "yx"), (1, 1, "yy")] {
            let _ = writeln!(s, "  M{ij}  {:>14.3} kg       {:>10.3} lb", e.m_kg[i][j], e.m_kg[i][j] / KG_PER_LB);
        }
        let _ = writeln!(s, "  r²     Re       Im");
        for (name, r) in [("Hxx", self.r2.hxx), ("Hxy", self.r2.hxy), ("Hyx", self.r2.hyx), ("Hyy", self.r2.hyy)] {
            let _ = writeln!(s, "  {name}  {:>7.4}  {:>7.4}", r[0], r[1]);
        }
        for a in &self.alternatives {
            let _ = writeln!(
                s,
                "  for comparison {}/{}: r² Re/Im Hxx {:.4}/{:.4}, Hyy {:.4}/{:.4}",
                crate::report::words(&a.structure),
                crate::report::words(&a.coupling),
                a.r2.hxx[0],
                a.r2.hxx[1],
                a.r2.hyy[0],
                a.r2.hyy[1]
            );
        }
        for w in &self.warnings {
            let _ = writeln!(s, "  warning: {w}");
        }
        s
    }
}

/// Measured and fitted real and imaginary parts of the four impedances against frequency
/// (slides 42–44), as SVG.
pub fn plot(
    target: &crate::files::Target,
    imp: &Impedances,
    support: &Support,
    element: &Coefficients,
    title: &str,
) -> anyhow::Result<()> {
    use crate::plot::err;
    use plotters::prelude::*;
    let f = &imp.frequencies_hz;
    let (f0, f1) = (f[0], f[f.len() - 1]);
    let fine: Vec<f64> = (0..=400).map(|i| f0 + (f1 - f0) * i as f64 / 400.0).collect();
    let model = |w: f64| element.impedance(w) + support.coefficients().impedance(w);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1400, 1500)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let root = root.titled(title, ("sans-serif", 22)).map_err(err)?;
        let panels = root.split_evenly((4, 2));
        let terms = [((0, 0), "Hxx"), ((0, 1), "Hxy"), ((1, 0), "Hyx"), ((1, 1), "Hyy")];
        for (idx, area) in panels.iter().enumerate() {
            let ((i, j), name) = terms[idx / 2];
            let re = idx % 2 == 0;
            let part = |c: nalgebra::Complex<f64>| if re { c.re } else { c.im };
            let meas: Vec<(f64, f64)> = f.iter().zip(&imp.h).map(|(&x, h)| (x, part(h[(i, j)]))).collect();
            let fit: Vec<(f64, f64)> =
                fine.iter().map(|&x| (x, part(model(2.0 * std::f64::consts::PI * x)[(i, j)]))).collect();
            let (lo, hi) =
                meas.iter().chain(&fit).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.1), b.max(p.1)));
            let pad = 0.05 * (hi - lo).max(1.0);
            let mut chart = ChartBuilder::on(area)
                .caption(format!("{} {name} [N/m]", if re { "Re" } else { "Im" }), ("sans-serif", 16))
                .margin(10)
                .x_label_area_size(35)
                .y_label_area_size(80)
                .build_cartesian_2d(f0..f1, (lo - pad)..(hi + pad))
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("frequency [Hz]")
                .y_label_formatter(&|v| format!("{v:.2e}"))
                .draw()
                .map_err(err)?;
            chart
                .draw_series(meas.iter().map(|&p| Circle::new(p, 3, BLUE.filled())))
                .map_err(err)?
                .label("measured")
                .legend(|(x, y)| Circle::new((x, y), 3, BLUE.filled()));
            chart
                .draw_series(LineSeries::new(fit, RED.stroke_width(2)))
                .map_err(err)?
                .label("identified model")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
            chart.configure_series_labels().border_style(BLACK).background_style(WHITE.mix(0.8)).draw().map_err(err)?;
        }
        root.present().map_err(err)?;
    }
    crate::files::write(target, svg.as_bytes())
}
