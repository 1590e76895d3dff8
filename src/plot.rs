//! Line plots as SVG (time histories, spectra): panels stacked vertically, one or more
//! labelled series each.

use crate::files::{self, Target};

/// One panel of a plot.
pub struct Panel {
    /// Caption.
    pub title: String,
    /// X axis label (with unit).
    pub x_desc: String,
    /// Y axis label (with unit).
    pub y_desc: String,
    /// Logarithmic y axis (values ≤ 0 are dropped).
    pub log_y: bool,
    /// (label, points).
    pub series: Vec<(String, Vec<(f64, f64)>)>,
}

pub(crate) fn err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow::anyhow!("drawing the plot failed: {e}")
}

/// The colour of a series by its role, the same in every panel and plot: the measurement black,
/// the declared model blue, the extended model ("with …") red, a reference green; other series
/// from a palette by their place.
fn colour_of(label: &str, index: usize) -> plotters::style::RGBColor {
    use plotters::style::RGBColor;
    let l = label.to_ascii_lowercase();
    if l.starts_with("measured") {
        RGBColor(0, 0, 0)
    } else if l.starts_with("declared") {
        RGBColor(31, 119, 180)
    } else if l.starts_with("with ") || l.starts_with("extended") {
        RGBColor(214, 39, 40)
    } else if l.starts_with("reference") {
        RGBColor(44, 160, 44)
    } else {
        const PALETTE: [RGBColor; 6] = [
            RGBColor(31, 119, 180),
            RGBColor(214, 39, 40),
            RGBColor(44, 160, 44),
            RGBColor(255, 127, 14),
            RGBColor(148, 103, 189),
            RGBColor(140, 86, 75),
        ];
        PALETTE[index % PALETTE.len()]
    }
}

/// A tick label: a plain number with as few digits as it needs (`1e-4`, `0.5`, `120`), never
/// the floating-point noise of a log axis (`9.999999999999999e-5`).
fn tick(v: &f64) -> String {
    let v = *v;
    if v == 0.0 {
        return "0".into();
    }
    let m = v.abs().log10().floor();
    if !(-3.0..5.0).contains(&m) {
        let mantissa = v / 10f64.powf(m);
        let mantissa = (mantissa * 100.0).round() / 100.0;
        return if (mantissa - 1.0).abs() < 1e-9 { format!("1e{m}") } else { format!("{mantissa}e{m}") };
    }
    let decimals = (2.0 - m).clamp(0.0, 6.0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Writes `panels` as SVG to `target` under `title` (drawn in memory, then written safely).
pub fn lines(target: &Target, title: &str, panels: &[Panel]) -> anyhow::Result<()> {
    use plotters::prelude::*;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1200, 360 * panels.len().max(1) as u32)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let root = root.titled(title, ("sans-serif", 22)).map_err(err)?;
        let areas = root.split_evenly((panels.len().max(1), 1));
        for (panel, area) in panels.iter().zip(areas.iter()) {
            let pts = || {
                panel
                    .series
                    .iter()
                    .flat_map(|(_, p)| p.iter())
                    .filter(|p| p.0.is_finite() && p.1.is_finite() && (!panel.log_y || p.1 > 0.0))
            };
            let (x0, x1) = pts().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.0), b.max(p.0)));
            let (y0, y1) = pts().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.1), b.max(p.1)));
            if !x0.is_finite() || !y0.is_finite() {
                continue;
            }
            let x1 = if x1 > x0 { x1 } else { x0 + 1.0 };
            let mut builder = ChartBuilder::on(area);
            // room for the y label beside its ticks, and on the right for the last x tick
            builder
                .caption(&panel.title, ("sans-serif", 16))
                .margin(10)
                .margin_right(30)
                .x_label_area_size(40)
                .y_label_area_size(90);
            if panel.log_y {
                let mut chart = builder.build_cartesian_2d(x0..x1, (y0..y1 * 1.5).log_scale()).map_err(err)?;
                draw(&mut chart, panel)?;
            } else {
                let pad = 0.05 * (y1 - y0).max(1e-9);
                let mut chart = builder.build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad)).map_err(err)?;
                draw(&mut chart, panel)?;
            }
        }
        root.present().map_err(err)?;
    }
    files::write(target, svg.as_bytes())
}

fn draw<'a, 'b: 'a, Y>(
    chart: &mut plotters::prelude::ChartContext<
        'a,
        plotters::prelude::SVGBackend<'b>,
        plotters::prelude::Cartesian2d<plotters::coord::types::RangedCoordf64, Y>,
    >,
    panel: &Panel,
) -> anyhow::Result<()>
where
    Y: plotters::coord::ranged1d::Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
{
    use plotters::prelude::*;
    chart
        .configure_mesh()
        .x_desc(&panel.x_desc)
        .y_desc(&panel.y_desc)
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .draw()
        .map_err(err)?;
    // the models first, the measurement last and on top (thin, so the fits under it show)
    let mut order: Vec<usize> = (0..panel.series.len()).collect();
    order.sort_by_key(|&i| panel.series[i].0.to_ascii_lowercase().starts_with("measured"));
    for i in order {
        let (label, p) = &panel.series[i];
        let c = colour_of(label, i);
        let width = if label.to_ascii_lowercase().starts_with("measured") { 1 } else { 2 };
        let data: Vec<(f64, f64)> =
            p.iter().copied().filter(|q| q.0.is_finite() && q.1.is_finite() && (!panel.log_y || q.1 > 0.0)).collect();
        chart
            .draw_series(LineSeries::new(data, c.stroke_width(width)))
            .map_err(err)?
            .label(label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
    }
    chart.configure_series_labels().border_style(BLACK).background_style(WHITE.mix(0.8)).draw().map_err(err)?;
    Ok(())
}
