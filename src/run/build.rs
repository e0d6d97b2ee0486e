//! A shell scene assembled into the problem the engine continues: elements,
//! essential conditions with their values per unit lambda, loads, obstacles
//! with their motion and the contact candidates (DESIGN §1, §3).

use crate::contact::search;
use crate::error::{Error, Result};
use crate::fe::dof::{Component, Dof, PER_NODE};
use crate::fe::{edge_load, surface_load};
use crate::mesh::Vec3;
use crate::scene::shell::{Load, ShellScene};
use crate::shell::model::FollowerPressure;
use crate::shell::{FollowerCouple, ShellModel};
use nalgebra::{DMatrix, Matrix6, SymmetricEigen};

/// Builds the shell model of a scene. Errors name the scene key at fault: an
/// inverted element (mesh file and line), a contact node that starts inside
/// an obstacle, fixes that leave a rigid-body motion free.
pub fn build_model(scene: &ShellScene) -> Result<ShellModel> {
    let mut m = ShellModel::new(
        scene.mesh.nodes.clone(),
        scene.directors.clone(),
        &scene.mesh.quads,
        scene.thickness,
        scene.material,
    )
    .map_err(|e| match e {
        Error::Element { element, problem } => Error::Mesh {
            file: scene.mesh.file.clone(),
            line: scene.mesh.quad_lines[element],
            problem: format!("element {}: {problem}", scene.mesh.quad_tags[element]),
        },
        other => other,
    })?;
    let fixed: Vec<(usize, usize)> = scene
        .fixed
        .keys()
        .map(|d| (d.node, d.component.offset()))
        .collect();
    m.node_tags = scene.mesh.node_tags.clone();
    m.length_scale = scene.length_scale;
    m.set_constraints(&fixed);
    let mut prescribed = vec![0.0; PER_NODE * m.n_nodes()];
    for (d, v) in &scene.fixed {
        prescribed[d.index()] = *v;
    }
    m.set_prescribed(prescribed);
    let quads = &scene.mesh.quads;
    let own_ramp: Vec<usize> = scene
        .friction
        .as_ref()
        .map(|f| f.load_ramps.iter().map(|(i, _)| *i).collect())
        .unwrap_or_default();
    for (i, load) in scene.loads.iter().enumerate() {
        if own_ramp.contains(&i) {
            // In time, with its own ramp: FrictionDae adds it (dead_pattern).
            continue;
        }
        if let Some(p) = dead_pattern(scene, load) {
            for (d, v) in m.dead.iter_mut().zip(p) {
                *d += v;
            }
            continue;
        }
        match load {
            Load::Moment { nodes, moment } => {
                for &n in nodes {
                    m.follower.push(FollowerCouple {
                        node: n,
                        moment: *moment,
                    });
                }
            }
            Load::Pressure {
                quads: elems,
                pressure,
                follower: true,
            } => {
                for &q in elems {
                    m.pressures.push(FollowerPressure {
                        nodes: quads[q],
                        pressure: *pressure,
                    });
                }
            }
            _ => unreachable!("dead_pattern covers every dead load"),
        }
    }
    // The residual norms square forces (see the scene's E t L check).
    let size = scene.mesh.size();
    let follower = m
        .pressures
        .iter()
        .map(|p| p.pressure.abs() * size * size)
        .chain(m.follower.iter().map(|c| c.moment.norm() / size))
        .fold(0.0, f64::max);
    let loads = m.dead.iter().fold(follower, |a, x| a.max(x.abs()));
    if !(loads <= 1e150) {
        return Err(Error::Invalid {
            file: scene.file.clone(),
            key: "load".into(),
            problem: format!(
                "the loads reach {loads:.3e} (force): squared in the residual norms they leave the range of a double; rescale the units"
            ),
        });
    }
    if let Some(ct) = &scene.contact {
        let shapes = scene.obstacles.iter().map(|o| o.shape.clone()).collect();
        m.set_contact(shapes, &ct.nodes, ct.k, ct.eta, ct.search_distance)
            .map_err(|(node, ob, h0)| Error::Invalid {
                file: scene.file.clone(),
                key: format!("obstacle[{ob}]"),
                problem: format!(
                    "contact node {} at {:?} has initial gap {h0:e}: {}{}",
                    scene.mesh.node_tags[node],
                    scene.mesh.nodes[node].as_slice(),
                    // Review 21: the penalty law has no delta; what both
                    // laws need is an unloaded start off the obstacle.
                    if ct.eta == 0.0 {
                        "the penalty law's series steps start off its kink (h = 0) and the unloaded shell must not be inside the obstacle: give the candidates a small initial gap (move the obstacle off by ~1e-6 of the model's size)"
                    } else {
                        "eq. (3) needs delta = h0 > 0 (the node starts on or inside the obstacle): give the candidates a small initial gap (move the obstacle off by ~1e-6 of the model's size)"
                    },
                    // Review 10: an off-centre crown gave this message
                    // with no word of the crown.
                    match scene.obstacles[ob].shape {
                        crate::contact::obstacle::Obstacle::Cylinder { crown, .. }
                            if crown > 0.0 =>
                        {
                            "; a crowned roll is highest at its centre's section, and a strip path runs at the radius of the strip's middle section: centre the crown on the strip (obstacle.centre) or raise mesh.offset above the crown's rise there"
                        }
                        _ => "",
                    }
                ),
            })?;
        // As the point-mass scenes (scene::friction): eq. (3) has a real
        // root at every gap only while eta < K delta. Review 12: eta = 1e12
        // on plate-cylinder-coarse ran into a bare "no convergence" at
        // lambda = 1e-11 after 1,151 factorizations.
        if let Some(p) = m
            .pairs
            .iter()
            .filter(|p| p.law.eta > 0.0)
            .min_by(|a, b| a.law.delta.total_cmp(&b.law.delta))
            .filter(|p| p.law.eta >= p.law.k * p.law.delta)
        {
            return Err(Error::Invalid {
                file: scene.file.clone(),
                key: "contact.eta".into(),
                problem: format!(
                    "{:e} must be below K delta for eq. (3) to have a real root at every gap: contact node {} starts at the gap delta = {:e} from obstacle[{}], so K delta = {:e}",
                    p.law.eta,
                    scene.mesh.node_tags[p.node],
                    p.law.delta,
                    p.obstacle,
                    p.law.k * p.law.delta
                ),
            });
        }
        m.set_motions(scene.obstacles.iter().map(|o| o.motion).collect());
        if scene.friction.is_some() {
            m.keep_nearest_pairs();
        }
        if scene.friction.is_none() {
            // Frictionless contact holds a rigid motion only along the
            // obstacles' normals (in time, with friction, the strip's
            // rigid motion along its path is the conveying itself).
            let normals: Vec<(usize, Vec3)> = m
                .pairs
                .iter()
                .filter_map(|p| Some((p.node, m.obstacles[p.obstacle].gap(&m.x0[p.node])?.n)))
                .collect();
            check_rigid_modes(scene, &normals)?;
        }
        m.kink_band = kink_band(&m, scene.solver.residual_tol);
        if !far_nodes_may_be_skipped(&m, scene.solver.residual_tol) {
            m.search_distance = f64::INFINITY;
            let rest = vec![0.0; PER_NODE * m.n_nodes()];
            m.update_active(&rest, 0.0);
        }
    } else {
        check_rigid_modes(scene, &[])?;
    }
    Ok(m)
}

