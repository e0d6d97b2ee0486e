//! Shell scenes (`kind = "plate-cylinder"`): a gmsh mesh, a 3D shell
//! material and thickness, clamped groups, dead point loads, rigid
//! obstacles with the regularized contact law (eq. 3), solver and output
//! settings. Every parameter is settable; validation errors name the file and
//! the key (`table.key`, `load[i].point`).
//!
//! ```toml
//! [scene]
//! kind = "plate-cylinder"
//! [mesh]
//! file = "../meshes/plate-cylinder.msh"   # relative to the scene file
//! clamp = ["clamp"]                       # physical groups, all 6 dofs fixed
//! contact = "strip"                       # physical group of candidate nodes
//! [material]
//! young = 200e9
//! poisson = 0.3
//! [shell]
//! thickness = 0.8e-3
//! [[obstacle]]
//! type = "cylinder"                       # or "plane" (point, normal)
//! centre = [1.0, 0.0, 0.5001]
//! axis = [0.0, 1.0, 0.0]
//! radius = 0.5
//! [contact]
//! k = 1e9
//! eta = 1e-6
//! search_distance = 0.05
//! [[load]]
//! point = [2.0, 0.0, 0.0]                 # or group = "load_A"
//! force = [0.0, 0.0, 10.0]                # per node, times lambda
//! [solver]
//! order = 15
//! eps = 1e-8
//! ...
//! [output]
//! lambda_step = 0.01
//! ...
//! ```

