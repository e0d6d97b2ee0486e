//! Shell scenes (`kind = "shell"`): any shell problem as data. A mesh (gmsh
//! file or built-in structured mesh), material and thickness, essential
//! conditions per group and component (`[[fix]]`, with values proportional to
//! lambda), loads (`[[load]]`: nodal forces and moments, line loads on edges,
//! tractions and dead or follower pressures on surfaces), rigid obstacles with
//! a motion (`[[obstacle]]`), the regularized contact law (eq. 3), named
//! outputs (`[[probe]]`), solver and output settings. Every key, its unit,
//! default and range: docs/scenes.md. Validation errors name the file and
//! the key (`table.key`, `load[2].pressure`).

use super::{Checker, parse, read, relative_to};
use crate::contact::{FrictionLaw, Motion, Obstacle};
use crate::error::Result;
use crate::fe::dof::{Component, Dof};
use crate::linalg::{Backend, Choice};
use crate::mesh::{CutSide, Mesh, Vec3, gmsh, strip_path, structured};
use crate::series::ContinuationConfig;
use crate::series::newton::{Control, NewtonConfig};
use crate::shell::Material;
use crate::shell::ramp::Ramp;
use crate::shell::time_path::Stepping;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Raw {
    scene: RawScene,
    mesh: RawMesh,
    #[serde(default)]
    group: Vec<RawGroup>,
    material: RawMaterial,
    shell: RawShell,
    #[serde(default)]
    fix: Vec<RawFix>,
    #[serde(default)]
    load: Vec<RawLoad>,
    #[serde(default)]
    obstacle: Vec<RawObstacle>,
    contact: Option<RawContact>,
    friction: Option<RawFriction>,
    #[serde(default)]
    probe: Vec<RawProbe>,
    solver: RawSolver,
    output: RawOutput,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    kind: String,
    description: Option<String>,
    units: Option<String>,
}

/// The unit names of a scene's numbers (`scene.units`), for the labels of
/// its plots only: the solver itself has no unit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Units {
    pub length: &'static str,
    pub force: &'static str,
    pub stress: &'static str,
}

impl Units {
    /// `scene.units` absent: the plots name the quantity, not a unit.
    pub const UNSTATED: Units = Units {
        length: "length unit",
        force: "force unit",
        stress: "stress unit",
    };

    /// The unit of a penalty stiffness K (force per length), e.g. "N/mm".
    pub fn stiffness(&self) -> String {
        if *self == Self::UNSTATED {
            "force unit/length unit".into()
        } else {
            format!("{}/{}", self.force, self.length)
        }
    }

    /// The label of a probe's unit as the scene states it (a probe's unit
    /// is "m", "N" or "-").
    pub fn of(&self, probe_unit: &str) -> &'static str {
        match probe_unit {
            "m" => self.length,
            "N" => self.force,
            "Pa" => self.stress,
            _ => "-",
        }
    }
}

fn units(c: &Checker, value: Option<&str>) -> Result<Units> {
    match value {
        None => Ok(Units::UNSTATED),
        Some("m") => Ok(Units {
            length: "m",
            force: "N",
            stress: "Pa",
        }),
        Some("mm") => Ok(Units {
            length: "mm",
            force: "N",
            stress: "MPa",
        }),
        Some(other) => Err(c.fail(
            "scene.units",
            format!("expected \"m\" (m, N, Pa) or \"mm\" (mm, N, MPa), got \"{other}\""),
        )),
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMesh {
    file: Option<String>,
    #[serde(rename = "type")]
    kind: Option<String>,
    #[serde(default, deserialize_with = "super::exact::option")]
    x: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "super::exact::option")]
    y: Option<[f64; 2]>,
    radius: Option<toml::Value>,
    #[serde(default, deserialize_with = "super::exact::option")]
    angle: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "super::exact::option")]
    longitude: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "super::exact::option")]
    latitude: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "super::exact::option")]
    divisions: Option<[usize; 2]>,
    node_tolerance: Option<f64>,
    /// "refuse" (default) or "keep": nodes of a mesh file within
    /// node_tolerance that share no element ([`Mesh::coincident_nodes`]).
    coincident_nodes: Option<String>,
    #[serde(default, deserialize_with = "super::exact::option")]
    start: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "super::exact::option")]
    end: Option<[f64; 2]>,
    rollers: Option<Vec<String>>,
    turn: Option<Vec<String>>,
    offset: Option<f64>,
    element_length: Option<f64>,
    arc_element_length: Option<f64>,
    divisions_across: Option<usize>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGroup {
    name: String,
    /// [[xmin, ymin, zmin], [xmax, ymax, zmax]]
    #[serde(rename = "box")]
    #[serde(deserialize_with = "super::exact::nested")]
    bounds: [[f64; 3]; 2],
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
struct RawFix {
    group: Option<String>,
    #[serde(default, deserialize_with = "super::exact::option")]
    point: Option<[f64; 3]>,
    dofs: Option<Vec<String>>,
    /// Per unit lambda, one per entry of `dofs`.
    value: Option<Vec<f64>>,
    clamp: Option<bool>,
    symmetry: Option<String>,
    simply_supported: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLoad {
    #[serde(default, deserialize_with = "super::exact::option")]
    point: Option<[f64; 3]>,
    group: Option<String>,
    edge: Option<String>,
    surface: Option<String>,
    #[serde(default, deserialize_with = "super::exact::option")]
    force: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "super::exact::option")]
    moment: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "super::exact::option")]
    line_force: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "super::exact::option")]
    traction: Option<[f64; 3]>,
    pressure: Option<f64>,
    follower: Option<bool>,
    #[serde(default, deserialize_with = "super::exact::option")]
    ramp: Option<[f64; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawObstacle {
    name: Option<String>,
    #[serde(rename = "type")]
    kind: String,
    #[serde(default, deserialize_with = "super::exact::option")]
    centre: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "super::exact::option")]
    axis: Option<[f64; 3]>,
    radius: Option<f64>,
    crown: Option<f64>,
    face: Option<f64>,
    #[serde(default, deserialize_with = "super::exact::option")]
    point: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "super::exact::option")]
    normal: Option<[f64; 3]>,
    motion: Option<RawMotion>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMotion {
    #[serde(rename = "type")]
    kind: String,
    #[serde(default, deserialize_with = "super::exact::option")]
    velocity: Option<[f64; 3]>,
    omega: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawContact {
    group: String,
    k: f64,
    eta: f64,
    search_distance: f64,
}

/// `[friction]`: the regularized friction law (eqs. 5, 6, 11) at every
/// contact node, which makes the scene a problem in time (issue 10).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
struct RawFriction {
    f: f64,
    q: f64,
    Vc: f64,
    omega: f64,
    zeta: Option<f64>,
    t_end: f64,
    #[serde(default, deserialize_with = "super::exact::option")]
    load_ramp: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "super::exact::option")]
    motion_ramp: Option<[f64; 2]>,
    output_step: Option<f64>,
    stability: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawProbe {
    name: String,
    quantity: String,
    #[serde(default, deserialize_with = "super::exact::option")]
    point: Option<[f64; 3]>,
    group: Option<String>,
    obstacle: Option<String>,
    side: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSolver {
    method: Option<String>,
    order: Option<usize>,
    eps: Option<f64>,
    pade: Option<bool>,
    contact_arclength: Option<f64>,
    lambda_end: f64,
    max_steps: Option<usize>,
    residual_tol: Option<f64>,
    correct: Option<bool>,
    max_corrections: Option<usize>,
    length_scale: Option<f64>,
    newton_control: Option<String>,
    newton_step: Option<f64>,
    newton_max_step: Option<f64>,
    newton_tol: Option<f64>,
    newton_line_search: Option<bool>,
    linear_solver: Option<String>,
    branch: Option<String>,
    branch_direction: Option<f64>,
    time_step: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOutput {
    lambda_step: f64,
    vtk_every: Option<usize>,
    plot: Option<bool>,
    snapshots: Option<Vec<f64>>,
    hdf5: Option<bool>,
    tangent_matrix: Option<bool>,
}

/// A load, scaled by lambda.
#[derive(Clone, Debug)]
pub enum Load {
    /// Force per node (N), dead.
    Nodal { nodes: Vec<usize>, force: Vec3 },
    /// Couple per node (N m) about a fixed axis, applied as the director
    /// force m × a3 (shell::model).
    Moment { nodes: Vec<usize>, moment: Vec3 },
    /// Force per unit length (N/m) on edges, dead, lumped consistently.
    Line { edges: Vec<[usize; 2]>, force: Vec3 },
    /// Force per unit reference area (Pa), dead.
    Traction { quads: Vec<usize>, traction: Vec3 },
    /// Pressure (Pa) along the element normal: the reference one (dead) or
    /// the current one (follower).
    Pressure {
        quads: Vec<usize>,
        pressure: f64,
        follower: bool,
    },
}

/// A rigid obstacle of the scene.
#[derive(Clone, Debug)]
pub struct ObstacleSpec {
    pub name: String,
    pub shape: Obstacle,
    pub motion: Motion,
}

/// Contact candidates and the law of eq. (3).
#[derive(Clone, Debug)]
pub struct ContactSpec {
    pub nodes: Vec<usize>,
    pub k: f64,
    pub eta: f64,
    pub search_distance: f64,
}

/// Friction at the contact nodes and the scene's dependence on time: loads
/// and prescribed values scaled by `load.value(t)` instead of lambda,
/// obstacle velocities (m/s, rad/s) by `motion.value(t)`.
#[derive(Clone, Debug)]
pub struct FrictionSpec {
    pub law: FrictionLaw,
    pub t_end: f64,
    pub load: Ramp,
    pub motion: Ramp,
    /// Loads with their own time function (`load.ramp`): (index into
    /// `ShellScene::loads`, ramp); the others follow `load`.
    pub load_ramps: Vec<(usize, Ramp)>,
    /// Rows of history.csv every `output_step` seconds.
    pub output_step: f64,
    /// `solver.time_step`: "implicit" (RODAS4 steps, shell::implicit_step),
    /// "explicit" (the Taylor series in t) or "auto" (per step).
    pub stepping: Stepping,
    /// `friction.stability`: the tied tangent's inertia and lowest
    /// eigenvalue at every output time, critical points between them
    /// (shell::stability).
    pub stability: bool,
}

/// What a probe measures.
#[derive(Clone, Debug, PartialEq)]
pub enum Quantity {
    /// A dof component (ux..wz), averaged over the nodes.
    Dof {
        nodes: Vec<usize>,
        component: Component,
    },
    /// Current position component (axis 0, 1, 2), averaged over the nodes.
    Position {
        nodes: Vec<usize>,
        axis: usize,
    },
    /// Resultant of the support reactions of fixed nodes along an axis.
    Reaction {
        nodes: Vec<usize>,
        axis: usize,
    },
    /// Sum of the normal contact reactions R (N) of the nodes (all contact
    /// nodes if None) against one obstacle (all if None).
    ContactNormal {
        nodes: Option<Vec<usize>>,
        obstacle: Option<usize>,
    },
    /// Resultant of the contact forces R n along an axis.
    ContactForce {
        nodes: Option<Vec<usize>>,
        obstacle: Option<usize>,
        axis: usize,
    },
    /// Smallest gap of a contact node (m).
    MinGap {
        obstacle: Option<usize>,
    },
    /// Number of contact nodes at or past the obstacle surface (gap <= 0).
    Contacts {
        obstacle: Option<usize>,
    },
    Lambda,
    /// Scaled arclength a summed along the path (dimensionless).
    Arclength,
    /// The force carried across a node row of a structured mesh (a
    /// cross-section of a strip: run::section).
    Tension {
        cut: crate::mesh::Cut,
    },
}

/// A named output: one history.csv column.
#[derive(Clone, Debug)]
pub struct Probe {
    pub name: String,
    pub quantity: Quantity,
    /// Unit of the column (for plots and docs).
    pub unit: &'static str,
}

/// How the path is followed.
#[derive(Clone, Debug)]
pub enum Method {
    Anm,
    Newton(NewtonConfig),
    /// One solve with the tangent at rest: u = lambda K0^-1 F.
    Linear,
}

/// Which branch an ANM path follows at the first bifurcation it crosses
/// (`solver.branch`, docs/bifurcation.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Branch {
    /// Stay on the path (critical points are reported only).
    Primary,
    /// Leave it along the located mode, in `direction` (+1 or −1) of the
    /// mode whose largest displacement component is positive.
    Secondary { direction: f64 },
}

/// Output settings.
#[derive(Clone, Debug)]
pub struct OutputSpec {
    pub lambda_step: f64,
    pub vtk_every: usize,
    pub plot: bool,
    pub snapshots: Vec<f64>,
    pub hdf5: bool,
    /// Write the initial tangent as tangent.mtx (MatrixMarket).
    pub tangent_matrix: bool,
}

/// A validated shell scene.
#[derive(Clone, Debug)]
pub struct ShellScene {
    pub file: PathBuf,
    /// The file's text as loaded: a run's checkpoint records it (a resume
    /// refuses a changed scene), without reading the file again.
    pub text: String,
    pub description: Option<String>,
    /// scene.units: the unit names of the plots' labels.
    pub units: Units,
    pub mesh: Mesh,
    pub directors: Vec<Vec3>,
    pub material: Material,
    pub thickness: f64,
    /// Fixed dofs and their values per unit lambda.
    pub fixed: BTreeMap<Dof, f64>,
    pub loads: Vec<Load>,
    pub obstacles: Vec<ObstacleSpec>,
    pub contact: Option<ContactSpec>,
    /// `[friction]`: None keeps the static path in lambda.
    pub friction: Option<FrictionSpec>,
    /// Input that is valid but likely not what the user meant (printed by
    /// `anm run`).
    pub warnings: Vec<String>,
    pub probes: Vec<Probe>,
    pub method: Method,
    pub solver: ContinuationConfig,
    /// solver.branch (ANM only).
    pub branch: Branch,
    /// Characteristic length of the step control (solver.length_scale).
    pub length_scale: f64,
    /// Weight of the contact reactions' logarithms in the ANM's
    /// pseudo-arclength (solver.contact_arclength; contact::log_reaction).
    pub contact_arclength: f64,
    pub output: OutputSpec,
}

impl ShellScene {
    /// The digest of the mesh file's bytes as they were read with the
    /// scene ([`crate::mesh::Mesh::digest`]); None for a built-in mesh. A
    /// resumed run refuses a mesh file changed since the run started
    /// (review 4: it went on with the new mesh, wrote rows of the mixed
    /// model and stopped on a residual of 7e2).
    pub fn mesh_digest(&self) -> Option<String> {
        self.mesh.digest.clone()
    }

    /// The error of a resumed run whose mesh file changed, if it did
    /// (`self` is the scene loaded for the resume).
    pub fn check_mesh_digest(&self, recorded: &Option<String>) -> Result<()> {
        if recorded.is_some() && *recorded != self.mesh_digest() {
            return Err(crate::error::Error::Invalid {
                file: self.file.clone(),
                key: "mesh.file".into(),
                problem: format!(
                    "{} changed since the run started: a resumed run must solve the same mesh",
                    self.mesh.file.display()
                ),
            });
        }
        Ok(())
    }

    /// The column of history.csv of a probe name (lambda is column 0).
    pub fn column(&self, name: &str) -> Option<usize> {
        self.probes
            .iter()
            .position(|p| p.name == name)
            .map(|i| i + 1)
    }

    /// The key output of the studies (audit, bench, stress): the first probe.
    pub fn key_probe(&self) -> Option<&Probe> {
        self.probes.first()
    }

    /// The contact output of the studies: the first `contact_rn` probe over
    /// every contact node and obstacle (no point, group or obstacle).
    pub fn total_contact_probe(&self) -> Option<&Probe> {
        self.probes.iter().find(|p| {
            p.quantity
                == Quantity::ContactNormal {
                    nodes: None,
                    obstacle: None,
                }
        })
    }
}

fn v3(a: [f64; 3]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

/// Scene validation with the mesh and its groups at hand.
struct Ctx<'a> {
    c: Checker<'a>,
    mesh: &'a Mesh,
    /// Scene-defined node groups (`[[group]]`).
    extra: BTreeMap<String, Vec<usize>>,
    tol: f64,
}

impl Ctx<'_> {
    fn finite3(&self, key: &str, v: [f64; 3]) -> Result<Vec3> {
        finite3(&self.c, key, v)
    }

    fn group(&self, name: &str, key: &str) -> Result<Vec<usize>> {
        if let Some(v) = self.extra.get(name) {
            return Ok(v.clone());
        }
        self.mesh
            .group(name, self.c.file, key)
            .map(|v| v.to_vec())
            .map_err(|_| {
                let mut known: Vec<String> = self.mesh.groups.keys().cloned().collect();
                known.extend(self.extra.keys().cloned());
                self.c.fail(
                    key,
                    format!(
                        "unknown group `{name}` (mesh {} and [[group]] have: {})",
                        self.mesh.file.display(),
                        known.join(", ")
                    ),
                )
            })
    }

    fn point(&self, p: [f64; 3], key: &str) -> Result<usize> {
        let x = self.finite3(key, p)?;
        self.mesh.node_at(&x, self.tol).ok_or_else(|| {
            let near = self
                .mesh
                .nodes
                .iter()
                .map(|n| (n - x).norm())
                .fold(f64::INFINITY, f64::min);
            self.c.fail(
                key,
                format!(
                    "({}, {}, {}) is not a node of {} (nearest node at {near:.3e}, tolerance mesh.node_tolerance = {:.3e})",
                    p[0],
                    p[1],
                    p[2],
                    self.mesh.file.display(),
                    self.tol
                ),
            )
        })
    }

    /// Nodes of exactly one of `point` or `group`.
    fn nodes(
        &self,
        point: Option<[f64; 3]>,
        group: &Option<String>,
        key: &str,
    ) -> Result<Vec<usize>> {
        match (point, group) {
            (Some(p), None) => Ok(vec![self.point(p, &format!("{key}.point"))?]),
            (None, Some(g)) => self.group(g, &format!("{key}.group")),
            _ => Err(self.c.fail(key, "give exactly one of `point` or `group`")),
        }
    }
}

