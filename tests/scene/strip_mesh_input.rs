//! The `strip` mesh and the `tension` probe (issue 10 item 4): the
//! conveying scene is read with its roller groups; bad paths, bad roller
//! references and probes on groups that are not cross-sections stop with
//! errors naming the file and the key.

use super::edited::{edited, expect_invalid};
use crate::scratch::ScratchFile;
use anm::scene::shell::{Quantity, load};
use std::path::Path;

const BASE: &str = "scenes/strip-conveying.toml";

/// The base scene with `edits` (old, new) applied.
fn scene(name: &str, edits: &[(&str, &str)]) -> ScratchFile {
    edited(BASE, "strip-mesh-input", name, edits)
}

/// The wrap angles of the scene's rollers (30, 90, 60 degrees) from the
/// mesh: the turn of the path between a roller's entry and exit rows.
#[test]
fn the_conveying_strip_wraps_its_rollers_by_the_designed_angles() {
    let s = load(Path::new(BASE)).unwrap();
    let grid = s.mesh.grid.expect("a structured mesh");
    for (name, degrees) in [("r1", 30.0), ("r2", 90.0), ("r3", 60.0)] {
        let row = |g: &str| {
            grid.row_of(&s.mesh.groups[&format!("{name}_{g}")])
                .expect("a row")
        };
        let (j_in, j_out) = (row("in"), row("out"));
        let direction = |j: usize| {
            (s.mesh.nodes[grid.node(0, j + 1)] - s.mesh.nodes[grid.node(0, j)]).normalize()
        };
        // The chords of the first and last arc elements lean by half an
        // element angle into the arc.
        let chord =
            (s.mesh.nodes[grid.node(0, j_in + 1)] - s.mesh.nodes[grid.node(0, j_in)]).norm();
        let dphi = 2.0 * (chord / (2.0 * 0.30000001)).asin();
        let turned = direction(j_in)
            .dot(&direction(j_out - 1))
            .clamp(-1.0, 1.0)
            .acos()
            + dphi;
        println!(
            "{name}: wrap {:.6} degrees (designed {degrees})",
            turned.to_degrees()
        );
        // The roller centres were placed for R = 0.3; the strip runs at
        // R + 1e-8, which turns its tangents by ~1e-8 rad (6e-7 degrees).
        assert!(
            (turned.to_degrees() - degrees).abs() < 1e-5,
            "{name}: {}",
            turned.to_degrees()
        );
    }
    assert!(
        s.probes
            .iter()
            .any(|p| matches!(p.quantity, Quantity::Tension { .. }))
    );
    assert!(s.mesh.groups.contains_key("wrapped"));
}

#[test]
fn bad_strip_meshes_name_the_key() {
    let cases: &[(&str, &str, &str, &str, &str)] = &[
        (
            "unknown-roller.toml",
            "rollers = [\"r1\", \"r2\", \"r3\"]",
            "rollers = [\"r1\", \"r9\", \"r3\"]",
            "mesh.rollers[1]",
            "no obstacle named `r9`",
        ),
        (
            "turn-count.toml",
            "turn = [\"cw\", \"ccw\", \"cw\"]",
            "turn = [\"cw\", \"ccw\"]",
            "mesh.turn",
            "2 turns for 3 rollers",
        ),
        (
            "turn-name.toml",
            "turn = [\"cw\", \"ccw\", \"cw\"]",
            "turn = [\"cw\", \"left\", \"cw\"]",
            "mesh.turn[1]",
            "`left`",
        ),
        (
            "overlap.toml",
            "centre = [0.0, 1.1660254037844386, 0.019615242270663302]",
            "centre = [0.0, 0.4, 0.0]",
            "mesh.rollers",
            "from roller `r1` to roller `r2`: they overlap",
        ),
        (
            "start-inside.toml",
            "start = [-0.5, 0.30000001]",
            "start = [0.0, 0.1]",
            "mesh.rollers",
            "the start point",
        ),
        (
            "no-offset.toml",
            "offset = 1e-8",
            "offset = 0.0",
            "mesh.offset",
            "> 0",
        ),
        (
            "no-across.toml",
            "divisions_across = 8",
            "divisions_across = 0",
            "mesh.divisions_across",
            "1 to 1e6",
        ),
        (
            "axis-y.toml",
            "axis = [1.0, 0.0, 0.0]",
            "axis = [0.0, 1.0, 0.0]",
            "mesh.rollers[0]",
            "along x",
        ),
        (
            "angle-key.toml",
            "divisions_across = 8",
            "divisions_across = 8\nangle = [0.0, 10.0]",
            "mesh.angle",
            "not used by a mesh of type `strip`",
        ),
        (
            "start-on-rectangle.toml",
            "type = \"strip\"",
            "type = \"rectangle\"",
            "mesh.start",
            "not used by a mesh of type `rectangle`",
        ),
    ];
    for (name, old, new, key, part) in cases {
        expect_invalid(&scene(name, &[(old, new)]), key, part);
    }
}