/// The nodal force vector (full dofs) of a dead load: a force per node,
/// a line force lumped on its edges, a traction or a dead pressure. None
/// for the follower loads (couples, follower pressures), which the model
/// applies at the current state.
pub fn dead_pattern(scene: &ShellScene, load: &Load) -> Option<Vec<f64>> {
    let x0 = &scene.mesh.nodes;
    let quads = &scene.mesh.quads;
    let mut out = vec![0.0; PER_NODE * x0.len()];
    let mut add = |node: usize, f: Vec3| {
        for (k, c) in Component::DISPLACEMENT.into_iter().enumerate() {
            out[Dof::new(node, c).index()] += f[k];
        }
    };
    let forces: Vec<(usize, Vec3)> = match load {
        Load::Nodal { nodes, force } => nodes.iter().map(|&n| (n, *force)).collect(),
        Load::Line { edges, force } => edge_load::assemble_line_load(x0, edges, *force)
            .into_iter()
            .enumerate()
            .collect(),
        Load::Traction {
            quads: elems,
            traction,
        } => surface_load::assemble_dead_traction(*traction, quads, elems, x0)
            .into_iter()
            .enumerate()
            .collect(),
        // A dead pressure is the follower pressure of the reference
        // configuration (its normal and area), held fixed.
        Load::Pressure {
            quads: elems,
            pressure,
            follower: false,
        } => surface_load::assemble_follower(*pressure, quads, elems, x0)
            .into_iter()
            .enumerate()
            .collect(),
        Load::Moment { .. } | Load::Pressure { follower: true, .. } => return None,
    };
    for (n, f) in forces {
        add(n, f);
    }
    Some(out)
}

