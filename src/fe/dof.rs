//! Degrees of freedom of the shell nodes: 6 per node, the mid-surface
//! displacement v (ux, uy, uz) and the director difference w = a3 − A3
//! (wx, wy, wz) of the director-difference model (DESIGN §3).
//!
//! [`Dof`] names one unknown of the full vector (node, component) and gives
//! its index once, so no file spells the `6 node + k` layout itself.

use std::fmt;

/// Unknowns per node.
pub const PER_NODE: usize = 6;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Component {
    Ux,
    Uy,
    Uz,
    Wx,
    Wy,
    Wz,
}

impl Component {
    pub const ALL: [Component; 6] = [
        Component::Ux,
        Component::Uy,
        Component::Uz,
        Component::Wx,
        Component::Wy,
        Component::Wz,
    ];
    /// The displacement components (x, y, z).
    pub const DISPLACEMENT: [Component; 3] = [Component::Ux, Component::Uy, Component::Uz];
    /// The director components (x, y, z).
    pub const DIRECTOR: [Component; 3] = [Component::Wx, Component::Wy, Component::Wz];

    /// Position of the component within a node's 6 unknowns.
    pub fn offset(self) -> usize {
        self as usize
    }

    /// The scene name: ux, uy, uz, wx, wy, wz.
    pub fn name(self) -> &'static str {
        ["ux", "uy", "uz", "wx", "wy", "wz"][self.offset()]
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }

    /// True for ux, uy, uz (a length), false for the dimensionless director.
    pub fn is_displacement(self) -> bool {
        self.offset() < 3
    }
}

impl fmt::Display for Component {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One unknown of the full vector.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Dof {
    pub node: usize,
    pub component: Component,
}

impl Dof {
    pub fn new(node: usize, component: Component) -> Self {
        Self { node, component }
    }

    /// Index in the full vector.
    pub fn index(self) -> usize {
        PER_NODE * self.node + self.component.offset()
    }

    /// The dof of a full-vector index.
    pub fn of_index(i: usize) -> Self {
        Self {
            node: i / PER_NODE,
            component: Component::ALL[i % PER_NODE],
        }
    }
}

/// Index in the full vector of a node's component by its offset (0..6:
/// ux, uy, uz, wx, wy, wz), for loops over components.
pub fn index(node: usize, offset: usize) -> usize {
    debug_assert!(offset < PER_NODE);
    PER_NODE * node + offset
}

/// The 3-vector of a node's displacement (`Component::DISPLACEMENT`) or
/// director difference (`Component::DIRECTOR`) in a full vector.
pub fn node_vector(full: &[f64], node: usize, comps: [Component; 3]) -> [f64; 3] {
    comps.map(|c| full[Dof::new(node, c).index()])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_and_names_round_trip() {
        for i in 0..60 {
            assert_eq!(Dof::of_index(i).index(), i);
        }
        for c in Component::ALL {
            assert_eq!(Component::from_name(c.name()), Some(c));
        }
        assert_eq!(Component::Wy.to_string(), "wy");
    }
}