/// Loads and validates a shell scene.
pub fn load(path: &Path) -> Result<ShellScene> {
    let text = read(path)?;
    let raw: Raw = parse(path, &text)?;
    let c = Checker { file: path };
    if raw.scene.kind != "shell" {
        return Err(c.fail(
            "scene.kind",
            format!("expected `shell`, got `{}`", raw.scene.kind),
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
    let obstacles = obstacles(&c, &raw.obstacle)?;
    let mesh = mesh(&c, path, &raw.mesh, &obstacles)?;
    let directors = mesh.directors()?;
    let size = mesh.size();
    // Ranges a double can carry (review 4: t = 1e-200 m stopped on a
    // "singular EAS matrix", E = 1e300 ran to a zero reaction). The
    // bending stiffness is (t / L)² of the membrane one: below 1e-16 it is
    // lost in the membrane's round-off. The residual norms square forces,
    // of the order of E t L: they must stay within about 1e±150.
    if thickness < 1e-8 * size {
        return Err(c.fail(
            "shell.thickness",
            format!(
                "{thickness:e} is below 1e-8 of the model's size {size:.3e}: the bending stiffness, (t/L)² of the membrane one, would be lost in its round-off"
            ),
        ));
    }
    let force_scale = young * thickness * size;
    if !(1e-150..=1e150).contains(&force_scale) {
        return Err(c.fail(
            "material.young",
            format!(
                "E t L = {force_scale:.3e} (the shell's force scale) is outside [1e-150, 1e150]: squared in the residual norms it leaves the range of a double; rescale the units"
            ),
        ));
    }
    let tol = match raw.mesh.node_tolerance {
        Some(t) => c.positive("mesh.node_tolerance", t)?,
        None => 1e-9 * size,
    };
    if raw.mesh.file.is_some()
        && raw.mesh.coincident_nodes.as_deref() != Some("keep")
        && let Some((a, b, d)) = mesh.coincident_nodes(tol)
    {
        let x = mesh.nodes[a];
        let at = |n: usize| {
            mesh.element_of(n).map_or(String::new(), |(tag, line)| {
                format!("element {tag}, line {line}")
            })
        };
        return Err(c.fail(
            "mesh.file",
            format!(
                "{}: nodes {} and {} at ({}, {}, {}) coincide (distance {d:.1e}, mesh.node_tolerance {tol:.1e}) but share no element ({}; {}): the shell is cut there. Merge them (gmsh: Coherence Mesh), or set mesh.coincident_nodes = \"keep\" for an intended cut",
                mesh.file.display(),
                mesh.node_tags[a],
                mesh.node_tags[b],
                x.x,
                x.y,
                x.z,
                at(a),
                at(b)
            ),
        ));
    }
    let mut ctx = Ctx {
        c: Checker { file: path },
        mesh: &mesh,
        extra: BTreeMap::new(),
        tol,
    };
    for (i, g) in raw.group.iter().enumerate() {
        let key = format!("group[{i}]");
        if g.name.is_empty() || mesh.groups.contains_key(&g.name) || ctx.extra.contains_key(&g.name)
        {
            return Err(c.fail(
                &format!("{key}.name"),
                format!("`{}` is empty or already a group name", g.name),
            ));
        }
        let lo = ctx.finite3(&format!("{key}.box"), g.bounds[0])?;
        let hi = ctx.finite3(&format!("{key}.box"), g.bounds[1])?;
        let nodes: Vec<usize> = (0..mesh.nodes.len())
            .filter(|&n| {
                let x = mesh.nodes[n];
                (0..3).all(|k| x[k] >= lo[k] - tol && x[k] <= hi[k] + tol)
            })
            .collect();
        if nodes.is_empty() {
            return Err(c.fail(
                &format!("{key}.box"),
                format!(
                    "no node of {} in the box {:?}",
                    mesh.file.display(),
                    g.bounds
                ),
            ));
        }
        ctx.extra.insert(g.name.clone(), nodes);
    }
    let fixed = fixes(&ctx, &raw.fix)?;
    let loads = loads(&ctx, &raw.load)?;
    let driven = !loads.is_empty()
        || fixed.values().any(|v| *v != 0.0)
        || (raw.contact.is_some()
            && raw.obstacle.iter().any(|o| {
                o.motion.as_ref().is_some_and(|m| {
                    m.kind == "translate" && m.velocity.is_some_and(|v| v.iter().any(|x| *x != 0.0))
                })
            }));
    if !driven && raw.friction.is_none() {
        return Err(c.fail(
            "load",
            "missing: nothing drives the path: give a [[load]], a [[fix]] with a non-zero `value`, or a translating [[obstacle]] with [contact] (all scaled by lambda)",
        ));
    }
    let contact = match &raw.contact {
        Some(ct) => {
            if obstacles.is_empty() {
                return Err(c.fail(
                    "obstacle",
                    "missing: [contact] needs at least one [[obstacle]]",
                ));
            }
            Some(ContactSpec {
                nodes: ctx.group(&ct.group, "contact.group")?,
                k: c.positive("contact.k", ct.k)?,
                // 0: the penalty law R = max(0, -K h) (contact::normal).
                eta: c.non_negative("contact.eta", ct.eta)?,
                search_distance: c.positive("contact.search_distance", ct.search_distance)?,
            })
        }
        None => None,
    };
    let loaded = !loads.is_empty() || fixed.values().any(|v| *v != 0.0);
    let friction = match &raw.friction {
        Some(fr) => Some(
            friction(
                &c,
                fr,
                raw.solver.time_step.as_deref(),
                &obstacles,
                contact.is_some(),
                loaded,
                &raw.load,
            )
            .and_then(|f| {
                stability_needs_inertia(&c, &f, raw.solver.linear_solver.as_deref())?;
                Ok(f)
            })?,
        ),
        None => {
            if let Some(i) = raw.load.iter().position(|l| l.ramp.is_some()) {
                return Err(c.fail(
                    &format!("load[{i}].ramp"),
                    "applies to scenes in time (with [friction]); remove it",
                ));
            }
            if raw.solver.time_step.is_some() {
                return Err(c.fail(
                    "solver.time_step",
                    "applies to scenes in time (with [friction]); remove it",
                ));
            }
            None
        }
    };
    let mut warnings = if friction.is_none() {
        motion_warnings(path, &obstacles)
    } else {
        vec![]
    };
    if contact.is_none() && !obstacles.is_empty() {
        warnings.push(format!(
            "{}: {} [[obstacle]] but no [contact]: nothing touches them (a strip's `mesh.rollers` only shape its path); give [contact] a node group to make them act",
            path.display(),
            obstacles.len()
        ));
    }
    if let Some(ct) = &contact {
        warnings.extend(out_of_reach(path, &obstacles, ct, &mesh.nodes));
        if friction.is_none() {
            let driven = !loads.is_empty() || fixed.values().any(|&v| v != 0.0);
            warnings.extend(moving_away(path, &obstacles, ct, &mesh.nodes, driven));
        }
    }
    warnings.extend(loads_on_fixed_dofs(path, &loads, &fixed, &mesh.quads));
    // Strains are formed from absolute positions (README "Strains from
    // displacements"): their round-off grows with the distance from the
    // origin (review 5: a 1 m cantilever on a plane, moved by 300 m, took
    // 60 factorizations for 11; by 1 km it stopped on no convergence).
    // Review 24: translated copies ran at 25.6 model sizes and failed at
    // 38 (a capstan in time) and 51 (plate-cylinder), below the first
    // threshold of 100 sizes.
    let far = mesh.nodes.iter().map(|x| x.norm()).fold(0.0, f64::max);
    if far > FAR_FROM_ORIGIN * size {
        warnings.push(format!(
            "{}: the mesh lies up to {far:.3e} from the origin, {:.0} times its size {size:.3e}: the strains' round-off grows with that distance (copies of shipped scenes failed from 38 sizes on: a capstan in time stopped on its step size, plate-cylinder on no convergence); translate the model and its obstacles near the origin",
            path.display(),
            far / size
        ));
    }
    // Review 17: a 10 m thickness on a 1 m plate (a unit slip) ran.
    if thickness > THICK * size {
        warnings.push(format!(
            "{}: shell.thickness = {thickness:e} is {:.2} times the model's size {size:.3e}: a shell model needs a thickness well below its span; check the units",
            path.display(),
            thickness / size
        ));
    }
    let probes = probes(
        &ctx,
        &raw.probe,
        &fixed,
        &obstacles,
        contact.as_ref().map(|ct| ct.nodes.as_slice()),
        friction.is_some(),
    )?;
    let (method, solver, length_scale) = solver(&c, &raw.solver, size)?;
    if friction.is_some() && !matches!(method, Method::Anm) {
        return Err(c.fail(
            "solver.method",
            "a scene with [friction] is solved in time by the series (solver.time_step); `newton` and `linear` do not apply: remove solver.method",
        ));
    }
    if contact.is_some() && matches!(method, Method::Linear) {
        // The linear solve keeps the tangent at lambda = 0, where the gap
        // law is either off (the shell passes through the obstacle) or at
        // its initial stiffness: either way not a contact solution.
        return Err(c.fail(
            "solver.method",
            "= \"linear\" solves with the tangent at lambda = 0, and contact is not linear (the gap law switches where the shell touches): use \"anm\" or \"newton\" with [contact], or remove [contact]",
        ));
    }
    if friction.is_some() {
        // Keys of the continuation in lambda that a run in time would
        // ignore.
        let unused = [
            ("solver.pade", raw.solver.pade.is_some()),
            (
                "solver.contact_arclength",
                raw.solver.contact_arclength.is_some(),
            ),
            ("solver.branch", raw.solver.branch.is_some()),
            (
                "solver.branch_direction",
                raw.solver.branch_direction.is_some(),
            ),
            ("output.snapshots", raw.output.snapshots.is_some()),
            // fields.h5 holds the snapshots of the lambda grid; a run in
            // time writes friction.vtu instead (before, it was ignored
            // without a word).
            ("output.hdf5", raw.output.hdf5 == Some(true)),
        ];
        if let Some((key, _)) = unused.iter().find(|(_, present)| *present) {
            return Err(c.fail(
                key,
                "applies to the continuation in lambda, not to a scene in time (with [friction]): remove it",
            ));
        }
    }
    let piecewise = contact.as_ref().is_some_and(|ct| ct.eta == 0.0);
    if piecewise && friction.is_some() {
        return Err(c.fail(
            "contact.eta",
            "= 0 (the penalty law) is for frictionless scenes: with [friction] it must be > 0",
        ));
    }
    let contact_arclength = match raw.solver.contact_arclength {
        Some(w) if piecewise && w != 0.0 => {
            return Err(c.fail(
                "solver.contact_arclength",
                format!(
                    "must be 0 with contact.eta = 0 (the penalty law has no switch band to stretch), got {w}"
                ),
            ));
        }
        Some(w) => c.within("solver.contact_arclength", w, 0.0, 100.0)?,
        None if piecewise => 0.0,
        None => DEFAULT_CONTACT_ARCLENGTH,
    };
    let branch = branch(&c, &raw.solver, &method)?;
    let o = &raw.output;
    let lambda_step = c.positive("output.lambda_step", o.lambda_step)?;
    let rows = solver.lambda_end.abs() / lambda_step;
    if rows > 1e6 {
        return Err(c.fail(
            "output.lambda_step",
            format!("gives {rows:.3e} history rows up to solver.lambda_end (at most 1e6)"),
        ));
    }
    let snapshots = o.snapshots.clone().unwrap_or_default();
    for (k, &l) in snapshots.iter().enumerate() {
        let on_grid = (l / lambda_step - (l / lambda_step).round()).abs() < 1e-9;
        if !(l >= 0.0 && l.is_finite() && on_grid) {
            return Err(c.fail(
                &format!("output.snapshots[{k}]"),
                format!("{l} is not a value of the lambda grid (multiples of output.lambda_step = {lambda_step})"),
            ));
        }
        let end = solver.lambda_end.abs();
        if l > end * (1.0 + 1e-12) {
            return Err(c.fail(
                &format!("output.snapshots[{k}]"),
                format!("{l} lies beyond solver.lambda_end = {end}: the path never reaches it"),
            ));
        }
    }
    let hdf5 = o.hdf5.unwrap_or(false);
    if hdf5 && !cfg!(feature = "hdf5") {
        return Err(c.fail(
            "output.hdf5",
            "this build has no HDF5 support: rebuild with `--features hdf5`",
        ));
    }
    ctx.extra.clear();
    Ok(ShellScene {
        branch,
        file: path.to_path_buf(),
        text,
        units: units(&c, raw.scene.units.as_deref())?,
        description: raw.scene.description,
        directors,
        material: Material { young, poisson },
        thickness,
        fixed,
        loads,
        obstacles,
        contact,
        friction,
        warnings,
        probes,
        method,
        solver,
        length_scale,
        contact_arclength,
        output: OutputSpec {
            lambda_step,
            vtk_every: o.vtk_every.unwrap_or(10),
            plot: o.plot.unwrap_or(true),
            snapshots,
            hdf5,
            tangent_matrix: o.tangent_matrix.unwrap_or(false),
        },
        mesh,
    })
}

/// The mesh: a gmsh file or a built-in structured mesh.
fn mesh(c: &Checker, path: &Path, m: &RawMesh, obstacles: &[ObstacleSpec]) -> Result<Mesh> {
    let deg = |key: &str, v: Option<[f64; 2]>| -> Result<(f64, f64)> {
        let v = v.ok_or_else(|| c.fail(key, "missing: required by this mesh type"))?;
        for x in v {
            c.finite(key, x)?;
        }
        if v[0] == v[1] {
            return Err(c.fail(key, format!("the range [{}, {}] is empty", v[0], v[1])));
        }
        // More than a turn overlaps itself.
        if (v[1] - v[0]).abs() > 360.0 {
            return Err(c.fail(
                key,
                format!(
                    "the range [{}, {}] spans more than 360 degrees: the surface would overlap itself",
                    v[0], v[1]
                ),
            ));
        }
        Ok((v[0].to_radians(), v[1].to_radians()))
    };
    let range = |key: &str, v: Option<[f64; 2]>| -> Result<(f64, f64)> {
        let v = v.ok_or_else(|| c.fail(key, "missing: required by this mesh type"))?;
        for x in v {
            c.finite(key, x)?;
        }
        if !(v[1] > v[0]) {
            return Err(c.fail(key, format!("needs min < max, got [{}, {}]", v[0], v[1])));
        }
        Ok((v[0], v[1]))
    };
    let unused = |key: &str, present: bool, kind: &str| -> Result<()> {
        if present {
            Err(c.fail(
                key,
                format!("not used by a mesh of type `{kind}`; remove it"),
            ))
        } else {
            Ok(())
        }
    };
    let divisions = || -> Result<(usize, usize)> {
        let d = m
            .divisions
            .ok_or_else(|| c.fail("mesh.divisions", "missing: required by this mesh type"))?;
        if d[0] == 0 || d[1] == 0 || d[0].saturating_mul(d[1]) > 1_000_000 {
            return Err(c.fail(
                "mesh.divisions",
                format!("needs 1 to 1e6 elements in all, got {d:?}"),
            ));
        }
        Ok((d[0], d[1]))
    };
    let radius_scalar = || -> Result<f64> {
        let r = m
            .radius
            .as_ref()
            .ok_or_else(|| c.fail("mesh.radius", "missing: required by this mesh type"))?;
        let r = r
            .as_float()
            .or_else(|| r.as_integer().map(|i| i as f64))
            .ok_or_else(|| c.fail("mesh.radius", format!("expected a number, got {r}")))?;
        c.positive("mesh.radius", r)
    };
    match (&m.file, &m.kind) {
        (Some(f), None) => {
            if let Some(v) = &m.coincident_nodes
                && v != "refuse"
                && v != "keep"
            {
                return Err(c.fail(
                    "mesh.coincident_nodes",
                    format!("expected \"refuse\" or \"keep\", got \"{v}\""),
                ));
            }
            for (k, present) in [
                ("mesh.x", m.x.is_some()),
                ("mesh.y", m.y.is_some()),
                ("mesh.radius", m.radius.is_some()),
                ("mesh.angle", m.angle.is_some()),
                ("mesh.longitude", m.longitude.is_some()),
                ("mesh.latitude", m.latitude.is_some()),
                ("mesh.divisions", m.divisions.is_some()),
            ]
            .into_iter()
            .chain(strip_keys(m))
            {
                unused(k, present, "file")?;
            }
            let file = relative_to(path, f);
            gmsh::read(&file).map_err(|e| match e {
                crate::Error::Io { source, .. } => c.fail(
                    "mesh.file",
                    format!("cannot read the mesh {}: {source}", file.display()),
                ),
                other => other,
            })
        }
        (None, Some(kind)) => {
            let kind = kind.as_str();
            unused("mesh.coincident_nodes", m.coincident_nodes.is_some(), kind)?;
            if kind != "strip" {
                for (k, present) in strip_keys(m) {
                    unused(k, present, kind)?;
                }
            }
            let mesh = match kind {
                "rectangle" => {
                    unused("mesh.radius", m.radius.is_some(), kind)?;
                    unused("mesh.angle", m.angle.is_some(), kind)?;
                    unused("mesh.longitude", m.longitude.is_some(), kind)?;
                    unused("mesh.latitude", m.latitude.is_some(), kind)?;
                    let (x0, x1) = range("mesh.x", m.x)?;
                    let (y0, y1) = range("mesh.y", m.y)?;
                    let (nx, ny) = divisions()?;
                    structured::rectangle(x0, x1, y0, y1, nx, ny)
                }
                "cylinder" => {
                    unused("mesh.y", m.y.is_some(), kind)?;
                    unused("mesh.longitude", m.longitude.is_some(), kind)?;
                    unused("mesh.latitude", m.latitude.is_some(), kind)?;
                    let r = radius_scalar()?;
                    let (x0, x1) = range("mesh.x", m.x)?;
                    let (a0, a1) = deg("mesh.angle", m.angle)?;
                    let (nx, ny) = divisions()?;
                    closed_turn(structured::cylinder_panel(r, x0, x1, a0, a1, nx, ny), a0, a1)
                }
                "sphere" => {
                    unused("mesh.x", m.x.is_some(), kind)?;
                    unused("mesh.y", m.y.is_some(), kind)?;
                    unused("mesh.angle", m.angle.is_some(), kind)?;
                    let r = radius_scalar()?;
                    let (l0, l1) = deg("mesh.longitude", m.longitude)?;
                    // The longitude runs along s, which the mesher does not
                    // close (the seam would be two unjoined node rows).
                    if (l1 - l0).abs() >= std::f64::consts::TAU * (1.0 - 1e-12) {
                        return Err(c.fail(
                            "mesh.longitude",
                            "a sphere patch spans less than 360 degrees of longitude (the built-in mesh does not close that seam): model a part with `fix.symmetry`, or give a closed mesh in `mesh.file`",
                        ));
                    }
                    let (b0, b1) = deg("mesh.latitude", m.latitude)?;
                    for (k, b) in [("mesh.latitude", b0), ("mesh.latitude", b1)] {
                        if !(b.abs() < std::f64::consts::FRAC_PI_2 - 1e-9) {
                            return Err(c.fail(k, "must lie strictly between -90 and 90 degrees (a pole collapses the elements)"));
                        }
                    }
                    let (nx, ny) = divisions()?;
                    structured::sphere_patch(r, l0, l1, b0, b1, nx, ny)
                }
                "annulus" => {
                    unused("mesh.x", m.x.is_some(), kind)?;
                    unused("mesh.y", m.y.is_some(), kind)?;
                    unused("mesh.longitude", m.longitude.is_some(), kind)?;
                    unused("mesh.latitude", m.latitude.is_some(), kind)?;
                    let r = m
                        .radius
                        .as_ref()
                        .and_then(|v| v.as_array())
                        .and_then(|a| {
                            let f: Option<Vec<f64>> = a
                                .iter()
                                .map(|x| x.as_float().or_else(|| x.as_integer().map(|i| i as f64)))
                                .collect();
                            f.filter(|f| f.len() == 2)
                        })
                        .ok_or_else(|| {
                            c.fail("mesh.radius", "an annulus needs radius = [inner, outer]")
                        })?;
                    if !(r[0] > 0.0 && r[1] > r[0] && r[1].is_finite()) {
                        return Err(c.fail("mesh.radius", format!("needs 0 < inner < outer, got {r:?}")));
                    }
                    let (a0, a1) = deg("mesh.angle", m.angle)?;
                    let (nr, nt) = divisions()?;
                    closed_turn(structured::annulus(r[0], r[1], a0, a1, nr, nt), a0, a1)
                }
                "strip" => {
                    for (k, present) in [
                        ("mesh.y", m.y.is_some()),
                        ("mesh.radius", m.radius.is_some()),
                        ("mesh.angle", m.angle.is_some()),
                        ("mesh.longitude", m.longitude.is_some()),
                        ("mesh.latitude", m.latitude.is_some()),
                        ("mesh.divisions", m.divisions.is_some()),
                    ] {
                        unused(k, present, kind)?;
                    }
                    strip(c, m, obstacles)?
                }
                other => {
                    return Err(c.fail(
                        "mesh.type",
                        format!("unknown mesh type `{other}` (known: rectangle, cylinder, sphere, annulus, strip)"),
                    ));
                }
            };
            Ok(mesh)
        }
        _ => Err(c.fail(
            "mesh",
            "give exactly one of `file` (gmsh .msh 4.1) or `type` (rectangle, cylinder, sphere, annulus, strip)",
        )),
    }
}

/// The keys only the `strip` mesh reads, and whether each is given.
fn strip_keys(m: &RawMesh) -> [(&'static str, bool); 8] {
    [
        ("mesh.start", m.start.is_some()),
        ("mesh.end", m.end.is_some()),
        ("mesh.rollers", m.rollers.is_some()),
        ("mesh.turn", m.turn.is_some()),
        ("mesh.offset", m.offset.is_some()),
        ("mesh.element_length", m.element_length.is_some()),
        ("mesh.arc_element_length", m.arc_element_length.is_some()),
        ("mesh.divisions_across", m.divisions_across.is_some()),
    ]
}

/// `type = "strip"`: the strip from `start` over the named cylinder
/// obstacles (axes along x) to `end` ([`strip_path`]).
/// A built-in mesh whose angle (along t) spans a full turn, its seam
/// closed ([`structured::close_t`]): left open, the two edges were separate
/// rows of coincident nodes (a tube under pressure deflected 80 m for
/// p R² / E t = 1e-3 m).
fn closed_turn(m: Mesh, a0: f64, a1: f64) -> Mesh {
    if (a1 - a0).abs() >= std::f64::consts::TAU * (1.0 - 1e-12) {
        structured::close_t(m)
    } else {
        m
    }
}

fn strip(c: &Checker, m: &RawMesh, obstacles: &[ObstacleSpec]) -> Result<Mesh> {
    let need = |key: &str, v: Option<[f64; 2]>| -> Result<[f64; 2]> {
        let v = v.ok_or_else(|| c.fail(key, "missing: required by a `strip` mesh"))?;
        for x in v {
            c.finite(key, x)?;
        }
        Ok(v)
    };
    let start = need("mesh.start", m.start)?;
    let end = need("mesh.end", m.end)?;
    if start == end {
        return Err(c.fail(
            "mesh.end",
            format!(
                "{end:?} is mesh.start: a strip mesh does not close a loop (its first and last edges would lie on each other unjoined)"
            ),
        ));
    }
    let width = need("mesh.x", m.x)?;
    if !(width[1] > width[0]) {
        return Err(c.fail("mesh.x", format!("needs min < max, got {width:?}")));
    }
    let names = m
        .rollers
        .as_ref()
        .filter(|r| !r.is_empty())
        .ok_or_else(|| {
            c.fail(
                "mesh.rollers",
                "missing: the names of the cylinder obstacles the strip wraps, in order",
            )
        })?;
    let turns = m.turn.as_ref().ok_or_else(|| {
        c.fail(
            "mesh.turn",
            "missing: `cw` or `ccw` per roller (seen from +x)",
        )
    })?;
    if turns.len() != names.len() {
        return Err(c.fail(
            "mesh.turn",
            format!("gives {} turns for {} rollers", turns.len(), names.len()),
        ));
    }
    let mut rollers = Vec::with_capacity(names.len());
    for (k, (name, turn)) in names.iter().zip(turns).enumerate() {
        let key = format!("mesh.rollers[{k}]");
        let ob = obstacles.iter().find(|o| &o.name == name).ok_or_else(|| {
            c.fail(
                &key,
                format!(
                    "no obstacle named `{name}` (have: {})",
                    obstacles
                        .iter()
                        .map(|o| o.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        })?;
        let Obstacle::Cylinder {
            centre,
            axis,
            radius,
            crown,
        } = ob.shape
        else {
            return Err(c.fail(&key, format!("`{name}` is not a cylinder")));
        };
        if axis.x.abs() < 1.0 - 1e-12 {
            return Err(c.fail(
                &key,
                format!(
                    "`{name}`'s axis must be along x, got ({}, {}, {})",
                    axis.x, axis.y, axis.z
                ),
            ));
        }
        let turn = strip_path::Turn::from_name(turn).ok_or_else(|| {
            c.fail(
                &format!("mesh.turn[{k}]"),
                format!("`{turn}`: expected `cw` or `ccw`"),
            )
        })?;
        // A crowned roll: the path runs at the radius of the strip's
        // middle section; the rest of the width starts off the roll by
        // the crown's fall from there.
        let mid = 0.5 * (width[0] + width[1]) - centre.x;
        rollers.push(strip_path::Roller {
            name: name.clone(),
            centre: [centre.y, centre.z],
            radius: radius - crown * mid * mid,
            turn,
        });
    }
    let offset = c.positive(
        "mesh.offset",
        m.offset.ok_or_else(|| {
            c.fail(
                "mesh.offset",
                "missing: the strip's initial distance to the rollers (eq. 3 needs a gap)",
            )
        })?,
    )?;
    let h = c.positive(
        "mesh.element_length",
        m.element_length
            .ok_or_else(|| c.fail("mesh.element_length", "missing: required by a `strip` mesh"))?,
    )?;
    let arc_h = match m.arc_element_length {
        Some(v) => c.positive("mesh.arc_element_length", v)?,
        None => h,
    };
    let across = m.divisions_across.ok_or_else(|| {
        c.fail(
            "mesh.divisions_across",
            "missing: required by a `strip` mesh",
        )
    })?;
    let p =
        strip_path::path(start, end, &rollers, offset).map_err(|e| c.fail("mesh.rollers", e))?;
    // A wrap whose arc is far shorter than an element is a strip that
    // barely touches the roller, most often a `turn` the wrong way: its one
    // arc element would be a sliver (review 3: 1e-4 degrees, a run that
    // collapsed at t = 1.2e-9 s).
    for (k, (r, wrap)) in rollers.iter().zip(&p.wraps).enumerate() {
        let arc = (r.radius + offset) * wrap;
        if arc < 1e-2 * arc_h {
            return Err(c.fail(
                &format!("mesh.turn[{k}]"),
                format!(
                    "the strip wraps roller `{}` by {:.3e} degrees only (an arc of {arc:.3e}, below 1/100 of the arc element length {arc_h:?}): it barely touches it; check its turn and the positions",
                    r.name,
                    wrap.to_degrees()
                ),
            ));
        }
    }
    // The cylinders along x that the path does not wrap must stay clear of
    // it too: the strip would start inside them.
    for (i, o) in obstacles.iter().enumerate() {
        if let Obstacle::Cylinder {
            centre,
            axis,
            radius,
            ..
        } = o.shape
            && axis.x.abs() >= 1.0 - 1e-12
            && !names.contains(&o.name)
            && p.crosses([centre.y, centre.z], radius)
        {
            return Err(c.fail(
                "mesh.rollers",
                format!(
                    "the strip's path passes through obstacle[{i}] `{}`, which it does not wrap: add it to mesh.rollers (with its turn) or move it",
                    o.name
                ),
            ));
        }
    }
    let along = p.length() / h.min(arc_h);
    if across == 0 || along * across as f64 > 1e6 {
        return Err(c.fail(
            "mesh.divisions_across",
            format!(
                "needs 1 to 1e6 elements in all, got {across} across and about {along:.0} along"
            ),
        ));
    }
    Ok(strip_path::mesh(&p, width, across, h, arc_h, names))
}

/// `[[fix]]` entries into fixed dofs with their values per unit lambda. A dof
/// fixed twice must get the same value.
fn fixes(ctx: &Ctx, raw: &[RawFix]) -> Result<BTreeMap<Dof, f64>> {
    let c = &ctx.c;
    let mut fixed: BTreeMap<Dof, f64> = BTreeMap::new();
    for (i, f) in raw.iter().enumerate() {
        let key = format!("fix[{i}]");
        let nodes = ctx.nodes(f.point, &f.group, &key)?;
        use Component::*;
        let shorthands = [
            f.dofs.is_some(),
            f.clamp == Some(true),
            f.symmetry.is_some(),
            f.simply_supported == Some(true),
        ];
        if shorthands.iter().filter(|x| **x).count() != 1 {
            return Err(c.fail(
                &key,
                "give exactly one of `dofs`, `clamp = true`, `symmetry = \"x\" | \"y\" | \"z\"`, `simply_supported = true`",
            ));
        }
        let comps: Vec<Component> = if let Some(d) = &f.dofs {
            if d.is_empty() {
                return Err(c.fail(&format!("{key}.dofs"), "is empty"));
            }
            let mut v = vec![];
            for (k, name) in d.iter().enumerate() {
                v.push(Component::from_name(name).ok_or_else(|| {
                    c.fail(
                        &format!("{key}.dofs[{k}]"),
                        format!("unknown component `{name}` (known: ux, uy, uz, wx, wy, wz)"),
                    )
                })?);
            }
            v
        } else if f.clamp == Some(true) {
            Component::ALL.to_vec()
        } else if let Some(s) = &f.symmetry {
            // A symmetry plane normal to e_k: no displacement along e_k and
            // the director stays in the plane (w_k = 0 for A3 in the plane).
            match s.as_str() {
                "x" => vec![Ux, Wx],
                "y" => vec![Uy, Wy],
                "z" => vec![Uz, Wz],
                other => {
                    return Err(c.fail(
                        &format!("{key}.symmetry"),
                        format!(
                            "expected \"x\", \"y\" or \"z\" (the plane's normal), got \"{other}\""
                        ),
                    ));
                }
            }
        } else {
            vec![Ux, Uy, Uz]
        };
        let values = match (&f.value, &f.dofs) {
            (None, _) => vec![0.0; comps.len()],
            (Some(v), Some(d)) => {
                if v.len() != d.len() {
                    return Err(c.fail(
                        &format!("{key}.value"),
                        format!("has {} entries for {} dofs", v.len(), d.len()),
                    ));
                }
                for &x in v {
                    c.finite(&format!("{key}.value"), x)?;
                }
                v.clone()
            }
            (Some(_), None) => {
                return Err(c.fail(
                    &format!("{key}.value"),
                    "prescribed values need `dofs` (the components they apply to)",
                ));
            }
        };
        for &n in &nodes {
            for (&comp, &val) in comps.iter().zip(&values) {
                let dof = Dof::new(n, comp);
                if let Some(old) = fixed.insert(dof, val)
                    && old != val
                {
                    return Err(c.fail(
                        &key,
                        format!(
                            "node {} {comp} is already fixed with value {old}, here {val}",
                            ctx.mesh.node_tags[n]
                        ),
                    ));
                }
            }
        }
    }
    Ok(fixed)
}

fn loads(ctx: &Ctx, raw: &[RawLoad]) -> Result<Vec<Load>> {
    let c = &ctx.c;
    let mut out = vec![];
    for (i, l) in raw.iter().enumerate() {
        let key = format!("load[{i}]");
        if l.ramp.is_some() && (l.moment.is_some() || l.follower == Some(true)) {
            return Err(c.fail(
                &format!("{key}.ramp"),
                "only a dead load (force, line_force, traction, dead pressure) takes its own ramp",
            ));
        }
        let kinds = [
            l.force.is_some(),
            l.moment.is_some(),
            l.line_force.is_some(),
            l.traction.is_some(),
            l.pressure.is_some(),
        ];
        if kinds.iter().filter(|x| **x).count() != 1 {
            return Err(c.fail(
                &key,
                "give exactly one of `force`, `moment` (with point or group), `line_force` (with edge), `traction` or `pressure` (with surface)",
            ));
        }
        if l.follower.is_some() && l.pressure.is_none() {
            return Err(c.fail(
                &format!("{key}.follower"),
                "only a `pressure` can be follower (a `moment` is always applied as m × a3)",
            ));
        }
        let targets = [
            l.point.is_some(),
            l.group.is_some(),
            l.edge.is_some(),
            l.surface.is_some(),
        ];
        if targets.iter().filter(|x| **x).count() != 1 {
            return Err(c.fail(
                &key,
                "give exactly one of `point`, `group`, `edge` or `surface`",
            ));
        }
        let wrong = |what: &str, needs: &str| c.fail(&key, format!("`{what}` needs {needs}"));
        let load = if let Some(f) = l.force {
            if l.edge.is_some() || l.surface.is_some() {
                return Err(wrong(
                    "force",
                    "`point` or `group` (a force per node; use `line_force` on an edge, `traction` on a surface)",
                ));
            }
            Load::Nodal {
                nodes: ctx.nodes(l.point, &l.group, &key)?,
                force: ctx.finite3(&format!("{key}.force"), f)?,
            }
        } else if let Some(m) = l.moment {
            if l.edge.is_some() || l.surface.is_some() {
                return Err(wrong("moment", "`point` or `group` (a couple per node)"));
            }
            Load::Moment {
                nodes: ctx.nodes(l.point, &l.group, &key)?,
                moment: ctx.finite3(&format!("{key}.moment"), m)?,
            }
        } else if let Some(q) = l.line_force {
            let Some(e) = &l.edge else {
                return Err(wrong("line_force", "`edge` (a group of mesh edges)"));
            };
            Load::Line {
                edges: edge_group(ctx, e, &format!("{key}.edge"))?,
                force: ctx.finite3(&format!("{key}.line_force"), q)?,
            }
        } else if let Some(t) = l.traction {
            let Some(s) = &l.surface else {
                return Err(wrong("traction", "`surface` (a group of elements)"));
            };
            Load::Traction {
                quads: surface_group(ctx, s, &format!("{key}.surface"))?,
                traction: ctx.finite3(&format!("{key}.traction"), t)?,
            }
        } else {
            let p = c.finite(&format!("{key}.pressure"), l.pressure.unwrap_or(0.0))?;
            let Some(s) = &l.surface else {
                return Err(wrong("pressure", "`surface` (a group of elements)"));
            };
            Load::Pressure {
                quads: surface_group(ctx, s, &format!("{key}.surface"))?,
                pressure: p,
                follower: l.follower.unwrap_or(false),
            }
        };
        out.push(load);
    }
    Ok(out)
}

fn edge_group(ctx: &Ctx, name: &str, key: &str) -> Result<Vec<[usize; 2]>> {
    if ctx.extra.contains_key(name) {
        return Err(ctx.c.fail(
            key,
            format!("`{name}` is a [[group]] of nodes, not a group of edges"),
        ));
    }
    Ok(ctx.mesh.edges(name, ctx.c.file, key)?.to_vec())
}

fn surface_group(ctx: &Ctx, name: &str, key: &str) -> Result<Vec<usize>> {
    if ctx.extra.contains_key(name) {
        return Err(ctx.c.fail(
            key,
            format!("`{name}` is a [[group]] of nodes, not a group of elements"),
        ));
    }
    Ok(ctx.mesh.surface(name, ctx.c.file, key)?.to_vec())
}

fn finite3(c: &Checker, key: &str, v: [f64; 3]) -> Result<Vec3> {
    for x in v {
        c.finite(key, x)?;
    }
    Ok(v3(v))
}

fn obstacles(c: &Checker, raw: &[RawObstacle]) -> Result<Vec<ObstacleSpec>> {
    let mut out: Vec<ObstacleSpec> = vec![];
    for (i, o) in raw.iter().enumerate() {
        let key = |k: &str| format!("obstacle[{i}].{k}");
        let need = |v: Option<[f64; 3]>, k: &str| -> Result<Vec3> {
            let v = v.ok_or_else(|| {
                c.fail(
                    &key(k),
                    format!("missing: required by a `{}` obstacle", o.kind),
                )
            })?;
            finite3(c, &key(k), v)
        };
        let not = |v: bool, k: &str| -> Result<()> {
            if v {
                Err(c.fail(
                    &key(k),
                    format!("not used by a `{}` obstacle; remove it", o.kind),
                ))
            } else {
                Ok(())
            }
        };
        let shape = match o.kind.as_str() {
            "cylinder" => {
                not(o.point.is_some(), "point")?;
                not(o.normal.is_some(), "normal")?;
                let centre = need(o.centre, "centre")?;
                let axis = need(o.axis, "axis")?;
                let r = o.radius.ok_or_else(|| {
                    c.fail(&key("radius"), "missing: required by a `cylinder` obstacle")
                })?;
                c.positive(&key("radius"), r)?;
                let crown = match (o.crown, o.face) {
                    (None, None) => 0.0,
                    (Some(crown), Some(face)) => {
                        c.non_negative(&key("crown"), crown)?;
                        if crown >= r {
                            return Err(c.fail(
                                &key("crown"),
                                format!("must be below the radius {r}, got {crown}"),
                            ));
                        }
                        c.positive(&key("face"), face)?;
                        crown
                    }
                    (Some(_), None) => {
                        return Err(c.fail(
                            &key("face"),
                            "missing: a crown is the radius drop over the face length `face`",
                        ));
                    }
                    (None, Some(_)) => {
                        return Err(c.fail(&key("face"), "given without `crown`; remove it"));
                    }
                };
                Obstacle::crowned_cylinder(centre, axis, r, crown, o.face.unwrap_or(1.0))
                    .ok_or_else(|| c.fail(&key("axis"), "must be a non-zero vector"))?
            }
            "plane" => {
                not(o.centre.is_some(), "centre")?;
                not(o.axis.is_some(), "axis")?;
                not(o.radius.is_some(), "radius")?;
                not(o.crown.is_some(), "crown")?;
                not(o.face.is_some(), "face")?;
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
        let motion = match &o.motion {
            None => Motion::Fixed,
            Some(m) => {
                let mk = |k: &str| format!("obstacle[{i}].motion.{k}");
                match m.kind.as_str() {
                    "fixed" => {
                        if m.velocity.is_some() || m.omega.is_some() {
                            return Err(
                                c.fail(&mk("type"), "a `fixed` motion takes no velocity or omega")
                            );
                        }
                        Motion::Fixed
                    }
                    "translate" => {
                        if m.omega.is_some() {
                            return Err(c.fail(&mk("omega"), "not used by a `translate` motion"));
                        }
                        let v = m.velocity.ok_or_else(|| {
                            c.fail(&mk("velocity"), "missing: required by a `translate` motion")
                        })?;
                        Motion::Translate {
                            velocity: finite3(c, &mk("velocity"), v)?,
                        }
                    }
                    "rotate" => {
                        if m.velocity.is_some() {
                            return Err(c.fail(&mk("velocity"), "not used by a `rotate` motion (it turns about the obstacle's own axis)"));
                        }
                        let w = m.omega.ok_or_else(|| {
                            c.fail(&mk("omega"), "missing: required by a `rotate` motion")
                        })?;
                        Motion::Rotate {
                            omega: c.finite(&mk("omega"), w)?,
                        }
                    }
                    other => {
                        return Err(c.fail(
                            &mk("type"),
                            format!("unknown motion `{other}` (known: fixed, translate, rotate)"),
                        ));
                    }
                }
            }
        };
        let name = o.name.clone().unwrap_or_else(|| format!("obstacle{i}"));
        if out.iter().any(|x| x.name == name) {
            return Err(c.fail(&key("name"), format!("`{name}` names two obstacles")));
        }
        out.push(ObstacleSpec {
            name,
            shape,
            motion,
        });
    }
    Ok(out)
}

/// The `[friction]` table: the law, the end time and the time functions.
fn friction(
    c: &Checker,
    fr: &RawFriction,
    time_step: Option<&str>,
    obstacles: &[ObstacleSpec],
    contact: bool,
    loaded: bool,
    loads: &[RawLoad],
) -> Result<FrictionSpec> {
    if !contact {
        return Err(c.fail(
            "friction",
            "needs [contact]: friction acts at the contact nodes",
        ));
    }
    let f = c.finite("friction.f", fr.f)?;
    if f <= 0.0 {
        // The slip velocities are the unknowns of the friction law: without
        // friction no equation holds them (a singular tangent).
        return Err(c.fail(
            "friction.f",
            format!(
                "must be > 0, got {f}: frictionless contact is solved without [friction] (leave it out)"
            ),
        ));
    }
    let q = c.within("friction.q", fr.q, 0.0, 1.0)?;
    let vc = c.positive("friction.Vc", fr.Vc)?;
    // Below q = 1 the law is singular at zero slip without omega.
    let omega = if q < 1.0 {
        c.positive("friction.omega", fr.omega)?
    } else {
        c.non_negative("friction.omega", fr.omega)?
    };
    c.slip_speeds(vc, omega, q)?;
    let zeta = match fr.zeta {
        Some(z) => Some(c.positive("friction.zeta", z)?),
        None => None,
    };
    let t_end = c.positive("friction.t_end", fr.t_end)?;
    let ramp = |key: &str, r: Option<[f64; 2]>| -> Result<Ramp> {
        let Some([start, end]) = r else {
            return Ok(Ramp::FULL);
        };
        c.non_negative(key, start)?;
        c.finite(key, end)?;
        if !(end >= start && start < t_end) {
            return Err(c.fail(
                key,
                format!("[start, end] = [{start:?}, {end:?}] must have start <= end and start < friction.t_end = {t_end:?}"),
            ));
        }
        if start > 0.0 && end == start {
            // A jump at t = start: the path in time is not smooth there,
            // and the series cannot cross it (review 4: a step collapse
            // blamed on friction).
            return Err(c.fail(
                key,
                format!("[{start:?}, {end:?}] is a jump at t = {start:?}: the path in time must be smooth; give end > start (a short rise), or [0, 0] for full from the start"),
            ));
        }
        Ok(Ramp { start, end })
    };
    let load = ramp("friction.load_ramp", fr.load_ramp)?;
    let motion = ramp("friction.motion_ramp", fr.motion_ramp)?;
    let mut load_ramps = vec![];
    for (i, l) in loads.iter().enumerate() {
        if let Some(r) = l.ramp {
            load_ramps.push((i, ramp(&format!("load[{i}].ramp"), Some(r))?));
        }
    }
    let moving = obstacles.iter().any(|o| match o.motion {
        Motion::Fixed => false,
        Motion::Translate { velocity } => velocity.norm() > 0.0,
        Motion::Rotate { omega } => omega != 0.0,
    });
    for (i, o) in obstacles.iter().enumerate() {
        if let Motion::Translate { velocity } = o.motion {
            // In time the obstacle's shape stays where the scene puts it and
            // only its surface velocity enters (friction); a translation that
            // moves the surface would change the gaps too.
            let off_surface = match &o.shape {
                Obstacle::Plane { normal, .. } => velocity.dot(normal).abs(),
                Obstacle::Cylinder { axis, .. } => velocity.cross(axis).norm(),
            };
            if off_surface > 1e-12 * velocity.norm() {
                return Err(c.fail(
                    &format!("obstacle[{i}].motion"),
                    "with [friction], a translation must keep the obstacle's surface in place (along a plane, or along a cylinder's axis): a translation that moves the surface is not supported in time yet",
                ));
            }
        }
    }
    let output_step = match fr.output_step {
        Some(v) => c.positive("friction.output_step", v)?,
        None => t_end / 100.0,
    };
    if output_step > t_end {
        return Err(c.fail(
            "friction.output_step",
            format!(
                "{output_step:?} s is longer than the run (t_end = {t_end:?} s): at most t_end"
            ),
        ));
    }
    if t_end / output_step > 1e6 {
        return Err(c.fail(
            "friction.output_step",
            format!("{output_step:?} s gives more than 1e6 rows up to t_end = {t_end:?} s"),
        ));
    }
    let stepping = match time_step {
        None | Some("auto") => Stepping::Auto,
        Some("implicit") => Stepping::Implicit,
        Some("explicit") => Stepping::Explicit,
        Some(other) => {
            return Err(c.fail(
                "solver.time_step",
                format!(
                    "expected \"auto\", \"implicit\" or \"explicit\" for a shell scene, got \"{other}\""
                ),
            ));
        }
    };
    let own_varies = load_ramps.iter().any(|(_, r)| r.varies());
    if !(moving || loaded && load.varies() || own_varies) {
        return Err(c.fail(
            "friction",
            "nothing moves in time: give an [[obstacle]] a `translate` or `rotate` motion, or [[load]]s / non-zero [[fix]] values that vary in time (friction.load_ramp)",
        ));
    }
    Ok(FrictionSpec {
        law: FrictionLaw {
            f,
            q,
            vc,
            omega,
            zeta,
        },
        t_end,
        load,
        motion,
        load_ramps,
        output_step,
        stepping,
        stability: fr.stability.unwrap_or(false),
    })
}

/// `friction.stability` counts the tied tangent's negative pivots, which an
/// LU does not give (review 9: every row read −1 and the event went
/// unreported while the lowest eigenvalue changed sign).
fn stability_needs_inertia(
    c: &Checker,
    fr: &FrictionSpec,
    linear_solver: Option<&str>,
) -> Result<()> {
    if fr.stability && linear_solver == Some("lu") {
        return Err(c.fail(
            "friction.stability",
            "counts the tangent's negative pivots, and solver.linear_solver = \"lu\" gives none: use \"auto\", \"ldlt\" or \"lblt\"",
        ));
    }
    Ok(())
}

/// Obstacle motions that only friction would feel, in a scene without it:
/// a rotation (only the surface moves) or a translation along the obstacle's
/// own surface (no gap changes).
/// A warning for each load that acts on fixed translations only: it goes
/// straight into the supports and does not load the shell (review 17: a
/// force on clamped nodes, the scene's only load, ran to w = 0 with exit 0
/// and no word).
fn loads_on_fixed_dofs(
    path: &Path,
    loads: &[Load],
    fixed: &BTreeMap<Dof, f64>,
    quads: &[[usize; 4]],
) -> Vec<String> {
    let takes = |node: usize, direction: Option<&Vec3>| {
        Component::DISPLACEMENT
            .into_iter()
            .enumerate()
            .filter(|(k, _)| direction.is_none_or(|f| f[*k] != 0.0))
            .any(|(_, c)| !fixed.contains_key(&Dof::new(node, c)))
    };
    let of_quads =
        |elems: &[usize]| -> Vec<usize> { elems.iter().flat_map(|&e| quads[e]).collect() };
    loads
        .iter()
        .enumerate()
        .filter_map(|(i, load)| {
            let (nodes, direction): (Vec<usize>, Option<&Vec3>) = match load {
                Load::Nodal { nodes, force } => (nodes.clone(), Some(force)),
                Load::Line { edges, force } => (edges.iter().flatten().copied().collect(), Some(force)),
                Load::Traction { quads: e, traction } => (of_quads(e), Some(traction)),
                Load::Pressure { quads: e, .. } => (of_quads(e), None),
                // A couple acts on the rotations (the director).
                Load::Moment { .. } => return None,
            };
            // A zero load is its own warning (review 21: force = [0, 0, 0]
            // was told it acts on fixed translations).
            if direction.is_some_and(|f| f.norm() == 0.0) {
                return Some(format!(
                    "{}: load[{i}] is zero: it loads nothing",
                    path.display()
                ));
            }
            (!nodes.is_empty() && !nodes.iter().any(|&n| takes(n, direction))).then(|| {
                format!(
                    "{}: load[{i}] acts on fixed translations only ({}, every loaded direction held by a [[fix]]): it goes straight into the supports and does not load the shell; apply it to free nodes",
                    path.display(),
                    {
                        let mut n = nodes.clone();
                        n.sort_unstable();
                        n.dedup();
                        if n.len() == 1 { "1 node".to_string() } else { format!("{} nodes", n.len()) }
                    }
                )
            })
        })
        .collect()
}

fn motion_warnings(path: &Path, obstacles: &[ObstacleSpec]) -> Vec<String> {
    let mut out = vec![];
    for (i, o) in obstacles.iter().enumerate() {
        let what = match (o.motion, &o.shape) {
            (Motion::Rotate { omega }, _) if omega != 0.0 => "turns the obstacle's surface",
            (Motion::Translate { velocity }, Obstacle::Plane { normal, .. })
                if velocity.norm() > 0.0 && velocity.dot(normal) == 0.0 =>
            {
                "slides the plane within itself"
            }
            (Motion::Translate { velocity }, Obstacle::Cylinder { axis, .. })
                if velocity.norm() > 0.0
                    && velocity.cross(axis).norm() <= 1e-12 * velocity.norm() =>
            {
                "slides the cylinder along its axis"
            }
            _ => continue,
        };
        out.push(format!(
            "{}: obstacle[{i}].motion {what}, which only friction feels: without [friction] it has no effect",
            path.display()
        ));
    }
    out
}

/// A warning for each translating obstacle whose motion opens the gap of
/// every contact candidate (review 17: a punch given an upward velocity
/// above a strip stopped with "no convergence after 1 iterations" and
/// nothing saying it never comes near the shell).
fn moving_away(
    path: &Path,
    obstacles: &[ObstacleSpec],
    contact: &ContactSpec,
    nodes: &[Vec3],
    driven: bool,
) -> Vec<String> {
    let mut out = vec![];
    for (i, o) in obstacles.iter().enumerate() {
        let Motion::Translate { velocity } = o.motion else {
            continue;
        };
        // dh/dλ = −n · v at each candidate (the obstacle moves by λ v).
        let opening = contact.nodes.iter().all(|&n| {
            o.shape
                .gap(&nodes[n])
                .is_some_and(|g| -g.n.dot(&velocity) > 0.0)
        });
        // With loads the shell may deflect onto a receding obstacle
        // (scenes/verification/moving-plane.toml).
        if velocity.norm() > 0.0 && !contact.nodes.is_empty() && opening && !driven {
            out.push(format!(
                "{}: obstacle[{i}] ({}) moves away from every contact candidate (motion.velocity opens each gap) and the scene has no load or prescribed value: nothing drives the shell but the faint pull of eq. (3)'s regularization; check the sign of its velocity",
                path.display(),
                o.name
            ));
        }
    }
    out
}

/// Distance from the origin, in model sizes, above which a scene is
/// warned of (round-off of strains from absolute positions).
const FAR_FROM_ORIGIN: f64 = 20.0;
/// A thickness above this share of the model's size is no shell.
const THICK: f64 = 0.25;

fn axis_of(s: &str) -> Option<usize> {
    match s {
        "x" => Some(0),
        "y" => Some(1),
        "z" => Some(2),
        _ => None,
    }
}

/// A warning for each obstacle farther than `contact.search_distance` from
/// every contact node at the start (it touches nothing unless it moves or
/// the shell deflects onto it; with friction, the regularized law's faint pull leaves the shell free
/// and a run in time crawls: 5,102 steps to t = 5e-4 s of 1 s in a new
/// user's scene with the roller 5 m away).
fn out_of_reach(
    path: &Path,
    obstacles: &[ObstacleSpec],
    contact: &ContactSpec,
    nodes: &[Vec3],
) -> Vec<String> {
    obstacles
        .iter()
        .filter_map(|o| {
            let nearest = contact
                .nodes
                .iter()
                .filter_map(|&n| o.shape.gap(&nodes[n]).map(|g| g.h))
                .fold(f64::INFINITY, f64::min);
            (nearest > contact.search_distance).then(|| {
                format!(
                    "{}: obstacle `{}` is {nearest:.3e} from the nearest contact node, beyond contact.search_distance = {:.3e}: it touches nothing unless it moves or the shell deflects that far toward it",
                    path.display(),
                    o.name,
                    contact.search_distance
                )
            })
        })
        .collect()
}

/// solver.contact_arclength when absent: one e-fold of a contact reaction
/// weighs in the ANM's pseudo-arclength as much as a displacement of
/// solver.length_scale (contact::log_reaction; README, "Contact events").
pub const DEFAULT_CONTACT_ARCLENGTH: f64 = 1.0;

/// The probe quantities, for error messages and docs.
pub const QUANTITIES: &str = "ux, uy, uz, wx, wy, wz, x, y, z, reaction_x, reaction_y, reaction_z, contact_rn, contact_x, contact_y, contact_z, min_gap, contacts, lambda, arclength, tension";

/// The columns of history.csv that a run in time (a scene with
/// `[friction]`) writes after the probes (run::shell_time): contact and
/// friction totals, then, with `friction.stability`, the monitor's. A probe
/// of one of these names, or `t`, made two columns of one name, and
/// summary.json's `end` kept one of them.
pub const TIME_FORCE_COLUMNS: [&str; 6] =
    ["rn_total", "ft_x", "ft_y", "ft_z", "max_slip", "slip_area"];
pub const TIME_STABILITY_COLUMNS: [&str; 5] = [
    "negative_pivots",
    "lowest_eigenvalue",
    "negative_pivots_tied",
    "lowest_eigenvalue_tied",
    "sticking_nodes",
];

fn probes(
    ctx: &Ctx,
    raw: &[RawProbe],
    fixed: &BTreeMap<Dof, f64>,
    obstacles: &[ObstacleSpec],
    candidates: Option<&[usize]>,
    in_time: bool,
) -> Result<Vec<Probe>> {
    let c = &ctx.c;
    let has_contact = candidates.is_some();
    let candidates: std::collections::BTreeSet<usize> =
        candidates.unwrap_or(&[]).iter().copied().collect();
    let mut out: Vec<Probe> = vec![];
    for (i, p) in raw.iter().enumerate() {
        let key = format!("probe[{i}]");
        let name = p.name.trim();
        let time_columns = || {
            std::iter::once("t")
                .chain(TIME_FORCE_COLUMNS)
                .chain(TIME_STABILITY_COLUMNS)
        };
        if in_time && time_columns().any(|col| col == name) {
            return Err(c.fail(
                &format!("{key}.name"),
                format!(
                    "`{name}` is a column that a run in time writes itself ({}): choose another name",
                    time_columns().collect::<Vec<_>>().join(", ")
                ),
            ));
        }
        if name.is_empty()
            || name.contains([',', '"', '\n'])
            || name == "lambda"
            || out.iter().any(|q| q.name == name)
        {
            return Err(c.fail(
                &format!("{key}.name"),
                format!("`{name}` is empty, repeated, `lambda` (always column 1) or holds a comma or quote"),
            ));
        }
        let q = p.quantity.as_str();
        let obstacle = match &p.obstacle {
            None => None,
            Some(o) => Some(obstacles.iter().position(|x| &x.name == o).ok_or_else(|| {
                c.fail(
                    &format!("{key}.obstacle"),
                    format!(
                        "no obstacle named `{o}` (have: {})",
                        obstacles
                            .iter()
                            .map(|x| x.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })?),
        };
        if p.side.is_some() && q != "tension" {
            return Err(c.fail(
                &format!("{key}.side"),
                format!("not used by a `{q}` probe (only by `tension`)"),
            ));
        }
        let is_contact = q.starts_with("contact") || q == "min_gap";
        if obstacle.is_some() && !is_contact {
            return Err(c.fail(
                &format!("{key}.obstacle"),
                format!("not used by a `{q}` probe"),
            ));
        }
        if is_contact && !has_contact {
            return Err(c.fail(
                &format!("{key}.quantity"),
                format!("`{q}` needs a [contact] table"),
            ));
        }
        let no_target = |what: &str| -> Result<()> {
            if p.point.is_some() || p.group.is_some() {
                Err(c.fail(&key, format!("a `{what}` probe takes no point or group")))
            } else {
                Ok(())
            }
        };
        // The nodes of a contact probe, all contact candidates: another
        // node reads 0 whatever happens (review 5).
        let optional_nodes = || -> Result<Option<Vec<usize>>> {
            if p.point.is_none() && p.group.is_none() {
                return Ok(None);
            }
            let nodes = ctx.nodes(p.point, &p.group, &key)?;
            if let Some(&n) = nodes.iter().find(|n| !candidates.contains(n)) {
                let x = ctx.mesh.nodes[n];
                return Err(c.fail(
                    &key,
                    format!(
                        "the node at ({}, {}, {}) is not a contact candidate (contact.group): a `{q}` probe there reads 0 whatever happens",
                        x.x, x.y, x.z
                    ),
                ));
            }
            Ok(Some(nodes))
        };
        let (quantity, unit) = if let Some(comp) = Component::from_name(q) {
            (
                Quantity::Dof {
                    nodes: ctx.nodes(p.point, &p.group, &key)?,
                    component: comp,
                },
                if comp.is_displacement() { "m" } else { "-" },
            )
        } else if let Some(axis) = axis_of(q) {
            (
                Quantity::Position {
                    nodes: ctx.nodes(p.point, &p.group, &key)?,
                    axis,
                },
                "m",
            )
        } else if let Some(axis) = q.strip_prefix("reaction_").and_then(axis_of) {
            let nodes = ctx.nodes(p.point, &p.group, &key)?;
            let comp = Component::DISPLACEMENT[axis];
            if let Some(&n) = nodes
                .iter()
                .find(|&&n| !fixed.contains_key(&Dof::new(n, comp)))
            {
                return Err(c.fail(
                    &key,
                    format!(
                        "a reaction needs fixed dofs, but node {} {comp} is free",
                        ctx.mesh.node_tags[n]
                    ),
                ));
            }
            (Quantity::Reaction { nodes, axis }, "N")
        } else if q == "contact_rn" {
            (
                Quantity::ContactNormal {
                    nodes: optional_nodes()?,
                    obstacle,
                },
                "N",
            )
        } else if let Some(axis) = q.strip_prefix("contact_").and_then(axis_of) {
            (
                Quantity::ContactForce {
                    nodes: optional_nodes()?,
                    obstacle,
                    axis,
                },
                "N",
            )
        } else if q == "min_gap" {
            no_target(q)?;
            (Quantity::MinGap { obstacle }, "m")
        } else if q == "contacts" {
            no_target(q)?;
            (Quantity::Contacts { obstacle }, "-")
        } else if q == "lambda" {
            no_target(q)?;
            (Quantity::Lambda, "-")
        } else if q == "arclength" {
            no_target(q)?;
            (Quantity::Arclength, "-")
        } else if q == "tension" {
            let nodes = ctx.nodes(p.point, &p.group, &key)?;
            let grid = ctx.mesh.grid.ok_or_else(|| {
                c.fail(&key, "`tension` needs a built-in mesh (mesh.type) that is not closed over a full turn: its cross-sections are its node rows of constant t")
            })?;
            let row = grid.row_of(&nodes).ok_or_else(|| {
                c.fail(&key, "`tension` needs a group that is one node row of constant t (t0, t1, a strip's <roller>_in or <roller>_out, or a [[group]] box around one row)")
            })?;
            let side = match p.side.as_deref() {
                None | Some("both") => CutSide::Both,
                Some("before") => CutSide::Before,
                Some("after") => CutSide::After,
                Some(other) => {
                    return Err(c.fail(
                        &format!("{key}.side"),
                        format!("expected \"both\", \"before\" or \"after\", got \"{other}\""),
                    ));
                }
            };
            let cut = grid.cut(row, &ctx.mesh.quads, side);
            if cut.sides.is_empty() {
                return Err(c.fail(
                    &format!("{key}.side"),
                    format!(
                        "node row {row} is an end of the mesh: it has no elements {} it",
                        if side == CutSide::Before {
                            "before"
                        } else {
                            "after"
                        }
                    ),
                ));
            }
            (Quantity::Tension { cut }, "N")
        } else {
            return Err(c.fail(
                &format!("{key}.quantity"),
                format!("unknown quantity `{q}` (known: {QUANTITIES})"),
            ));
        };
        out.push(Probe {
            name: name.to_string(),
            quantity,
            unit,
        });
    }
    Ok(out)
}

/// solver.branch and solver.branch_direction.
fn branch(c: &Checker, s: &RawSolver, method: &Method) -> Result<Branch> {
    let secondary = match s.branch.as_deref() {
        None | Some("primary") => false,
        Some("secondary") => true,
        Some(other) => {
            return Err(c.fail(
                "solver.branch",
                format!("expected \"primary\" or \"secondary\", got \"{other}\""),
            ));
        }
    };
    if secondary && !matches!(method, Method::Anm) {
        return Err(c.fail(
            "solver.branch",
            "\"secondary\" needs solver.method = \"anm\"",
        ));
    }
    // The bifurcation is found by the tangent's inertia, which an LU has
    // not (review 9: the run followed the straight Euler column and said
    // the path crossed no bifurcation).
    if secondary && s.linear_solver.as_deref() == Some("lu") {
        return Err(c.fail(
            "solver.branch",
            "\"secondary\" needs the tangent's inertia to find the bifurcation, and solver.linear_solver = \"lu\" gives none: use \"auto\", \"ldlt\" or \"lblt\"",
        ));
    }
    match (secondary, s.branch_direction) {
        (false, Some(_)) => Err(c.fail(
            "solver.branch_direction",
            "only with solver.branch = \"secondary\"; remove it",
        )),
        (false, None) => Ok(Branch::Primary),
        (true, d) => {
            let direction = d.unwrap_or(1.0);
            if direction != 1.0 && direction != -1.0 {
                return Err(c.fail(
                    "solver.branch_direction",
                    format!("must be 1 or -1, got {direction}"),
                ));
            }
            Ok(Branch::Secondary { direction })
        }
    }
}

fn solver(c: &Checker, s: &RawSolver, size: f64) -> Result<(Method, ContinuationConfig, f64)> {
    let lambda_end = c.finite("solver.lambda_end", s.lambda_end)?;
    if lambda_end == 0.0 {
        return Err(c.fail(
            "solver.lambda_end",
            "must differ from 0 (the path starts at lambda = 0)",
        ));
    }
    let order = s.order.unwrap_or(15);
    if !(2..=60).contains(&order) {
        return Err(c.fail("solver.order", format!("must lie in [2, 60], got {order}")));
    }
    let max_steps = s.max_steps.unwrap_or(20_000);
    if max_steps == 0 {
        return Err(c.fail("solver.max_steps", "must be >= 1"));
    }
    let residual_tol = c.positive("solver.residual_tol", s.residual_tol.unwrap_or(1e-6))?;
    let length_scale = match s.length_scale {
        Some(l) => c.positive("solver.length_scale", l)?,
        None => size,
    };
    let linear = match s.linear_solver.as_deref() {
        None | Some("auto") => Choice::Auto,
        Some(name) => match Backend::from_name(name) {
            Some(b) => Choice::Only(b),
            None => {
                return Err(c.fail(
                    "solver.linear_solver",
                    format!(
                        "expected \"auto\", \"ldlt\", \"lblt\", \"lu\" or (feature mumps) \"mumps\", got \"{name}\""
                    ),
                ));
            }
        },
    };
    let cfg = ContinuationConfig {
        order,
        linear,
        eps: c.within("solver.eps", s.eps.unwrap_or(1e-8), 1e-16, 1.0)?,
        lambda_end,
        max_steps,
        pade: s.pade.unwrap_or(false),
        residual_tol,
        correct: s.correct.unwrap_or(true),
        max_corrections: s.max_corrections.unwrap_or(10),
        ..Default::default()
    };
    let newton_keys = [
        ("solver.newton_control", s.newton_control.is_some()),
        ("solver.newton_step", s.newton_step.is_some()),
        ("solver.newton_max_step", s.newton_max_step.is_some()),
        ("solver.newton_tol", s.newton_tol.is_some()),
        ("solver.newton_line_search", s.newton_line_search.is_some()),
    ];
    let anm_keys = [
        ("solver.order", s.order.is_some()),
        ("solver.eps", s.eps.is_some()),
        ("solver.pade", s.pade.is_some()),
        ("solver.contact_arclength", s.contact_arclength.is_some()),
        // The ANM's step-end and grid corrections (review 16: accepted and
        // ignored by Newton, whose increments iterate to newton_tol).
        ("solver.correct", s.correct.is_some()),
        ("solver.max_corrections", s.max_corrections.is_some()),
    ];
    let method_name = s.method.as_deref().unwrap_or("anm");
    let refuse = |keys: &[(&str, bool)]| -> Result<()> {
        match keys.iter().find(|(_, present)| *present) {
            Some((k, _)) => Err(c.fail(
                k,
                format!("not used by solver.method = \"{method_name}\"; remove it"),
            )),
            None => Ok(()),
        }
    };
    let method = match method_name {
        "anm" => {
            refuse(&newton_keys)?;
            Method::Anm
        }
        "linear" => {
            refuse(&newton_keys)?;
            refuse(&anm_keys)?;
            Method::Linear
        }
        "newton" => {
            refuse(&anm_keys)?;
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
            let max_step =
                c.positive("solver.newton_max_step", s.newton_max_step.unwrap_or(0.1))?;
            // Review 16: a first increment five times the cap was taken.
            if initial_step > max_step {
                return Err(c.fail(
                    "solver.newton_step",
                    format!(
                        "the first increment {initial_step:e} exceeds solver.newton_max_step = {max_step:e}, the largest increment"
                    ),
                ));
            }
            Method::Newton(NewtonConfig {
                control,
                initial_step,
                max_step,
                tol: c.positive("solver.newton_tol", s.newton_tol.unwrap_or(residual_tol))?,
                lambda_end,
                max_steps,
                linear,
                line_search: s.newton_line_search.unwrap_or(false),
                ..Default::default()
            })
        }
        other => {
            return Err(c.fail(
                "solver.method",
                format!("expected \"anm\", \"newton\" or \"linear\", got \"{other}\""),
            ));
        }
    };
    Ok((method, cfg, length_scale))
}