/// |F|: the 2-norm of the dead load pattern on the free dofs (N), the scale
/// of the residual test |R| / |F| <= solver.residual_tol.
pub fn load_norm(m: &ShellModel) -> f64 {
    m.dead
        .iter()
        .zip(&m.free)
        .filter(|(_, f)| f.is_some())
        .map(|(x, _)| x * x)
        .sum::<f64>()
        .sqrt()
}

/// The penalty law's band around its kink (ShellModel::kink_band): K band
/// = 0.1 solver.residual_tol |F|, the force a pair may miss, and at least
/// the round-off of a gap, epsilon times the model's size (plate-cylinder,
/// K = 1e9 N/m, |F| = 17.3 N: 1.7e-15 m at residual_tol = 1e-6; at 1e-7 the
/// round-off floor, 4.4e-16 m, about 4 ulps of a 1 m coordinate).
fn kink_band(m: &ShellModel, residual_tol: f64) -> f64 {
    let k = m.pairs.iter().map(|p| p.law.k).fold(0.0, f64::max);
    let size = m.x0.iter().map(|x| x.norm()).fold(0.0, f64::max);
    let round_off = f64::EPSILON * size;
    if k > 0.0 {
        (0.1 * residual_tol * load_norm(m) / k).max(round_off)
    } else {
        round_off
    }
}

/// DESIGN §3: far candidates may be left out of the active set only where
/// their forces are below the accuracy asked for. A pair left out at gap
/// h >= s (the search distance) carries at most
/// [`search::skipped_force_bound`] (a pull of up to eta, or a push of about
/// eta (delta − h) / h for a node that started farther than s); skipping is
/// allowed while the 2-norm of those bounds stays within
/// solver.residual_tol |F|. Otherwise every candidate carries its term.
pub fn far_nodes_may_be_skipped(m: &ShellModel, residual_tol: f64) -> bool {
    let bound = m
        .pairs
        .iter()
        .map(|p| search::skipped_force_bound(p, m.search_distance).powi(2))
        .sum::<f64>()
        .sqrt();
    bound <= residual_tol * load_norm(m)
}

/// The free rigid motions, the columns of `null` (orthonormal; rows t, then
/// ω scaled by the model size), in words. The basis is first turned so
/// that its pure translations come apart (the right singular vectors of
/// its rotation rows with a zero singular value); each other motion is
/// then a rotation ω about the axis through p = c + ω × t / |ω|² (plus a
/// slide along ω, a screw, where t · ω ≠ 0): a plate on a cylinder turns
/// about the cylinder's axis.
fn describe_free_motions(null: &DMatrix<f64>, c: Vec3, size: f64) -> Vec<String> {
    if null.ncols() == 0 {
        return vec![];
    }
    let rotation = null.rows(3, 3).into_owned();
    let svd = rotation.svd(false, true);
    let v_t = svd.v_t.expect("asked for");
    let basis = null * v_t.transpose();
    let clean = |x: f64| if x.abs() < 1e-9 { 0.0 } else { x };
    let xyz = |v: Vec3| {
        format!(
            "({:.3}, {:.3}, {:.3})",
            clean(v[0]),
            clean(v[1]),
            clean(v[2])
        )
    };
    (0..basis.ncols())
        .map(|j| {
            let u = basis.column(j);
            let (mut t, mut w) = (
                Vec3::new(u[0], u[1], u[2]),
                Vec3::new(u[3], u[4], u[5]) / size,
            );
            // The sign that makes the direction's largest component
            // positive (a null vector's sign is arbitrary).
            let d = if w.norm() * size < 1e-9 { t } else { w };
            if d[d.iamax()] < 0.0 {
                (t, w) = (-t, -w);
            }
            if w.norm() * size < 1e-9 {
                return format!("translation along {}", xyz(t / t.norm()));
            }
            let axis = w / w.norm();
            let p = c + w.cross(&t) / w.norm_squared();
            let slide = t.dot(&axis);
            let screw = match slide.abs() < 1e-9 * t.norm().max(w.norm() * size) {
                true => String::new(),
                false => format!(
                    " with a slide along it ({:.3e} per radian)",
                    slide / w.norm()
                ),
            };
            format!(
                "rotation about the axis {} through ({:.4}, {:.4}, {:.4}){screw}",
                xyz(axis),
                clean(p[0]),
                clean(p[1]),
                clean(p[2])
            )
        })
        .collect()
}

