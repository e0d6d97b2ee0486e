//! Sweeps run item by item: the same study in one process, on several
//! processes of one machine (GNU parallel) or as a cluster job array (Slurm).
//!
//! A sweep (`anm audit`, `anm stress`, `anm bench --scaling`) is a list of
//! items. Each item is one independent run; its whole result (enough to
//! rebuild every table and plot: histories, counters, checks, wall times) is
//! written as `DIR/items/K.json`. The merge reads every item file and writes
//! the sweep's tables and plots. Three ways to drive it:
//!
//! - `anm audit ... -o DIR`: every item in this process (threads), each item
//!   file written as it finishes, then the merge from the files on disk;
//! - `anm audit ... --item K -o DIR`: item K only (any order, any process,
//!   any machine sharing DIR), then `anm merge DIR`;
//! - `anm audit ... --list-items`: the items, `K<TAB>label` per line.
//!
//! `DIR/sweep.json` (the manifest) holds the sweep's arguments, the labels of
//! its items and a digest of every file it read (scenes, and the mesh files
//! they read); every `--item` process writes it (or checks that the one in
//! DIR is the same sweep), so `anm merge DIR` needs no arguments and cannot
//! be given other ones than the items ran with, and refuses a scene or mesh
//! changed since. Each item file carries the digest of the manifest it ran
//! under: an item copied from another sweep's DIR is refused, even with the
//! same number and label (review 7).
//!
//! Floats in the item files and the manifest are written as strings of
//! Rust's shortest round-trip form ("0.705805084", "1e-8", "NaN", "inf"):
//! they read back bit for bit (serde_json's default float parser may be off
//! by one unit in the last place, and JSON numbers have no NaN), so a table
//! merged from the files is the table of the run that wrote them.

use super::pool;
use crate::error::{Error, Result};
use crate::output::create_dir;
use serde::de::{self, Deserializer, Visitor};
use serde::{Deserialize, Serialize, Serializer};
use std::path::{Path, PathBuf};

/// Version of the manifest and item files (2: digests of the inputs instead
/// of their text, the mesh files among them, and the manifest's digest in
/// each item file).
pub const FORMAT: u32 = 2;

/// A float written as a string that reads back bit for bit (see the module
/// doc); reads JSON numbers too.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exact(pub f64);

impl Serialize for Exact {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(&format!("{:?}", self.0))
    }
}

impl<'de> Deserialize<'de> for Exact {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Exact;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a float (string or number)")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<Exact, E> {
                v.parse::<f64>()
                    .map(Exact)
                    .map_err(|_| E::custom(format!("`{v}` is not a float")))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<Exact, E> {
                Ok(Exact(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<Exact, E> {
                Ok(Exact(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<Exact, E> {
                Ok(Exact(v as f64))
            }
        }
        d.deserialize_any(V)
    }
}

/// `#[serde(with = "exact")]` for an f64 field.
pub mod exact {
    use super::Exact;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};
    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        Exact(*v).serialize(s)
    }
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Exact::deserialize(d).map(|e| e.0)
    }
}

/// `#[serde(with = "exact_vec")]` for a `Vec<f64>` field.
pub mod exact_vec {
    use super::Exact;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};
    pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
        v.iter().map(|x| Exact(*x)).collect::<Vec<_>>().serialize(s)
    }
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        Ok(Vec::<Exact>::deserialize(d)?
            .into_iter()
            .map(|e| e.0)
            .collect())
    }
}

/// `#[serde(with = "exact_opt")]` for an `Option<f64>` field.
pub mod exact_opt {
    use super::Exact;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};
    pub fn serialize<S: Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
        v.map(Exact).serialize(s)
    }
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
        Ok(Option::<Exact>::deserialize(d)?.map(|e| e.0))
    }
}

