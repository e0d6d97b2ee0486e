//! Notes on contact regularizations that carry the answer.
//!
//! Eq. (3) lets each candidate pull up to eta and sink about R / K into an
//! obstacle. Review 12: eta = 1e3 N on plate-cylinder-coarse (63
//! candidates: 63 kN of possible pull against a 30 N load) gave
//! rn_total = 67 N for the 30 N load with exit 0, and K = 1e-3 N/m ran the
//! strip 1.7 m through the cylinder to max_steps; neither run said why.
//! The audit measures such effects (`anm audit --eta`, `--k`); these notes
//! say when a run's own values make them large.

use crate::contact::obstacle::Obstacle;
use crate::scene::shell::ObstacleSpec;
use crate::shell::ShellModel;

/// The candidates' possible pull, above this fraction of the applied
/// loads, is noted.
const PULL: f64 = 0.1;
/// A candidate deeper than this fraction of the model's size inside its
/// obstacle is noted (a penalty law sinks nodes by R / K by design).
const SINK: f64 = 1e-2;

/// A note when the candidates' eta adds up to a sizeable part of the
/// loads applied at `lambda` (the sum of the absolute load entries).
pub fn pull_note(model: &ShellModel, lambda: f64) -> Option<String> {
    let eta = model.pairs.first()?.law.eta;
    let candidates = {
        let mut nodes: Vec<usize> = model.pairs.iter().map(|p| p.node).collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes.len()
    };
    let pull = candidates as f64 * eta;
    let loads = lambda.abs() * model.dead.iter().map(|f| f.abs()).sum::<f64>();
    (pull > PULL * loads).then(|| {
        format!(
            "contact.eta = {eta:e} per candidate: its {candidates} candidates can pull up to {pull:.3e} in all, {:.2e} times the applied loads' {loads:.3e} (the sum of their entries at the end): eq. (3)'s regularization may carry much of the answer; `anm audit --eta` measures how much",
            pull / loads.max(f64::MIN_POSITIVE)
        )
    })
}

/// A note when a contact candidate ends deeper inside its obstacle than
/// [`SINK`] of the model's size, from the state `full` at `lambda`.
pub fn sink_note(
    model: &ShellModel,
    obstacles: &[Obstacle],
    specs: &[ObstacleSpec],
    full: &[f64],
    lambda: f64,
) -> Option<String> {
    let (depth, pair) = model
        .pairs
        .iter()
        .filter_map(|p| {
            let x = model.position(full, p.node);
            Some((-obstacles[p.obstacle].distance(&x)?, p))
        })
        .max_by(|a, b| a.0.total_cmp(&b.0))?;
    (depth > SINK * model.length_scale).then(|| {
        format!(
            "contact node {} ends {depth:.3e} inside `{}` at lambda = {lambda} ({:.1}% of the model's size): contact.k = {:e} is too soft for the forces it carries (the penalty sinks a node by about R / K)",
            model.node_tag(pair.node),
            specs[pair.obstacle].name,
            100.0 * depth / model.length_scale,
            pair.law.k
        )
    })
}
