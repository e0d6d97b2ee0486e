//! Results along a structured strip (issue 10 item 4): per node row of
//! constant t (a cross-section), the reference arclength, the tension, the
//! contact pressure, the slip and the membrane stresses; written as
//! along.csv and plotted as along.svg by the runs in time.

use super::section::{MembraneStress, membrane_stress, tension};
use crate::error::{Error, Result};
use crate::mesh::{CutSide, Grid, Vec3};
use crate::output::plot::{Curve, Panel, draw};
use crate::scene::shell::Units;
use crate::shell::ShellModel;
use crate::shell::time_path::NodeFriction;
use std::path::Path;

/// One cross-section.
#[derive(Clone, Debug, PartialEq)]
pub struct AlongRow {
    /// Reference arclength from row 0 (through the row centroids).
    pub s: f64,
    /// Force across the row (run::section).
    pub tension: f64,
    /// Σ R_N of the row over its tributary reference area (half of each
    /// adjacent element row).
    pub pressure: f64,
    /// Largest slip speed |v_s| of the row's friction nodes (0 if none).
    pub slip_speed: f64,
    /// Friction nodes of the row with |v_s| > `slip_threshold`.
    pub slip_nodes: usize,
    /// Mean membrane stress along the strip of the adjacent elements.
    pub stress_along: f64,
    /// Smallest membrane stress across the strip of the adjacent elements
    /// (negative: the transverse compression that drives wrinkling).
    pub stress_across_min: f64,
    /// Smallest principal membrane stress of the adjacent elements.
    pub stress_min: f64,
}

pub const HEADER: [&str; 8] = [
    "s",
    "tension",
    "pressure",
    "slip_speed",
    "slip_nodes",
    "stress_along",
    "stress_across_min",
    "stress_min",
];

impl AlongRow {
    pub fn values(&self) -> [f64; 8] {
        [
            self.s,
            self.tension,
            self.pressure,
            self.slip_speed,
            self.slip_nodes as f64,
            self.stress_along,
            self.stress_across_min,
            self.stress_min,
        ]
    }
}

fn quad_area(x: &[Vec3; 4]) -> f64 {
    0.5 * (x[2] - x[0]).cross(&(x[3] - x[1])).norm()
}

/// Every row of the structured mesh at the full state; `slip_threshold`
/// tells slip from stick (10 ω Vc, as friction.csv).
pub fn rows(
    model: &ShellModel,
    grid: &Grid,
    quads: &[[usize; 4]],
    thickness: f64,
    full: &[f64],
    friction: &[NodeFriction],
    slip_threshold: f64,
) -> Vec<AlongRow> {
    let mut rn = vec![0.0; grid.ny + 1];
    let mut slip = vec![0.0f64; grid.ny + 1];
    let mut slipping = vec![0usize; grid.ny + 1];
    for f in friction {
        let j = grid.row_index(f.node);
        rn[j] += f.rn;
        let v = f.slip.norm();
        slip[j] = slip[j].max(v);
        if v > slip_threshold {
            slipping[j] += 1;
        }
    }
    let element_rows: Vec<Vec<MembraneStress>> = (0..grid.ny)
        .map(|je| {
            (0..grid.nx)
                .map(|i| membrane_stress(model, grid.element(i, je), full, thickness))
                .collect()
        })
        .collect();
    let element_area: Vec<f64> = (0..grid.ny)
        .map(|je| {
            (0..grid.nx)
                .map(|i| {
                    let q = quads[grid.element(i, je)];
                    quad_area(&q.map(|n| model.x0[n]))
                })
                .sum()
        })
        .collect();
    let centroid = |j: usize| {
        let row = grid.row(j);
        row.iter().map(|&n| model.x0[n]).sum::<Vec3>() / row.len() as f64
    };
    let mut s = 0.0;
    let mut out = Vec::with_capacity(grid.ny + 1);
    for j in 0..=grid.ny {
        if j > 0 {
            s += (centroid(j) - centroid(j - 1)).norm();
        }
        let sides: Vec<usize> = [j.checked_sub(1), (j < grid.ny).then_some(j)]
            .into_iter()
            .flatten()
            .collect();
        let adjacent: Vec<&MembraneStress> =
            sides.iter().flat_map(|&je| &element_rows[je]).collect();
        let area: f64 = sides.iter().map(|&je| 0.5 * element_area[je]).sum();
        out.push(AlongRow {
            s,
            tension: tension(model, &grid.cut(j, quads, CutSide::Both), full),
            pressure: rn[j] / area,
            slip_speed: slip[j],
            slip_nodes: slipping[j],
            stress_along: adjacent.iter().map(|m| m.along).sum::<f64>() / adjacent.len() as f64,
            stress_across_min: adjacent
                .iter()
                .map(|m| m.across)
                .fold(f64::INFINITY, f64::min),
            stress_min: adjacent.iter().map(|m| m.min).fold(f64::INFINITY, f64::min),
        });
    }
    out
}

/// Rows left out at each end of a contact zone by [`pressure_alternation`]:
/// next to a tangent point the pressure alternates by the bent plate's
/// edge reaction (docs/shell-friction.md).
const EDGE_ROWS: usize = 4;

/// Amplitude of a row-to-row alternation of the contact pressure above
/// which the run says so (a share of the zone's mean).
pub const ALTERNATION: f64 = 0.05;

