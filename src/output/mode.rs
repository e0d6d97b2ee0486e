//! A critical or buckling mode on the mesh: its VTK file (on the reference
//! surface, with the mode's displacement and director parts as point data,
//! scaled to a largest displacement of 1) and its dominant wavelength.
//!
//! Wavelength: the mode's normal displacement w = u · n (or, for a mode
//! mostly in the surface's plane, its largest displacement component) is
//! read along the mesh lines through its largest value (chains of element
//! edges, against their arc length: a curved shell is read along its
//! surface), and its wavenumber taken as the Rayleigh quotient
//! k² = ∫ w''² / ∫ w'² (finite differences on the line): exact for
//! sin(k x) and 1 − cos(k x) alike, so a sine with m half-waves over a span
//! a gives 2a/m, and a clamped–free column's n-th mode 1 − cos((2n − 1) pi
//! x / 2L) gives 4L/(2n − 1). The line read is the one with the shortest
//! wavelength 2 pi / k among those along which the mode varies by at least
//! [`FLAT`] of its largest value; its half-waves are k × its length / pi.

use super::vtk::{PointData, write_vtu};
use crate::error::Result;
use crate::fe::dof::index as dof;
use crate::mesh::Vec3;
use serde::Serialize;
use std::path::Path;

/// Dominant wavelength of a mode (module docs).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Wavelength {
    /// "x", "y" or "z": the axis most along the mesh line read.
    pub direction: &'static str,
    /// k × the line's arc length / pi (0.5 for a quarter wave).
    pub half_waves: f64,
    pub wavelength: f64,
    /// The displacement read: "un" (normal) or "ux", "uy", "uz".
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
    let curvatures: Vec<(f64, f64)> = slopes
        .windows(2)
        .map(|w| {
            let dm = w[1].0 - w[0].0;
            ((w[1].1 - w[0].1) / dm, dm)
        })
        .collect();
    // The half cells at the line's ends carry the nearest curvature: left
    // out, ∫ w''² is short by O(h) where the mode curves at its ends (a
    // ring's cos 2θ read 0.934, 0.968, 0.984 half-waves for 1).
    let ends = match (curvatures.first(), curvatures.last()) {
        (Some(a), Some(b)) => {
            0.5 * (a.0 * a.0 * slopes[0].2 + b.0 * b.0 * slopes[slopes.len() - 1].2)
        }
        _ => 0.0,
    };
    let second: f64 = curvatures.iter().map(|(c, dm)| c * c * dm).sum::<f64>() + ends;
    (first > 0.0).then(|| (second / first).sqrt())
}

/// The dominant wavelength of the mode `full` on nodes at `x0` with unit
/// reference normals `normals`, on the mesh `quads` (module docs).
pub fn wavelength(
    x0: &[Vec3],
    normals: &[Vec3],
    quads: &[[usize; 4]],
    full: &[f64],
) -> Option<Wavelength> {
    let n = x0.len();
    let u = |i: usize| Vec3::new(full[dof(i, 0)], full[dof(i, 1)], full[dof(i, 2)]);
    // (component, node) of the largest displacement entry; the normal
    // displacement where it is as large, so that a curved shell is read
    // as such (review 11: a ring's ovalization read in ux gave 1.23, 1.49,
    // 1.79 half-waves a quarter on 16, 32, 64 elements instead of 1).
    let (comp, node) = (0..3)
        .flat_map(|k| (0..n).map(move |i| (k, i)))
        .max_by(|a, b| {
            full[dof(a.1, a.0)]
                .abs()
                .total_cmp(&full[dof(b.1, b.0)].abs())
        })?;
    let big = full[dof(node, comp)].abs();
    if big == 0.0 {
        return None;
    }
    let normal: Vec<f64> = (0..n).map(|i| u(i).dot(&normals[i])).collect();
    let top_normal = (0..n).max_by(|&a, &b| normal[a].abs().total_cmp(&normal[b].abs()))?;
    // The values read: the normal displacement, or the largest component.
    let (start, component, values) = if normal[top_normal].abs() >= 0.5 * big {
        (top_normal, "un", normal)
    } else {
        let values = (0..n).map(|i| full[dof(i, comp)]).collect();
        (node, ["ux", "uy", "uz"][comp], values)
    };
    let value = |i: usize| values[i];
    let largest = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut best: Option<(f64, Wavelength)> = None;
    for line in mesh_lines(quads, n, start) {
        // A line along which the mode barely changes (a column's width,
        // across which it varies by Poisson's ratio alone) has no wave.
        let (lo, hi) = line
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &i| {
                (lo.min(value(i)), hi.max(value(i)))
            });
        if hi - lo < FLAT * largest {
            continue;
        }
        let mut s = 0.0;
        let samples: Vec<(f64, f64)> = line
            .iter()
            .enumerate()
            .map(|(j, &i)| {
                if j > 0 {
                    s += (x0[i] - x0[line[j - 1]]).norm();
                }
                (s, value(i))
            })
            .collect();
        let Some(k) = wavenumber(&samples) else {
            continue;
        };
        let chord = x0[line[line.len() - 1]] - x0[line[0]];
        let axis = chord.iamax();
        let w = Wavelength {
            direction: ["x", "y", "z"][axis],
            half_waves: k * s / std::f64::consts::PI,
            wavelength: 2.0 * std::f64::consts::PI / k,
            component,
        };
        // The shortest wavelength: the wrinkles' pitch across a strip
        // rather than the length of their lobe along the path (review 13:
        // 6.81 "half-waves" over the 3.63 m path of strip-wrinkling, whose
        // mode has 3.05 across the width), m half-waves along a plate's
        // side when a/m is shorter than 2b, and one across it otherwise.
        if best.as_ref().is_none_or(|(kb, _)| k > *kb) {
            best = Some((k, w));
        }
    }
    best.map(|(_, w)| w)
}

