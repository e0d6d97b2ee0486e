//! Head-to-head at an error target: the fastest ANM setting and the fastest
//! baseline setting (IDA, diffsol BDF or diffsol ESDIRK, whichever is
//! fastest) that reach it, timed again with interleaved repetitions and
//! counted in instructions (issue criteria: "error 1e-8, ANM time <= IDA
//! time"; issue 16: the ANM against the best baseline).
//!
//! The work-precision pass ([`super::bench::work_precision`]) shortlists the
//! settings whose error meets the target by their fastest repetition; the
//! shortlist is then run round after round, every setting once per round, so
//! that all see the same load. Each setting is summarized by its minimum
//! (the least disturbed run) and median, and the chosen pair by the
//! distribution of its per-round time ratio, which cancels load that drifts
//! slower than a round.

use super::bench::{BenchRow, Method};
use super::timing::{self, Spread};
use crate::error::Result;
use crate::scene::friction::FrictionScene;
use std::path::Path;

/// ANM settings and baseline settings kept for the head-to-head.
const SHORTLIST_ANM: usize = 3;
const SHORTLIST_BASELINE: usize = 3;

/// One shortlisted setting, timed.
#[derive(Clone, Debug)]
pub struct Contender {
    pub method: Method,
    pub error: f64,
    pub steps: usize,
    pub spread: Spread,
    /// Instructions of one solve (callgrind), when counted.
    pub instructions: Option<u64>,
}

/// The head-to-head of one case.
#[derive(Clone, Debug)]
pub struct HeadToHead {
    pub case: String,
    pub target: f64,
    /// Every shortlisted setting; [`HeadToHead::anm`] and
    /// [`HeadToHead::baseline`] pick the fastest (by minimum wall time).
    pub contenders: Vec<Contender>,
    /// ANM / best-baseline wall time, round by round, for the two fastest.
    pub ratio: Spread,
}

impl HeadToHead {
    fn fastest(&self, anm: bool) -> Option<&Contender> {
        self.contenders
            .iter()
            .filter(|c| c.method.is_baseline() != anm)
            .min_by(|a, b| a.spread.min().total_cmp(&b.spread.min()))
    }
    pub fn anm(&self) -> Option<&Contender> {
        self.fastest(true)
    }
    /// The fastest baseline (IDA or diffsol).
    pub fn baseline(&self) -> Option<&Contender> {
        self.fastest(false)
    }
}

/// The settings of `rows` (one case) that reach `target`, fastest first by
/// minimum wall time: up to `SHORTLIST_ANM` ANM and `SHORTLIST_BASELINE`
/// baseline ones.
fn shortlist(rows: &[BenchRow], methods: &[Method], target: f64) -> Vec<(Method, f64, usize)> {
    let mut ok: Vec<(&BenchRow, &Method)> = rows
        .iter()
        .filter(|r| r.error <= target)
        .filter_map(|r| {
            methods
                .iter()
                .find(|m| m.label() == r.method && m.setting() == r.setting)
                .map(|m| (r, m))
        })
        .collect();
    ok.sort_by(|a, b| a.0.wall_min_s.total_cmp(&b.0.wall_min_s));
    let pick = |anm: bool, n: usize| {
        ok.iter()
            .filter(move |(_, m)| m.is_baseline() != anm)
            .take(n)
            .map(|(r, m)| ((*m).clone(), r.error, r.steps))
    };
    pick(true, SHORTLIST_ANM)
        .chain(pick(false, SHORTLIST_BASELINE))
        .collect()
}

/// Runs the head-to-head of one case: `rounds` interleaved rounds over the
/// shortlist, and the instruction count of each contender when `anm_exe` (the
/// `anm` binary that `anm time` runs under callgrind) is given.
pub fn head_to_head(
    case: &str,
    scene: &FrictionScene,
    rows: &[BenchRow],
    methods: &[Method],
    target: f64,
    rounds: usize,
    anm_exe: Option<&Path>,
) -> Result<HeadToHead> {
    let list = shortlist(rows, methods, target);
    let ms: Vec<Method> = list.iter().map(|(m, ..)| m.clone()).collect();
    let timed = timing::interleaved(scene, &ms, rounds.max(1))?;
    let contenders: Vec<Contender> = list
        .into_iter()
        .zip(timed)
        .map(|((method, error, steps), t)| Contender {
            instructions: anm_exe.and_then(|exe| timing::instructions(exe, &scene.file, &method)),
            method,
            error,
            steps,
            spread: t.spread,
        })
        .collect();
    let mut h = HeadToHead {
        case: case.into(),
        target,
        contenders,
        ratio: Spread::default(),
    };
    if let (Some(a), Some(i)) = (h.anm(), h.baseline()) {
        h.ratio.samples = a
            .spread
            .samples
            .iter()
            .zip(&i.spread.samples)
            .map(|(x, y)| x / y)
            .collect();
    }
    Ok(h)
}

fn ms(x: f64) -> String {
    format!("{:.3}", 1e3 * x)
}

/// The head-to-heads as markdown: every contender, then the verdict line.
pub fn markdown(list: &[HeadToHead]) -> String {
    let mut s = String::from(
        "| case | target | method | setting | error | steps | wall min (ms) | median (ms) | p10–p90 (ms) | runs | instructions |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for h in list {
        for c in &h.contenders {
            s += &format!(
                "| {} | {:.0e} | {} | {} | {:.2e} | {} | {} | {} | {}–{} | {} | {} |\n",
                h.case,
                h.target,
                c.method.label(),
                c.method.setting(),
                c.error,
                c.steps,
                ms(c.spread.min()),
                ms(c.spread.median()),
                ms(c.spread.quantile(0.1)),
                ms(c.spread.quantile(0.9)),
                c.spread.samples.len(),
                c.instructions
                    .map(|n| format!("{:.2}M", n as f64 / 1e6))
                    .unwrap_or_else(|| "–".into()),
            );
        }
    }
    s += "\n| case | target | fastest ANM | fastest baseline | ANM / baseline: min | per-round median (p10–p90) | instructions |\n|---|---|---|---|---|---|---|\n";
    for h in list {
        let (Some(a), Some(i)) = (h.anm(), h.baseline()) else {
            s += &format!(
                "| {} | {:.0e} | {} | {} | – | – | – |\n",
                h.case,
                h.target,
                h.anm()
                    .map_or("none reaches it".into(), |a| a.method.spec()),
                h.baseline()
                    .map_or("none reaches it".into(), |i| i.method.spec()),
            );
            continue;
        };
        let instr = match (a.instructions, i.instructions) {
            (Some(x), Some(y)) => format!("{:.2}", x as f64 / y as f64),
            _ => "–".into(),
        };
        s += &format!(
            "| {} | {:.0e} | {} {} | {} {} | {:.2} | {:.2} ({:.2}–{:.2}) | {} |\n",
            h.case,
            h.target,
            a.method.label(),
            a.method.setting(),
            i.method.label(),
            i.method.setting(),
            a.spread.min() / i.spread.min(),
            h.ratio.median(),
            h.ratio.quantile(0.1),
            h.ratio.quantile(0.9),
            instr,
        );
    }
    s
}

/// Writes target.md.
pub fn write(list: &[HeadToHead], dir: &Path) -> Result<()> {
    let file = dir.join("target.md");
    std::fs::write(&file, markdown(list)).map_err(|e| crate::Error::Io { file, source: e })
}
