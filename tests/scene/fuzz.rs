//! Scenes mutated at random (fixed seed): wrong types, odd values, missing
//! and extra keys, in the canonical shell scene and a scene with every
//! table. Every case either fails validation with an error that names the
//! file, or runs (at most 15 steps) without a panic, and nothing written is
//! NaN.

use std::panic::{AssertUnwindSafe, catch_unwind};
use toml::Value;

/// xorshift64*: a fixed, dependency-free sequence.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// Every (path) of a leaf value in the table; arrays of tables by index.
fn leaves(v: &Value, path: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    match v {
        Value::Table(t) => {
            for (k, x) in t {
                path.push(k.clone());
                leaves(x, path, out);
                path.pop();
            }
        }
        Value::Array(a) if a.iter().all(|x| x.is_table()) && !a.is_empty() => {
            for (i, x) in a.iter().enumerate() {
                path.push(i.to_string());
                leaves(x, path, out);
                path.pop();
            }
        }
        _ => out.push(path.clone()),
    }
}

fn get_mut<'a>(v: &'a mut Value, path: &[String]) -> &'a mut Value {
    path.iter().fold(v, |v, k| match v {
        Value::Table(t) => t.get_mut(k).unwrap(),
        Value::Array(a) => &mut a[k.parse::<usize>().unwrap()],
        _ => unreachable!(),
    })
}

fn mutate(rng: &mut Rng, doc: &mut Value) -> String {
    let mut all = vec![];
    leaves(doc, &mut vec![], &mut all);
    let path = all[rng.below(all.len())].clone();
    let (parent, key) = path.split_at(path.len() - 1);
    let what = rng.below(6);
    let odd = [
        Value::Float(f64::NAN),
        Value::Float(f64::INFINITY),
        Value::Float(-1.0),
        Value::Float(0.0),
        Value::Float(1e300),
        Value::Float(1e-300),
        Value::Integer(-3),
        Value::String("??".into()),
        Value::Boolean(true),
        Value::Array(vec![]),
        Value::Array(vec![Value::Float(1.0); 2]),
    ];
    let target = get_mut(doc, parent);
    match what {
        0 => {
            if let Value::Table(t) = target {
                t.remove(&key[0]);
            }
        }
        1 => {
            if let Value::Table(t) = target {
                t.insert(format!("{}_typo", key[0]), Value::Integer(1));
            }
        }
        _ => {
            let v = get_mut(target, key);
            *v = match v.clone() {
                Value::Float(x) if what == 2 => {
                    Value::Float(x * [-1.0, 0.0, 1e-12, 1e12][rng.below(4)])
                }
                Value::Array(mut a) if what == 3 && !a.is_empty() => {
                    let i = rng.below(a.len());
                    a[i] = odd[rng.below(odd.len())].clone();
                    Value::Array(a)
                }
                _ => odd[rng.below(odd.len())].clone(),
            };
        }
    }
    format!(
        "{} ({})",
        path.join("."),
        [
            "removed",
            "extra key",
            "scaled",
            "array entry",
            "odd value",
            "odd value"
        ][what]
    )
}

