//! Built-in meshes and fixed-length arrays: input the loader used to take
//! without a word (a new user's scenes, this session's review) is refused
//! naming the file and the key.

use super::edited::{edited, expect_invalid};

const BASE: &str = "scenes/verification/pinched-cylinder.toml";

fn base() -> String {
    format!("{}/{BASE}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn a_built_in_mesh_spanning_more_than_a_turn_is_refused() {
    // A full turn closes the seam (tests/shell/closed_tube.rs); more than
    // one overlaps the surface with itself.
    for angle in ["[-90.0, 300.0]", "[400.0, 0.0]"] {
        let f = edited(
            &base(),
            "mesh-360",
            "tube.toml",
            &[("angle = [0.0, 90.0]", &format!("angle = {angle}"))],
        );
        expect_invalid(&f, "mesh.angle", "more than 360 degrees");
    }
    // A sphere's longitude runs along s, whose seam the mesher does not
    // close: a full turn is refused too.
    for (longitude, part) in [
        ("[0.0, 400.0]", "more than 360 degrees"),
        ("[0.0, 360.0]", "less than 360 degrees"),
    ] {
        let f = edited(
            &base(),
            "mesh-360",
            "sphere.toml",
            &[
                ("type = \"cylinder\"", "type = \"sphere\""),
                (
                    "x = [0.0, 300.0]\nangle = [0.0, 90.0]",
                    &format!("longitude = {longitude}\nlatitude = [0.0, 45.0]"),
                ),
            ],
        );
        expect_invalid(&f, "mesh.longitude", part);
    }
}

#[test]
fn arrays_longer_or_shorter_than_their_key_takes_are_refused() {
    for (old, new, key) in [
        (
            "divisions = [32, 32]",
            "divisions = [32, 32, 2]",
            "mesh.divisions",
        ),
        ("divisions = [32, 32]", "divisions = [32]", "mesh.divisions"),
        ("x = [0.0, 300.0]", "x = [0.0, 300.0, 600.0]", "mesh.x"),
    ] {
        let f = edited(&base(), "array-length", "s.toml", &[(old, new)]);
        // A parse error (as a wrong type is), naming the file and the key.
        let msg = match anm::scene::shell::load(&f) {
            Ok(_) => panic!("{new}: expected an error"),
            Err(e) => e.to_string(),
        };
        println!("{msg}");
        for part in ["s.toml", key, "expected an array of 2 entries"] {
            assert!(msg.contains(part), "`{msg}` lacks `{part}`");
        }
    }
}
