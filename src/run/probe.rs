//! The scene's probes evaluated at a state (one history.csv row), and the
//! contact and reaction fields that the probes, VTK and HDF5 files share.

use crate::error::Result;
use crate::fe::dof::{Component, Dof, node_vector};
use crate::mesh::Vec3;
use crate::scene::shell::{Probe, Quantity};
use crate::shell::ShellModel;

/// A state on the path: the full vector (fixed dofs included), lambda and
/// the scaled arclength from the start of the run.
pub struct State<'a> {
    pub full: &'a [f64],
    pub lambda: f64,
    pub arclength: f64,
    /// The full residual that support reactions are read from, where it is
    /// not the model's at this state (a linear analysis gives the linear
    /// part of the residual: [`linear_residual`]); None: the model's.
    pub residual: Option<&'a [f64]>,
    /// (u_1, lambda_end) of a linear analysis (u = lambda u_1): the
    /// section forces are then the linear model's ([`linear_tension`]), not
    /// the shell's nonlinear ones at the linear solution.
    pub linear: Option<(&'a [f64], f64)>,
}

/// The residual of a linear analysis along its solution (λ u_1, λ):
/// R_lin(λ) = R_0 + λ R_1, with R_1 = dR/dλ along the path at λ = 0 on every
/// dof (fixed ones included), so that its support reactions balance the
/// loads of the linear model. R_1 is the derivative at 0 of the
/// interpolating cubic through the model's residual at λ = 0, h, 2h, 3h:
/// exact for the shell's internal forces, cubic in the displacements, and
/// for dead and follower loads (polynomials of degree ≤ 3 in λ along the
/// path). h = λ_end / 3, shortened so that h u_1 stays within 1e-2 of each
/// unknown's scale (model length, or 1 for a director): beyond it the
/// nonlinear terms' round-off swamps the linear part (review 5: at a
/// deflection of 1.4e4 plate lengths the reactions summed to 9.16 N for
/// 1 N of load). (A linear run refuses contact, whose law is not a
/// polynomial.) Returns (R_0, R_1).
pub fn linear_residual(
    model: &ShellModel,
    u1: &[f64],
    lambda_end: f64,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let rotation = u1
        .iter()
        .zip(model.scales())
        .map(|(x, s)| x.abs() / s)
        .fold(0.0, f64::max);
    let third = lambda_end / 3.0;
    let h = third * (1e-2 / (third.abs() * rotation)).min(1.0);
    let at = |k: f64| -> Result<Vec<f64>> {
        let l = k * h;
        let u: Vec<f64> = u1.iter().map(|x| l * x).collect();
        model.residual_full(&model.expand(&u, l), l)
    };
    let (r0, r1, r2, r3) = (at(0.0)?, at(1.0)?, at(2.0)?, at(3.0)?);
    let slope = r0
        .iter()
        .zip(&r1)
        .zip(&r2)
        .zip(&r3)
        .map(|(((&a, &b), &c), &d)| slope_at_zero([a, b, c, d], h))
        .collect();
    Ok((r0, slope))
}

/// The derivative at 0 of the cubic through (k h, f_k), k = 0..3
/// (Lagrange).
fn slope_at_zero(f: [f64; 4], h: f64) -> f64 {
    (-11.0 * f[0] + 18.0 * f[1] - 9.0 * f[2] + 2.0 * f[3]) / (6.0 * h)
}

/// The tension across `cut` of a linear analysis at lambda: lambda times
/// its derivative at 0 along (lambda u_1, lambda), from the interpolating
/// cubic through lambda = 0, h, 2h, 3h as in [`linear_residual`], with a
/// short h = 1e-3 lambda_end / 3: the element forces are cubic in the
/// displacements, but the cut's current directions are not polynomial
/// (they enter the derivative at order 0 only, where the forces are
/// zero; the difference error is O(h³), round-off ~1e-12). The shell's tension
/// at the linear solution held the nonlinear terms: 200.345 N for a
/// reaction of 200 N, +18 % at 100 times the load (review 4).
pub fn linear_tension(
    model: &ShellModel,
    cut: &crate::mesh::Cut,
    u1: &[f64],
    lambda_end: f64,
    lambda: f64,
) -> f64 {
    let h = 1e-3 * lambda_end / 3.0;
    let at = |k: f64| {
        let l = k * h;
        let u: Vec<f64> = u1.iter().map(|x| l * x).collect();
        super::section::tension(model, cut, &model.expand(&u, l))
    };
    lambda * slope_at_zero([at(0.0), at(1.0), at(2.0), at(3.0)], h)
}