#[test]
fn mutated_scenes_give_errors_or_finite_results_never_panics() {
    let root = env!("CARGO_MANIFEST_DIR");
    let tmp = crate::scratch::scratch("fuzz");
    let dir = tmp.path();
    let bases = [
        (
            format!("{root}/scenes/plate-cylinder-coarse.toml"),
            format!("{root}/meshes/plate-cylinder-20x2.msh"),
        ),
        (
            format!("{root}/tests/data/shell-every-table.toml"),
            String::new(),
        ),
    ];
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let (mut rejected, mut ran, mut stopped) = (0, 0, 0);
    let cases = 300;
    for case in 0..cases {
        let (scene, mesh) = &bases[case % bases.len()];
        let text = std::fs::read_to_string(scene).unwrap();
        let mut doc: Value = toml::from_str(&text).unwrap();
        if !mesh.is_empty() {
            doc["mesh"]["file"] = Value::String(mesh.clone());
        }
        let what = mutate(&mut rng, &mut doc);
        // Keep runs short: cap the steps (unless the mutation removed them).
        if let Some(s) = doc.get_mut("solver").and_then(|s| s.as_table_mut()) {
            s.insert("max_steps".into(), Value::Integer(15));
        }
        let p = dir.join(format!("case{case}.toml"));
        std::fs::write(&p, toml::to_string(&doc).unwrap()).unwrap();
        let t0 = std::time::Instant::now();
        let result = catch_unwind(AssertUnwindSafe(|| {
            let s = anm::scene::shell::load(&p)?;
            anm::run::run_loaded(&s, None, false)
        }));
        if t0.elapsed().as_secs_f64() > 2.0 {
            println!("case {case}: {what}: {:.1} s", t0.elapsed().as_secs_f64());
        }
        match result {
            Err(_) => panic!("case {case}: {what}: panic"),
            Ok(Err(e)) => {
                let msg = e.to_string();
                assert!(
                    msg.contains(&format!("case{case}.toml"))
                        || matches!(
                            e,
                            anm::Error::Mesh { .. }
                                | anm::Error::SingularMatrix { .. }
                                | anm::Error::NoConvergence { .. }
                                | anm::Error::NonFinite { .. }
                                | anm::Error::StepCollapse { .. }
                        ),
                    "case {case}: {what}: error does not name the scene: {msg}"
                );
                rejected += 1;
            }
            Ok(Ok(r)) => {
                assert!(
                    r.history.iter().flatten().all(|x| x.is_finite()),
                    "case {case}: {what}: NaN in the output"
                );
                if r.stop.reason == "end" || r.stop.reason == "max_steps" {
                    ran += 1;
                } else {
                    assert!(
                        r.stop.message.is_some(),
                        "case {case}: {what}: stop without diagnosis"
                    );
                    stopped += 1;
                }
            }
        }
    }
    println!(
        "{cases} mutated scenes: {rejected} rejected, {ran} ran, {stopped} stopped with a diagnosis"
    );
    assert!(
        rejected > 50 && ran > 20,
        "the mutations must exercise both paths"
    );
}

/// The same mutations on the three friction scenes (time-dependent DAEs):
/// an error naming the file, or a run (at most 400 steps) without a panic,
/// finite histories and step rows, and a diagnosis for every stop that is
/// not the end or a located singularity. (An output grid of 1e300 rows
/// used to panic on its allocation.)
#[test]
fn mutated_friction_scenes_give_errors_or_finite_results_never_panics() {
    let root = env!("CARGO_MANIFEST_DIR");
    let tmp = crate::scratch::scratch("fuzz-friction");
    let dir = tmp.path();
    let bases = ["friction-1d", "friction-plane", "friction-roller"];
    let mut rng = Rng(0xD1B5_4A32_D192_ED03);
    let (mut rejected, mut ran) = (0, 0);
    let cases = 600;
    for case in 0..cases {
        let scene = format!("{root}/scenes/{}.toml", bases[case % bases.len()]);
        let mut doc: Value = toml::from_str(&std::fs::read_to_string(&scene).unwrap()).unwrap();
        let what = mutate(&mut rng, &mut doc);
        if let Some(s) = doc.get_mut("solver").and_then(|s| s.as_table_mut()) {
            s.insert("max_steps".into(), Value::Integer(400));
        }
        let p = dir.join(format!("case{case}.toml"));
        std::fs::write(&p, toml::to_string(&doc).unwrap()).unwrap();
        let result = catch_unwind(AssertUnwindSafe(|| {
            let text = anm::scene::read(&p)?;
            let kind = anm::scene::kind(&p, &text)?;
            let s = anm::scene::friction::load(&p, &text, kind)?;
            anm::model::friction_run::run(&s, None, false)
        }));
        match result {
            Err(_) => panic!("case {case}: {what}: panic"),
            Ok(Err(e)) => {
                let msg = e.to_string();
                assert!(
                    msg.contains(&format!("case{case}.toml")),
                    "case {case}: {what}: error does not name the scene: {msg}"
                );
                rejected += 1;
            }
            Ok(Ok(r)) => {
                assert!(
                    r.history
                        .iter()
                        .chain(&r.steps)
                        .flatten()
                        .all(|x| x.is_finite()),
                    "case {case}: {what}: non-finite value in the output"
                );
                if !matches!(r.stop.reason.as_str(), "end" | "singularity") {
                    assert!(
                        r.stop.message.is_some(),
                        "case {case}: {what}: stop {} without diagnosis",
                        r.stop.reason
                    );
                }
                ran += 1;
            }
        }
    }
    println!("{cases} mutated friction scenes: {rejected} rejected, {ran} ran");
    assert!(
        rejected > 100 && ran > 50,
        "the mutations must exercise both paths"
    );
}

