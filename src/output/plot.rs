//! SVG line plots (plotters' SVG backend: no system fonts or libraries needed).

use crate::error::{Error, Result};
use plotters::coord::types::RangedCoordf64;
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

/// Tick labels per axis (plotters' bold key points: the labelled ticks).
const LABELS: usize = 11;

/// How the tick labels of one axis are written: decided once per axis from
/// its range and its ticks, so that every label on it has the same form.
#[derive(Clone, Copy, Debug, PartialEq)]
enum TickFormat {
    /// Fixed notation with this many decimals (0.0, 0.2, 0.4; 0.70, 0.75).
    Fixed(usize),
    /// Scientific with this many mantissa decimals (1.0e-3, 1.5e-3).
    Scientific(usize),
    /// Logarithmic axis with at least two powers of ten among its ticks:
    /// those are written 1e-8, 1e-6, ...; ticks between them get no label
    /// (grid lines only).
    Powers,
    /// Logarithmic axis with fewer: ticks as a mantissa with this many
    /// decimals times a power of ten (1e-2, 2e-2, 5e-2; with integer
    /// mantissas only 1, 2 and 5 are labelled).
    LogMantissa(usize),
}

/// The label writer of one axis.
#[derive(Clone, Copy, Debug)]
struct AxisLabels {
    format: TickFormat,
    /// |v| up to this (1e-9 x the axis span) is written as zero.
    zero: f64,
}

/// The fewest decimals (up to 15) that write `x` to 1e-6 of itself.
fn decimals(x: f64) -> usize {
    let x = x.abs();
    if x == 0.0 || !x.is_finite() {
        return 0;
    }
    (0..15)
        .find(|&d| {
            let s = x * 10f64.powi(d as i32);
            (s - s.round()).abs() <= 1e-6 * s
        })
        .unwrap_or(15)
}

/// Decimal exponent of |x| (x != 0), robust to round-off (9.999999999999999e-5 -> -4).
fn exponent(x: f64) -> i32 {
    (x.abs().log10() + 1e-9).floor() as i32
}

/// log10(v) when v > 0 is a power of ten (to round-off).
fn power_of_ten(v: f64) -> Option<i32> {
    let l = v.log10();
    (v > 0.0 && (l - l.round()).abs() < 1e-6).then(|| l.round() as i32)
}

impl AxisLabels {
    /// The labels of an axis over `lo..hi` (logarithmic when `log`), decided
    /// from the ticks plotters labels on it.
    fn new(lo: f64, hi: f64, log: bool) -> Self {
        let ticks: Vec<f64> = if log {
            let c: LogCoord<f64> = (lo..hi).log_scale().into();
            c.key_points(LABELS)
        } else {
            RangedCoordf64::from(lo..hi).key_points(LABELS)
        };
        Self::from_ticks(lo, hi, log, &ticks)
    }

    fn from_ticks(lo: f64, hi: f64, log: bool, ticks: &[f64]) -> Self {
        let zero = 1e-9 * (hi - lo).abs();
        let format = if log {
            if ticks.iter().filter_map(|v| power_of_ten(*v)).count() >= 2 {
                TickFormat::Powers
            } else {
                let d = ticks
                    .iter()
                    .filter(|v| **v > 0.0)
                    .map(|v| decimals(v / 10f64.powi(exponent(*v))))
                    .max()
                    .unwrap_or(0);
                TickFormat::LogMantissa(d.min(3))
            }
        } else {
            // The step between consecutive ticks, and the largest magnitude.
            let step = ticks
                .windows(2)
                .map(|w| (w[1] - w[0]).abs())
                .fold(f64::INFINITY, f64::min);
            let step = if step.is_finite() && step > 0.0 {
                step
            } else {
                (hi - lo).abs().max(f64::MIN_POSITIVE)
            };
            let big = ticks
                .iter()
                .chain(&[lo, hi])
                .map(|v| v.abs())
                .fold(0.0, f64::max);
            // Decimals that tell consecutive ticks apart.
            let d = decimals(step);
            if d <= 3 && big < 1e5 {
                TickFormat::Fixed(d)
            } else {
                // Mantissa decimals relative to the largest tick's exponent.
                let e = exponent(big.max(f64::MIN_POSITIVE));
                TickFormat::Scientific(decimals(step / 10f64.powi(e)))
            }
        };
        AxisLabels { format, zero }
    }

