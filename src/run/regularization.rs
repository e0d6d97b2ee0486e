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

/// Share of the model's largest displacement beyond which a candidate's
/// depth inside its obstacle is noted.
const SINK_SHARE: f64 = 0.1;

/// A note when the candidates' eta adds up to a sizeable part of the
/// forces at `lambda`: the larger of the applied loads (the sum of the
/// absolute load entries) and the contact reactions (the sum of |R|, from
/// the state `full`). A path driven by a moving obstacle or by moments
/// has no load sum (review 15: "3.69e300 times the applied loads' 0"
/// against 1.5 N of contact force).
pub fn pull_note(model: &ShellModel, full: &[f64], lambda: f64) -> Option<String> {
    let eta = model.pairs.first()?.law.eta;
    let candidates = {
        let mut nodes: Vec<usize> = model.pairs.iter().map(|p| p.node).collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes.len()
    };
    // Each (node, obstacle) pair has its own eq. (3) and pulls up to eta
    // (review 21: a strip over two cylinders counted 82 nodes for its 164
    // pairs, half the capacity).
    let pairs = model.pairs.len();
    let pull = pairs as f64 * eta;
    let loads = lambda.abs() * model.dead.iter().map(|f| f.abs()).sum::<f64>();
    let contact: f64 = model
        .contact_forces(full, lambda)
        .map(|c| c.iter().map(|n| n.r.abs()).sum())
        .unwrap_or(0.0);
    let (reference, what) = if contact > loads {
        (contact, "contact reactions'")
    } else {
        (loads, "applied loads'")
    };
    (pull > PULL * reference && reference > 0.0).then(|| {
        format!(
            "contact.eta = {eta:e} per candidate and obstacle: its {pairs} pairs ({candidates} candidate nodes) can pull up to {pull:.3e} in all, {:.2e} times the {what} {reference:.3e} (the sum of their magnitudes at the end): eq. (3)'s regularization may carry much of the answer; `anm audit --eta` measures how much",
            pull / reference
        )
    })
}

/// A note when a contact candidate ends deeper inside its obstacle than
/// [`SINK`] of the model's size, or than [`SINK_SHARE`] of the model's
/// largest displacement (review 15: K = 10 N/m sank a cantilever's tip 6.2
/// times its gap, 86 % of its deflection, and changed the contact force by
/// 23 %, under 1 % of the model's size), from the state `full` at `lambda`.
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
    let moved = model.largest_translation(full);
    let of_size = depth > SINK * model.length_scale;
    let of_motion = depth > SINK_SHARE * moved && depth > 1e-6 * model.length_scale;
    (of_size || of_motion).then(|| {
        // Review 27: two rolls of a nip moved onto a strip that cannot
        // give way held 300 N at K = 1e8 and 30,000 N at 1e10, and the
        // share of the displacement read as a 306-digit number (0 moved).
        if depth >= moved {
            return format!(
                "contact node {} ends {depth:.3e} inside `{}` at lambda = {lambda}, more than the shell's largest displacement ({moved:.3e}): the obstacles' placement or motion overlaps a shell that cannot give way (a nip closing on a strip held between two obstacles), and the contact force there, about K × depth, is set by contact.k = {:e}, not by the structure; leave the shell a way to move, or drive it by a load",
                model.node_tag(pair.node),
                specs[pair.obstacle].name,
                pair.law.k
            );
        }
        format!(
            "contact node {} ends {depth:.3e} inside `{}` at lambda = {lambda} ({:.1}% of the model's size, {:.0}% of its largest displacement): contact.k = {:e} is too soft for the forces it carries (the penalty sinks a node by about R / K)",
            model.node_tag(pair.node),
            specs[pair.obstacle].name,
            100.0 * depth / model.length_scale,
            100.0 * depth / moved.max(f64::MIN_POSITIVE),
            pair.law.k
        )
    })
}
