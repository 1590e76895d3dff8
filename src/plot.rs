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

/// Writes `panels` as SVG to `target` under `title` (drawn in memory, then written safely).
pub fn lines(target: &Target, title: &str, panels: &[Panel]) -> anyhow::Result<()> {
    use plotters::prelude::*;
    let colours = [BLUE, RED, RGBColor(0, 140, 0), RGBColor(200, 120, 0), MAGENTA, BLACK];
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
            builder.caption(&panel.title, ("sans-serif", 16)).margin(10).x_label_area_size(35).y_label_area_size(80);
            if panel.log_y {
                let mut chart = builder.build_cartesian_2d(x0..x1, (y0..y1 * 1.5).log_scale()).map_err(err)?;
                draw(&mut chart, panel, &colours)?;
            } else {
                let pad = 0.05 * (y1 - y0).max(1e-9);
                let mut chart = builder.build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad)).map_err(err)?;
                draw(&mut chart, panel, &colours)?;
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
    colours: &[plotters::prelude::RGBColor],
) -> anyhow::Result<()>
where
    Y: plotters::coord::ranged1d::Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
{
    use plotters::prelude::*;
    chart.configure_mesh().x_desc(&panel.x_desc).y_desc(&panel.y_desc).draw().map_err(err)?;
    for (i, (label, p)) in panel.series.iter().enumerate() {
        let c = colours[i % colours.len()];
        let data: Vec<(f64, f64)> =
            p.iter().copied().filter(|q| q.0.is_finite() && q.1.is_finite() && (!panel.log_y || q.1 > 0.0)).collect();
        chart
            .draw_series(LineSeries::new(data, c.stroke_width(2)))
            .map_err(err)?
            .label(label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
    }
    chart.configure_series_labels().border_style(BLACK).background_style(WHITE.mix(0.8)).draw().map_err(err)?;
    Ok(())
}
