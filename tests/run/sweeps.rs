//! Sweeps run item by item (`--item K -o DIR`, `anm merge DIR`) give the
//! tables and plots of the single-process run.
//!
//! Three sweeps, cheap enough for a test: the friction audit of
//! friction-plane (omega, zeta, eta), the shell audit of the coarse
//! plate-cylinder (eta, K), the stress matrix of friction-1d. For each:
//! 1. the single-process run `-o S` (which writes S/items/K.json and merges
//!    them);
//! 2. `anm merge` of a copy of S's item files: every table and plot byte for
//!    byte the same as S's (identity by construction: the same files, the
//!    same merge);
//! 3. the same sweep by GNU parallel on 2 workers (`parallel -j 2 anm ...
//!    --item {} -o P ::: 0 1 ...`), then `anm merge P`: every table and plot
//!    the same as S's except the wall-time columns (separate runs take
//!    different times), which are removed from both before the comparison;
//! 4. (friction audit) the Slurm array script docs/slurm-sweep.sh, one task
//!    per item with SLURM_ARRAY_TASK_ID set as Slurm sets it (no Slurm
//!    here), then `anm merge`: the same as S's but wall times.
//!
//! Without GNU parallel the test says so and skips step 3, unless CI=true,
//! where it fails (ci/install-reference.sh installs it).

use std::path::Path;
use std::process::{Command, Output};

const ANM: &str = env!("CARGO_BIN_EXE_anm");

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn ok(what: &str, out: Output) -> String {
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "{what}: {}\nstdout:\n{text}\nstderr:\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    text
}

