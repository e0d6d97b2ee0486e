//! Cross-section results of a structured strip (issue 10 item 4): the
//! tension a node row carries and the membrane stresses of its elements.
//!
//! Tension across a cut (a free-body cut, as Abaqus' *SECTION PRINT): the
//! part on one side S of the cut acts on the cut's nodes through the
//! internal forces f_S(n) of S's elements. For a strip in tension T the
//! elements on either side pull the node toward themselves, so
//! −f_S(n) · u_S(n) summed over the cut's nodes is T, u_S(n) the unit
//! vector from n toward its neighbour on S. Both sides give T up to the
//! external forces at the cut's nodes (contact, friction, loads); their
//! mean splits those evenly (at an end row, the one side present).

use crate::mesh::{Cut, Vec3};
use crate::shell::ShellModel;

/// The tension carried across `cut` at the full state (force, positive
/// when the two sides pull apart).
pub fn tension(model: &ShellModel, cut: &Cut, full: &[f64]) -> f64 {
    // Current position of a node (only the cut's nodes and neighbours).
    let x = |n: usize| {
        let i = crate::fe::dof::index(n, 0);
        model.x0[n] + Vec3::new(full[i], full[i + 1], full[i + 2])
    };
    let mut total = 0.0;
    for side in &cut.sides {
        let mut element = usize::MAX;
        let mut f = [0.0; 24];
        for t in side {
            if t.element != element {
                element = t.element;
                f = model.element_internal(element, full);
            }
            let force = Vec3::new(f[6 * t.local], f[6 * t.local + 1], f[6 * t.local + 2]);
            let u = (x(t.neighbour) - x(t.node)).normalize();
            total -= force.dot(&u);
        }
    }
    total / cut.sides.len().max(1) as f64
}

/// Membrane stresses (resultant / thickness) of one element in its own
/// frame: `along` its η direction (t of a structured mesh, the strip's
/// running direction), `across` its ξ direction, and the principal values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MembraneStress {
    pub along: f64,
    pub across: f64,
    pub shear: f64,
    pub min: f64,
    pub max: f64,
}

/// The membrane stresses of element `e` at the full state.
pub fn membrane_stress(
    model: &ShellModel,
    e: usize,
    full: &[f64],
    thickness: f64,
) -> MembraneStress {
    in_element_frame(model, e, model.membrane_resultant(e, full) / thickness)
}

/// The membrane stresses of element `e` from the strain linear in the
/// displacement, as the linear method's solution means them (review 22:
/// the Green–Lagrange strain gave 934.02 where Hooke gives 933.33 on the
/// membrane patch). The strain is exactly quadratic, E(u) = L u + Q(u, u),
/// and the resultant linear in it, so L u = (E(u) − E(−u)) / 2.
pub fn linear_membrane_stress(
    model: &ShellModel,
    e: usize,
    full: &[f64],
    thickness: f64,
) -> MembraneStress {
    let minus: Vec<f64> = full.iter().map(|x| -x).collect();
    linear_from(model, e, full, &minus, thickness)
}

/// [`linear_membrane_stress`] with −full given (negated once for all
/// elements).
fn linear_from(
    model: &ShellModel,
    e: usize,
    full: &[f64],
    minus: &[f64],
    thickness: f64,
) -> MembraneStress {
    let n = (model.membrane_resultant(e, full) - model.membrane_resultant(e, minus)) * 0.5;
    in_element_frame(model, e, n / thickness)
}

/// The membrane stresses of every element: of the Green–Lagrange strain,
/// or of the linear strain (`linear`: the linear method's solution).
pub fn membrane_stresses(
    model: &ShellModel,
    full: &[f64],
    thickness: f64,
    linear: bool,
) -> Vec<MembraneStress> {
    let elements = 0..model.elements.len();
    if linear {
        let minus: Vec<f64> = full.iter().map(|x| -x).collect();
        elements
            .map(|e| linear_from(model, e, full, &minus, thickness))
            .collect()
    } else {
        elements
            .map(|e| membrane_stress(model, e, full, thickness))
            .collect()
    }
}

/// A membrane stress tensor (global frame) along, across and principal.
fn in_element_frame(model: &ShellModel, e: usize, n: nalgebra::Matrix3<f64>) -> MembraneStress {
    let el = &model.elements[e];
    let x: [Vec3; 4] = std::array::from_fn(|i| model.x0[el.nodes[i]]);
    let a_xi = (x[1] + x[2] - x[0] - x[3]) * 0.5;
    let a_eta = (x[2] + x[3] - x[0] - x[1]) * 0.5;
    let along = a_eta.normalize();
    let normal = a_xi.cross(&a_eta).normalize();
    let across = along.cross(&normal);
    let (a, b, c) = (
        along.dot(&(n * along)),
        across.dot(&(n * across)),
        along.dot(&(n * across)),
    );
    let mean = 0.5 * (a + b);
    let radius = (0.25 * (a - b) * (a - b) + c * c).sqrt();
    MembraneStress {
        along: a,
        across: b,
        shear: c,
        min: mean - radius,
        max: mean + radius,
    }
}

/// The membrane stresses of every element as VTK cell data: along and
/// across the element's η direction, shear, principal min and max
/// (friction.vtu, shell_NNNN.vtu and shell_final.vtu; review 19: the static
/// outputs had no stresses); from the linear strain for the linear method.
pub fn stress_cells(
    model: &ShellModel,
    full: &[f64],
    thickness: f64,
    linear: bool,
) -> Vec<crate::output::vtk::PointData<'static>> {
    use crate::output::vtk::PointData;
    let stress = membrane_stresses(model, full, thickness, linear);
    let cell = |f: fn(&MembraneStress) -> f64| stress.iter().map(f).collect();
    vec![
        PointData::Scalar("stress_along", cell(|m| m.along)),
        PointData::Scalar("stress_across", cell(|m| m.across)),
        PointData::Scalar("stress_shear", cell(|m| m.shear)),
        PointData::Scalar("stress_min", cell(|m| m.min)),
        PointData::Scalar("stress_max", cell(|m| m.max)),
    ]
}
