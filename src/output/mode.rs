//! A critical or buckling mode on the mesh: its VTK file (on the reference
//! surface, with the mode's displacement and director parts as point data,
//! scaled to a largest displacement of 1) and its dominant wavelength.
//!
//! Wavelength: the mode's largest displacement component w (ux, uy or uz)
//! is read along the nodal line through its largest value, in each
//! coordinate direction in which the mesh extends (nodes at one coordinate
//! averaged), and its wavenumber taken as the Rayleigh quotient
//! k² = ∫ w''² / ∫ w'² (finite differences on the line): exact for
//! sin(k x) and 1 − cos(k x) alike, so a sine with m half-waves over a span
//! a gives 2a/m, and a clamped–free column's n-th mode 1 − cos((2n − 1) pi
//! x / 2L) gives 4L/(2n − 1). The dominant direction is the one with the
//! most half-waves k span / pi; the wavelength is 2 pi / k.

use super::vtk::{PointData, write_vtu};
use crate::error::Result;
use crate::fe::dof::index as dof;
use crate::mesh::Vec3;
use serde::Serialize;
use std::path::Path;

/// Dominant wavelength of a mode (module docs).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Wavelength {
    /// "x", "y" or "z".
    pub direction: &'static str,
    /// k × span / pi along that direction (0.5 for a quarter wave).
    pub half_waves: f64,
    pub wavelength: f64,
    /// The displacement component read ("ux", "uy", "uz").
    pub component: &'static str,
}

/// The mode's full vector (6 per node) scaled to a largest displacement
/// component of 1 in modulus, with the sign that makes that entry positive.
pub fn normalized(full: &[f64], nodes: usize) -> Vec<f64> {
    let mut big = 0.0f64;
    for i in 0..nodes {
        for k in 0..3 {
            let v = full[dof(i, k)];
            if v.abs() > big.abs() {
                big = v;
            }
        }
    }
    if big == 0.0 {
        return full.to_vec();
    }
    full.iter().map(|v| v / big).collect()
}

/// k² = ∫ w''² / ∫ w'² on sorted samples (x, w) (module docs).
fn wavenumber(line: &[(f64, f64)]) -> Option<f64> {
    if line.len() < 3 {
        return None;
    }
    let slopes: Vec<(f64, f64, f64)> = line
        .windows(2)
        .map(|w| {
            let dx = w[1].0 - w[0].0;
            (0.5 * (w[0].0 + w[1].0), (w[1].1 - w[0].1) / dx, dx)
        })
        .collect();
    let first: f64 = slopes.iter().map(|(_, s, dx)| s * s * dx).sum();
    let second: f64 = slopes
        .windows(2)
        .map(|w| {
            let dm = w[1].0 - w[0].0;
            let c = (w[1].1 - w[0].1) / dm;
            c * c * dm
        })
        .sum();
    (first > 0.0).then(|| (second / first).sqrt())
}

/// The dominant wavelength of the mode `full` on nodes at `x0`.
pub fn wavelength(x0: &[Vec3], full: &[f64]) -> Option<Wavelength> {
    let n = x0.len();
    if n == 0 {
        return None;
    }
    // (component, node) of the largest displacement entry.
    let (comp, node) = (0..3)
        .flat_map(|k| (0..n).map(move |i| (k, i)))
        .max_by(|a, b| {
            full[dof(a.1, a.0)]
                .abs()
                .total_cmp(&full[dof(b.1, b.0)].abs())
        })?;
    if full[dof(node, comp)] == 0.0 {
        return None;
    }
    let lo = x0.iter().fold(Vec3::repeat(f64::INFINITY), |m, x| m.inf(x));
    let hi = x0
        .iter()
        .fold(Vec3::repeat(f64::NEG_INFINITY), |m, x| m.sup(x));
    let size = (hi - lo).max();
    let tol = 0.5 * size / (n as f64).sqrt();
    let mut best: Option<Wavelength> = None;
    for d in 0..3 {
        let span = hi[d] - lo[d];
        if span <= 1e-9 * size {
            continue;
        }
        let mut pts: Vec<(f64, f64)> = (0..n)
            .filter(|&i| (0..3).all(|e| e == d || (x0[i][e] - x0[node][e]).abs() <= tol))
            .map(|i| (x0[i][d], full[dof(i, comp)]))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Nodes at one coordinate: averaged.
        let mut line: Vec<(f64, f64, usize)> = vec![];
        for (x, v) in pts {
            match line.last_mut() {
                Some(l) if (x - l.0).abs() <= 1e-9 * size => {
                    l.1 += v;
                    l.2 += 1;
                }
                _ => line.push((x, v, 1)),
            }
        }
        let line: Vec<(f64, f64)> = line.iter().map(|l| (l.0, l.1 / l.2 as f64)).collect();
        let Some(k) = wavenumber(&line) else {
            continue;
        };
        let w = Wavelength {
            direction: ["x", "y", "z"][d],
            half_waves: k * span / std::f64::consts::PI,
            wavelength: 2.0 * std::f64::consts::PI / k,
            component: ["ux", "uy", "uz"][comp],
        };
        if best.is_none_or(|b| w.half_waves > b.half_waves) {
            best = Some(w);
        }
    }
    best
}