/// `#[serde(with = "exact_rows")]` for a `Vec<Vec<f64>>` field (a history).
pub mod exact_rows {
    use super::Exact;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};
    pub fn serialize<S: Serializer>(v: &[Vec<f64>], s: S) -> Result<S::Ok, S::Error> {
        v.iter()
            .map(|r| r.iter().map(|x| Exact(*x)).collect::<Vec<_>>())
            .collect::<Vec<_>>()
            .serialize(s)
    }
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Vec<f64>>, D::Error> {
        Ok(Vec::<Vec<Exact>>::deserialize(d)?
            .into_iter()
            .map(|r| r.into_iter().map(|e| e.0).collect())
            .collect())
    }
}

/// `#[serde(with = "exact_opt3")]` for an `Option<[f64; 3]>` field.
pub mod exact_opt3 {
    use super::Exact;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};
    pub fn serialize<S: Serializer>(v: &Option<[f64; 3]>, s: S) -> Result<S::Ok, S::Error> {
        v.map(|a| a.map(Exact)).serialize(s)
    }
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[f64; 3]>, D::Error> {
        Ok(Option::<[Exact; 3]>::deserialize(d)?.map(|a| a.map(|e| e.0)))
    }
}

/// What a sweep is: the arguments of the command that defines its items.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "sweep", rename_all = "lowercase")]
pub enum Spec {
    /// `anm audit SCENE --omega ... --zeta ... --eta ... --penalty ...`
    Audit {
        scene: PathBuf,
        #[serde(with = "exact_vec")]
        omega: Vec<f64>,
        #[serde(with = "exact_vec")]
        zeta: Vec<f64>,
        #[serde(with = "exact_vec")]
        eta: Vec<f64>,
        #[serde(with = "exact_vec")]
        penalty: Vec<f64>,
    },
    /// `anm stress --scenes DIR --cases a,b --max-steps N`
    Stress {
        scenes: PathBuf,
        cases: Vec<String>,
        max_steps: usize,
    },
    /// `anm bench --scaling NXxNY,... --scaling-steps N` (template: the
    /// plate-cylinder scene).
    Scaling {
        template: PathBuf,
        sizes: Vec<(usize, usize)>,
        steps: usize,
        /// Write each size's initial tangent and factor it (factor.md).
        #[serde(default)]
        write_matrix: bool,
    },
}

/// A file the sweep read, with the FNV-1a digest of its bytes
/// (`mesh::digest`): the merge refuses a changed one. A digest, not the
/// text: a mesh file may hold millions of nodes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Input {
    pub file: PathBuf,
    pub digest: String,
}

/// The files a shell scene reads: the scene, and its mesh file unless the
/// mesh is built in.
pub fn scene_inputs(scene: &crate::scene::shell::ShellScene) -> Vec<PathBuf> {
    let mut files = vec![scene.file.clone()];
    if scene.mesh.digest.is_some() {
        files.push(scene.mesh.file.clone());
    }
    files
}

fn file_digest(file: &Path) -> Result<String> {
    let bytes = std::fs::read(file).map_err(io(file))?;
    Ok(crate::mesh::digest(&bytes))
}

/// `DIR/sweep.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub format: u32,
    pub spec: Spec,
    /// One label per item, in item order.
    pub items: Vec<String>,
    pub inputs: Vec<Input>,
}

/// What a merge produced.
#[derive(Clone, Debug)]
pub struct Merged {
    /// The table printed on stdout (the single-process run prints the same).
    pub markdown: String,
    /// The sweep's own verdict is a failure (stress: a failed run): exit 1.
    pub failed: bool,
}

/// A sweep: items that run independently, and the merge of their results.
pub trait Sweep: Sync {
    /// The label of every item, in item order (what `--list-items` prints).
    fn labels(&self) -> Vec<String>;
    /// The files the items read (scenes, templates), for the manifest.
    fn inputs(&self) -> Vec<PathBuf>;
    /// Items may run concurrently in one process (false: one at a time,
    /// e.g. the scaling study, whose items measure time and peak memory).
    fn concurrent(&self) -> bool {
        true
    }
    /// Runs item `k`; a failed run is a result (recorded in the value), not
    /// an error. `dir`: the output folder (the scaling study writes its
    /// meshes and child runs there).
    fn run_item(&self, k: usize, dir: Option<&Path>) -> Result<serde_json::Value>;
    /// Builds the tables from every item's result, in item order, and writes
    /// them into `dir` when given.
    fn merge(&self, items: &[serde_json::Value], dir: Option<&Path>) -> Result<Merged>;
}

