//! The `[friction]` table of shell scenes (issue 10 items 2 and 7): a valid
//! table, bad values and missing drivers stop with errors naming the file
//! and the key; an obstacle motion that only friction would feel, in a scene
//! without friction, is allowed with a warning (the keys' documentation:
//! tests/scene/docs.rs).

use super::edited::{edited, expect_invalid};
use crate::scratch::ScratchFile;
use anm::Error;
use anm::contact::FrictionLaw;
use anm::scene::shell::load;
use anm::shell::ramp::Ramp;
use std::path::Path;

const BASE: &str = "tests/data/shell-friction.toml";

/// The base scene with `edits` (old, new) applied.
fn scene(name: &str, edits: &[(&str, &str)]) -> ScratchFile {
    edited(BASE, "shell-friction-input", name, edits)
}

#[test]
fn the_friction_table_is_read() {
    let s = load(Path::new(BASE)).unwrap();
    let fr = s.friction.expect("[friction]");
    assert_eq!(
        fr.law,
        FrictionLaw {
            f: 0.2,
            q: 0.0,
            vc: 0.1,
            omega: 1e-3,
            zeta: Some(1e-6)
        }
    );
    assert_eq!(fr.t_end, 2.0);
    assert_eq!(
        fr.load,
        Ramp {
            start: 0.0,
            end: 0.5
        }
    );
    assert_eq!(
        fr.motion,
        Ramp {
            start: 0.5,
            end: 0.6
        }
    );
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

#[test]
fn bad_friction_values_name_the_key() {
    let cases: &[(&str, &str, &str, &str)] = &[
        ("negative-f.toml", "f = 0.2", "f = -0.1", "friction.f"),
        ("q-above.toml", "q = 0.0", "q = 1.5", "friction.q"),
        ("q-below.toml", "q = 0.0", "q = -0.2", "friction.q"),
        ("vc-zero.toml", "Vc = 0.1", "Vc = 0.0", "friction.Vc"),
        (
            "omega-zero.toml",
            "omega = 1e-3",
            "omega = 0.0",
            "friction.omega",
        ),
        (
            "zeta-negative.toml",
            "zeta = 1e-6",
            "zeta = -1.0",
            "friction.zeta",
        ),
        (
            "t-end-zero.toml",
            "t_end = 2.0",
            "t_end = 0.0",
            "friction.t_end",
        ),
        (
            "ramp-backward.toml",
            "load_ramp = [0.0, 0.5]",
            "load_ramp = [0.5, 0.2]",
            "friction.load_ramp",
        ),
        // Review 4: a jump at 0.3 s ended in a step collapse blamed on
        // friction.
        (
            "ramp-jump.toml",
            "load_ramp = [0.0, 0.5]",
            "load_ramp = [0.3, 0.3]",
            "friction.load_ramp",
        ),
        (
            "ramp-late.toml",
            "motion_ramp = [0.5, 0.6]",
            "motion_ramp = [3.0, 4.0]",
            "friction.motion_ramp",
        ),
    ];
    for (name, old, new, key) in cases {
        let p = scene(name, &[(old, new)]);
        let problem = match *key {
            "friction.f" | "friction.load_ramp" | "friction.motion_ramp" => "",
            _ => "must",
        };
        expect_invalid(&p, key, problem);
    }
    // The penalty law (eta = 0) is for frictionless scenes.
    expect_invalid(
        &scene("eta-zero.toml", &[("eta = 1e-6", "eta = 0.0")]),
        "contact.eta",
        "frictionless",
    );
    // The range is stated: f > 0, q in [0, 1]; f = 0 (no equation for
    // the slip velocities: a singular tangent at step 0) says how to model
    // frictionless contact.
    expect_invalid(
        &scene("nf.toml", &[("f = 0.2", "f = -0.1")]),
        "friction.f",
        "> 0",
    );
    expect_invalid(
        &scene("f0.toml", &[("f = 0.2", "f = 0.0")]),
        "friction.f",
        "without [friction]",
    );
    // Keys of the continuation in lambda are refused in time.
    for (key, line) in [
        ("solver.pade", "pade = true"),
        ("solver.branch", "branch = \"secondary\""),
        ("solver.contact_arclength", "contact_arclength = 1.0"),
    ] {
        let p = scene(
            "lambda-key.toml",
            &[("[solver]\n", &format!("[solver]\n{line}\n"))],
        );
        expect_invalid(&p, key, "not to a scene in time");
    }
    // fields.h5 holds snapshots of the lambda grid: a run in time wrote
    // none and said nothing.
    expect_invalid(
        &scene(
            "hdf5-in-time.toml",
            &[("[output]\n", "[output]\nhdf5 = true\n")],
        ),
        "output.hdf5",
        "not to a scene in time",
    );
    expect_invalid(
        &scene(
            "late-output.toml",
            &[("t_end = 2.0", "t_end = 2.0\noutput_step = 3.0")],
        ),
        "friction.output_step",
        "at most t_end",
    );
    expect_invalid(
        &scene("vc-huge.toml", &[("Vc = 0.1", "Vc = 1e300")]),
        "friction.Vc",
        "out of the range of a double",
    );
    expect_invalid(
        &scene("q.toml", &[("q = 0.0", "q = 1.5")]),
        "friction.q",
        "[0, 1]",
    );
    // Viscous friction (q = 1) needs no slip regularization.
    let p = scene(
        "viscous.toml",
        &[("q = 0.0", "q = 1.0"), ("omega = 1e-3", "omega = 0.0")],
    );
    assert!(load(&p).is_ok());
}

#[test]
fn friction_needs_something_that_moves_in_time() {
    let still = ("velocity = [0.1, 0.0, 0.0]", "velocity = [0.0, 0.0, 0.0]");
    // No obstacle motion and a load full from t = 0: nothing moves.
    let p = scene("still.toml", &[still, ("load_ramp = [0.0, 0.5]\n", "")]);
    expect_invalid(&p, "friction", "nothing moves in time");
    // No load at all and a fixed floor: the same error (not the lambda one).
    let p = scene(
        "still-unloaded.toml",
        &[
            still,
            ("[[load]]\ngroup = \"tip\"\nforce = [0.0, 0.0, -0.5]\n", ""),
        ],
    );
    expect_invalid(&p, "friction", "nothing moves in time");
    // A load that rises in time is enough; so is a turning obstacle.
    assert!(load(&scene("ramped.toml", &[still])).is_ok());
    let p = scene(
        "turning.toml",
        &[
            still,
            ("load_ramp = [0.0, 0.5]\n", ""),
            (
                "type = \"plane\"\npoint = [0.0, 0.0, -0.01]\nnormal = [0.0, 0.0, 1.0]\nmotion = { type = \"translate\", velocity = [0.0, 0.0, 0.0] }",
                "type = \"cylinder\"\ncentre = [1.0, 0.0, -0.51]\naxis = [0.0, 1.0, 0.0]\nradius = 0.5\nmotion = { type = \"rotate\", omega = 0.2 }",
            ),
        ],
    );
    assert!(load(&p).is_ok());
    // Friction without contact.
    let p = scene(
        "no-contact.toml",
        &[(
            "[contact]\ngroup = \"tip\"\nk = 1e9\neta = 1e-6\nsearch_distance = 1.0\n",
            "",
        )],
    );
    expect_invalid(&p, "friction", "[contact]");
}

#[test]
fn a_motion_only_friction_feels_warns_without_friction() {
    let frictionless = (
        "[friction]\nf = 0.2\nq = 0.0\nVc = 0.1\nomega = 1e-3\nzeta = 1e-6\nt_end = 2.0\nload_ramp = [0.0, 0.5]\nmotion_ramp = [0.5, 0.6]\n",
        "",
    );
    // The floor slides within its own plane: allowed, with a warning.
    let p = scene("sliding-floor.toml", &[frictionless]);
    let s = load(&p).unwrap();
    assert!(s.friction.is_none());
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    let w = &s.warnings[0];
    assert!(
        w.contains("sliding-floor.toml")
            && w.contains("obstacle[0].motion")
            && w.contains("[friction]"),
        "{w}"
    );
    // A floor that approaches the strip changes gaps: no warning.
    let p = scene(
        "rising-floor.toml",
        &[
            frictionless,
            ("velocity = [0.1, 0.0, 0.0]", "velocity = [0.0, 0.0, 0.01]"),
        ],
    );
    assert!(load(&p).unwrap().warnings.is_empty());
    // The same scene with [friction] is a problem in time: the static path
    // refuses it rather than drop the friction.
    let s = load(Path::new(BASE)).unwrap();
    let e = anm::run::shell::run_loaded(&s, None, false).unwrap_err();
    assert!(
        matches!(&e, Error::Invalid { key, .. } if key == "friction"),
        "{e}"
    );
}

#[test]
fn in_time_a_translation_must_keep_the_surface_in_place() {
    // The obstacle's shape stays where the scene puts it in time; a
    // translation out of its surface would change the gaps.
    let p = scene(
        "rising-floor-friction.toml",
        &[("velocity = [0.1, 0.0, 0.0]", "velocity = [0.0, 0.0, 0.01]")],
    );
    expect_invalid(&p, "obstacle[0].motion", "surface");
    let p = scene(
        "output-step.toml",
        &[("t_end = 2.0\n", "t_end = 2.0\noutput_step = -1.0\n")],
    );
    expect_invalid(&p, "friction.output_step", "> 0");
}

#[test]
fn time_step_is_read_and_bad_values_are_named() {
    use anm::shell::time_path::Stepping;
    // Default: auto; "implicit" and "explicit" select one step.
    assert_eq!(
        load(Path::new(BASE)).unwrap().friction.unwrap().stepping,
        Stepping::Auto
    );
    for (name, stepping) in [
        ("implicit", Stepping::Implicit),
        ("explicit", Stepping::Explicit),
    ] {
        let p = scene(
            &format!("{name}.toml"),
            &[("[solver]\n", &format!("[solver]\ntime_step = \"{name}\"\n"))],
        );
        assert_eq!(load(&p).unwrap().friction.unwrap().stepping, stepping);
    }
    expect_invalid(
        &scene(
            "time-step-bad.toml",
            &[("[solver]\n", "[solver]\ntime_step = \"rosenbrock\"\n")],
        ),
        "solver.time_step",
        "\"auto\", \"implicit\" or \"explicit\"",
    );
    // A static scene (no [friction]) has no steps in time.
    let text = std::fs::read_to_string("scenes/verification/sliding-plate.toml").unwrap();
    let start = text.find("[friction]").unwrap();
    let end = text[start..].find("\n\n").unwrap() + start;
    let mut text = format!("{}{}", &text[..start], &text[end..]);
    text = text.replacen("[solver]\n", "[solver]\ntime_step = \"implicit\"\n", 1);
    let p = ScratchFile::with_text("shell-friction-input", "static-time-step.toml", &text);
    expect_invalid(&p, "solver.time_step", "[friction]");
}

/// `load.ramp` (a load with its own time function, issue 10 item 3c): read
/// with [friction]; refused without it, on a follower load, and with bad
/// values, each naming the key.
#[test]
fn a_load_ramp_is_read_and_bad_ones_are_named() {
    let p = scene(
        "own-ramp.toml",
        &[(
            "force = [0.0, 0.0, -0.5]",
            "force = [0.0, 0.0, -0.5]\nramp = [0.2, 0.4]",
        )],
    );
    let s = load(&p).unwrap();
    assert_eq!(
        s.friction.expect("[friction]").load_ramps,
        vec![(
            0,
            Ramp {
                start: 0.2,
                end: 0.4
            }
        )]
    );
    for (name, ramp, part) in [
        (
            "own-ramp-backward.toml",
            "ramp = [0.4, 0.2]",
            "start <= end",
        ),
        (
            "own-ramp-late.toml",
            "ramp = [3.0, 4.0]",
            "start < friction.t_end",
        ),
        ("own-ramp-negative.toml", "ramp = [-1.0, 0.2]", ">= 0"),
    ] {
        let p = scene(
            name,
            &[(
                "force = [0.0, 0.0, -0.5]",
                &format!("force = [0.0, 0.0, -0.5]\n{ramp}"),
            )],
        );
        expect_invalid(&p, "load[0].ramp", part);
    }
    let p = scene(
        "own-ramp-moment.toml",
        &[(
            "force = [0.0, 0.0, -0.5]",
            "moment = [0.0, 0.0, 0.5]\nramp = [0.0, 0.4]",
        )],
    );
    expect_invalid(&p, "load[0].ramp", "only a dead load");
    let text = std::fs::read_to_string(BASE).unwrap();
    let start = text.find("[friction]").unwrap();
    let end = text[start..]
        .find("\n[[")
        .or_else(|| text[start..].find("\n[solver]"))
        .unwrap();
    let without = format!("{}{}", &text[..start], &text[start + end + 1..]).replacen(
        "force = [0.0, 0.0, -0.5]",
        "force = [0.0, 0.0, -0.5]\nramp = [0.0, 0.4]",
        1,
    );
    let p = ScratchFile::with_text("shell-friction-input", "own-ramp-static.toml", &without);
    expect_invalid(&p, "load[0].ramp", "applies to scenes in time");
}

#[test]
fn an_obstacle_out_of_reach_of_every_contact_node_is_a_warning() {
    // The floor 5 m below the strip, contact.search_distance 1 m: with
    // friction the law's faint pull leaves the strip free and a run in time
    // crawls (a new user's scene: 5,102 steps to t = 5e-4 s of 1 s).
    let p = scene(
        "far-floor.toml",
        &[("point = [0.0, 0.0, -0.01]", "point = [0.0, 0.0, -5.0]")],
    );
    let s = load(&p).unwrap();
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("`floor`") && w.contains("beyond contact.search_distance")),
        "{:?}",
        s.warnings
    );
}

/// A probe named like a column that a run in time writes itself (`t`,
/// `slip_area`, …) is refused, naming the key: it made two columns of one
/// name in history.csv, and summary.json's `end.t` held the probe's value
/// (review 3, D2). Without [friction] such names stay free (plate-cylinder
/// probes `rn_total`).
#[test]
fn a_probe_named_like_a_time_column_is_refused() {
    for name in ["t", "slip_area", "rn_total", "negative_pivots"] {
        let p = scene(
            &format!("probe-{name}.toml"),
            &[("name = \"w_tip\"", &format!("name = \"{name}\""))],
        );
        expect_invalid(&p, "probe[0].name", "a run in time writes itself");
    }
    assert!(load(Path::new("scenes/plate-cylinder-coarse.toml")).is_ok());
}