/// A mesh line whose values vary by less than this fraction of the mode's
/// largest is not read for a wave.
const FLAT: f64 = 0.1;

/// The mesh lines through `start`: chains of element edges that go
/// straight on at every node (the edge opposite the one they came by: one
/// that shares no element with it), as node lists, one per pair of
/// opposite edges at `start`; a line ends at an edge of the mesh, at a
/// node where going straight on is ambiguous, or where it closes.
fn mesh_lines(quads: &[[usize; 4]], n: usize, start: usize) -> Vec<Vec<usize>> {
    let mut at: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (q, quad) in quads.iter().enumerate() {
        for &i in quad {
            at[i].push(q);
        }
    }
    let neighbours = |i: usize| -> Vec<usize> {
        let mut m: Vec<usize> = at[i]
            .iter()
            .flat_map(|&q| {
                let k = quads[q].iter().position(|&x| x == i).unwrap_or(0);
                [quads[q][(k + 1) % 4], quads[q][(k + 3) % 4]]
            })
            .collect();
        m.sort_unstable();
        m.dedup();
        m
    };
    // The node after `b` coming from `a`: b's neighbour in no element with a.
    let straight_on = |a: usize, b: usize| -> Option<usize> {
        let mut next = neighbours(b).into_iter().filter(|&m| {
            m != a
                && !at[b]
                    .iter()
                    .any(|&q| quads[q].contains(&a) && quads[q].contains(&m))
        });
        let m = next.next()?;
        next.next().is_none().then_some(m)
    };
    let walk = |first: usize| -> Vec<usize> {
        let (mut a, mut b) = (start, first);
        let mut nodes = vec![first];
        while let Some(c) = straight_on(a, b) {
            if c == start || nodes.contains(&c) {
                break;
            }
            nodes.push(c);
            (a, b) = (b, c);
        }
        nodes
    };
    let mut lines = Vec::new();
    let mut used = Vec::new();
    for m in neighbours(start) {
        if used.contains(&m) {
            continue;
        }
        used.push(m);
        let mut line: Vec<usize> = walk(m).into_iter().rev().collect();
        line.push(start);
        if let Some(o) = straight_on(m, start) {
            used.push(o);
            line.extend(
                walk(o)
                    .into_iter()
                    .filter(|x| !line.contains(x))
                    .collect::<Vec<_>>(),
            );
        }
        lines.push(line);
    }
    lines
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A quarter of a ring of radius 1 (`segments` elements around, one
    /// across) with the normal displacement cos(n θ).
    fn ring_mode(segments: usize, n: f64) -> Option<Wavelength> {
        let mut x0 = Vec::new();
        let mut normals = Vec::new();
        for j in 0..=segments {
            let theta = std::f64::consts::FRAC_PI_2 * j as f64 / segments as f64;
            let normal = Vec3::new(theta.cos(), theta.sin(), 0.0);
            for z in [0.0, 0.05] {
                x0.push(normal + Vec3::new(0.0, 0.0, z));
                normals.push(normal);
            }
        }
        let quads: Vec<[usize; 4]> = (0..segments)
            .map(|j| [2 * j, 2 * j + 2, 2 * j + 3, 2 * j + 1])
            .collect();
        let mut full = vec![0.0; 6 * x0.len()];
        for (i, normal) in normals.iter().enumerate() {
            let theta = normal.y.atan2(normal.x);
            for k in 0..3 {
                full[dof(i, k)] = (n * theta).cos() * normal[k];
            }
        }
        wavelength(&x0, &normals, &quads, &full)
    }

    #[test]
    fn a_ring_mode_is_read_along_the_ring() {
        // Review 11: the quarter ring's n = 2 ovalization (one half-wave a
        // quarter) read 1.23, 1.49 and 1.79 half-waves on 16, 32 and 64
        // elements along coordinate lines; along the ring it converges to 1
        // (and n = 4 to 2), as h² with the end cells counted.
        let mut last = f64::INFINITY;
        for segments in [16, 32, 64] {
            let w = ring_mode(segments, 2.0).expect("a wavelength");
            println!("{segments} elements: {w:?}");
            assert_eq!(w.component, "un");
            let error = (w.half_waves - 1.0).abs();
            assert!(error < 0.01 && error < last, "{segments}: {w:?}");
            last = error;
            let w4 = ring_mode(segments, 4.0).expect("a wavelength");
            assert!((w4.half_waves - 2.0).abs() < 0.05, "{segments}: {w4:?}");
        }
    }
}