fn io(file: &Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        file: file.to_path_buf(),
        source,
    }
}

/// The manifest of `sweep` with arguments `spec` (reads its input files).
pub fn manifest(spec: &Spec, sweep: &dyn Sweep) -> Result<Manifest> {
    let inputs = sweep
        .inputs()
        .into_iter()
        .map(|file| {
            let digest = file_digest(&file)?;
            Ok(Input { file, digest })
        })
        .collect::<Result<_>>()?;
    Ok(Manifest {
        format: FORMAT,
        spec: spec.clone(),
        items: sweep.labels(),
        inputs,
    })
}

/// `K<TAB>label` per item (`--list-items`).
pub fn list(sweep: &dyn Sweep) -> String {
    sweep
        .labels()
        .iter()
        .enumerate()
        .map(|(k, l)| format!("{k}\t{l}\n"))
        .collect()
}

fn items_dir(dir: &Path) -> PathBuf {
    dir.join("items")
}

/// `DIR/items/K.json`.
pub fn item_file(dir: &Path, k: usize) -> PathBuf {
    items_dir(dir).join(format!("{k}.json"))
}

/// Writes `text` to `file` through a temporary file and a rename, so that a
/// reader (or a concurrent writer of the same content) never sees half a file.
fn write_atomic(file: &Path, text: &str) -> Result<()> {
    let tmp = file.with_extension(format!("tmp.{}", std::process::id()));
    std::fs::write(&tmp, text).map_err(io(&tmp))?;
    std::fs::rename(&tmp, file).map_err(io(file))
}

fn to_json<T: Serialize>(file: &Path, v: &T) -> Result<String> {
    serde_json::to_string_pretty(v)
        .map(|s| s + "\n")
        .map_err(|e| Error::write(file, e))
}

fn read_manifest(dir: &Path) -> Result<Manifest> {
    let file = dir.join("sweep.json");
    let text = std::fs::read_to_string(&file).map_err(io(&file))?;
    let m: Manifest = serde_json::from_str(&text).map_err(|e| Error::Parse {
        file: file.clone(),
        message: e.to_string(),
    })?;
    if m.format != FORMAT {
        return Err(Error::Parse {
            file,
            message: format!(
                "format {} (this anm reads format {FORMAT}): merge with the anm that ran the items",
                m.format
            ),
        });
    }
    Ok(m)
}

/// Makes DIR ready for items: a new manifest (`fresh`: the single-process
/// run, which also removes item files of an earlier sweep), or the same
/// manifest as the one already there (`--item`: a different sweep in the
/// same DIR is an error).
fn prepare(dir: &Path, m: &Manifest, fresh: bool) -> Result<()> {
    create_dir(&items_dir(dir))?;
    let file = dir.join("sweep.json");
    if fresh {
        let mut removed = 0;
        for e in std::fs::read_dir(items_dir(dir)).map_err(io(dir))? {
            let p = e.map_err(io(dir))?.path();
            let numbered = p.extension().is_some_and(|x| x == "json")
                && p.file_stem()
                    .and_then(|s| s.to_str())
                    .is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()));
            if numbered {
                std::fs::remove_file(&p).map_err(io(&p))?;
                removed += 1;
            }
        }
        // Review 26: 11 items of another sweep went without a word.
        if removed > 0 {
            eprintln!(
                "note: removed {removed} item files of an earlier sweep from {}",
                items_dir(dir).display()
            );
        }
    } else if file.exists() {
        let there = read_manifest(dir)?;
        if &there != m {
            let what = if there.spec != m.spec || there.items != m.items {
                "the items of another sweep"
            } else {
                "items run on other input files (a scene or mesh file changed)"
            };
            return Err(Error::Invalid {
                file,
                key: "sweep".into(),
                problem: format!(
                    "{} holds {what}: give another -o DIR, or remove it",
                    dir.display()
                ),
            });
        }
        return Ok(());
    }
    write_atomic(&file, &to_json(&file, m)?)
}