/// Contact of one pair at a state.
#[derive(Clone, Debug)]
pub struct PairContact {
    pub node: usize,
    pub obstacle: usize,
    pub gap: f64,
    /// Normal reaction R (eq. 3), positive when the obstacle pushes.
    pub r: f64,
    pub normal: Vec3,
}

/// Contact reactions of every candidate pair at the state, by eq. (3) (the
/// stated problem, including far candidates the model may skip while their
/// forces stay below the residual tolerance, DESIGN §3).
pub fn contacts(model: &ShellModel, full: &[f64], lambda: f64) -> Vec<PairContact> {
    let x = model.positions(full);
    let obstacles = model.obstacles_at(lambda);
    model
        .pairs
        .iter()
        .filter_map(|p| {
            let g = obstacles[p.obstacle].gap(&x[p.node])?;
            Some(PairContact {
                node: p.node,
                obstacle: p.obstacle,
                gap: g.h,
                r: p.law.force(g.h),
                normal: g.n,
            })
        })
        .collect()
}

/// Per node: normal reaction R summed over obstacles, and force Σ R n.
pub fn nodal_contact(n_nodes: usize, contacts: &[PairContact]) -> (Vec<f64>, Vec<Vec3>) {
    let mut r = vec![0.0; n_nodes];
    let mut f = vec![Vec3::zeros(); n_nodes];
    for c in contacts {
        r[c.node] += c.r;
        f[c.node] += c.normal * c.r;
    }
    (r, f)
}

/// One value per probe, in scene order.
pub fn evaluate(model: &ShellModel, probes: &[Probe], s: &State) -> Result<Vec<f64>> {
    let needs_contact = probes.iter().any(|p| {
        matches!(
            p.quantity,
            Quantity::ContactNormal { .. }
                | Quantity::ContactForce { .. }
                | Quantity::MinGap { .. }
                | Quantity::Contacts { .. }
        )
    });
    let cont = if needs_contact {
        contacts(model, s.full, s.lambda)
    } else {
        vec![]
    };
    let needs_residual = probes
        .iter()
        .any(|p| matches!(p.quantity, Quantity::Reaction { .. }));
    let residual = match (needs_residual, s.residual) {
        (true, Some(r)) => r.to_vec(),
        // Support reactions: the residual f_int − f_ext at the fixed dofs.
        (true, None) => model.residual_full(s.full, s.lambda)?,
        (false, _) => vec![],
    };
    let mean = |nodes: &[usize], f: &dyn Fn(usize) -> f64| {
        nodes.iter().map(|&n| f(n)).sum::<f64>() / nodes.len() as f64
    };
    let selected = |c: &&PairContact, nodes: &Option<Vec<usize>>, obstacle: &Option<usize>| {
        obstacle.is_none_or(|o| c.obstacle == o)
            && nodes
                .as_ref()
                .is_none_or(|ns| ns.binary_search(&c.node).is_ok())
    };
    Ok(probes
        .iter()
        .map(|p| match &p.quantity {
            Quantity::Dof { nodes, component } => {
                mean(nodes, &|n| s.full[Dof::new(n, *component).index()])
            }
            Quantity::Position { nodes, axis } => mean(nodes, &|n| {
                model.x0[n][*axis] + node_vector(s.full, n, Component::DISPLACEMENT)[*axis]
            }),
            Quantity::Reaction { nodes, axis } => nodes
                .iter()
                .map(|&n| residual[Dof::new(n, Component::DISPLACEMENT[*axis]).index()])
                .sum(),
            Quantity::ContactNormal { nodes, obstacle } => cont
                .iter()
                .filter(|c| selected(c, nodes, obstacle))
                .map(|c| c.r)
                .sum(),
            Quantity::ContactForce {
                nodes,
                obstacle,
                axis,
            } => cont
                .iter()
                .filter(|c| selected(c, nodes, obstacle))
                .map(|c| c.r * c.normal[*axis])
                .sum(),
            Quantity::MinGap { obstacle } => cont
                .iter()
                .filter(|c| obstacle.is_none_or(|o| c.obstacle == o))
                .map(|c| c.gap)
                .fold(f64::INFINITY, f64::min),
            Quantity::Contacts { obstacle } => cont
                .iter()
                .filter(|c| obstacle.is_none_or(|o| c.obstacle == o) && c.gap <= 0.0)
                .count() as f64,
            Quantity::Lambda => s.lambda,
            Quantity::Arclength => s.arclength,
            Quantity::Tension { cut } => match s.linear {
                Some((u1, end)) => linear_tension(model, cut, u1, end, s.lambda),
                None => super::section::tension(model, cut, s.full),
            },
        })
        .collect())
}
