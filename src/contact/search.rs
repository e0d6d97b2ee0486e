//! Contact candidates: which nodes carry contact terms, and their laws.
//!
//! Every node of the contact group gets, per obstacle, the regularized law
//! of eq. (3) with delta = its initial gap (the gap in the reference
//! configuration). A node is *active* (its term is assembled) while its
//! current gap is below the search distance s. DESIGN §3: a node far from
//! the obstacle would feel the pull R → −eta (h ≫ delta), or, if it started
//! farther than s and closes in, a push of about eta (delta − h)/h; skipping
//! it changes the residual by at most [`skipped_force_bound`], the bound the
//! run summary reports and the shell model uses to decide whether skipping
//! is allowed at all. The active set is refreshed at every step start only,
//! so one ANM step sees one smooth problem.

use super::normal::NormalLaw;
use super::obstacle::{Obstacle, Vec3};

/// One possible contact pair (node, obstacle) with its law.
#[derive(Clone, Debug)]
pub struct ContactPair {
    pub node: usize,
    pub obstacle: usize,
    pub law: NormalLaw,
}

/// All pairs of the candidate nodes with the obstacles; delta is each node's
/// gap at its reference position `x0[node]`. Returns Err(node) for a node
/// whose gap is undefined (on a cylinder axis) or not positive (initially
/// penetrating, where eq. 3 with delta = h0 <= 0 has no contact branch).
pub fn pairs(
    nodes: &[usize],
    x0: &[Vec3],
    obstacles: &[Obstacle],
    k: f64,
    eta: f64,
) -> Result<Vec<ContactPair>, (usize, usize, f64)> {
    let mut out = Vec::new();
    for (oi, ob) in obstacles.iter().enumerate() {
        for &node in nodes {
            let h0 = ob.gap(&x0[node]).map(|g| g.h).unwrap_or(f64::NAN);
            if !(h0 > 0.0) {
                return Err((node, oi, h0));
            }
            out.push(ContactPair {
                node,
                obstacle: oi,
                law: NormalLaw { k, eta, delta: h0 },
            });
        }
    }
    Ok(out)
}

/// Largest |R| a pair can carry while its gap h is at least `distance`:
/// R(h) of eq. (3) decreases from R(distance) toward -eta as h grows, so the
/// bound is max(|R(distance)|, eta). A node that starts far away (delta >
/// distance) and closes in is *pushed* there, by about eta (delta - h) / h,
/// which exceeds eta: e.g. 1.1e-5 N for eta = 1e-6 N, delta = 0.6 m, h = 0.05 m.
pub fn skipped_force_bound(pair: &ContactPair, distance: f64) -> f64 {
    pair.law.force(distance).abs().max(pair.law.eta)
}

/// Indices into `pairs` of the pairs whose current gap is below `distance`
/// (positions `x` of all nodes).
pub fn active(
    pairs: &[ContactPair],
    x: &[Vec3],
    obstacles: &[Obstacle],
    distance: f64,
) -> Vec<usize> {
    pairs
        .iter()
        .enumerate()
        .filter(|(_, p)| {
            obstacles[p.obstacle]
                .gap(&x[p.node])
                .is_some_and(|g| g.h < distance)
        })
        .map(|(i, _)| i)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn search_keeps_only_near_nodes_and_sets_delta_to_the_initial_gap() {
        let cyl = Obstacle::cylinder(Vec3::new(1.0, 0.0, 0.5001), Vec3::y(), 0.5).unwrap();
        let x: Vec<Vec3> = (0..=20)
            .map(|i| Vec3::new(0.1 * i as f64, 0.0, 0.0))
            .collect();
        let all: Vec<usize> = (0..x.len()).collect();
        let p = pairs(&all, &x, std::slice::from_ref(&cyl), 1e9, 1e-6).unwrap();
        assert!((p[10].law.delta - 1e-4).abs() < 1e-15);
        let act = active(&p, &x, &[cyl], 0.05);
        // Gap below 0.05 m: |x - 1| < sqrt(0.55^2 - 0.5001^2) = 0.2288.
        assert_eq!(act, vec![8, 9, 10, 11, 12]);
    }

    #[test]
    fn the_force_bound_of_a_skipped_pair_covers_pull_and_push() {
        let law = NormalLaw {
            k: 1e9,
            eta: 1e-6,
            delta: 0.6,
        };
        let pair = ContactPair {
            node: 0,
            obstacle: 0,
            law,
        };
        let b = skipped_force_bound(&pair, 0.05);
        // Push near the search distance: about eta (delta - h) / h = 1.1e-5 N.
        assert!((b - 1.1e-5).abs() < 1e-8, "{b}");
        for h in [0.05, 0.1, 0.6, 1.0, 10.0, 1e6] {
            assert!(law.force(h).abs() <= b * (1.0 + 1e-12), "h = {h}");
        }
        // A node starting inside the search distance is only ever pulled.
        let near = ContactPair {
            law: NormalLaw { delta: 1e-4, ..law },
            ..pair
        };
        assert_eq!(skipped_force_bound(&near, 0.05), 1e-6);
    }
}