/// Where a mode's wrinkles sit and how many there are, on a flat mesh in
/// the plane z = 0 with the mode's largest component uz: the nodal line
/// across y (x = const) through |uz|max, read for its crests (sign changes
/// of uz + 1, entries below 1e-3 of the maximum ignored), and the nodal
/// line along x (y = const) through |uz|max, read for the range of x where
/// |uz| exceeds half its maximum.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Wrinkles {
    /// Crests across the width (wrinkles).
    pub count: usize,
    /// Position of |uz|max.
    pub at: [f64; 2],
    /// [x_min, x_max] where |uz| > max / 2 along x through |uz|max.
    pub extent_x: [f64; 2],
}

/// The [`Wrinkles`] of the mode `full` on nodes `x0` (None when the mode's
/// uz vanishes).
pub fn wrinkles(x0: &[Vec3], full: &[f64]) -> Option<Wrinkles> {
    let n = x0.len();
    let uz = |i: usize| full[dof(i, 2)];
    let top = (0..n).max_by(|&a, &b| uz(a).abs().total_cmp(&uz(b).abs()))?;
    let big = uz(top).abs();
    if big == 0.0 {
        return None;
    }
    let size = x0
        .iter()
        .map(|x| x.amax())
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let on = |i: usize, k: usize| (x0[i][k] - x0[top][k]).abs() <= 1e-9 * size;
    let mut across: Vec<(f64, f64)> = (0..n)
        .filter(|&i| on(i, 0))
        .map(|i| (x0[i][1], uz(i)))
        .collect();
    across.sort_by(|a, b| a.0.total_cmp(&b.0));
    let signs: Vec<bool> = across
        .iter()
        .filter(|p| p.1.abs() > 1e-3 * big)
        .map(|p| p.1 > 0.0)
        .collect();
    let count = 1 + signs.windows(2).filter(|w| w[0] != w[1]).count();
    let along: Vec<f64> = (0..n)
        .filter(|&i| on(i, 1) && uz(i).abs() > 0.5 * big)
        .map(|i| x0[i][0])
        .collect();
    let lo = along.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = along.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Some(Wrinkles {
        count,
        at: [x0[top][0], x0[top][1]],
        extent_x: [lo, hi],
    })
}

/// Writes the mode as a .vtu on the reference surface: point data `mode`
/// (displacement part) and `mode_director` (director part), scaled by
/// [`normalized`].
pub fn write(path: &Path, x0: &[Vec3], quads: &[[usize; 4]], full: &[f64]) -> Result<()> {
    let m = normalized(full, x0.len());
    let part = |off: usize| -> Vec<Vec3> {
        (0..x0.len())
            .map(|i| Vec3::new(m[dof(i, off)], m[dof(i, off + 1)], m[dof(i, off + 2)]))
            .collect()
    };
    write_vtu(
        path,
        x0,
        quads,
        &[
            PointData::Vector("mode", part(0)),
            PointData::Vector("mode_director", part(3)),
        ],
    )
}