#[derive(Serialize, Deserialize)]
struct ItemFile {
    format: u32,
    /// The digest of the manifest the item ran under ([`Manifest::digest`]).
    sweep: String,
    item: usize,
    label: String,
    result: serde_json::Value,
}

impl Manifest {
    /// FNV-1a of the manifest's JSON text: what an item file names its
    /// sweep by.
    pub fn digest(&self) -> Result<String> {
        let text = serde_json::to_string(self).map_err(|e| Error::write("sweep.json", e))?;
        Ok(crate::mesh::digest(text.as_bytes()))
    }
}

fn write_item(
    dir: &Path,
    sweep: &str,
    k: usize,
    label: &str,
    result: serde_json::Value,
) -> Result<()> {
    let file = item_file(dir, k);
    // Compact: a history is thousands of floats.
    let text = serde_json::to_string(&ItemFile {
        format: FORMAT,
        sweep: sweep.to_string(),
        item: k,
        label: label.to_string(),
        result,
    })
    .map_err(|e| Error::write(&file, e))?;
    write_atomic(&file, &(text + "\n"))
}

/// Every item's result from DIR; an error naming the missing items (to run
/// again with `--item K`) or a file that belongs to another item.
fn read_items(dir: &Path, m: &Manifest) -> Result<Vec<serde_json::Value>> {
    let digest = m.digest()?;
    let mut out = vec![];
    let mut missing = vec![];
    for (k, label) in m.items.iter().enumerate() {
        let file = item_file(dir, k);
        let text = match std::fs::read_to_string(&file) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                missing.push(format!("{k} ({label})"));
                continue;
            }
            Err(e) => return Err(io(&file)(e)),
        };
        let f: ItemFile = serde_json::from_str(&text).map_err(|e| Error::Parse {
            file: file.clone(),
            message: e.to_string(),
        })?;
        if f.format != FORMAT || f.item != k || &f.label != label {
            return Err(Error::Parse {
                file,
                message: format!(
                    "holds item {} `{}` (format {}), the manifest's item {k} is `{label}` (format {FORMAT})",
                    f.item, f.label, f.format
                ),
            });
        }
        if f.sweep != digest {
            return Err(Error::Parse {
                file,
                message: format!(
                    "item {k} `{label}` ran in another sweep (manifest digest {}, this DIR's sweep.json {digest}): another scene, mesh or argument; run it again here with --item {k}",
                    f.sweep
                ),
            });
        }
        out.push(f.result);
    }
    // Item files the manifest does not list (a larger sweep's, or a stray
    // copy): named, since they are left out of the tables.
    let listed = m.items.len();
    let mut stray: Vec<usize> = std::fs::read_dir(items_dir(dir))
        .map_err(io(dir))?
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter_map(|n| n.strip_suffix(".json")?.parse::<usize>().ok())
        .filter(|&k| k >= listed)
        .collect();
    stray.sort_unstable();
    if !stray.is_empty() {
        eprintln!(
            "warning: {}: item files {} are not items of this sweep ({listed} items, 0 to {}): left out",
            items_dir(dir).display(),
            stray
                .iter()
                .map(|k| format!("{k}.json"))
                .collect::<Vec<_>>()
                .join(", "),
            listed.saturating_sub(1)
        );
    }
    if !missing.is_empty() {
        return Err(Error::Invalid {
            file: items_dir(dir),
            key: "items".into(),
            problem: format!(
                "{} of {} items have no result file: {}; run them with --item K -o {}",
                missing.len(),
                m.items.len(),
                missing.join(", "),
                dir.display()
            ),
        });
    }
    Ok(out)
}