fn anm(args: &[&str]) -> Output {
    Command::new(ANM)
        .args(args)
        .current_dir(root())
        .output()
        .unwrap()
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// A CSV without the columns named in `drop`.
fn csv_without(text: &str, drop: &[&str]) -> String {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(text.as_bytes());
    let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
    let keep: Vec<usize> = (0..rows[0].len())
        .filter(|&j| !drop.contains(&&rows[0][j]))
        .collect();
    assert!(keep.len() < rows[0].len(), "no column {drop:?} in {text}");
    rows.iter()
        .map(|r| keep.iter().map(|&j| &r[j]).collect::<Vec<_>>().join(","))
        .collect::<Vec<_>>()
        .join("\n")
}

/// A Markdown table without the column whose header is `drop` (every line
/// starting with `|` loses that cell).
fn md_without(text: &str, drop: &str) -> String {
    let header = text.lines().find(|l| l.starts_with('|')).expect("a table");
    let cells: Vec<&str> = header.split('|').map(str::trim).collect();
    let j = cells
        .iter()
        .position(|c| *c == drop)
        .unwrap_or_else(|| panic!("no column `{drop}` in {header}"));
    text.lines()
        .map(|l| {
            if l.starts_with('|') {
                let mut c: Vec<&str> = l.split('|').collect();
                c.remove(j);
                c.join("|")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The files a sweep writes, and how to take the wall times out of each
/// (None: compared whole).
struct Outputs {
    files: Vec<(&'static str, Option<&'static str>)>,
}

impl Outputs {
    fn same(&self, a: &Path, b: &Path) {
        for (f, _) in &self.files {
            assert_eq!(
                read(&a.join(f)),
                read(&b.join(f)),
                "{f} of {} and {} differ",
                a.display(),
                b.display()
            );
        }
    }

    /// Equal but the wall times; returns how many files were compared whole.
    fn same_but_wall_times(&self, a: &Path, b: &Path) -> usize {
        let mut whole = 0;
        for (f, wall) in &self.files {
            let (x, y) = (read(&a.join(f)), read(&b.join(f)));
            match (f.rsplit('.').next(), wall) {
                (_, None) => {
                    whole += 1;
                    assert_eq!(x, y, "{f} of {} and {} differ", a.display(), b.display());
                }
                (Some("csv"), Some(col)) => {
                    assert_eq!(
                        csv_without(&x, &[col]),
                        csv_without(&y, &[col]),
                        "{f} of {} and {} differ beyond {col}",
                        a.display(),
                        b.display()
                    );
                }
                (_, Some(col)) => assert_eq!(
                    md_without(&x, col),
                    md_without(&y, col),
                    "{f} of {} and {} differ beyond `{col}`",
                    a.display(),
                    b.display()
                ),
            }
        }
        whole
    }
}

fn have_parallel() -> bool {
    let found = Command::new("parallel")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success() && String::from_utf8_lossy(&o.stdout).contains("GNU"));
    if !found {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "GNU parallel is missing under CI=true: ci/install-reference.sh installs it (apt package `parallel`)"
        );
        println!(
            "SKIPPED: the GNU parallel part of this test: GNU parallel is not installed (apt-get install parallel, or bash ci/install-reference.sh)"
        );
    }
    found
}

/// Runs `sweep` (arguments without -o) in one process, merges a copy of its
/// item files, by GNU parallel on 2 workers, and (with `slurm`) through the
/// Slurm array script; compares as the module doc says.
fn check_sweep(name: &str, sweep: &[&str], outputs: &Outputs, slurm: bool) {
    let tmp = crate::scratch::scratch(&format!("sweeps-{name}"));
    let dir = tmp.path();
    let list = ok("--list-items", anm(&[sweep, &["--list-items"]].concat()));
    let ids: Vec<String> = list
        .lines()
        .map(|l| l.split('\t').next().unwrap().to_string())
        .collect();
    assert!(ids.len() >= 3, "{list}");
    assert_eq!(
        ids,
        (0..ids.len()).map(|k| k.to_string()).collect::<Vec<_>>()
    );

    // 1. Single process.
    let single = dir.join("single");
    let t = std::time::Instant::now();
    ok(
        "single",
        anm(&[sweep, &["-o", single.to_str().unwrap()]].concat()),
    );
    let t_single = t.elapsed().as_secs_f64();
    for k in 0..ids.len() {
        assert!(single.join(format!("items/{k}.json")).is_file());
    }

    // 2. Merge of the same item files: identical to the byte.
    let copy = dir.join("copy");
    std::fs::create_dir_all(copy.join("items")).unwrap();
    std::fs::copy(single.join("sweep.json"), copy.join("sweep.json")).unwrap();
    for k in 0..ids.len() {
        let f = format!("items/{k}.json");
        std::fs::copy(single.join(&f), copy.join(&f)).unwrap();
    }
    ok("merge copy", anm(&["merge", copy.to_str().unwrap()]));
    outputs.same(&single, &copy);

    // A missing item is named, and nothing is written.
    let gap = dir.join("gap");
    std::fs::create_dir_all(gap.join("items")).unwrap();
    std::fs::copy(single.join("sweep.json"), gap.join("sweep.json")).unwrap();
    for k in 1..ids.len() {
        let f = format!("items/{k}.json");
        std::fs::copy(single.join(&f), gap.join(&f)).unwrap();
    }
    let out = anm(&["merge", gap.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("1 of") && err.contains("no result file: 0 ("),
        "{err}"
    );
    assert!(!gap.join(outputs.files[0].0).exists());

    // 3. GNU parallel, 2 workers.
    if have_parallel() {
        let par = dir.join("parallel");
        let t = std::time::Instant::now();
        let out = Command::new("parallel")
            .args(["--halt", "now,fail=1", "-j", "2", ANM])
            .args(sweep)
            .args(["--item", "{}", "-o", par.to_str().unwrap(), ":::"])
            .args(&ids)
            .current_dir(root())
            .output()
            .unwrap();
        ok("parallel", out);
        ok("merge parallel", anm(&["merge", par.to_str().unwrap()]));
        let t_par = t.elapsed().as_secs_f64();
        let whole = outputs.same_but_wall_times(&single, &par);
        println!(
            "{name}: {} items; single process {t_single:.2} s, GNU parallel -j 2 + merge {t_par:.2} s; merged tables identical but the wall times, {whole} of {} files byte for byte",
            ids.len(),
            outputs.files.len()
        );
    }

    // 4. The Slurm array script, one task per item.
    if slurm {
        let arr = dir.join("slurm");
        for k in &ids {
            let out = Command::new("bash")
                .arg(root().join("docs/slurm-sweep.sh"))
                .arg(&arr)
                .arg(ANM)
                .args(sweep)
                .env("SLURM_ARRAY_TASK_ID", k)
                .current_dir(root())
                .output()
                .unwrap();
            ok("slurm task", out);
        }
        ok("merge slurm", anm(&["merge", arr.to_str().unwrap()]));
        outputs.same_but_wall_times(&single, &arr);
    }
}

fn audit_outputs(wall_md: &'static str) -> Outputs {
    Outputs {
        files: vec![
            ("audit.csv", Some("wall_s")),
            ("audit.md", Some(wall_md)),
            ("audit.svg", None),
        ],
    }
}

#[test]
fn sweeps_item_by_item_merge_to_the_single_process_tables() {
    check_sweep(
        "friction-audit",
        &[
            "audit",
            "scenes/friction-plane.toml",
            "--omega",
            "0.3,0.1,0.03",
            "--zeta",
            "0.3,0.1",
            "--eta",
            "1e-2,1e-3",
        ],
        &audit_outputs("wall (s)"),
        true,
    );
    check_sweep(
        "shell-audit",
        &[
            "audit",
            "scenes/plate-cylinder-coarse.toml",
            "--eta",
            "1e-2,1e-1,0",
            "--penalty",
            "1e7,1e9",
        ],
        &audit_outputs("wall (s)"),
        false,
    );
    check_sweep(
        "stress",
        &["stress", "--cases", "friction-1d", "--max-steps", "5000"],
        &Outputs {
            files: vec![("stress.csv", Some("wall_s")), ("stress.md", None)],
        },
        false,
    );
}

#[test]
fn an_item_refuses_a_folder_of_another_sweep_and_a_missing_item() {
    let tmp = crate::scratch::scratch("sweeps-refuse");
    let d = tmp.path().to_str().unwrap();
    let a = ["audit", "scenes/friction-1d.toml", "--omega", "0.3,0.1"];
    ok("item 0", anm(&[&a[..], &["--item", "0", "-o", d]].concat()));
    // Another sweep into the same folder.
    let out = anm(&[
        "audit",
        "scenes/friction-1d.toml",
        "--omega",
        "0.3,0.03",
        "--item",
        "1",
        "-o",
        d,
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("items of another sweep"), "{err}");
    // An item beyond the list.
    let out = anm(&[&a[..], &["--item", "2", "-o", d]].concat());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("2 items, 0 to 1"),
        "{err}"
    );
    // The merge names item 1, not yet run.
    let out = anm(&["merge", d]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("1 (omega=1e-1)"),
        "{err}"
    );
    ok("item 1", anm(&[&a[..], &["--item", "1", "-o", d]].concat()));
    let md = ok("merge", anm(&["merge", d]));
    assert!(md.contains("| omega | 1.000e-1 |"), "{md}");
}

/// The scaling study item by item (one size per item, each its own `anm
/// run` child): the merge of the single-process run's item files is its
/// scaling.md byte for byte; items run one by one merge to the same mesh,
/// unknowns, steps and stop (the other columns are timings and memory).
#[test]
fn scaling_items_merge_to_the_single_process_table() {
    let tmp = crate::scratch::scratch("sweeps-scaling");
    let dir = tmp.path();
    let d = |s: &str| dir.join(s).to_str().unwrap().to_string();
    // Review 26: a size given twice is refused up front (it gave NaN
    // exponents, and two items wrote into one folder).
    let twice = anm(&["bench", "--scaling", "20x2,20x2", "-o", &d("twice")]);
    let err = String::from_utf8_lossy(&twice.stderr);
    assert!(
        !twice.status.success() && err.contains("given twice"),
        "{err}"
    );
    let sweep = ["bench", "--scaling", "20x2,40x4", "--scaling-steps", "2"];
    let list = ok(
        "--list-items",
        anm(&[&sweep[..], &["--list-items"]].concat()),
    );
    assert_eq!(list, "0\t20x2\n1\t40x4\n");
    ok("single", anm(&[&sweep[..], &["-o", &d("single")]].concat()));
    std::fs::create_dir_all(dir.join("copy/items")).unwrap();
    for f in ["sweep.json", "items/0.json", "items/1.json"] {
        std::fs::copy(dir.join("single").join(f), dir.join("copy").join(f)).unwrap();
    }
    ok("merge copy", anm(&["merge", &d("copy")]));
    assert_eq!(
        read(&dir.join("single/scaling.md")),
        read(&dir.join("copy/scaling.md"))
    );
    for k in ["1", "0"] {
        ok(
            "item",
            anm(&[&sweep[..], &["--item", k, "-o", &d("items")]].concat()),
        );
    }
    ok("merge items", anm(&["merge", &d("items")]));
    let fixed = |p: &Path| -> Vec<String> {
        read(p)
            .lines()
            .filter(|l| l.starts_with("| ") && !l.starts_with("| mesh"))
            .map(|l| {
                let c: Vec<&str> = l.split('|').map(str::trim).collect();
                format!("{} {} {} {}", c[1], c[2], c[3], c[10])
            })
            .collect()
    };
    let a = fixed(&dir.join("single/scaling.md"));
    assert_eq!(a, ["20×2 360 2 max_steps", "40×4 1200 2 max_steps"]);
    assert_eq!(a, fixed(&dir.join("items/scaling.md")));
}

/// Review 7: the manifest held the scene's text but not its mesh, and an
/// item file only its number and label, so a merge mixed items run on two
/// meshes, and took another sweep's item copied in, with exit code 0. Now
/// the manifest holds a digest of the mesh file too and each item file the
/// digest of its manifest; item files beyond the sweep's are named.
#[test]
fn a_merge_refuses_items_of_another_mesh_or_sweep() {
    let tmp = crate::scratch::scratch("sweeps-mesh");
    let dir = tmp.path();
    let mesh = dir.join("m.msh");
    let copy_mesh = |name: &str| {
        std::fs::copy(root().join("meshes").join(name), &mesh).unwrap();
    };
    copy_mesh("plate-cylinder-20x2.msh");
    let coarse = read(&root().join("scenes/plate-cylinder-coarse.toml"));
    let scene = coarse.replace("../meshes/plate-cylinder-20x2.msh", "m.msh");
    assert_ne!(scene, coarse);
    std::fs::write(dir.join("a.toml"), &scene).unwrap();
    std::fs::write(
        dir.join("b.toml"),
        scene.replace("order = 15", "order = 10"),
    )
    .unwrap();
    let s = |p: &str| dir.join(p).to_str().unwrap().to_string();
    let sweep = |scene: &str| -> Vec<String> {
        ["audit", &s(scene), "--eta", "1e-1,1"]
            .map(String::from)
            .to_vec()
    };
    let item = |scene: &str, k: &str, out: &str| {
        let args: Vec<String> = [
            sweep(scene),
            vec!["--item".into(), k.into(), "-o".into(), s(out)],
        ]
        .concat();
        anm(&args.iter().map(String::as_str).collect::<Vec<_>>())
    };

    let merge = || anm(&["merge", &s("mixed")]);
    let refused = |out: Output, needles: &[&str]| {
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{err}");
        for n in needles {
            assert!(err.contains(n), "`{n}` not in: {err}");
        }
    };

    // Item 0 on the 0.1 m mesh; the mesh regenerated (0.05 m) before item 1.
    ok("item 0", item("a.toml", "0", "mixed"));
    copy_mesh("plate-cylinder-40x4.msh");
    refused(
        item("a.toml", "1", "mixed"),
        &["a scene or mesh file changed"],
    );
    refused(merge(), &["m.msh", "changed since the items ran"]);

    // Both items of scene a, and item 1 of scene b (order 10) copied over
    // a's item 1: same number, same label, another sweep.
    copy_mesh("plate-cylinder-20x2.msh");
    ok("item 1", item("a.toml", "1", "mixed"));
    ok("merge", merge());
    ok("b item 1", item("b.toml", "1", "other"));
    std::fs::copy(
        dir.join("other/items/1.json"),
        dir.join("mixed/items/1.json"),
    )
    .unwrap();
    refused(merge(), &["ran in another sweep"]);

    // A stray item file beyond the sweep's items is named.
    ok("item 1 again", item("a.toml", "1", "mixed"));
    std::fs::copy(
        dir.join("mixed/items/0.json"),
        dir.join("mixed/items/7.json"),
    )
    .unwrap();
    let out = merge();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && err.contains("7.json"), "{err}");
}

/// Review 26: a single-process sweep into a folder that holds another
/// sweep's items removed them without a word; it now says how many.
#[test]
fn a_sweep_that_replaces_earlier_items_says_so() {
    let tmp = crate::scratch::scratch("sweeps-replace");
    let d = tmp.path().join("a").to_str().unwrap().to_string();
    let sweep = [
        "audit",
        "scenes/friction-plane.toml",
        "--zeta",
        "1e-2,1e-1",
        "-o",
        &d,
    ];
    let first = anm(&sweep);
    assert!(first.status.success(), "{first:?}");
    let second = anm(&sweep);
    let err = String::from_utf8_lossy(&second.stderr);
    assert!(second.status.success(), "{err}");
    assert!(
        err.contains("removed 2 item files of an earlier sweep"),
        "{err}"
    );
}
