//! Nodes inside an obstacle they do not feel.
//!
//! Only the nodes of `contact.group` carry contact terms; the others pass
//! through the obstacles. A strip pulled over rollers with a contact group
//! on part of it was pulled straight through the other rollers, 1.23 m
//! along, with exit 0 and no word after the run (review 10). The run now
//! checks every step end (and a run in time its last state) and says so in
//! its notes.

use crate::contact::obstacle::Obstacle;
use crate::scene::shell::ObstacleSpec;
use crate::shell::ShellModel;

/// The deepest penetration of a state: how many nodes were inside, and
/// the deepest one (depth, node index, obstacle index).
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct Inside {
    pub nodes: usize,
    pub depth: f64,
    pub node: usize,
    pub obstacle: usize,
    /// The path parameter (lambda or t) of that state.
    pub at: f64,
    /// The obstacle the deepest node is paired with, if it is a contact
    /// candidate (paired with another obstacle than the one it is in).
    #[serde(default)]
    pub paired: Option<usize>,
}

/// Nodes inside an obstacle they do not feel (where their motion has
/// taken them) in the state `full` (full dof vector) at `at`: nodes
/// outside the contact candidates, and candidates inside an obstacle they
/// are not paired with. Depths below 1e-9 of the model's length scale are
/// round-off.
///
/// A contact candidate feels only the obstacles it is paired with (with
/// friction, its nearest one): inside another, it is counted (review
/// 27: an idle nip roll 5e-9 m off a wrapped strip took the two nodes
/// under it, which sank 2.8e-6 m into the main roller unfelt, and the
/// held tension moved by 0.37 %, with exit 0 and no note).
pub fn inside(model: &ShellModel, obstacles: &[Obstacle], full: &[f64], at: f64) -> Option<Inside> {
    let mut paired: Vec<Vec<usize>> = vec![vec![]; model.x0.len()];
    for p in &model.pairs {
        paired[p.node].push(p.obstacle);
    }
    let floor = 1e-9 * model.length_scale;
    let mut found: Option<Inside> = None;
    let mut nodes = 0;
    for (node, own) in paired.iter().enumerate() {
        let x = model.position(full, node);
        let deepest = obstacles
            .iter()
            .enumerate()
            .filter(|(k, _)| !own.contains(k))
            .filter_map(|(k, o)| o.distance(&x).map(|d| (-d, k)))
            .filter(|(depth, _)| *depth > floor)
            .max_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((depth, obstacle)) = deepest {
            nodes += 1;
            if found.is_none_or(|f| depth > f.depth) {
                found = Some(Inside {
                    nodes: 0,
                    depth,
                    node,
                    obstacle,
                    at,
                    paired: own.first().copied(),
                });
            }
        }
    }
    found.map(|f| Inside { nodes, ..f })
}

/// The deeper of two penetrations.
pub fn deeper(a: Option<Inside>, b: Option<Inside>) -> Option<Inside> {
    match (a, b) {
        (Some(a), Some(b)) => Some(if b.depth > a.depth { b } else { a }),
        (a, b) => a.or(b),
    }
}

/// The note of the run: `param` names the path parameter ("lambda", "t");
/// `obstacles` are the scene's (for their names).
pub fn note(
    model: &ShellModel,
    inside: &Inside,
    obstacles: &[ObstacleSpec],
    param: &str,
) -> String {
    if let Some(own) = inside.paired {
        return format!(
            "{} nodes were inside an obstacle they do not feel (the deepest: node {} at {:.3e} inside `{}`, at {param} = {}, a contact node paired with `{}`): a contact node feels only the obstacle it was paired with at the start (with friction, its nearest one), so where two obstacles are within contact.search_distance of the same nodes (a nip, a roll close to another) the other passes through it; its forces and the tensions they carry are then wrong there",
            inside.nodes,
            model.node_tag(inside.node),
            inside.depth,
            obstacles[inside.obstacle].name,
            inside.at,
            obstacles[own].name
        );
    }
    format!(
        "{} nodes outside contact.group were inside an obstacle (the deepest: node {} at {:.3e} inside `{}`, at {param} = {}): only the contact group's nodes feel the obstacles, the others pass through them; add those nodes to contact.group",
        inside.nodes,
        model.node_tag(inside.node),
        inside.depth,
        obstacles[inside.obstacle].name,
        inside.at
    )
}