/// Fixes and frictionless contact must hold every rigid-body motion of the
/// shell. A rigid motion (translation t, rotation ω about the mesh centroid
/// c) moves node n by t + ω × (X_n − c) and turns its director by ω × A3; it
/// is free when it moves no fixed dof and changes no contact candidate's gap
/// to first order (its displacement along the obstacle's normal n at the
/// node, `contact`). The free ones are the null space of the 6 × 6 Gram
/// matrix of those rows of the six modes. (A shell resting on a cylinder
/// alone may slide along its axis and turn about it: its tangent is
/// singular, and the factorization's round-off pivots read as bifurcations.)
fn check_rigid_modes(scene: &ShellScene, contact: &[(usize, Vec3)]) -> Result<()> {
    let x0 = &scene.mesh.nodes;
    let c = x0.iter().fold(Vec3::zeros(), |a, x| a + x) / x0.len() as f64;
    let size = scene.mesh.size();
    let mut g = Matrix6::<f64>::zeros();
    let mut add = |row: [f64; 6]| {
        for i in 0..6 {
            for j in 0..6 {
                g[(i, j)] += row[i] * row[j];
            }
        }
    };
    // Mode j's displacement of node n (translation along e_j for j < 3,
    // rotation about e_{j-3} through c, scaled by the size) and its
    // director's turn.
    let unit = |j: usize| {
        let mut e = Vec3::zeros();
        e[j % 3] = 1.0;
        e
    };
    let moves = |j: usize, n: usize| match j < 3 {
        true => unit(j),
        false => unit(j).cross(&(x0[n] - c)) / size,
    };
    let turns = |j: usize, n: usize| match j < 3 {
        true => Vec3::zeros(),
        false => unit(j).cross(&scene.directors[n]),
    };
    for &(node, n) in contact {
        add(std::array::from_fn(|j| n.dot(&moves(j, node)) / n.norm()));
    }
    for d in scene.fixed.keys() {
        let k = d.component.offset() % 3;
        add(std::array::from_fn(|j| {
            match d.component.is_displacement() {
                true => moves(j, d.node)[k],
                false => turns(j, d.node)[k],
            }
        }));
    }
    let eig = SymmetricEigen::new(g);
    let top = eig.eigenvalues.max().max(1.0);
    let null: Vec<usize> = (0..6)
        .filter(|&i| eig.eigenvalues[i] <= 1e-10 * top)
        .collect();
    let free = describe_free_motions(
        &DMatrix::from_fn(6, null.len(), |r, j| eig.eigenvectors[(r, null[j])]),
        c,
        size,
    );
    if free.is_empty() {
        return Ok(());
    }
    Err(Error::Invalid {
        file: scene.file.clone(),
        key: "fix".into(),
        problem: format!(
            "the fixed dofs{} leave the shell free to move as a rigid body (singular stiffness): {}; fix more components ([[fix]] with clamp, symmetry, simply_supported or dofs)",
            match contact.is_empty() {
                true => "",
                false =>
                    " and the frictionless contact (which holds only along the obstacles' normals)",
            },
            free.join("; ")
        ),
    })
}