/// The canonical coarse mesh corrupted at random (fixed seed): truncated, a
/// line replaced or removed, a token replaced by an odd one. Loading the
/// scene either fails with an error that names the mesh or the scene, or
/// gives a model, never a panic. (A one-off sweep of `anm check` and `anm
/// run` over 300 such meshes found none either.)
#[test]
fn corrupted_meshes_give_errors_never_panics() {
    let root = env!("CARGO_MANIFEST_DIR");
    let tmp = crate::scratch::scratch("fuzz-mesh");
    let dir = tmp.path();
    let lines: Vec<String> =
        std::fs::read_to_string(format!("{root}/meshes/plate-cylinder-20x2.msh"))
            .unwrap()
            .lines()
            .map(String::from)
            .collect();
    let odd = [
        "nan",
        "-1",
        "0",
        "1e308",
        "4294967296",
        "-99999",
        "x",
        "",
        "1.5",
        "$Nodes",
    ];
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let (mut rejected, mut loaded) = (0, 0);
    let cases = 400;
    for case in 0..cases {
        let mut m = lines.clone();
        let i = rng.below(m.len());
        let what = match rng.below(4) {
            0 => {
                m.truncate(i);
                "truncated"
            }
            1 => {
                m[i] = odd[rng.below(odd.len())].to_string();
                "line replaced"
            }
            2 => {
                let mut t: Vec<String> = m[i].split(' ').map(String::from).collect();
                let k = rng.below(t.len());
                t[k] = odd[rng.below(odd.len())].to_string();
                m[i] = t.join(" ");
                "token replaced"
            }
            _ => {
                m.remove(i);
                "line removed"
            }
        };
        let mesh = dir.join(format!("case{case}.msh"));
        std::fs::write(&mesh, m.join("\n") + "\n").unwrap();
        let text = std::fs::read_to_string(format!("{root}/scenes/plate-cylinder-coarse.toml"))
            .unwrap()
            .replace("../meshes/plate-cylinder-20x2.msh", mesh.to_str().unwrap());
        let scene = dir.join(format!("case{case}.toml"));
        std::fs::write(&scene, text).unwrap();
        match catch_unwind(AssertUnwindSafe(|| anm::scene::shell::load(&scene))) {
            Err(_) => panic!("case {case}: line {}: {what}: panic", i + 1),
            Ok(Err(e)) => {
                let msg = e.to_string();
                assert!(
                    msg.contains(&format!("case{case}.")),
                    "case {case}: line {}: {what}: error names neither file: {msg}",
                    i + 1
                );
                rejected += 1;
            }
            Ok(Ok(_)) => loaded += 1,
        }
    }
    println!("{cases} corrupted meshes: {rejected} rejected, {loaded} loaded");
    assert!(
        rejected > 200 && loaded > 5,
        "the corruptions must exercise both paths"
    );
}