use super::{Checker, Kind, parse, read, relative_to};
use crate::contact::Obstacle;
use crate::error::Result;
use crate::mesh::{Mesh, Vec3, gmsh};
use crate::series::ContinuationConfig;
use crate::shell::Material;
use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Raw {
    scene: RawScene,
    mesh: RawMesh,
    material: RawMaterial,
    shell: RawShell,
    #[serde(default)]
    obstacle: Vec<RawObstacle>,
    contact: Option<RawContact>,
    #[serde(default)]
    load: Vec<RawLoad>,
    solver: RawSolver,
    output: RawOutput,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    kind: String,
    #[serde(default)]
    description: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMesh {
    file: String,
    clamp: Vec<String>,
    contact: Option<String>,
    /// Tolerance (m) to match load points and probes with nodes.
    #[serde(default = "default_node_tol")]
    node_tolerance: f64,
}

fn default_node_tol() -> f64 {
    1e-9
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    young: f64,
    poisson: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawShell {
    thickness: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawObstacle {
    #[serde(rename = "type")]
    kind: String,
    centre: Option<[f64; 3]>,
    axis: Option<[f64; 3]>,
    radius: Option<f64>,
    point: Option<[f64; 3]>,
    normal: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawContact {
    k: f64,
    eta: f64,
    search_distance: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLoad {
    point: Option<[f64; 3]>,
    group: Option<String>,
    force: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSolver {
    order: usize,
    eps: f64,
    #[serde(default)]
    pade: bool,
    lambda_end: f64,
    #[serde(default = "default_max_steps")]
    max_steps: usize,
    #[serde(default = "default_residual_tol")]
    residual_tol: f64,
    #[serde(default = "default_true")]
    correct: bool,
    #[serde(default = "default_max_corr")]
    max_corrections: usize,
    /// "anm" (default) or "newton" (the Newton-Raphson baseline).
    method: Option<String>,
    /// Newton: "arclength" (default) or "load" control.
    newton_control: Option<String>,
    /// Newton: first increment (of the arclength, or of lambda).
    newton_step: Option<f64>,
    /// Newton: largest increment.
    newton_max_step: Option<f64>,
    /// Newton: convergence tolerance on |R| / |R_lambda|.
    newton_tol: Option<f64>,
}

fn default_max_steps() -> usize {
    20_000
}
fn default_residual_tol() -> f64 {
    1e-6
}
fn default_true() -> bool {
    true
}
fn default_max_corr() -> usize {
    10
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOutput {
    /// Uniform lambda grid step of history.csv.
    lambda_step: f64,
    /// Probe point A (uz_A, ux_A).
    probe: [f64; 3],
    /// x of the node rows B, C, D (rn_B, rn_C, rn_D).
    contact_rows: [f64; 3],
    /// VTK of the deformed shell every `vtk_every` steps (0: none) and at the end.
    #[serde(default = "default_vtk_every")]
    vtk_every: usize,
    #[serde(default = "default_true")]
    plot: bool,
    /// Lambda values (on the grid) where the full mid-surface fields are
    /// kept: HDF5 output and the comparison with the dolfinx reference.
    #[serde(default = "default_snapshots")]
    snapshots: Vec<f64>,
    /// Write fields.h5 (needs a build with the `hdf5` feature).
    #[serde(default)]
    hdf5: bool,
}

fn default_snapshots() -> Vec<f64> {
    vec![0.05, 0.1, 0.2, 0.5, 1.0]
}

fn default_vtk_every() -> usize {
    10
}

/// A point load: node and force per unit lambda.
#[derive(Clone, Debug)]
pub struct PointLoad {
    pub node: usize,
    pub force: Vec3,
}

/// A validated shell scene.
#[derive(Clone, Debug)]
pub struct ShellScene {
    pub file: PathBuf,
    pub description: Option<String>,
    pub mesh: Mesh,
    pub directors: Vec<Vec3>,
    pub material: Material,
    pub thickness: f64,
    pub clamped: Vec<usize>,
    pub obstacles: Vec<Obstacle>,
    pub contact_nodes: Vec<usize>,
    pub contact_k: f64,
    pub contact_eta: f64,
    pub search_distance: f64,
    pub loads: Vec<PointLoad>,
    pub solver: ContinuationConfig,
    pub lambda_step: f64,
    pub probe: usize,
    pub rows: [Vec<usize>; 3],
    pub row_x: [f64; 3],
    pub vtk_every: usize,
    pub plot: bool,
    /// The Newton-Raphson baseline instead of the ANM (`solver.method = "newton"`).
    pub newton: Option<crate::series::newton::NewtonConfig>,
    pub snapshots: Vec<f64>,
    pub hdf5: bool,
}

fn v3(a: [f64; 3]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

/// Loads and validates a plate-cylinder (shell) scene.
pub fn load(path: &Path) -> Result<ShellScene> {
    let text = read(path)?;
    let raw: Raw = parse(path, &text)?;
    let c = Checker { file: path };
    if raw.scene.kind != Kind::PlateCylinder.name() {
        return Err(c.fail(
            "scene.kind",
            format!("expected `plate-cylinder`, got `{}`", raw.scene.kind),
        ));
    }
    let young = c.positive("material.young", raw.material.young)?;
    let poisson = c.finite("material.poisson", raw.material.poisson)?;
    if !(-1.0 < poisson && poisson < 0.5) {
        return Err(c.fail(
            "material.poisson",
            format!("must lie in (-1, 0.5), got {poisson}"),
        ));
    }
    let thickness = c.positive("shell.thickness", raw.shell.thickness)?;
    let tol = c.positive("mesh.node_tolerance", raw.mesh.node_tolerance)?;
    let mesh_path = relative_to(path, &raw.mesh.file);
    let mesh = gmsh::read(&mesh_path)?;
    let directors = mesh.directors()?;
    let mut clamped = vec![];
    for (i, g) in raw.mesh.clamp.iter().enumerate() {
        clamped.extend_from_slice(mesh.group(g, path, &format!("mesh.clamp[{i}]"))?);
    }
    if clamped.is_empty() {
        return Err(c.fail(
            "mesh.clamp",
            "no clamped node: the problem would be singular",
        ));
    }
    let mut obstacles = vec![];
    for (i, o) in raw.obstacle.iter().enumerate() {
        let key = |k: &str| format!("obstacle[{i}].{k}");
        let need = |v: Option<[f64; 3]>, k: &str| {
            v.map(v3).ok_or_else(|| {
                c.fail(
                    &key(k),
                    format!("missing: required by a `{}` obstacle", o.kind),
                )
            })
        };
        let ob = match o.kind.as_str() {
            "cylinder" => {
                let centre = need(o.centre, "centre")?;
                let axis = need(o.axis, "axis")?;
                let r = o.radius.ok_or_else(|| {
                    c.fail(&key("radius"), "missing: required by a `cylinder` obstacle")
                })?;
                c.positive(&key("radius"), r)?;
                Obstacle::cylinder(centre, axis, r)
                    .ok_or_else(|| c.fail(&key("axis"), "must be a non-zero vector"))?
            }
            "plane" => {
                let p = need(o.point, "point")?;
                let n = need(o.normal, "normal")?;
                Obstacle::plane(p, n)
                    .ok_or_else(|| c.fail(&key("normal"), "must be a non-zero vector"))?
            }
            other => {
                return Err(c.fail(
                    &key("type"),
                    format!("unknown obstacle `{other}` (known: cylinder, plane)"),
                ));
            }
        };
        obstacles.push(ob);
    }
    let (contact_nodes, contact_k, contact_eta, search_distance) =
        match (&raw.contact, &raw.mesh.contact) {
            (Some(ct), Some(group)) => {
                let nodes = mesh.group(group, path, "mesh.contact")?.to_vec();
                (
                    nodes,
                    c.positive("contact.k", ct.k)?,
                    c.positive("contact.eta", ct.eta)?,
                    c.positive("contact.search_distance", ct.search_distance)?,
                )
            }
            (None, None) => (vec![], 0.0, 0.0, 0.0),
            (Some(_), None) => {
                return Err(c.fail(
                    "mesh.contact",
                    "missing: [contact] needs the group of candidate nodes",
                ));
            }
            (None, Some(_)) => {
                return Err(c.fail(
                    "contact",
                    "missing: mesh.contact is set but there is no [contact] table",
                ));
            }
        };
    if !contact_nodes.is_empty() && obstacles.is_empty() {
        return Err(c.fail(
            "obstacle",
            "missing: [contact] needs at least one [[obstacle]]",
        ));
    }
    let mut loads = vec![];
    for (i, l) in raw.load.iter().enumerate() {
        let force = v3(l.force);
        if !force.iter().all(|x| x.is_finite()) {
            return Err(c.fail(&format!("load[{i}].force"), "must be finite"));
        }
        match (&l.point, &l.group) {
            (Some(p), None) => {
                let node = mesh.node_at(&v3(*p), tol).ok_or_else(|| {
                    c.fail(
                        &format!("load[{i}].point"),
                        format!(
                            "({}, {}, {}) is not a node of {} (no node within {tol:e} m)",
                            p[0],
                            p[1],
                            p[2],
                            mesh.file.display()
                        ),
                    )
                })?;
                loads.push(PointLoad { node, force });
            }
            (None, Some(g)) => {
                for &node in mesh.group(g, path, &format!("load[{i}].group"))? {
                    loads.push(PointLoad { node, force });
                }
            }
            _ => {
                return Err(c.fail(
                    &format!("load[{i}]"),
                    "give exactly one of `point` or `group`",
                ));
            }
        }
    }
    if loads.is_empty() {
        return Err(c.fail("load", "missing: at least one [[load]]"));
    }
    let s = &raw.solver;
    if s.order < 2 {
        return Err(c.fail("solver.order", format!("must be >= 2, got {}", s.order)));
    }
    let solver = ContinuationConfig {
        order: s.order,
        eps: c.positive("solver.eps", s.eps)?,
        lambda_end: c.finite("solver.lambda_end", s.lambda_end)?,
        max_steps: s.max_steps,
        pade: s.pade,
        residual_tol: c.positive("solver.residual_tol", s.residual_tol)?,
        correct: s.correct,
        max_corrections: s.max_corrections,
        ..Default::default()
    };
    let newton = match s.method.as_deref() {
        None | Some("anm") => None,
        Some("newton") => {
            use crate::series::newton::{Control, NewtonConfig};
            let control = match s.newton_control.as_deref() {
                None | Some("arclength") => Control::Arclength,
                Some("load") => Control::Load,
                Some(other) => {
                    return Err(c.fail(
                        "solver.newton_control",
                        format!("expected \"arclength\" or \"load\", got \"{other}\""),
                    ));
                }
            };
            let initial_step = c.positive("solver.newton_step", s.newton_step.unwrap_or(0.01))?;
            Some(NewtonConfig {
                control,
                initial_step,
                max_step: c.positive("solver.newton_max_step", s.newton_max_step.unwrap_or(0.1))?,
                tol: c.positive("solver.newton_tol", s.newton_tol.unwrap_or(s.residual_tol))?,
                lambda_end: solver.lambda_end,
                max_steps: s.max_steps,
                ..Default::default()
            })
        }
        Some(other) => {
            return Err(c.fail(
                "solver.method",
                format!("expected \"anm\" or \"newton\", got \"{other}\""),
            ));
        }
    };
    let o = &raw.output;
    let lambda_step = c.positive("output.lambda_step", o.lambda_step)?;
    let probe = mesh.node_at(&v3(o.probe), tol).ok_or_else(|| {
        c.fail(
            "output.probe",
            format!("({:?}) is not a node of {}", o.probe, mesh.file.display()),
        )
    })?;
    for (k, &l) in o.snapshots.iter().enumerate() {
        let on_grid = (l / lambda_step - (l / lambda_step).round()).abs() < 1e-9;
        if !(l >= 0.0 && l.is_finite() && on_grid) {
            return Err(c.fail(&format!("output.snapshots[{k}]"), format!("{l} is not a value of the lambda grid (multiples of output.lambda_step = {lambda_step})")));
        }
    }
    if o.hdf5 && !cfg!(feature = "hdf5") {
        return Err(c.fail(
            "output.hdf5",
            "this build has no HDF5 support: rebuild with `--features hdf5`",
        ));
    }
    let mut rows: [Vec<usize>; 3] = Default::default();
    for (k, &x) in o.contact_rows.iter().enumerate() {
        rows[k] = (0..mesh.nodes.len())
            .filter(|&n| (mesh.nodes[n][0] - x).abs() <= tol)
            .collect();
        if rows[k].is_empty() {
            return Err(c.fail(
                &format!("output.contact_rows[{k}]"),
                format!("no node row at x = {x} in {}", mesh.file.display()),
            ));
        }
    }
    Ok(ShellScene {
        file: path.to_path_buf(),
        description: raw.scene.description,
        directors,
        material: Material { young, poisson },
        thickness,
        clamped,
        obstacles,
        contact_nodes,
        contact_k,
        contact_eta,
        search_distance,
        loads,
        solver,
        lambda_step,
        probe,
        rows,
        row_x: o.contact_rows,
        vtk_every: o.vtk_every,
        plot: o.plot,
        newton,
        snapshots: o.snapshots.clone(),
        hdf5: o.hdf5,
        mesh,
    })
}
