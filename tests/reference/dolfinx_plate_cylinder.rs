//! plate-cylinder (paper §2.2, DESIGN §4) against an independent FEniCSx /
//! dolfinx 0.5.2 solution (reference/dolfinx/plate_cylinder.py: 3D St
//! Venant-Kirchhoff solid, 27-node hexahedra, 160 x 2 x 1 elements, Newton
//! with load stepping; data in reference/data/plate-cylinder/, see
//! reference/README.md).
//!
//! ```text
//!            ___
//!          /     \   rigid cylinder, D = 1 m, centre (1, 0, 0.5001)
//!          \ ___ /
//!   |=================  strip 2 m x 0.2 m x 0.8 mm, clamped at x = 0
//!   |                ^ 3 x 10 lambda N at x = 2
//! ```
//! Tolerances (issue 4): uz_A and ux_A within 1% of their max over lambda in
//! [0, 1]; total contact force within 3%; contact-zone ends within 0.02 m;
//! deformed mid-surface within 1% of the max displacement. Row forces at B,
//! C, D are mesh-dependent: reported side by side, not asserted.

#![cfg(feature = "reference")]

use anm::run::{RunReport, Snapshot, run_loaded};
use std::path::Path;
use std::sync::OnceLock;

const MESH: &str = "nx160_ny2";

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The ANM run of the canonical scene on the 0.025 m mesh, shared by the
/// tests (the 0.05 m mesh resolves the contact-zone ends only to its node
/// spacing, and deviates by up to 1.4% in uz_A during the sliding-line phase).
fn anm() -> &'static RunReport {
    static RUN: OnceLock<RunReport> = OnceLock::new();
    RUN.get_or_init(|| {
        let scene = anm::scene::shell::load(&root().join("scenes/plate-cylinder-fine.toml"))
            .expect("scene");
        let r = run_loaded(&scene, None, false).expect("ANM run");
        assert_eq!(r.stop.reason, "end", "{:?}", r.stop);
        r
    })
}

