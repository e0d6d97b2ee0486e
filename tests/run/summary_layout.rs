//! Every `anm run` writes summary.json with one common core, whatever the
//! scene's kind (a static shell, a shell in time, a point-mass friction
//! problem): a downstream script reads `stop.reason`, `columns` and `end`
//! the same way for all of them. `end` is history.csv's last row, read back
//! from the file.

use crate::common::anm_run as run;
use crate::scratch::scratch;
use std::path::Path;

/// history.csv's header and last row.
fn last_row(dir: &Path) -> (Vec<String>, Vec<f64>) {
    let mut r = csv::Reader::from_path(dir.join("history.csv")).unwrap();
    let head: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let last = r
        .records()
        .map(|rec| {
            rec.unwrap()
                .iter()
                .map(|x| x.parse::<f64>().unwrap())
                .collect::<Vec<f64>>()
        })
        .last()
        .expect("a row");
    (head, last)
}

#[test]
fn every_kind_of_run_writes_the_same_summary_core() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let dir = scratch("summary-layout");
    for (scene, kind, param) in [
        ("plate-cylinder-coarse.toml", "shell", "lambda"),
        ("verification/sliding-plate.toml", "shell", "t"),
        ("friction-plane.toml", "friction-plane", "t"),
    ] {
        let out = dir.path().join(scene.replace('/', "-"));
        let o = run(&root.join(scene), &out);
        assert!(o.status.success(), "{scene}: {o:?}");
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(s["kind"], kind, "{scene}");
        assert_eq!(s["method"], "anm", "{scene}");
        assert!(s["scene"].as_str().unwrap().ends_with(scene), "{scene}");
        for key in ["steps", "factorizations"] {
            assert!(s[key].as_u64().unwrap() > 0, "{scene}: {key}");
        }
        assert!(s["wall_s"].as_f64().unwrap() > 0.0, "{scene}");
        assert_eq!(s["stop"]["reason"], "end", "{scene}: {}", s["stop"]);
        assert!(s["stop"][param].is_number(), "{scene}: {}", s["stop"]);
        let (head, last) = last_row(&out);
        let columns: Vec<&str> = s["columns"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_str().unwrap())
            .collect();
        assert_eq!(columns, head, "{scene}: columns = history.csv's header");
        let end = s["end"].as_object().unwrap();
        assert_eq!(end.len(), head.len(), "{scene}: {end:?}");
        // In history.csv's order too (review 11: the probes came out
        // sorted by name, so `columns` zipped with `end`'s values paired
        // the wrong ones).
        #[derive(serde::Deserialize)]
        struct Ordered {
            end: indexmap::IndexMap<String, f64>,
        }
        let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
        let ordered: Ordered = serde_json::from_str(&text).unwrap();
        let keys: Vec<&str> = ordered.end.keys().map(String::as_str).collect();
        assert_eq!(keys, head, "{scene}: end's keys in history.csv's order");
        for (name, value) in head.iter().zip(&last) {
            // The same double in both files (17 significant digits in
            // history.csv, the shortest round trip in summary.json), read
            // back within an ulp: serde_json's default float parser is not
            // correctly rounded.
            let got = end[name].as_f64().unwrap();
            assert!(
                (got - value).abs() <= f64::EPSILON * value.abs(),
                "{scene}: end.{name} = {got} against {value} in history.csv"
            );
        }
        println!(
            "{scene}: kind {kind}, stop {} at {param} = {}, {} columns, end = the last row",
            s["stop"]["reason"],
            s["stop"][param],
            head.len()
        );
    }
}