/// Checks that the files the items read are unchanged.
fn check_inputs(m: &Manifest) -> Result<()> {
    for i in &m.inputs {
        if file_digest(&i.file)? != i.digest {
            return Err(Error::Invalid {
                file: i.file.clone(),
                key: "sweep".into(),
                problem: "changed since the items ran: merge the items of one scene and mesh"
                    .into(),
            });
        }
    }
    Ok(())
}

/// Runs item `k` alone and writes `DIR/items/K.json` (and the manifest).
/// Returns the item file.
pub fn run_one(spec: &Spec, sweep: &dyn Sweep, k: usize, dir: &Path) -> Result<PathBuf> {
    let labels = sweep.labels();
    let Some(label) = labels.get(k) else {
        return Err(Error::Invalid {
            file: PathBuf::from("--item"),
            key: "item".into(),
            problem: format!(
                "item {k} does not exist: this sweep has {} items, 0 to {} (--list-items)",
                labels.len(),
                labels.len() as isize - 1
            ),
        });
    };
    let m = manifest(spec, sweep)?;
    prepare(dir, &m, false)?;
    let result = sweep.run_item(k, Some(dir))?;
    write_item(dir, &m.digest()?, k, label, result)?;
    Ok(item_file(dir, k))
}

/// `anm merge DIR`: reads the manifest and every item file and writes the
/// sweep's tables and plots into DIR. `open` builds the sweep from its spec.
pub fn merge_dir(dir: &Path, open: impl Fn(&Spec) -> Result<Box<dyn Sweep>>) -> Result<Merged> {
    let m = read_manifest(dir)?;
    check_inputs(&m)?;
    let sweep = open(&m.spec)?;
    if sweep.labels() != m.items {
        return Err(Error::Invalid {
            file: dir.join("sweep.json"),
            key: "items".into(),
            problem: "the item labels differ from the ones this anm gives the same arguments"
                .into(),
        });
    }
    let items = read_items(dir, &m)?;
    sweep.merge(&items, Some(dir))
}

/// The whole sweep in this process. With `dir`: every item file written as
/// its item ends, then [`merge_dir`] on DIR, exactly as `anm merge DIR`
/// would. Without: the item results go through the same JSON text in
/// memory, then the same merge (tables on stdout only).
pub fn run_all(
    spec: &Spec,
    sweep: &dyn Sweep,
    dir: Option<&Path>,
    open: impl Fn(&Spec) -> Result<Box<dyn Sweep>>,
) -> Result<Merged> {
    let labels = sweep.labels();
    let mut digest = String::new();
    if let Some(dir) = dir {
        let m = manifest(spec, sweep)?;
        prepare(dir, &m, true)?;
        digest = m.digest()?;
    }
    let job = |k: &usize| -> Result<String> {
        let result = sweep.run_item(*k, dir)?;
        match dir {
            Some(dir) => {
                write_item(dir, &digest, *k, &labels[*k], result)?;
                Ok(String::new())
            }
            None => serde_json::to_string(&result).map_err(|e| Error::write("item", e)),
        }
    };
    let ks: Vec<usize> = (0..labels.len()).collect();
    let done: Vec<std::result::Result<Result<String>, String>> = if sweep.concurrent() {
        pool::map(&ks, job)
    } else {
        ks.iter().map(|k| Ok(job(k))).collect()
    };
    let mut texts = vec![];
    for (k, d) in done.into_iter().enumerate() {
        match d {
            Ok(Ok(t)) => texts.push(t),
            Ok(Err(e)) => return Err(e),
            Err(panic) => {
                return Err(Error::study(
                    "sweep",
                    labels[k].clone(),
                    format!("panicked: {panic}"),
                ));
            }
        }
    }
    match dir {
        Some(dir) => merge_dir(dir, open),
        None => {
            let items = texts
                .iter()
                .map(|t| serde_json::from_str(t).map_err(|e| Error::write("item", e)))
                .collect::<Result<Vec<serde_json::Value>>>()?;
            sweep.merge(&items, None)
        }
    }
}

