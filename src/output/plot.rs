//! SVG line plots (plotters' SVG backend: no system fonts or libraries needed).

use crate::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;

/// One curve of a plot.
pub struct Curve<'a> {
    pub label: &'a str,
    pub points: Vec<(f64, f64)>,
}

/// One panel: title, axis labels and its curves.
pub struct Panel<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub curves: Vec<Curve<'a>>,
    /// Logarithmic axes (x, y).
    pub log: (bool, bool),
}

const COLORS: [RGBColor; 6] = [BLUE, RED, GREEN, MAGENTA, CYAN, BLACK];

/// A tick label: the shortest form, or 2 significant digits in exponent
/// form when that is long (log axes give values such as 9.999999999999999e-5).
fn tick(v: f64) -> String {
    let plain = format!("{v}");
    if plain.len() <= 6 {
        plain
    } else {
        format!("{v:.1e}").replace(".0e", "e")
    }
}

fn bounds(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return if log { (1e-16, 1.0) } else { (0.0, 1.0) };
    }
    if log {
        return (lo / 1.5, hi * 1.5);
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        lo.abs().max(1.0) * 0.05
    };
    (lo - pad, hi + pad)
}

/// Draws the panels stacked vertically into one SVG file.
pub fn draw(path: &Path, panels: &[Panel]) -> Result<()> {
    let err = |e: String| Error::Output(format!("{}: plot: {e}", path.display()));
    let height = 420 * panels.len() as u32;
    let root = SVGBackend::new(path, (900, height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
    let areas = root.split_evenly((panels.len(), 1));
    for (area, panel) in areas.iter().zip(panels) {
        let (x0, x1) = bounds(
            panel
                .curves
                .iter()
                .flat_map(|c| c.points.iter().map(|p| p.0)),
            panel.log.0,
        );
        let (y0, y1) = bounds(
            panel
                .curves
                .iter()
                .flat_map(|c| c.points.iter().map(|p| p.1)),
            panel.log.1,
        );
        let mut builder = ChartBuilder::on(area);
        builder
            .caption(panel.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(80);
        macro_rules! finish {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(panel.x_label)
                    .y_desc(panel.y_label)
                    .x_label_formatter(&|v| tick(*v))
                    .y_label_formatter(&|v| tick(*v))
                    .draw()
                    .map_err(|e| err(e.to_string()))?;
                for (i, c) in panel.curves.iter().enumerate() {
                    let color = COLORS[i % COLORS.len()];
                    let pts: Vec<(f64, f64)> = c
                        .points
                        .iter()
                        .copied()
                        .filter(|(x, y)| x.is_finite() && y.is_finite())
                        .filter(|(x, y)| (!panel.log.0 || *x > 0.0) && (!panel.log.1 || *y > 0.0))
                        .collect();
                    chart
                        .draw_series(LineSeries::new(pts, color.stroke_width(2)))
                        .map_err(|e| err(e.to_string()))?
                        .label(c.label)
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                        });
                }
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .draw()
                    .map_err(|e| err(e.to_string()))?;
            }};
        }
        match panel.log {
            (false, false) => finish!(
                builder
                    .build_cartesian_2d(x0..x1, y0..y1)
                    .map_err(|e| err(e.to_string()))?
            ),
            (false, true) => finish!(
                builder
                    .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                    .map_err(|e| err(e.to_string()))?
            ),
            (true, false) => finish!(
                builder
                    .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
                    .map_err(|e| err(e.to_string()))?
            ),
            (true, true) => finish!(
                builder
                    .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
                    .map_err(|e| err(e.to_string()))?
            ),
        }
    }
    root.present().map_err(|e| err(e.to_string()))
}