    fn label(&self, v: f64) -> String {
        if !v.is_finite() {
            return String::new();
        }
        // Round-off at zero (and -0.0) is written as zero.
        let v = if v.abs() <= self.zero { 0.0 } else { v };
        match self.format {
            TickFormat::Fixed(d) => format!("{v:.d$}"),
            TickFormat::Scientific(_) if v == 0.0 => "0".into(),
            TickFormat::Scientific(p) if v != 0.0 => format!("{v:.p$e}"),
            // Integer mantissas: only 1, 2 and 5 are labelled (8e-2 and 9e-2
            // would crowd the next power of ten).
            TickFormat::LogMantissa(0) if v > 0.0 => {
                let s = format!("{v:.0e}");
                if ["1e", "2e", "5e"].iter().any(|m| s.starts_with(m)) {
                    s
                } else {
                    String::new()
                }
            }
            TickFormat::LogMantissa(p) if v > 0.0 => format!("{v:.p$e}"),
            TickFormat::Powers => power_of_ten(v).map_or(String::new(), |e| format!("1e{e}")),
            _ => String::new(),
        }
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
        let (lo, hi) = (lo / 1.5, hi * 1.5);
        // plotters labels a log axis at the powers of ten in it (and between
        // them when there are few): an axis inside one decade would get no
        // label, so it is widened to the decade around it (and a little more,
        // lest round-off in plotters leave out an end).
        if lo.log10().ceil() > hi.log10().floor() {
            return (
                0.99 * 10f64.powf(lo.log10().floor()),
                1.01 * 10f64.powf(hi.log10().ceil()),
            );
        }
        return (lo, hi);
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
    let err = |e: String| Error::write(path, format!("plot: {e}"));
    let height = 420 * panels.len() as u32;
    let root = SVGBackend::new(path, (900, height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
    let areas = root.split_evenly((panels.len(), 1));
    for (area, panel) in areas.iter().zip(panels) {
        // Every axis states its unit: "t (s)", "error (relative)", "lambda (-)".
        debug_assert!(
            [panel.x_label, panel.y_label]
                .iter()
                .all(|l| l.trim_end().ends_with(')')),
            "axis labels need a unit in parentheses: {:?}, {:?}",
            panel.x_label,
            panel.y_label
        );
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
        let (fx, fy) = (
            AxisLabels::new(x0, x1, panel.log.0),
            AxisLabels::new(y0, y1, panel.log.1),
        );
        let mut builder = ChartBuilder::on(area);
        builder
            .caption(panel.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(86);
        macro_rules! finish {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(panel.x_label)
                    .y_desc(panel.y_label)
                    .label_style(("sans-serif", 15))
                    .axis_desc_style(("sans-serif", 16))
                    .x_labels(LABELS)
                    .y_labels(LABELS)
                    .x_label_formatter(&|v| fx.label(*v))
                    .y_label_formatter(&|v| fy.label(*v))
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
                    .label_font(("sans-serif", 15))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The labels plotters would draw on an axis over lo..hi.
    fn labels(lo: f64, hi: f64, log: bool) -> (TickFormat, Vec<String>) {
        let a = AxisLabels::new(lo, hi, log);
        let ticks: Vec<f64> = if log {
            let c: LogCoord<f64> = (lo..hi).log_scale().into();
            c.key_points(LABELS)
        } else {
            RangedCoordf64::from(lo..hi).key_points(LABELS)
        };
        (a.format, ticks.iter().map(|v| a.label(*v)).collect())
    }

    #[test]
    fn draw_writes_the_labels() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("plot.svg");
        let line: Vec<(f64, f64)> = (0..=50)
            .map(|i| (i as f64 / 50.0, 2e-4 * i as f64 / 50.0 + 1e-4))
            .collect();
        let decay: Vec<(f64, f64)> = (0..=40)
            .map(|i| (1e-3 * 1.2f64.powi(i), 10f64.powf(-2.0 - i as f64 / 5.0)))
            .collect();
        draw(
            &path,
            &[
                Panel {
                    title: "linear",
                    x_label: "t (s)",
                    y_label: "u (m)",
                    curves: vec![Curve {
                        label: "u",
                        points: line,
                    }],
                    log: (false, false),
                },
                Panel {
                    title: "log-log",
                    x_label: "wall time (s)",
                    y_label: "error (relative)",
                    curves: vec![Curve {
                        label: "e",
                        points: decay,
                    }],
                    log: (true, true),
                },
            ],
        )
        .unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        if std::env::var_os("ANM_KEEP_PLOT").is_some() {
            // Kept to be looked at: the directory outlives the test.
            let _ = tmp.keep();
            eprintln!("{}", path.display());
        }
        for text in ["0.0", "1.0", "1.0e-4", "3.0e-4", "1e-8", "1e-2", "t (s)"] {
            let text = format!("\n{text}\n");
            assert!(svg.contains(&text), "{text} missing: {svg}");
        }
        assert!(!svg.contains("e-16\n") && !svg.contains("\n-0"));
    }

    fn decimals_of(s: &str) -> usize {
        s.split_once('.').map_or(0, |(_, d)| d.len())
    }

    #[test]
    fn linear_unit_axis_is_fixed_with_one_decimal_count() {
        let (f, l) = labels(0.0, 1.0, false);
        assert_eq!(f, TickFormat::Fixed(1), "{l:?}");
        assert!(l.len() >= 5, "{l:?}");
        assert!(l.iter().all(|s| !s.contains('e')), "{l:?}");
        assert!(l.iter().all(|s| decimals_of(s) == 1), "{l:?}");
        assert_eq!(l[0], "0.0");
        assert_eq!(l.last().unwrap(), "1.0");
        // A finer axis: 0.70, 0.75, ...
        let (f, l) = labels(0.7, 0.95, false);
        assert_eq!(f, TickFormat::Fixed(2), "{l:?}");
        assert!(l.contains(&"0.75".to_string()), "{l:?}");
        assert!(l.iter().all(|s| decimals_of(s) == 2), "{l:?}");
    }

    #[test]
    fn round_off_at_zero_prints_zero() {
        let (f, l) = labels(-2.2e-16, 1.0, false);
        assert_eq!(f, TickFormat::Fixed(1));
        assert_eq!(l[0], "0.0", "{l:?}");
        let a = AxisLabels::new(-2.2e-16, 1.0, false);
        assert_eq!(a.label(-2.2e-16), "0.0");
        assert_eq!(a.label(-0.0), "0.0");
        assert!(
            l.iter().all(|s| !s.contains('e') && !s.starts_with('-')),
            "{l:?}"
        );
        // Scientific axes write zero as 0.
        let a = AxisLabels::new(-2e-4, 3e-4, false);
        assert!(matches!(a.format, TickFormat::Scientific(_)));
        assert_eq!(a.label(3e-21), "0");
    }

    #[test]
    fn small_values_share_one_scientific_format() {
        let (f, l) = labels(1e-4, 3e-4, false);
        assert_eq!(f, TickFormat::Scientific(1), "{l:?}");
        assert!(l.len() >= 5, "{l:?}");
        for s in &l {
            let (m, e) = s.split_once('e').expect("exponent form");
            assert_eq!(decimals_of(m), 1, "{l:?}");
            assert_eq!(e, "-4", "{l:?}");
        }
        assert_eq!(l[0], "1.0e-4");
        assert!(l.contains(&"1.5e-4".to_string()) || l.contains(&"1.2e-4".to_string()));
        assert_eq!(l.last().unwrap(), "3.0e-4");
        // Large values too.
        let (f, l) = labels(0.0, 3e6, false);
        assert!(matches!(f, TickFormat::Scientific(_)), "{l:?}");
        assert!(l[1..].iter().all(|s| s.contains("e")), "{l:?}");
    }

    #[test]
    fn log_axes_print_powers_of_ten_only() {
        let (f, l) = labels(1e-10, 1e-2, true);
        assert_eq!(f, TickFormat::Powers);
        let shown: Vec<&String> = l.iter().filter(|s| !s.is_empty()).collect();
        assert!(shown.len() >= 4, "{l:?}");
        for s in &shown {
            let e: i32 = s
                .strip_prefix("1e")
                .expect("1eN")
                .parse()
                .expect("exponent");
            assert!((-10..=-2).contains(&e), "{l:?}");
        }
        // Two decades: the 2..9 ticks stay unlabelled.
        let (f, l) = labels(1e-3 / 1.5, 5e-2, true);
        assert_eq!(f, TickFormat::Powers, "{l:?}");
        assert!(
            l.iter().all(|s| s.is_empty() || s == "1e-3" || s == "1e-2"),
            "{l:?}"
        );
        // One power of ten: all ticks in one mantissa form.
        let (f, l) = labels(1.5e-3, 4e-2, true);
        assert_eq!(f, TickFormat::LogMantissa(0), "{l:?}");
        assert_eq!(l, ["1e-2", "2e-2", "", ""]);
        // Inside one decade: the axis is widened to the decade.
        let (lo, hi) = bounds([2e-3, 3e-3].into_iter(), true);
        assert!(
            lo < 1e-3 && lo > 0.9e-3 && hi > 1e-2 && hi < 1.1e-2,
            "{lo} {hi}"
        );
        let (f, l) = labels(lo, hi, true);
        assert_eq!(f, TickFormat::Powers, "{l:?}");
        assert!(l.contains(&"1e-3".to_string()) && l.contains(&"1e-2".to_string()));
    }
}