/// dolfinx curves: lambda, uz_A, ux_A, rn_B, rn_C, rn_D, rn_total, x_lo, x_hi.
fn reference() -> Vec<Vec<f64>> {
    let path = root().join(format!("reference/data/plate-cylinder/curves_{MESH}.csv"));
    let mut r = csv::Reader::from_path(&path).expect("reference curves");
    r.records()
        .map(|rec| {
            rec.unwrap()
                .iter()
                .map(|x| x.parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect()
}

/// Linear interpolation of column j of the reference at lambda.
fn interp(rows: &[Vec<f64>], j: usize, lambda: f64) -> f64 {
    let k = rows
        .iter()
        .position(|r| r[0] >= lambda - 1e-12)
        .expect("lambda within the reference");
    if k == 0 || (rows[k][0] - lambda).abs() < 1e-12 {
        return rows[k][j];
    }
    let (a, b) = (&rows[k - 1], &rows[k]);
    a[j] + (b[j] - a[j]) * (lambda - a[0]) / (b[0] - a[0])
}

#[test]
fn tip_displacements_within_one_percent_of_their_max() {
    let (anm, refr) = (anm(), reference());
    println!("lambda   uz_A ANM   uz_A dolfinx   ux_A ANM   ux_A dolfinx");
    for (col, name) in [(1, "uz_A"), (2, "ux_A")] {
        let max = refr.iter().map(|r| r[col].abs()).fold(0.0, f64::max);
        let mut worst: (f64, f64) = (0.0, 0.0);
        for row in anm.history.iter().filter(|r| r[0] > 0.0) {
            let d = (row[col] - interp(&refr, col, row[0])).abs() / max;
            if d > worst.0 {
                worst = (d, row[0]);
            }
        }
        println!(
            "{name}: max |ANM - dolfinx| / max|dolfinx| = {:.3e} at lambda = {:.2}",
            worst.0, worst.1
        );
        assert!(
            worst.0 <= 0.01,
            "{name}: {:.3e} at lambda = {}",
            worst.0,
            worst.1
        );
    }
    for l in [0.05, 0.1, 0.2, 0.5, 1.0] {
        let a = anm
            .history
            .iter()
            .find(|r| (r[0] - l).abs() < 1e-9)
            .unwrap();
        println!(
            "{l:<8} {:<10.5} {:<14.5} {:<10.5} {:.5}",
            a[1],
            interp(&refr, 1, l),
            a[2],
            interp(&refr, 2, l)
        );
    }
}

#[test]
fn total_contact_force_within_three_percent_and_row_forces_side_by_side() {
    let (anm, refr) = (anm(), reference());
    println!("lambda   rn_total ANM  dolfinx   | rn_B ANM / dolfinx | rn_C | rn_D");
    let mut worst: f64 = 0.0;
    for l in [0.05, 0.1, 0.2, 0.5, 1.0] {
        let a = anm
            .history
            .iter()
            .find(|r| (r[0] - l).abs() < 1e-9)
            .unwrap();
        let want = interp(&refr, 6, l);
        let d = (a[6] - want).abs() / want.abs();
        worst = worst.max(d);
        println!(
            "{l:<8} {:<13.4} {:<9.4} | {:.4} / {:.4} | {:.4} / {:.4} | {:.4} / {:.4}",
            a[6],
            want,
            a[3],
            interp(&refr, 3, l),
            a[4],
            interp(&refr, 4, l),
            a[5],
            interp(&refr, 5, l)
        );
        assert!(
            d <= 0.03,
            "rn_total at lambda = {l}: ANM {} vs dolfinx {want} ({d:.3e})",
            a[6]
        );
    }
    println!("max relative deviation of rn_total: {worst:.3e}");
}

fn snapshot(l: f64) -> &'static Snapshot {
    anm()
        .snapshots
        .iter()
        .find(|s| (s.lambda - l).abs() < 1e-9)
        .expect("snapshot")
}

#[test]
fn contact_zone_ends_within_two_centimetres() {
    let refr = reference();
    println!("lambda   ANM zone            dolfinx zone   (nodes with R > 1e-3 N)");
    let mut failures = vec![];
    for l in [0.1, 0.2, 0.5, 1.0] {
        let (lo, hi) = snapshot(l)
            .contact_zone(1e-3)
            .expect("contact at this load");
        let (rlo, rhi) = (interp(&refr, 7, l), interp(&refr, 8, l));
        println!("{l:<8} [{lo:.4}, {hi:.4}]    [{rlo:.4}, {rhi:.4}]");
        if (lo - rlo).abs() > 0.02 || (hi - rhi).abs() > 0.02 {
            failures.push((l, lo, hi, rlo, rhi));
        }
    }
    assert!(
        failures.is_empty(),
        "zone ends off by more than 0.02 m: {failures:?}"
    );
}

#[test]
fn deformed_mid_surface_within_one_percent_of_max_displacement() {
    let file = hdf5::File::open(root().join(format!(
        "reference/data/plate-cylinder/midsurface_{MESH}.h5"
    )))
    .expect("reference HDF5");
    for l in [0.1, 0.5, 1.0] {
        let g = file.group(&format!("lambda_{l}")).expect("group");
        let x: ndarray::Array2<f64> = g.dataset("X").unwrap().read_2d().unwrap();
        let u: ndarray::Array2<f64> = g.dataset("u").unwrap().read_2d().unwrap();
        let s = snapshot(l);
        let umax = u
            .rows()
            .into_iter()
            .map(|r| r.dot(&r).sqrt())
            .fold(0.0, f64::max);
        let mut worst: f64 = 0.0;
        for (xr, ur) in x.rows().into_iter().zip(u.rows()) {
            let ua = interpolate_on_strip(s, [xr[0], xr[1]]);
            let d = ((ua[0] - ur[0]).powi(2) + (ua[1] - ur[1]).powi(2) + (ua[2] - ur[2]).powi(2))
                .sqrt();
            worst = worst.max(d / umax);
        }
        println!(
            "lambda = {l}: max |u_ANM - u_dolfinx| / max|u| = {worst:.3e} over {} reference nodes (max |u| = {umax:.4} m)",
            x.nrows()
        );
        assert!(worst <= 0.01, "lambda = {l}: {worst:e}");
    }
}

/// The ANM displacement at reference point (x, y) of the flat strip: bilinear
/// interpolation in the structured grid of ANM nodes (the element's own
/// shape functions on its rectangular cells).
fn interpolate_on_strip(s: &Snapshot, p: [f64; 2]) -> [f64; 3] {
    let mut xs: Vec<f64> = s.x0.iter().map(|x| x[0]).collect();
    let mut ys: Vec<f64> = s.x0.iter().map(|x| x[1]).collect();
    for v in [&mut xs, &mut ys] {
        v.sort_by(f64::total_cmp);
        v.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    }
    let cell = |v: &[f64], t: f64| {
        let i = v
            .iter()
            .position(|&a| a > t + 1e-12)
            .unwrap_or(v.len() - 1)
            .clamp(1, v.len() - 1);
        (i - 1, (t - v[i - 1]) / (v[i] - v[i - 1]))
    };
    let (i, sx) = cell(&xs, p[0]);
    let (j, sy) = cell(&ys, p[1]);
    let node = |x: f64, y: f64| {
        s.x0.iter()
            .position(|q| (q[0] - x).abs() < 1e-9 && (q[1] - y).abs() < 1e-9)
            .expect("structured grid node")
    };
    let corners = [
        (i, j, (1.0 - sx) * (1.0 - sy)),
        (i + 1, j, sx * (1.0 - sy)),
        (i, j + 1, (1.0 - sx) * sy),
        (i + 1, j + 1, sx * sy),
    ];
    let mut u = [0.0; 3];
    for (a, b, w) in corners {
        let n = node(xs[a], ys[b]);
        for (uk, dk) in u.iter_mut().zip(s.displacement[n]) {
            *uk += w * dk;
        }
    }
    u
}