#[test]
fn a_tension_probe_needs_a_cross_section() {
    let p = scene(
        "tension-on-arc.toml",
        &[(
            "quantity = \"tension\"\ngroup = \"r1_in\"",
            "quantity = \"tension\"\ngroup = \"r1_arc\"",
        )],
    );
    expect_invalid(&p, "probe[1]", "one node row of constant t");
    let p = scene(
        "tension-on-point.toml",
        &[(
            "quantity = \"tension\"\ngroup = \"r1_in\"",
            "quantity = \"tension\"\npoint = [0.0, 2.6856406460551017, 0.8856406560551019]",
        )],
    );
    expect_invalid(&p, "probe[1]", "one node row of constant t");
}

/// `probe.side`: one of three words, only on a `tension` probe, and a side
/// that has elements (t1 is the strip's last row).
#[test]
fn a_tension_probe_side_is_checked() {
    let p = scene(
        "side-word.toml",
        &[("side = \"before\"", "side = \"upstream\"")],
    );
    expect_invalid(&p, "probe[5].side", "\"both\", \"before\" or \"after\"");
    let p = scene(
        "side-at-end.toml",
        &[(
            "quantity = \"tension\"\ngroup = \"t1\"",
            "quantity = \"tension\"\ngroup = \"t1\"\nside = \"after\"",
        )],
    );
    expect_invalid(&p, "probe[0].side", "no elements after it");
    let p = scene(
        "side-on-uy.toml",
        &[("quantity = \"uy\"", "quantity = \"uy\"\nside = \"before\"")],
    );
    expect_invalid(&p, ".side", "only by `tension`");
    // The end row's one side, named, is accepted.
    let p = scene(
        "side-end-ok.toml",
        &[(
            "quantity = \"tension\"\ngroup = \"t1\"",
            "quantity = \"tension\"\ngroup = \"t1\"\nside = \"before\"",
        )],
    );
    anm::scene::shell::load(&p).expect("t1 has elements before it");
}

/// `anm check` shows what the strip mesher worked out: the path's length
/// and each roller's wrap angle.
#[test]
fn check_prints_the_strip_path() {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_anm"))
        .arg("check")
        .arg(BASE)
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    println!("{out}");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for part in [
        "1413 nodes, 1248 elements",
        "strip path 3.94",
        "r1 30.0000",
        "r2 90.0000",
        "r3 60.0000",
    ] {
        assert!(out.contains(part), "`{out}` lacks `{part}`");
    }
}