/// The largest row-to-row alternation of the contact pressure inside a
/// contact zone (rows of positive pressure, [`EDGE_ROWS`] left out at each
/// end): max |p_i − (p_(i−1) + p_(i+1)) / 2| / 2 over the zone's mean
/// pressure, with the zone's s range, smallest and largest pressure and
/// mean. Review 18: a strip carried 8.5 mm by a driven roller showed
/// 12–2676 Pa along the whole arc against T/(R b) = 1333 Pa (totals and
/// two-row means right), with no word.
pub fn pressure_alternation(rows: &[AlongRow]) -> Option<(f64, [f64; 2], [f64; 2], f64)> {
    let mut worst: Option<(f64, [f64; 2], [f64; 2], f64)> = None;
    let mut k = 0;
    while k < rows.len() {
        if rows[k].pressure <= 0.0 {
            k += 1;
            continue;
        }
        let start = k;
        while k < rows.len() && rows[k].pressure > 0.0 {
            k += 1;
        }
        if k - start < 2 * EDGE_ROWS + 3 {
            continue;
        }
        let zone = &rows[start + EDGE_ROWS..k - EDGE_ROWS];
        let mean = zone.iter().map(|r| r.pressure).sum::<f64>() / zone.len() as f64;
        let amplitude = zone
            .windows(3)
            .map(|w| (w[1].pressure - 0.5 * (w[0].pressure + w[2].pressure)).abs() / 2.0)
            .fold(0.0, f64::max)
            / mean;
        let range = zone.iter().fold([f64::INFINITY, 0.0f64], |[lo, hi], r| {
            [lo.min(r.pressure), hi.max(r.pressure)]
        });
        if worst.is_none_or(|w| amplitude > w.0) {
            worst = Some((amplitude, [zone[0].s, zone[zone.len() - 1].s], range, mean));
        }
    }
    worst
}

/// along.csv.
pub fn write_csv(path: &Path, rows: &[AlongRow]) -> Result<()> {
    let err = |e: csv::Error| Error::write(path, e.to_string());
    let mut w = csv::Writer::from_path(path).map_err(err)?;
    w.write_record(HEADER).map_err(err)?;
    for r in rows {
        w.write_record(r.values().map(crate::output::csv_number))
            .map_err(err)?;
    }
    w.flush().map_err(|e| Error::write(path, e.to_string()))
}

/// along.svg: tension, slip speed, and the membrane stresses with the
/// contact pressure, against the arclength.
pub fn plot(path: &Path, units: Units, rows: &[AlongRow]) -> Result<()> {
    let s_label = format!("s ({})", units.length);
    let tension = format!("tension ({})", units.force);
    let speed = format!("|v_s| ({}/s)", units.length);
    let stress = format!("stress ({})", units.stress);
    let curve = |label: &'static str, f: fn(&AlongRow) -> f64| Curve {
        label,
        points: rows.iter().map(|r| (r.s, f(r))).collect(),
    };
    draw(
        path,
        &[
            Panel {
                title: "tension along the strip",
                x_label: &s_label,
                y_label: &tension,
                curves: vec![curve("tension", |r| r.tension)],
                log: (false, false),
            },
            Panel {
                title: "largest slip speed of each cross-section",
                x_label: &s_label,
                y_label: &speed,
                curves: vec![curve("slip_speed", |r| r.slip_speed)],
                log: (false, false),
            },
            Panel {
                title: "membrane stresses and contact pressure",
                x_label: &s_label,
                y_label: &stress,
                curves: vec![
                    curve("stress_along", |r| r.stress_along),
                    curve("stress_across_min", |r| r.stress_across_min),
                    curve("stress_min", |r| r.stress_min),
                    curve("pressure", |r| r.pressure),
                ],
                log: (false, false),
            },
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(s: f64, pressure: f64) -> AlongRow {
        AlongRow {
            s,
            tension: 0.0,
            pressure,
            slip_speed: 0.0,
            slip_nodes: 0,
            stress_along: 0.0,
            stress_across_min: 0.0,
            stress_min: 0.0,
        }
    }

    /// A zone whose interior alternates ±50 % around 1000 is measured at
    /// 0.5; the same zone with a uniform interior and alternating edge
    /// rows (the tangent points' reaction) at 0; spans (p = 0) split zones.
    #[test]
    fn the_pressure_alternation_is_measured_inside_the_zones() {
        let zone = |alternate_inside: bool| -> Vec<AlongRow> {
            let mut rows = vec![row(0.0, 0.0)];
            for i in 0..20 {
                let edge = !(EDGE_ROWS..20 - EDGE_ROWS).contains(&i);
                let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
                let p = if edge || alternate_inside {
                    1000.0 * (1.0 + 0.5 * sign)
                } else {
                    1000.0
                };
                rows.push(row(1.0 + i as f64, p));
            }
            rows.push(row(30.0, 0.0));
            rows
        };
        let (a, s, range, mean) = pressure_alternation(&zone(true)).expect("a zone");
        assert!((a - 0.5).abs() < 1e-12, "{a}");
        assert_eq!(s, [1.0 + EDGE_ROWS as f64, 20.0 - EDGE_ROWS as f64]);
        assert_eq!(range, [500.0, 1500.0]);
        assert!((mean - 1000.0).abs() < 1e-9);
        let (a, ..) = pressure_alternation(&zone(false)).expect("a zone");
        assert_eq!(a, 0.0);
        assert!(pressure_alternation(&[row(0.0, 0.0), row(1.0, 5.0)]).is_none());
    }
}