/// The sweep of `spec`: loads and validates its scenes (`anm merge DIR`
/// builds the sweep of DIR's manifest with it).
pub fn open(spec: &Spec) -> Result<Box<dyn Sweep>> {
    use crate::scene::{self, Kind};
    Ok(match spec {
        Spec::Audit {
            scene: path,
            omega,
            zeta,
            eta,
            penalty,
        } => {
            let sweeps = super::audit::Sweeps {
                omega: omega.clone(),
                zeta: zeta.clone(),
                eta: eta.clone(),
                penalty: penalty.clone(),
            };
            let text = scene::read(path)?;
            match scene::kind(path, &text)? {
                Kind::Shell => {
                    let shell = scene::shell::load(path)?;
                    if shell.friction.is_some() {
                        Box::new(super::time_audit::TimeAudit::new(shell, &sweeps)?)
                    } else {
                        Box::new(super::shell_audit::ShellAudit::new(shell, &sweeps)?)
                    }
                }
                kind => Box::new(super::audit::FrictionAudit::new(
                    scene::friction::load(path, &text, kind)?,
                    &sweeps,
                )?),
            }
        }
        Spec::Stress {
            scenes,
            cases,
            max_steps,
        } => Box::new(super::stress::StressSweep::new(scenes, cases, *max_steps)?),
        Spec::Scaling {
            template,
            sizes,
            steps,
            write_matrix,
        } => Box::new(super::scaling::ScalingSweep {
            exe: std::env::current_exe().map_err(io(Path::new("anm")))?,
            template: template.clone(),
            sizes: sizes.clone(),
            steps: *steps,
            write_matrix: *write_matrix,
        }),
    })
}

/// Catches a panic of `f` as `Err(message)` (a run that panics is an item
/// result, as in the single-process pool).
pub fn catch<R>(f: impl FnOnce() -> R) -> std::result::Result<R, String> {
    pool::catch(f)
}

/// Decodes an item result.
pub fn decode<T: serde::de::DeserializeOwned>(k: usize, v: &serde_json::Value) -> Result<T> {
    T::deserialize(v).map_err(|e| Error::Parse {
        file: PathBuf::from(format!("items/{k}.json")),
        message: e.to_string(),
    })
}

/// Decodes every item result, in item order.
pub fn decode_all<T: serde::de::DeserializeOwned>(items: &[serde_json::Value]) -> Result<Vec<T>> {
    items
        .iter()
        .enumerate()
        .map(|(k, v)| decode(k, v))
        .collect()
}

/// Encodes an item result.
pub fn encode<T: Serialize>(v: &T) -> Result<serde_json::Value> {
    serde_json::to_value(v).map_err(|e| Error::write("item", e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_read_back_bit_for_bit() {
        let xs = [
            0.1,
            1.0 / 3.0,
            0.705805084,
            1e-8,
            5e-324,
            f64::MAX,
            -0.0,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            2.0f64.powi(60) + 1.0,
        ];
        let v: Vec<Exact> = xs.iter().map(|x| Exact(*x)).collect();
        let text = serde_json::to_string(&v).unwrap();
        let back: Vec<Exact> = serde_json::from_str(&text).unwrap();
        for (a, b) in xs.iter().zip(&back) {
            assert_eq!(a.to_bits(), b.0.to_bits(), "{a:?} -> {text}");
        }
        // Through serde_json::Value as well (the item results do).
        let value: serde_json::Value = serde_json::from_str(&text).unwrap();
        let back: Vec<Exact> = serde_json::from_value(value).unwrap();
        for (a, b) in xs.iter().zip(&back) {
            assert_eq!(a.to_bits(), b.0.to_bits());
        }
        // Numbers written by hand are read too.
        let n: Exact = serde_json::from_str("2.5").unwrap();
        assert_eq!(n.0, 2.5);
    }
}