/// A crowned roll (`obstacle.crown`, `face`): the strip of
/// strip-wrinkling.toml runs at the radius of its middle section, so its
/// middle row starts at the path's offset from the roll and its edges off
/// it by the crown's fall there (0.5 mm at ±0.5 m for 0.5 mm over a 1 m
/// face); bad crowns name the key.
#[test]
fn a_crowned_roll_is_read_and_bad_crowns_name_the_key() {
    let sc = load(Path::new("scenes/strip-wrinkling.toml")).expect("scene");
    let roll = &sc.obstacles[0].shape;
    let arc = &sc.mesh.groups["roll_arc"];
    let gaps: Vec<(f64, f64)> = arc
        .iter()
        .map(|&n| {
            let x = sc.mesh.nodes[n];
            (x.x, roll.gap(&x).expect("a gap").h)
        })
        .collect();
    for &(x, h) in &gaps {
        let expected = 1e-8 + 5e-4 * (2.0 * x).powi(2);
        assert!(
            (h - expected).abs() < 1e-12,
            "gap {h} at x = {x}, expected {expected}"
        );
    }
    let base = "scenes/strip-wrinkling.toml";
    let cases: &[(&str, &str, &str, &str, &str)] = &[
        (
            "no-face.toml",
            "face = 1.0\n",
            "",
            "obstacle[0].face",
            "missing",
        ),
        (
            "no-crown.toml",
            "crown = 5e-4\n",
            "",
            "obstacle[0].face",
            "without `crown`",
        ),
        (
            "negative.toml",
            "crown = 5e-4",
            "crown = -5e-4",
            "obstacle[0].crown",
            ">= 0",
        ),
        (
            "too-big.toml",
            "crown = 5e-4",
            "crown = 0.5",
            "obstacle[0].crown",
            "below the radius",
        ),
        (
            "zero-face.toml",
            "face = 1.0",
            "face = 0.0",
            "obstacle[0].face",
            "> 0",
        ),
    ];
    for (name, old, new, key, part) in cases {
        let p = edited(base, "crown-input", name, &[(old, new)]);
        expect_invalid(&p, key, part);
    }
}

/// Input a new user's scenes got through (this session's review): a path
/// that ends where it starts, a path through a cylinder it does not wrap,
/// and a static method with [friction].
/// A file name, its edits (old, new), the key and a part of the message.
type Case<'a> = (&'a str, &'a [(&'a str, &'a str)], &'a str, &'a str);

#[test]
fn loops_unwrapped_cylinders_and_static_methods_are_refused() {
    let base = format!("{}/{BASE}", env!("CARGO_MANIFEST_DIR"));
    let cases: [Case; 4] = [
        // Review 3: a strip that touches r1 over 1e-4 degrees (its one arc
        // element a sliver) passed `check` and collapsed at t = 1.2e-9 s.
        (
            "sliver.toml",
            &[
                (
                    "end = [2.6856406460551017, 0.8856406560551019]",
                    "end = [0.5, 0.29999901]",
                ),
                ("rollers = [\"r1\", \"r2\", \"r3\"]", "rollers = [\"r1\"]"),
                ("turn = [\"cw\", \"ccw\", \"cw\"]", "turn = [\"cw\"]"),
            ],
            "mesh.turn[0]",
            "wraps roller `r1` by 1.146e-4 degrees only",
        ),
        (
            "loop.toml",
            &[(
                "end = [2.6856406460551017, 0.8856406560551019]",
                "end = [-0.5, 0.30000001]",
            )],
            "mesh.end",
            "does not close a loop",
        ),
        // r3 dropped from the rollers: the path's last straight piece, from
        // r2 to the end point, ran through it (the strip started inside it).
        (
            "through.toml",
            &[
                (
                    "rollers = [\"r1\", \"r2\", \"r3\"]",
                    "rollers = [\"r1\", \"r2\"]",
                ),
                (
                    "turn = [\"cw\", \"ccw\", \"cw\"]",
                    "turn = [\"cw\", \"ccw\"]",
                ),
            ],
            "mesh.rollers",
            "passes through obstacle[2] `r3`",
        ),
        (
            "newton.toml",
            &[("eps = 1e-6\n", "method = \"newton\"\n")],
            "solver.method",
            "[friction]",
        ),
    ];
    for (name, edits, key, part) in cases {
        let f = edited(&base, "strip-review", name, edits);
        expect_invalid(&f, key, part);
    }
}
